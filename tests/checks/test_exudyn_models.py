"""Exudyn multibody models of the scenes (rbcheck.exudyn.models) against a scipy ODE.

The reference here is self-contained: Euler's equations about the pivot (gravity scenes)
or the centre of mass, plus quaternion kinematics q̇ = ½ q ⊗ (0, ω), integrated by
scipy's DOP853 at rtol = atol = 1e-12, piecewise between input switching times. The
Exudyn side uses its own formulation (rigid-body node, spherical joint, loads,
connector) and its own integrators. The inertia checks compare modelsrc.inertia with
Exudyn's RigidBodyInertia utilities.
"""

from __future__ import annotations

import dataclasses
import itertools

import exudyn as exu
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from modelsrc import inertia as mi
from modelsrc.scene import load_scene
from rbcheck.exudyn import models as ex
from rbcheck.numerics.rotation_np import quat_mul

# ----------------------------------------------------------------------------------
# self-contained reference ODE
# ----------------------------------------------------------------------------------


_qmul = quat_mul  # rbcheck.numerics.rotation_np: the numpy quaternion product, tested in test_quaternion.py


def _R(q):
    """Rotation matrix body -> world of a (normalised) scalar-first quaternion."""
    w, x, y, z = np.asarray(q) / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def _held(v, t):
    """Scene input at time t: a constant (3,) or table rows [t, x, y, z] held from each t."""
    v = np.asarray(v, dtype=float)
    if v.ndim == 1:
        return v
    return v[max(int(np.searchsorted(v[:, 0], t, side="right")) - 1, 0), 1:]


def _rhs_factory(scene):
    """Right-hand side f(t, y, tau_body, tau_world) of y = (q, ω_body)."""
    grav = scene.has("gravity")
    m = scene.mass if grav else 0.0
    r = np.asarray(scene.r_cm) if grav else np.zeros(3)
    g = np.asarray(scene.g) if grav else np.zeros(3)
    c = scene.c_friction if scene.has("friction") else 0.0
    Ip = scene.inertia + m * (r @ r * np.eye(3) - np.outer(r, r))  # about the pivot (parallel axes)
    Ip_inv = np.linalg.inv(Ip)

    def rhs(t, y, tb, tw):
        q, w = y[:4], y[4:]
        Rm = _R(q)
        M = np.cross(r, Rm.T @ (m * g)) - c * w + tb + Rm.T @ tw  # weight, friction, inputs (body)
        return np.concatenate([0.5 * _qmul(q, np.r_[0.0, w]), Ip_inv @ (M - np.cross(w, Ip @ w))])

    return rhs


def _integrate(rhs, y0, a, b, tb, tw, t_eval):
    """DOP853 from a to b; returns (y at t_eval (k, 7), y(b))."""
    te = np.unique(np.r_[t_eval, b])
    sol = solve_ivp(rhs, (a, b), y0, method="DOP853", rtol=1e-12, atol=1e-12, t_eval=te, args=(tb, tw))
    assert sol.success and sol.t[-1] == b
    return sol.y.T[np.isin(te, t_eval)], sol.y[:, -1]


def reference(scene, ts, torque=None, breaks=()):
    """scipy solution at times ts: (w_body (n,3), R (n,3,3)).

    torque(t) -> (tau_body, tau_world) (N m), constant between consecutive `breaks`.
    """
    rhs = _rhs_factory(scene)
    edges = sorted({float(ts[0]), float(ts[-1]), *[b for b in breaks if ts[0] < b < ts[-1]]})
    y = np.r_[scene.q0, scene.w0]
    Y = np.empty((len(ts), 7))
    for a, b in itertools.pairwise(edges):
        tb, tw = torque(a) if torque is not None else (np.zeros(3), np.zeros(3))
        sel = (ts >= a) & (ts <= b)
        Y[sel], y = _integrate(rhs, y, a, b, tb, tw, ts[sel])
    return Y[:, 4:], np.array([_R(q) for q in Y[:, :4]])


def errors(res, W, Rref):
    """Max |Δω| (rad/s) and max |ΔR| (entries of the rotation matrix) over all samples."""
    R_ex = np.array([_R(q) for q in res["q"]])
    return float(np.abs(res["w_body"] - W).max()), float(np.abs(R_ex - Rref).max())


# ----------------------------------------------------------------------------------
# free bodies
# ----------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["free_asymmetric", "symmetric_free"])
def test_free_body_rk67_matches_scipy_and_conserves(name):
    sc = load_scene(name)
    # power-of-two steps: the communication points are hit exactly
    res = ex.simulate_scene(sc, stop_time=4.0, step=2.0**-4, solver="RK67", h=2.0**-7)
    assert res["model"] == "free" and res["n_steps"] == 512
    W, Rref = reference(sc, res["time"])
    ew, eR = errors(res, W, Rref)
    # measured 4e-13 / 1e-12 (asymmetric), 6e-13 / 3e-12 (symmetric): the scipy side dominates
    assert ew < 1e-9 and eR < 1e-9, (ew, eR)
    E, L = res["E_kin"], res["L_world"]
    assert np.abs(E - E[0]).max() <= 1e-12 * E[0]  # measured 1e-14
    assert np.abs(L - L[0]).max() <= 1e-12 * np.linalg.norm(L[0])  # measured 3e-14
    nL = np.linalg.norm(res["L_body"], axis=1)
    assert np.abs(nL - nL[0]).max() <= 1e-12 * nL[0]
    # outputs are consistent with each other
    q = res["q"]
    assert np.allclose(q[0], sc.q0, atol=1e-15) and np.allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-14)
    assert np.all(np.einsum("ij,ij->i", q[1:], q[:-1]) > 0)  # sign-continuous
    Rq = np.array([_R(x) for x in q])
    assert np.abs(np.einsum("nij,nj->ni", Rq, res["w_body"]) - res["w_world"]).max() < 1e-14
    assert np.abs(res["L_body"] - res["w_body"] @ sc.inertia).max() < 1e-13  # about the CM, I symmetric


@pytest.mark.parametrize("name", ["free_asymmetric", "symmetric_free"])
def test_free_body_rk67_matches_closed_forms(name):
    """rbcheck's closed forms (Jacobi elliptic / precession) are sharper than scipy at 1e-12."""
    from rbcheck.closed_forms import free_asymmetric, free_symmetric

    sc = load_scene(name)
    res = ex.simulate_scene(sc, stop_time=10.0, step=2.0**-4, solver="RK67", h=2.0**-7, record_every=4)
    t = res["time"]
    assert np.allclose(np.diff(t), 0.25) and t[-1] == 10.0
    I = np.diag(sc.inertia)
    if name == "free_asymmetric":
        w, q = free_asymmetric.solve(I, sc.w0, sc.q0, t)
    else:
        w, q = free_symmetric.solve(I[0], I[2], sc.w0, sc.q0, t)
    ew, eR = errors(res, w, np.array([_R(x) for x in q]))
    assert ew < 1e-12 and eR < 1e-12, (ew, eR)  # measured 3e-14 / 5e-14 (asymmetric)


@pytest.mark.parametrize(
    "solver, h, tol", [("RK44", 2.0**-10, 1e-9), ("DOPRI5", 2.0**-6, 1e-9), ("TrapezoidalIndex2", 2.0**-12, 1e-8)]
)
def test_free_asymmetric_other_solvers(solver, h, tol):
    sc = load_scene("free_asymmetric")
    res = ex.simulate_scene(sc, stop_time=4.0, step=2.0**-4, solver=solver, h=h)
    ew, eR = errors(res, *reference(sc, res["time"]))
    # measured: RK44 4e-13/1e-12, DOPRI5 (rtol=atol=1e-10) 4e-13/1e-12, trapezoidal (2nd order) 1.5e-10/2.5e-10
    assert ew < tol and eR < tol, (ew, eR)


def test_chunked_run_equals_one_solve_dynamic():
    """Co-simulation stepping (SolveSteps per communication step) = one SolveDynamic run."""
    sc = load_scene("free_asymmetric")
    T, h = 4.0, 2.0**-7
    chunked = ex.simulate_scene(sc, stop_time=T, step=2.0**-4, solver="RK67", h=h)
    one = ex.simulate_scene(sc, stop_time=T, step=T, solver="RK67", h=h)
    mdl = ex.build_exudyn_model(sc)
    ss = ex.exudyn_settings("RK67")
    ss.timeIntegration.endTime, ss.timeIntegration.numberOfSteps = T, int(T / h)
    exu.SolveDynamic(mdl.mbs, ss, solverType=exu.DynamicSolverType.RK67)
    direct = mdl.outputs()
    for key in ("w_body", "L_world"):
        assert np.array_equal(chunked[key][-1], one[key][-1])  # bit-identical
        assert np.array_equal(chunked[key][-1], direct[key])
    # q is sign-continuous along the recorded samples; one-chunk runs see no samples in between
    sign = np.sign(chunked["q"][-1] @ direct["q"])
    assert np.array_equal(chunked["q"][-1], sign * direct["q"]) and np.array_equal(direct["q"], one["q"][-1])


@pytest.mark.parametrize("solver, tol", [("TrapezoidalIndex2", 1e-9), ("GeneralizedAlpha", 1e-8)])
def test_implicit_chunked_run_equals_one_chunk(solver, tol):
    """Implicit solvers restarted every communication step: same steps, Newton-level differences."""
    sc = load_scene("heavy_top")
    T, h = 3 * 2.0**-4, 2.0**-16
    a = ex.simulate_scene(sc, stop_time=T, step=2.0**-10, solver=solver, h=h)
    b = ex.simulate_scene(sc, stop_time=T, step=T, solver=solver, h=h)
    assert a["n_steps"] == b["n_steps"] == 12288
    # measured 2e-11 (trapezoidal) and 1.7e-10 (generalized-α) rad/s at ω3 = 150 rad/s
    assert np.abs(a["w_body"][-1] - b["w_body"][-1]).max() < tol


def test_no_files_written(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    ex.simulate_scene(load_scene("symmetric_free"), stop_time=0.5, solver="RK67")
    ex.simulate_scene(load_scene("heavy_top"), stop_time=0.01, solver="TrapezoidalIndex2")
    assert list(tmp_path.iterdir()) == []


# ----------------------------------------------------------------------------------
# heavy top (spins at 150 rad/s: h ω sets the error)
# ----------------------------------------------------------------------------------
def _conserved_heavy_top(res, sc, rel):
    E, Lw, Lb = res["E_total"], res["L_world"], res["L_body"]
    assert np.abs(E - E[0]).max() <= rel * abs(E[0])
    # p_φ = L·e_z (world) and p_ψ = L·e3 (body) are conserved for the symmetric top
    assert np.abs(Lw[:, 2] - Lw[0, 2]).max() <= rel * np.linalg.norm(Lw[0])
    assert np.abs(Lb[:, 2] - Lb[0, 2]).max() <= rel * np.linalg.norm(Lw[0])


@pytest.mark.parametrize(
    "solver, h, tol_w, tol_R",
    [
        # 6th-order RK67 at h ω = 0.037: measured |Δω| 6e-11 rad/s (of 150), |ΔR| 4e-12
        ("RK67", 2.0**-12, 1e-9, 1e-10),
        # 4th-order RK44 at h ω = 0.009: measured 2.6e-9 / 1.5e-10
        ("RK44", 2.0**-14, 2e-8, 2e-9),
    ],
)
def test_heavy_top_explicit_pivot_model(solver, h, tol_w, tol_R):
    sc = load_scene("heavy_top")
    res = ex.simulate_scene(sc, stop_time=0.2, step=2.0**-10, solver=solver, h=h)
    assert res["model"] == "pivot"
    ew, eR = errors(res, *reference(sc, res["time"]))
    assert ew < tol_w and eR < tol_R, (ew, eR)
    _conserved_heavy_top(res, sc, 1e-11)  # measured E: 6e-15 J of 0.63 J


@pytest.mark.parametrize(
    "solver, node_type, tol_w, tol_R",
    [
        # 2nd-order implicit integrators at h = 2^-16 s (h ω = 2.3e-3): measured |Δω| 2.7e-6 / 1.8e-6
        # rad/s and |ΔR| 9e-8 / 8e-8 (Lie-group node), 1.2e-5 / 1.5e-5 and 3.3e-6 (Euler parameters)
        ("TrapezoidalIndex2", "RotVecLG", 1e-5, 1e-6),
        ("GeneralizedAlpha", "RotVecLG", 1e-5, 1e-6),
        ("TrapezoidalIndex2", "EulerParameters", 5e-5, 1e-5),
    ],
)
def test_heavy_top_implicit_jointed_model(solver, node_type, tol_w, tol_R):
    sc = load_scene("heavy_top")
    runs = {}
    for k in (14, 16):
        res = ex.simulate_scene(sc, stop_time=0.2, step=2.0**-10, solver=solver, h=2.0**-k, node_type=node_type)
        assert res["model"] == "joint"
        runs[k] = errors(res, *reference(sc, res["time"]))
    ew, eR = runs[16]
    assert ew < tol_w and eR < tol_R, runs
    # second order: 4x smaller step -> ~16x smaller error (measured 15-16)
    assert runs[14][0] / ew > 10 and runs[14][1] / eR > 10, runs
    _conserved_heavy_top(res, sc, 1e-7)  # index-2/3: measured 2e-9 J


def test_heavy_top_models_agree_on_energy_and_momentum_outputs():
    """Pivot model (inertia shifted by Exudyn, weight at r_cm) and jointed model (CM node +
    spherical joint + mass-proportional load) give the same outputs about the pivot."""
    sc = load_scene("heavy_top")
    a = ex.simulate_scene(sc, stop_time=0.05, step=2.0**-10, solver="RK67", h=2.0**-12)
    b = ex.simulate_scene(sc, stop_time=0.05, step=2.0**-10, solver="GeneralizedAlpha", h=2.0**-16)
    for key, tol in (("E_kin", 1e-8), ("E_total", 1e-8), ("L_world", 1e-7), ("L_body", 1e-7), ("w_world", 1e-5)):
        assert np.abs(a[key] - b[key]).max() < tol, key
    # E_total = E_kin + M g l cos θ, θ0 = 0.3
    assert abs(a["E_total"][0] - a["E_kin"][0] - 0.5 * 9.81 * 0.04 * np.cos(0.3)) < 1e-15


@pytest.mark.parametrize("friction", ["connector", "user"])
def test_sleeping_top_friction(friction):
    sc = load_scene("sleeping_top")
    res = ex.simulate_scene(sc, stop_time=0.5, step=2.0**-10, solver="RK67", h=2.0**-13, friction=friction)
    ew, eR = errors(res, *reference(sc, res["time"]))
    assert ew < 1e-9 and eR < 1e-10, (ew, eR)  # measured 3e-11 / 3e-11
    # the spin decays as exp(-c t / I3) (ω3 is decoupled: I1 = I2 about the pivot)
    w3 = sc.w0[2] * np.exp(-sc.c_friction * res["time"] / sc.inertia[2, 2])
    assert np.abs(res["w_body"][:, 2] - w3).max() < 1e-9


# ----------------------------------------------------------------------------------
# torque inputs
# ----------------------------------------------------------------------------------
def _scene_torque(sc):
    return lambda t: (_held(sc.inputs["tau_body"], t), _held(sc.inputs["tau_world"], t))


def test_torque_driven_tables_match_scipy():
    sc = load_scene("torque_driven")
    res = ex.simulate_scene(sc, solver="RK67")  # scene: 8 s, step 0.01 s, h = h_max = 1e-3 s
    breaks = [t for v in sc.inputs.values() for t in v[:, 0]]
    W, Rref = reference(sc, res["time"], _scene_torque(sc), breaks)
    ew, eR = errors(res, W, Rref)
    assert ew < 1e-10 and eR < 1e-9, (ew, eR)
    t = res["time"]
    first = t <= 2.0  # tau_body = (0, 0, 0.3) N m from rest: ω3 = 0.1 t exactly (constant ω̇)
    assert np.abs(res["w_body"][first, 2] - 0.1 * t[first]).max() < 1e-13
    assert np.all(res["w_body"][first, :2] == 0.0)
    assert {2.0, 4.0, 6.0} <= set(t)


def test_input_fn_reproducing_the_tables_gives_the_same_run():
    sc = load_scene("torque_driven")
    tables = ex.simulate_scene(sc, stop_time=5.0, solver="RK44")
    tq = _scene_torque(sc)

    def fn(t, y):
        tb, tw = tq(t)
        return {**{f"tau_body[{k + 1}]": tb[k] for k in range(3)}, **{f"tau_world[{k + 1}]": tw[k] for k in range(3)}}

    closed = ex.simulate_scene(sc, stop_time=5.0, solver="RK44", input_fn=fn)
    assert np.array_equal(tables["time"], closed["time"])
    assert np.array_equal(tables["w_body"], closed["w_body"]) and np.array_equal(tables["q"], closed["q"])


def test_closed_loop_input_fn_zero_order_hold():
    """input_fn sees the outputs at t_k; the torque it returns is held on [t_k, t_k+1)."""
    sc = dataclasses.replace(load_scene("torque_driven"), w0=np.array([0.3, -0.5, 0.8]))
    k_fb, H, T = 0.5, 2.0**-5, 1.0
    tw = np.array([0.0, 0.0, 0.1])
    seen = []

    def fn(t, y):
        seen.append(t)
        return {f"tau_body[{i}]": -k_fb * y[f"w_body[{i}]"] for i in (1, 2, 3)} | {"tau_world[3]": tw[2]}

    res = ex.simulate_scene(sc, stop_time=T, step=H, solver="RK67", h=2.0**-8, input_fn=fn)
    ts = res["time"]
    assert seen == list(ts[:-1])
    # reference: the same zero-order hold, scipy on each communication interval
    rhs = _rhs_factory(sc)
    Y = np.empty((len(ts), 7))
    Y[0] = np.r_[sc.q0, sc.w0]
    for i in range(len(ts) - 1):
        _, Y[i + 1] = _integrate(rhs, Y[i], ts[i], ts[i + 1], -k_fb * Y[i, 4:], tw, [])
    ew, eR = errors(res, Y[:, 4:], np.array([_R(q) for q in Y[:, :4]]))
    assert ew < 1e-10 and eR < 1e-10, (ew, eR)  # measured ~1e-13


# ----------------------------------------------------------------------------------
# inertia: modelsrc.inertia vs Exudyn's RigidBodyInertia
# ----------------------------------------------------------------------------------
def _rel(a, b):
    return float(np.abs(np.asarray(a) - np.asarray(b)).max() / np.abs(b).max())


_A = np.array([[2.0, 0.3, -0.1], [0.3, 1.5, 0.2], [-0.1, 0.2, 1.8]])  # a full inertia tensor (kg m^2)


def _rot(a, b, c):
    """Rotation matrix Rz(a) Rx(b) Rz(c)."""

    def rz(x):
        return np.array([[np.cos(x), -np.sin(x), 0], [np.sin(x), np.cos(x), 0], [0, 0, 1.0]])

    rx = np.array([[1.0, 0, 0], [0, np.cos(b), -np.sin(b)], [0, np.sin(b), np.cos(b)]])
    return rz(a) @ rx @ rz(c)


@pytest.mark.parametrize(
    "ours, theirs",
    [
        (lambda: mi.solid_disc(0.5, 0.03), lambda: ex.exudyn_inertia("disc", 0.5, 0.03)),
        (lambda: mi.solid_cylinder(2.3, 0.07, 0.4), lambda: ex.exudyn_inertia("cylinder", 2.3, 0.07, 0.4)),
        (lambda: mi.cuboid(1.7, 0.3, 0.2, 0.05), lambda: ex.exudyn_inertia("cuboid", 1.7, 0.3, 0.2, 0.05)),
        (lambda: mi.solid_sphere(3.1, 0.12), lambda: ex.exudyn_inertia("sphere", 3.1, 0.12)),
        (
            lambda: mi.point_masses([0.3, 1.2, 0.7], [[0.1, -0.2, 0.3], [-0.4, 0.1, 0.05], [0.2, 0.25, -0.15]]),
            lambda: ex.exudyn_inertia(
                "point_masses", [0.3, 1.2, 0.7], [[0.1, -0.2, 0.3], [-0.4, 0.1, 0.05], [0.2, 0.25, -0.15]]
            ),
        ),
        (
            lambda: mi.parallel_axis_shift(_A, 0.8, [0.1, -0.3, 0.2]),
            lambda: ex.exudyn_inertia("translated", _A, 0.8, [0.1, -0.3, 0.2]),
        ),
        (
            lambda: mi.parallel_axis_shift(mi.solid_disc(0.5, 0.03), 0.5, [0.0, 0.0, 0.04]),
            lambda: ex.exudyn_inertia("translated", ex.exudyn_inertia_disc(0.5, 0.03), 0.5, [0.0, 0.0, 0.04]),
        ),
        (
            lambda: mi.rotate_inertia(_A, _rot(0.3, 1.1, -0.7)),
            lambda: ex.exudyn_inertia("rotated", _A, _rot(0.3, 1.1, -0.7)),
        ),
    ],
    ids=["disc", "cylinder", "cuboid", "sphere", "point_masses", "parallel_axis", "heavy_top_pivot", "rotation"],
)
def test_inertia_helpers_match_exudyn(ours, theirs):
    assert _rel(ours(), theirs()) <= 1e-14  # measured <= 2e-16


def test_principal_axes_diagonalise_in_exudyn():
    moments, A = mi.principal_axes(_A)
    assert _rel(ex.exudyn_inertia_rotated(_A, A.T), np.diag(moments)) <= 1e-14
    assert _rel(ex.exudyn_inertia_rotated(np.diag(moments), A), _A) <= 1e-14


def test_heavy_top_scene_is_an_exudyn_disc():
    sc = load_scene("heavy_top")
    assert _rel(sc.inertia, ex.exudyn_inertia_disc(sc.mass, 0.03)) <= 1e-14


def test_bad_arguments_are_refused():
    sc = load_scene("heavy_top")
    with pytest.raises(ValueError, match="explicit solvers cannot"):
        ex.simulate_scene(sc, solver="RK67", model="joint")
    with pytest.raises(ValueError, match="implicit solver"):
        ex.simulate_scene(sc, solver="RK44", node_type="EulerParameters")
    with pytest.raises(ValueError, match="unknown solver"):
        ex.simulate_scene(sc, solver="Euler")
    with pytest.raises(ValueError, match="step"):
        ex.simulate_scene(sc, step=0.0)
