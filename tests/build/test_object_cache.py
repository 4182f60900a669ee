"""The host build's object cache: a unit is compiled again exactly when it, a header it includes or the flags change."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

from fmu.build import compile as compile_module
from fmu.build.compile import BuildError, compile_native
from fmu.build.object_cache import CACHE_ENV

UNITS = [("a.c", []), ("b.c", [])]


@pytest.fixture
def sources(tmp_path, monkeypatch) -> Path:
    """Two units: a.c includes h1.h, which includes h2.h; b.c includes nothing local. An empty cache."""
    monkeypatch.setenv(CACHE_ENV, str(tmp_path / "cache"))
    src = tmp_path / "src"
    src.mkdir()
    (src / "h2.h").write_text("#define SCALE 2.0\n")
    (src / "h1.h").write_text('#include "h2.h"\n')
    (src / "a.c").write_text('#include "h1.h"\ndouble a(double x) { return SCALE * x; }\n')
    (src / "b.c").write_text("double b(double x) { return x + 1.0; }\n")
    return src


@pytest.fixture
def compiles(monkeypatch) -> list[str]:
    """The units gcc compiles (not links), in order."""
    seen: list[str] = []
    real = subprocess.run

    def counting(cmd, *args, **kwargs):
        if "-c" in cmd:
            seen.append(Path(cmd[cmd.index("-c") + 1]).name)
        return real(cmd, *args, **kwargs)

    monkeypatch.setattr(compile_module.subprocess, "run", counting)
    return seen


def _build(src: Path, out: Path, flags: list[str] | None = None) -> bytes:
    compile_native(src, out, "3", flags or [], UNITS)
    return out.read_bytes()


def test_a_rebuild_of_the_same_content_compiles_nothing_and_links_the_same_library(sources, compiles, tmp_path):
    first = _build(sources, tmp_path / "one.so")
    assert compiles == ["a.c", "b.c"]
    second = _build(sources, tmp_path / "two.so")
    assert compiles == ["a.c", "b.c"]  # nothing compiled the second time
    assert first == second


def test_a_header_included_through_another_recompiles_only_its_units(sources, compiles, tmp_path):
    _build(sources, tmp_path / "one.so")
    (sources / "h2.h").write_text("#define SCALE 3.0\n")
    _build(sources, tmp_path / "two.so")
    assert compiles == ["a.c", "b.c", "a.c"]
    (sources / "unrelated.h").write_text("#define NOTHING 1\n")  # included by no unit
    _build(sources, tmp_path / "three.so")
    assert compiles == ["a.c", "b.c", "a.c"]


def test_other_flags_compile_again(sources, compiles, tmp_path):
    _build(sources, tmp_path / "one.so")
    _build(sources, tmp_path / "two.so", ["-DEXTRA=1"])
    assert compiles == ["a.c", "b.c", "a.c", "b.c"]


def test_a_cached_unit_reports_its_warnings_again(sources, compiles, tmp_path):
    (sources / "b.c").write_text("double b(double x) { int unused; return x + 1.0; }\n")
    first = compile_native(sources, tmp_path / "one.so", "3", ["-Wall"], UNITS)
    second = compile_native(sources, tmp_path / "two.so", "3", ["-Wall"], UNITS)
    assert "unused" in first
    assert second == first
    assert compiles == ["a.c", "b.c"]


def test_a_failed_compile_caches_nothing(sources, compiles, tmp_path):
    (sources / "b.c").write_text("double b(double x) { return x + ; }\n")
    for _ in range(2):
        with pytest.raises(BuildError, match=r"gcc failed on b\.c"):
            _build(sources, tmp_path / "one.so")
    assert compiles == ["a.c", "b.c", "b.c"]  # a.c cached, the broken b.c tried again
    assert not list((tmp_path / "cache").rglob("*.tmp*"))


def test_a_debug_build_is_compiled_every_time_and_not_cached(sources, compiles, tmp_path):
    """-g records the source's path in the object: such objects would never be found again."""
    _build(sources, tmp_path / "one.so", ["-g"])
    _build(sources, tmp_path / "two.so", ["-g"])
    assert compiles == ["a.c", "b.c", "a.c", "b.c"]
    assert not (tmp_path / "cache").exists() or not list((tmp_path / "cache").rglob("*.o"))
