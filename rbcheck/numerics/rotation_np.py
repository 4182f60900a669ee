"""Small numpy rotation helpers (independent of modelsrc/fmu).

Conventions
-----------
* Quaternions are scalar first, ``q = (w, x, y, z)``; a unit quaternion rotates
  body -> world: ``v_world = R(q) v_body``.
* Kinematics: ``q_dot = 0.5 * q (x) (0, omega_body)``, ``R_dot = R [omega_body]x``.
* Euler angles z-x-z ``(phi, theta, psi)`` with ``R = Rz(phi) Rx(theta) Rz(psi)``
  (body -> world), so that ``omega_body = (phi' sin(theta) sin(psi) + theta' cos(psi),
  phi' sin(theta) cos(psi) - theta' sin(psi), phi' cos(theta) + psi')``.

All functions broadcast over leading dimensions (quaternions ``(..., 4)``,
vectors ``(..., 3)``, matrices ``(..., 3, 3)``). Angles are in radians.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "euler_zxz_rates_to_omega",
    "euler_zxz_to_matrix",
    "euler_zxz_to_quat",
    "matrix_to_euler_zxz",
    "matrix_to_quat",
    "omega_to_euler_zxz_rates",
    "quat_conj",
    "quat_from_axis_angle",
    "quat_mul",
    "quat_normalize",
    "quat_to_matrix",
    "rot_x",
    "rot_z",
    "rotation_angle_between",
    "skew",
]


def quat_mul(p: ArrayLike, q: ArrayLike) -> NDArray[np.float64]:
    """Hamilton product ``p (x) q`` of scalar-first quaternions (broadcasting)."""
    p = np.asarray(p, dtype=float)
    q = np.asarray(q, dtype=float)
    pw, px, py, pz = np.moveaxis(p, -1, 0)
    qw, qx, qy, qz = np.moveaxis(q, -1, 0)
    return np.stack(
        [
            pw * qw - px * qx - py * qy - pz * qz,
            pw * qx + px * qw + py * qz - pz * qy,
            pw * qy - px * qz + py * qw + pz * qx,
            pw * qz + px * qy - py * qx + pz * qw,
        ],
        axis=-1,
    )


def quat_conj(q: ArrayLike) -> NDArray[np.float64]:
    """Conjugate ``(w, -x, -y, -z)`` (the inverse for a unit quaternion)."""
    q = np.array(q, dtype=float)
    q[..., 1:] *= -1.0
    return q


def quat_normalize(q: ArrayLike) -> NDArray[np.float64]:
    """Return ``q / |q|``."""
    q = np.asarray(q, dtype=float)
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def quat_from_axis_angle(axis: ArrayLike, angle: ArrayLike) -> NDArray[np.float64]:
    """Unit quaternion of a right-handed rotation by ``angle`` [rad] about unit ``axis``."""
    axis = np.asarray(axis, dtype=float)
    half = 0.5 * np.asarray(angle, dtype=float)[..., None]
    return np.concatenate([np.cos(half), np.sin(half) * axis], axis=-1)


def quat_to_matrix(q: ArrayLike) -> NDArray[np.float64]:
    """Rotation matrix (body -> world) of a quaternion (normalised first)."""
    w, x, y, z = np.moveaxis(quat_normalize(q), -1, 0)
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
        ],
        axis=-2,
    )


def cross3(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """a × b of two 3-vectors, by components: np.cross costs ~20x more per call on
    3-vectors (axis handling), which dominated the scipy baselines' right-hand sides."""
    a0, a1, a2 = a
    b0, b1, b2 = b
    return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])


def quat_to_matrix1(q: NDArray[np.float64]) -> NDArray[np.float64]:
    """quat_to_matrix of one quaternion (normalised first), by components: the form a
    right-hand side called 1e5 times wants (quat_to_matrix's stacking costs ~10x more)."""
    n = 1.0 / np.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    w, x, y, z = q[0] * n, q[1] * n, q[2] * n, q[3] * n
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def matrix_to_quat(R: ArrayLike) -> NDArray[np.float64]:
    """Unit quaternion (w >= 0) of a rotation matrix (Shepperd's branch choice).

    For each matrix the largest of ``(trace, R11, R22, R33)`` selects the
    component that is computed from a square root, which keeps the division
    well conditioned.
    """
    R = np.asarray(R, dtype=float)
    shp = R.shape[:-2]
    R = R.reshape(-1, 3, 3)
    tr = R[:, 0, 0] + R[:, 1, 1] + R[:, 2, 2]
    cand = np.stack([tr, R[:, 0, 0], R[:, 1, 1], R[:, 2, 2]], axis=-1)
    k = np.argmax(cand, axis=-1)
    q = np.empty((R.shape[0], 4))
    for i in range(R.shape[0]):
        m = R[i]
        if k[i] == 0:
            s = 2.0 * np.sqrt(1.0 + tr[i])
            q[i] = (0.25 * s, (m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s)
        elif k[i] == 1:
            s = 2.0 * np.sqrt(1.0 + m[0, 0] - m[1, 1] - m[2, 2])
            q[i] = ((m[2, 1] - m[1, 2]) / s, 0.25 * s, (m[0, 1] + m[1, 0]) / s, (m[0, 2] + m[2, 0]) / s)
        elif k[i] == 2:
            s = 2.0 * np.sqrt(1.0 - m[0, 0] + m[1, 1] - m[2, 2])
            q[i] = ((m[0, 2] - m[2, 0]) / s, (m[0, 1] + m[1, 0]) / s, 0.25 * s, (m[1, 2] + m[2, 1]) / s)
        else:
            s = 2.0 * np.sqrt(1.0 - m[0, 0] - m[1, 1] + m[2, 2])
            q[i] = ((m[1, 0] - m[0, 1]) / s, (m[0, 2] + m[2, 0]) / s, (m[1, 2] + m[2, 1]) / s, 0.25 * s)
    q *= np.where(q[:, :1] < 0.0, -1.0, 1.0)
    q = quat_normalize(q)
    return q.reshape(shp + (4,))


def skew(v: ArrayLike) -> NDArray[np.float64]:
    """Cross-product matrix ``[v]x`` with ``[v]x u = v x u``."""
    v = np.asarray(v, dtype=float)
    z = np.zeros_like(v[..., 0])
    return np.stack(
        [
            np.stack([z, -v[..., 2], v[..., 1]], -1),
            np.stack([v[..., 2], z, -v[..., 0]], -1),
            np.stack([-v[..., 1], v[..., 0], z], -1),
        ],
        axis=-2,
    )


def rot_x(a: ArrayLike) -> NDArray[np.float64]:
    """Right-handed rotation matrix about x by angle ``a`` [rad]."""
    a = np.asarray(a, dtype=float)
    c, s, o, z = np.cos(a), np.sin(a), np.ones_like(a), np.zeros_like(a)
    return np.stack([np.stack([o, z, z], -1), np.stack([z, c, -s], -1), np.stack([z, s, c], -1)], axis=-2)


def rot_z(a: ArrayLike) -> NDArray[np.float64]:
    """Right-handed rotation matrix about z by angle ``a`` [rad]."""
    a = np.asarray(a, dtype=float)
    c, s, o, z = np.cos(a), np.sin(a), np.ones_like(a), np.zeros_like(a)
    return np.stack([np.stack([c, -s, z], -1), np.stack([s, c, z], -1), np.stack([z, z, o], -1)], axis=-2)


def euler_zxz_to_matrix(phi: ArrayLike, theta: ArrayLike, psi: ArrayLike) -> NDArray[np.float64]:
    """``R = Rz(phi) Rx(theta) Rz(psi)`` (body -> world), angles in rad."""
    return rot_z(phi) @ rot_x(theta) @ rot_z(psi)


def matrix_to_euler_zxz(R: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Inverse of :func:`euler_zxz_to_matrix`: ``(phi, theta, psi)`` with theta in [0, pi].

    ``theta = atan2(hypot(R13, R23), R33)``, ``phi = atan2(R13, -R23)``,
    ``psi = atan2(R31, R32)``. At the singularity ``sin(theta) == 0`` the
    convention ``psi = 0`` is used and phi carries the whole z-rotation.
    """
    R = np.asarray(R, dtype=float)
    st = np.hypot(R[..., 0, 2], R[..., 1, 2])
    theta = np.arctan2(st, R[..., 2, 2])
    phi = np.arctan2(R[..., 0, 2], -R[..., 1, 2])
    psi = np.arctan2(R[..., 2, 0], R[..., 2, 1])
    sing = st == 0.0
    if np.any(sing):
        # R = Rz(phi + psi) (theta = 0) or Rz(phi) diag(1,-1,-1) Rz(psi) (theta = pi)
        phi = np.where(sing, np.arctan2(R[..., 1, 0], R[..., 0, 0]), phi)
        psi = np.where(sing, 0.0, psi)
    return phi, theta, psi


def euler_zxz_to_quat(phi: ArrayLike, theta: ArrayLike, psi: ArrayLike) -> NDArray[np.float64]:
    """Quaternion of ``Rz(phi) Rx(theta) Rz(psi)`` (body -> world)."""
    ez = np.array([0.0, 0.0, 1.0])
    ex = np.array([1.0, 0.0, 0.0])
    return quat_mul(
        quat_mul(quat_from_axis_angle(ez, phi), quat_from_axis_angle(ex, theta)), quat_from_axis_angle(ez, psi)
    )


def euler_zxz_rates_to_omega(theta, psi, theta_dot, phi_dot, psi_dot) -> NDArray[np.float64]:
    """Body angular velocity [rad/s] from z-x-z Euler angles [rad] and rates [rad/s]."""
    st, ct, sp, cp = np.sin(theta), np.cos(theta), np.sin(psi), np.cos(psi)
    return np.stack(
        [phi_dot * st * sp + theta_dot * cp, phi_dot * st * cp - theta_dot * sp, phi_dot * ct + psi_dot], axis=-1
    )


def omega_to_euler_zxz_rates(theta, psi, omega) -> tuple:
    """Inverse of :func:`euler_zxz_rates_to_omega`: ``(theta_dot, phi_dot, psi_dot)``.

    Singular at ``sin(theta) == 0`` (raises ``ValueError`` there).
    """
    omega = np.asarray(omega, dtype=float)
    st = np.sin(theta)
    if np.any(st == 0.0):
        raise ValueError("z-x-z Euler rates are undefined at sin(theta) == 0")
    sp, cp = np.sin(psi), np.cos(psi)
    w1, w2, w3 = omega[..., 0], omega[..., 1], omega[..., 2]
    theta_dot = w1 * cp - w2 * sp
    phi_dot = (w1 * sp + w2 * cp) / st
    psi_dot = w3 - phi_dot * np.cos(theta)
    return theta_dot, phi_dot, psi_dot


def rotation_angle_between(Ra: ArrayLike, Rb: ArrayLike) -> NDArray[np.float64]:
    """Angle [rad] of the relative rotation ``Ra^T Rb`` (robust for tiny angles)."""
    Ra = np.asarray(Ra, dtype=float)
    Rb = np.asarray(Rb, dtype=float)
    D = np.swapaxes(Ra, -1, -2) @ Rb
    s = 0.5 * np.linalg.norm(
        np.stack([D[..., 2, 1] - D[..., 1, 2], D[..., 0, 2] - D[..., 2, 0], D[..., 1, 0] - D[..., 0, 1]], -1), axis=-1
    )
    c = 0.5 * (D[..., 0, 0] + D[..., 1, 1] + D[..., 2, 2] - 1.0)
    return np.arctan2(s, c)
