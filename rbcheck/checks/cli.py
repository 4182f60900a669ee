"""Entry point of ``rbfmu check``: options, FMU build per scene, the printed tables.

``add_arguments`` and ``run`` let the ``rbfmu`` command mount ``check`` as a
subcommand of its own parser; ``main`` is the stand-alone entry
(``python -m rbcheck.checks``).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path

from fmu.build_fmu import BuildError, build_fmu, ensure_fmu
from fmu.run import FmuError
from modelsrc.errors import ModelInputError
from modelsrc.scene import list_scenes, load_scene

from .registry import format_report, scene_report

__all__ = ["add_arguments", "main", "run"]

DESCRIPTION = "Print the cross-check tables (FMU vs Exudyn vs closed forms) of the scenes."


def _scene_argument(value: str) -> str:
    """Validate --scene (a shipped name or a .toml path) while parsing, so an unknown
    name or a bad file is a usage error naming the known scenes or the bad field."""
    try:
        load_scene(value)
    except ModelInputError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return value


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the options of ``rbfmu check`` to ``parser``."""
    parser.add_argument("--quick", action="store_true", help="shorter horizons, fewer spins (for tests)")
    parser.add_argument(
        "--scene",
        action="append",
        type=_scene_argument,
        metavar="NAME_OR_PATH",
        help="a shipped scene name or a path to a .toml scene file (repeatable; default: every shipped scene)",
    )
    parser.add_argument(
        "--fmu-dir",
        type=Path,
        default=None,
        help="directory of built FMUs to reuse (rebuilt when the scene or sources changed); "
        "default: build fresh FMUs in a temporary directory",
    )


def run(args: argparse.Namespace) -> int:
    """Build each scene's FMU, run its checks and print its table. Returns 0.

    args: ``scene`` (list of names/paths, or None for every shipped scene), ``quick``,
    ``fmu_dir`` (Path or None), as added by :func:`add_arguments`."""
    names = args.scene or list_scenes()
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="rbcheck_") as tmp:
        for name in names:
            sc = load_scene(name)
            path = ensure_fmu(sc, args.fmu_dir) if args.fmu_dir is not None else build_fmu(sc, Path(tmp))
            print(format_report(scene_report(sc, path, quick=args.quick)))
            print()
            sys.stdout.flush()
    print(f"cross-check done in {time.perf_counter() - t0:.1f} s")
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """Parse ``argv`` (default: sys.argv[1:]) and :func:`run`; 2 on a scene, FMU or build error."""
    ap = argparse.ArgumentParser(prog="rbfmu check", description=DESCRIPTION)
    add_arguments(ap)
    args = ap.parse_args(list(argv) if argv is not None else None)
    try:
        return run(args)
    except (ModelInputError, FmuError, BuildError) as exc:
        print(f"rbfmu check: error: {exc}", file=sys.stderr)
        return 2
