"""Smoke tests of the work-precision report's machinery (rbcheck.workprecision, rbcheck.baselines.rigid_body).

Interpolation and the fastest-method table on synthetic data, observed orders of the FMU
methods on a tiny ladder, the scipy baseline, the controller, and the command itself."""

from __future__ import annotations

import argparse
import itertools
import math
import os
import re
import subprocess
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from fmu.bench.benchmark import c_step_ns, c_step_ns_all
from fmu.drive.instance import FmuInstance
from modelsrc.scene import load_scene
from rbcheck.baselines.rigid_body import AttitudePD, comm_grid, integrate_scipy, outputs_dict
from rbcheck.numerics.rotation_np import quat_from_axis_angle, quat_mul
from rbcheck.workprecision.batch import SceneResult, batch_target, run_ladder, saturate_min_work, scipy_point
from rbcheck.workprecision.cli import add_arguments, main
from rbcheck.workprecision.config import LEVELS, pow2
from rbcheck.workprecision.harness import FmuDriver, guarded
from rbcheck.workprecision.measures import Line, Point, best_of, fastest_table, observed_order, time_at_level
from rbcheck.workprecision.references import make_reference


# ----------------------------------------------------------------------------------
# interpolation and the table, on synthetic lines (exact answers known)
# ----------------------------------------------------------------------------------
def power_line(name: str, family: str, t0: float, e0: float, order: float, errs) -> Line:
    """A line on the exact power law e = e0 (t/t0)^(-order): log-log interpolation between
    its points reproduces the law exactly, so the table's times are known in closed form."""
    pts = [Point("x", 0.0, t0 * (e / e0) ** (-1.0 / order), e, e, e) for e in errs]
    return Line(name, family, pts)


def law_time(t0: float, e0: float, order: float, level: float) -> float:
    return t0 * (level / e0) ** (-1.0 / order)


def test_time_at_level_interpolates_in_log_log():
    hit = time_at_level([(1e-3, 1e-4), (1e-2, 1e-8)], 1e-6)
    assert hit is not None and not hit[1]
    assert hit[0] == pytest.approx(10**-2.5, rel=1e-12)  # midway in log e -> midway in log t
    assert time_at_level([(1e-3, 1e-4), (1e-2, 1e-8)], 1e-4) == (1e-3, True)  # first rung: upper bound
    assert time_at_level([(1e-3, 1e-4), (1e-2, 1e-8)], 1e-9) is None
    # a later rung that gets worse does not count before the first crossing
    assert time_at_level([(1.0, 1e-3), (2.0, 1e-2), (4.0, 1e-5)], 1e-4)[0] > 2.0
    with pytest.raises(ValueError, match="error level must be > 0, got 0"):
        time_at_level([(1.0, 1.0)], 0.0)


def test_fastest_table_on_synthetic_lines():
    errs = [10.0**-k for k in range(2, 14)]
    fmu_fast = power_line("FMU rk8", "FMU", 1e-4, 1e-2, 8, errs)
    fmu_slow = power_line("FMU rk4", "FMU", 1e-4, 1e-2, 4, errs)
    exu = power_line("Exudyn RK67", "Exudyn", 3e-3, 1e-2, 6, errs[:7])  # stops at 1e-8
    sci = power_line("scipy DOP853", "scipy", 2e-2, 1e-2, 8, errs)
    rows = fastest_table([exu, fmu_slow, sci, fmu_fast], LEVELS)
    assert [r.level for r in rows] == list(LEVELS)
    for r in rows:
        t_fmu = min(law_time(1e-4, 1e-2, 8, r.level), law_time(1e-4, 1e-2, 4, r.level))
        name = "FMU rk8" if law_time(1e-4, 1e-2, 8, r.level) < law_time(1e-4, 1e-2, 4, r.level) else "FMU rk4"
        assert r.fastest == name == r.fmu.line
        assert r.fmu.time == pytest.approx(t_fmu, rel=1e-9)
        assert r.speedup_scipy == pytest.approx(law_time(2e-2, 1e-2, 8, r.level) / t_fmu, rel=1e-9)
        if r.level >= 1e-8:
            assert not r.exudyn.lower_bound
            assert r.speedup_exudyn == pytest.approx(law_time(3e-3, 1e-2, 6, r.level) / t_fmu, rel=1e-9)
        else:  # Exudyn never got there: bounded below by its most expensive run
            assert r.exudyn.lower_bound and r.exudyn.line is None
            assert r.exudyn.time == pytest.approx(max(p.wall for p in exu.points))
    ok, fails, unverified = batch_target([SceneResult("s", 1.0, 0.1, 10, None, [], rows)])
    # scipy: 200x at equal order; Exudyn: smallest ratio 36x at 1e-4 (3e-3/1e-4 · 100^(1/6 - 1/8)),
    # and past 1e-8 its bound 0.03 s against the FMU's 1.3e-3 s at 1e-11: 22x
    assert ok and not fails and not unverified, (fails, unverified)


def test_fastest_table_reports_a_slow_fmu_as_not_met():
    errs = [10.0**-k for k in range(2, 14)]
    fmu = power_line("FMU rk4", "FMU", 1e-2, 1e-2, 4, errs)
    exu = power_line("Exudyn RK67", "Exudyn", 1e-2, 1e-2, 6, errs)  # same start, higher order: faster
    rows = fastest_table([fmu, exu], LEVELS)
    assert all(r.fastest == "Exudyn RK67" for r in rows)
    ok, fails, _ = batch_target([SceneResult("s", 1.0, 0.1, 10, None, [], rows)])
    assert not ok and len(fails) == len(LEVELS)
    # levels under 3x the reference's own error are not judged
    rows = fastest_table([fmu, exu], LEVELS, ref_floor=1e-9)
    assert [r.resolved for r in rows] == [lev >= 3e-9 for lev in LEVELS]


def test_first_rung_is_an_upper_bound_unless_it_is_the_least_work():
    pts = [
        Point("h=1", 1.0, wall=1e-3, err=1e-6, e_w=0.0, e_R=0.0, work=10),
        Point("h=0.5", 0.5, wall=2e-3, err=1e-9, e_w=0.0, e_R=0.0, work=20),
    ]
    line = Line("Exudyn RK67", "Exudyn", pts)
    b = best_of([line], 1e-5)
    assert b.upper_bound and b.time == 1e-3  # a coarser rung might have been cheaper
    line.min_work = 10  # ... unless this one is one step per interval
    b = best_of([line], 1e-5)
    assert not b.upper_bound and b.time == 1e-3 and b.line == "Exudyn RK67"
    # tolerance ladders: saturated when the two loosest rungs did the same work
    tol = Line("scipy DOP853", "scipy", [replace(pts[0], work=284), replace(pts[1], work=284)])
    assert saturate_min_work(tol).min_work == 284
    assert saturate_min_work(Line("scipy LSODA", "scipy", pts)).min_work is None


# ----------------------------------------------------------------------------------
# the FMU ladder: observed orders on the closed-form scene
# ----------------------------------------------------------------------------------
@pytest.mark.parametrize("method, order", [("rk4", 4), ("implicit_midpoint", 2), ("splitting", 2)])
def test_fmu_ladder_errors_fall_at_the_method_order(fmus, method, order):
    sc = load_scene("symmetric_free")
    grid = comm_grid(sc, sc.stop_time, sc.stop_time / 10)
    ref = make_reference(sc, grid)
    assert ref.source.startswith("closed form")
    # DOP853 at rtol 1e-13 and the closed form agree (measured 1.7e-14)
    assert ref.floor < 1e-12
    drv = FmuDriver(fmus["symmetric_free"], sc)
    # rungs θ = h·Ω inside the method's rotation limit (docs/theory.md §5.4), else the FMU
    # refines the coarse rungs to the same step and they collapse
    from modelsrc.methods import METHODS

    k0 = 3 if METHODS[method].rotation_limit >= 0.13 else 5
    try:
        line = run_ladder(
            Line(method, "FMU"),
            pow2(k0, k0 + 2),
            lambda th: drv.point(method, th / ref.omega_scale, grid, ref, 1),
            cap=5.0,
            floor=1e-14,
            growth=2.0,
        )
    finally:
        drv.close()
    h = [p.value for p in line.points]
    e = [p.err for p in line.points]
    assert len(h) == 3 and all(a > b for a, b in itertools.pairwise(e))
    assert min(e) > 1e3 * ref.floor  # far above the reference's own error
    p = observed_order(h, e)
    # the slope is the order + O(h Ω): with h Ω ≤ 1/8 the ladder stays within 6 % of it
    # (the same band as tests/physics/test_methods.py at h Ω ≤ 0.4)
    assert abs(p - order) < 0.06 * order, (method, p, e)
    assert all(pt.wall > 0 for pt in line.points)
    # torque-free body: E and |L| drift are measured, and |q| stays unit (projection)
    assert all(math.isfinite(pt.drift_E) and math.isfinite(pt.drift_L) for pt in line.points)
    assert all(pt.drift_q < 1e-14 for pt in line.points)


def test_scipy_baseline_converges_and_respects_explicit_tolerances():
    sc = load_scene("symmetric_free")
    grid = comm_grid(sc, sc.stop_time, sc.stop_time / 10)
    ref = make_reference(sc, grid)
    pts = [scipy_point(sc, grid, "DOP853", rt, 1e-3 * rt, ref, 1) for rt in (1e-5, 1e-8, 1e-11)]
    e = [p.err for p in pts]
    assert e[0] > e[1] > e[2]
    # DOP853 keeps the global error within ~100x of rtol on this smooth, short problem
    assert all(err < 100 * rt for err, rt in zip(e, (1e-5, 1e-8, 1e-11))), e
    assert pts[0].drift_q > pts[2].drift_q  # scipy does not project |q| = 1
    with pytest.raises(ValueError, match="unknown scipy method 'RK45'"):
        integrate_scipy(sc, grid, "RK45")
    with pytest.raises(ValueError, match="rtol=0"):
        integrate_scipy(sc, grid, "DOP853", rtol=0.0)


def test_reference_of_a_torque_driven_scene_is_dop853():
    sc = load_scene("torque_driven")
    grid = comm_grid(sc, sc.stop_time, sc.stop_time / 10)
    assert {2.0, 4.0, 6.0} <= set(np.round(grid, 12))  # the table's switching times are points
    ref = make_reference(sc, grid)
    assert ref.source.startswith("scipy DOP853")
    assert ref.floor < 1e-11  # rtol 1e-12 vs 1e-13 agree


# ----------------------------------------------------------------------------------
# controller, guard, command
# ----------------------------------------------------------------------------------
def test_attitude_controller_is_the_quaternion_feedback_law():
    qt = quat_from_axis_angle(np.array([0.0, 0.6, 0.8]), 1.0)
    ctrl = AttitudePD(qt, kp=2.0, kd=0.5, tau_world=(0.0, 0.1, 0.0))
    q = quat_from_axis_angle(np.array([1.0, 0.0, 0.0]), 2.5)
    w = np.array([0.3, -0.2, 0.1])
    u = ctrl(0.0, outputs_dict(q, w))
    e = quat_mul(qt * np.array([1, -1, -1, -1]), q)  # independent path: numpy product
    expected = -2.0 * np.sign(e[0]) * e[1:] - 0.5 * w
    assert np.allclose([u[f"tau_body[{k}]"] for k in (1, 2, 3)], expected, rtol=0, atol=1e-15)
    assert u["tau_world[2]"] == 0.1 and ctrl.calls == 1
    with pytest.raises(ValueError, match="kp and kd must be > 0, got kp=-1"):
        AttitudePD(qt, kp=-1.0, kd=1.0)


def _sleep(s: float) -> float:
    time.sleep(s)
    return s


def test_guard_kills_a_runaway_child():
    assert guarded(_sleep, 0.01, timeout=10.0) == 0.01
    tic = time.perf_counter()
    with pytest.raises(TimeoutError, match="no result within"):
        guarded(_sleep, 30.0, timeout=0.5)
    assert time.perf_counter() - tic < 5.0


def test_main_rejects_an_unknown_scene(capsys):
    assert main(["--scenes", "no_such_scene"]) == 2
    assert "unknown scene 'no_such_scene'" in capsys.readouterr().err


def test_main_measures_a_scene_file_under_its_own_name(tmp_path, capsys):
    # a user's scene file: it was refused ("unknown scene"); now its section, plot and FMU carry
    # the scene's name, nothing is written beside the file, and two scenes of one name are refused
    text = (Path(__file__).parents[2] / "modelsrc" / "scenes" / "skewed_bar.toml").read_text()
    path = tmp_path / "scene" / "my_bar.toml"
    path.parent.mkdir()
    path.write_text(text.replace('name = "skewed_bar"', 'name = "held_bar"', 1))
    out = tmp_path / "report"
    assert main(["--short", "--scenes", str(path), "--out", str(out)]) == 0
    report = (out / "report.md").read_text()
    assert "## held_bar" in report and "(held_bar.png)" in report and str(path) not in report
    assert (out / "held_bar.png").stat().st_size > 10_000
    assert sorted(p.name for p in path.parent.iterdir()) == ["my_bar.toml"]
    assert "uniform_rotation" in report and "No Exudyn lines" in report
    capsys.readouterr()
    assert main(["--scenes", str(path), "skewed_bar", "held_bar_too.toml"]) == 2
    assert "no such scene file 'held_bar_too.toml'" in capsys.readouterr().err
    twin = tmp_path / "twin.toml"
    twin.write_text(path.read_text())
    assert main(["--scenes", str(path), str(twin)]) == 2
    assert "two of the scenes are named 'held_bar'" in capsys.readouterr().err
    # a body that never turns has no error scale: refused with the reason (it was a traceback)
    still = tmp_path / "still.toml"
    still_text = re.sub(r"(?m)^w_body = \[[^]]*\]", "w_body = [0.0, 0.0, 0.0]", text)
    still.write_text(still_text.replace('name = "skewed_bar"', 'name = "still_bar"', 1))
    assert not np.any(load_scene(still).w0)
    assert main(["--short", "--scenes", str(still), "--out", str(out)]) == 2
    assert "scene still_bar: its reference never turns" in capsys.readouterr().err


@pytest.mark.slow
def test_main_quick_writes_report_and_diagram(tmp_path, capsys):
    out = tmp_path / "report"
    assert main(["--quick", "--scenes", "symmetric_free", "--skip", "cosim", "bench", "inputs", "--out", str(out)]) == 0
    text = (out / "report.md").read_text()
    assert "## symmetric_free" in text and "## Long horizon" in text and "| target | status |" in text
    assert (out / "symmetric_free.png").stat().st_size > 10_000
    assert (out / "long_horizon.png").is_file()
    err = capsys.readouterr().err
    assert "[" in err and "]" in err  # the progress bar went to stderr


def test_report_options_mount_on_another_parser():
    # rbfmu's own parser takes the report's options as a subcommand (add_arguments + run)
    top = argparse.ArgumentParser(prog="rbfmu")
    add_arguments(top.add_subparsers(dest="cmd").add_parser("report"))
    args = top.parse_args(["report", "--quick", "--scenes", "heavy_top", "--skip", "cosim", "long", "--out", "x"])
    assert (args.quick, args.scenes, args.skip, args.out) == (True, ["heavy_top"], ["cosim", "long"], "x")
    assert top.parse_args(["report"]).out == "out/report"  # relative to the current directory


def test_c_step_cost_of_every_method_by_its_enumeration_value(fmus):
    # the harness is given the modelDescription's enumeration values (not indices into the C tables)
    path = fmus["free_asymmetric"]
    with FmuInstance(path) as inst:
        values = inst.method_values
    ns = c_step_ns_all(path, 2_000, 200)
    assert list(ns) == list(values) and len(ns) >= 2
    assert all(raw > 0 and fmi > 0 for raw, fmi in ns.values())
    with pytest.raises(subprocess.CalledProcessError):  # no method has value 99: the harness refuses
        c_step_ns(path, 2_000, method_value=99)


def test_short_report_has_few_rungs_and_says_so(tmp_path):
    """`make demo`'s report (`--short`): every ladder at most SHORT_RUNGS rungs, its coarsest
    and finest kept, the batch part only, and a title that says it is the short one."""
    from rbcheck.workprecision.batch import exudyn_ladder
    from rbcheck.workprecision.config import EXUDYN_IMPLICIT, SHORT_RUNGS, Config, thin_ladder
    from rbcheck.workprecision.markdown import write_markdown

    full, short = Config(), Config.short()
    assert SHORT_RUNGS <= 3 and short.scenes == full.scenes and short.max_repeats == 1
    exudyn = [exudyn_ladder(s, gravity, short) for s in short.exudyn_theta for gravity in (False, True)]
    ladders = [*short.fmu_theta.values(), *exudyn, *short.scipy_rtol.values(), short.dopri_tol]
    assert all(len(ladder) <= SHORT_RUNGS for ladder in ladders)
    assert not set(short.exudyn_theta) & set(EXUDYN_IMPLICIT)  # seconds a run on the tops
    # the full report's implicit line on a top: from the jointed model's limit down, whole
    joint = exudyn_ladder("GeneralizedAlpha", True, full)
    assert joint[0] == full.joint_theta_start and len(joint) > SHORT_RUNGS
    rk4 = full.fmu_theta["rk4"]
    assert short.fmu_theta["rk4"] == (rk4[0], rk4[6], rk4[-1])  # 12 rungs: first, middle, last
    assert thin_ladder((1.0, 2.0), 3) == (1.0, 2.0)
    top = argparse.ArgumentParser(prog="rbfmu")
    add_arguments(top.add_subparsers(dest="cmd").add_parser("report"))
    args = top.parse_args(["report", "--short", "--build-dir", "build"])
    assert args.short and args.build_dir == "build"
    with pytest.raises(SystemExit):  # --short and --quick are two lengths: one at a time
        top.parse_args(["report", "--short", "--quick"])
    write_markdown(tmp_path / "report.md", short, [], {}, None, [], {"total": 1.0})
    head = (tmp_path / "report.md").read_text().splitlines()[:3]
    assert head[0].startswith("# Short work-precision report")
    assert f"Short report: {SHORT_RUNGS} rungs per ladder" in head[2] and "`make report` for the full one" in head[2]


def _scene_pid(name, fmu_path, cfg, progress):
    """A stand-in scene measurement: what it was given and the process it ran in."""
    return name, str(fmu_path), cfg, os.getpid()


@pytest.mark.parametrize("jobs", [1, 2])
def test_map_scenes_keeps_the_order_and_runs_one_scene_per_process(jobs):
    from rbcheck.workprecision.harness import map_scenes

    names = ["c", "a", "b"]
    fmus = {n: Path(f"/x/{n}.fmu") for n in names}
    got = list(map_scenes(_scene_pid, names, fmus, {"k": 1}, None, jobs, lambda n: 1))
    assert [g[0] for g in got] == names  # the order of `names`, not of completion
    assert [g[1][:3] for g in got] == [(n, f"/x/{n}.fmu", {"k": 1}) for n in names]
    assert all(wall >= 0.0 for _, _, wall in got)
    pids = {g[1][3] for g in got}
    assert (pids == {os.getpid()}) if jobs == 1 else (os.getpid() not in pids)


@pytest.mark.parametrize("value", ["0", "-1", "two"])
def test_report_refuses_a_bad_jobs_value(value, capsys, tmp_path):
    assert main(["--quick", "--jobs", value, "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert f"--jobs: {value!r} is not allowed" in err


@pytest.mark.parametrize(
    "argv, needle",
    [
        (["--scenes", "dual_spin", "--parts", "cosim"], "--scenes chooses the scenes of the batch and error-control"),
        (["--scenes", "dual_spin", "--skip", "batch", "tolerance"], "neither is run"),
        (["--scenes", "reaction_wheel_slew", "--parts", "tolerance"], "'reaction_wheel_slew' has no scipy reference"),
        (["--short", "--parts", "tolerance"], "--short is the batch part only"),
        (["--short", "--parts", "batch", "cosim"], "other parts asked for: cosim"),
        (["--skip", "batch", "cosim", "long", "bench", "tolerance", "inputs"], "leave no part to run"),
    ],
)
def test_report_refuses_options_that_would_be_silently_ignored(argv, needle, capsys, tmp_path):
    assert main([*argv, "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("rbfmu report: ") and needle in err
    assert not (tmp_path / "report.md").exists()
