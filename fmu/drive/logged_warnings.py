"""The warnings an FMU logged, raised as FmuWarnings: each distinct message once, with its count, also on failure.

An FMU says that something went on but not as asked (a tolerance its error estimate cannot
resolve, an importer's tolerance it does not apply, ...) by logging a message with status
Warning; fmpy hands it to the instance's log callback, which keeps it (`FmuInstance.warnings`,
`fmu.linear.model_exchange.ModelExchange.warnings`). `LoggedWarnings` raises the ones logged
inside a `with` block when the block ends, so every driver of an FMU (a run, a sweep's rows
on the client, a linearisation, a trim) shows them the same way; `rbfmu` prints each as one
line `rbfmu: warning: ...` (fmu.cli.warnings_as_lines).
"""

from __future__ import annotations

import contextlib
import warnings
from collections import Counter
from collections.abc import Callable, Mapping
from pathlib import Path
from types import TracebackType
from typing import Protocol

from .instance import FmuWarning

# A run shows at most this many distinct warnings of the FMU (each once, with its count), then one line for the rest.
MAX_WARNINGS_SHOWN = 5


class Logging(Protocol):
    """What keeps an FMU's logged warnings: the archive's path and the messages of status Warning, in order."""

    path: Path
    warnings: list[str]


def in_this_run(n: int) -> str:
    """The count of a message logged n times in one run, as warn_counts appends it."""
    return f" (logged {n} times in this run)" if n > 1 else ""


def warn_counts(source: str, counts: Mapping[str, int], count_text: Callable[[int], str], stacklevel: int) -> None:
    """Raise one FmuWarning `{source}: the FMU logged a warning: {message}{count_text(n)}` per
    distinct message of `counts` (message -> n, in the order given); past MAX_WARNINGS_SHOWN
    of them, one FmuWarning counts the rest. stacklevel: as warnings.warn's, from here."""
    for k, (message, n) in enumerate(counts.items()):
        if k == MAX_WARNINGS_SHOWN:
            rest = list(counts.values())[k:]
            text = f"the FMU logged {len(rest)} more distinct warnings ({sum(rest)} in all), not shown"
            warnings.warn(f"{source}: {text}", FmuWarning, stacklevel=stacklevel)
            break
        warnings.warn(
            f"{source}: the FMU logged a warning: {message}{count_text(n)}", FmuWarning, stacklevel=stacklevel
        )


def warn_logged(inst: Logging, first: int = 0, stacklevel: int = 1) -> None:
    """Raise one FmuWarning for each distinct warning the FMU logged since its warning number
    `first` (inst.warnings), in the order first logged, with its count when logged more than
    once (`warn_counts`). stacklevel 1: the warnings point at the caller of warn_logged, 2 at
    its caller, ..."""
    warn_counts(inst.path.name, Counter(inst.warnings[first:]), in_this_run, stacklevel + 2)


class LoggedWarnings:
    """`with LoggedWarnings(inst): ...`: the warnings the FMU logged inside the block raised on
    leaving it (`warn_logged`), also when the block failed; then FmuWarnings made errors
    (warnings.simplefilter("error", FmuWarning)) are dropped, so that they never hide the
    block's own error. first: the warning number to start from (default: the number logged
    when the block starts; 0 for an instance made for the block, whose initialisation's
    warnings count too). stacklevel 2: the warnings point at the caller of the function
    holding the `with` (1: that function)."""

    __slots__ = ("first", "inst", "stacklevel")  # made per linearisation: no instance dict

    def __init__(self, inst: Logging, first: int | None = None, stacklevel: int = 2):
        self.inst = inst
        self.first = len(inst.warnings) if first is None else first
        self.stacklevel = stacklevel

    def __enter__(self) -> LoggedWarnings:
        return self

    def __exit__(self, kind: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None) -> None:
        if len(self.inst.warnings) <= self.first:  # nothing logged in the block: no Counter (a linearisation's 1-3 µs)
            return
        level = self.stacklevel + 1  # counted from __exit__, whose caller is the function holding the `with`
        if kind is None:
            warn_logged(self.inst, self.first, level)
            return
        with contextlib.suppress(FmuWarning):
            warn_logged(self.inst, self.first, level)
