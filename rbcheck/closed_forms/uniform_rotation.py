"""A body held at a constant body rate (features.prescribed_rate): uniform rotation about a fixed axis, in closed form.

With ω̇ = 0 (docs/theory.md §4.4) the axis ω/|ω| is the same in body and world
(R ω is constant: d/dt (R ω) = R (ω × ω) = 0), and q̇ = ½ q ⊗ (0, ω) (§1.2) is solved by

  q(t) = q0 ⊗ (cos(|ω| t / 2), sin(|ω| t / 2) ω/|ω|),

the rotation by the angle |ω| t about ω/|ω|. Its own error in double precision is that of
the angle, about ε |ω| t. Units SI; ω (rad/s) in the body frame, q body -> world (scalar first).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..numerics.rotation_np import quat_from_axis_angle, quat_mul


def solve(w0: ArrayLike, q0: ArrayLike, t: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(w (n, 3) rad/s body, q (n, 4) body -> world) at times t (s) of the body held at the
    body rate w0 from the attitude q0 (normalised here: the start of a run is q0/|q0|)."""
    w0 = np.asarray(w0, dtype=float).reshape(3)
    q0 = np.asarray(q0, dtype=float).reshape(4)
    t = np.atleast_1d(np.asarray(t, dtype=float))
    rate = float(np.linalg.norm(w0))
    w = np.tile(w0, (t.size, 1))
    if rate == 0.0:
        return w, np.tile(q0 / np.linalg.norm(q0), (t.size, 1))
    return w, quat_mul(q0 / np.linalg.norm(q0), quat_from_axis_angle(w0 / rate, rate * t))
