"""The worker side of a sweep: one FMU instance per worker process, reused through fmi3Reset for every run it is sent.

A chunk of runs arrives with the FMU archive's bytes (so workers need no shared file
system) and a `Job` that says what every run does. The first chunk a worker process
(thread) gets writes the archive to a private temporary directory and instantiates it
once; every later run of any chunk with the same archive (same SHA-256) resets that
instance (fmi3Reset restores the start values of instantiation), sets the run's values
and steps it with fmu.drive.run.simulate, the loop of `run_fmu` (doStep and getFloat64 through
ctypes, fmu.drive.instance.DirectCalls: the same calls without fmpy's wrapper). A run the FMU refuses
(bad parameters, a numerical failure) becomes a row with ok = False and the FMU's
message; it does not stop the chunk.
"""

from __future__ import annotations

import atexit
import contextlib
import hashlib
import shutil
import tempfile
import threading
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from modelsrc.errors import ModelInputError
from modelsrc.scene import Scene

from ..drive.inputs import InputPlan
from ..drive.instance import FmuError, FmuInstance
from ..drive.run import simulate
from .figures import Figure, evaluate

# Columns of every result row besides the swept values and the figures.
STATUS_COLUMNS = ("ok", "error")
# Timings (s) of a run on its worker: the doStep/getFloat64 loop (RunResult.wall_time) and
# the whole run from fmi3Reset to the figures. They differ between runs of the same sweep.
TIMING_COLUMNS = ("loop_s", "run_s")
# The key of a row that holds the FMU's warnings during its run (the messages it logged with
# status Warning, a list): they travel back to the client with the row, which shows them once
# for the whole sweep (fmu.sweep.api) and leaves them out of the table.
WARNINGS = "warnings"


@dataclass(frozen=True)
class Job:
    """What every run of a sweep does, besides the values swept for it.

    fmu_key: SHA-256 of the archive; scene: the scene the FMU was built from (input
    tables, which invariants hold); stop_time, step: s; fixed: values set for every run
    (`--set`); columns: the swept variables, in the order of each run's values; inputs:
    those of them that are FMU inputs (held constant over the run, as are the inputs in
    `fixed`: simulate replaces their schedule); figures: what to record; read: the
    outputs read at every communication point; input_mode: "continuous" (the scene's
    harmonics given to the FMU inside a step, FMI 3.0 intermediate update) or "hold"
    (fmu.drive.inputs).
    """

    fmu_key: str
    scene: Scene
    stop_time: float
    step: float
    fixed: Mapping[str, float]
    columns: tuple[str, ...]
    inputs: frozenset[str]
    figures: tuple[Figure, ...]
    read: tuple[str, ...]
    input_mode: str = "continuous"

    @property
    def node_inputs(self) -> tuple[str, ...]:
        """The input components the workers' instances are asked for inside a step: those of
        the input plan of the values every run shares (a run's own plan, built by
        fmu.drive.run.simulate, asks for these or fewer)."""
        return InputPlan.of(self.scene, self.fixed, self.input_mode).node_inputs


Run = tuple[int, tuple[float, ...]]  # (run number, the swept values in Job.columns order)


def archive_key(fmu_bytes: bytes) -> str:
    """The cache key of an FMU archive: the SHA-256 of its bytes."""
    return hashlib.sha256(fmu_bytes).hexdigest()


def _scratch() -> str | None:
    """Where a worker keeps its files: the dask worker's local directory (removed by dask,
    also after a killed worker), else the system's temporary directory."""
    try:
        from distributed import get_worker

        return str(get_worker().local_directory)
    except (ImportError, ValueError):  # not inside a dask worker
        return None


class _Cached:
    """An instance of one archive in this worker: the archive's file and its instance."""

    def __init__(self, fmu_bytes: bytes, node_inputs: tuple[str, ...] = ()):
        self.node_inputs = node_inputs
        self.dir = Path(tempfile.mkdtemp(prefix="rbfmu_sweep_", dir=_scratch()))
        self.path = self.dir / "model.fmu"
        self.path.write_bytes(fmu_bytes)
        self.inst = self._instantiate()

    def _instantiate(self) -> FmuInstance:
        global _extractions
        with _lock:
            _extractions += 1
        unzipdir = Path(tempfile.mkdtemp(prefix="unzipped_", dir=self.dir))
        return FmuInstance(self.path, instance_name="rbfmu_sweep", unzipdir=unzipdir, node_inputs=self.node_inputs)

    def renew(self) -> None:
        """A new instance after one that cannot be reset any more (rare: a fatal error)."""
        self.close_instance()
        self.inst = self._instantiate()

    def close_instance(self) -> None:
        with contextlib.suppress(Exception):  # dropped either way; its error was recorded
            self.inst.close()

    def close(self) -> None:
        self.close_instance()
        shutil.rmtree(self.dir, ignore_errors=True)


_local = threading.local()  # each thread of a worker its own instance: FMU instances are not thread-safe
_lock = threading.Lock()
_all: list[_Cached] = []
_extractions = 0


def extraction_count() -> int:
    """How many times this process has extracted and instantiated an FMU for sweeps."""
    return _extractions


def _instance(key: str, fmu_bytes: bytes, node_inputs: tuple[str, ...] = ()) -> _Cached:
    cache: dict[tuple[str, tuple[str, ...]], _Cached] = _local.__dict__.setdefault("cache", {})
    if (key, node_inputs) not in cache:
        if archive_key(fmu_bytes) != key:
            raise ValueError("the FMU bytes sent with the chunk do not match their key")
        cached = _Cached(fmu_bytes, node_inputs)
        with _lock:
            _all.append(cached)
        cache[key, node_inputs] = cached
    return cache[key, node_inputs]


def release_instances() -> None:
    """Free every cached instance of this process and remove their files (at exit, and
    after a sweep run in this process)."""
    with _lock:
        items = list(_all)
        _all.clear()
    for c in items:
        c.close()
    _local.__dict__.pop("cache", None)


atexit.register(release_instances)


def run_one(inst: FmuInstance, job: Job, values: Mapping[str, float]) -> dict[str, Any]:
    """One run on an instance just reset: its figures, or ok = False and the FMU's
    message, and under WARNINGS the warnings the FMU logged during the run (not raised
    here, in a worker whose stderr nobody reads: the client shows them). Inputs in `values`
    and `job.fixed` are held constant for the run (they are also their start values;
    fmu.drive.run.simulate replaces their schedules)."""
    start = {**job.fixed, **values}
    first = len(inst.warnings)
    try:
        res = simulate(
            inst, job.scene, job.stop_time, job.step, start_values=start, outputs=job.read, direct=True,
            inputs=job.input_mode, raise_warnings=False,
        )  # fmt: skip
    except (FmuError, ModelInputError) as exc:
        return {"ok": False, "error": str(exc), "loop_s": np.nan, WARNINGS: inst.warnings[first:]}
    row: dict[str, Any] = evaluate(res, job.figures)
    row.update(ok=True, error="", loop_s=res.wall_time)
    row[WARNINGS] = inst.warnings[first:]
    return row


def run_chunk(fmu_bytes: bytes, job: Job, runs: Sequence[Run]) -> list[dict[str, Any]]:
    """Run a chunk on this worker's instance of the archive; one row per run, with its
    number (`run`), the swept values, the figures, ok/error, the timings and the FMU's
    warnings (WARNINGS)."""
    cached = _instance(job.fmu_key, fmu_bytes, job.node_inputs)
    rows = []
    for number, vals in runs:
        tic = time.perf_counter()
        values = dict(zip(job.columns, vals))
        try:
            cached.inst.reset()
        except FmuError:
            cached.renew()
        row = {"run": number, **values, **run_one(cached.inst, job, values)}
        row["run_s"] = time.perf_counter() - tic
        rows.append(row)
    return rows
