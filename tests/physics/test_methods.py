"""The integrators inside the FMU: observed order against the closed form, and the invariants they keep.

The invariants each method preserves by construction: docs/theory.md §5."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fmu.drive.instance import FmuError, FmuInstance
from fmu.drive.run import run_fmu
from modelsrc.methods import METHODS
from modelsrc.scene import load_scene
from rbcheck.closed_forms import free_symmetric

from ..harness.stepping import fixed_steps

EPS = np.finfo(float).eps

# method: (order, two internal steps h with errors well above round-off, comm. step);
# h·|ω| (|ω| = 2.04) stays within each method's rotation limit (docs/theory.md §5.4), so
# the FMU takes exactly these steps
LADDER = {
    "rk4": (4, 0.05, 0.025, 0.2),
    "rk8": (8, 0.2, 0.1, 0.2),
    "implicit_midpoint": (2, 0.02, 0.01, 0.2),
    "gauss4": (4, 0.1, 0.05, 0.2),
    "gauss6": (6, 0.2, 0.1, 0.2),
    "splitting": (2, 0.02, 0.01, 0.2),
}


def omega_error(fmu, method: str, h: float, step: float, T: float = 10.0) -> float:
    sc = load_scene("symmetric_free")
    res = run_fmu(fmu, sc, stop_time=T, step=step, start_values=fixed_steps(h, method))
    w_ref, _ = free_symmetric.solve(1.0, 1.6, sc.w0, sc.q0, np.array([T]))
    return float(np.max(np.abs(res.vector("w_body")[-1] - w_ref[0])))


@pytest.mark.parametrize("method", list(LADDER))
def test_observed_order(fmus, method):
    order, h1, h2, step = LADDER[method]
    e1, e2 = (
        omega_error(fmus["symmetric_free"], method, h1, step),
        omega_error(fmus["symmetric_free"], method, h2, step),
    )
    p = math.log2(e1 / e2)
    print(f"\n{method}: e({h1})={e1:.3e}, e({h2})={e2:.3e}, observed order {p:.2f}")
    # log2(e(h)/e(h/2)) = order + O(h|ω|): the ladder keeps h|ω| <= 0.41, so within ±6 %
    assert abs(p - order) < 0.06 * order


@pytest.mark.parametrize("method", ["implicit_midpoint", "gauss4", "gauss6"])
def test_gauss_methods_keep_quadratic_invariants(fmus, method):
    sc = load_scene("free_asymmetric")
    h = 0.05  # large: RK4 drifts visibly at this step
    res = run_fmu(
        fmus["free_asymmetric"],
        sc,
        stop_time=30.0,
        step=0.5,
        start_values=fixed_steps(h, method),
    )
    E, L = res.values["E_kin"], res.vector("L_world")
    dE = np.max(np.abs(E - E[0])) / E[0]
    dL = np.max(np.abs(np.linalg.norm(L, axis=1) - np.linalg.norm(L[0]))) / np.linalg.norm(L[0])
    print(f"\n{method} h={h}: E drift {dE:.2e}, |L| drift {dL:.2e} over {30 / h:.0f} steps")
    # exact up to the Newton tolerance (1e-14 on the stage increments) and round-off
    # accumulated over 600 steps (~ sqrt(600)·eps·cond): 1e-13
    assert dE < 1e-13 and dL < 1e-13


def test_rk4_drifts_where_gauss_does_not(fmus):
    sc = load_scene("free_asymmetric")
    res = run_fmu(fmus["free_asymmetric"], sc, stop_time=30.0, step=0.5, start_values=fixed_steps(0.05, "rk4"))
    E = res.values["E_kin"]
    assert np.max(np.abs(E - E[0])) / E[0] > 1e-9  # so the Gauss test above could fail


def test_splitting_keeps_norm_of_L_and_bounds_energy(fmus):
    sc = load_scene("free_asymmetric")
    res = run_fmu(
        fmus["free_asymmetric"],
        sc,
        stop_time=60.0,
        step=0.5,
        start_values={"h_max": 0.05, "method": METHODS["splitting"].value},
    )
    E, L = res.values["E_kin"], res.vector("L_world")
    nL = np.linalg.norm(L, axis=1)
    assert np.max(np.abs(nL - nL[0])) / nL[0] < 100 * EPS  # axis rotations are exact isometries
    dE = np.abs(E - E[0]) / E[0]
    half = len(E) // 2
    # symplectic: the energy error oscillates, it does not grow: the second half is no worse
    assert dE[half:].max() < 1.5 * dE[:half].max()


def test_unknown_method_is_refused_with_the_allowed_list(fmus):
    with FmuInstance(fmus["symmetric_free"]) as inst:
        with pytest.raises(FmuError, match=r"method 42 is not compiled into this FMU; allowed: 1=rk4, 2=rk8"):
            inst.set({"method": 42})


def test_splitting_needs_centre_of_mass_on_a_body_axis(fmus):
    with FmuInstance(fmus["heavy_top"]) as inst:
        inst.set({"method": METHODS["splitting"].value, "r_cm[1]": 0.01})
        with pytest.raises(FmuError, match="splitting needs principal axes"):
            inst.initialize()
    with FmuInstance(fmus["heavy_top"]) as inst:  # the same r_cm is fine for rk4
        inst.set({"r_cm[1]": 0.01})
        inst.initialize()
        inst.do_step(1e-3)


@pytest.mark.parametrize("scene, I", [("free_asymmetric", (1.0, 2.0, 3.0)), ("symmetric_free", (1.0, 1.0, 1.6))])
def test_exact_free_flow_is_exact_at_any_step(fmus, scene, I):
    """Torque-free: the exact flow (Celledoni et al. 2008) in one doStep of the whole
    horizon agrees with the closed form to round-off, with no sub-steps (h_max = T)."""
    from rbcheck.closed_forms import free_asymmetric

    sc = load_scene(scene)
    T = 20.0
    res = run_fmu(
        fmus[scene], sc, stop_time=T, step=T, start_values={"method": METHODS["exact_free"].value, "h_max": T}
    )
    assert res.n_steps == 1
    if I[0] == I[1]:
        w_ref, q_ref = free_symmetric.solve(I[0], I[2], sc.w0, sc.q0, np.array([T]))
    else:
        w_ref, _q_ref = free_asymmetric.solve(np.array(I), sc.w0, sc.q0, np.array([T]))
    err = float(np.max(np.abs(res.vector("w_body")[-1] - w_ref[0])))
    # one evaluation of the flow: round-off of the elliptic phase, ~eps·|ω|T ≈ 1e-14; the
    # tennis-racket amplification e^{λT} of accumulated errors does not arise in one step
    assert err < 1e-12, err
    print(f"\n{scene}: one exact step of {T} s, |dw| = {err:.2e}")


def test_exact_free_with_torques_is_second_order(fmus):
    """With gravity, kick - exact free flow - kick is order 2 (Strang splitting)."""
    sc = load_scene("heavy_top")
    T = 0.2

    def final_w(method: str, h: float):
        r = run_fmu(fmus["heavy_top"], sc, stop_time=T, step=0.01, start_values=fixed_steps(h, method))
        return r.vector("w_body")[-1]

    ref = final_w("rk8", 1e-5)  # rk8: error ~ T·ω·(hω)⁸ ≈ 1e-20, round-off only
    e1 = np.abs(final_w("exact_free", 1e-3) - ref).max()
    e2 = np.abs(final_w("exact_free", 5e-4) - ref).max()
    p = math.log2(e1 / e2)
    print(f"\nheavy_top exact_free: e(1e-3)={e1:.3e}, e(5e-4)={e2:.3e}, order {p:.2f}")
    assert abs(p - 2) < 0.12  # Strang: 2 + O(h); h·|ω| = 0.15 and 0.075
