"""Trim points, refused input (nothing written), the files and the objects scipy.signal and python-control accept."""

from __future__ import annotations

import json

import numpy as np
import pytest

from fmu.cli import main
from fmu.linear.files import load, write
from fmu.linear.linearize import linearize
from fmu.linear.operating_point import OperatingPoint, start_point
from fmu.linear.step_map import step_map
from fmu.linear.trim import TrimError, trim
from modelsrc.errors import ModelInputError
from modelsrc.scene import load_scene


def test_dual_spin_wheel_that_holds_a_tilted_spin(fmus):
    # ω = (a, 0, b): ω × (I ω + h) = 0 needs h_w = (I1 − I3) b (docs/theory.md §10.4)
    p = start_point(fmus["dual_spin"], {"w_body[1]": 0.3, "w_body[3]": 1.0})
    r = trim(fmus["dual_spin"], p, ["Omega_wheel"], ["der(w_body)"])
    assert abs(r.values[0] - 50.0) / 50.0 < 1e-12
    assert np.max(np.abs(linearize(fmus["dual_spin"], r.point, outputs=[]).drift)) < 1e-15


def test_gravity_gradient_attitude_at_rest_in_the_orbit_frame(fmus):
    fmu = fmus["gravity_gradient_boom"]
    p = start_point(fmu)  # pitched by 0.1 rad
    r = trim(fmu, p, ["attitude", "w_body"], ["der(w_body)", "w_lvlh"])
    assert abs(r.values[1] + 0.1) < 1e-12  # the pitch taken back
    with __import__("fmu.linear.model_exchange", fromlist=["x"]).ModelExchange(fmu) as me:
        me.set_states(r.point.x)
        q_lvlh = me.get(me.value_references([f"q_lvlh[{k}]" for k in (1, 2, 3, 4)], me.outputs, "outputs"))
    assert np.max(np.abs(q_lvlh[1:])) < 1e-12


def test_no_trim_and_not_unique_are_said(fmus):
    q = fmus["quadrotor"]
    up = {"g[3]": 9.81, **{f"Omega_dot_p{k}": 0.0 for k in range(1, 5)}}
    p = start_point(q, up)  # gravity upwards: no thrust k_f Ω² ≥ 0 balances it
    with pytest.raises(TrimError, match="no trim point"):
        trim(q, p, ["Omega_p1"], ["der(v_cm[3])"])
    p = start_point(fmus["dual_spin"], {"w_body[1]": 0.0})  # a spin along the wheel: any wheel speed holds it
    with pytest.raises(TrimError, match="not unique"):
        trim(fmus["dual_spin"], p, ["Omega_wheel"], ["der(w_body[2])"])
    with pytest.raises(ModelInputError, match="more unknowns than equations"):
        trim(q, start_point(q), ["Omega_p1", "Omega_p2"], ["der(v_cm[3])"])
    with pytest.raises(ModelInputError, match="quaternion"):
        trim(q, start_point(q), ["Omega_p1"], ["der(q[1])"])


def test_bad_input_refused(fmus):
    fmu = fmus["torque_driven"]
    p = start_point(fmu)
    with pytest.raises(ModelInputError, match=r"w_body\[1\] must be finite"):
        OperatingPoint({**p.states, "w_body[1]": float("nan")}, p.inputs)
    with pytest.raises(ModelInputError, match="tau_bdy"):
        linearize(fmu, p, inputs=["tau_bdy"])
    with pytest.raises(ModelInputError, match="E_total"):
        linearize(fmu, p, outputs=["E_total"])  # not an output of this scene
    with pytest.raises(ModelInputError, match="coordinates"):
        linearize(fmu, p, coordinates="euler")
    with pytest.raises(ModelInputError, match="frame must be one of rotating, fixed, got 'body'"):
        linearize(fmu, p, frame="body")
    with pytest.raises(ModelInputError, match=r"frame 'fixed': the raw coordinates .* have no attitude reference"):
        linearize(fmu, p, coordinates="raw", frame="fixed")  # was ignored: the raw model has no frame
    sc = load_scene("torque_driven")
    with pytest.raises(ModelInputError, match="finite number > 0"):
        step_map(sc, p, float("inf"))
    with pytest.raises(ModelInputError, match="not compiled"):
        step_map(load_scene("quadrotor"), start_point(fmus["quadrotor"]), 0.01, method="splitting")
    top = load_scene("heavy_top")
    with pytest.raises(ModelInputError, match="Newton iteration did not converge"):
        step_map(top, start_point(fmus["heavy_top"]), 10.0, method="gauss4", substeps=1)


def test_cli_writes_nothing_on_bad_input(fmus, tmp_path, capsys):
    out = tmp_path / "m.npz"
    build = str(next(iter(fmus.values())).parent)
    cases = [
        ["linearize", "dual_spin", "--set", "w_body[1]=nan"],
        ["linearize", "dual_spin", "--at", "-1"],
        ["linearize", "dual_spin", "--outputs", "nope"],
        ["linearize", "dual_spin", "--step-map", "0"],
        ["linearize", "dual_spin", "--substeps", "3"],
        ["linearize", "dual_spin", "--raw", "--frame", "fixed"],
        # settings that had no effect, or lost to another without a word
        ["linearize", "dual_spin", "--set", "tolerance=1e-2"],
        ["linearize", "dual_spin", "--step-map", "0.1", "--set", "method=gauss4", "--method", "rk4"],
        ["linearize", "dual_spin", "--step-map", "0.1", "--substeps", "3", "--set", "h_max=1e-5"],
        ["linearize", "dual_spin", "--step-map", "0.1", "--set", "work_limit=5"],
        ["linearize", "dual_spin", "--outputs", ","],
        ["linearize", "dual_spin", "--outputs", "E_kin,E_kin"],
        ["linearize", "dual_spin", "--step-map", "0.1", "--method", ""],
        ["trim", "dual_spin", "--set", "h_max=1e-3", "--unknown", "Omega_wheel", "--equation", "der(w_body[2])"],
        ["trim", "dual_spin", "--unknown", "Omega_wheel", "--equation", "der(w_body[2])", "--equation", "der(w_body)"],
        ["linearize", "dual_spin", "--step-map", "0.1", "--frame", "rotating"],
        ["trim", "dual_spin", "--unknown", "Omega_wheel", "--unknown", "u_wheel", "--equation", "der(w_body[2])"],
        ["trim", "dual_spin", "--set", "w_body[1]=0", "--unknown", "Omega_wheel", "--equation", "der(w_body[2])"],
    ]
    for args in cases:
        assert main([*args, "--out", str(out), "--build-dir", build]) == 2, args
        assert not out.exists() and not out.with_suffix(".json").exists(), args
    assert main(["linearize", "dual_spin", "--out", str(tmp_path / "m.txt")]) == 2
    err = capsys.readouterr().err
    assert (
        "--set 'w_body[1]=nan': value must be finite" in err
        and "not unique" in err
        and "more unknowns" in err
        and ".npz" in err
        and "frame 'fixed': the raw coordinates" in err
        and "--set tolerance: a setting of the FMU's integration" in err
        and "--set method and --method: the step map's method given twice" in err
        and "--set h_max: --substeps fixes the step map's internal steps" in err
        and "--set work_limit: the step map takes fixed internal steps" in err
        and "--outputs ',': no name given" in err
        and "outputs: E_kin asked for twice" in err
        and "--method '': give a method name" in err
        and "--set h_max: a setting of the FMU's integration" in err
        and "--equation: der(w_body[2]) is asked for twice" in err
        and "--frame rotating: the step map takes its attitude errors about the attitude at the start" in err
    )


def test_cli_trim_writes_the_model(fmus, tmp_path, capsys):
    out = tmp_path / "hover.npz"
    build = str(fmus["quadrotor"].parent)
    args = ["trim", "quadrotor", "--build-dir", build, "--out", str(out), "--outputs", "x_cm,v_cm"]
    args += [a for k in range(1, 5) for a in ("--set", f"Omega_dot_p{k}=0", "--unknown", f"Omega_p{k}")]
    args += ["--equation", "der(v_cm[3])", "--equation", "der(w_body)"]
    assert main(args) == 0
    text = capsys.readouterr().out
    assert "Omega_p1 = 442.944691807002" in text and "eigenvalue" in text
    m = load(out)
    data = json.loads(out.with_suffix(".json").read_text())
    assert data["states"] == list(m.states) and np.array_equal(np.array(data["A"]), m.A)
    assert m.outputs == ("x_cm[1]", "x_cm[2]", "x_cm[3]", "v_cm[1]", "v_cm[2]", "v_cm[3]")


def test_scipy_and_python_control_accept_the_model(fmus, tmp_path):
    import control
    from scipy import signal

    p = start_point(fmus["reaction_wheel_slew"])
    m = linearize(fmus["reaction_wheel_slew"], p, outputs=["w_body"])
    for sys in (signal.StateSpace(*m), m.to_scipy(), control.ss(*m), m.to_control()):
        assert sys.A.shape == (9, 9) and sys.B.shape == (9, 3) and sys.C.shape == (3, 9)
    assert m.to_control().state_labels == list(m.states)
    d = step_map(load_scene("reaction_wheel_slew"), p, 0.1)
    assert d.to_scipy().dt == 0.1 and d.to_control().dt == 0.1
    write(d, tmp_path / "d.npz", "reaction_wheel_slew")
    back = load(tmp_path / "d.npz")
    assert back.dt == 0.1 and np.array_equal(back.A, d.A) and back.states == d.states


# --set of a rotor speed holds it, in linearize and trim as in a run (where the driver derives
# Omega_dot_<name> from the held schedule: 0); the quadrotor's start values have the schedule's
# Omega_dot = 80 rad/s² on every rotor (40 sin 2t), whose reaction torque yaws the body
HOVER = 442.944691807002  # rad/s, √(m g / (4 k_f)), the scene's description


def test_a_held_rotor_speed_has_no_derivative_at_the_point(fmus):
    from fmu.linear.operating_point import held_start_values

    scene, fmu = load_scene("quadrotor"), fmus["quadrotor"]
    speeds = {f"Omega_p{k}": HOVER * (-1) ** (k + 1) for k in range(1, 5)}
    values = held_start_values(scene, speeds)
    assert values == speeds | {f"Omega_dot_p{k}": 0.0 for k in range(1, 5)}
    assert np.max(np.abs(linearize(fmu, start_point(fmu, values), outputs=[]).drift)) == 0.0  # the hover
    # not held: the schedule's derivative at t = 0 (the FMU's start value); given: the value given
    one = held_start_values(scene, {"Omega_p1": HOVER, "Omega_dot_p1": 5.0})
    assert one["Omega_dot_p1"] == 5.0 and one["Omega_dot_p2"] == 80.0 == start_point(fmu).inputs["Omega_dot_p2"]
    assert held_start_values(scene, {}, held=["Omega_p3"]) == {"Omega_dot_p1": 80.0, "Omega_dot_p2": 80.0,
                                                              "Omega_dot_p3": 0.0, "Omega_dot_p4": 80.0}  # fmt: skip
    assert held_start_values(load_scene("heavy_top"), {"w_body[3]": 1.0}) == {"w_body[3]": 1.0}  # no rotors


def test_trim_refuses_a_rotor_speed_that_changes(fmus):
    fmu = fmus["quadrotor"]
    unknowns, eqs = [f"Omega_p{k}" for k in range(1, 5)], ["der(v_cm[3])", "der(w_body)"]
    with pytest.raises(ModelInputError, match=r"Omega_dot_p1 = 80 rad/s\^2 at the start point.*--set 'Omega_dot_p1=0'"):
        trim(fmu, start_point(fmu), unknowns, eqs)  # the start values: every rotor accelerating
    with pytest.raises(ModelInputError, match=r"--unknown 'Omega_dot_p2'.*ask for Omega_p2 instead"):
        trim(fmu, start_point(fmu, {f"Omega_dot_p{k}": 0.0 for k in range(1, 5)}), ["Omega_dot_p2"], eqs)


def test_cli_trim_holds_its_unknown_speeds(fmus, capsys):
    # no Omega_dot given: the unknown speeds are held, so their derivatives are 0; from ±400 rad/s
    args = ["trim", "quadrotor", "--build-dir", str(fmus["quadrotor"].parent), "--outputs", "x_cm"]
    args += [
        a for k in range(1, 5) for a in ("--set", f"Omega_p{k}={400 * (-1) ** (k + 1)}", "--unknown", f"Omega_p{k}")
    ]
    args += ["--equation", "der(v_cm[3])", "--equation", "der(w_body)"]
    assert main(args) == 0
    text = capsys.readouterr().out
    assert "after 4 Newton iterations" in text and f"Omega_p2 = {-HOVER!r}" in text and "(an equilibrium)" in text
    # from a run to 0.3 s: the speeds the schedules give there, held from then on (Omega_dot 0)
    at = ["trim", "quadrotor", "--build-dir", str(fmus["quadrotor"].parent), "--at", "0.3"]
    at += [a for k in range(1, 5) for a in ("--unknown", f"Omega_p{k}")]
    assert main([*at, "--equation", "der(v_cm[3])", "--equation", "der(w_body)"]) == 0
    assert "trim point after" in capsys.readouterr().out


def test_an_operating_point_cannot_change_under_its_vectors(fmus):
    """A point keeps its states and inputs as vectors made once (a linearisation reads them
    at every call): the mappings are read-only copies, the vectors read-only, so that the
    two never disagree; `with_values` makes a changed point."""
    p = start_point(fmus["torque_driven"])
    given = dict(p.states)
    q = OperatingPoint(given, p.inputs)
    given["w_body[1]"] = 5.0  # the caller's dict: not the point's
    assert q.states["w_body[1]"] == p.states["w_body[1]"] and q.x[4] == p.x[4]
    with pytest.raises(TypeError):
        q.states["w_body[1]"] = 5.0  # type: ignore[index]
    with pytest.raises(ValueError, match="read-only"):
        q.x[4] = 5.0
    moved = q.with_values(states={"w_body[1]": 5.0}, inputs={"tau_body[2]": 0.25})
    assert moved.x[list(moved.states).index("w_body[1]")] == 5.0
    assert moved.u[list(moved.inputs).index("tau_body[2]")] == 0.25
    assert q.x[4] == p.x[4]
    import copy
    import pickle

    for twin in (pickle.loads(pickle.dumps(moved)), copy.deepcopy(moved)):
        assert twin == moved and np.array_equal(twin.x, moved.x) and twin.input_names == moved.input_names


def test_trim_refuses_a_frame_in_raw_coordinates_before_it_trims(fmus, capsys):
    build = str(fmus["dual_spin"].parent)
    args = ["trim", "dual_spin", "--raw", "--frame", "fixed", "--unknown", "Omega_wheel"]
    args += ["--equation", "der(w_body[2])"]
    assert main([*args, "--build-dir", build]) == 2
    out, err = capsys.readouterr()
    assert out == "" and "frame 'fixed': the raw coordinates (the FMU's q[1..4]) have no attitude reference" in err
