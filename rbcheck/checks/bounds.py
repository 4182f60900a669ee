"""The tolerance of a row of a shipped scene's check: what the FMU's error control promises, and a reference's error.

The FMU keeps a relative error per second of simulated time of its `tolerance` (docs/theory.md
§5.4): over a run of T seconds a quantity of size S may be off by about tolerance·T·S. A row
allows FMU_MARGIN times that plus a round-off floor ROUND_OFF·S (`fmu_bound`, the rule the
feature checks of any scene use, rbcheck.checks.feature_checks), plus what the comparison itself
does not model: a closed form linearised at an amplitude a differs from the motion by O(a²)
relative (`model`), and a reference (scipy, Exudyn) carries its own error, estimated from a
second run and allowed three times over (`reference`; the estimates are good to a factor ~2).
T is the longest run of the check (the bound of a shorter run is smaller), S the size the row
names (a frequency, a radius, a peak rate). These are a-priori bounds: they hold for any
setting of the scene, where the tests in tests/ hold the shipped settings to their measured,
much smaller errors. With fixed steps (tolerance 0) there is no a-priori bound: nan, the row is
shown without a verdict. Units: those of the row.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from modelsrc.scene import Scene

from .feature_checks import fmu_bound

REFERENCE_MARGIN = 3.0  # a reference's estimated own error, allowed this many times over
VERTEX_GRID = 4000  # points of the closed form over the span of `vertex_error`


def allowed(scene: Scene, stop_time: float, scale: float, model: float = 0.0, reference: float = 0.0) -> float:
    """The tolerance of a row: (fmu_bound(scene, stop_time) + model) · |scale| + REFERENCE_MARGIN ·
    reference. stop_time [s]: the longest run behind the row; scale: the size of the quantity
    (the row's unit); model: the comparison's own relative error (a linearisation's O(a²));
    reference: a reference's estimated error (the row's unit). nan with fixed steps."""
    bound = fmu_bound(scene, stop_time)
    if not math.isfinite(bound):
        return bound
    return (bound + model) * abs(scale) + REFERENCE_MARGIN * abs(reference)


def vertex_error(closed: Callable[[np.ndarray], np.ndarray], span: float, dt: float) -> float:
    """A bound of the error of an extremum refined by the parabola through the extreme sample
    and its two neighbours dt (s) apart (rbcheck.numerics.motion_fits.refined_extrema, vertex
    error O(dt³ f‴)): max |f‴| dt³ over [0, span] (s), f‴ by central differences of the closed
    form `closed` (a function of time in s, in the row's unit) on VERTEX_GRID + 1 points; the
    error constant of the interpolating parabola taken as 1 (between the samples it is 1/(9√3))."""
    s = span / VERTEX_GRID
    t = np.linspace(2 * s, span + 2 * s, VERTEX_GRID + 1)
    f = [np.asarray(closed(t + k * s), dtype=float) for k in (-2, -1, 1, 2)]
    third = (f[3] - 2.0 * f[2] + 2.0 * f[1] - f[0]) / (2.0 * s**3)
    return float(np.max(np.abs(third))) * dt**3
