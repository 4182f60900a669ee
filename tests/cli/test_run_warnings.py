"""The warnings an FMU logs during a run reach the user: `rbfmu: warning: ...` lines, FmuWarnings from the API.

A tolerance of 1e-18 per second is below what rk8's error estimate resolves at torque_driven's
steps (the estimate's floor 1e-16 per step, docs/user_guide.md §2.2): the FMU holds ~1.3e-14
and logs a warning (status Warning) once; the run goes on. Before, `rbfmu run`, `run_fmu` and
`simulate` collected that message and never showed it.
"""

from __future__ import annotations

import warnings
from pathlib import Path
from types import SimpleNamespace

import pytest

from fmu.cli import MAX_FMU_WARNING_LINES, main, warnings_as_lines
from fmu.drive.instance import FmuInstance, FmuWarning
from fmu.drive.logged_warnings import MAX_WARNINGS_SHOWN, warn_logged
from fmu.drive.run import run_fmu, simulate
from modelsrc.scene import load_scene

from ..harness.scenes import shared_fmu

BELOW_FLOOR = {"tolerance": 1e-18}  # 1/s: below rk8's floor at torque_driven's internal steps (~7.5 ms)
FLOOR_WARNING = "the error control holds"


@pytest.fixture(scope="module")
def torque_driven(build_dir) -> Path:
    return shared_fmu(build_dir, "torque_driven")


def test_rbfmu_run_prints_the_fmus_warning_once_as_one_line(capsys, build_dir, torque_driven):
    code = main(["run", "torque_driven", "--stop-time", "1", "--set", "tolerance=1e-18", "--build-dir", str(build_dir)])
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert code == 0 and len(lines) == 1, err
    assert lines[0].startswith("rbfmu: warning: torque_driven.fmu: the FMU logged a warning: fmi3DoStep:"), err
    assert FLOOR_WARNING in lines[0] and "not tolerance = 1e-18" in lines[0], err


def test_rbfmu_run_at_the_default_tolerance_prints_no_warning(capsys, build_dir, torque_driven):
    assert main(["run", "torque_driven", "--stop-time", "1", "--build-dir", str(build_dir)]) == 0
    assert capsys.readouterr().err == ""


def test_run_fmu_raises_the_fmus_warning(torque_driven):
    with pytest.warns(FmuWarning, match="not tolerance = 1e-18") as caught:
        run_fmu(torque_driven, "torque_driven", stop_time=1.0, start_values=BELOW_FLOOR)
    fmu_warnings = [w for w in caught if issubclass(w.category, FmuWarning)]
    assert len(fmu_warnings) == 1 and fmu_warnings[0].filename == __file__  # it points at the caller


class Stop(Exception):
    """The closed loop's own failure, raised by `failing_loop` after the FMU's warning."""


def failing_loop(t: float, outputs) -> dict[str, float]:
    """A closed loop (input_fn) that fails at t = 0.5 s, after the FMU warned in its first doStep."""
    if t >= 0.5:
        raise Stop(f"the loop failed at t = {t}")
    return {}


def test_a_failing_run_shows_its_warnings_and_warnings_made_errors_do_not_hide_its_error(torque_driven):
    with pytest.warns(FmuWarning, match="not tolerance = 1e-18"), pytest.raises(Stop):
        run_fmu(torque_driven, "torque_driven", stop_time=1.0, start_values=BELOW_FLOOR, input_fn=failing_loop)
    with warnings.catch_warnings():
        warnings.simplefilter("error", FmuWarning)
        with pytest.raises(Stop):  # the run's own error, not the FmuWarning
            run_fmu(torque_driven, "torque_driven", stop_time=1.0, start_values=BELOW_FLOOR, input_fn=failing_loop)
        with pytest.raises(FmuWarning, match="not tolerance = 1e-18"):  # a run that ends: the warning as error
            run_fmu(torque_driven, "torque_driven", stop_time=1.0, start_values=BELOW_FLOOR)


def test_simulate_raises_each_runs_warnings_on_a_reused_instance(torque_driven):
    sc = load_scene("torque_driven")
    with FmuInstance(torque_driven, node_inputs=()) as inst:
        for _ in range(2):  # the second run, after fmi3Reset, warns again, and only of its own messages
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                simulate(inst, sc, stop_time=1.0, start_values=BELOW_FLOOR, inputs="hold")
            assert [str(w.message).count(FLOOR_WARNING) for w in caught] == [1], [str(w.message) for w in caught]
            inst.reset()
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            simulate(inst, sc, stop_time=1.0, inputs="hold")
        assert caught == []


def _raised(logged: list[str]) -> list[str]:
    """The FmuWarnings' texts warn_logged raises for these logged messages."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        warn_logged(SimpleNamespace(path=Path("x.fmu"), warnings=logged))  # type: ignore[arg-type]
    assert all(issubclass(w.category, FmuWarning) for w in caught)
    return [str(w.message) for w in caught]


def test_each_distinct_warning_once_with_its_count_and_the_rest_counted():
    assert _raised(["a", "b", "a", "a"]) == [
        "x.fmu: the FMU logged a warning: a (logged 3 times in this run)",
        "x.fmu: the FMU logged a warning: b",
    ]
    many = [f"m{k}" for k in range(MAX_WARNINGS_SHOWN + 3)] + ["m0", "m7"]
    texts = _raised(many)
    assert len(texts) == MAX_WARNINGS_SHOWN + 1 and texts[0].endswith("m0 (logged 2 times in this run)")
    assert texts[-1] == "x.fmu: the FMU logged 3 more distinct warnings (4 in all), not shown"
    assert _raised([]) == []


def test_the_cli_prints_at_most_its_limit_of_fmu_warning_lines(capsys):
    with warnings_as_lines():
        for k in range(MAX_FMU_WARNING_LINES + 5):
            warnings.warn(f"run {k}", FmuWarning, stacklevel=1)
        warnings.warn("run 0", FmuWarning, stacklevel=1)  # a repeated text is not printed again
    lines = capsys.readouterr().err.splitlines()
    assert lines[:2] == ["rbfmu: warning: run 0", "rbfmu: warning: run 1"]
    assert len(lines) == MAX_FMU_WARNING_LINES + 1
    assert lines[-1] == "rbfmu: warning: the FMU logged further warnings, not shown"
