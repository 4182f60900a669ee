"""Benchmark of the FMU build: time with and without the cross-compiled binaries, first and cached, per scene.

For every scene (default: all shipped ones) and FMI version, builds the FMU three times
and prints one table:
- host only (gcc, its objects not yet in the cache: what a first `rbfmu run` does);
- every platform, first build in the cache directory as it stands (the first scene of a
  fresh cache directory also pays for zig's C runtimes: MinGW for Windows, glibc and
  libSystem stubs, compiler-rt);
- every platform again, with every object in the cache (only the links run).
Each archive's binaries are then read with lief (when installed): file format, machine
and export table (exactly the fmi3*/fmi2* functions of the standard's header; on Mach-O
also the linker's two header symbols), the same check as tests/platforms/test_platforms.py.

    .venv/bin/python tools/build_timing.py [--cache-dir DIR] [--scenes a,b] [--fmi-versions 3,2]

Without --cache-dir a fresh temporary directory is used, so the first row is a cold
build. Timings are wall times from one run on this machine (shared CPUs: compare ratios).
"""

from __future__ import annotations

import argparse
import os
import re
import sys
import tempfile
import time
import zipfile
from pathlib import Path

from fmu.build.build_fmu import build_fmu
from fmu.build.cross_compile import CACHE_ENV
from fmu.build.platforms import PLATFORMS, binary_folder, platforms_for
from modelsrc.scene import list_scenes

MACHO_LINKER_SYMBOLS = {"__mh_dylib_header", "___dso_handle"}


def check_binaries(fmu: Path, model_id: str, version: str) -> str:
    """'ok' when every platform's binary has the right format, machine and exports, else what is wrong."""
    try:
        import lief
    except ImportError:
        return "lief not installed"
    lief.logging.disable()
    with zipfile.ZipFile(fmu) as z:
        header = z.read(f"sources/fmi{version}Functions.h").decode()
        declared = set(re.findall(rf"^\s*FMI{version}_Export\s+\w+TYPE\s+(fmi{version}\w+);", header, re.M))
        problems = []
        for name in platforms_for(version):
            p = PLATFORMS[name]
            member = f"binaries/{binary_folder(name, version)}/{model_id}{p.suffix}"
            binary = lief.parse(list(z.read(member)))
            field = {"MACHO": "cpu_type", "PE": "machine", "ELF": "machine_type"}[p.binary_format]
            exported = {e.name.removeprefix(p.symbol_prefix) for e in binary.exported_functions}
            extra = {s[1:] for s in MACHO_LINKER_SYMBOLS} if p.binary_format == "MACHO" else set()
            if binary.format.name != p.binary_format or getattr(binary.header, field).name != p.machine:
                problems.append(f"{name}: wrong format/machine")
            elif exported != declared | extra:
                problems.append(f"{name}: exports differ")
    return (
        "ok (" + ", ".join(binary_folder(n, version) for n in platforms_for(version)) + ")"
        if not problems
        else ("; ".join(problems))
    )


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cache-dir", help="cross-compilation cache (default: a fresh temporary directory: cold)")
    ap.add_argument("--scenes", default=",".join(list_scenes()), help="comma-separated scenes (default: all)")
    ap.add_argument("--fmi-versions", default="3,2", help="comma-separated FMI versions (default: 3,2)")
    ap.add_argument("--out", default=None, help="where the FMUs go (default: a temporary directory)")
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="rbfmu_timing_") as tmp:
        os.environ[CACHE_ENV] = args.cache_dir or str(Path(tmp) / "cache")
        out = Path(args.out or Path(tmp) / "fmus")
        load = os.getloadavg()[0]
        print(f"cache: {os.environ[CACHE_ENV]} ({'given' if args.cache_dir else 'fresh, cold'}); "
              f"{os.cpu_count()} CPUs, load average {load:.2f} at start")  # fmt: skip
        head = f"{'scene':<16}{'FMI':>4}{'host only (s)':>15}{'all, first (s)':>16}{'all, cached (s)':>17}  binaries"
        print(head)
        print("-" * len(head))
        for scene in args.scenes.split(","):
            for version in args.fmi_versions.split(","):
                t0 = time.perf_counter()
                build_fmu(scene, out / "host", fmi_version=version)
                t1 = time.perf_counter()
                build_fmu(scene, out / "all", fmi_version=version, platforms="all")
                t2 = time.perf_counter()
                fmu = build_fmu(scene, out / "all", fmi_version=version, platforms="all")
                t3 = time.perf_counter()
                status = check_binaries(fmu, scene, version)
                print(f"{scene:<16}{version:>4}{t1 - t0:>15.1f}{t2 - t1:>16.1f}{t3 - t2:>17.1f}  {status}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
