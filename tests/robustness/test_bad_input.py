"""Bad input gives a clear error naming the value and what is allowed: no crash, no traceback."""

from __future__ import annotations

import math
import subprocess
import sys

import pytest

from fmu.drive.instance import FmuError, FmuInstance
from fmu.drive.run import run_fmu
from modelsrc.errors import ModelInputError
from modelsrc.scene import load_scene

from ..harness.scenes import write_scene

GOOD_BODY = """
[body]
principal_moments = [1.0, 2.0, 3.0]
[initial]
w_body = [0.0, 1.0, 0.0]
"""


def test_unknown_scene_lists_known_ones():
    with pytest.raises(ModelInputError, match=r"unknown scene 'no_such'.*heavy_top"):
        load_scene("no_such")


@pytest.mark.parametrize(
    "body, match",
    [
        ("principal_moments = [1.0, 2.0, 3.5]", r"I_i \+ I_j >= I_k.*\[1.0, 2.0, 3.5\]|3\.5"),
        ("principal_moments = [1.0, -2.0, 3.0]", r"positive definite"),
        ("inertia = [[1.0, 0.5, 0.0], [0.4, 2.0, 0.0], [0.0, 0.0, 2.5]]", r"symmetric: I\[1,2\] = I\[2,1\]"),
        ("principal_moments = [1.0, 2.0]", r"body.principal_moments.*list of 3 numbers"),
        ("principal_moments = [1.0, 2.0, nan]", r"must be finite"),
    ],
)
def test_invalid_inertia_is_rejected_with_values(tmp_path, body, match):
    path = write_scene(tmp_path, f"[body]\n{body}\n[initial]\nw_body = [0.0, 1.0, 0.0]\n")
    with pytest.raises(ModelInputError, match=match) as exc:
        load_scene(path)
    assert str(path) in str(exc.value)  # names the file


def test_triangle_equality_is_valid_and_just_past_is_not(tmp_path):
    ok = write_scene(
        tmp_path, "[body]\nprincipal_moments = [1.0, 2.0, 3.0]\n[initial]\nw_body = [1.0, 0.0, 0.0]\n", "flat"
    )
    assert load_scene(ok).inertia[2, 2] == 3.0
    bad = write_scene(
        tmp_path, "[body]\nprincipal_moments = [1.0, 2.0, 3.000001]\n[initial]\nw_body = [1.0, 0.0, 0.0]\n", "past"
    )
    with pytest.raises(ModelInputError, match="I_i \\+ I_j >= I_k"):
        load_scene(bad)


@pytest.mark.parametrize(
    "extra, match",
    [
        ("[experiment]\nstep = -0.01\n", r"experiment.step.*> 0, got -0.01"),
        ("[experiment]\nstop_time = inf\n", r"experiment.stop_time.*finite"),
        ("[experiment]\nh_maxx = 0.1\n", r"experiment.h_maxx.*unknown key.*h_max"),
        ("[features]\ngravity = true\n", r"body.mass.*required"),
        ("[features]\nfriction = 1\n", r"features.friction.*true or false"),
        ("[inputs]\ntau_body = [0.0, 0.0, 1.0]\n", r"inputs.tau_body.*features.torque_body is not true"),
    ],
)
def test_malformed_scene_names_file_field_and_rule(tmp_path, extra, match):
    with pytest.raises(ModelInputError, match=match):
        load_scene(write_scene(tmp_path, GOOD_BODY + extra))


def test_non_unit_start_quaternion(tmp_path):
    p = write_scene(
        tmp_path, GOOD_BODY.replace("w_body = [0.0, 1.0, 0.0]", "w_body = [0.0, 1.0, 0.0]\nq = [1.0, 0.1, 0.0, 0.0]")
    )
    with pytest.raises(ModelInputError, match=r"initial.q.*unit quaternion.*1.00498"):
        load_scene(p)


def test_fmu_rejects_non_finite_start_value(fmus):
    with FmuInstance(fmus["heavy_top"]) as inst:
        with pytest.raises(FmuError, match=r"'w_body\[3\]'.*must be finite, got nan"):
            inst.set({"w_body[3]": math.nan})


def test_fmu_rejects_invalid_inertia_at_initialisation(fmus):
    with FmuInstance(fmus["free_asymmetric"]) as inst:
        inst.set({"I_principal[3]": 10.0})
        with pytest.raises(FmuError, match=r"I_i \+ I_j >= I_k.*I_principal\[3\]=10"):
            inst.initialize()


def test_fmu_rejects_non_positive_step(fmus):
    with FmuInstance(fmus["symmetric_free"]) as inst:
        inst.initialize()
        for h in (0.0, -1e-3):
            with pytest.raises(FmuError, match=r"communicationStepSize must be finite and > 0"):
                inst.do_step(h)
        inst.do_step(1e-3)  # still usable after a refused call
        assert inst.get(["time"])[0] == pytest.approx(1e-3)


def test_fmu_rejects_wrong_state_calls(fmus):
    with FmuInstance(fmus["heavy_top"]) as inst:
        with pytest.raises(FmuError, match=r"fmi3DoStep: not allowed in state Instantiated"):
            inst.do_step(1e-3)
        inst.initialize()
        with pytest.raises(FmuError, match=r"'mass'.*cannot be set in state StepMode"):
            inst.set({"mass": 2.0})


def test_run_rejects_unknown_variable(fmus):
    with pytest.raises(
        ModelInputError,
        match=r"unknown variable 'tau_body\[1\]'; did you mean 'w_body\[1\]'\? Settable: q\[1\.\.4\], w_body",
    ):
        run_fmu(fmus["free_asymmetric"], load_scene("free_asymmetric"), start_values={"tau_body[1]": 1.0})


def test_unknown_variable_suggests_the_closest_settable_names(fmus):
    """The closest settable names first, then only the settable ones: no der(...), no outputs."""
    sc = load_scene("free_asymmetric")
    with pytest.raises(ModelInputError) as exc:
        run_fmu(fmus["free_asymmetric"], sc, start_values={"w_bdy[3]": 1.0})
    msg = str(exc.value)
    assert msg.startswith("unknown variable 'w_bdy[3]'; did you mean 'w_body[3]'? Settable: "), msg
    assert "der(" not in msg and "E_kin" not in msg and "euler_zxz" not in msg
    with pytest.raises(ModelInputError, match=r"^variable 'E_kin' is not settable; settable: "):
        run_fmu(fmus["free_asymmetric"], sc, start_values={"E_kin": 1.0})


@pytest.mark.parametrize(
    "args, match",
    [
        (["run", "no_such_scene"], "unknown scene 'no_such_scene'"),
        (["run", "symmetric_free", "--set", "w_body[1]=nan"], "must be finite"),
        (["run", "symmetric_free", "--set", "I_principal[1]=-1", "--stop-time", "0.1"], "positive definite"),
        (["run", "symmetric_free", "--step", "0", "--stop-time", "0.1"], "step must be a finite number > 0"),
    ],
)
@pytest.mark.slow
def test_cli_errors_are_one_clear_line(tmp_path, args, match):
    proc = subprocess.run(
        [sys.executable, "-m", "fmu.cli", *args, "--out", str(tmp_path)], capture_output=True, text=True, timeout=120
    )
    assert proc.returncode == 2
    assert match in proc.stderr
    assert "Traceback" not in proc.stderr


def test_unknown_variable_message_closest_first_then_the_allowed_compacted():
    from modelsrc.errors import unknown_variable

    allowed = ["q[1]", "q[2]", "q[3]", "q[4]", "w_body[1]", "w_body[2]", "w_body[3]", "mass", "tolerance", "method"]
    msg = str(unknown_variable("w_bdy[3]", allowed))
    assert msg == (
        "unknown variable 'w_bdy[3]'; did you mean 'w_body[3]'? "
        "Settable: q[1..4], w_body[1..3], mass, tolerance, method"
    )
    assert str(unknown_variable("xyz", allowed)).startswith("unknown variable 'xyz'; settable: q[1..4], ")
    msg = str(unknown_variable("der(q[1])", allowed, known={"der(q[1])"}, where="--set 'der(q[1])=1'"))
    assert msg.startswith("--set 'der(q[1])=1': variable 'der(q[1])' is not settable; did you mean 'q[1]'? Settable:")
