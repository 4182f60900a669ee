"""The `rbfmu systems` and `rbfmu system build|run` subcommands: list, build an .ssp archive, run one in a master.

`add_subcommands(sub)` adds them to the `rbfmu` parser (fmu/cli.py calls it). Bad input is
refused as one line naming the value (ModelInputError; fmu/cli.py prints it and exits 2):
every check of a system runs before its archive is written (fmu.system.checks), and a
missing or damaged archive is refused before a master is started (fmu.system.archive).
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

from modelsrc.errors import ModelInputError

from .masters import MASTERS


def add_subcommands(sub) -> None:
    """Add `systems` and `system {build,run}` to the subparsers of the rbfmu parser."""
    sub.add_parser("systems", help="list the shipped systems (fmu/system/systems/)").set_defaults(fn=run_list)
    s = sub.add_parser("system", help="systems of FMUs as SSP 1.0 archives, run by ECOS or libcosim",
                       description="Systems of FMUs (docs/user_guide.md, Systems)")  # fmt: skip
    ssub = s.add_subparsers(dest="system_cmd", required=True, metavar="ACTION")
    b = ssub.add_parser("build", help="build the components' FMUs and write NAME.ssp")
    b.add_argument("system", help="a shipped system name or a path to a system .toml file")
    b.add_argument("--out", default="build", help="where NAME.ssp goes (default: build)")
    b.add_argument("--build-dir", default="build", help="where the components' FMUs are built and cached")
    b.set_defaults(fn=run_build)
    r = ssub.add_parser("run", help="run an .ssp archive in a co-simulation master, write CSV and a plot")
    r.add_argument("archive", help="an .ssp archive written by `rbfmu system build`")
    r.add_argument("--master", choices=MASTERS, default="ecos", help="the co-simulation master (default: ecos)")
    r.add_argument("--stop-time", type=float, help="s, a whole number of communication steps (default: the SSD's)")
    r.add_argument("--out", default="out", help="directory of NAME_MASTER.csv and NAME_MASTER.png (default: out)")
    r.set_defaults(fn=run_run)


def run_list(args: argparse.Namespace) -> int:
    from .system_file import list_systems, read_system

    for name in list_systems():
        print(f"{name:<16} {read_system(name).description}")
    return 0


def _out_dir(path: str, option: str) -> Path:
    """The directory `option` names, checked before anything is run or written: not empty
    (that would be the current directory), not a file, and creatable: its nearest existing
    ancestor is a directory this process may write in. Nothing is created here."""
    if not path.strip():
        raise ModelInputError(f"{option} {path!r}: give a directory name (it is created if missing)")
    p = Path(path)
    if p.exists() and not p.is_dir():
        raise ModelInputError(f"{option} {path}: is a file; give a directory (it is created if missing)")
    if p.is_dir():
        if not os.access(p, os.W_OK | os.X_OK):
            raise ModelInputError(f"{option} {path}: the directory is not writable")
        return p
    ancestor = p.absolute().parent
    while not ancestor.exists():
        ancestor = ancestor.parent
    if not ancestor.is_dir():
        raise ModelInputError(f"{option} {path}: {ancestor} is a file, so the directory cannot be created")
    if not os.access(ancestor, os.W_OK | os.X_OK):
        raise ModelInputError(f"{option} {path}: cannot be created, {ancestor} is not writable")
    return p


def _make_dir(p: Path, option: str) -> None:
    try:
        p.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ModelInputError(f"{option} {p}: cannot create the directory ({exc.strerror})") from None


def run_build(args: argparse.Namespace) -> int:
    from .build import build_system

    print(build_system(args.system, _out_dir(args.out, "--out"), _out_dir(args.build_dir, "--build-dir")))
    return 0


def run_run(args: argparse.Namespace) -> int:
    from .archive import open_archive
    from .masters import run_system
    from .results import plot_result, write_result_csv

    archive = open_archive(args.archive)
    out = _out_dir(args.out, "--out")
    result = run_system(archive, args.master, args.stop_time)
    _make_dir(out, "--out")
    stem = out / f"{archive.name}_{args.master}"
    write_result_csv(result, stem.with_suffix(".csv"))
    plot_result(result, stem.with_suffix(".png"), archive.sources or None)
    print(f"{archive.name}: {len(result.t) - 1} steps of {archive.step} s in {args.master} to t = {result.t[-1]:.6g} s")
    print(f"results: {stem}.csv, {stem}.png")
    return 0
