"""The work-precision report on the scenes whose reference point moves: references, scipy baselines, batch step.

The scipy equations of rbcheck.baselines.motion are a third implementation of
docs/theory.md §7 (numpy), beside the FMU's CasADi and Exudyn's multibody models.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from fmu.drive.run import run_fmu
from modelsrc.methods import METHODS
from modelsrc.scene import load_scene
from rbcheck.baselines.motion import integrate
from rbcheck.baselines.rigid_body import comm_grid
from rbcheck.workprecision.batch import batch_step
from rbcheck.workprecision.config import Config
from rbcheck.workprecision.harness import FmuDriver
from rbcheck.workprecision.references import errors, make_reference


def test_reference_of_the_thrown_racket_is_the_closed_form_and_parabola():
    sc = load_scene("thrown_racket")
    grid = comm_grid(sc, sc.stop_time, sc.stop_time / 10)
    ref = make_reference(sc, grid)
    assert "free_asymmetric" in ref.source and "parabola" in ref.source
    assert ref.x is not None and ref.x_scale > 2.0  # the racket flies ~2.5 m
    # DOP853 at rtol 3e-14 agrees with the closed forms (rotation and parabola) to 1e-12
    assert ref.floor < 1e-11


def test_batch_resolves_a_harmonic_input():
    sc = load_scene("top_on_shaker")
    omega = sc.inputs["a_pivot"].omega
    assert batch_step(sc, Config()) == pytest.approx(0.1 * 2 * math.pi / omega, rel=1e-15)  # ten per period
    assert batch_step(load_scene("thrown_racket"), Config()) == 1.4 / 10


def test_scipy_moving_pivot_agrees_with_the_fmu(fmus):
    # two independent implementations of Euler's equations about a moving point (§7.3):
    # DOP853 at rtol 1e-12 and the FMU with gauss6 at h|ω| = 7.5e-3 (error ~1e-13)
    sc = load_scene("top_on_shaker")
    T, H = 0.2, 1e-3
    grid = comm_grid(sc, T, H)
    tr = integrate(sc, grid, "DOP853", rtol=1e-12, atol=1e-14)
    r = run_fmu(fmus["top_on_shaker"], sc, stop_time=T, start_values={"method": METHODS["gauss6"].value})
    dw = float(np.max(np.abs(r.vector("w_body") - tr.w_body)))
    dx = float(np.max(np.abs(r.vector("x_cm") - tr.extra["x_cm"])))
    print(f"\nFMU gauss6 vs scipy DOP853 (moving pivot): |dw| {dw:.1e} rad/s, |dx_cm| {dx:.1e} m")
    assert dw < 1e-8 * 150.0 and dx < 1e-10  # DOP853's global error ~ 10-100 rtol


def test_fmu_ladder_on_a_free_body_measures_the_centre_of_mass(fmus):
    sc = load_scene("spacecraft_thruster")
    grid = comm_grid(sc, sc.stop_time, sc.stop_time / 10)
    ref = make_reference(sc, grid)
    assert ref.source.startswith("scipy DOP853") and ref.x is not None
    drv = FmuDriver(Path(fmus["spacecraft_thruster"]), sc)
    try:
        pts = [drv.point("rk4", h, grid, ref, 1) for h in (0.4, 0.2)]
        _, Y = drv.run("rk4", 0.4, grid, record=True)
    finally:
        drv.close()
    # order 4: halving h divides the error by ~16 (> 8 allows for the constant's variation)
    assert pts[0].err / pts[1].err > 8, [p.err for p in pts]
    # the headline error includes e_x / X (the centre of mass), and never undercuts it
    assert Y is not None
    x_err = float(np.max(np.abs(Y[-1, -3:] - ref.x[-1]))) / ref.x_scale
    assert pts[0].err >= x_err and x_err > 0
    assert errors(Y[:, 4:7], Y[:, :4], ref, Y[:, -3:])[2] == pts[0].err
