"""The fuzz test's driver: random FMI call sequences through ctypes, each call judged against the model.

Sequences come from hypothesis byte strings (tests/robustness/test_fuzz_fmi.py runs them); the
expected outcome of each call comes from tests/harness/fuzz_fmi_model.py (its state table is read
through the module, `spec.ALLOWED`, so a test can replace it).
"""

from __future__ import annotations

import copy
import ctypes as C
import math
import random
import time

from . import fuzz_fmi_attacks as attacks
from . import fuzz_fmi_model as spec
from .fmi3_ctypes import ERROR, OK, Fmi3Instance, Fmi3Library
from .fuzz_fmi_model import (
    ALL_CHECKS,
    BAD_STEP_SIZES,
    CONT,
    COST,
    ERR,
    EVENT,
    INIT,
    INST,
    METHOD_VALUES_BAD,
    NON_FINITE,
    P_INVALID,
    P_NON_FINITE,
    SETTABLE,
    START_TIMES,
    STEP,
    STEP_SIZES,
    TERM,
    UNIT_QUATERNIONS,
    Expect,
    FmuModel,
    Stats,
    values_of,
)
from .fuzz_fmi_sequences import FREE_IN_CALLBACK_SHARE, SEQUENCE_TIME_LIMIT, choose_kind


class Fuzzer:
    """Runs decoded call sequences against one library and checks them against FmuModel."""

    def __init__(self, lib: Fmi3Library, stats: Stats):
        self.lib, self.stats = lib, stats
        self.model = FmuModel(lib.info)
        kinds = self.model.kinds
        self.names = sorted(kinds, key=lambda n: lib.info.vr[n])
        self.never_settable = [n for n in self.names if kinds[n] in ("independent", "output", "derivative", "local")]
        self.settable = [n for n in self.names if n not in self.never_settable]
        self.settable_later = [n for n in self.names if STEP in SETTABLE[kinds[n]] or CONT in SETTABLE[kinds[n]]]
        self.snapshots: list[list] = []  # [ctypes handle, ModelState]
        self.freed: list[int] = []  # addresses of FMU states freed in this sequence (never valid again)

    # ---- argument decoding ----
    def _value_for(self, rng: random.Random, name: str) -> float:
        r = rng.random()
        if r < P_NON_FINITE:
            return rng.choice(NON_FINITE)
        valid, invalid = values_of(name, self.model.kinds.get(name))
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
        """A unit quaternion, then each further state's valid values (w_body, x_cm, v_cm,
        Omega_<rotor>, orbit_angle); sometimes one non-finite."""
        x = list(rng.choice(UNIT_QUATERNIONS))
        x += [rng.choice(values_of(self.names[1 + k])[0]) for k in range(len(x), self.model.nx)]
        if rng.random() < 0.1:
            x[rng.randrange(self.model.nx)] = rng.choice(NON_FINITE)
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
            exp = self._unchecked_overflow(inst, n_log, exp, status, [m.kinds.get(n) for _, n in pairs])
            after = lambda: self._compare_read([n for _, n in pairs], got)
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
            after = lambda: self._check(ivals[0] == m.s.method, f"method {ivals[0]}, model {m.s.method}")
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
            if h == 1e308 and not m.s.values["h_max"] > 0:  # no cap: the rate limits of an untracked
                h = math.inf  # state size the steps (a body at rest takes 1e308 s in one); refusal unpredictable
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
            NX = m.nx
            n = NX if rng.random() < 0.95 else rng.choice((0, NX - 1, NX + 1))
            fn = "fmi3GetContinuousStates" if kind == "get_states" else "fmi3GetContinuousStateDerivatives"
            exp = self._refusal(fn) or (
                Expect(False, (f"{NX} continuous states, got {n}",)) if n != NX else Expect(True)
            )
            status, x = (inst.get_continuous_states if kind == "get_states" else inst.get_derivatives)(n)
            if kind == "get_derivatives":
                exp = self._unchecked_overflow(inst, n_log, exp, status, ["derivative"])
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
            exp = self._refusal(fn) or (Expect(True) if snap else Expect(False, ("not a live FMU state",)))
            status = inst.set_fmu_state(snap[0] if snap else None)
            if exp.ok:
                m.s = copy.deepcopy(snap[1])
        elif kind == "free_fmu_state":
            fn = "fmi3FreeFMUState"
            exp = self._refusal(fn) or Expect(True)
            if self.snapshots and rng.random() < 0.8:
                snap = self.snapshots.pop(rng.randrange(len(self.snapshots)))
                self.freed.append(snap[0].value)
                status = inst.free_fmu_state(snap[0])
                self._check(status != OK or not snap[0].value, "FreeFMUState must set the pointer to NULL")
            else:
                status = inst.free_fmu_state(C.c_void_p())  # freeing NULL: a no-op
        elif kind == "serialize_roundtrip":
            status, exp, fn = self._serialize_roundtrip(inst, rng)
        elif kind in ("crafted_state", "misuse"):
            status, exp, fn = (attacks.crafted_state if kind == "crafted_state" else attacks.misuse)(self, inst, rng)
        else:
            raise AssertionError(kind)
        self._judge(inst, fn, state_before, n_log, status, exp, seed)
        if status == OK and after is not None:
            after()

    def _serialize_roundtrip(self, inst: Fmi3Instance, rng: random.Random):
        """SerializedFMUStateSize + SerializeFMUState + DeserializeFMUState of a snapshot
        (allowed in every state), with a wrong size or a corrupted token sometimes."""
        if not self.snapshots:  # NULL is no FMU state of this instance
            status, size = inst.serialized_size(None)
            return status, Expect(False, ("not a live FMU state",)), "fmi3SerializedFMUStateSize"
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

    def _unchecked_overflow(
        self, inst: Fmi3Instance, n_log: int, exp: Expect, status: int, kinds: list[str | None]
    ) -> Expect:
        """A Get of outputs or derivatives at values not yet checked (no valid run: start
        values in InitializationMode, the Error state) is refused when one is non-finite
        (docs/robustness.md, Values entering and leaving the FMU); the model does not compute
        the outputs, so such a refusal, naming the value, is what it expects there. In a
        valid run the prediction stands."""
        s = self.model.s
        computed = any(k in ("output", "derivative") for k in kinds)
        named = any("would be" in e for e in inst.errors_since(n_log))
        if exp.ok and not s.valid_run and computed and status == ERROR and named:
            return Expect(False, ("would be",))
        return exp

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
        assert status == exp.status, f"{where}: must be refused with status {exp.status}, got {status}"
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
        if self.model.s.state in spec.ALLOWED[fn]:
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
        if m.overflows():  # checks pass, an output is non-finite (docs/robustness.md §2)
            s.state = ERR
            return Expect(False, ("would be", f"{m.overflows()}="), frozenset())
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
        if not (math.isfinite(t + h) and t + h > t):
            return Expect(False, ("the time overflows" if not math.isfinite(t + h) else "resolution",))
        # fixed steps (the fuzzed tolerance is 0): ceil(H/h_max) for the h_max part, 1 without
        # a cap; the rounding guard of docs/theory.md §5.4 is below 1e-6 relative
        steps = h / s.values["h_max"] * (1.0 - 1e-6) if s.values["h_max"] > 0 else 1.0
        steps = math.ceil(steps) if math.isfinite(steps) else steps
        if steps * COST[self.model.method_names[s.method]] > s.values["work_limit"]:  # refused before it runs
            return Expect(False, ("internal steps", "more than work_limit", "raise the tunable parameter work_limit"))
        s.values["time"] = t + h  # the layer continues from the caller's t (within tolerance)
        s.states_known = False
        return Expect(True)

    def _expect_set_states(self, x: list[float]) -> Expect:
        s, NX = self.model.s, self.model.nx
        if len(x) != NX:
            return Expect(False, (f"{NX} continuous states, got {len(x)}",))
        for k, v in enumerate(x):
            if not math.isfinite(v):
                return Expect(False, (f"'{self.names[1 + k]}'", "must be finite"))
        old = dict(s.values)
        for k, v in enumerate(x):
            s.values[self.names[1 + k]] = v
        bad = self.model.violated()
        if bad:  # a state outside the model's domain (x_cm at the central body): Discard, unchanged
            s.values = old
            return Expect(False, ("state values:",), frozenset(bad), status=2)
        s.states_known = True
        return Expect(True)

    def _compare_read(self, names: list[str | None], got: list[float]) -> None:
        m, s = self.model, self.model.s
        where = f"read in state {s.state}"
        for name, x in zip(names, got):
            kind = m.kinds[name]
            if kind == "local":  # the step report: counts and step sizes the model does not predict
                assert math.isfinite(x) and x >= 0, f"{where}: {name} = {x}"
                continue
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
        self.snapshots, self.freed = [], []
        variant = rng.random()
        logging_on = rng.random() < 0.5
        fn = "fmi3InstantiateModelExchange" if me else "fmi3InstantiateCoSimulation"
        # CPU time of this process, not wall time: a spinning FMU (the hang this guards
        # against) burns CPU, while a loaded machine (other test workers) only delays it.
        t0 = time.process_time()
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
            # some Co-Simulation instances end by fmi3FreeInstance from inside the
            # intermediate-update callback of a doStep (issue 23.2): they get a callback
            inputs = [vr for name, vr in self.lib.info.vr.items() if name.startswith("tau_body")]
            free_in_callback = not me and bool(inputs) and rng.random() < FREE_IN_CALLBACK_SHARE
            armed: list[Fmi3Instance] = []

            def update(_t: float) -> None:
                if armed:
                    self.lib.FreeInstance(armed.pop().handle)

            inst = self.lib.instantiate(
                logging_on=logging_on,
                model_exchange=me,
                intermediate_update=update if free_in_callback else None,
                required=inputs if free_in_callback else (),
            )
            assert inst.handle, f"instantiation failed: {inst.log}"
            assert not inst.errors_since(0), inst.log
            try:
                for byte, seed in calls:
                    self.run_call(inst, choose_kind(self.model.s.state, byte), seed)
            finally:
                for handle, _ in self.snapshots:
                    if rng.random() < 0.5:  # the others are left to fmi3FreeInstance, which frees them
                        assert inst.free_fmu_state(handle) == OK
                if free_in_callback and self.model.s.state == STEP:
                    self._free_in_callback(inst, armed)
                inst.free()
        elapsed = time.process_time() - t0
        self.stats.sequences += 1
        self.stats.max_sequence_time = max(self.stats.max_sequence_time, elapsed)
        assert elapsed < SEQUENCE_TIME_LIMIT, f"sequence took {elapsed:.2f} s (> {SEQUENCE_TIME_LIMIT} s)"

    def _free_in_callback(self, inst: Fmi3Instance, armed: list[Fmi3Instance]) -> None:
        """A doStep whose intermediate-update callback calls fmi3FreeInstance: the free is
        deferred to the end of the doStep, which returns fmi3Error (docs/fmi_layer.md,
        Intermediate update); the instance is then gone (LeakSanitizer checks that it and
        its FMU states were freed). A doStep the work limit refuses asks nothing."""
        armed.append(inst)
        n = len(inst.log)
        status = inst.do_step(self.model.s.values["time"], 1e-3)[0]
        self.stats.calls += 1
        if armed:  # never asked: refused before any internal step, or no node to ask at
            armed.clear()
            return
        self.stats.transitions[("fmi3FreeInstance", spec.IUM, "deferred")] += 1
        inst.handle = None  # freed by the doStep
        text = "\n".join(m for _, _, m in inst.log[n:])
        assert status == ERROR, f"doStep with fmi3FreeInstance in its callback returned {status}: {text}"
        assert "fmi3FreeInstance: called in state IntermediateUpdateMode" in text, text

    def _expect_null(self, inst: Fmi3Instance, fn: str, fragment: str) -> None:
        self.stats.calls += 1
        self.stats.refused += 1
        self.stats.transitions[(fn, "-", "NULL")] += 1
        assert not inst.handle, f"{fn} must return NULL"
        text = "\n".join(inst.errors_since(0))
        assert fn in text and fragment in text, inst.log
