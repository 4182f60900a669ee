"""Quaternion kinematics and the z-x-z Euler-angle outputs."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from modelsrc.quaternion import euler_zxz, quat_derivative, quat_from_euler_zxz, quat_mul, rotation_matrix
from rbcheck.numerics.rotation_np import euler_zxz_to_matrix, quat_to_matrix
from rbcheck.numerics.rotation_np import quat_mul as quat_mul_np

q_sym = ca.SX.sym("q", 4)
w_sym = ca.SX.sym("w", 3)
R_fun = ca.Function("R", [q_sym], [rotation_matrix(q_sym)])
E_fun = ca.Function("E", [q_sym], [euler_zxz(rotation_matrix(q_sym))])
qd_fun = ca.Function("qd", [q_sym, w_sym], [quat_derivative(q_sym, w_sym)])


@pytest.mark.parametrize("angles", [(0.3, 1.1, -2.0), (-3.0, 0.01, 2.5), (1.0, 3.1, 0.2), (2.0, 1e-7, 0.5)])
def test_euler_round_trip(angles):
    q = quat_from_euler_zxz(*angles)
    # rotation matrix of the quaternion = Rz(φ) Rx(θ) Rz(ψ) (independent numpy construction)
    assert np.allclose(np.array(R_fun(q)), euler_zxz_to_matrix(*angles), atol=1e-15)
    assert np.allclose(np.array(E_fun(q)).ravel(), angles, atol=1e-9)


@pytest.mark.parametrize("q", [[1, 0, 0, 0], [0, 1, 0, 0], quat_from_euler_zxz(0.7, 0.0, 0.4)])
def test_euler_outputs_finite_at_singularity(q):
    e = np.array(E_fun(np.asarray(q, float))).ravel()
    assert np.all(np.isfinite(e))
    R = euler_zxz_to_matrix(*e)
    assert np.allclose(R, np.array(R_fun(np.asarray(q, float))), atol=1e-12)  # same rotation


def test_kinematics_is_body_frame():
    # Ṙ = R [ω]× for body-frame ω: compare q̇ with a finite difference of R
    q = quat_from_euler_zxz(0.3, 0.8, -0.4)
    w = np.array([0.3, -1.2, 0.7])
    qd = np.array(qd_fun(q, w)).ravel()
    h = 1e-7
    Rd = (np.array(R_fun(q + h * qd)) - np.array(R_fun(q - h * qd))) / (2 * h)
    R = np.array(R_fun(q))
    W = np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])
    assert np.allclose(Rd, R @ W, atol=1e-8)


def test_quaternion_products_compose_rotations():
    # The model's product (CasADi) and the checks' product (numpy) are the same Hamilton
    # product: R(p ⊗ q) = R(p) R(q), and both agree to round-off.
    p_sym, r_sym = ca.SX.sym("p", 4), ca.SX.sym("r", 4)
    mul = ca.Function("mul", [p_sym, r_sym], [quat_mul(p_sym, r_sym)])
    p = quat_from_euler_zxz(0.3, 1.1, -2.0)
    r = quat_from_euler_zxz(-1.0, 0.4, 0.9)
    pr = np.array(mul(p, r)).ravel()
    assert np.allclose(pr, quat_mul_np(p, r), atol=1e-15)
    assert np.allclose(quat_to_matrix(pr), quat_to_matrix(p) @ quat_to_matrix(r), atol=1e-14)
    assert np.allclose(np.array(R_fun(pr)), np.array(R_fun(p)) @ np.array(R_fun(r)), atol=1e-14)
