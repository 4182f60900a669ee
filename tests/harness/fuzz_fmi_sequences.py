"""The fuzz test's call sequences: how many, the shares of each kind of instance, and the kinds drawn per state.

A sequence is one hypothesis byte string (SEQUENCES): a header choosing the FMU, the
interface and the instantiation seed, then CALL_BYTES per call; choose_kind maps a choice
byte to a call kind, guided by the instance's current state (tests/harness/fuzz_fmi_driver.py
runs them, tests/robustness/test_fuzz_fmi.py decides how many).
"""

from __future__ import annotations

from hypothesis import strategies as st

from .fuzz_fmi_model import CONT, ERR, EVENT, INIT, INST, STEP, TERM

N_SEQUENCES = 10_000  # in-process run: 1e4 sequences (docs/robustness.md §3)
N_SEQUENCES_ASAN = 1_500  # sanitized run: ~4x slower per call under ASan + UBSan
SEQUENCE_TIME_LIMIT = 2.0  # s of CPU time; the slowest legal sequence (60 gauss6 doSteps of 50
#                               substeps at ~12 µs) takes ~40 ms, ~0.2 s under ASan
FREE_SHARE = 0.7  # fraction of sequences on extreme_free (the rest: sleeping_top)
ME_SHARE = 0.25  # fraction of Model Exchange instances
FREE_IN_CALLBACK_SHARE = 0.1  # of the Co-Simulation instances with inputs (issue 23.2)

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
    "crafted_state",  # tests/harness/fuzz_fmi_attacks.py: bit flips and crafted fields of serialized states
    "misuse",  # tests/harness/fuzz_fmi_attacks.py: foreign FMU-state pointers, NULL arrays
)
GUIDED_SHARE = 0.8
_SNAP = {
    "get_fmu_state": 0.3,
    "set_fmu_state": 0.3,
    "free_fmu_state": 0.1,
    "serialize_roundtrip": 0.2,
    "crafted_state": 0.2,
    "misuse": 0.1,
}
GUIDED = {
    INST: {"set_float64": 5, "set_int64": 1, "enter_init": 3, "reset": 0.2, "misuse": 0.1},
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
