"""The rotating shaft with a skewed bar (MIT 2.003J): the bearing torque in closed form.

MIT 2.003J, "Rigid Body Dynamics", example.

A bar (principal moments I_a about its axis, I_t across it, about its centre C) is fixed
at C to a massless shaft along world x at angle φ, and turned at a constant rate θ̇. The
bearings must supply

  τ = −(I_t − I_a) θ̇² sin φ cos φ k_A,   thin rod (I_a = 0, I_t = m L²/12): −(m L²/12) θ̇² sin φ cos φ k_A,

with k_A the shaft-fixed axis normal to the plane of shaft and bar (k_A(0) = world z,
turning with the shaft). Zero at φ = 0 and φ = π/2. The same bar on an Exudyn revolute joint:
rbcheck.exudyn.skewed_bar.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray


def bearing_torque(t: ArrayLike, I_a: float, I_t: float, phi: float, theta_dot: float) -> NDArray[np.float64]:
    """Bearing torque on the bar (N·m, world frame) at times t (s), shaft along world x."""
    t = np.atleast_1d(np.asarray(t, dtype=float))
    k_A = np.column_stack([np.zeros_like(t), -np.sin(theta_dot * t), np.cos(theta_dot * t)])
    return -(I_t - I_a) * theta_dot**2 * np.sin(phi) * np.cos(phi) * k_A
