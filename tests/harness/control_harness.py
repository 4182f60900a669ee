"""Drives an FMU's doSteps through ctypes and records what each one did, for the error-control tests.

The error-control, step-rounding and default-accuracy tests (tests/physics/test_error_control.py,
tests/physics/test_step_rounding.py, tests/physics/test_defaults_accuracy.py) run an FMU's own binary
(tests/harness/fmi3_ctypes.py) over a sequence of communication steps and read, after every doStep,
the states and the variables that report the internal stepping: internal_steps,
rejected_steps, h_last and h_next (docs/theory.md §5.5). Errors are measured against the
references of rbcheck (closed forms, else scipy DOP853) with the measures of
rbcheck.workprecision.references.
"""

from __future__ import annotations

import ctypes as C
import functools
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from modelsrc.methods import METHODS
from rbcheck.numerics.rotation_np import quat_to_matrix, rotation_angle_between

from .fmi3_ctypes import LOG_CALLBACK, OK, Fmi3Instance, Fmi3Library, extract_fmu

STATE = ("q[1]", "q[2]", "q[3]", "q[4]", "w_body[1]", "w_body[2]", "w_body[3]")
REPORT = ("internal_steps", "rejected_steps", "h_last", "h_next")


@functools.cache
def library(fmu: Path) -> Fmi3Library:
    """The extracted, loaded binary of a built FMU (once per process and archive). Extracted
    into a folder of this process: the session's FMUs are shared by the xdist workers
    (tests/conftest.py), and a second worker extracting into the same folder would overwrite
    the binary the first has loaded (a segfault in fmi3InstantiateCoSimulation)."""
    fmu = Path(fmu)
    return Fmi3Library(extract_fmu(fmu, fmu.parent / f"{fmu.stem}_unzipped_{os.getpid()}"))


@dataclass
class Run:
    """A co-simulation: the time after each doStep (s, as the FMU holds it), the named
    outputs at t = 0 and after each doStep (rows), the report variables of each doStep,
    and the status and log of the last call."""

    time: np.ndarray
    out: dict[str, np.ndarray]
    report: dict[str, np.ndarray]
    status: int
    log: list[str]

    def vec(self, prefix: str, n: int) -> np.ndarray:
        """The output vector `prefix`[1..n] at every point, shape (points, n)."""
        return np.column_stack([self.out[f"{prefix}[{k + 1}]"] for k in range(n)])

    @property
    def q(self) -> np.ndarray:
        return self.vec("q", 4)

    @property
    def w(self) -> np.ndarray:
        return self.vec("w_body", 3)


def simulate(
    lib: Fmi3Library,
    steps: Sequence[float],
    starts: dict[str, float] | None = None,
    method: str | None = None,
    names: Sequence[str] = (),
    times: Sequence[float] | None = None,
    retune: dict[int, dict[str, float]] | None = None,
    start_time: float = 0.0,
) -> Run:
    """doSteps of the sizes `steps` (s) from t = start_time with start values `starts` (by name) and
    `method` (None: the FMU's default). The current communication point passed to each
    doStep is the FMU's own time (the sum of the steps) unless `times` gives them (an
    importer's own clock); `retune` maps a doStep's index to values (tunable parameters) set
    just before it. Stops at the first refused doStep."""
    info = lib.info
    names = tuple(n for n in (*STATE, *names) if n in info.vr)
    inst = lib.instantiate()
    try:
        starts = starts or {}
        assert inst.set_float64([info.vr[k] for k in starts], [float(v) for v in starts.values()]) == OK, inst.log
        if method is not None:
            assert inst.set_int64([info.int64_vrs["method"]], [METHODS[method].value]) == OK, inst.log
        assert inst.enter_initialization_mode(start_time) == OK, inst.log
        assert inst.exit_initialization_mode() == OK, inst.log
        vrs = [info.vr[k] for k in names]
        rep = [info.vr[k] for k in REPORT]
        rows, reports, clock, status = [inst.get_float64(vrs)[1]], [], [start_time], OK
        for i, H in enumerate(steps):
            t = clock[-1] if times is None else float(times[i])
            for k, v in (retune or {}).get(i, {}).items():
                assert inst.set_float64([info.vr[k]], [float(v)]) == OK, inst.log
            status, _ = inst.do_step(t, float(H))
            if status != OK:
                break
            rows.append(inst.get_float64(vrs)[1])
            reports.append(inst.get_float64(rep)[1])
            clock.append(inst.get_float64([info.vr["time"]])[1][0])
        arr, rarr = np.array(rows), np.array(reports).reshape(-1, len(REPORT))
        return Run(
            np.array(clock),
            {k: arr[:, i] for i, k in enumerate(names)},
            {k: rarr[:, i] for i, k in enumerate(REPORT)},
            status,
            [m for _, _, m in inst.log],
        )
    finally:
        inst.free()


def attitude_error(q: np.ndarray, q_ref: np.ndarray) -> float:
    """Rotation angle (rad) between two attitudes (unit quaternions, body -> world)."""
    return float(rotation_angle_between(quat_to_matrix(np.asarray(q)), quat_to_matrix(np.asarray(q_ref))))


def relative_error(run: Run, w_ref: np.ndarray, q_ref: np.ndarray) -> float:
    """The end error the tolerance is about: max(|ω − ω_ref|∞ / |ω_ref|, attitude angle in rad)
    at the last point (dimensionless; ω body frame)."""
    w_ref = np.asarray(w_ref)
    e_w = float(np.max(np.abs(run.w[-1] - w_ref)) / np.linalg.norm(w_ref))
    return max(e_w, attitude_error(run.q[-1], q_ref))


# fmi3IntermediateUpdateCallback (FMI 3.0 §4.2.3): (environment, time, set requested, get
# requested, step finished, can return early, *early return requested, *early return time).
UPDATE_CALLBACK = C.CFUNCTYPE(
    None, C.c_void_p, C.c_double, C.c_bool, C.c_bool, C.c_bool, C.c_bool, C.POINTER(C.c_bool), C.POINTER(C.c_double)
)


class AskingInstance(Fmi3Instance):
    """A Co-Simulation instance that gives the FMU an intermediateUpdate callback for its
    inputs `inputs` (names), and records the time of every call: the FMU asks at each node
    c_k > 0 of every internal step it attempts, rejected ones included (docs/fmi_layer.md)."""

    def __init__(self, lib: Fmi3Library, inputs: Sequence[str]):
        self.lib, self.model_exchange, self.asked = lib, False, []
        self.log: list[tuple[int, str, str]] = []

        def _update(env, t, set_req, get_req, finished, can_return, early, early_time):
            self.asked.append(float(t))

        def _log(env, status, category, message):
            self.log.append((int(status), "", (message or b"").decode("utf-8", "replace")))

        self._cbs = (UPDATE_CALLBACK(_update), LOG_CALLBACK(_log))  # alive as long as the instance
        vrs = (C.c_uint32 * len(inputs))(*[lib.info.vr[n] for n in inputs])
        self.handle = lib.InstantiateCoSimulation(
            b"asking", lib.info.token.encode(), None, False, False, False, False, vrs, len(inputs), None,
            self._cbs[1], C.cast(self._cbs[0], C.c_void_p),
        )  # fmt: skip
        assert self.handle, self.log
