"""The object cache stays within $RBFMU_CACHE_MAX_MB: least recently used objects go, a bad limit is refused."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest

from fmu.build import object_cache
from fmu.build.compile import BuildError, compile_native
from fmu.build.object_cache import CACHE_ENV, LIMIT_ENV, PRUNE_TO, limit_bytes, prune

MB = 2**20


@pytest.fixture
def cache(tmp_path, monkeypatch) -> Path:
    """An empty cache of its own, and no objects handed out by this process yet."""
    monkeypatch.setenv(CACHE_ENV, str(tmp_path / "cache"))
    monkeypatch.delenv(LIMIT_ENV, raising=False)
    _new_process(monkeypatch)
    return tmp_path / "cache"


def _new_process(monkeypatch) -> None:
    """The cache as a new process sees it: no object handed out, no store made yet."""
    monkeypatch.setattr(object_cache, "_handed_out", set())
    monkeypatch.setattr(object_cache, "_stores", [0])


def _fake_objects(cache: Path, sizes_kib: list[int]) -> list[Path]:
    """Objects of the given sizes, the first the least recently used (mtimes 1000 s apart)."""
    objs = []
    for i, kib in enumerate(sizes_kib):
        key = f"{i:02d}" + "ab" * 31
        obj = cache / "objects" / key[:2] / f"{key}.o"
        obj.parent.mkdir(parents=True, exist_ok=True)
        obj.write_bytes(b"\0" * (kib * 1024))
        obj.with_suffix(".log").write_text("")
        os.utime(obj, ns=(10**12 * (i + 1), 10**12 * (i + 1)))
        objs.append(obj)
    return objs


def test_the_default_limit_and_a_limit_given(cache, monkeypatch):
    assert limit_bytes() == 512 * MB
    monkeypatch.setenv(LIMIT_ENV, "1.5")
    assert limit_bytes() == int(1.5 * MB)


@pytest.mark.parametrize("bad", ["0", "-5", "nan", "inf", "lots", "512MB"])
def test_a_limit_that_is_not_a_positive_number_is_refused_by_name(cache, monkeypatch, bad, tmp_path):
    monkeypatch.setenv(LIMIT_ENV, bad)
    with pytest.raises(BuildError, match=rf"\$RBFMU_CACHE_MAX_MB='{bad}'.*megabytes > 0"):
        limit_bytes()
    src = tmp_path / "src"
    src.mkdir()
    (src / "a.c").write_text("double a(double x) { return x; }\n")
    with pytest.raises(BuildError, match="RBFMU_CACHE_MAX_MB"):  # before anything is compiled
        compile_native(src, tmp_path / "a.so", "3", [], [("a.c", [])])
    assert not list(cache.rglob("*.o"))


def test_within_the_limit_nothing_goes(cache):
    objs = _fake_objects(cache, [100, 100, 100])
    assert prune(400 * 1024) == 0
    assert all(o.is_file() for o in objs)


def test_over_the_limit_the_least_recently_used_go_down_to_80_percent(cache):
    objs = _fake_objects(cache, [100, 100, 100, 100, 100])  # 500 KiB
    limit = 400 * 1024
    removed = prune(limit)
    left = [o for o in objs if o.is_file()]
    assert removed == 2 and left == objs[2:]  # the two oldest, with their diagnostics
    assert not objs[0].with_suffix(".log").exists()
    assert sum(o.stat().st_size for o in left) <= PRUNE_TO * limit


def test_objects_this_process_handed_out_and_objects_being_written_stay(cache):
    objs = _fake_objects(cache, [100, 100, 100, 100])
    object_cache._handed_out.add(objs[0])  # the oldest, but a build of this process links it
    tmp = objs[1].with_name(objs[1].stem + ".123.456.tmp.o")
    tmp.write_bytes(b"\0" * 100 * 1024)
    os.utime(tmp, ns=(1, 1))  # older than all: another build is writing it
    prune(250 * 1024)
    assert objs[0].is_file() and tmp.is_file()
    assert not objs[1].exists() and not objs[2].exists() and objs[3].is_file()


def test_a_hit_counts_as_a_use_and_a_build_prunes_what_it_does_not_use(cache, monkeypatch, tmp_path):
    src = tmp_path / "src"
    src.mkdir()
    for name in "abc":
        (src / f"{name}.c").write_text(f"double {name}(double x) {{ return x * {ord(name)}.0; }}\n")
    compile_native(src, tmp_path / "ab.so", "3", [], [("a.c", []), ("b.c", [])])
    objs = sorted(cache.rglob("*.o"), key=lambda o: o.stat().st_mtime_ns)
    for i, obj in enumerate(objs):  # a.c's and b.c's objects, made long ago
        os.utime(obj, ns=(10**12 * (i + 1), 10**12 * (i + 1)))
    _new_process(monkeypatch)
    compile_native(src, tmp_path / "a.so", "3", [], [("a.c", [])])  # a hit: a.c's object used now
    used = max(cache.rglob("*.o"), key=lambda o: o.stat().st_mtime_ns)
    assert used.stat().st_mtime_ns > 10**13
    # a limit that holds two objects of this size: c.c's store must push the unused b.c out
    size = max(o.stat().st_size for o in objs)
    monkeypatch.setenv(LIMIT_ENV, repr(2.2 * size / MB))
    _new_process(monkeypatch)
    compile_native(src, tmp_path / "ac.so", "3", [], [("a.c", []), ("c.c", [])])
    assert len(list(cache.rglob("*.o"))) == 2 and used.is_file()
    assert (tmp_path / "ac.so").is_file()


def test_the_size_is_checked_at_the_first_store_and_every_16th(cache, monkeypatch):
    scans = []
    monkeypatch.setattr(object_cache, "prune", lambda limit: scans.append(limit) or 0)

    def compile_to(obj: Path) -> str:
        obj.write_bytes(b"object")
        return ""

    for i in range(object_cache.RESCAN_EVERY + 1):
        object_cache.cached_object(f"{i:064x}", compile_to)
    object_cache.cached_object(f"{0:064x}", compile_to)  # a hit: no scan
    assert scans == [512 * MB, 512 * MB]


def test_zig_keeps_no_copy_of_the_objects_in_its_own_cache(cache, tmp_path):
    """zig's local cache is a scratch folder: the cross objects are kept once, in the size-limited cache."""
    if shutil.which("zig") is None:
        pytest.importorskip("ziglang", reason="cross builds need the ziglang package")
    from fmu.build.cross_compile import compile_object, target_flags

    src = tmp_path / "src"
    src.mkdir()
    (src / "a.c").write_text("double a(double x) { return 2.0 * x; }\n")
    obj, _, cached = compile_object(src, "a.c", target_flags("aarch64-linux"))
    assert obj.is_file() and not cached
    zig_dir = cache / "zig"
    assert not [p for p in zig_dir.rglob("*") if p.is_file() and p.suffix in (".o", ".obj")]
