"""The gyrostat in the work-precision report: dual_spin's scipy reference, Exudyn lines on the jointed model, parts."""

from __future__ import annotations

import math

import numpy as np

from modelsrc.scene import load_scene
from rbcheck.baselines.rigid_body import comm_grid
from rbcheck.workprecision.batch import count_batch_units, exudyn_ladder, exudyn_point, exudyn_rate, exudyn_solvers
from rbcheck.workprecision.config import DEFAULT_SCENES, Config
from rbcheck.workprecision.harness import FmuDriver
from rbcheck.workprecision.references import make_reference
from rbcheck.workprecision.report_scenes import report_scene
from rbcheck.workprecision.tolerance import tolerance_scenes


def test_dual_spin_is_in_the_batch_and_tolerance_parts_with_a_scipy_reference():
    assert "dual_spin" in DEFAULT_SCENES and "dual_spin" in tolerance_scenes(Config())
    # make demo's short report: Exudyn's explicit solvers only, none of which takes the joints
    assert exudyn_ladder("TrapezoidalIndex2", False, Config.short()) == ()
    sc = load_scene("dual_spin")
    grid = comm_grid(sc, 2.0, 0.2)
    ref = make_reference(sc, grid)  # raised on a scene with rotors before rbcheck.baselines.gyrostat
    assert ref.source.startswith("scipy DOP853") and ref.floor < 1e-12 and ref.omega_scale > 1.0
    # the jointed model steps its wheel: the ladder's rate is the wheel's absolute rate, the
    # reference's max |Ω| + max |ω| (100 + 1 rad/s); the trapezoidal rule only (generalized-α
    # diverges on the Lie-group nodes at coarse steps)
    assert exudyn_solvers(sc) == ("TrapezoidalIndex2",)
    assert math.isclose(exudyn_rate(sc, ref), 101.0, rel_tol=1e-3)
    # progress units: reference + 3 scipy + 1 Exudyn line + one per FMU method
    cfg = Config(scenes=("dual_spin",))
    methods = {"dual_spin": ["rk4", "rk8"]}
    assert count_batch_units(cfg, methods) == 1 + 3 + 1 + 2


def test_the_jointed_exudyn_gyrostat_converges_to_the_scipy_reference_at_second_order():
    # Exudyn's trapezoidal rule (order 2) on the wheel-on-a-joint model over 1 s against the
    # scipy gyrostat baseline (rtol 3e-14): halving h divides the error by 4 (measured
    # 4.0001; the next term is O((hΩ)²) ~ 1/64 of the leading one at hΩ = 1/8: asserted 3.8
    # to 4.2), and the rungs of the report's ladder are errors of Exudyn, not of the
    # reference (its floor ~1e-15 against errors ~1e-6). Two models built independently
    # (joints and bodies; the gyrostat's equations) meet at h → 0.
    sc = load_scene("dual_spin")
    T, H = 1.0, 0.1
    grid = comm_grid(sc, T, H)
    ref = make_reference(sc, grid)
    hs = [2.0**-3 / exudyn_rate(sc, ref), 2.0**-4 / exudyn_rate(sc, ref)]
    pts = [exudyn_point(sc, H, T, "TrapezoidalIndex2", h, 1e-10, ref, 2.0, 1) for h in hs]
    ratio = pts[0].err / pts[1].err
    print([p.err for p in pts], ratio)
    assert 3.8 < ratio < 4.2 and pts[0].err < 1e-4
    assert all(np.isfinite([p.drift_E, p.drift_L]).all() for p in pts)  # E_kin and |L| of the jointed model


def test_the_forced_scenes_table_takes_only_scenes_with_a_scipy_reference():
    """The report's part "inputs" (continuous against held inputs) integrates each scene
    with scipy, scenes that turn from their start: not quadrotor (its speed-mode baseline came
    later; a run of `make report-docs` had crashed on it) nor reaction_wheel_slew (at rest
    without its loop); the other scenes with inputs stay in."""
    from modelsrc.scene import list_scenes, load_scene
    from rbcheck.workprecision.forced_inputs import forced_scenes

    names = {sc.name for sc in forced_scenes(map(load_scene, list_scenes()))}
    assert "quadrotor" not in names and "reaction_wheel_slew" not in names
    assert {"top_on_shaker", "spacecraft_thruster", "torque_driven"} <= names


def test_the_slew_runs_open_loop_on_the_loops_own_torques_and_the_fmu_driver_sets_them(fmus):
    """reaction_wheel_slew in the report: the PD loop's torques at its exact sampled-data
    solution as u tables (rbcheck.closed_forms.slew.open_loop_torques). The FMU fed them by the report's
    driver (scalar inputs u_x, u_y, u_z: without them it would stay at rest) follows the
    scipy reference; measured e 9.8e-16 with rk8 at h_max = 0.1 s over 10 s (the loop's own FMU run
    and the exact recursion agree to 6.7e-16 rad, docs/theory.md §8.4)."""
    assert {"reaction_wheel_slew", "quadrotor"} <= set(DEFAULT_SCENES)
    sc = report_scene("reaction_wheel_slew")
    assert sorted(sc.inputs) == ["u_x", "u_y", "u_z"] and sc.inputs["u_x"].shape == (400, 2)
    grid = comm_grid(sc, 10.0, 1.0)  # the tables add their 0.1 s rows
    assert len(grid) == 101
    ref = make_reference(sc, grid)
    assert ref.rotor_scale > 100.0  # the wheels spin up to 110 rad/s from rest
    drv = FmuDriver(fmus["reaction_wheel_slew"], sc)
    try:
        p = drv.point("rk8", 0.1, grid, ref, 1)
    finally:
        drv.close()
    assert p.err < 1e-12, p


def test_the_quadrotors_exudyn_line_measures_exudyns_error_at_second_order():
    """quadrotor in the report: constant rotor speeds (report_scenes), so the FMU, scipy and
    the jointed Exudyn model integrate the same system; its Exudyn rungs converge to the
    scipy reference at order 2 (measured e 5.2e-5, 1.3e-5 at θ = 2^-3, 2^-4 over 0.5 s: ratio 4.0), so they
    measure Exudyn, not a difference of inputs."""
    sc = report_scene("quadrotor")
    assert all(not np.any(sc.input_at(f"Omega_dot_{n}", 1.0)) for n in sc.rotors)
    T, H = 0.5, 0.1
    grid = comm_grid(sc, T, H)
    ref = make_reference(sc, grid)
    rate = exudyn_rate(sc, ref)
    assert 480.0 < rate < 500.0  # the propellers' ~485 rad/s
    pts = [exudyn_point(sc, H, T, "TrapezoidalIndex2", th / rate, 1e-10, ref, 2.0, 1) for th in (2.0**-3, 2.0**-4)]
    ratio = pts[0].err / pts[1].err
    assert 3.5 < ratio < 4.6, [p.err for p in pts]
