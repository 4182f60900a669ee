"""The exception and the warning for bad user input (scene files, parameters, start values), and the number check.

ModelInputError refuses a value; ModelInputWarning names a value that is allowed but almost
surely a unit mistake (modelsrc.unit_mistakes) and its likely intent: the run goes on.

finite_number is shared by the command line's options (rbfmu run --set, the sweep's --set, --param, --sample);
unknown_variable is the one message for a variable name an FMU does not have or does not let be set.
"""

import difflib
import math
import re
from collections.abc import Collection, Sequence


class ModelInputError(ValueError):
    """Raised for invalid user input; the message names the value and what is allowed."""


class ModelInputWarning(UserWarning):
    """Warned for a value that is allowed but almost surely a unit mistake; the message names
    the value and the likely intent (`rbfmu` prints it as one line `rbfmu: warning: ...`)."""


def finite_number(text: object, where: str, what: str = "value") -> float:
    """float(text), or a ModelInputError naming `where`, `what` and the text when it is not a
    number or not finite (the command line's --set, --param and --sample values)."""
    try:
        v = float(text)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ModelInputError(f"{where}: {what} {str(text).strip()!r} is not a number") from None
    if not math.isfinite(v):
        raise ModelInputError(f"{where}: {what} must be finite, got {str(text).strip()}")
    return v


def _compact_names(names: Sequence[str]) -> str:
    """Names joined by commas, a run of array elements x[1], x[2], ..., x[n] written x[1..n]."""
    runs: list[list] = []  # [base, first, last] of an array run, or [name, None, None]
    for name in names:
        m = re.fullmatch(r"(.+)\[(\d+)\]", name)
        if m and runs and runs[-1][0] == m.group(1) and runs[-1][2] == int(m.group(2)) - 1:
            runs[-1][2] += 1
        elif m:
            runs.append([m.group(1), int(m.group(2)), int(m.group(2))])
        else:
            runs.append([name, None, None])
    text = (b if i is None else f"{b}[{i}]" if i == j else f"{b}[{i}..{j}]" for b, i, j in runs)
    return ", ".join(text)


def unknown_variable(
    name: str,
    allowed: Sequence[str],
    known: Collection[str] = (),
    where: str = "",
    listed: str = "settable",
    is_not: str | None = None,
) -> ModelInputError:
    """The error for a variable name the caller cannot use: the closest allowed names first
    (difflib), then every allowed one (array elements compacted as x[1..3]).

    allowed: the names that may be given here (e.g. the settable ones: start values,
    parameters, inputs), in the FMU's order; known: every name of the FMU, so that a name
    it has but which may not be given here is said to be so rather than unknown; where:
    the option or call, put first; listed: what the allowed names are, for the message;
    is_not: what a known name that is not allowed is not (default `listed`).
    """
    close = difflib.get_close_matches(name, list(allowed), n=3, cutoff=0.6)
    # only the matches about as close as the best: 'w_bdy[3]' suggests 'w_body[3]', not also [1] and [2]
    ratio = lambda c: difflib.SequenceMatcher(None, name, c).ratio()
    close = [c for c in close if ratio(c) >= ratio(close[0]) - 0.05]
    head = f"variable {name!r} is not {is_not or listed}" if name in known else f"unknown variable {name!r}"
    hint = f"; did you mean {' or '.join(repr(c) for c in close)}? {listed.capitalize()}" if close else f"; {listed}"
    prefix = f"{where}: " if where else ""
    return ModelInputError(f"{prefix}{head}{hint}: {_compact_names(allowed)}")
