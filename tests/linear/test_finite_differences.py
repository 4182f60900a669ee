"""Every shipped scene's A, B, C, D against central differences of the FMU, and Φ, Γ against differences of doStep.

The agreement asked is the difference's own error (fmu.linear.finite_differences.fd_error:
the truncation term estimated from the differences at h and 2h, plus round-off of a few
ε|f|/h), times 4 for the estimate's own looseness: far below any error in a column of the
exact Jacobian, which would be of the size of the entry.
"""

from __future__ import annotations

import numpy as np
import pytest

from fmu.drive.instance import FmuInstance
from fmu.linear.attitude import chart
from fmu.linear.finite_differences import chart_differences, fd_error, raw_differences
from fmu.linear.linearize import linearize
from fmu.linear.model_exchange import ModelExchange
from fmu.linear.operating_point import start_point
from fmu.linear.step_map import step_map
from modelsrc.errors import ModelInputError
from modelsrc.scene import list_scenes, load_scene

SCENES = list_scenes()
REL = 1e-5  # the differences' step relative to each variable's scale: truncation ~1e-10, round-off ~1e-11


def assert_within(exact: np.ndarray, J_h: np.ndarray, J_2h: np.ndarray, f_scale: np.ndarray, h: np.ndarray, what):
    err = fd_error(J_h, J_2h, f_scale, h)
    bad = np.abs(exact - J_h) > 4 * err
    assert not bad.any(), (what, np.argwhere(bad)[:5], (exact - J_h)[bad][:5], err[bad][:5])


@pytest.mark.parametrize("scene", SCENES)
def test_linearisation_against_central_differences(fmus, scene):
    fmu = fmus[scene]
    point = start_point(fmu)
    with ModelExchange(fmu) as me:
        ins, outs = list(me.inputs), list(me.outputs)
        if "euler_zxz[2]" in outs:
            me.set_states(point.x)
            theta = me.get(me.value_references(["euler_zxz[2]"], outs, "outputs"))[0]
            if min(theta, np.pi - theta) < 1e-3:  # φ, ψ are singular at θ = 0 (docs/theory.md §1.3): no derivative
                outs = [o for o in outs if not o.startswith("euler_zxz")]
        raw = linearize(fmu, point, outputs=outs, coordinates="raw", instance=me)
        exact = np.block([[raw.A, raw.B], [raw.C, raw.D]])
        J_h, f0 = raw_differences(me, point, ins, outs, REL)
        J_2h, _ = raw_differences(me, point, ins, outs, 2 * REL)
        scale = np.concatenate((np.maximum(np.abs(point.x), me.nominals), np.maximum(np.abs(point.u), 1.0)))
        assert_within(exact, J_h, J_2h, np.abs(f0) + np.abs(exact) @ scale, REL * scale, f"{scene} raw")
        m = linearize(fmu, point, outputs=outs, instance=me)
        ch = chart(me.states, point.x, "rotating")
        exact = np.block([[m.A, m.B], [m.C, m.D]])
        Z_h = chart_differences(me, point, ch, ins, outs, m.nominals, REL)
        Z_2h = chart_differences(me, point, ch, ins, outs, m.nominals, 2 * REL)
        zscale = np.concatenate((m.nominals, np.maximum(np.abs(point.u), 1.0)))
        f_scale = np.abs(np.concatenate((m.drift, f0[me.nx :]))) + np.abs(exact) @ zscale
        assert_within(exact, Z_h, Z_2h, f_scale, REL * zscale, f"{scene} attitude error")


def do_step(fmu, scene, point, H, n, method, x, inputs):
    """The states after one doStep of H from x (fixed steps: tolerance 0, h_max = H/n)."""
    with FmuInstance(fmu) as inst:
        inst.set({**dict(zip(point.states, x)), **inputs, "tolerance": 0.0, "h_max": H / n,
                  "method": inst.method_values[method]})  # fmt: skip
        inst.initialize(0.0)
        inst.step(0.0, H)
        assert inst.get(["internal_steps"])[0] == n  # the same internal steps as the step map
        return inst.get(list(point.states))


@pytest.mark.parametrize("scene", SCENES)
def test_step_map_against_differences_of_do_step(fmus, scene):
    fmu, sc = fmus[scene], load_scene(scene)
    point = start_point(fmu)
    H = sc.step
    if sc.method == "exact_free" and sc.inertia[0, 0] == sc.inertia[1, 1]:
        # the exact flow's AD is 0/0 at a symmetric body's modulus 0: refused with the reason
        with pytest.raises(ModelInputError, match="not finite at this point"):
            step_map(sc, point, H)
        m = step_map(sc, point, H, method="rk8")
    else:
        m = step_map(sc, point, H)
    n, method = m.substeps, m.method
    ch0 = chart(list(point.states), point.x, "fixed")
    x_end = do_step(fmu, sc, point, H, n, method, point.x, point.inputs)
    ch1 = chart(list(point.states), x_end, "fixed")
    nz = len(ch0.states)
    zscale = np.array([1.0 if s.startswith("dtheta") else max(abs(point.states[s]), 1.0) for s in ch0.states])
    uscale = np.maximum(np.abs(point.u), 1.0)

    def column(j, h):
        vals = []
        for sgn in (1.0, -1.0):
            x, u = point.x, dict(point.inputs)
            if j < nz:
                dz = np.zeros(nz)
                dz[j] = sgn * h
                x = ch0.to_raw(point.x, dz)
            else:
                name = list(point.inputs)[j - nz]
                u[name] += sgn * h
            vals.append(ch1.from_raw(x_end, do_step(fmu, sc, point, H, n, method, x, u)))
        return (vals[0] - vals[1]) / (2 * h)

    scales = np.concatenate((zscale, uscale))
    exact = np.hstack((m.A, m.B))
    D_h = np.column_stack([column(j, REL * s) for j, s in enumerate(scales)])
    D_2h = np.column_stack([column(j, 2 * REL * s) for j, s in enumerate(scales)])
    f_scale = np.abs(ch1.from_raw(np.zeros_like(x_end), x_end)) + np.abs(exact) @ scales
    assert_within(exact, D_h, D_2h, f_scale * n, REL * scales, f"{scene} step map ({method}, {n} steps)")
