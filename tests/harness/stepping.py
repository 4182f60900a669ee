"""Start values that select fixed internal steps, for the tests that predict fixed-step errors (docs/theory.md §5.4).

The shipped FMUs choose their steps by error control (tolerance > 0, docs/theory.md §5.5)
and, for a torque-free body, the exact flow. A test whose tolerance comes from a
method's order at a known step asks for fixed steps explicitly: tolerance 0 and h_max.
"""

from __future__ import annotations

from modelsrc.methods import METHODS
from modelsrc.scene import Scene


def fixed_steps(h_max: float, method: str | None = None) -> dict[str, float]:
    """Start values: fixed steps of at most h_max (s), with `method` when given."""
    out = {"tolerance": 0.0, "h_max": float(h_max)}
    if method is not None:
        out["method"] = METHODS[method].value
    return out


def rk4_fixed(scene: Scene, h_max: float | None = None) -> dict[str, float]:
    """Start values: rk4 with fixed steps of h_max, by default the scene's fixed step."""
    return fixed_steps(scene.fixed_step if h_max is None else h_max, "rk4")
