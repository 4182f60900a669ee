"""Torque-free symmetric top (I1 = I2 != I3): closed-form reference solution.

Frames/units: body frame = principal axes, inertia ``diag(I1, I1, I3)`` [kg m^2];
``w`` is the angular velocity in the BODY frame [rad/s]; ``q`` the unit
quaternion (w, x, y, z) rotating body -> world; time in s.

Derivation (checked against an ODE in tests/checks/test_closed_forms.py)
------------------------------------------------------------------
Euler's equations with I1 = I2 give ``w3 = const`` and
``w1' = Omega w2``, ``w2' = -Omega w1`` with ``Omega = w3 (I1 - I3)/I1``, so
``(w1, w2)`` rotates rigidly: ``w_perp(t) = Rz(-Omega t) w_perp(0)``.

Attitude: ``L_body = I w`` gives ``w = L_body / I1 + (1/I3 - 1/I1) L3 e3`` with
``L3 = I3 w3``. Then ``R' = R [w]x = [L_world]x R / I1 + c R [e3]x``
(``c = (1/I3 - 1/I1) L3``, using ``R [v]x = [R v]x R``), solved by

    R(t) = exp(t |L|/I1 [n]x) R0 exp(c t [e3]x),   n = L_world/|L|,

i.e. the symmetry axis precesses about the fixed ``L_world`` at rate ``|L|/I1``
while the body spins about e3 at rate ``c`` relative to that precessing frame
(note ``c = -Omega``).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..numerics.rotation_np import quat_from_axis_angle, quat_mul, quat_normalize, quat_to_matrix

__all__ = ["body_precession_about_L", "precession_rate", "solve"]


def precession_rate(I1: float, I3: float, w3: float) -> float:
    """Rate ``Omega = w3 (I1 - I3)/I1`` [rad/s] at which (w1, w2) rotates in the body.

    Sign convention: ``w1' = Omega w2``, ``w2' = -Omega w1`` (so for ``Omega > 0``
    the transverse part turns clockwise about +e3 as seen in the body frame).
    """
    return float(w3) * (float(I1) - float(I3)) / float(I1)


def body_precession_about_L(I1: float, L: ArrayLike) -> float:
    """Rate ``|L|/I1`` [rad/s] at which the symmetry axis precesses about L_world.

    ``L`` may be the angular-momentum vector [kg m^2/s] (any frame) or its magnitude.
    """
    return float(np.linalg.norm(np.atleast_1d(np.asarray(L, dtype=float)))) / float(I1)


def solve(
    I1: float, I3: float, w0: ArrayLike, q0: ArrayLike, t: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Closed-form torque-free motion of a symmetric body.

    Parameters
    ----------
    I1, I3 : transverse (= I2) and axial principal moments [kg m^2], > 0.
    w0 : initial body angular velocity [rad/s], shape (3,).
    q0 : initial unit quaternion (w, x, y, z), body -> world (normalised here).
    t : times [s] (measured from the initial state), shape (n,).

    Returns
    -------
    w : (n, 3) body angular velocity [rad/s].
    q : (n, 4) unit quaternions body -> world (sign chosen by the product formula).
    """
    I1 = float(I1)
    I3 = float(I3)
    if not (I1 > 0.0 and I3 > 0.0):
        raise ValueError("I1 and I3 must be positive")
    w0 = np.asarray(w0, dtype=float).reshape(3)
    q0 = quat_normalize(np.asarray(q0, dtype=float).reshape(4))
    t = np.atleast_1d(np.asarray(t, dtype=float))

    Om = precession_rate(I1, I3, w0[2])
    c, s = np.cos(Om * t), np.sin(Om * t)
    w = np.empty((t.size, 3))
    w[:, 0] = c * w0[0] + s * w0[1]
    w[:, 1] = -s * w0[0] + c * w0[1]
    w[:, 2] = w0[2]

    L_body = np.array([I1 * w0[0], I1 * w0[1], I3 * w0[2]])
    L_world = quat_to_matrix(q0) @ L_body
    Lmag = float(np.linalg.norm(L_world))
    if Lmag == 0.0:
        return w, np.tile(q0, (t.size, 1))
    n = L_world / Lmag
    spin = (1.0 / I3 - 1.0 / I1) * L_body[2]  # = -Omega
    q_prec = quat_from_axis_angle(n, (Lmag / I1) * t)
    q_spin = quat_from_axis_angle(np.array([0.0, 0.0, 1.0]), spin * t)
    q = quat_mul(quat_mul(q_prec, q0), q_spin)
    return w, q
