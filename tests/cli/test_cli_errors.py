"""Bad command lines end in one line `rbfmu: error: ...` naming the value and what is allowed, before any build.

Run in process through fmu.cli.main (no FMU is built for any of them: `run` checks its
arguments first), except the run whose grid would have needed gigabytes: that one runs
in a subprocess with its address space capped, so that a regression fails instead of
exhausting the machine's memory.
"""

from __future__ import annotations

import os
import resource
import subprocess
import sys
from pathlib import Path

import pytest

from fmu.cli import main
from fmu.drive.instance import FmuInstance

from ..harness.fmi3_ctypes import shared_fmu

GOOD = "[body]\nprincipal_moments = [1.0, 2.0, 3.0]\n[initial]\nw_body = [0.0, 0.0, 1.0]\n"


def one_line_error(capsys, *args: str) -> str:
    code = main(list(args))
    err = capsys.readouterr().err
    assert code == 2 and err.startswith("rbfmu: error: ") and err.count("\n") == 1, (code, err)
    return err


@pytest.fixture
def files(tmp_path):
    """A good scene, a plain file, a directory, and scenes that cannot be built."""
    (tmp_path / "good.toml").write_text(f'name = "good"\n{GOOD}')
    (tmp_path / "plain").write_text("not a directory")
    (tmp_path / "dir").mkdir()
    (tmp_path / "nested.toml").write_text("name = 'n'\nw = " + "[" * 5000 + "]" * 5000 + "\n")
    (tmp_path / "long.toml").write_text(f'name = "{"x" * 300}"\n{GOOD}')
    return tmp_path


@pytest.mark.parametrize(
    "args, fragments",
    [
        (["run", "{d}/nested.toml"], ["nested too deeply"]),
        (["run", "{d}/long.toml"], ["has 300 characters, at most 64 are allowed"]),
        (["build", "{d}/good.toml", "--out", "{d}/plain"], ["--out {d}/plain: is a file; give a directory"]),
        (["run", "{d}/good.toml", "--build-dir", "{d}/plain"], ["--build-dir {d}/plain: is a file"]),
        (["run", "{d}/good.toml", "--out", "{d}/plain"], ["--build-dir {d}/plain: is a file"]),  # the earlier name
        (["demo", "--out", "{d}/plain"], ["--out {d}/plain: is a file"]),
        (["demo", "--build-dir", "{d}/plain"], ["--build-dir {d}/plain: is a file"]),
        (["demo", "--jobs", "0"], ["--jobs: '0' is not allowed: give a whole number >= 1"]),
        (["demo", "--jobs", "two"], ["--jobs: 'two' is not allowed: give a whole number >= 1"]),
        (["run", "{d}/good.toml", "--build-dir", "{d}/fmus", "--csv", "{d}/dir"], ["--csv {d}/dir: is a directory"]),
        (["run", "{d}/good.toml", "--csv", "{d}/no/such/x.csv"], ["the directory {d}/no/such does not exist"]),
        (["run", "{d}/good.toml", "--plot", "{d}/x.foo"], ["--plot {d}/x.foo: the suffix chooses the format", ".png"]),
        (["run", "{d}/good.toml", "--set", "method=1e300"], ["method must be a method name or its value (1 = rk4"]),
        (["run", "{d}/good.toml", "--set", "w_body[3]=fast"], ["--set 'w_body[3]=fast': value 'fast' is not a number"]),
        (["run", "{d}/good.toml", "--set", "w_body[3]=inf"], ["--set 'w_body[3]=inf': value must be finite, got inf"]),
        # one option under its two names: the last won without a word
        (
            ["run", "{d}/good.toml", "--build-dir", "{d}/fmus", "--out", "{d}/other"],
            ["--build-dir {d}/fmus and --out {d}/other: one option under two names (given twice)"],
        ),
        (["run", "{d}/good.toml", "--build-dir", ""], ["--build-dir: an empty path; give a directory"]),
        (["build", "{d}/good.toml", "--out", " "], ["--out: an empty path; give a directory"]),
        # the plot overwrote the table
        (
            ["run", "{d}/good.toml", "--csv", "{d}/same.png", "--plot", "{d}/same.png"],
            ["one file for both; the plot would overwrite the table"],
        ),
        # cut to one step of the stop time without a word
        (["run", "{d}/good.toml", "--step", "100"], ["step 100 s is longer than the run"]),
        # a method without an error estimate ignored the tolerance
        (
            ["run", "{d}/good.toml", "--set", "method=splitting", "--set", "tolerance=1e-3"],
            ["tolerance = 0.001: method splitting has no error estimate and always takes fixed steps"],
        ),
        # the earlier value was dropped without a word
        (
            ["run", "{d}/good.toml", "--set", "w_body[1]=5", "--set", "w_body[1]=0.4"],
            ["--set 'w_body[1]=0.4': w_body[1] is set twice; give each name once"],
        ),
        # nothing to hold: a scene without inputs, and a shaker whose one harmonic component --set makes constant
        (
            ["run", "{d}/good.toml", "--build-dir", "{d}/fmus", "--input-hold"],
            ["every input of scene good is constant in time"],
        ),
        (
            ["run", "top_on_shaker", "--build-dir", "{d}/fmus", "--input-hold", "--set", "a_pivot[3]=0"],
            ["every input of scene top_on_shaker is constant in time (with the values set for this run)"],
        ),
        (
            [
                "sweep",
                "{d}/good.toml",
                "--param",
                "w_body[3]=1:2:2",
                "--workers",
                "0",
                "--build-dir",
                "{d}/fmus",
                "--out",
                "{d}/s.csv",
                "--input-hold",
            ],
            ["holding the inputs over a step would change nothing"],
        ),
        # a table switches on communication points: held, it is the table (was run as if held)
        (
            ["run", "torque_driven", "--build-dir", "{d}/fmus", "--input-hold"],
            ["every input of scene torque_driven is a table or constant", "only a harmonic input changes"],
        ),
    ],
    ids=lambda v: " ".join(v) if isinstance(v, list) and v and v[0] in ("run", "build", "demo", "sweep") else "",
)
def test_bad_arguments_are_one_line(capsys, files, args, fragments):
    err = one_line_error(capsys, *[a.format(d=files) for a in args])
    for f in fragments:
        assert f.format(d=files) in err
    assert not (files / "fmus").exists()  # refused before the FMU was built


def _cap_memory() -> None:
    cap = 2 * 2**30  # 2 GB of address space: python with casadi and numpy needs ~1 GB
    resource.setrlimit(resource.RLIMIT_AS, (cap, cap))


def test_a_run_of_too_many_communication_steps_is_refused_before_allocating(files):
    """--step 1e-10 over 1 s: 1e10 points (the old grid was a list of them). Refused at
    once with the count and the limit, in a process that could not have held the grid."""
    proc = subprocess.run(
        [sys.executable, "-m", "fmu.cli", "run", str(files / "good.toml"), "--stop-time", "1", "--step", "1e-10"],
        capture_output=True,
        text=True,
        timeout=120,
        preexec_fn=_cap_memory,
        cwd=files,
        env={**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parent.parent.parent)},  # this checkout's code
    )
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1, proc.stderr[-2000:]
    assert "stop_time 1 s with step 1e-10 s makes 1e+10 communication steps" in proc.stderr
    assert "at most 1,000,000: take a larger step or a shorter stop time" in proc.stderr


def test_close_unloads_the_library_once():
    """fmpy (>= 0.3.32) unloads the FMU's library in freeInstance; a second unload by
    FmuInstance.close() would free the loader's data twice."""
    inst = FmuInstance(shared_fmu("extreme_free"))
    unloads = []
    real = inst.fmu.freeLibrary
    inst.fmu.freeLibrary = lambda: (unloads.append(1), real())[1]
    inst.close()
    assert len(unloads) == 1


def test_demo_refuses_its_jobs_before_it_makes_its_output_folder(tmp_path, capsys):
    out = tmp_path / "new"
    assert main(["demo", "--jobs", "0", "--out", str(out), "--build-dir", str(tmp_path / "b")]) == 2
    assert not out.exists()  # it was created, then the run refused
    assert "--jobs: '0' is not allowed" in capsys.readouterr().err
