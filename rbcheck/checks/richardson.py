"""FMU against a reference run at two steps: Richardson extrapolation of an order-p method and its error estimate.

The jointed Exudyn gyrostat (rbcheck.exudyn.rotors) integrates with the trapezoidal rule,
order p = 2: run at h and h/2, x_R = (2^p x(h/2) − x(h)) / (2^p − 1) removes the h^p term
of its error, and |x(h/2) − x(h)| ≈ (2^p − 1) × the error of the finer run (its own error
estimate, shown next to the agreement). Units: those of the compared outputs.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["Agreement", "richardson_agreement"]


@dataclass(frozen=True)
class Agreement:
    """Per output: max over time and components of |FMU − x_R| (`diff`), of |x(h/2) − x(h)|
    (`estimate`), and of |FMU − x(h/2)| (`plain`)."""

    diff: dict[str, float]
    estimate: dict[str, float]
    plain: dict[str, float]


def richardson_agreement(
    fmu: Mapping[str, ArrayLike],
    coarse: Mapping[str, ArrayLike],
    fine: Mapping[str, ArrayLike],
    keys: Sequence[str],
    order: int = 2,
) -> Agreement:
    """Compare the FMU's outputs `fmu[key]` with the reference runs at h (`coarse`) and h/2
    (`fine`) on the same communication points, for each key (arrays (n,) or (n, k))."""
    if order < 1:
        raise ValueError(f"order must be >= 1, got {order}")
    f = 2.0**order
    diff, est, plain = {}, {}, {}
    for k in keys:
        a, b, x = (np.asarray(d[k], dtype=float) for d in (coarse, fine, fmu))
        if not (a.shape == b.shape == x.shape):
            raise ValueError(f"{k}: shapes differ: FMU {x.shape}, coarse {a.shape}, fine {b.shape}")
        rich = (f * b - a) / (f - 1.0)
        diff[k] = float(np.max(np.abs(x - rich)))
        est[k] = float(np.max(np.abs(b - a)))
        plain[k] = float(np.max(np.abs(x - b)))
    return Agreement(diff, est, plain)
