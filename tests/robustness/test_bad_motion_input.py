"""Bad input to free flight, force points and the moving pivot: refused with the file, the field and what is allowed.

Scene files are refused at load time (ModelInputError naming the file and field); the
FMU refuses non-finite forces and pivot accelerations in any state, naming the input
(docs/robustness.md §2).
"""

from __future__ import annotations

import math
import re

import pytest

from fmu.drive.instance import FmuError, FmuInstance
from fmu.drive.run import run_fmu
from modelsrc.errors import ModelInputError
from modelsrc.scene import load_scene

from ..harness.scenes import write_scene

# inline tables for the body and the start: each scene is its features and a line per part
FREE = """
body = { principal_moments = [1.0, 2.0, 3.0], mass = 1.0 }
initial = { w_body = [0.0, 1.0, 0.0] }
[features]
translation = true
"""
TOP = """
body = { principal_moments = [1.0, 1.0, 2.0], mass = 1.0 }
gravity = { r_cm = [0.0, 0.0, 0.1], g = [0.0, 0.0, -9.81] }
initial = { w_body = [0.0, 0.0, 10.0] }
[features]
gravity = true
moving_pivot = true
"""
JET = '[forces.jet]\npoint = [0.0, 1.0, 0.0]\nframe = "body"\n'
FREE_GRAVITY = (
    FREE.replace("translation = true", "translation = true\ngravity = true") + "[gravity]\nr_cm = [0.0, 0.0, 0.1]\n"
)
TOP_X_CM = TOP.replace("w_body = [0.0, 0.0, 10.0]", "w_body = [0.0, 0.0, 10.0], x_cm = [0.0, 0.0, 0.0]")
SPIN_ONLY = FREE.replace("translation = true", "torque_body = true")

# (scene text, what the error must say)
BAD_SCENES = [
    (TOP.replace("gravity = true\n", ""), r"features.moving_pivot.*needs features.gravity = true"),
    (TOP.replace("gravity = true\n", "gravity = true\ntranslation = true\n"), r"features.translation.*excludes"),
    (FREE.replace(", mass = 1.0", ""), r"body.mass.*required when features.translation"),
    (FREE.replace("translation = true", "force_body = true"), r"features.force_body.*needs features.translation"),
    (FREE + "[features.x]\n", r"not valid TOML|features"),
    (FREE_GRAVITY + "g = [0.0, 0.0, -9.81]\n", r"gravity.r_cm.*free body.*has no pivot"),
    (FREE + JET.replace("1.0", "nan"), r"forces.jet.point\[2\].*must be finite"),
    (FREE + JET.replace("1.0", "inf"), r"forces.jet.point\[2\].*must be finite"),
    (FREE + JET.replace('"body"', '"nose"'), r"forces.jet.frame.*\"body\" or \"world\""),
    (FREE + JET.replace("jet", "pivot"), r"forces.pivot.*identifier other than"),
    (FREE + JET.replace('frame = "body"\n', ""), r"forces.jet.*frame = \"body\" or \"world\""),
    (SPIN_ONLY + JET, r"forces.*need features.translation"),
    (FREE + "[inputs]\nf_jet = [1.0, 0.0, 0.0]\n", r"inputs.f_jet.*unknown key"),
    (FREE + "[inputs]\nf_body = [1.0, 0.0, 0.0]\n", r"inputs.f_body.*features.force_body is not true"),
    (FREE + "[initial.x]\n", r"not valid TOML|initial"),
    (TOP + "[inputs]\na_pivot = [0.0, nan, 0.0]\n", r"inputs.a_pivot\[2\].*must be finite"),
    (TOP + "[inputs]\na_pivot = { amplitude = [0.0, 0.0, 1.0] }\n", r"inputs.a_pivot.*harmonic input.*omega"),
    (TOP + "[inputs]\na_pivot = { amplitude = [0.0, 0.0, 1.0], omega = -3.0 }\n", r"a_pivot.omega.*> 0"),
    (TOP + "[inputs]\na_pivot = [[0.0, 0, 0, 1], [0.0, 0, 0, 2]]\n", r"inputs.a_pivot.*increase strictly"),
    (TOP_X_CM, r"initial.x_cm.*features.translation is not true"),
    ('outputs = ["f_pivot"]\n' + FREE, r"'f_pivot' needs features.moving_pivot"),
    ('outputs = ["x_cm"]\n' + SPIN_ONLY.replace(", mass = 1.0", ""), r"'x_cm' needs features"),
]


@pytest.mark.parametrize("text, match", BAD_SCENES)
def test_bad_motion_scene_names_file_field_and_rule(tmp_path, text, match):
    path = write_scene(tmp_path, text)
    with pytest.raises(ModelInputError, match=match) as exc:
        load_scene(path)
    assert str(path) in str(exc.value) or "not valid TOML" in str(exc.value)


@pytest.mark.parametrize("name, value", [("f_thruster[1]", math.nan), ("f_thruster[3]", -math.inf)])
def test_fmu_refuses_a_non_finite_force(fmus, name, value):
    with FmuInstance(fmus["spacecraft_thruster"]) as inst:
        inst.initialize()
        with pytest.raises(FmuError, match=re.escape(f"'{name}'") + ".*must be finite"):
            inst.set({name: value})
        inst.do_step(0.01)  # refused all or nothing: the instance steps on
        assert math.isfinite(inst.get(["x_cm[1]"])[0])


def test_fmu_refuses_a_non_finite_pivot_acceleration_from_a_controller(fmus):
    sc = load_scene("top_on_shaker")
    with pytest.raises(FmuError, match=r"'a_pivot\[3\]'.*must be finite, got nan"):
        run_fmu(fmus["top_on_shaker"], sc, stop_time=0.01, input_fn=lambda t, y: {"a_pivot[3]": math.nan})
