"""Sweeps on a real dask cluster on 127.0.0.1: the same table as in one process, and every row after a worker is killed.

Each test starts `dask scheduler` and two `dask worker` processes (no nanny, so a killed
worker stays dead) with bounded lifetimes, and stops them when it ends.
"""

from __future__ import annotations

import contextlib
import json
import os
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pandas as pd
import pytest

from fmu.cli import main
from fmu.sweep import sweep
from fmu.sweep.results import read_table
from fmu.sweep.worker import TIMING_COLUMNS, extraction_count

DASK = Path(sys.executable).with_name("dask")
LIFETIME_S = 240  # the cluster ends itself after this even if a test is killed


@contextlib.contextmanager
def dask_cluster(tmp: Path, n_workers: int = 2) -> Iterator[tuple[str, list[subprocess.Popen]]]:
    """(scheduler address, worker processes) of a scheduler and n single-threaded
    workers on 127.0.0.1, all terminated on exit."""
    if not DASK.exists():
        pytest.skip(f"the dask command is not installed next to {sys.executable}")
    info = tmp / "scheduler.json"
    log = (tmp / "dask.log").open("w")
    common = ["--no-dashboard", "--host", "127.0.0.1"]
    procs = [
        subprocess.Popen(
            [str(DASK), "scheduler", "--port", "0", "--scheduler-file", str(info), "--idle-timeout", f"{LIFETIME_S}s"]
            + common,
            stdout=log,
            stderr=subprocess.STDOUT,
        )
    ]
    try:
        deadline = time.monotonic() + 60
        while not info.exists() or not info.read_text().strip():
            assert time.monotonic() < deadline, "the dask scheduler did not start within 60 s"
            assert procs[0].poll() is None, (tmp / "dask.log").read_text()
            time.sleep(0.1)
        address = json.loads(info.read_text())["address"]
        for k in range(n_workers):
            cmd = [str(DASK), "worker", address, "--nthreads", "1", "--no-nanny", "--name", f"w{k}"]
            cmd += ["--lifetime", f"{LIFETIME_S}s", "--death-timeout", "30s", "--local-directory", str(tmp / f"w{k}")]
            procs.append(subprocess.Popen(cmd + common, stdout=log, stderr=subprocess.STDOUT))
        from distributed import Client

        with Client(address, timeout="30s") as c:
            c.wait_for_workers(n_workers, timeout=90)
        yield address, procs[1:]
    finally:
        for p in procs:
            if p.poll() is None:
                p.terminate()
        for p in procs:
            try:
                p.wait(timeout=20)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait(timeout=10)
        log.close()


def _comparable(df: pd.DataFrame) -> pd.DataFrame:
    """Everything but the timings, which differ between any two runs."""
    return df.drop(columns=list(TIMING_COLUMNS))


@pytest.mark.slow
def test_scheduler_sweep_is_exactly_the_serial_sweep(fmus, build_dir, tmp_path):
    args = [
        "sweep",
        "sleeping_top",
        "--param",
        "w_body[3]=80:160:5",
        "--param",
        "r_cm[3]=0.02:0.06:3",
        "--param",
        "method=rk4,gauss4",
        "--record",
        "max(euler_zxz[2])",
        "--record",
        "cross(euler_zxz[2], 0.1)",
        "--set",
        "c_friction=0",
        "--stop-time",
        "0.6",
        "--chunk-size",
        "2",
        "--build-dir",
        str(build_dir),
        "--no-progress",
    ]
    assert main([*args, "--workers", "0", "--out", str(tmp_path / "serial.parquet")]) == 0
    serial = read_table(tmp_path / "serial.parquet")
    with dask_cluster(tmp_path) as (address, _workers):
        assert main([*args, "--scheduler", address, "--out", str(tmp_path / "dask.parquet")]) == 0
        from distributed import Client

        with Client(address) as c:
            extractions = c.run(extraction_count)
    remote = read_table(tmp_path / "dask.parquet")
    assert len(serial) == 30 and serial["ok"].all()
    pd.testing.assert_frame_equal(_comparable(remote), _comparable(serial), check_exact=True)
    # 15 chunks over two workers: each worker extracted the FMU once and reused it
    assert sorted(extractions.values()) == [1, 1], extractions


@pytest.mark.slow
def test_local_cluster_sweep_is_exactly_the_serial_sweep(fmus):
    # no client: a LocalCluster of worker processes started (and stopped) for the sweep
    grid = {"w_body[3]": [100.0, 130.0, 160.0, 190.0], "method": ["rk4", "gauss6"]}
    kwargs = dict(scene="heavy_top", stop_time=0.3, chunk_size=2)
    serial = sweep(fmus["heavy_top"], grid, ["max(euler_zxz[2])"], workers=0, **kwargs)
    local = sweep(fmus["heavy_top"], grid, ["max(euler_zxz[2])"], workers=2, **kwargs)
    assert local.attrs["workers"] == 2 and serial.attrs["workers"] == 0
    pd.testing.assert_frame_equal(_comparable(local), _comparable(serial), check_exact=True)


@pytest.mark.slow
def test_killed_worker_mid_sweep_still_gives_every_row(fmus, tmp_path):
    from distributed import Client

    # nested, so that cloudpickle sends it by value (the workers cannot import tests/)
    def _chunks_of_worker(dask_worker) -> tuple[int, int]:
        """On a worker: (tasks it has finished, tasks it is running now)."""
        return dask_worker.state.executed_count, len(dask_worker.state.executing)

    # 72 chunks of ~0.1 s: on two idle cores 24 chunks ended before w0 had finished two
    grid = {"w_body[3]": [100.0 + 5 * k for k in range(12)], "r_cm[3]": [0.02 + 0.002 * k for k in range(24)]}
    kwargs = dict(stop_time=4.0, fixed={"c_friction": 0.0}, chunk_size=4, scene="sleeping_top")
    figures = ["max(euler_zxz[2])"]
    serial = sweep(fmus["sleeping_top"], grid, figures, workers=0, **kwargs)
    with dask_cluster(tmp_path) as (address, workers), Client(address) as client, Client(address) as watcher:
        result: dict[str, object] = {}

        def run() -> None:
            try:
                result["df"] = sweep(fmus["sleeping_top"], grid, figures, client, **kwargs)
            except BaseException as exc:  # reported by the test thread
                result["error"] = exc

        thread = threading.Thread(target=run, daemon=True)
        thread.start()
        victim = workers[0]
        victim_address = next(a for a, w in watcher.scheduler_info()["workers"].items() if w["name"] == "w0")
        deadline = time.monotonic() + 120
        # kill the worker w0 while it runs a chunk, after it has finished another one
        while True:
            assert thread.is_alive(), f"the sweep ended before a worker could be killed: {result}"
            assert time.monotonic() < deadline, "the worker w0 got no second chunk within 120 s"
            finished, running = watcher.run(_chunks_of_worker, workers=[victim_address])[victim_address]
            if finished >= 2 and running:  # its first task may be the archive's
                break
            time.sleep(0.01)
        os.kill(victim.pid, signal.SIGKILL)
        victim.wait(timeout=10)
        thread.join(timeout=180)
        assert not thread.is_alive(), "the sweep did not finish after the worker was killed"
        assert "error" not in result, result.get("error")
        assert victim_address not in client.nthreads()  # the scheduler saw it go
    df = result["df"]
    assert isinstance(df, pd.DataFrame)
    assert list(df.index) == list(range(288)) and df["ok"].all()
    pd.testing.assert_frame_equal(_comparable(df), _comparable(serial), check_exact=True)
