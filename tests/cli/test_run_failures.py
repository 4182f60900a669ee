"""A run that does not reach its stop time is an error, never exit 0 with garbage (issue 34 item 3).

Every way a co-simulation can end before its stop time, through `rbfmu run`, `run_fmu` and
`simulate` (fmpy's calls and the direct ctypes calls of the sweeps): a doStep refused by the
work limit (WorkLimitError, the CLI's exit 2 with one line naming the limit, the time reached
and how to raise it), and a doStep that returns OK but sets terminateSimulation or
earlyReturn (EarlyEndError; the rbfmu C layer never sets them, an FMU doing so is simulated).
"""

from __future__ import annotations

import pytest

from fmu.cli import main
from fmu.drive.instance import EarlyEndError, FmuError, FmuInstance, WorkLimitError
from fmu.drive.run import run_fmu, simulate
from modelsrc.scene import load_scene

from ..harness.scenes import shared_fmu


@pytest.fixture(scope="module")
def heavy_top(build_dir):
    return shared_fmu(build_dir, "heavy_top")


def test_rbfmu_run_exits_2_naming_the_work_limit_the_time_reached_and_how_to_raise_it(capsys, build_dir, heavy_top):
    # 3300: the first step's own forecast (at the stability bound of docs/theory.md §5.4, 201 rk8
    # steps, 3216 evaluations) passes, and the error control's steps reach the limit at t = 0.36 s
    code = main(["run", "heavy_top", "--stop-time", "1", "--step", "0.5", "--set", "work_limit=3300",
                 "--out", str(build_dir)])  # fmt: skip
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and lines[0].startswith("rbfmu: error: doStep(t=0.0, h=0.5) failed:"), err
    assert "more than work_limit = 3300" in err and "at t=0.3" in err  # the limit, the time reached in the step
    assert "--set work_limit=N" in err and "start_values={'work_limit': N}" in err  # how to raise it


@pytest.mark.parametrize("direct", [False, True])
def test_simulate_and_run_fmu_raise_the_work_limit_error(heavy_top, direct):
    sc = load_scene("heavy_top")
    with pytest.raises(WorkLimitError, match="more than work_limit = 100"):
        run_fmu(heavy_top, sc, stop_time=1.0, step=0.5, start_values={"work_limit": 100})
    with FmuInstance(heavy_top) as inst, pytest.raises(WorkLimitError, match="start_values=\\{'work_limit': N\\}"):
        simulate(inst, sc, stop_time=1.0, step=0.5, start_values={"work_limit": 100}, inputs="hold", direct=direct)


def _fake_flags(inst: FmuInstance, terminate: bool, direct: bool) -> None:
    """Make every doStep of inst return OK with terminateSimulation (or earlyReturn) set,
    having reached 0.25 s: what an FMU that stops a run does (fmpy's call, or the raw one)."""
    if not direct:
        inst.fmu.doStep = lambda t, h, *rest: (False, terminate, not terminate, 0.25)
        return
    calls = inst.direct_calls()

    def do(comp, t, h, no_set, r_event, r_terminate, r_early, r_last):
        (r_terminate if terminate else r_early)._obj.value = True
        r_last._obj.value = 0.25
        return 0

    calls._do = do
    inst.direct_calls = lambda: calls  # type: ignore[method-assign]


@pytest.mark.parametrize("direct", [False, True])
@pytest.mark.parametrize("terminate", [True, False])
def test_a_do_step_that_ends_the_run_early_is_an_error(heavy_top, direct, terminate):
    sc = load_scene("heavy_top")
    flag = "terminateSimulation" if terminate else "earlyReturn"
    with FmuInstance(heavy_top) as inst:
        _fake_flags(inst, terminate, direct)
        with pytest.raises(EarlyEndError, match=f"the FMU set {flag}, having reached t = 0.25 s of 0.5 s") as err:
            simulate(inst, sc, stop_time=1.0, step=0.5, inputs="hold", direct=direct)
    assert isinstance(err.value, FmuError) and str(err.value).startswith("doStep(t=0.0, h=0.5) ended the run early")
