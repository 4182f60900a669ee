"""Linear models of a scene's FMU for control design: operating points, linearisation, trim and the step map.

`linearize` (A, B, C, D from the FMU's directional derivatives through FMI calls, in
attitude-error coordinates or the FMU's own states), `trim` (Newton on the same
derivatives), `step_map` (Φ, Γ of one communication step through the generated integrator
steps), `modes` (the eigenvalue table) and the files they are written to; docs/theory.md
§10 and docs/user_guide.md §6.
"""

from .eigen import modes, table
from .linear_model import LinearModel
from .linearize import linearize
from .operating_point import OperatingPoint, held_start_values, run_point, start_point
from .step_map import step_map
from .trim import TrimError, TrimResult, trim

__all__ = [
    "LinearModel", "OperatingPoint", "TrimError", "TrimResult", "held_start_values", "linearize", "modes", "run_point",
    "start_point", "step_map", "table", "trim",
]  # fmt: skip
