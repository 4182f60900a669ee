"""The LQR designed on reaction_wheel_slew's step map, run through the FMU; the linearisation's CPU time."""

from __future__ import annotations

import numpy as np

from fmu.linear.bench import measure
from fmu.linear.slew_lqr import design, run


def test_lqr_on_the_linear_model_slews_the_fmu(fmus):
    fmu = fmus["reaction_wheel_slew"]
    d = design(fmu)
    assert np.all(np.abs(d.closed_loop) < 1)  # the sampled-data loop is stable on the model
    r = run(fmu)
    # 90° slew: the slowest closed-loop rate (−0.56 1/s) brings 1.57 rad below 1e-8 within 40 s
    # (1.57 e^{-0.56 · 40} ~ 3e-10 with the polynomial factor of the pairs); the wheels keep
    # the total momentum 0 to round-off (docs/theory.md §8.4)
    assert r["final_angle"] < 1e-8 and r["settle_1mrad"] < 20.0
    assert r["max_L_world"] < 1e-13
    assert r["slowest_rate"] < -0.5


def test_linearisation_costs_less_than_20_ms(fmus):
    for scene in ("quadrotor", "eccentric_orbit", "free_asymmetric"):
        m = measure(fmus[scene], repeats=5)
        assert m["linearize"] < 0.020, (scene, m)
        assert m["linearize"] < m["differences"], (scene, m)  # fewer FMI calls than 2 (nx + nu) evaluations
