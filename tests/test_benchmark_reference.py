"""The benchmark's hand-written C reference integrates the same equations as the generated RK4 step.

`rbfmu bench` prints the generated step's cost beside a minimal hand-written C RK4 of the
same scene (fmu/c/bench_reference.c). The comparison is only fair if both do the same
arithmetic job: after N steps of h_max from the same start, both trajectories agree to
rounding. RK4's global error at these steps is far above rounding (the two codes order
their operations differently), so agreement to 1e-9 relative means equal equations, not
an accident: a wrong sign or a missing term differs at O(h) after N = 2000 steps.
"""

from __future__ import annotations

import pytest

from fmu import benchmark
from fmu.benchmark import generated_rk4_last_state, reference_last_state
from modelsrc.scene import list_scenes, load_scene

N = 2000


# the hand-written reference kernel of the gyrostat (rotors) is not written yet (issue 28's
# benchmark item): the rotor scenes are left out of the benchmark and of this test; so are
# the orbit scenes and the central field (the kernel has no gravity gradient;
# fmu.benchmark.reference_features)
@pytest.mark.parametrize(
    "name",
    [
        n
        for n in list_scenes()
        if not load_scene(n).rotors and not load_scene(n).features & {"orbit", "central_gravity"}
    ],
)
def test_reference_reproduces_the_generated_rk4_trajectory(fmus, name):
    sc = load_scene(name)
    assert sc.methods[0] == "rk4", "the harness runs the FMU's first method"
    gen = generated_rk4_last_state(fmus[name], N)
    ref = reference_last_state(sc, N)
    # the last state component: w_body[3] of a 7-state body, v[3] of a 13-state one
    scale = max(abs(gen), 1.0)
    assert abs(gen - ref) <= 1e-9 * scale, (name, gen, ref)


def test_bench_times_both_sides_in_alternating_processes_and_reports_the_spread(monkeypatch, tmp_path):
    """`rbfmu bench` runs the harness and the reference in separate processes, alternately
    (A B A B ...), and its ratio row is the median with min..max over the pairs, not one
    process's best. The processes are replaced by a recorder: what is checked is the order
    of the runs and the arithmetic of the spread."""
    calls: list[str] = []
    raw_ns = iter([100.0, 300.0, 120.0])
    ref_ns = iter([100.0, 100.0, 100.0])
    monkeypatch.setattr(benchmark, "_compile_harness", lambda fmu, tmp: tmp / "bench")
    monkeypatch.setattr(benchmark, "_compile_reference", lambda scene, tmp: [str(tmp / "reference"), "1e-3"])
    monkeypatch.setattr(benchmark, "default_step", lambda fmu: 1e-3)

    def harness(exe, n, method_value, h):
        calls.append("harness")
        raw = next(raw_ns)
        return raw, 2 * raw, 0.0

    def reference(cmd, n):
        calls.append("reference")
        return next(ref_ns), 0.0

    monkeypatch.setattr(benchmark, "_run_harness", harness)
    monkeypatch.setattr(benchmark, "_run_reference", reference)
    iv = benchmark.interleaved_step_ns(tmp_path / "x.fmu", load_scene("symmetric_free"), pairs=3, n=10)
    assert calls == ["harness", "reference"] * 3
    assert iv.ratio_spread() == (1.0, 1.2, 3.0)  # one slow harness process moves the max, not the median
    assert iv.median("raw") == 120.0 and iv.median("fmi") == 240.0 and iv.median("ref") == 100.0
