"""The rbfmu command, as a user runs it."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from modelsrc.scene import list_scenes, load_scene


def rbfmu(*args: str, cwd=None) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "fmu.cli", *args], capture_output=True, text=True, timeout=300, cwd=cwd
    )


def test_scenes_lists_every_scene():
    proc = rbfmu("scenes")
    assert proc.returncode == 0
    for name in list_scenes():
        assert name in proc.stdout


@pytest.mark.slow
def test_run_writes_csv_plot_and_summary(tmp_path):
    csv, png = tmp_path / "r.csv", tmp_path / "r.png"
    proc = rbfmu(
        "run",
        "symmetric_free",
        "--stop-time",
        "1",
        "--step",
        "0.05",
        "--set",
        "w_body[3]=3",
        "--csv",
        str(csv),
        "--plot",
        str(png),
        "--out",
        str(tmp_path),
    )
    assert proc.returncode == 0, proc.stderr
    assert "symmetric_free" in proc.stdout and "E drift" in proc.stdout
    data = np.genfromtxt(csv, delimiter=",", names=True)
    assert data["time"][-1] == 1.0 and len(data) == 21
    assert np.allclose(data["w_body3"], 3.0)  # the --set start value was used; ω3 stays constant
    assert png.stat().st_size > 10_000


@pytest.mark.slow
def test_build_writes_fmu(tmp_path):
    proc = rbfmu("build", "heavy_top", "--out", str(tmp_path), "--platforms", "host")
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "heavy_top.fmu").is_file()


@pytest.mark.slow
def test_check_runs_through_the_command(tmp_path):
    # one parser serves every subcommand: `check` gets its options from rbcheck.checks.cli
    proc = rbfmu("check", "--quick", "--scene", "symmetric_free", "--fmu-dir", str(tmp_path))
    assert proc.returncode == 0, proc.stderr
    assert "symmetric_free" in proc.stdout and "closed form" in proc.stdout
    bad = rbfmu("check", "--scene", "no_such_scene")
    assert bad.returncode == 2 and "unknown scene 'no_such_scene'" in bad.stderr


@pytest.mark.slow
def test_run_reuses_an_fmu_only_when_built_from_the_same_content(tmp_path):
    # the cache is keyed by content, never by name and time: a same-named scene from
    # another file must be rebuilt, not answered with the other scene's FMU
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    text = 'name = "body"\n[body]\nprincipal_moments = [1.0, 2.0, 3.0]\n[initial]\nw_body = [0.0, 0.0, {w}]\n'
    (tmp_path / "a" / "body.toml").write_text(text.format(w=1.0))
    (tmp_path / "b" / "body.toml").write_text(text.format(w=5.0))
    (tmp_path / "b" / "other.toml").write_text(text.format(w=7.0))  # another file, the same name field
    out = str(tmp_path / "fmus")
    for sub, w in (("a/body", 1.0), ("b/body", 5.0), ("a/body", 1.0), ("b/other", 7.0)):
        proc = rbfmu("run", str(tmp_path / f"{sub}.toml"), "--stop-time", "0.1", "--build-dir", out)
        assert proc.returncode == 0, proc.stderr
        w3 = float(proc.stdout.splitlines()[2].split()[5])
        assert w3 == w, (sub, proc.stdout)


def test_bad_method_value_is_one_clear_line():
    proc = rbfmu("run", "symmetric_free", "--set", "method=1e300")
    assert proc.returncode == 2
    assert proc.stderr.count("\n") == 1 and "method must be a method name or its value (1 = rk4" in proc.stderr


def test_demo_builds_in_parallel_processes_and_reuses_what_is_built(fmus, build_dir):
    """`rbfmu demo --jobs 2`'s build step: ensure_fmu of every scene in worker processes,
    each returning its archive; the session's FMUs are current, so none is rebuilt (the
    archives' modification times stay)."""
    from fmu.build.build_fmu import build_all

    names = sorted(fmus)[:3]
    before = {n: fmus[n].stat().st_mtime_ns for n in names}
    got = build_all(names, build_dir, jobs=2)
    assert got == {n: fmus[n] for n in names}
    assert {n: got[n].stat().st_mtime_ns for n in names} == before


def test_demo_names_a_scene_that_stays_at_rest():
    """`rbfmu demo` says which scenes never moved (reaction_wheel_slew without its loop), so
    that a row of zeros does not read as a failure; a scene that moved in any state is not named."""
    from fmu.cli import at_rest
    from fmu.drive.run import RunResult

    sc = load_scene("reaction_wheel_slew")
    t = np.linspace(0.0, 1.0, 3)
    values = {f"q[{k}]": np.full(3, 0.5) for k in range(1, 5)} | {f"w_body[{k}]": np.zeros(3) for k in (1, 2, 3)}
    assert at_rest(RunResult(sc, t, values, 0.0, 2))
    moved = dict(values) | {"w_body[2]": np.array([0.0, 0.0, 1e-300])}
    assert not at_rest(RunResult(sc, t, moved, 0.0, 2))
    free = dict(values) | {f"x_cm[{k}]": np.array([0.0, 0.0, float(k == 3)]) for k in (1, 2, 3)}
    assert not at_rest(RunResult(sc, t, free, 0.0, 2))
