"""FMU states an importer hands back are checked like values set through the API: integrity, interface, values.

A serialized state is read through its documented layout (tests/harness/fmu_state_bytes.py:
fields, then zlib's CRC-32 of them), so these tests craft states the FMU never made,
with a valid CRC, and see each refused with a message naming what is wrong; the
instance is unchanged after every refusal and steps on. Pointers that are not one of
the instance's FMU states are refused without being written to or freed.
"""

from __future__ import annotations

import ctypes as C
import math
import zlib
from dataclasses import replace

import pytest

from ..harness.fmi3_ctypes import OK, Fmi3Instance
from ..harness.fmu_state_bytes import CO_SIMULATION, MODEL_EXCHANGE, STATE_NUMBERS, StateBytes
from ..harness.misuse_helpers import STEP, in_state, refused

STATE_NAMES = [f"q[{k}]" for k in range(1, 5)] + [f"w_body[{k}]" for k in range(1, 4)]


def _serialized(inst: Fmi3Instance) -> tuple[bytes, C.c_void_p]:
    status, snap = inst.get_fmu_state()
    assert status == OK, inst.log
    status, size = inst.serialized_size(snap)
    assert status == OK, inst.log
    status, data = inst.serialize(snap, size)
    assert status == OK, inst.log
    return data, snap


def _stepped(lib, n: int = 3) -> Fmi3Instance:
    """A Co-Simulation instance in step mode after n doSteps of 1e-2 s from a tumbling start."""
    inst = lib.instantiate()
    vr = lib.info.vr
    assert inst.set_float64([vr["w_body[1]"], vr["w_body[2]"]], [0.3, 1.0]) == OK
    assert inst.enter_initialization_mode(0.0) == OK and inst.exit_initialization_mode() == OK
    for k in range(n):
        assert inst.do_step(k * 1e-2, 1e-2)[0] == OK
    return inst


def test_serialized_state_has_the_documented_layout_and_crc(free_lib):
    """The bytes parse as docs/fmi_layer.md says, hold the instance's values, end with
    zlib's CRC-32 of the rest, and identical states serialize identically (no padding or
    heap garbage in them): two instances with the same history, and one state twice."""
    a, b = _stepped(free_lib), _stepped(free_lib)
    data_a, snap_a = _serialized(a)
    data_b, snap_b = _serialized(b)
    assert data_a == data_b
    assert a.get_fmu_state(snap_a)[0] == OK and _serialized(a)[0] == data_a  # overwritten with the same state
    sb = StateBytes.parse(data_a)
    assert sb.token == free_lib.info.token.encode() + b"\0"
    assert (sb.fmt, sb.interface, sb.state) == (1, CO_SIMULATION, STATE_NUMBERS["StepMode"])
    assert sb.method == free_lib.info.int64_start["method"]
    assert sb.crc == zlib.crc32(sb.body()) and sb.pack() == data_a
    vr = free_lib.info.vr
    names = ["time", *STATE_NAMES, "h_max", "I_principal[2]", "work_limit"]
    assert [sb.values[vr[n]] for n in names] == a.get_float64([vr[n] for n in names])[1]
    for inst, snap in ((a, snap_a), (b, snap_b)):
        assert inst.free_fmu_state(snap) == OK
        inst.free()


def test_every_single_bit_flip_is_refused(free_lib):
    """All 8 x len bits, one at a time: the token catches flips in its bytes, the CRC-32
    every other (it detects every error of up to three bits at this length)."""
    inst = _stepped(free_lib)
    data, snap = _serialized(inst)
    token_bytes = len(free_lib.info.token) + 1
    refused_by = {"token": 0, "crc": 0}
    for bit in range(8 * len(data)):
        flipped = bytearray(data)
        flipped[bit // 8] ^= 1 << (bit % 8)
        n = len(inst.log)
        status, state = inst.deserialize(bytes(flipped))
        assert status != OK and not state.value, f"bit {bit}: a corrupted state was accepted"
        if bit // 8 < token_bytes:
            refused(inst, status, n, "fmi3DeserializeFMUState", "not a serialized state of this FMU build")
            refused_by["token"] += 1
        else:
            refused(inst, status, n, "fmi3DeserializeFMUState", "the serialized state is corrupted: its CRC-32")
            refused_by["crc"] += 1
    print(f"\n{8 * len(data)} single-bit flips of a {len(data)}-byte state refused: {refused_by}")
    status, state = inst.deserialize(data)  # the intact bytes still restore
    assert status == OK and inst.set_fmu_state(state) == OK
    for s in (snap, state):
        assert inst.free_fmu_state(s) == OK
    inst.free()


def _crafted(lib, sb: StateBytes, field: str, value) -> bytes:
    if field in ("interface", "state", "method", "fmt"):
        return replace(sb, **{field: value}).pack()
    if field == "count":
        return sb.pack(count=value)
    return sb.with_value(lib.info.vr[field], value).pack()


# (what is crafted, value, fragments of the refusal): each with a valid CRC
CRAFTED = [
    ("time", math.nan, ("'time' (vr 0) must be finite, got nan",)),
    ("h_max", math.nan, ("'h_max'", "must be finite, got nan")),
    ("h_max", -1.0, ("h_max must be >= 0 (0: no cap) (check value -1)", "fails the checks a running instance passes")),
    ("I_principal[1]", -1.0, ("inertia must be positive definite", "I_principal[1]=-1")),
    ("work_limit", 0.0, ("work_limit must be > 0",)),
    ("c_friction", -0.5, ("c_friction must be >= 0",)),
    ("tau_body[2]", math.inf, ("'tau_body[2]'", "must be finite, got inf")),
    ("interface", 7, ("interface type 7, neither Co-Simulation (0) nor Model Exchange (1)",)),
    ("interface", MODEL_EXCHANGE, ("taken from a Model Exchange instance; this one is Co-Simulation",)),
    ("state", STATE_NUMBERS["ContinuousTimeMode"], ("instance state 4 (ContinuousTimeMode)", "Co-Simulation")),
    ("state", STATE_NUMBERS["Instantiated"], ("instance state 0 (Instantiated)",)),
    ("state", 99, ("instance state 99 (unknown)",)),
    ("method", 99, ("method 99 is not compiled into this FMU",)),
    ("fmt", 2, ("format 2", "this FMU reads format 1")),
    ("count", 9, ("with 9 values",)),
]


@pytest.mark.parametrize("field, value, fragments", CRAFTED, ids=[f"{f}={v}" for f, v, _ in CRAFTED])
def test_crafted_state_is_refused_and_the_instance_is_unchanged(free_lib, field, value, fragments):
    inst = _stepped(free_lib)
    data, snap = _serialized(inst)
    vr = free_lib.info.vr
    names = ["time", *STATE_NAMES, "h_max", "I_principal[1]"]
    before = inst.get_float64([vr[n] for n in names])
    n = len(inst.log)
    status, state = inst.deserialize(_crafted(free_lib, StateBytes.parse(data), field, value))
    refused(inst, status, n, "fmi3DeserializeFMUState", *fragments)
    assert not state.value  # nothing allocated
    assert inst.get_float64([vr[n] for n in names]) == before
    assert inst.do_step(before[1][0], 1e-2)[0] == OK  # still in step mode and stepping
    assert inst.free_fmu_state(snap) == OK
    inst.free()


def test_crafted_values_of_an_unchecked_state_pass_like_values_set_in_initialisation(free_lib):
    """A state saved in InitializationMode holds start values not checked yet: a finite
    inertia (-1, -1, -1) is accepted as setting it would be, and exitInitializationMode
    then refuses it, as it would have."""
    inst = in_state(free_lib, "InitializationMode")
    data, snap = _serialized(inst)
    sb = StateBytes.parse(data)
    for k in (1, 2, 3):
        sb = sb.with_value(free_lib.info.vr[f"I_principal[{k}]"], -1.0)
    status, state = inst.deserialize(sb.pack())
    assert status == OK and inst.set_fmu_state(state) == OK, inst.log
    n = len(inst.log)
    refused(inst, inst.exit_initialization_mode(), n, "inertia must be positive definite", "I_principal[1]=-1")
    for s in (snap, state):
        assert inst.free_fmu_state(s) == OK
    inst.free()


def test_model_exchange_state_with_a_drifted_quaternion_restores(free_lib):
    """The importer's solver may leave |q| != 1 in Model Exchange (the outputs use q/|q|):
    such a state is the FMU's own and must restore, serialized or not."""
    inst = free_lib.instantiate(model_exchange=True)
    assert inst.enter_initialization_mode(0.0) == OK and inst.exit_initialization_mode() == OK
    assert inst.enter_continuous_time_mode() == OK
    assert inst.set_continuous_states([1.2, 0.3, 0.0, 0.0, 0.1, 0.2, 1.0]) == OK
    data, snap = _serialized(inst)
    status, copy = inst.deserialize(data)
    assert status == OK, inst.log
    assert inst.set_fmu_state(copy) == OK and inst.set_fmu_state(snap) == OK
    assert inst.get_continuous_states(7) == (OK, [1.2, 0.3, 0.0, 0.0, 0.1, 0.2, 1.0])
    for s in (snap, copy):
        assert inst.free_fmu_state(s) == OK
    inst.free()


def test_pointers_that_are_not_states_of_the_instance_are_refused_untouched(free_lib):
    """GetFMUState into *FMUState, SetFMUState, FreeFMUState, Serialize and its size with a
    pointer the instance did not make (memory of the test's, a freed state, a state of
    another instance): refused, nothing written or freed. Another instance's state moves
    by serialization."""
    inst, other = in_state(free_lib, STEP), in_state(free_lib, STEP)
    buffer = (C.c_ubyte * 512)()
    status, freed = inst.get_fmu_state()
    address = freed.value
    assert status == OK and inst.free_fmu_state(freed) == OK
    status, foreign_state = other.get_fmu_state()
    assert status == OK
    for foreign in (C.addressof(buffer), address, foreign_state.value):
        lib = free_lib
        for fn, call in (
            ("fmi3GetFMUState", lambda p: lib.GetFMUState(inst.handle, C.byref(p))),
            ("fmi3SetFMUState", lambda p: lib.SetFMUState(inst.handle, p)),
            ("fmi3FreeFMUState", lambda p: lib.FreeFMUState(inst.handle, C.byref(p))),
            ("fmi3SerializeFMUState", lambda p: lib.SerializeFMUState(inst.handle, p, buffer, 512)),
            ("fmi3SerializedFMUStateSize", lambda p: lib.SerializedFMUStateSize(inst.handle, p, C.byref(C.c_size_t()))),
        ):
            pointer = C.c_void_p(foreign)
            n = len(inst.log)
            refused(inst, call(pointer), n, fn, "is not a live FMU state of this instance")
            assert pointer.value == foreign and bytes(buffer) == bytes(512), fn
    _, data = other.serialize(foreign_state, other.serialized_size(foreign_state)[1])
    status, mine = inst.deserialize(data)  # the way between instances
    assert status == OK and inst.set_fmu_state(mine) == OK
    assert other.free_fmu_state(foreign_state) == OK and inst.free_fmu_state(mine) == OK
    other.free()
    inst.free()
