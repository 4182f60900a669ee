"""Fuzzing the FMI 3.0 layer (fmu/c/rbfmu_fmi3.c over rbfmu_core.c) with random call sequences.

One hypothesis example is the life of one instance: instantiation (Co-Simulation or
Model Exchange; sometimes with a wrong token, an empty name or eventModeUsed), a list
of FMI calls whose arguments are drawn from sets of valid and invalid values, then
fmi3FreeFMUState of every snapshot taken and fmi3FreeInstance. Calls go through ctypes
(tests/fmi3_ctypes.py) to the FMU's shared library.

A Python model of the state machine (docs/fmi_layer.md; the masks of rbfmu_fmi3.c for
the states the docs table does not have yet) and of the documented checks predicts
every call's outcome, and for every call the test asserts:
- the status is fmi3OK exactly when the model says the call is allowed and valid
  (a call that must be refused is refused, a call that must succeed succeeds);
- a refused call logs, during that call, an error-status message that names the
  function and says what is wrong (the model's fragments); an OK call logs no error;
- values read back are the model's: time, parameters, inputs, method, and the states
  until the first doStep (then finite, |q| = 1 to round-off); a restored FMU state
  brings back the values of its snapshot;
- no sequence takes longer than SEQUENCE_TIME_LIMIT (no hang), nothing crashes.

test_asan_fuzz repeats a shorter run against an FMU built with AddressSanitizer and
UBSan, in a subprocess with libasan preloaded and leak detection on, after a positive
control showing that LeakSanitizer reports an instance leaked on purpose.
"""

from __future__ import annotations

import argparse
import copy
import ctypes as C
import faulthandler
import json
import math
import os
import random
import re
import shutil
import subprocess
import sys
import tempfile
import time
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import pytest
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

from .fmi3_ctypes import ERROR, OK, Fmi3Instance, Fmi3Library, ModelInfo, extract_fmu, shared_fmu, shared_library

N_SEQUENCES = 10_000  # in-process run: 1e4 sequences (docs/robustness.md §3)
N_SEQUENCES_ASAN = 1_500  # sanitized run: ~4x slower per call under ASan + UBSan
SEQUENCE_TIME_LIMIT = 2.0  # s; the slowest legal sequence (60 gauss6 doSteps of 50
#                               substeps at ~12 µs) takes ~40 ms, ~0.2 s under ASan
FREE_SHARE = 0.7  # fraction of sequences on extreme_free (the rest: sleeping_top)
ME_SHARE = 0.25  # fraction of Model Exchange instances

INST, INIT, STEP, EVENT, CONT, TERM, ERR = (
    "Instantiated",
    "InitializationMode",
    "StepMode",
    "EventMode",
    "ContinuousTimeMode",
    "Terminated",
    "Error",
)
ALL_STATES = (INST, INIT, STEP, EVENT, CONT, TERM, ERR)
CS_STATES = (INST, INIT, STEP, TERM, ERR)
ME_STATES = (INST, INIT, EVENT, CONT, TERM, ERR)
GETTERS = {INIT, STEP, EVENT, CONT, TERM, ERR}

# Where each function may be called: docs/fmi_layer.md for the Co-Simulation states; the
# Model Exchange and FMU-state rows follow rbfmu_fmi3.c (the docs table predates them).
ALLOWED = {
    "fmi3EnterInitializationMode": {INST},
    "fmi3ExitInitializationMode": {INIT},
    "fmi3SetFloat64": {INST, INIT, STEP, EVENT, CONT},  # and per variable kind: SETTABLE
    "fmi3GetFloat64": GETTERS,
    "fmi3SetInt64": {INST, INIT, STEP, EVENT},
    "fmi3GetInt64": GETTERS,
    "fmi3DoStep": {STEP},
    "fmi3Terminate": {STEP, EVENT, CONT},
    "fmi3Reset": set(ALL_STATES),
    "fmi3SetDebugLogging": set(ALL_STATES),
    "fmi3EnterEventMode": {EVENT, CONT},
    "fmi3EnterStepMode": set(),  # Co-Simulation without event mode: never
    "fmi3EnterContinuousTimeMode": {EVENT},
    "fmi3CompletedIntegratorStep": {CONT},
    "fmi3SetTime": {EVENT, CONT},
    "fmi3SetContinuousStates": {CONT},
    "fmi3GetContinuousStates": {INIT, EVENT, CONT, TERM, ERR},
    "fmi3GetContinuousStateDerivatives": {INIT, EVENT, CONT, TERM, ERR},
    "fmi3UpdateDiscreteStates": {EVENT},
    "fmi3GetFMUState": GETTERS,
    "fmi3SetFMUState": GETTERS,
    "fmi3FreeFMUState": set(ALL_STATES),
    "fmi3SerializedFMUStateSize": set(ALL_STATES),
    "fmi3SerializeFMUState": set(ALL_STATES),
    "fmi3DeserializeFMUState": set(ALL_STATES),
}
SETTABLE = {
    "state": {INST, INIT},
    "fixed": {INST, INIT},
    "input": {INST, INIT, STEP, EVENT, CONT},
    "tunable": {INST, INIT, STEP, EVENT},
    "independent": set(),
    "output": set(),
    "derivative": set(),
}

# Validity checks of exitInitializationMode (generated model_checks): a fragment of each
# message, as written in modelsrc/model.py and modelsrc/inertia.py.
CHK_PD = "inertia must be positive definite"
CHK_TRIANGLE = "principal moments must satisfy I_i + I_j >= I_k"
CHK_MASS = "mass must be > 0"
CHK_FRICTION = "c_friction must be >= 0"
CHK_HMAX = "h_max must be > 0"
CHK_SPLIT = "method splitting needs principal axes"
CHK_EXACT = "method exact_free needs principal axes"
CHK_QUAT = "quaternion q must have unit norm"
ALL_CHECKS = (CHK_PD, CHK_TRIANGLE, CHK_MASS, CHK_FRICTION, CHK_HMAX, CHK_SPLIT, CHK_EXACT, CHK_QUAT)
REL_TOL = 1e-12  # modelsrc/inertia.py REL_TOL (docs/theory.md §3.4)
QUAT_NORM_TOL = 1e-6  # modelsrc/scene.py QUAT_NORM_TOL
MAX_SUBSTEPS = 1e8  # fmu/model_data.py MAX_SUBSTEPS

# Values the fuzzer draws: (valid, invalid) per variable. Valid values keep every doStep
# cheap and predictable (|w| <= 10 rad/s, torques <= 100 N m: stiffness rate <= ~1e3 1/s);
# invalid ones hit each check. All are exact binary fractions or far from a check's
# boundary, so the model's floating-point evaluation of the checks agrees with the C.
# h_max = 1e-12 passes the checks but makes every doStep exceed the substep limit.
VALUES = {
    "I_principal": ((1.5, 2.0, 2.5, 3.0, 1.0), (-1.0, 0.0, 10.0)),
    "c_friction": ((0.0, 0.1, 2.0), (-0.1,)),
    "h_max": ((1e-3, 1e-2, 2.5e-2), (0.0, -1e-3, 1e-12)),
    "q": ((1.0, 0.0, 0.6, 0.8), (2.0, 1.000002, 0.5)),
    "w_body": ((0.0, 1.0, -2.0, 10.0, 0.3), ()),
    "tau_body": ((0.0, 1.0, -5.0, 100.0), ()),
    "mass": ((0.5, 2.0), (0.0, -0.5)),
    "r_cm": ((0.0, 0.04, -0.02), ()),
    "g": ((0.0, -9.81, 3.0), ()),
}
# Unit quaternions set as a whole (the last is within the 1e-6 tolerance: normalised).
UNIT_QUATERNIONS = (
    (1.0, 0.0, 0.0, 0.0),
    (0.6, 0.8, 0.0, 0.0),
    (0.5, 0.5, 0.5, -0.5),
    (0.0, 0.0, 0.6, 0.8),
    (1.0000005, 0.0, 0.0, 0.0),
)
P_NON_FINITE, P_INVALID = 0.04, 0.10
NON_FINITE = (math.nan, math.inf, -math.inf)
STEP_SIZES = (1e-3, 1e-2, 5e-2)
BAD_STEP_SIZES = (0.0, -1e-2, math.nan, math.inf)
START_TIMES = (0.0, 1.5, -2.0, 1e6)
METHOD_VALUES_BAD = (0, 7, -1, 2**40)
NX = 7


def classify(info: ModelInfo) -> dict[str, str]:
    """Variable kind by name from modelDescription.xml: independent, state (output with
    a start value), output (calculated), derivative (local der(x)), input, fixed, tunable."""
    kinds = {}
    for name in info.vr:
        if name in info.int64_vrs:
            continue
        c = info.causality[name]
        if c == "independent":
            kinds[name] = "independent"
        elif c == "output":
            kinds[name] = "state" if name in info.start else "output"
        elif c == "local" and name.startswith("der("):
            kinds[name] = "derivative"
        elif c == "input":
            kinds[name] = "input"
        elif c == "parameter":
            kinds[name] = "tunable" if info.variability[name] == "tunable" else "fixed"
        else:
            raise AssertionError(f"unexpected variable {name} (causality {c!r}): extend the fuzzer's model")
    return kinds


@dataclass
class ModelState:
    """The part of the model an FMU state snapshot saves and restores."""

    state: str = INST
    values: dict = field(default_factory=dict)
    method: int = 1
    states_known: bool = True  # states exactly predicted (false after a doStep)
    valid_run: bool = False  # passed exitInitializationMode since the last reset


class FmuModel:
    """Python model of one instance: its state, variable values and method."""

    def __init__(self, info: ModelInfo):
        self.info = info
        self.kinds = classify(info)
        self.name_of = {vr: n for n, vr in info.vr.items()}
        self.nv = 1 + max(vr for n, vr in info.vr.items() if n not in info.int64_vrs)
        self.method_vr = info.int64_vrs["method"]
        self.method_names = dict(info.enum_items)  # enumeration value -> method name
        self.me = False
        self.s = ModelState()
        self.reset()

    def reset(self) -> None:
        values = {n: self.info.start.get(n, 0.0) for n, k in self.kinds.items() if k not in ("output", "derivative")}
        values["time"] = 0.0
        self.s = ModelState(INST, values, self.info.int64_start["method"], True, False)

    # ---- the generated checks, evaluated like the C (same formulas) ----
    def violated(self) -> set[str]:
        v, bad = self.s.values, set()
        I = [v["I_principal[1]"], v["I_principal[2]"], v["I_principal[3]"]]
        if not (I[0] > 0 and I[0] * I[1] > 0 and I[0] * (I[1] * I[2]) > 0):  # Sylvester
            bad.add(CHK_PD)
        tr = I[0] + I[1] + I[2]
        J = [0.5 * tr - x for x in I]  # tr(I)/2 - I >= 0 <=> triangle inequality (theory §3.4)
        tri = [J[k] + REL_TOL * tr >= 0 for k in range(3)]
        tri += [J[i] * J[j] + REL_TOL * tr**2 >= 0 for i, j in ((0, 1), (0, 2), (1, 2))]
        tri.append(J[0] * J[1] * J[2] + REL_TOL * tr**3 >= 0)
        if not all(tri):
            bad.add(CHK_TRIANGLE)
        if "mass" in v and not v["mass"] > 0:
            bad.add(CHK_MASS)
        if "c_friction" in v and not v["c_friction"] >= 0:
            bad.add(CHK_FRICTION)
        if not v["h_max"] > 0:
            bad.add(CHK_HMAX)
        method_name = self.method_names.get(self.s.method)
        if method_name in ("splitting", "exact_free") and "mass" in v:  # both need a diagonal pivot inertia
            m, r = v["mass"], [v["r_cm[1]"], v["r_cm[2]"], v["r_cm[3]"]]
            trp = tr + 2.0 * m * (r[0] ** 2 + r[1] ** 2 + r[2] ** 2)  # trace about the pivot
            off = max(abs(m * r[0] * r[1]), abs(m * r[0] * r[2]), abs(m * r[1] * r[2]))
            if not 1e-12 * trp - off >= 0:
                bad.add(CHK_SPLIT if method_name == "splitting" else CHK_EXACT)
        qn = math.sqrt(sum(v[f"q[{k}]"] ** 2 for k in range(1, 5)))
        if not QUAT_NORM_TOL - abs(qn - 1) >= 0:
            bad.add(CHK_QUAT)
        return bad


@dataclass
class Expect:
    """The predicted outcome of one call: ok, and for a refusal the fragments the logged
    messages must contain; for failed validity checks, exactly these check categories."""

    ok: bool
    fragments: tuple[str, ...] = ()
    checks: frozenset[str] | None = None


@dataclass
class Stats:
    """What the fuzzer exercised: sequences, calls, (function, state, outcome) counts."""

    sequences: int = 0
    calls: int = 0
    refused: int = 0
    transitions: Counter = field(default_factory=Counter)
    max_sequence_time: float = 0.0

    def as_dict(self) -> dict:
        return {
            "sequences": self.sequences,
            "calls": self.calls,
            "refused": self.refused,
            "max_sequence_time": self.max_sequence_time,
            "transitions": {"|".join(k): n for k, n in sorted(self.transitions.items())},
        }


# Kinds of calls and, per state, how often a protocol-following run makes each. Most
# calls (GUIDED_SHARE) are chosen by these weights from the current state, so that runs
# reach step / continuous-time mode and stay there; the rest pick any kind uniformly:
# that is where most calls in a wrong state come from.
CALL_KINDS = (
    "set_float64",
    "get_float64",
    "set_int64",
    "get_int64",
    "enter_init",
    "exit_init",
    "do_step",
    "terminate",
    "reset",
    "set_debug_logging",
    "enter_event_mode",
    "enter_step_mode",
    "enter_continuous",
    "completed_step",
    "set_time",
    "set_states",
    "get_states",
    "get_derivatives",
    "update_discrete",
    "get_fmu_state",
    "set_fmu_state",
    "free_fmu_state",
    "serialize_roundtrip",
)
GUIDED_SHARE = 0.8
_SNAP = {"get_fmu_state": 0.3, "set_fmu_state": 0.3, "free_fmu_state": 0.1, "serialize_roundtrip": 0.2}
GUIDED = {
    INST: {"set_float64": 5, "set_int64": 1, "enter_init": 3, "reset": 0.2},
    INIT: {
        "set_float64": 3,
        "get_float64": 1,
        "get_int64": 0.3,
        "set_int64": 0.5,
        "exit_init": 3,
        "terminate": 0.2,
        "get_states": 0.2,
        **_SNAP,
    },
    STEP: {
        "do_step": 6,
        "set_float64": 2,
        "get_float64": 3,
        "set_int64": 0.7,
        "get_int64": 0.3,
        "terminate": 0.3,
        "reset": 0.3,
        **_SNAP,
    },
    EVENT: {
        "enter_continuous": 3,
        "update_discrete": 1,
        "set_time": 1,
        "set_float64": 1.5,
        "get_float64": 1,
        "set_int64": 0.5,
        "terminate": 0.3,
        **_SNAP,
    },
    CONT: {
        "set_time": 2,
        "set_states": 2,
        "get_derivatives": 2,
        "get_states": 1,
        "completed_step": 1,
        "enter_event_mode": 1,
        "get_float64": 1,
        "set_float64": 0.5,
        "terminate": 0.2,
        **_SNAP,
    },
    TERM: {"get_float64": 2, "get_int64": 0.5, "reset": 2, **_SNAP},
    ERR: {"get_float64": 2, "reset": 2, **_SNAP},
}
CALL_BYTES = 4  # per call: 1 byte chooses the kind, 3 bytes seed its arguments
MIN_CALLS, MAX_CALLS = 12, 60
HEADER_BYTES = 6  # FMU choice, interface type, instantiation seed (4 bytes)
# One example = one byte string (a single hypothesis draw: cheap to generate, and
# shrinking it shrinks the call list).
SEQUENCES = st.binary(min_size=HEADER_BYTES + MIN_CALLS * CALL_BYTES, max_size=HEADER_BYTES + MAX_CALLS * CALL_BYTES)


def choose_kind(state: str, byte: int) -> str:
    """The call kind for one choice byte in the instance's current state."""
    u = byte / 256.0
    if u >= GUIDED_SHARE:
        return CALL_KINDS[int((u - GUIDED_SHARE) / (1 - GUIDED_SHARE) * len(CALL_KINDS))]
    weights = GUIDED[state]
    x = u / GUIDED_SHARE * sum(weights.values())
    for kind, w in weights.items():
        if x < w:
            return kind
        x -= w
    return kind


class Fuzzer:
    """Runs decoded call sequences against one library and checks them against FmuModel."""

    def __init__(self, lib: Fmi3Library, stats: Stats):
        self.lib, self.stats = lib, stats
        self.model = FmuModel(lib.info)
        kinds = self.model.kinds
        self.names = sorted(kinds, key=lambda n: lib.info.vr[n])
        self.never_settable = [n for n in self.names if kinds[n] in ("independent", "output", "derivative")]
        self.settable = [n for n in self.names if n not in self.never_settable]
        self.settable_later = [n for n in self.names if STEP in SETTABLE[kinds[n]] or CONT in SETTABLE[kinds[n]]]
        self.snapshots: list[list] = []  # [ctypes handle, ModelState]

    # ---- argument decoding ----
    def _value_for(self, rng: random.Random, name: str) -> float:
        r = rng.random()
        if r < P_NON_FINITE:
            return rng.choice(NON_FINITE)
        valid, invalid = VALUES.get(name.split("[")[0], ((0.0, 1.0, -3.0), ()))  # else: never settable
        return rng.choice(invalid) if invalid and r < P_NON_FINITE + P_INVALID else rng.choice(valid)

    def _vr_for(self, rng: random.Random) -> tuple[int, str | None]:
        r = rng.random()
        if r < 0.04:
            return rng.choice((self.model.nv, self.model.nv + 7, 2**32 - 1)), None
        if r < 0.12:
            name = rng.choice(self.never_settable)
        elif self.model.s.state in (STEP, EVENT, CONT) and r < 0.7:  # mostly what these modes allow
            name = rng.choice(self.settable_later)
        else:
            name = rng.choice(self.settable)
        return self.lib.info.vr[name], name

    def _state_vector(self, rng: random.Random) -> list[float]:
        x = list(rng.choice(UNIT_QUATERNIONS)) + [rng.choice(VALUES["w_body"][0]) for _ in range(3)]
        if rng.random() < 0.1:
            x[rng.randrange(NX)] = rng.choice(NON_FINITE)
        return x

    # ---- one call: decode, predict, perform, compare ----
    def run_call(self, inst: Fmi3Instance, kind: str, seed: int) -> None:
        rng = random.Random(seed)
        m = self.model
        n_log = len(inst.log)
        state_before = m.s.state
        after = None  # check to run after the call on success
        if kind == "set_float64":
            pairs = [self._vr_for(rng) for _ in range(rng.choice((0, 1, 1, 1, 2, 3)))]
            vrs = [vr for vr, _ in pairs]
            vals = [self._value_for(rng, name or "x") for _, name in pairs]
            if len(pairs) == 1 and pairs[0][1] and pairs[0][1].startswith("q[") and rng.random() < 0.8:
                vrs = [self.lib.info.vr[f"q[{k}]"] for k in range(1, 5)]  # a whole unit quaternion
                vals = list(rng.choice(UNIT_QUATERNIONS))
            n_values = len(vals) + (1 if rng.random() < 0.03 else 0)
            fn, exp = "fmi3SetFloat64", self._expect_set_float64(vrs, vals, n_values)
            status = inst.set_float64(vrs, vals, n_values=n_values)
        elif kind == "get_float64":
            pairs = [self._vr_for(rng) for _ in range(rng.choice((1, 2, 4)))]
            if rng.random() < 0.3:
                pairs = [(self.lib.info.vr[n], n) for n in self.names]  # read everything back
            vrs = [vr for vr, _ in pairs]
            n_values = len(vrs) + (1 if rng.random() < 0.03 else 0)
            fn, exp = "fmi3GetFloat64", self._expect_get_float64(vrs, n_values)
            status, got = inst.get_float64(vrs, n_values=n_values)
            after = lambda: self._compare_read([n for _, n in pairs], got)  # noqa: E731
        elif kind == "set_int64":
            vr = m.method_vr if rng.random() < 0.9 else rng.choice((1, m.nv + 3))
            value = rng.choice(list(m.method_names)) if rng.random() < 0.85 else rng.choice(METHOD_VALUES_BAD)
            fn, exp = "fmi3SetInt64", self._expect_set_int64(vr, value)
            status = inst.set_int64([vr], [value])
        elif kind == "get_int64":
            vr = m.method_vr if rng.random() < 0.9 else 1
            fn = "fmi3GetInt64"
            exp = self._refusal(fn) or Expect(vr == m.method_vr, (f"value reference {vr}",))
            status, ivals = inst.get_int64([vr])
            after = lambda: self._check(ivals[0] == m.s.method, f"method {ivals[0]}, model {m.s.method}")  # noqa
        elif kind == "enter_init":
            start = rng.choice(START_TIMES) if rng.random() < 0.93 else rng.choice(NON_FINITE)
            stop = rng.choice((None, start + 1.0)) if rng.random() < 0.9 else rng.choice((start - 1.0, math.nan))
            fn, exp = "fmi3EnterInitializationMode", self._expect_enter_init(start, stop)
            status = inst.enter_initialization_mode(start, stop)
        elif kind == "exit_init":
            fn, exp = "fmi3ExitInitializationMode", self._expect_exit_init()
            status = inst.exit_initialization_mode()
        elif kind == "do_step":
            h = rng.choice(STEP_SIZES) if rng.random() < 0.9 else rng.choice(BAD_STEP_SIZES)
            r = rng.random()
            t = m.s.values["time"] + (0.0 if r < 0.85 else 1e-12 if r < 0.9 else rng.choice((1e-3, -1e-3, math.nan)))
            time_before = m.s.values["time"]
            fn, exp = "fmi3DoStep", self._expect_do_step(t, h)
            status, last = inst.do_step(t, h)
            if state_before == STEP:  # lastSuccessfulTime: the new time, or the unchanged one
                self._check(last == (t + h if exp.ok else time_before), f"lastSuccessfulTime {last!r}")
        elif kind in (
            "terminate",
            "reset",
            "set_debug_logging",
            "enter_event_mode",
            "enter_continuous",
            "enter_step_mode",
            "completed_step",
            "update_discrete",
        ):
            fn, new_state, call = {
                "terminate": ("fmi3Terminate", TERM, inst.terminate),
                "reset": ("fmi3Reset", INST, inst.reset),
                "set_debug_logging": ("fmi3SetDebugLogging", None, lambda: inst.set_debug_logging(rng.random() < 0.5)),
                "enter_event_mode": ("fmi3EnterEventMode", EVENT, inst.enter_event_mode),
                "enter_continuous": ("fmi3EnterContinuousTimeMode", CONT, inst.enter_continuous_time_mode),
                "enter_step_mode": ("fmi3EnterStepMode", STEP, inst.enter_step_mode),
                "completed_step": ("fmi3CompletedIntegratorStep", None, inst.completed_integrator_step),
                "update_discrete": ("fmi3UpdateDiscreteStates", None, inst.update_discrete_states),
            }[kind]
            exp = self._refusal(fn) or Expect(True)
            if exp.ok and fn == "fmi3Reset":
                m.reset()
            elif exp.ok and new_state:
                m.s.state = new_state
            status = call()
        elif kind == "set_time":
            t = rng.choice(START_TIMES) + rng.random() if rng.random() < 0.9 else rng.choice(NON_FINITE)
            fn = "fmi3SetTime"
            exp = self._refusal(fn) or (Expect(False, ("time must be finite",)) if not math.isfinite(t) else None)
            if exp is None:
                exp, m.s.values["time"] = Expect(True), t
            status = inst.set_time(t)
        elif kind == "set_states":
            x = self._state_vector(rng)
            if rng.random() < 0.05:
                x = x[: rng.choice((0, 6))] if rng.random() < 0.5 else x + [0.0]
            fn = "fmi3SetContinuousStates"
            exp = self._refusal(fn) or self._expect_set_states(x)
            status = inst.set_continuous_states(x)
        elif kind in ("get_states", "get_derivatives"):
            n = NX if rng.random() < 0.95 else rng.choice((0, 6, 8))
            fn = "fmi3GetContinuousStates" if kind == "get_states" else "fmi3GetContinuousStateDerivatives"
            exp = self._refusal(fn) or (
                Expect(False, (f"{NX} continuous states, got {n}",)) if n != NX else Expect(True)
            )
            status, x = (inst.get_continuous_states if kind == "get_states" else inst.get_derivatives)(n)
            names = [self.names[1 + k] for k in range(NX)] if kind == "get_states" else None
            after = (
                (lambda: self._compare_read(names, x))
                if names
                else (lambda: self._check(not m.s.valid_run or all(map(math.isfinite, x)), f"derivatives {x}"))
            )
        elif kind == "get_fmu_state":
            fn = "fmi3GetFMUState"
            reuse = self.snapshots and rng.random() < 0.3  # overwrite an existing snapshot
            exp = self._refusal(fn) or Expect(True)
            target = self.snapshots[rng.randrange(len(self.snapshots))] if reuse else None
            status, handle = inst.get_fmu_state(target[0] if target else None)
            if status == OK and exp.ok:
                if target:
                    target[1] = copy.deepcopy(m.s)
                else:
                    self.snapshots.append([handle, copy.deepcopy(m.s)])
        elif kind == "set_fmu_state":
            fn = "fmi3SetFMUState"
            snap = self.snapshots[rng.randrange(len(self.snapshots))] if self.snapshots and rng.random() < 0.9 else None
            exp = self._refusal(fn) or (Expect(True) if snap else Expect(False, ("not an FMU state",)))
            status = inst.set_fmu_state(snap[0] if snap else None)
            if exp.ok:
                m.s = copy.deepcopy(snap[1])
        elif kind == "free_fmu_state":
            fn = "fmi3FreeFMUState"
            exp = self._refusal(fn) or Expect(True)
            if self.snapshots and rng.random() < 0.8:
                snap = self.snapshots.pop(rng.randrange(len(self.snapshots)))
                status = inst.free_fmu_state(snap[0])
                self._check(status != OK or not snap[0].value, "FreeFMUState must set the pointer to NULL")
            else:
                status = inst.free_fmu_state(C.c_void_p())  # freeing NULL: a no-op
        elif kind == "serialize_roundtrip":
            status, exp, fn = self._serialize_roundtrip(inst, rng)
        else:
            raise AssertionError(kind)
        self._judge(inst, fn, state_before, n_log, status, exp, seed)
        if status == OK and after is not None:
            after()

    def _serialize_roundtrip(self, inst: Fmi3Instance, rng: random.Random):
        """SerializedFMUStateSize + SerializeFMUState + DeserializeFMUState of a snapshot
        (allowed in every state), with a wrong size or a corrupted token sometimes."""
        if not self.snapshots:
            status, size = inst.serialized_size(None)
            return status, Expect(True), "fmi3SerializedFMUStateSize"
        snap = self.snapshots[rng.randrange(len(self.snapshots))]
        status, size = inst.serialized_size(snap[0])
        self._judge(inst, "fmi3SerializedFMUStateSize", self.model.s.state, len(inst.log), status, Expect(True), 0)
        n_log = len(inst.log)
        wrong = rng.random() < 0.1
        status, data = inst.serialize(snap[0], size - 1 if wrong else size)
        exp = Expect(False, ("bytes",)) if wrong else Expect(True)
        if wrong:
            return status, exp, "fmi3SerializeFMUState"
        self._judge(inst, "fmi3SerializeFMUState", self.model.s.state, n_log, status, exp, 0)
        corrupt = rng.random() < 0.1
        if corrupt:  # the instantiation token leads the bytes: a state of another build
            data = data[:1] + bytes([data[1] ^ 0x5A]) + data[2:]
        status, handle = inst.deserialize(data)
        if status == OK and not corrupt:
            self.snapshots.append([handle, copy.deepcopy(snap[1])])
        return (
            status,
            (Expect(False, ("not a serialized state",)) if corrupt else Expect(True)),
            "fmi3DeserializeFMUState",
        )

    def _check(self, cond: bool, what: str) -> None:
        assert cond, f"{what} (state {self.model.s.state})"

    def _judge(
        self, inst: Fmi3Instance, fn: str, state_before: str, n_log: int, status: int, exp: Expect, seed: int
    ) -> None:
        """Compare one call's status and log with the model's prediction."""
        errors = inst.errors_since(n_log)
        where = f"{fn} in state {state_before} (seed {seed})"
        self.stats.calls += 1
        self.stats.transitions[(fn, state_before, "OK" if status == OK else "Error")] += 1
        if exp.ok:
            assert status == OK, f"{where}: must succeed, got status {status}; log: {errors}"
            assert not errors, f"{where}: succeeded but logged errors: {errors}"
            return
        self.stats.refused += 1
        assert status == ERROR, f"{where}: must be refused with fmi3Error, got status {status}"
        assert errors, f"{where}: refused without a logged message"
        assert all(s == ERROR for s, _, _ in inst.log[n_log:] if s != OK), f"{where}: {inst.log[n_log:]}"
        text = "\n".join(errors)
        assert fn in text, f"{where}: the message does not name the function: {errors}"
        for frag in exp.fragments:
            assert frag in text, f"{where}: expected {frag!r} in the log, got {errors}"
        if exp.checks is not None:
            found = {c for c in ALL_CHECKS if c in text}
            assert found == exp.checks, f"{where}: violated checks logged {found}, model {set(exp.checks)}"

    # ---- predictions (they update the model as the call would) ----
    def _refusal(self, fn: str) -> Expect | None:
        """None when fn may be called in the current state, else the predicted refusal."""
        if self.model.s.state in ALLOWED[fn]:
            return None
        return Expect(False, (f"{fn}: not allowed in state {self.model.s.state}",))

    def _expect_set_float64(self, vrs: list[int], vals: list[float], n_values: int) -> Expect:
        m, s = self.model, self.model.s
        refusal = self._refusal("fmi3SetFloat64")
        if refusal:
            return refusal
        if n_values != len(vrs):
            return Expect(False, ("nValues",))
        for vr, x in zip(vrs, vals):  # the C validates every element before changing any
            if vr >= m.nv:
                return Expect(False, (f"value reference {vr}",))
            name = m.name_of[vr]
            if s.state not in SETTABLE[m.kinds[name]]:
                return Expect(False, (f"'{name}'", f"cannot be set in state {s.state}"))
            if not math.isfinite(x):
                return Expect(False, (f"'{name}'", "must be finite"))
        old = dict(s.values)
        for vr, x in zip(vrs, vals):
            s.values[m.name_of[vr]] = x
        if s.state in (STEP, EVENT) and any(m.kinds[m.name_of[vr]] == "tunable" for vr in vrs):
            bad = m.violated()
            if bad:  # refused as a whole, nothing changes (docs/fmi_layer.md, Checks)
                s.values = old
                return Expect(False, (), frozenset(bad))
        return Expect(True)

    def _expect_get_float64(self, vrs: list[int], n_values: int) -> Expect:
        refusal = self._refusal("fmi3GetFloat64")
        if refusal:
            return refusal
        if n_values != len(vrs):
            return Expect(False, ("nValues",))
        for vr in vrs:
            if vr >= self.model.nv:
                return Expect(False, (f"value reference {vr}",))
        return Expect(True)

    def _expect_set_int64(self, vr: int, value: int) -> Expect:
        m, s = self.model, self.model.s
        refusal = self._refusal("fmi3SetInt64")
        if refusal:
            return refusal
        if vr != m.method_vr:
            return Expect(False, (f"value reference {vr}",))
        if value not in m.method_names:
            return Expect(False, (f"method {value}", "allowed:"))
        old, s.method = s.method, value
        if s.state in (STEP, EVENT):
            bad = m.violated()
            if bad:
                s.method = old
                return Expect(False, (), frozenset(bad))
        return Expect(True)

    def _expect_enter_init(self, start: float, stop: float | None) -> Expect:
        s = self.model.s
        refusal = self._refusal("fmi3EnterInitializationMode")
        if refusal:
            return refusal
        if not math.isfinite(start):
            return Expect(False, ("startTime must be finite",))
        if stop is not None and not stop >= start:
            return Expect(False, ("stopTime",))
        s.values["time"], s.state = start, INIT
        return Expect(True)

    def _expect_exit_init(self) -> Expect:
        m, s = self.model, self.model.s
        refusal = self._refusal("fmi3ExitInitializationMode")
        if refusal:
            return refusal
        bad = m.violated()
        if bad:
            s.state = ERR
            return Expect(False, ("parameter values:",), frozenset(bad))
        q = [s.values[f"q[{k}]"] for k in range(1, 5)]
        qn = math.sqrt(sum(x * x for x in q))
        for k in range(4):  # the start quaternion is normalised
            s.values[f"q[{k + 1}]"] = q[k] / qn
        s.state, s.valid_run = (EVENT if m.me else STEP), True
        return Expect(True)

    def _expect_do_step(self, t: float, h: float) -> Expect:
        s = self.model.s
        refusal = self._refusal("fmi3DoStep")
        if refusal:
            return refusal
        if not (h > 0 and math.isfinite(h)):
            return Expect(False, ("communicationStepSize must be finite and > 0",))
        now = s.values["time"]
        if not abs(t - now) <= 1e-10 * max(1.0, abs(now)):
            return Expect(False, ("currentCommunicationPoint",))
        if math.ceil(h / s.values["h_max"] * (1.0 - 1e-12)) > MAX_SUBSTEPS:
            return Expect(False, ("internal steps", "more than the limit"))
        s.values["time"] = t + h  # the layer continues from the caller's t (within tolerance)
        s.states_known = False
        return Expect(True)

    def _expect_set_states(self, x: list[float]) -> Expect:
        s = self.model.s
        if len(x) != NX:
            return Expect(False, (f"{NX} continuous states, got {len(x)}",))
        for k, v in enumerate(x):
            if not math.isfinite(v):
                return Expect(False, (f"'{self.names[1 + k]}'", "must be finite"))
        for k, v in enumerate(x):
            s.values[self.names[1 + k]] = v
        s.states_known = True
        return Expect(True)

    def _compare_read(self, names: list[str | None], got: list[float]) -> None:
        m, s = self.model, self.model.s
        where = f"read in state {s.state}"
        for name, x in zip(names, got):
            kind = m.kinds[name]
            if kind in ("output", "derivative"):
                if s.valid_run and s.state != ERR:
                    assert math.isfinite(x), f"{where}: {name} = {x}"
                continue
            want = s.values[name]
            if kind == "state" and not s.states_known:
                assert math.isfinite(x), f"{where}: state {name} = {x}"
                continue
            if kind == "state" and name.startswith("q[") and s.valid_run:
                # normalised in C as q/|q|: the same operations up to summation order, 2 ulp
                assert abs(x - want) <= 4.5e-16 * max(1.0, abs(want)), f"{where}: {name} = {x!r}, model {want!r}"
                continue
            assert x == want, f"{where}: {name} = {x!r}, model {want!r}"
        if not s.states_known and all(f"q[{k}]" in names for k in range(1, 5)):
            q = [got[names.index(f"q[{k}]")] for k in range(1, 5)]
            # every internal step ends with the projection q/|q|: |q| = 1 to a few ulp
            assert abs(math.sqrt(sum(x * x for x in q)) - 1.0) < 1e-15, f"{where}: q = {q}"

    # ---- one sequence ----
    def run_sequence(self, me: bool, inst_seed: int, calls: list[tuple[int, int]]) -> None:
        """calls: (choice byte, argument seed) pairs; each call's kind is chosen in the
        state the model is in when it is made (choose_kind)."""
        rng = random.Random(inst_seed)
        self.model.reset()
        self.model.me = me
        self.snapshots = []
        variant = rng.random()
        logging_on = rng.random() < 0.5
        fn = "fmi3InstantiateModelExchange" if me else "fmi3InstantiateCoSimulation"
        t0 = time.perf_counter()
        if variant < 0.02:
            inst = self.lib.instantiate(
                token="{00000000-0000-0000-0000-000000000000}", logging_on=logging_on, model_exchange=me
            )
            self._expect_null(inst, fn, "'{00000000-0000-0000-0000-000000000000}' does not match")
        elif variant < 0.03:
            inst = self.lib.instantiate(name="", logging_on=logging_on, model_exchange=me)
            self._expect_null(inst, fn, "instanceName must be a non-empty string")
        elif variant < 0.04 and not me:
            inst = self.lib.instantiate(event_mode_used=True, logging_on=logging_on)
            self._expect_null(inst, fn, "eventModeUsed=true")
        else:
            inst = self.lib.instantiate(logging_on=logging_on, model_exchange=me)
            assert inst.handle, f"instantiation failed: {inst.log}"
            assert not inst.errors_since(0), inst.log
            try:
                for byte, seed in calls:
                    self.run_call(inst, choose_kind(self.model.s.state, byte), seed)
            finally:
                for handle, _ in self.snapshots:
                    assert inst.free_fmu_state(handle) == OK
                inst.free()
        elapsed = time.perf_counter() - t0
        self.stats.sequences += 1
        self.stats.max_sequence_time = max(self.stats.max_sequence_time, elapsed)
        assert elapsed < SEQUENCE_TIME_LIMIT, f"sequence took {elapsed:.2f} s (> {SEQUENCE_TIME_LIMIT} s)"

    def _expect_null(self, inst: Fmi3Instance, fn: str, fragment: str) -> None:
        self.stats.calls += 1
        self.stats.refused += 1
        self.stats.transitions[(fn, "-", "NULL")] += 1
        assert not inst.handle, f"{fn} must return NULL"
        text = "\n".join(inst.errors_since(0))
        assert fn in text and fragment in text, inst.log


def fuzz(libs: dict[str, Fmi3Library], n_sequences: int, shrink: bool = True) -> Stats:
    """Run n_sequences hypothesis examples (derandomized: the same sequences every run)
    over the libraries {"extreme_free": ..., optionally one more}; return statistics.
    A mismatch raises AssertionError with hypothesis' (shrunk) falsifying example."""
    stats = Stats()
    fuzzers = {k: Fuzzer(lib, stats) for k, lib in libs.items()}
    other = [k for k in fuzzers if k != "extreme_free"]

    @settings(
        max_examples=n_sequences,
        derandomize=True,
        database=None,
        deadline=None,
        phases=(Phase.generate, Phase.shrink) if shrink else (Phase.generate,),
        suppress_health_check=list(HealthCheck),
        print_blob=False,
    )
    @given(SEQUENCES)
    def one_sequence(blob):
        key = other[0] if other and blob[0] >= 256 * FREE_SHARE else "extreme_free"
        me = blob[1] < 256 * ME_SHARE
        inst_seed = int.from_bytes(blob[2:6], "little")
        calls = [
            (blob[i], int.from_bytes(blob[i + 1 : i + CALL_BYTES], "little"))
            for i in range(HEADER_BYTES, len(blob) - CALL_BYTES + 1, CALL_BYTES)
        ]
        fuzzers[key].run_sequence(me, inst_seed, calls)

    one_sequence()
    return stats


def required_cells() -> dict[tuple[str, str], str]:
    """Every (function, state) cell of the model's table and the outcome the run must have
    seen there at least once: OK where the call is allowed, Error where it is not. Every
    state is reachable (Co-Simulation instances reach StepMode, Model Exchange instances
    EventMode and ContinuousTimeMode)."""
    return {(fn, s): ("OK" if s in allowed else "Error") for fn, allowed in ALLOWED.items() for s in ALL_STATES}


def test_fuzz_fmi_call_sequences():
    libs = {"extreme_free": shared_library("extreme_free"), "sleeping_top": shared_library("sleeping_top")}
    # no hang: a C-level infinite loop cannot be interrupted from Python, so a watchdog
    # dumps the stacks and ends the process (far above the ~25 s this run takes)
    faulthandler.dump_traceback_later(300, exit=True)
    try:
        t0 = time.perf_counter()
        stats = fuzz(libs, N_SEQUENCES)
        wall = time.perf_counter() - t0
    finally:
        faulthandler.cancel_dump_traceback_later()
    outcomes = Counter()
    for (_, _, status), n in stats.transitions.items():
        outcomes[status] += n
    print(
        f"\nfuzz: {stats.sequences} sequences, {stats.calls} calls ({stats.refused} refused), {wall:.1f} s, "
        f"slowest sequence {stats.max_sequence_time * 1e3:.1f} ms; outcomes {dict(outcomes)}; "
        f"doStep OK {stats.transitions[('fmi3DoStep', STEP, 'OK')]}"
    )
    assert stats.sequences >= N_SEQUENCES
    missing = [
        f"{fn} in {state}: never {want}"
        for (fn, state), want in required_cells().items()
        if stats.transitions[(fn, state, want)] == 0
    ]
    assert not missing, "state-table cells never exercised with the required outcome:\n" + "\n".join(missing)


@pytest.mark.parametrize(
    "fn, state, flip",
    [
        ("fmi3Terminate", INST, "allow"),  # a call the FMU must refuse, modelled as allowed
        ("fmi3GetFloat64", STEP, "forbid"),  # a call the FMU must accept, modelled as refused
    ],
)
def test_fuzz_oracle_detects_a_wrong_model(monkeypatch, fn, state, flip):
    """The oracle is live: with one cell of the model's table wrong, a short run fails."""
    table = {k: set(v) for k, v in ALLOWED.items()}
    (table[fn].add if flip == "allow" else table[fn].discard)(state)
    monkeypatch.setattr(sys.modules[__name__], "ALLOWED", table)
    with pytest.raises(AssertionError, match=fn):
        fuzz({"extreme_free": shared_library("extreme_free")}, 300, shrink=False)


# ---------------------------------------------------------------------------------------
# The sanitized run (AddressSanitizer + UBSan + LeakSanitizer) in a subprocess
# ---------------------------------------------------------------------------------------


def _sanitizer_available() -> str | None:
    """None when gcc can build and run a program with -fsanitize=address,undefined, else
    the reason it cannot."""
    if shutil.which("gcc") is None:
        return "gcc not found"
    with tempfile.TemporaryDirectory() as tmp:
        src = Path(tmp) / "t.c"
        src.write_text("#include <stdlib.h>\nint main(void){char*p=malloc(4);p[0]=1;int r=p[0]-1;free(p);return r;}\n")
        proc = subprocess.run(
            ["gcc", "-fsanitize=address,undefined", str(src), "-o", str(Path(tmp) / "t")],
            capture_output=True,
            text=True,
        )
        if proc.returncode != 0:
            return f"gcc cannot compile with -fsanitize=address,undefined: {proc.stderr.strip()[:300]}"
        run = subprocess.run([str(Path(tmp) / "t")], capture_output=True, text=True)
        if run.returncode != 0:
            return f"a program built with -fsanitize=address,undefined does not run: {run.stderr[:300]}"
    lib = subprocess.run(["gcc", "-print-file-name=libasan.so"], capture_output=True, text=True).stdout.strip()
    if not os.path.isabs(lib) or not os.path.exists(lib):
        return "gcc -print-file-name=libasan.so does not name an existing shared libasan"
    return None


def _sanitizer_env() -> dict[str, str]:
    env = dict(os.environ)
    libasan = subprocess.run(["gcc", "-print-file-name=libasan.so"], capture_output=True, text=True).stdout.strip()
    env["LD_PRELOAD"] = libasan  # ASan's runtime must come first; python itself is not instrumented
    env["ASAN_OPTIONS"] = "detect_leaks=1"
    env["UBSAN_OPTIONS"] = "halt_on_error=1:print_stacktrace=1"
    env["PYTHONPATH"] = str(Path(__file__).resolve().parent.parent)
    return env


def _leak_blocks(stderr: str) -> list[str]:
    """The LeakSanitizer report split into one text block per leaked allocation."""
    return re.findall(r"(?:Direct|Indirect) leak of .*?(?:\n\s*\n|\Z)", stderr, flags=re.S)


def _fmu_frames(block: str, so_name: str) -> bool:
    """True when an allocation stack passes through the FMU's code (its .so or an fmi3*
    function); the python interpreter's own blocks left at exit do not."""
    return so_name in block or "fmi3" in block or "model_funcs" in block


SANITIZER_FAULTS = ("ERROR: AddressSanitizer", "runtime error:", "SUMMARY: UndefinedBehaviorSanitizer")


def test_asan_fuzz(tmp_path):
    reason = _sanitizer_available()
    if reason:
        pytest.skip(f"compiler lacks the sanitizers: {reason}")
    fmu = shared_fmu("extreme_free", sanitize=True)
    so_name = "extreme_free.so"
    env = _sanitizer_env()
    cmd = [sys.executable, "-m", "tests.test_fuzz_fmi", "--fmu", str(fmu), "--workdir", str(tmp_path)]
    # positive control: an instance leaked on purpose must be reported with the FMU's frames
    canary = subprocess.run(cmd + ["--leak-canary"], capture_output=True, text=True, env=env, timeout=120)
    assert "CANARY-DONE" in canary.stdout, canary.stderr[-3000:]
    leaks = [b for b in _leak_blocks(canary.stderr) if _fmu_frames(b, so_name)]
    assert leaks and "fmi3InstantiateCoSimulation" in "".join(leaks), (
        f"LeakSanitizer did not report the deliberately leaked instance:\n{canary.stderr[-3000:]}"
    )
    # the sanitized fuzz run
    run = subprocess.run(
        cmd + ["--sequences", str(N_SEQUENCES_ASAN)], capture_output=True, text=True, env=env, timeout=600
    )
    out = run.stdout + run.stderr
    for fault in SANITIZER_FAULTS:
        assert fault not in out, f"sanitizer report:\n{out[-6000:]}"
    assert "FUZZ-DONE" in run.stdout, f"sanitized fuzz run failed (exit {run.returncode}):\n{out[-6000:]}"
    fmu_leaks = [b for b in _leak_blocks(run.stderr) if _fmu_frames(b, so_name)]
    assert not fmu_leaks, "leaks in the FMU:\n" + "\n".join(fmu_leaks)
    # python's own blocks left at exit (none through the FMU, checked above) make
    # LeakSanitizer end the process with a nonzero code; nothing else may
    assert run.returncode == 0 or "ERROR: LeakSanitizer: detected memory leaks" in run.stderr, out[-3000:]
    stats = json.loads(run.stdout.split("FUZZ-DONE", 1)[1])
    print(
        f"\nASan fuzz: {stats['sequences']} sequences, {stats['calls']} calls ({stats['refused']} refused), "
        f"slowest {stats['max_sequence_time'] * 1e3:.1f} ms; leak blocks outside the FMU "
        f"(python at exit): {len(_leak_blocks(run.stderr))}"
    )
    assert stats["sequences"] >= N_SEQUENCES_ASAN


HARNESS = Path(__file__).resolve().parent / "c" / "alloc_count.c"


def test_no_heap_use_in_do_step(tmp_path):
    """tests/c/alloc_count.c linked with the FMU's own sources and --wrap=malloc,calloc,
    realloc,free: doStep (every method, with the sets and gets between steps and the
    refused calls) allocates and frees nothing; instantiate/free and FMU states balance."""
    from fmu.build_fmu import CFLAGS, GENERATED_EXTRA

    src = extract_fmu(shared_fmu("extreme_free"), tmp_path / "fmu") / "sources"
    exe = tmp_path / "alloc_count"
    c_files = [HARNESS] + [src / f for f in ("rbfmu_fmi3.c", "rbfmu_core.c", "model_funcs.c")]
    flags = [f for f in CFLAGS if f not in ("-fPIC", "-fvisibility=hidden")] + GENERATED_EXTRA
    build = subprocess.run(
        [
            "gcc",
            *flags,
            "-I",
            str(src),
            *map(str, c_files),
            "-lm",
            "-Wl,--wrap=malloc,--wrap=calloc,--wrap=realloc,--wrap=free",
            "-o",
            str(exe),
        ],
        capture_output=True,
        text=True,
    )
    assert build.returncode == 0, build.stderr
    run = subprocess.run([str(exe)], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0 and run.stdout.rstrip().endswith("done"), run.stdout + run.stderr
    phases: dict[str, list[dict[str, int]]] = {}
    for line in run.stdout.splitlines():
        if line.startswith("phase="):
            name, *counts = line.split()
            phases.setdefault(name[6:], []).append({k: int(v) for k, v in (c.split("=") for c in counts)})
    totals = dict(kv.split("=") for kv in run.stdout.split() if kv.startswith("total_"))
    print("\n" + run.stdout)
    step_phases = [p for p in phases if p.startswith("step_")]
    assert len(step_phases) == 7, phases  # every method of the scene
    for name in step_phases + ["terminate_reset", "refused_instantiation"]:
        for counts in phases[name]:
            assert counts == {"malloc": 0, "calloc": 0, "realloc": 0, "free": 0}, (name, counts)
    # the counters see the FMU's allocations: instantiation allocates (instance, name, env)
    life = phases["lifecycle"][0]
    assert life["malloc"] + life["calloc"] > 0 and life["malloc"] + life["calloc"] == life["free"], life
    snap = phases["fmu_state"][0]  # two states (one via deserialize), both freed
    assert snap["malloc"] + snap["calloc"] == 2 and snap["free"] == 2, snap
    assert int(totals["total_alloc"]) == int(totals["total_free"]) > 0, totals


def _main() -> None:
    """Entry point of the sanitized subprocess: python -m tests.test_fuzz_fmi --fmu F --workdir D
    [--sequences N | --leak-canary]. The FMU is extracted into D, which must outlive the
    process: LeakSanitizer symbolizes its report at exit, from the .so on disk."""
    ap = argparse.ArgumentParser()
    ap.add_argument("--fmu", required=True, type=Path)
    ap.add_argument("--workdir", required=True, type=Path)
    ap.add_argument("--sequences", type=int, default=100)
    ap.add_argument("--leak-canary", action="store_true")
    args = ap.parse_args()
    lib = Fmi3Library(extract_fmu(args.fmu, args.workdir / ("canary" if args.leak_canary else "fuzz")))
    if args.leak_canary:
        inst = lib.instantiate()
        assert inst.handle
        inst.handle = None  # dropped without fmi3FreeInstance: a leak LeakSanitizer must report
        print("CANARY-DONE", flush=True)
        return
    stats = fuzz({"extreme_free": lib}, args.sequences)
    print("FUZZ-DONE" + json.dumps(stats.as_dict()), flush=True)


if __name__ == "__main__":
    _main()
