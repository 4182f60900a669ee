"""Input schedules as the driver and references feed them: a set value replaces a schedule; harmonics are continuous.

Issue 24.1: `--set NAME=VALUE` (start_values, the sweeps' fixed values and grids) on an
input component holds it constant for the whole run, in place of the scene's table or
harmonic (modelsrc.scene_inputs.hold_component). Issue 25.1: the driver gives a harmonic
input to the FMU at every internal node (FMI 3.0 intermediate update) and the references
integrate it as a function of time, so that the cross-check sees the error of holding it
over a communication step (fmu.drive.inputs, rbcheck.baselines.motion, rbcheck.exudyn.motion).
"""

from __future__ import annotations

import numpy as np
import pytest

from fmu.drive.inputs import node_input_names
from fmu.drive.instance import FmuInstance
from fmu.drive.run import run_fmu, simulate
from fmu.sweep import sweep
from modelsrc.errors import ModelInputError
from modelsrc.scene import load_scene
from modelsrc.scene_inputs import Harmonic, hold_component, input_at
from rbcheck.baselines.motion import integrate
from rbcheck.closed_forms.free_flight import accelerating_pivot_top, harmonic_motion

# The FMU's defaults: rk8 with error control at tolerance 1e-10 per second of run
# (docs/theory.md §5.5); over the runs below (≤ 0.5 s) its error is ≤ 1e-10 relative.
DEFAULT_TOLERANCE = 1e-10


def test_hold_component_keeps_the_other_components_schedules():
    h = Harmonic(np.array([1.0, 0.0, 2.0]), omega=3.0, phase=0.5)
    held = hold_component(h, 2, 0.25)
    for t in (0.0, 0.3, 1.7):
        assert input_at(held, t)[0] == input_at(h, t)[0]
        assert input_at(held, t)[2] == 0.25
    table = np.array([[0.0, 1.0, 2.0, 3.0], [1.0, 4.0, 5.0, 6.0]])
    assert np.array_equal(hold_component(table, 0, 9.0)[:, 1:], [[9.0, 2.0, 3.0], [9.0, 5.0, 6.0]])
    assert np.array_equal(hold_component(None, 1, 2.0), [0.0, 2.0, 0.0])


def test_a_thruster_set_to_zero_does_not_fire(fmus):
    # spacecraft_thruster's only force is the table of f_thruster (x component 50 N for
    # 4 s, -50 N for 2 s): set to zero, the momentum and the spin stay exactly zero (the
    # scene starts at rest). Today's main still fires it (|p| up to 200 N s).
    sc = load_scene("spacecraft_thruster")
    r = run_fmu(fmus["spacecraft_thruster"], sc, stop_time=12.0, start_values={"f_thruster[1]": 0.0})
    assert np.max(np.abs(r.vector("p"))) == 0.0
    assert np.max(np.abs(r.vector("w_body"))) == 0.0


@pytest.mark.parametrize("a3", [0.0, 2.0])
def test_a_pivot_component_set_constant_is_the_top_in_g_minus_a(fmus, a3):
    # top_on_shaker with a_pivot[3] set: the harmonic's third (its only non-zero)
    # component becomes the constant a3, i.e. the heavy top in gravity g - a
    # (rbcheck.closed_forms.free_flight.accelerating_pivot_top, closed form); a3 = 0 is the unshaken
    # heavy top. Measured 1.1e-12 and 1.3e-12 rad/s; the shaken run is 1e-3 rad/s off.
    sc = load_scene("top_on_shaker")
    r = run_fmu(fmus["top_on_shaker"], sc, stop_time=0.5, start_values={"a_pivot[3]": a3})
    w, q = accelerating_pivot_top(sc.inertia, sc.mass, sc.r_cm, sc.g, (0.0, 0.0, a3), sc.q0, sc.w0, r.time)
    scale = float(np.max(np.abs(w)))
    assert np.max(np.abs(r.vector("w_body") - w)) <= DEFAULT_TOLERANCE * scale
    assert np.max(np.abs(r.vector("q") - q)) <= DEFAULT_TOLERANCE
    assert np.max(np.abs(r.vector("v_pivot")[:, 2] - a3 * r.time)) <= 1e-14  # v = a t (v0 = 0), to round-off


def test_sweep_set_and_param_on_a_harmonic_input_hold_it(fmus):
    # `rbfmu sweep --set 'a_pivot[3]=0'` and `--param 'a_pivot[3]=0,2'`: every run holds the
    # component constant (today's main ignores --set on an input and refuses --param on a harmonic)
    sc = load_scene("top_on_shaker")
    common = dict(scene="top_on_shaker", workers=0, stop_time=0.2)
    fixed = sweep(fmus["top_on_shaker"], {"w_body[3]": [150.0]}, [], fixed={"a_pivot[3]": 0.0}, **common)
    grid = sweep(fmus["top_on_shaker"], {"a_pivot[3]": [0.0, 2.0]}, [], **common)
    assert fixed["ok"].all() and grid["ok"].all(), (fixed["error"], grid["error"])
    rows = [(0.0, fixed.iloc[0]), (0.0, grid.iloc[0]), (2.0, grid.iloc[1])]
    for a3, row in rows:
        w, _ = accelerating_pivot_top(sc.inertia, sc.mass, sc.r_cm, sc.g, (0.0, 0.0, a3), sc.q0, sc.w0, [0.2])
        got = np.array([row[f"end(w_body[{k}])"] for k in (1, 2, 3)])
        assert np.max(np.abs(got - w[-1])) <= DEFAULT_TOLERANCE * 150.0, (a3, got - w[-1])


def test_continuous_inputs_need_an_instance_that_asks(fmus):
    sc = load_scene("top_on_shaker")
    assert node_input_names(sc) == ["a_pivot[1]", "a_pivot[2]", "a_pivot[3]"]
    assert node_input_names(sc, "hold") == []
    with pytest.raises(ModelInputError, match=r"inputs must be one of continuous, hold, got 'zoh'"):
        node_input_names(sc, "zoh")
    with FmuInstance(fmus["top_on_shaker"]) as inst:
        with pytest.raises(ModelInputError, match=r"asks for a_pivot\[1\].*inputs='hold'"):
            simulate(inst, sc, stop_time=0.01)


def test_cross_check_sees_the_hold_error_of_a_harmonic(fmus):
    # top_on_shaker at H = 1 ms: the FMU fed a(t) at every node (intermediate update)
    # against scipy DOP853 at rtol 1e-13 with a(t) in its right-hand side agree to the
    # FMU's tolerance (measured 1.9e-15 relative over 0.2 s); the held run (the mean of a
    # over each step) is 2.9e-6 off: it would fail the cross-check's tolerance by 4
    # orders. The pivot follows the shaker's closed form (−A/ω² cos ωt) to round-off when
    # continuous; held, its position is off by O(A H) (measured 1.3e-6 m over 2 s).
    sc = load_scene("top_on_shaker")
    T, H = 0.2, 1e-3
    runs = {m: run_fmu(fmus["top_on_shaker"], sc, stop_time=T, step=H, inputs=m) for m in ("continuous", "hold")}
    ref = integrate(sc, runs["continuous"].time, "DOP853", rtol=1e-13, atol=1e-15, inputs="continuous")
    scale = float(np.max(np.linalg.norm(ref.w_body, axis=1)))

    def error(m: str) -> float:
        return float(np.max(np.linalg.norm(runs[m].vector("w_body") - ref.w_body, axis=1))) / scale

    assert error("continuous") <= DEFAULT_TOLERANCE * T
    assert error("hold") > 1e3 * DEFAULT_TOLERANCE * T
    spec = sc.inputs["a_pivot"]
    x_h, v_h = harmonic_motion(spec.amplitude, spec.omega, spec.phase, sc.x0, sc.v0, runs["continuous"].time)
    assert np.max(np.abs(runs["continuous"].vector("x_pivot") - x_h)) < 1e-14  # |x| ~ 5e-4 m
    assert np.max(np.abs(runs["hold"].vector("x_pivot") - x_h)) > 1e-8


def test_report_table_shows_continuous_and_held_side_by_side(fmus):
    # the report's forced-scene table (rbcheck.workprecision.forced_scenes) on a tiny ladder
    from rbcheck.workprecision.forced_scenes import measure_forced_scenes, write_forced_scenes

    scenes = [load_scene("top_on_shaker")]
    res = measure_forced_scenes(fmus, scenes, steps=(0.01, 0.005), horizon=0.2)
    e = res[0].errors
    assert max(e["continuous"]) <= DEFAULT_TOLERANCE * 0.2  # measured 7e-14
    assert min(e["hold"]) > 1e3 * max(e["continuous"])  # measured 3e-4 at H = 0.01 s
    lines: list[str] = []
    write_forced_scenes(lines.append, res)
    row = next(s for s in lines if s.startswith("| `top_on_shaker`"))
    assert row.count("|") == 1 + 1 + 2 * 2 and "a_pivot harmonic" in row


def test_check_set_holds_an_input_and_refuses_other_names():
    from rbcheck.checks.cli import scene_with_set_inputs

    sc = scene_with_set_inputs(load_scene("top_on_shaker"), ["a_pivot[3]=0"])
    assert sc.inputs_varying_in_step == [] and np.array_equal(sc.input_at("a_pivot", 0.37), np.zeros(3))
    with pytest.raises(ModelInputError, match=r"check --set w_body\[1\]: only an input component.*a_pivot\[1\.\.3\]"):
        scene_with_set_inputs(load_scene("top_on_shaker"), ["w_body[1]=3"])


def test_build_check_gives_a_harmonic_continuously(fmus, tmp_path):
    # the build-time figures (fmu.build.build_check) drive the FMU as run_fmu does: the shaker's
    # pivot then follows its closed form (held over steps of 0.01 s it is O(H² A ω²) ~ 1e-4 m off)
    from fmpy import extract, read_model_description

    from fmu.build.build_check import _run

    sc = load_scene("top_on_shaker")
    path = fmus["top_on_shaker"]
    unzipdir = extract(str(path), unzipdir=str(tmp_path / "x"))
    x = _run(unzipdir, read_model_description(str(path)), sc, "rk8", {}, 0.01, ["x_pivot[3]"])[:, 0]
    spec = sc.inputs["a_pivot"]
    t = np.arange(len(x)) * 0.01
    x_h, _ = harmonic_motion(spec.amplitude, spec.omega, spec.phase, sc.x0, sc.v0, t)
    # within the error control's tolerance·T of |x| (measured 3.3e-14 m after 2 s)
    assert np.max(np.abs(x - x_h[:, 2])) < DEFAULT_TOLERANCE * sc.stop_time * float(np.max(np.abs(x_h)))


WOBBLE = """name = "wobble"
description = "Free body from rest driven by a harmonic body torque and a world torque table."
outputs = ["q", "w_body"]
[features]
torque_body = true
torque_world = true
[body]
principal_moments = [1.0, 2.0, 3.0]
[initial]
w_body = [0.1, 0.0, 0.5]
[inputs]
tau_body = { amplitude = [0.3, 0.1, 0.2], omega = 20.0, phase = 0.4 }
tau_world = [[0.0, 0.0, 0.0, 0.0], [0.5, 0.0, 0.2, 0.0]]
[experiment]
stop_time = 1.0
step = 0.01
"""


def test_references_integrate_a_harmonic_torque_continuously(tmp_path):
    # a harmonic body torque on a free body: scipy DOP853 with τ(t) in its right-hand side
    # and Exudyn RK67 with τ(t) as a load user function are independent; they agree far
    # below the hold's error (measured: 2e-14 rad/s against 2.5e-6 for the held torque;
    # the FMU fed τ(t) by intermediate update agrees with both to 3e-15 and 2e-14)
    from rbcheck.exudyn.models import simulate_scene

    from ..harness.scenes import write_scene

    sc = load_scene(write_scene(tmp_path, WOBBLE, "wobble"))
    grid = np.arange(101) * 0.01
    scipy_w = {m: integrate(sc, grid, inputs=m).w_body for m in ("continuous", "hold")}
    exudyn_w = simulate_scene(sc, h=1e-3, inputs="continuous")["w_body"]
    assert np.max(np.abs(scipy_w["continuous"] - exudyn_w)) < 1e-12
    assert np.max(np.abs(scipy_w["hold"] - exudyn_w)) > 1e-7
