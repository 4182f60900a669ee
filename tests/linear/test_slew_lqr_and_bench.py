"""The LQR designed on reaction_wheel_slew's step map, run through the FMU; the linearisation's CPU time."""

from __future__ import annotations

import numpy as np

from fmu.linear.bench import measure
from fmu.linear.finite_differences import differences_model
from fmu.linear.linearize import linearize
from fmu.linear.model_exchange import ModelExchange
from fmu.linear.operating_point import start_point
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
        assert m["linearize"] < m["differences"], (scene, m)  # nz + nu calls against 2 (nz + nu) evaluations
        # the FMI calls alone: one directional derivative (the Jacobian evaluated once per
        # point in the FMU, then one column extracted) against two evaluations of three calls
        # each (set the state, get the rates, get the outputs), the same ctypes path: 0.15-0.34
        assert m["jacobian calls"] < 0.5 * m["difference calls"], (scene, m)


def test_differences_model_is_the_same_model(fmus):
    """The bench's yardstick computes what linearize does: central differences along the same
    directions agree with the directional derivatives to the differences' error (step
    h = 1e-6 of the scale: round-off ~ eps |f| / h ~ 1e-10 |f|, truncation ~ h^2 times the
    third derivative; measured 6e-12 of the largest entry)."""
    fmu = fmus["reaction_wheel_slew"]
    point = start_point(fmu)
    with ModelExchange(fmu) as me:
        for coordinates in ("attitude", "raw"):
            exact = linearize(fmu, point, coordinates=coordinates, instance=me)
            fd = differences_model(me, point, coordinates=coordinates)
            assert exact.states == fd.states and exact.outputs == fd.outputs
            for a, b in zip(exact, fd):
                scale = max(1.0, np.abs(a).max(initial=0))
                assert np.all(np.isfinite(a)) and np.abs(a - b).max(initial=0) <= 1e-7 * scale
            assert np.array_equal(exact.drift, fd.drift)


def test_directional_derivatives_follow_the_point(fmus):
    """The FMU keeps its Jacobian while x, u, p and the method stay (docs/fmi_layer.md): after a
    new state or input, a column is the one a fresh instance gives there, to the bit."""
    fmu = fmus["reaction_wheel_slew"]
    point = start_point(fmu)
    moved = point.with_values(states={"w_body[1]": 0.3, "w_body[3]": -0.2}, inputs={"u_y": 0.05})
    with ModelExchange(fmu) as me, ModelExchange(fmu) as fresh:
        first = linearize(fmu, point, coordinates="raw", instance=me)
        again = linearize(fmu, moved, coordinates="raw", instance=me)  # same instance, new point
        reference = linearize(fmu, moved, coordinates="raw", instance=fresh)
        for a, b in zip(again, reference):
            assert np.array_equal(a, b)
        assert np.array_equal(again.drift, reference.drift)
        assert not np.array_equal(again.A, first.A)  # the point moved the Jacobian
