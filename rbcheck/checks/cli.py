"""Entry point of ``rbfmu check``: options, FMU build per scene, the printed tables.

``add_arguments`` and ``run`` let the ``rbfmu`` command mount ``check`` as a
subcommand of its own parser; ``main`` is the stand-alone entry
(``python -m rbcheck.checks``).
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path

from fmu.build.build_fmu import BuildError, build_fmu, ensure_fmu
from fmu.drive.instance import FmuError
from modelsrc.errors import ModelInputError
from modelsrc.scene import Scene, list_scenes, load_scene
from modelsrc.scene_inputs import input_component, input_width

from .feature_table import check_outputs
from .registry import format_report, registered_scenes, scene_report

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
        "--set",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="hold an input component constant for the whole run in the FMU and the references, replacing the "
        "scene's schedule for it, e.g. --set 'a_pivot[3]=0'",
    )
    parser.add_argument(
        "--fmu-dir",
        type=Path,
        default=None,
        help="directory of built FMUs to reuse (rebuilt when the scene or sources changed); "
        "default: build fresh FMUs in a temporary directory",
    )


def scene_with_set_inputs(sc: Scene, items: Sequence[str]) -> Scene:
    """The scene with the `--set NAME=VALUE` input components held constant for the whole
    run (FMU and references alike); any other name is refused: each check sets its own
    start values and parameters."""
    from fmu.drive.options import parse_set

    values = parse_set(items)
    bad = [n for n in values if input_component(n, sc.input_names) is None]
    if bad:
        comps = ", ".join(b if input_width(b) == 1 else f"{b}[1..3]" for b in sc.input_names) or "none"
        raise ModelInputError(
            f"check --set {bad[0]}: only an input component can be set for the checks (scene {sc.name}'s inputs: "
            f"{comps}); start values and parameters are chosen by each check"
        )
    return sc.with_inputs_held(values)


def run(args: argparse.Namespace) -> int:
    """Build each scene's FMU, run its checks and print its table. Returns 0 when every scene
    passes, 1 when one fails (a row out of its tolerance, a check that could not run, or no
    check applied to it: ``SceneReport.failures``).

    args: ``scene`` (list of names/paths, or None for every shipped scene), ``quick``,
    ``fmu_dir`` (Path or None), as added by :func:`add_arguments`."""
    names = args.scene or list_scenes()
    t0 = time.perf_counter()
    failed: list[str] = []
    judged = compared = 0
    # every scene and its --set checked before the first check runs (minutes): a bad one
    # refused after the others had run would waste them
    scenes = [scene_with_set_inputs(load_scene(name), getattr(args, "set", []) or []) for name in names]
    with tempfile.TemporaryDirectory(prefix="rbcheck_") as tmp:
        for sc in scenes:
            extra = check_outputs(sc) if sc.name not in registered_scenes() else ()
            if extra:  # the feature checks read them; the scene's own outputs stay as they are
                sc = dataclasses.replace(sc, outputs=tuple(sc.outputs) + extra)
                print(f"{sc.name}: the checks add the outputs {', '.join(extra)} to the FMU they build")
            path = ensure_fmu(sc, args.fmu_dir) if args.fmu_dir is not None else build_fmu(sc, Path(tmp))
            rep = scene_report(sc, path, quick=args.quick)
            print(format_report(rep))
            print()
            sys.stdout.flush()
            if rep.failures():
                failed.append(sc.name)
            judged += rep.judged_rows
            compared += rep.exudyn_judged
    took = time.perf_counter() - t0
    if failed:
        print(f"cross-check FAILED for {len(failed)} of {len(names)} scene(s) ({', '.join(failed)}) in {took:.1f} s")
        return 1
    print(f"cross-check: no failures in {len(names)} scene(s) ({judged} row(s) and {compared} FMU-vs-Exudyn "
          f"comparison(s) judged) in {took:.1f} s")  # fmt: skip
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
