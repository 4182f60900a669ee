"""Inertia helpers of modelsrc against the defining integral and textbook values."""

from __future__ import annotations

import numpy as np
import pytest

from modelsrc import inertia as ti
from modelsrc.errors import ModelInputError


def test_disc_matches_lecture_notes():
    M, R = 2.0, 0.3
    I = ti.solid_disc(M, R)
    assert np.allclose(np.diag(I), [M * R**2 / 4, M * R**2 / 4, M * R**2 / 2], rtol=0, atol=1e-15)


def test_disc_against_numerical_integration_of_density():
    # I_αβ = ∫ρ (r² δ_αβ − r_α r_β) dA on a polar grid, midpoint rule in r and θ (error O(n⁻²))
    M, R, n = 1.5, 0.2, 400
    r = (np.arange(n) + 0.5) * R / n
    th = (np.arange(n) + 0.5) * 2 * np.pi / n
    rr, tt = np.meshgrid(r, th, indexing="ij")
    dm = M / (np.pi * R**2) * rr * (R / n) * (2 * np.pi / n)
    pts = np.stack([rr * np.cos(tt), rr * np.sin(tt), np.zeros_like(rr)], -1).reshape(-1, 3)
    I_num = ti.point_masses(dm.ravel(), pts)
    assert np.allclose(I_num, ti.solid_disc(M, R), rtol=1e-4, atol=1e-12)


def test_parallel_axis_shift_matches_point_masses():
    rng = np.random.default_rng(1)
    m = rng.uniform(0.1, 1.0, 6)
    x = rng.normal(size=(6, 3))
    c = m @ x / m.sum()
    I_cm = ti.point_masses(m, x - c)
    P = np.array([0.3, -0.2, 0.5])
    assert np.allclose(ti.parallel_axis_shift(I_cm, m.sum(), c - P), ti.point_masses(m, x - P), atol=1e-13)


def test_rotation_and_principal_axes():
    I = np.array([[2.0, 0.3, -0.1], [0.3, 3.0, 0.2], [-0.1, 0.2, 4.0]])
    moments, R = ti.principal_axes(I)
    assert np.linalg.det(R) == pytest.approx(1.0)
    assert np.allclose(R.T @ I @ R, np.diag(moments), atol=1e-14)
    assert np.allclose(ti.rotate_inertia(I, R.T), np.diag(moments), atol=1e-14)
    assert np.all(np.diff(moments) > 0)


def test_symmetry_plane_gives_zero_products():
    # mirror-symmetric about the x-y plane: I13 = I23 = 0
    x = np.array([[0.1, 0.2, 0.3], [0.1, 0.2, -0.3], [-0.4, 0.1, 0.2], [-0.4, 0.1, -0.2]])
    I = ti.point_masses([1, 1, 2, 2], x)
    assert I[0, 2] == 0 and I[1, 2] == 0


def test_shapes_and_validation():
    ti.validate_inertia(ti.cuboid(1, 0.1, 0.2, 0.3))
    ti.validate_inertia(ti.solid_sphere(1, 0.1))
    ti.validate_inertia(ti.solid_cylinder(1, 0.1, 0.5))
    with pytest.raises(ModelInputError, match="positive definite"):
        ti.validate_inertia(ti.thin_rod(1, 1))  # I33 = 0: not a body on its own
    with pytest.raises(ModelInputError, match="principal moments"):
        ti.validate_inertia([[1, 0, 0], [0, 1, 0], [0, 0, 2.5]])
    # a rotated valid tensor stays valid, a rotated invalid one is caught through the full-tensor test
    R = ti.principal_axes(np.array([[2.0, 0.3, 0], [0.3, 1.0, 0.1], [0, 0.1, 3.0]]))[1]
    ti.validate_inertia(ti.rotate_inertia(np.diag([1.0, 2.0, 3.0]), R))
    with pytest.raises(ModelInputError, match="I_i \\+ I_j >= I_k"):
        ti.validate_inertia(ti.rotate_inertia(np.diag([1.0, 2.0, 3.1]), R))
