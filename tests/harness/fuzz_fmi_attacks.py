"""The fuzz test's attacks: crafted and bit-flipped serialized FMU states, and calls an importer gets wrong.

Two call kinds of tests/harness/fuzz_fmi_driver.py, each returning (status, Expect, function):
- `crafted_state` serializes one of the sequence's snapshots and deserializes it altered:
  one bit flipped anywhere (the CRC-32 or the token must catch it), or, with a fresh CRC
  (tests/harness/fmu_state_bytes.py), a field no saved instance holds (interface, instance state,
  method, format, count) or one value replaced. A replaced value must pass what the API
  checks: finite always, and the generated validity checks once the saved instance was
  initialised; an accepted state joins the snapshots with the value in its model, so
  that restoring it later is predicted too.
- `misuse` hands the FMU pointers that are not its FMU states (a buffer of the test's, the
  address of a state freed earlier) and NULL arrays, and checks that nothing was written.
"""

from __future__ import annotations

import copy
import ctypes as C
import math
import random
from dataclasses import replace
from typing import TYPE_CHECKING

from .fmi3_ctypes import OK, Fmi3Instance
from .fmu_state_bytes import CO_SIMULATION, MODEL_EXCHANGE, STATE_NUMBERS, StateBytes
from .fuzz_fmi_model import ERR, INIT, NON_FINITE, START_TIMES, Expect, values_of

if TYPE_CHECKING:
    from .fuzz_fmi_driver import Fuzzer

Outcome = tuple[int, Expect, str]
FOREIGN = "not a live FMU state of this instance"


def _serialized(fz: Fuzzer, inst: Fmi3Instance, snap: list) -> bytes:
    """The bytes of a snapshot, the two calls judged as successful ones."""
    n_log = len(inst.log)
    status, size = inst.serialized_size(snap[0])
    fz._judge(inst, "fmi3SerializedFMUStateSize", fz.model.s.state, n_log, status, Expect(True), 0)
    n_log = len(inst.log)
    status, data = inst.serialize(snap[0], size)
    fz._judge(inst, "fmi3SerializeFMUState", fz.model.s.state, n_log, status, Expect(True), 0)
    return data


def _crafted_value(fz: Fuzzer, sb: StateBytes, model_state, rng: random.Random) -> tuple[bytes, Expect, object]:
    """One value of the state replaced (fresh CRC); the prediction, and the snapshot's model
    state if the FMU must accept it."""
    m = fz.model
    names = [n for n in fz.names[: len(sb.values)] if m.kinds[n] not in ("state",)]
    name = rng.choice(names)
    if rng.random() < 0.3:
        value = rng.choice(NON_FINITE)
    elif name == "time":
        value = rng.choice(START_TIMES)
    else:
        valid, invalid = values_of(name, m.kinds[name], default=(0.0, 1.0))  # the step report: >= 0
        value = rng.choice(valid + invalid)
    data = sb.with_value(m.info.vr[name], value).pack()
    if not math.isfinite(value):
        return data, Expect(False, (f"'{name}'", "must be finite")), None
    new = copy.deepcopy(model_state)
    new.values[name] = value
    if model_state.state in (INIT, ERR):  # values as the API takes them there: only finite
        return data, Expect(True), new
    saved, m.s = m.s, new
    try:
        bad = m.violated()
    finally:
        m.s = saved
    if bad:
        return data, Expect(False, ("fails the checks a running instance passes",), frozenset(bad)), None
    return data, Expect(True), new


def crafted_state(fz: Fuzzer, inst: Fmi3Instance, rng: random.Random) -> Outcome:
    """Deserialize a snapshot altered by a bit flip or a crafted field (see the module)."""
    fn = "fmi3DeserializeFMUState"
    if not fz.snapshots:  # bytes of no state at all
        status, handle = inst.deserialize(bytes(rng.randrange(256) for _ in range(rng.randrange(1, 64))))
        return status, Expect(False, ("not a serialized state",)), fn
    snap = fz.snapshots[rng.randrange(len(fz.snapshots))]
    data = _serialized(fz, inst, snap)
    sb = StateBytes.parse(data)
    accepted = None
    r = rng.random()
    if r < 0.4:  # one bit flipped anywhere: the token's bytes, the fields, the values or the CRC
        bit = rng.randrange(8 * len(data))
        flipped = bytearray(data)
        flipped[bit // 8] ^= 1 << (bit % 8)
        data = bytes(flipped)
        exp = Expect(False, ("not a serialized state" if bit // 8 < len(sb.token) else "is corrupted",))
    elif r < 0.5:
        own = MODEL_EXCHANGE if fz.model.me else CO_SIMULATION
        kind = rng.choice((7, 2**32 - 1, 1 - own))
        data = replace(sb, interface=kind).pack()
        exp = Expect(False, ("taken from a",) if kind == 1 - own else (f"interface type {kind}",))
    elif r < 0.6:
        other = STATE_NUMBERS["StepMode" if fz.model.me else "ContinuousTimeMode"]
        st = rng.choice((STATE_NUMBERS["Instantiated"], other, 7, 2**32 - 1))
        data = replace(sb, state=st).pack()
        exp = Expect(False, ("never saved in",))
    elif r < 0.67:
        data = replace(sb, method=rng.choice((0, 99, -1, 2**40))).pack()
        exp = Expect(False, ("not compiled into this FMU",))
    elif r < 0.72:
        data = replace(sb, fmt=2).pack() if rng.random() < 0.5 else sb.pack(len(sb.values) + 1)
        exp = Expect(False, ("this FMU reads format",))
    else:
        data, exp, accepted = _crafted_value(fz, sb, snap[1], rng)
    status, handle = inst.deserialize(data)
    kind = "bit flip" if r < 0.4 else "crafted field" if r < 0.72 else "crafted value"
    fz.stats.attacks[f"{kind}, {'accepted' if status == OK else 'refused'}"] += 1
    if status == OK and accepted is not None:
        fz.snapshots.append([handle, accepted])
    elif status != OK:
        fz._check(not handle.value, "a refused DeserializeFMUState must not return a state")
    return status, exp, fn


MISUSE_CASES = 11


def misuse(fz: Fuzzer, inst: Fmi3Instance, rng: random.Random, case: int | None = None) -> Outcome:
    """One call with a pointer that is not one of the instance's FMU states, or a NULL
    array where the call has elements (case 0..MISUSE_CASES-1, else drawn); the refusal
    is predicted, and nothing is written."""
    lib, h, m = inst.lib, inst.handle, fz.model
    buffer = (C.c_ubyte * 64)()  # memory of the test's own: must stay untouched
    # a freed state's address, unless the allocator has handed it out again for a live one
    freed = [a for a in fz.freed if a not in {s[0].value for s in fz.snapshots}]
    foreign = C.c_void_p(freed[-1] if freed and rng.random() < 0.5 else C.addressof(buffer))
    address = foreign.value
    vr1 = (C.c_uint32 * 1)(m.info.vr["time"])
    case = rng.randrange(MISUSE_CASES) if case is None else case
    if case == 0:
        fn, status = "fmi3GetFMUState", lib.GetFMUState(h, C.byref(foreign))
        fz._check(foreign.value == address, "GetFMUState replaced a foreign pointer")
        why = FOREIGN
    elif case == 1:
        fn, status, why = "fmi3SetFMUState", lib.SetFMUState(h, foreign), FOREIGN
    elif case == 2:
        fn, status, why = "fmi3FreeFMUState", lib.FreeFMUState(h, C.byref(foreign)), FOREIGN
    elif case == 3:
        fn, status, why = "fmi3SerializeFMUState", lib.SerializeFMUState(h, foreign, buffer, 64), FOREIGN
    elif case == 4:
        size = C.c_size_t(0)
        fn, status, why = "fmi3SerializedFMUStateSize", lib.SerializedFMUStateSize(h, foreign, C.byref(size)), FOREIGN
    elif case == 5 and fz.snapshots:
        fn, why = "fmi3SerializedFMUStateSize", "the pointer for the result is NULL"
        status = lib.SerializedFMUStateSize(h, fz.snapshots[0][0], None)
    elif case == 6:
        fn, status, why = "fmi3GetFloat64", lib.GetFloat64(h, vr1, 1, None, 1), "the value array is NULL"
    elif case == 7:
        values = (C.c_double * 1)(1.0)
        why = "the value reference array is NULL"
        fn, status = "fmi3SetFloat64", lib.SetFloat64(h, None, 1, values, 1)
    elif case == 8:
        method = (C.c_uint32 * 1)(m.method_vr)
        fn = rng.choice(("fmi3GetInt64", "fmi3SetInt64"))
        status, why = getattr(lib, fn[4:])(h, method, 1, None, 1), "values is NULL"
    elif case == 9:
        fn, status, why = "fmi3GetContinuousStates", lib.GetContinuousStates(h, None, m.nx), "the array is NULL"
    else:  # with a pointer (allowed in every state) or with NULL
        fn, count = "fmi3GetNumberOfContinuousStates", C.c_size_t(0)
        if rng.random() < 0.5:
            status = lib.GetNumberOfContinuousStates(h, C.byref(count))
            fz._check(status != OK or count.value == m.nx, f"{count.value} continuous states")
            return status, Expect(True), fn
        status, why = lib.GetNumberOfContinuousStates(h, None), "the pointer for the result is NULL"
    fz._check(bytes(buffer) == bytes(64), f"{fn} wrote into memory that is not its own")
    fz.stats.attacks["foreign FMU state" if why == FOREIGN else "NULL array or result pointer"] += 1
    return status, fz._refusal(fn) or Expect(False, (why,)), fn
