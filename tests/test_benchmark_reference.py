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

from fmu.benchmark import generated_rk4_last_state, reference_last_state
from modelsrc.scene import list_scenes, load_scene

N = 2000


@pytest.mark.parametrize("name", list_scenes())
def test_reference_reproduces_the_generated_rk4_trajectory(fmus, name):
    sc = load_scene(name)
    assert sc.methods[0] == "rk4", "the harness runs the FMU's first method"
    gen = generated_rk4_last_state(fmus[name], N)
    ref = reference_last_state(sc, N)
    # the last state component: w_body[3] of a 7-state body, v[3] of a 13-state one
    scale = max(abs(gen), 1.0)
    assert abs(gen - ref) <= 1e-9 * scale, (name, gen, ref)
