"""Alias until 0.5.0 (CHANGELOG.md): the code lives in rbcheck/numerics/rotation_np.py."""

from rbcheck.numerics.rotation_np import (
    euler_zxz_rates_to_omega,
    euler_zxz_to_matrix,
    euler_zxz_to_quat,
    matrix_to_euler_zxz,
    matrix_to_quat,
    omega_to_euler_zxz_rates,
    quat_conj,
    quat_from_axis_angle,
    quat_mul,
    quat_normalize,
    quat_to_matrix,
    rot_x,
    rot_z,
    rotation_angle_between,
    skew,
)

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
