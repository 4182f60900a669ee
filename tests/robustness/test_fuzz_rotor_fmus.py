"""Fuzzing the FMI 3.0 layer of rotor, orbit and central-field FMUs (issue 39, item 3).

The fuzzer of tests/robustness/test_fuzz_fmi.py (its driver, model and attacks in
tests/harness/fuzz_fmi_*.py) on three FMUs that carry every rotor, orbit and central-field
variable: the shipped quadrotor (four speed-mode propellers: inputs Omega_pN and
Omega_dot_pN, parameters J_pN; translation x_cm, v_cm and gravity), and the scenes of
tests/harness/fuzz_scenes.py: offaxis_wheel (a torque-mode wheel along (0.6, 0.8, 0):
state Omega_wheel, input u_wheel, J_wheel; an orbit: state orbit_angle, n_orbit) and
central_wheel (the central field: x_cm, v_cm, mu; a wheel). The model predicts the ranges
of docs/robustness.md §2 (J in [1e-100, 1e100], n_orbit > 0, |orbit_angle| <= 1e6 rad,
mu > 0, |x_cm| above the body's size) at exitInitializationMode, for tunable changes and
crafted FMU states, a wheel speed whose energy overflows (refused: an output 'would be'
inf), and Model Exchange SetContinuousStates at the central body (Discard).
"""

from __future__ import annotations

import sys

import pytest

from ..harness import fuzz_fmi_model as spec
from ..harness.fmi3_ctypes import shared_fmu, shared_library
from .test_fuzz_fmi import _sanitizer_available, fuzz, sanitized_fuzz_run, watched_fuzz

ROTOR_FMUS = ("quadrotor", "offaxis_wheel", "central_wheel")
N_SEQUENCES_ROTORS = 3_000  # in process, ~5 ms each
N_SEQUENCES_ROTORS_ASAN = 600  # sanitized, ~4x slower per call


def _libs():
    return {k: shared_library(k) for k in ROTOR_FMUS}


@pytest.mark.slow
def test_fuzz_rotor_orbit_and_central_field_fmus():
    """Every call on the three FMUs matches the model; the run reaches step mode on each and
    sees the new checks refuse (exitInitializationMode) and pass (doStep OK)."""
    stats, wall, outcomes = watched_fuzz(_libs(), N_SEQUENCES_ROTORS)
    print(
        f"\nrotor fuzz: {stats.sequences} sequences, {stats.calls} calls ({stats.refused} refused), {wall:.1f} s, "
        f"slowest sequence {stats.max_sequence_time * 1e3:.1f} ms; outcomes {dict(outcomes)}; "
        f"doStep OK {stats.transitions[('fmi3DoStep', spec.STEP, 'OK')]}; "
        f"SetContinuousStates Error {stats.transitions[('fmi3SetContinuousStates', spec.CONT, 'Error')]}; "
        f"attacks {dict(sorted(stats.attacks.items()))}"
    )
    assert stats.sequences >= N_SEQUENCES_ROTORS
    assert stats.transitions[("fmi3DoStep", spec.STEP, "OK")] > 100
    assert stats.transitions[("fmi3ExitInitializationMode", spec.INIT, "Error")] > 10


@pytest.mark.slow
@pytest.mark.parametrize("check", [spec.CHK_CENTRAL, spec.CHK_ORBIT_ANGLE, spec.CHK_J["J_wheel"]])
def test_fuzz_oracle_knows_the_rotor_orbit_and_central_field_ranges(monkeypatch, check):
    """The oracle is live for the new ranges: with the model blind to one of them, a short
    run on the FMU that has it fails (a refusal the model did not predict)."""
    original = spec.FmuModel.violated
    monkeypatch.setattr(spec.FmuModel, "violated", lambda self: original(self) - {check})
    lib = "central_wheel" if check == spec.CHK_CENTRAL else "offaxis_wheel"
    with pytest.raises(AssertionError):
        fuzz({lib: shared_library(lib)}, 400, shrink=False)


@pytest.mark.sanitizer
def test_asan_fuzz_rotor_orbit_and_central_field_fmus(tmp_path):
    """The sanitized run of tests/robustness/test_fuzz_fmi.py (AddressSanitizer + UBSan +
    LeakSanitizer, in a subprocess) on the three FMUs, attack battery included."""
    reason = _sanitizer_available()
    if reason:
        pytest.skip(f"compiler lacks the sanitizers: {reason}")
    fmus = [shared_fmu(k, sanitize=True) for k in ROTOR_FMUS]
    cmd = [sys.executable, "-m", "tests.robustness.test_fuzz_fmi", "--workdir", str(tmp_path)]
    for f in fmus:
        cmd += ["--fmu", str(f)]
    stats, _ = sanitized_fuzz_run(cmd, N_SEQUENCES_ROTORS_ASAN, [f"{k}.so" for k in ROTOR_FMUS])
    print(
        f"\nASan rotor fuzz: {stats['sequences']} sequences, {stats['calls']} calls ({stats['refused']} refused), "
        f"slowest {stats['max_sequence_time'] * 1e3:.1f} ms; attacks {stats['attacks']}"
    )
    assert stats["sequences"] >= N_SEQUENCES_ROTORS_ASAN
