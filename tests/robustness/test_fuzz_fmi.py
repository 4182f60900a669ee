"""Fuzzing the FMI 3.0 layer (fmu/c/rbfmu_fmi3.c over rbfmu_core.c) with random call sequences.

One hypothesis example is the life of one instance: instantiation (Co-Simulation or
Model Exchange; sometimes with a wrong token, an empty name or eventModeUsed), a list
of FMI calls whose arguments are drawn from sets of valid and invalid values, then
fmi3FreeFMUState of every snapshot taken and fmi3FreeInstance. Calls go through ctypes
(tests/harness/fmi3_ctypes.py) to the FMU's shared library.

A Python model of the state machine (tests/harness/fuzz_fmi_model.py, written from
docs/fmi_layer.md and compared with the C masks by tests/fmi/test_fmi_rules.py) and of the
documented checks predicts
every call's outcome, and for every call the test asserts:
- the status is fmi3OK exactly when the model says the call is allowed and valid
  (a call that must be refused is refused, a call that must succeed succeeds);
- a refused call logs, during that call, an error-status message that names the
  function and says what is wrong (the model's fragments); an OK call logs no error;
- values read back are the model's: time, parameters, inputs, method, and the states
  until the first doStep (then finite, |q| = 1 to round-off); a restored FMU state
  brings back the values of its snapshot;
- no sequence takes longer than SEQUENCE_TIME_LIMIT (no hang), nothing crashes.
Two call kinds attack the layer (tests/harness/fuzz_fmi_attacks.py): serialized states with a bit
flipped or a field or value crafted under a valid CRC, and pointers that are not the
instance's FMU states or NULL arrays; their outcomes are predicted the same way.

test_asan_fuzz repeats a shorter run against an FMU built with AddressSanitizer and
UBSan, in a subprocess with libasan preloaded and leak detection on, after a positive
control showing that LeakSanitizer reports an instance leaked on purpose. Sequences end
by freeing about half of their FMU states and leaving the rest to fmi3FreeInstance,
which must free them (LeakSanitizer would report them).
"""

from __future__ import annotations

import argparse
import copy
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
from dataclasses import replace
from pathlib import Path

import pytest
from hypothesis import HealthCheck, Phase, given, settings

from fmu.build.build_fmu import c_sources

from ..harness import fuzz_fmi_attacks as attacks
from ..harness import fuzz_fmi_model as spec
from ..harness.fmi3_ctypes import ERROR, OK, Fmi3Library, extract_fmu, shared_fmu, shared_library
from ..harness.fmu_state_bytes import StateBytes
from ..harness.fuzz_fmi_driver import Fuzzer, Stats
from ..harness.fuzz_fmi_model import ALL_STATES, EVENT, INST, STEP
from ..harness.fuzz_fmi_sequences import (
    CALL_BYTES,
    FREE_SHARE,
    HEADER_BYTES,
    ME_SHARE,
    N_SEQUENCES,
    N_SEQUENCES_ASAN,
    SEQUENCES,
)


def fuzz(libs: dict[str, Fmi3Library], n_sequences: int, shrink: bool = True) -> Stats:
    """Run n_sequences hypothesis examples (derandomized: the same sequences every run)
    over the libraries: {"extreme_free": ..., optionally more} (extreme_free takes FREE_SHARE
    of the sequences, the others the rest), or libraries without extreme_free (an equal
    share each); return statistics. A mismatch raises AssertionError with hypothesis'
    (shrunk) falsifying example."""
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
        if "extreme_free" not in fuzzers:
            key = other[blob[0] % len(other)]
        else:
            key = other[blob[2] % len(other)] if other and blob[0] >= 256 * FREE_SHARE else "extreme_free"
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
    state but IntermediateUpdateMode is reachable (Co-Simulation instances reach StepMode,
    Model Exchange instances EventMode and ContinuousTimeMode); that one exists only inside
    an importer's intermediateUpdate callback, which the fuzzer does not pass:
    tests/fmi/test_inputs_inside_step_fmi3.py makes every call of the table there."""
    states = [s for s in ALL_STATES if s != spec.IUM]
    return {(fn, s): ("OK" if s in allowed else "Error") for fn, allowed in spec.ALLOWED.items() for s in states}


def watched_fuzz(libs: dict[str, Fmi3Library], n_sequences: int) -> tuple[Stats, float, Counter]:
    """`fuzz` under a watchdog: (stats, wall time in s, how many calls ended with each status).
    No hang: a C-level infinite loop cannot be interrupted from Python, so the watchdog dumps
    the stacks and ends the process (far above the ~25 s such a run takes)."""
    faulthandler.dump_traceback_later(300, exit=True)
    try:
        t0 = time.perf_counter()
        stats = fuzz(libs, n_sequences)
        wall = time.perf_counter() - t0
    finally:
        faulthandler.cancel_dump_traceback_later()
    outcomes: Counter = Counter()
    for (_, _, status), n in stats.transitions.items():
        outcomes[status] += n
    return stats, wall, outcomes


@pytest.mark.slow
def test_fuzz_fmi_call_sequences():
    libs = {"extreme_free": shared_library("extreme_free"), "sleeping_top": shared_library("sleeping_top")}
    stats, wall, outcomes = watched_fuzz(libs, N_SEQUENCES)
    print(
        f"\nfuzz: {stats.sequences} sequences, {stats.calls} calls ({stats.refused} refused), {wall:.1f} s, "
        f"slowest sequence {stats.max_sequence_time * 1e3:.1f} ms; outcomes {dict(outcomes)}; "
        f"doStep OK {stats.transitions[('fmi3DoStep', STEP, 'OK')]}; attacks {dict(sorted(stats.attacks.items()))}"
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
    table = {k: set(v) for k, v in spec.ALLOWED.items()}
    (table[fn].add if flip == "allow" else table[fn].discard)(state)
    monkeypatch.setattr(spec, "ALLOWED", table)
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
    env["PYTHONPATH"] = str(Path(__file__).resolve().parent.parent.parent)
    return env


def _leak_blocks(stderr: str) -> list[str]:
    """The LeakSanitizer report split into one text block per leaked allocation."""
    return re.findall(r"(?:Direct|Indirect) leak of .*?(?:\n\s*\n|\Z)", stderr, flags=re.S)


def _fmu_frames(block: str, so_name: str) -> bool:
    """True when an allocation stack passes through the FMU's code (its .so or an fmi3*
    function); the python interpreter's own blocks left at exit do not."""
    return so_name in block or "fmi3" in block or "model_funcs" in block


SANITIZER_FAULTS = ("ERROR: AddressSanitizer", "runtime error:", "SUMMARY: UndefinedBehaviorSanitizer")


@pytest.mark.sanitizer
def sanitized_fuzz_run(
    cmd: list[str], n_sequences: int, so_names: list[str]
) -> tuple[dict, subprocess.CompletedProcess]:
    """Run the fuzzer's command line `cmd` (this module's _main) under the sanitizers and assert
    what a clean run shows: no sanitizer report, the run's end marker, no leak through the
    FMUs' libraries (so_names) and no nonzero exit but LeakSanitizer's; return its statistics
    and the finished process."""
    run = subprocess.run(
        cmd + ["--sequences", str(n_sequences)], capture_output=True, text=True, env=_sanitizer_env(), timeout=600
    )
    out = run.stdout + run.stderr
    for fault in SANITIZER_FAULTS:
        assert fault not in out, f"sanitizer report:\n{out[-6000:]}"
    assert "FUZZ-DONE" in run.stdout, f"sanitized fuzz run failed (exit {run.returncode}):\n{out[-6000:]}"
    fmu_leaks = [b for b in _leak_blocks(run.stderr) if any(_fmu_frames(b, so) for so in so_names)]
    assert not fmu_leaks, "leaks in the FMU:\n" + "\n".join(fmu_leaks)
    # python's own blocks left at exit (none through the FMU, checked above) make
    # LeakSanitizer end the process with a nonzero code; nothing else may
    assert run.returncode == 0 or "ERROR: LeakSanitizer: detected memory leaks" in run.stderr, out[-3000:]
    return json.loads(run.stdout.split("FUZZ-DONE", 1)[1]), run


def test_asan_fuzz(tmp_path):
    reason = _sanitizer_available()
    if reason:
        pytest.skip(f"compiler lacks the sanitizers: {reason}")
    fmu = shared_fmu("extreme_free", sanitize=True)
    so_name = "extreme_free.so"
    env = _sanitizer_env()
    cmd = [sys.executable, "-m", "tests.robustness.test_fuzz_fmi", "--fmu", str(fmu), "--workdir", str(tmp_path)]
    # positive control: an instance leaked on purpose must be reported with the FMU's frames
    canary = subprocess.run(cmd + ["--leak-canary"], capture_output=True, text=True, env=env, timeout=120)
    assert "CANARY-DONE" in canary.stdout, canary.stderr[-3000:]
    leaks = [b for b in _leak_blocks(canary.stderr) if _fmu_frames(b, so_name)]
    assert leaks and "fmi3InstantiateCoSimulation" in "".join(leaks), (
        f"LeakSanitizer did not report the deliberately leaked instance:\n{canary.stderr[-3000:]}"
    )
    stats, run = sanitized_fuzz_run(cmd, N_SEQUENCES_ASAN, [so_name])
    print(
        f"\nASan fuzz: {stats['sequences']} sequences, {stats['calls']} calls ({stats['refused']} refused), "
        f"slowest {stats['max_sequence_time'] * 1e3:.1f} ms; attacks {stats['attacks']}; leak blocks outside the FMU "
        f"(python at exit): {len(_leak_blocks(run.stderr))}"
    )
    assert stats["sequences"] >= N_SEQUENCES_ASAN


def attack_battery(lib: Fmi3Library) -> dict[str, int]:
    """The attacks of tests/harness/fuzz_fmi_attacks.py made exhaustively, for the sanitized run: on
    a Co-Simulation instance in step mode and a Model Exchange one in event mode, every
    single-bit flip of its serialized state, a NaN in every saved value and each crafted
    field (all refused, nothing allocated), and every case of `misuse` (judged by the
    fuzzer's oracle). Returns how many of each were made."""
    counts = Counter()
    fz = Fuzzer(lib, Stats())
    for me in (False, True):
        fz.model.reset()
        fz.model.me = me
        inst = lib.instantiate(model_exchange=me)
        assert inst.enter_initialization_mode(0.0) == OK and inst.exit_initialization_mode() == OK
        fz.model.s.state = EVENT if me else STEP
        status, snap = inst.get_fmu_state()
        status, data = inst.serialize(snap, inst.serialized_size(snap)[1])
        assert status == OK, inst.log
        sb = StateBytes.parse(data)
        bad = []
        for bit in range(8 * len(data)):
            flipped = bytearray(data)
            flipped[bit // 8] ^= 1 << (bit % 8)
            bad.append(bytes(flipped))
        counts["bit flips"] += len(bad)
        crafted = [sb.with_value(vr, math.nan).pack() for vr in range(len(sb.values))]
        crafted += [replace(sb, interface=k).pack() for k in (7, 1 - sb.interface)]
        crafted += [replace(sb, state=st).pack() for st in (0, 2 if me else 4, 7, 2**32 - 1)]
        crafted += [replace(sb, method=99).pack(), replace(sb, fmt=2).pack(), sb.pack(count=len(sb.values) + 1)]
        counts["crafted"] += len(crafted)
        for data_ in bad + crafted:
            status, handle = inst.deserialize(data_)
            assert status == ERROR and not handle.value, (me, data_)
        fz.snapshots = [[snap, copy.deepcopy(fz.model.s)]]
        for case in range(attacks.MISUSE_CASES):
            n_log = len(inst.log)
            status, exp, fn = attacks.misuse(fz, inst, random.Random(case), case)
            fz._judge(inst, fn, fz.model.s.state, n_log, status, exp, case)
            counts["misuse"] += 1
        assert inst.free_fmu_state(snap) == OK
        inst.free()
    return dict(counts)


HARNESS = Path(__file__).resolve().parent.parent / "c" / "alloc_count.c"


@pytest.mark.slow
def test_no_heap_use_in_do_step(tmp_path):
    """tests/c/alloc_count.c linked with the FMU's own sources and --wrap=malloc,calloc,
    realloc,free: doStep (every method, with the sets and gets between steps and the
    refused calls) allocates and frees nothing; instantiate/free and FMU states balance."""
    from fmu.build.build_fmu import CFLAGS, GENERATED_EXTRA

    src = extract_fmu(shared_fmu("extreme_free"), tmp_path / "fmu") / "sources"
    exe = tmp_path / "alloc_count"
    c_files = [HARNESS] + [src / f for f in c_sources(3)]
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
    """Entry point of the sanitized subprocess: python -m tests.robustness.test_fuzz_fmi --fmu F [--fmu F2 ...]
    --workdir D [--sequences N | --leak-canary]. The FMUs are extracted into D, which must outlive the
    process: LeakSanitizer symbolizes its report at exit, from the .so on disk."""
    ap = argparse.ArgumentParser()
    ap.add_argument("--fmu", required=True, type=Path, action="append", help="repeat for several FMUs")
    ap.add_argument("--workdir", required=True, type=Path)
    ap.add_argument("--sequences", type=int, default=100)
    ap.add_argument("--leak-canary", action="store_true")
    args = ap.parse_args()
    libs = {
        f.stem: Fmi3Library(extract_fmu(f, args.workdir / ("canary" if args.leak_canary else "fuzz") / f.stem))
        for f in args.fmu
    }
    lib = next(iter(libs.values()))
    if args.leak_canary:
        inst = lib.instantiate()
        assert inst.handle
        inst.handle = None  # dropped without fmi3FreeInstance: a leak LeakSanitizer must report
        print("CANARY-DONE", flush=True)
        return
    stats = fuzz(libs, args.sequences)
    for name, one in libs.items():
        prefix = "battery: " if len(libs) == 1 else f"battery {name}: "
        stats.attacks.update({prefix + k: n for k, n in attack_battery(one).items()})
    print("FUZZ-DONE" + json.dumps(stats.as_dict()), flush=True)


if __name__ == "__main__":
    _main()
