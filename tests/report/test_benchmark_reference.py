"""The benchmark's hand-written C reference integrates the same equations as the generated RK4 and RK8 steps.

`rbfmu bench` prints the generated step's cost beside a minimal hand-written C kernel of
the same scene and method (fmu/c/bench_reference.c). The comparison is only fair if both
do the same arithmetic job: after N fixed steps from the same start, with the same inputs
held, the whole states agree to rounding. The start is the scene's, turned (ω + (0.1,
−0.2, 0.15) rad/s, every rotor rate + k rad/s) and every input moved off its start value
(+ 1e-3 k), so that no term of the equations is zero by accident (reaction_wheel_slew
starts at rest without inputs). Agreement to 1e-10 (relative, over max(|x|, 1)) means
equal equations: the two codes order their operations differently, and their difference
grows from ~1e-16 per step to at most 7e-12 after N = 2000 steps (thrown_racket's flip,
growth rate 10.5 1/s, measured); a wrong sign or a missing term moves the states by the
size of that term times the 2 s to 2000 s simulated, far above 1e-10 (the states move by
0.26 to 1.9 over the run, each term of the right-hand side is ≥ 1e-3 of it).
"""

from __future__ import annotations

import numpy as np
import pytest
from fmpy import read_model_description

from fmu.bench import benchmark
from fmu.bench.benchmark import generated_state, reference_state
from modelsrc.scene import list_scenes, load_scene

N = 2000


# every scene but those in a central field, which the C reference has no kernel for
# (fmu.bench.benchmark.reference_features; docs/theory.md §9.7)
@pytest.mark.parametrize("method", ["rk4", "rk8"])
@pytest.mark.parametrize("name", [n for n in list_scenes() if not load_scene(n).has("central_gravity")])
def test_reference_reproduces_the_generated_trajectory(fmus, name, method):
    sc = load_scene(name)
    x0 = np.array(benchmark._start_state(sc), dtype=float)
    x0[4:7] += [0.1, -0.2, 0.15]
    n_rotor_states = len(benchmark._torque_and_speed_rotors(sc)[0])
    i0 = 13 if sc.moves else 7
    x0[i0 : i0 + n_rotor_states] += np.arange(1, n_rotor_states + 1)
    names = [v.name for v in read_model_description(str(fmus[name])).modelVariables if v.causality == "input"]
    start = benchmark._start_inputs(sc)
    assert set(names) == set(start), "the reference's inputs are the FMU's"
    u = {n: start[n] + 1e-3 * (k + 1) for k, n in enumerate(names)}
    gen = generated_state(fmus[name], N, method, x0, [u[n] for n in names])
    ref = reference_state(sc, N, method, x0, u)
    scale = np.maximum(np.abs(gen), 1.0)
    assert np.max(np.abs(gen - x0) / scale) > 0.1, "the run must move the state"
    assert np.max(np.abs(gen - ref) / scale) <= 1e-10, (name, method, gen, ref)


def test_bench_times_both_sides_in_alternating_processes_and_reports_the_spread(monkeypatch, tmp_path):
    """`rbfmu bench` runs the harness and the reference in separate processes, alternately
    (A B A B ...), and its ratio row is the median with min..max over the pairs, not one
    process's best. The processes are replaced by a recorder: what is checked is the order
    of the runs, the method each runs and the arithmetic of the spread."""
    calls: list[str] = []
    raw_ns = iter([100.0, 300.0, 120.0])
    ref_ns = iter([100.0, 100.0, 100.0])
    monkeypatch.setattr(benchmark, "_compile_harness", lambda fmu, tmp: tmp / "bench")
    monkeypatch.setattr(benchmark, "_compile_reference", lambda scene, tmp: [str(tmp / "reference"), "1e-3"])
    monkeypatch.setattr(benchmark, "default_step", lambda fmu: 1e-3)

    def harness(exe, n, method_value, h):
        calls.append(f"harness {method_value}")
        raw = next(raw_ns)
        return raw, 2 * raw

    def reference(cmd, n, method):
        calls.append(f"reference {method}")
        return next(ref_ns), np.zeros(7)

    monkeypatch.setattr(benchmark, "_run_harness", harness)
    monkeypatch.setattr(benchmark, "_run_reference", reference)
    iv = benchmark.interleaved_step_ns(tmp_path / "x.fmu", load_scene("symmetric_free"), "rk8", pairs=3, n=10)
    assert calls == [f"harness {benchmark.METHODS['rk8'].value}", "reference rk8"] * 3
    assert iv.ratio_spread() == (1.0, 1.2, 3.0)  # one slow harness process moves the max, not the median
    assert iv.median("raw") == 120.0 and iv.median("fmi") == 240.0 and iv.median("ref") == 100.0
