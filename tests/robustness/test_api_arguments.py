"""The Python API refuses a bad argument with the project's error naming it, never a raw exception (issue 34 item 4).

Each argument of run_fmu, simulate, build_fmu and ensure_fmu (docs/user_guide.md §4.1) is
given a wrong type or value; each call raises modelsrc.errors.ModelInputError with the
argument's name and what is accepted (on main these raised TypeError, AttributeError or
zipfile.BadZipFile, or ran an FMU with another scene's experiment).
"""

from __future__ import annotations

import pytest

from fmu.build.build_fmu import build_fmu, ensure_fmu
from fmu.drive.instance import FmuInstance
from fmu.drive.run import run_fmu, simulate
from modelsrc.errors import ModelInputError
from modelsrc.scene import load_scene

from ..harness.scenes import shared_fmu


@pytest.fixture(scope="module")
def heavy_top(build_dir):
    return shared_fmu(build_dir, "heavy_top")


RUN_FMU = [
    ({"fmu_path": 123}, "fmu_path must be a path (str or pathlib.Path), got int 123"),
    ({"fmu_path": "/nonexistent/x.fmu"}, "fmu_path /nonexistent/x.fmu: no such file"),
    ({"fmu_path": __file__}, "not an FMU archive (not a zip file)"),
    ({"scene": None}, "scene must be a Scene (modelsrc.scene.load_scene), a shipped scene's name or a .toml"),
    ({"scene": "free_asymmetric"}, "was built from scene 'heavy_top', not from the given scene 'free_asymmetric'"),
    ({"input_fn": "pd"}, "input_fn must be a function (t, outputs) -> {input name: value} or None, got str 'pd'"),
    ({"outputs": "q[1]"}, "outputs must be a list of variable names (e.g. ['q[1]', 'E_kin']), got str 'q[1]'"),
    ({"outputs": 5}, "outputs must be a list of variable names"),
    ({"outputs": [1]}, "outputs: variable names are strings, got int 1"),
]


@pytest.mark.parametrize("bad, words", RUN_FMU)
def test_run_fmu_names_a_bad_argument(heavy_top, bad, words):
    args = {"fmu_path": heavy_top, "scene": load_scene("heavy_top"), "stop_time": 0.01, **bad}
    with pytest.raises(ModelInputError) as err:
        run_fmu(**args)
    assert words in str(err.value)


def test_run_fmu_takes_the_scene_by_name(heavy_top):
    assert run_fmu(heavy_top, "heavy_top", stop_time=0.01, start_values={"method": "gauss4"}).n_steps > 0


@pytest.mark.parametrize(
    "bad, words",
    [
        ({"inst": "heavy_top.fmu"}, "inst must be an FmuInstance (fmu.drive.instance), got str"),
        ({"direct": "yes"}, "direct must be True or False, got str 'yes'"),
        ({"outputs": "E_kin"}, "outputs must be a list of variable names"),
        ({"scene": "free_asymmetric"}, "not from the given scene 'free_asymmetric'"),
    ],
)
def test_simulate_names_a_bad_argument(heavy_top, bad, words):
    with FmuInstance(heavy_top) as inst:
        args = {"inst": inst, "scene": load_scene("heavy_top"), "stop_time": 0.01, "inputs": "hold", **bad}
        with pytest.raises(ModelInputError) as err:
            simulate(**args)
    assert words in str(err.value)


@pytest.mark.parametrize("build", [build_fmu, ensure_fmu])
@pytest.mark.parametrize(
    "bad, words",
    [
        ({"scene": 123}, "scene must be a Scene"),
        ({"out_dir": None}, "out_dir must be a path (str or pathlib.Path), got NoneType None"),
        ({"platforms": 5}, "platforms must be None (the host's binary), 'all', 'host' or platform names"),
        ({"platforms": "mars"}, "platform 'mars' cannot be built; allowed for FMI 3.0: x86_64-linux"),
        ({"fmi_version": 4}, "fmi_version must be 2 or 3, got 4"),
        ({"fmi_version": True}, "fmi_version must be 2 or 3, got True"),
    ],
)
def test_build_names_a_bad_argument(tmp_path, build, bad, words):
    args = {"scene": "skewed_bar", "out_dir": tmp_path, **bad}
    with pytest.raises(ModelInputError) as err:
        build(**args)
    assert words in str(err.value)
    assert not list(tmp_path.glob("*.fmu"))


def test_build_fmu_refuses_flags_given_as_one_string(tmp_path):
    with pytest.raises(ModelInputError, match=r"extra_cflags must be a list of compiler flags .* got str '-O2'"):
        build_fmu("skewed_bar", tmp_path, extra_cflags="-O2")  # type: ignore[arg-type]


GRID = {"w_body[3]": [1.0, 2.0]}


@pytest.mark.parametrize(
    "bad, words",
    [
        ({"fmu_or_scene": 123}, "fmu_or_scene must be a Scene"),
        ({"scene": 5}, "scene must be a Scene"),
        ({"grid_or_samples": [1, 2]}, "grid_or_samples must be a DataFrame (one row per run) or a mapping"),
        ({"grid_or_samples": {"w_body[3]": 1.0}}, "grid_or_samples must be a DataFrame"),
        ({"outputs": "E_kin"}, "outputs must be a list of variable names"),
        ({"client": "tcp://127.0.0.1:8786"}, "client must be a dask.distributed.Client or None, got str"),
        ({"fixed": [1]}, "fixed must be a mapping variable name -> value, got list"),
        ({"progress": "yes"}, "progress must be True or False, got str 'yes'"),
        ({"dashboard": 5}, "dashboard must be HOST:PORT (a str) or None, got 5"),
        ({"fmu_or_scene": "heavy_top", "build_dir": 5}, "build_dir must be a path"),
    ],
)
def test_sweep_names_a_bad_argument(heavy_top, bad, words):
    from fmu.sweep.api import sweep

    args = {"fmu_or_scene": heavy_top, "grid_or_samples": GRID, "scene": "heavy_top", "workers": 0, **bad}
    with pytest.raises(ModelInputError) as err:
        sweep(**args)
    assert words in str(err.value)


@pytest.mark.parametrize(
    "bad, words",
    [
        ({"distributions": [1]}, "distributions must be a mapping name -> (kind, a, b), got list"),
        ({"distributions": {"w_body[3]": 5}}, "distributions['w_body[3]'] must be (kind, a, b)"),
        ({"distributions": {"w_body[3]": ("normal", "x", 1)}}, "numbers a, b, got ('normal', 'x', 1)"),
        ({"seed": "a"}, "seed must be a whole number or None, got 'a'"),
    ],
)
def test_sample_runs_names_a_bad_argument(bad, words):
    from fmu.sweep.api import sample_runs

    args = {"distributions": {"w_body[3]": ("normal", 0.0, 1.0)}, "n": 3, **bad}
    with pytest.raises(ModelInputError) as err:
        sample_runs(**args)
    assert words in str(err.value)
