"""Inputs of `system build` and `system run` that the audit found mishandled, each now refused or warned about.

Each refusal is one line (exit 2, nothing written) naming the value and where it came from,
made before anything is allocated, built or run; a parameter almost surely in the wrong unit
is warned about; libcosim's harmless FMI Library line is hidden, every other line kept.
"""

from __future__ import annotations

import os
import re
import zipfile
from pathlib import Path

import pytest

import fmu.system.masters as masters
from fmu.cli import main
from fmu.drive.run import MAX_COMMUNICATION_POINTS
from fmu.system.build import build_system
from fmu.system.system_file import SHIPPED

HARMLESS = "[FMI Library: FMI2XML] Start attribute is required for this causality, variability and initial combination"


@pytest.fixture(scope="module")
def slew_ssp(tmp_path_factory, system_build_dir) -> Path:
    return build_system("slew", tmp_path_factory.mktemp("slew"), system_build_dir)


def _with_ssd(src: Path, dst: Path, pattern: str, repl: str) -> Path:
    """A copy of the archive src whose SystemStructure.ssd has `pattern` replaced (once) by `repl`."""
    with zipfile.ZipFile(src) as z, zipfile.ZipFile(dst, "w") as out:
        for info in z.infolist():
            data = z.read(info.filename)
            if info.filename == "SystemStructure.ssd":
                text, k = re.subn(pattern, repl, data.decode())
                assert k == 1
                data = text.encode()
            out.writestr(info, data)
    return dst


def _refused(capsys, argv: list[str], *words: str) -> str:
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("rbfmu: error: "), err
    for w in words:
        assert w in err[0], err[0]
    return err[0]


def _no_master(monkeypatch) -> None:
    """Fail the test if a master is started (the refusal must come before)."""

    def started(*args):
        raise AssertionError("a master was started")

    monkeypatch.setattr(masters, "run_ecos", started)
    monkeypatch.setattr(masters, "run_libcosim", started)


# ---- 1. at most MAX_COMMUNICATION_POINTS steps, refused before any allocation or master ----


def test_run_refuses_too_many_communication_steps(slew_ssp, tmp_path, capsys, monkeypatch):
    _no_master(monkeypatch)
    out = tmp_path / "o"
    for master in ("ecos", "libcosim"):
        argv = ["system", "run", str(slew_ssp), "--stop-time", "1e15", "--master", master, "--out", str(out)]
        _refused(
            capsys, argv, "--stop-time 1e+15", "H = 0.1 s", "1e+16 communication steps", f"{MAX_COMMUNICATION_POINTS:,}"
        )
    assert not out.exists()


def test_run_refuses_an_archive_whose_step_makes_too_many_steps(slew_ssp, tmp_path, capsys, monkeypatch):
    _no_master(monkeypatch)
    tiny = _with_ssd(slew_ssp, tmp_path / "tiny.ssp", r'(<CommunicationStep value=")[^"]*"', r'\g<1>1e-12"')
    out = tmp_path / "o"
    _refused(
        capsys,
        ["system", "run", str(tiny), "--out", str(out)],
        "DefaultExperiment stopTime = 40",
        "H = 1e-12 s",
        "4e+13",
    )
    assert not out.exists()


# ---- 2. a parameter on an input a connection drives ----


def test_build_refuses_a_parameter_on_a_connected_input(tmp_path, system_build_dir, capsys):
    text = (SHIPPED / "slew.toml").read_text().replace('name = "slew"', 'name = "slewp"')
    path = tmp_path / "slewp.toml"
    path.write_text(text + "\n[components.plant.parameters]\nu_x = 5.0\n")
    out = tmp_path / "out"
    argv = ["system", "build", str(path), "--out", str(out), "--build-dir", str(system_build_dir)]
    _refused(capsys, argv, "component plant: parameter u_x = 5", "connection pd.u_x -> plant.u_x")
    assert not out.exists()


def test_build_names_the_written_connection_of_a_vector_element(tmp_path, system_build_dir, capsys):
    text = (SHIPPED / "slew.toml").read_text().replace('name = "slew"', 'name = "slewq"')
    path = tmp_path / "slewq.toml"
    path.write_text(text.replace("k_d = 1.0", 'k_d = 1.0\n"q[2]" = 0.5'))
    argv = ["system", "build", str(path), "--out", str(tmp_path / "out"), "--build-dir", str(system_build_dir)]
    _refused(capsys, argv, "component pd: parameter q[2] = 0.5", "connection plant.q -> pd.q (plant.q[2] -> pd.q[2])")


# ---- 3. --out and --build-dir: not empty, creatable, checked before anything runs ----


@pytest.mark.parametrize("option", ["--out", "--build-dir"])
def test_build_refuses_an_empty_directory_option(tmp_path, capsys, monkeypatch, option):
    monkeypatch.chdir(tmp_path)
    argv = ["system", "build", "slew", "--out", str(tmp_path / "o"), "--build-dir", str(tmp_path / "b")]
    argv[argv.index(option) + 1] = ""
    _refused(capsys, argv, f"{option} '': give a directory name")
    assert not list(tmp_path.iterdir())


def test_run_refuses_an_empty_out(slew_ssp, tmp_path, capsys, monkeypatch):
    _no_master(monkeypatch)
    monkeypatch.chdir(tmp_path)
    _refused(
        capsys, ["system", "run", str(slew_ssp), "--stop-time", "0.1", "--out", ""], "--out '': give a directory name"
    )
    assert not list(tmp_path.iterdir())


def test_run_refuses_an_out_under_a_file_before_the_run(slew_ssp, tmp_path, capsys, monkeypatch):
    _no_master(monkeypatch)
    (tmp_path / "f").write_text("")
    bad = tmp_path / "f" / "sub"
    _refused(
        capsys, ["system", "run", str(slew_ssp), "--stop-time", "0.1", "--out", str(bad)], f"--out {bad}", "is a file"
    )


# ---- 4. a system-file parameter almost surely in the wrong unit is warned about at build ----


def test_build_warns_for_a_period_given_as_the_orbit_rate(tmp_path, system_build_dir, capsys):
    path = tmp_path / "g.toml"
    path.write_text(
        'name = "g"\nstep = 0.1\nstop_time = 0.3\n[components.boom]\nscene = "gravity_gradient_boom"\n'
        "[components.boom.parameters]\nn_orbit = 5677.0\n"
    )
    assert main(["system", "build", str(path), "--out", str(tmp_path), "--build-dir", str(system_build_dir)]) == 0
    err = capsys.readouterr().err
    assert "rbfmu: warning: g.toml: components.boom.parameters.n_orbit = 5677 rad/s" in err, err
    assert (tmp_path / "g.ssp").is_file()  # warned, not refused


# ---- 5. libcosim's harmless FMI Library line hidden, any other line on fd 1 kept ----


def test_hidden_on_stdout_keeps_every_other_line(capfd):
    with masters._hidden_on_stdout(HARMLESS):
        os.write(1, f"[error] {HARMLESS}\n[error] something else failed\n".encode())
        print("python's own line", flush=True)
    out = capfd.readouterr().out
    assert HARMLESS not in out
    assert "[error] something else failed\n" in out and "python's own line\n" in out


def test_libcosim_run_prints_no_fmi_library_line(slew_ssp, tmp_path, capfd):
    argv = ["system", "run", str(slew_ssp), "--master", "libcosim", "--stop-time", "0.1", "--out", str(tmp_path)]
    assert main(argv) == 0
    out = capfd.readouterr().out
    assert "Start attribute is required" not in out, out
    assert "slew: 1 steps of 0.1 s in libcosim" in out


# ---- 6. an invalid stop time of the archive is named as the archive's ----


@pytest.mark.parametrize(("stop", "words"), [("0.25", "positive whole number"), ("inf", "finite time > 0 s")])
def test_run_names_the_archives_stop_time(slew_ssp, tmp_path, capsys, monkeypatch, stop, words):
    _no_master(monkeypatch)
    bad = _with_ssd(slew_ssp, tmp_path / "bad.ssp", r'stopTime="[^"]*"', f'stopTime="{stop}"')
    out = tmp_path / "o"
    msg = _refused(
        capsys, ["system", "run", str(bad), "--out", str(out)], f"its DefaultExperiment stopTime = {stop}", words
    )
    assert "--stop-time " + stop not in msg
    assert not out.exists()
