"""Values a user got wrong: unit-mistake warnings, one unit-length rule, start values checked by name.

A start attitude beyond a full turn and an orbit rate faster than any orbit are warned
about (ModelInputWarning naming the value and the likely intent), in the scene file, in
`rbfmu run --set` and in run_fmu; a rotor axis and a start quaternion 1e-7 off unit length
are both normalised, 1e-3 off both refused; run_fmu takes the method by name as --set
does and refuses bad values with a ModelInputError.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from fmu.cli import main
from fmu.drive.run import run_fmu
from modelsrc.errors import ModelInputError, ModelInputWarning
from modelsrc.scene import load_scene

from ..harness.scenes import write_scene

BODY = "[body]\nprincipal_moments = [1.0, 2.0, 3.0]\n[initial]\nw_body = [0.0, 0.0, 1.0]\n"
ORBIT = (
    'name = "orb"\n[features]\norbit = true\n[orbit]\nrate = {rate}\n'
    "[body]\nprincipal_moments = [1.0, 2.0, 3.0]\n[initial]\nw_body = [0.0, 0.0, 0.0]\n"
)
ROTOR = f"{BODY}[rotors.wheel]\naxis = [0.0, 0.0, {{z}}]\nJ = 0.01\n"


def warned(fn, *args) -> list[str]:
    with warnings.catch_warnings(record=True) as got:
        warnings.simplefilter("always")
        fn(*args)
    return [str(w.message) for w in got if issubclass(w.category, ModelInputWarning)]


def test_euler_angles_in_degrees_are_warned_with_the_radians(tmp_path):
    path = write_scene(tmp_path, f"{BODY}euler_zxz = [0, 30, 0]\n")
    msgs = warned(load_scene, path)
    assert len(msgs) == 1 and "'initial.euler_zxz' = [0, 30, 0]: 30 is more than a full turn" in msgs[0]
    assert "if degrees were meant, give [0, 0.523599, 0]" in msgs[0]
    assert warned(load_scene, write_scene(tmp_path, f"{BODY}euler_zxz = [0, 3, -6]\n")) == []


@pytest.mark.parametrize(
    "rate, intent",
    [
        (5677, "an orbital period in s (2 pi / 5677 s = 0.0011068 rad/s)"),
        (90, "an orbital period in min (2 pi / (90 x 60 s) = 0.0011636 rad/s)"),
        (15.5, "a mean motion in rev/day (15.5 x 2 pi / 86400 s = 0.0011272 rad/s)"),
    ],
)
def test_an_orbit_rate_no_orbit_allows_is_warned_with_its_likely_reading(tmp_path, rate, intent):
    msgs = warned(load_scene, write_scene(tmp_path, ORBIT.format(rate=rate)))
    assert len(msgs) == 1 and f"'orbit.rate' = {rate:g} rad/s is an orbital period of" in msgs[0]
    assert "no circular orbit around a planet turns faster than 0.01 rad/s" in msgs[0] and intent in msgs[0]
    assert warned(load_scene, write_scene(tmp_path, ORBIT.format(rate=0.0011635528346628863))) == []


def test_the_bound_is_above_the_fastest_orbit_of_any_dense_body():
    from modelsrc.unit_mistakes import ORBIT_RATE_MAX, SURFACE_ORBIT_RATE

    # n = sqrt(4 pi G rho / 3) at the surface of a sphere of osmium: 2.51e-3 rad/s (42 min)
    assert pytest.approx(2.513e-3, rel=1e-3) == SURFACE_ORBIT_RATE and SURFACE_ORBIT_RATE < ORBIT_RATE_MAX


@pytest.mark.parametrize("z, ok", [(1.0 + 1e-7, True), (1.0 + 1e-3, False)])
def test_rotor_axes_and_quaternions_share_one_unit_length_rule(tmp_path, z, ok):
    rotor = write_scene(tmp_path, ROTOR.format(z=z), name="rotor")
    quat = write_scene(tmp_path, f"{BODY}q = [{z}, 0.0, 0.0, 0.0]\n", name="quat")
    for path in (rotor, quat):
        if ok:
            sc = load_scene(path)
            assert np.linalg.norm(sc.q0) == pytest.approx(1.0, abs=1e-15)
            if sc.rotors:
                assert np.linalg.norm(sc.rotors["wheel"].axis) == pytest.approx(1.0, abs=1e-15)
        else:
            with pytest.raises(ModelInputError, match="within 1e-06 of 1"):
                load_scene(path)


def test_rbfmu_run_prints_the_warning_of_a_scene_and_of_set_once(capsys, tmp_path, build_dir):
    path = write_scene(tmp_path, ORBIT.format(rate=0.001), name="orb")
    code = main(["run", str(path), "--stop-time", "1", "--set", "n_orbit=5677", "--build-dir", str(build_dir)])
    err = capsys.readouterr().err
    assert code == 0, err
    lines = [x for x in err.splitlines() if x.startswith("rbfmu: warning: ")]
    assert len(lines) == 1 and "n_orbit = 5677 rad/s is an orbital period" in lines[0], err


def test_run_fmu_takes_the_method_by_name_and_refuses_bad_values(fmus):
    sc = load_scene("heavy_top")
    res = run_fmu(fmus["heavy_top"], sc, stop_time=0.01, start_values={"method": "gauss4"})
    assert np.isfinite(res.values["w_body[3]"][-1])
    bad = [
        ({"method": "gaus4"}, "method 'gaus4' is not a method name or its value; allowed: 1 = rk4"),
        ({"method": math.nan}, "method nan is not a method name"),
        ({"w_body[3]": "fast"}, "start_values['w_body[3]']: value 'fast' is not a number"),
        ({"w_body[3]": math.nan}, "start_values['w_body[3]']: value must be finite, got nan"),
        ({"w_body[3]": None}, "value 'None' is not a number"),
        ({"nosuch": 1.0}, "unknown variable 'nosuch'"),
    ]
    for values, words in bad:
        with pytest.raises(ModelInputError) as err:
            run_fmu(fmus["heavy_top"], sc, stop_time=0.01, start_values=values)
        assert words in str(err.value)
    with pytest.raises(ModelInputError, match="stop_time must be a finite number > 0, got '1'"):
        run_fmu(fmus["heavy_top"], sc, stop_time="1")  # type: ignore[arg-type]


def test_rbfmu_run_exits_non_zero_when_a_do_step_hits_the_work_limit(capsys, build_dir):
    code = main(["run", "heavy_top", "--stop-time", "1", "--step", "0.5", "--set", "work_limit=1",
                 "--out", str(build_dir)])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 2 and err.startswith("rbfmu: error: doStep(t=0.0, h=0.5) failed: fmi3DoStep:"), err
    assert "more than work_limit = 1" in err
