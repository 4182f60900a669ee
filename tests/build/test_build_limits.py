"""A scene that loads either builds or is refused with one line, and a failed build leaves nothing behind.

Issue 23, items 4, 6 and 14: numbers that overflow the model description (a mass of
1e-310 kg makes the body's size sqrt(tr I / m) infinite, a start position of 1e200 m
squares to infinity), more force points than a build handles in bounded time, and names
Windows reserves for devices. Each is refused before anything is generated or compiled,
so these tests run no compiler.
"""

from __future__ import annotations

import os
import re
import tempfile
from pathlib import Path

import pytest

import fmu.build.build_fmu as build_module
from fmu.build.build_fmu import build_fmu
from fmu.cli import main
from modelsrc import scene_limits
from modelsrc.errors import ModelInputError
from modelsrc.scene import load_scene
from modelsrc.scene_limits import MAX_FORCE_POINTS

RACKET = (Path(__file__).resolve().parent.parent.parent / "modelsrc" / "scenes" / "thrown_racket.toml").read_text()


def _racket(tmp_path: Path, old: str, new: str, name: str = "racket") -> Path:
    """The shipped thrown_racket with one line changed, as scene `name`."""
    assert old in RACKET
    text = RACKET.replace(old, new).replace('name = "thrown_racket"', f'name = "{name}"')
    path = tmp_path / f"{name}.toml"
    path.write_text(text)
    return path


@pytest.mark.parametrize(
    "old, new, what",
    [
        ("mass = 0.34", "mass = 1e-310", r"the body's size sqrt\(tr I / m\) \(mass 1e-310 kg\) overflows"),
        ("x_cm = [0.0, 0.0, 1.5]", "x_cm = [1e200, 0.0, 1.5]", r"\|initial.x_cm\| overflows"),
        ("v_cm = [1.0, 0.0, 7.0]", "v_cm = [1.0, 1e300, 7.0]", r"\|initial.v_cm\| overflows"),
    ],
    ids=["tiny_mass", "huge_x_cm", "huge_v_cm"],
)
def test_overflowing_scene_is_one_error_line_and_leaves_nothing(tmp_path, capsys, old, new, what):
    """Today's main wrote nominal="inf" into modelDescription.xml, compiled, ended in fmpy's
    ValidationError traceback and left NAME.fmu.part in --out."""
    scene = _racket(tmp_path, old, new)
    load_scene(scene)  # the scene itself is valid: every number is finite
    out = tmp_path / "out"
    assert main(["build", str(scene), "--out", str(out), "--platforms", "host"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("rbfmu: error: ") and "\n" not in err
    assert re.search(what, err), err
    assert not out.exists() or list(out.iterdir()) == []


def _fake_compile(src_dir, out, fmi_version, extra_flags):  # no gcc: an empty "binary"
    out.write_bytes(b"")
    return ""


def _interrupt(*args, **kwargs):
    raise KeyboardInterrupt


def test_interrupted_build_leaves_no_part_file_log_or_build_folder(tmp_path, monkeypatch):
    """Ctrl-C while the archive is checked (after it was zipped into out/NAME.fmu.part):
    the .part file, the build log and the temporary build folder are all removed (today's
    main left NAME.fmu.part and NAME.build.log in --out)."""
    temp_root = tmp_path / "tmp"
    temp_root.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(temp_root))
    monkeypatch.setattr(build_module, "compile_native", _fake_compile)
    monkeypatch.setattr(build_module, "check_build", _interrupt)
    out = tmp_path / "out"
    with pytest.raises(KeyboardInterrupt):
        build_fmu(load_scene("skewed_bar"), out)
    assert list(out.iterdir()) == []
    assert os.listdir(temp_root) == []


def test_failed_build_keeps_the_previous_archive_and_its_log(tmp_path, monkeypatch):
    """A failure removes only what this build made: an archive and log built before stay."""
    monkeypatch.setattr(build_module, "compile_native", _fake_compile)
    monkeypatch.setattr(build_module, "check_build", _interrupt)
    out = tmp_path / "out"
    out.mkdir()
    (out / "skewed_bar.fmu").write_bytes(b"the previous archive")
    (out / "skewed_bar.build.log").write_text("the previous log")
    with pytest.raises(KeyboardInterrupt):
        build_fmu(load_scene("skewed_bar"), out)
    assert sorted(p.name for p in out.iterdir()) == ["skewed_bar.build.log", "skewed_bar.fmu"]
    assert (out / "skewed_bar.fmu").read_bytes() == b"the previous archive"


def _force_points(n: int) -> str:
    return "".join(f'[forces.p{i}]\npoint = [0.0, {i * 1e-3}, 0.1]\nframe = "body"\n' for i in range(n))


def test_force_points_above_the_limit_are_refused_at_load(tmp_path):
    """Today's main accepted 2,000 force points (a 113 MB model_funcs.c, gcc still running
    after 900 s); above the limit the scene is refused when it is read, naming the limit."""
    head = RACKET.split("[sensor]")[0]
    tail = "[sensor]" + RACKET.split("[sensor]")[1]
    path = tmp_path / "many.toml"
    head = head.replace('name = "thrown_racket"', 'name = "many"')
    path.write_text(head + _force_points(MAX_FORCE_POINTS + 1) + tail)
    with pytest.raises(ModelInputError, match=rf"{MAX_FORCE_POINTS + 1} force points; at most {MAX_FORCE_POINTS}"):
        load_scene(path)
    path.write_text(head + _force_points(MAX_FORCE_POINTS) + tail)
    assert len(load_scene(path).force_points) == MAX_FORCE_POINTS


def test_input_tables_above_the_limit_are_refused_at_load(tmp_path, monkeypatch):
    """With the limit lowered to 50 rows (the real one, 1e5, takes seconds to write and read)."""
    monkeypatch.setattr(scene_limits, "MAX_TABLE_ROWS", 50)
    text = (Path(__file__).resolve().parent.parent.parent / "modelsrc" / "scenes" / "spacecraft_thruster.toml").read_text()
    rows = ", ".join(f"[{i}.0, 1.0, 0.0, 0.0]" for i in range(51))
    start = text.index("f_thruster = [[")
    end = text.index("]]", start) + 2
    path = tmp_path / "long_table.toml"
    path.write_text(text[:start] + f"f_thruster = [{rows}]" + text[end:])
    with pytest.raises(ModelInputError, match=r"'inputs.f_thruster': 51 table rows; at most 50 are allowed"):
        load_scene(path)
    path.write_text(text[:start] + f"f_thruster = [{rows.rsplit(', [', 1)[0]}]" + text[end:])
    assert len(load_scene(path).inputs["f_thruster"]) == 50


@pytest.mark.parametrize("name", ["con", "NUL", "Aux", "prn", "COM1", "lpt9"])
def test_windows_device_names_are_refused(tmp_path, name):
    """Given as the name, or taken from the file name (con.toml): the FMU's files carry it."""
    with pytest.raises(ModelInputError, match=f"'name': '{name}' is a device name Windows reserves"):
        load_scene(_racket(tmp_path, "mass = 0.34", "mass = 0.34", name=name))
    stem_only = tmp_path / f"{name}.toml"
    stem_only.write_text("\n".join(line for line in RACKET.splitlines() if not line.startswith("name =")))
    with pytest.raises(ModelInputError, match="device name Windows reserves"):
        load_scene(stem_only)


def test_names_that_only_contain_a_device_name_are_accepted(tmp_path):
    for name in ("con_1", "console", "COM10", "nul2"):
        assert load_scene(_racket(tmp_path, "mass = 0.34", "mass = 0.34", name=name)).name == name
