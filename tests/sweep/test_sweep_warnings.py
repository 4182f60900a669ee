"""The FMU's warnings in a sweep's runs come back from the workers, shown once per message with the runs that logged it.

A tolerance of 1e-18 per second is below what rk8's error estimate resolves at torque_driven's
steps (tests/cli/test_run_warnings.py): every run logs the same warning once. Before, each run
on a dask worker raised it there (on the worker's stderr, as `model.fmu: ...`, lost to the
user), and a sweep in this process raised it once per run.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import pytest

from fmu.cli import main
from fmu.drive.instance import FmuWarning
from fmu.sweep import sweep

from ..harness.scenes import shared_fmu

FLOOR_WARNING = "the error control holds"
SAME_RUNS = {"tau_body[1]": [0.0, 0.0, 0.0]}  # three equal runs: one message, logged by each


@pytest.fixture(scope="module")
def torque_driven(build_dir) -> Path:
    return shared_fmu(build_dir, "torque_driven")


def _fmu_warnings(call):
    """(call's result, its FmuWarnings: (text, file))."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = call()
    return result, [(str(w.message), w.filename) for w in caught if issubclass(w.category, FmuWarning)]


def test_a_sweep_raises_each_distinct_warning_once_with_its_runs(torque_driven):
    df, raised = _fmu_warnings(
        lambda: sweep(torque_driven, SAME_RUNS, fixed={"tolerance": 1e-18}, stop_time=1.0, workers=0)
    )
    assert df["ok"].all() and "warnings" not in df.columns  # brought back, shown, not kept
    assert len(raised) == 1, raised
    text, where = raised[0]
    assert text.startswith("torque_driven.fmu: the FMU logged a warning: fmi3DoStep: ") and FLOOR_WARNING in text
    assert "not tolerance = 1e-18" in text
    assert text.endswith(" (in 3 of the sweep's 3 runs)") and where == __file__, raised
    _, raised = _fmu_warnings(lambda: sweep(torque_driven, SAME_RUNS, stop_time=1.0, workers=0))
    assert raised == []  # the default tolerance: nothing to say


@pytest.mark.slow
def test_rbfmu_sweep_on_a_cluster_prints_the_workers_warnings_once(torque_driven, tmp_path, capfd):
    args = ["sweep", "torque_driven", "--param", "tau_body[1]=0,0,0", "--set", "tolerance=1e-18", "--stop-time", "1"]
    args += ["--workers", "1", "--build-dir", str(torque_driven.parent), "--out", str(tmp_path / "s.parquet")]
    assert main(args) == 0
    err = capfd.readouterr().err  # the workers' stderr too: no warning is printed there
    lines = [line for line in err.splitlines() if "warning" in line.lower()]
    assert len(lines) == 1, err
    assert lines[0].startswith("rbfmu: warning: torque_driven.fmu: the FMU logged a warning: fmi3DoStep: "), err
    assert FLOOR_WARNING in lines[0] and lines[0].endswith(" (in 3 of the sweep's 3 runs)"), err
