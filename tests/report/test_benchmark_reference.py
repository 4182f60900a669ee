"""The benchmark's hand-written C reference integrates the same equations as the generated RK4 and RK8 steps.

`rbfmu bench` prints the generated step's cost beside a hand-written C kernel of the same
scene and method (fmu/c/bench_reference.c). The comparison is only fair if both do the
same arithmetic job: after N fixed steps from the same start, with the same inputs held,
the whole states agree to rounding. The start is the scene's, turned (ω + (0.1, −0.2,
0.15) rad/s, every rotor rate + k rad/s) and every input moved off its start value
(+ 1e-3 k), so that no term of the equations is zero by accident (reaction_wheel_slew
starts at rest without inputs). Agreement to 1e-10 (relative, over max(|x|, 1)) means
equal equations: the two codes order their operations differently (the reference sums
the centre of mass's stages in closed form, turns vectors with the quaternion and takes
the orbit angle's sine by angle addition), and their difference grows from ~1e-16 per
step to at most 1.4e-11 after N = 2000 steps (thrown_racket's flip, growth rate 10.5
1/s, measured; 4e-13 in the central field); a wrong sign or a missing term moves the
states by the size of that term times the 2 s to 2000 s simulated, far above 1e-10 (the
states move by 0.26 to 2.9 over the run, each term of the right-hand side is ≥ 1e-3 of
it). The mutants show it: the reference without one of its terms, or with one moment of
inertia 1e-6 off, misses the generated state by more than 1e-8, a hundred times the
tolerance.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from fmpy import read_model_description

from fmu.bench import reference, steps
from fmu.bench.benchmark import generated_states
from fmu.bench.reference import reference_features, reference_state, start_inputs, start_state
from modelsrc.scene import list_scenes, load_scene

N = 2000
TOLERANCE = 1e-10  # agreement of the whole state (see the module docstring)
MUTANT_MISS = 1e-8  # how far a mutant must miss: 100 times the tolerance
# the features whose term the reference can leave out with the same states and parameters
DROPPABLE = ("REF_GRAVITY", "REF_FRICTION", "REF_TAU_BODY", "REF_TAU_WORLD", "REF_GRAVITY_GRADIENT",
             "REF_FREE_GRAVITY", "REF_PROPELLERS", "REF_CENTRAL", "REF_FORCE_BODY", "REF_FORCE_WORLD",
             "REF_PRESCRIBED")  # fmt: skip


def moved_start(fmu, name):
    """(scene, x0, input names in the FMU's order, input values by name): the scene's start
    turned and its inputs moved off their start values."""
    sc = load_scene(name)
    x0 = np.array(start_state(sc), dtype=float)
    x0[4:7] += [0.1, -0.2, 0.15]
    n_rotor_states = len(reference.torque_and_speed_rotors(sc)[0])
    i0 = 13 if sc.moves else 7
    x0[i0 : i0 + n_rotor_states] += np.arange(1, n_rotor_states + 1)
    names = [v.name for v in read_model_description(str(fmu)).modelVariables if v.causality == "input"]
    start = start_inputs(sc)
    assert set(names) == set(start), "the reference's inputs are the FMU's"
    return sc, x0, names, {n: start[n] + 1e-3 * (k + 1) for k, n in enumerate(names)}


_GENERATED: dict[str, dict[str, np.ndarray]] = {}


def generated(fmu, name):
    """(scene, x0, inputs by name, method -> generated state after N steps from the moved
    start): both methods from one compile of the FMU's C, kept for the module's tests."""
    sc, x0, names, u = moved_start(fmu, name)
    if name not in _GENERATED:
        _GENERATED[name] = generated_states(fmu, N, ("rk4", "rk8"), x0, [u[n] for n in names])
    return sc, x0, u, _GENERATED[name]


def miss(gen, ref):
    return float(np.max(np.abs(gen - ref) / np.maximum(np.abs(gen), 1.0)))


@pytest.mark.parametrize("method", ["rk4", "rk8"])
@pytest.mark.parametrize("name", list_scenes())
def test_reference_reproduces_the_generated_trajectory(fmus, name, method):
    sc, x0, u, gens = generated(fmus[name], name)
    gen = gens[method]
    ref = reference_state(sc, N, method, x0, u)
    assert miss(gen, x0) > 0.1, "the run must move the state"
    assert miss(gen, ref) <= TOLERANCE, (name, method, gen, ref)


@pytest.mark.parametrize("name", list_scenes())
def test_a_reference_with_a_term_missing_or_wrong_fails_the_check(fmus, name):
    """Each term the scene's reference can drop (its feature macro left out), and one moment
    of inertia 1e-6 off, moves the state after N RK4 steps by more than MUTANT_MISS."""
    sc, x0, u, gens = generated(fmus[name], name)
    gen = gens["rk4"]
    features = reference_features(sc)
    mutants = {f"without {f}": dict(features=[g for g in features if g != f]) for f in features if f in DROPPABLE}
    inertia = np.array(sc.inertia, dtype=float)
    inertia[0, 0] *= 1 + 1e-6
    wrong = dataclasses.replace(sc, inertia=inertia.tolist())
    if not sc.has("prescribed_rate"):  # a held rate does not depend on the inertia
        mutants["I_1 1e-6 off"] = dict(parameters=reference.reference_parameters(wrong))
    assert mutants, f"{name}: no mutant to try"
    for what, change in mutants.items():
        ref = reference_state(sc, N, "rk4", x0, u, **change)
        assert miss(gen, ref) > MUTANT_MISS, f"{name}: the reference {what} still agrees ({miss(gen, ref):.1e})"


def test_bench_times_both_sides_in_alternating_processes_and_reports_the_spread(monkeypatch, tmp_path):
    """`rbfmu bench` runs the harness and the reference in separate processes, alternately
    (A B A B ...), and its ratio rows are the medians with min..max over the pairs, not one
    process's best; the doStep ratios are taken within each harness process. The processes
    are replaced by a recorder: what is checked is the order of the runs, the method each
    runs and the arithmetic of the spreads."""
    calls: list[str] = []
    raw_ns = iter([100.0, 300.0, 120.0])
    ref_ns = iter([100.0, 100.0, 100.0])
    monkeypatch.setattr(steps, "compile_harness", lambda fmu, tmp: tmp / "bench")
    monkeypatch.setattr(steps, "reference_command", lambda scene, tmp: [str(tmp / "reference"), "1e-3"])
    monkeypatch.setattr(steps, "default_step", lambda fmu: 1e-3)

    def harness(exe, n, method_value, h):
        calls.append(f"harness {method_value}")
        raw = next(raw_ns)
        return raw, 1.1 * raw, 4 * raw, 12 * raw  # long doStep, doStep of 1 and of 10 steps

    def reference_run(cmd, n, method):
        calls.append(f"reference {method}")
        return next(ref_ns), np.zeros(7)

    monkeypatch.setattr(steps, "run_loops", harness)
    monkeypatch.setattr(steps, "run_reference", reference_run)
    iv = steps.interleaved_step_ns(tmp_path / "x.fmu", load_scene("symmetric_free"), "rk8", pairs=3, n=10)
    assert calls == [f"harness {steps.METHODS['rk8'].value}", "reference rk8"] * 3
    assert iv.ratio_spread() == (1.0, 1.2, 3.0)  # one slow harness process moves the max, not the median
    assert iv.median("raw") == 120.0 and iv.median("fmi") == pytest.approx(132.0) and iv.median("ref") == 100.0
    assert iv.ratio_spread("loop1") == (4.0, 4.0, 4.0) and iv.ratio_spread("loop10") == pytest.approx((1.2,) * 3)


def test_bench_says_when_valgrind_is_missing(monkeypatch, capsys):
    """Without valgrind the instruction columns read "n/a", a line above the tables says why,
    and the instruction targets read "not counted" instead of met or NOT met; the time columns
    and targets stay."""
    monkeypatch.setattr(steps.instructions, "have_valgrind", lambda: False)
    iv = steps.Interleaved((100.0,), (110.0,), (400.0,), (1200.0,), (90.0,))
    steps.print_tables([("symmetric_free", "rk4", iv, steps.Counts(None, None, None, None, None), 30.0, 7)])
    out = capsys.readouterr().out
    assert steps.instructions.MISSING in out
    step_row, dostep_row = (line.split() for line in out.splitlines() if line.startswith("symmetric_free"))
    assert step_row[2:5] == ["n/a"] * 3 and step_row[5:7] == ["100.0", "90.0"]  # instructions; then ns
    assert dostep_row[2:8] == ["n/a"] * 6 and dostep_row[8:10] == ["100.0", "400.0"]
    assert "target generated/reference instructions <= 1.15: worst n/a: not counted" in out
    assert "target generated/reference CPU time (median of pairs) <= 1.2: worst 1.111 (symmetric_free rk4): met" in out
