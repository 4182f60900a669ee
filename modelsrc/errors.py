"""The one exception type for bad user input (scene files, parameters, start values), and the number check.

finite_number is shared by the command line's options (rbfmu run --set, the sweep's --set, --param, --sample).
"""

import math


class ModelInputError(ValueError):
    """Raised for invalid user input; the message names the value and what is allowed."""


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
