"""The `rbfmu linearize` and `rbfmu trim` subcommands: their options, the checks before any work, printout and files.

`add_subcommands(sub)` adds both to the `rbfmu` parser (fmu/cli.py calls it). Every
argument is checked before the FMU is built or anything is computed (names, numbers, the
--out path), and a refused one writes nothing (docs/user_guide.md §6).
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path


def _common(p: argparse.ArgumentParser) -> None:
    p.add_argument("scene", help="a shipped scene name or a path to a .toml scene file")
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="start value, parameter or input at the operating point, e.g. --set 'w_body[1]=0'",
    )
    p.add_argument("--at", type=float, metavar="T",
                   help="take the operating point from a run of the scene to T seconds (states there, inputs of "
                        "the schedules at T) instead of the start values")  # fmt: skip
    p.add_argument("--outputs", help="comma-separated outputs (a vector's base name for all of it; default: all)")
    p.add_argument("--inputs", help="comma-separated inputs (default: all)")
    p.add_argument("--raw", action="store_true", help="the FMU's own states (q[1..4]) instead of attitude-error ones")
    p.add_argument("--frame", choices=("rotating", "fixed"),
                   help="attitude reference of the attitude-error coordinates: rotating with the point's body rate "
                        "(default; a steady spin or a body at rest in an orbit frame is then an equilibrium) or fixed; "
                        "not with --raw or --step-map")  # fmt: skip
    p.add_argument("--out", help="write FILE.npz and FILE.json (A, B, C, D, names, operating point, modes)")
    p.add_argument("--build-dir", default="build", help="where FMUs are built and cached (default: build)")


def add_subcommands(sub) -> None:
    """Add `linearize` and `trim` to the subparsers of the rbfmu parser."""
    lin = sub.add_parser("linearize", help="A, B, C, D at an operating point from the FMU's directional derivatives",
                         description="Linear model of a scene's FMU (docs/user_guide.md §6)")  # fmt: skip
    _common(lin)
    lin.add_argument("--step-map", type=float, metavar="H",
                     help="instead: the discrete map of one communication step of H seconds (Phi, Gamma)")  # fmt: skip
    lin.add_argument("--method", help="integrator of the step map (default: the scene's)")
    lin.add_argument("--substeps", type=int, help="internal steps of the step map (default: the FMU's fixed-step rule)")
    lin.set_defaults(fn=run_linearize)
    tr = sub.add_parser("trim", help="inputs (and states) that zero chosen derivatives: Newton on exact derivatives",
                        description="Trim a scene's FMU (docs/user_guide.md §6)")  # fmt: skip
    _common(tr)
    tr.add_argument(
        "--unknown",
        action="append",
        default=[],
        metavar="NAME",
        help="an input, a state (not q) or 'attitude'; a vector's base name for all of it; repeatable",
    )
    tr.add_argument(
        "--equation",
        action="append",
        default=[],
        metavar="EQ",
        help="der(STATE) (= 0), OUTPUT (= 0) or OUTPUT=VALUE; repeatable",
    )
    tr.set_defaults(fn=run_trim)


def _names(text: str | None, option: str) -> list[str] | None:
    """The comma-separated names of `option` (None: not given); ModelInputError for an empty
    list, which would give a model of none where the default is all."""
    if text is None:
        return None
    names = [n.strip() for n in text.split(",") if n.strip()]
    if not names:
        from modelsrc.errors import ModelInputError

        raise ModelInputError(f"{option} {text!r}: no name given; leave {option} out for all of them")
    return names


# the FMU's settings of its integration: a linearisation or trim at start values evaluates the
# derivatives at a point and integrates nothing, so they would have no effect there
INTEGRATION_SETTINGS = ("method", "tolerance", "h_max", "work_limit")


def _refuse_unused_settings(args: argparse.Namespace, values: dict[str, float]) -> None:
    """ModelInputError for a --set of the integration (INTEGRATION_SETTINGS) that would have
    no effect: without --at (no run to the point) and, for linearize, without --step-map; with
    --step-map, a method also given by --method, an h_max where --substeps fixes the steps, and a
    tolerance or work_limit (the step map takes fixed steps, docs/theory.md §10.3)."""
    from modelsrc.errors import ModelInputError

    if args.at is not None:
        return  # they set the run to the point
    for name in (n for n in INTEGRATION_SETTINGS if n in values):
        if getattr(args, "step_map", None) is None:
            also = ", with --step-map H the step map" if hasattr(args, "step_map") else ""
            raise ModelInputError(f"--set {name}: a setting of the FMU's integration; the derivatives at a point "
                                  f"integrate nothing, so it would have no effect (with --at T it sets the run to the "
                                  f"point{also})")  # fmt: skip
        if name == "method" and args.method is not None:
            raise ModelInputError("--set method and --method: the step map's method given twice; give --method")
        if name == "h_max" and args.substeps is not None:
            raise ModelInputError("--set h_max: --substeps fixes the step map's internal steps; give one of them")
        if name in ("tolerance", "work_limit"):
            raise ModelInputError(f"--set {name}: the step map takes fixed internal steps (docs/theory.md §10.3), "
                                  "so it would have no effect; choose them with --substeps or --set h_max")  # fmt: skip


def _checked(args: argparse.Namespace):
    """The scene, the --set values and the --out path, checked before any work."""
    from modelsrc.errors import ModelInputError
    from modelsrc.scene import load_scene

    from ..drive.options import parse_set
    from .files import check_output
    from .linearize import frame_of

    scene = load_scene(args.scene)
    values = parse_set(args.set)
    _refuse_unused_settings(args, values)
    _names(args.inputs, "--inputs"), _names(args.outputs, "--outputs")  # an empty list refused before any work
    if getattr(args, "method", None) == "":
        raise ModelInputError("--method '': give a method name (default: the scene's)")
    if args.frame is not None and args.raw:  # before any work: trim would run first
        frame_of("raw", args.frame)  # refuses it, with the reason
    if args.at is not None and not (math.isfinite(args.at) and args.at > 0):
        raise ModelInputError(f"--at: the time must be a finite number > 0 (s), got {args.at}")
    if args.out is not None:
        check_output(args.out)
    return scene, values


def _point(args, scene, values, held=()):
    """The FMU and the operating point: the start values with `values`, or a run to --at;
    an input given in `values` or named in `held` (a trim's unknowns) is held as a run holds
    an input given by --set, so a held rotor speed's derivative is 0 there
    (operating_point.held_start_values)."""
    from ..build.build_fmu import ensure_fmu
    from .operating_point import held_start_values, run_point, start_point

    fmu = ensure_fmu(scene, Path(args.build_dir))
    if args.at is None:
        point = start_point(fmu, held_start_values(scene, values, held))
    else:
        point = run_point(fmu, scene, args.at, values, held)
    return fmu, point


def _show(model, scene_name: str, out: str | None) -> None:
    import numpy as np

    from .eigen import table
    from .files import write

    drift = float(np.max(np.abs(model.drift))) if len(model.drift) else 0.0
    if model.dt:
        kind = f"discrete map over {model.dt:g} s ({model.method}, {model.substeps} internal steps)"
    else:
        kind = f"continuous, drift max|rate at the point| = {drift:.3g}" + (" (an equilibrium)" if drift == 0 else "")
    print(f"{scene_name}: {len(model.states)} states, {len(model.inputs)} inputs, {len(model.outputs)} outputs; "
          f"{model.coordinates}{f' ({model.frame} frame)' if model.frame else ''}; {kind}; point: "
          f"{model.point.source}")  # fmt: skip
    print("states: " + ", ".join(model.states))
    print(table(model))
    if out:
        npz, js = write(model, out, scene_name)
        print(f"written: {npz}, {js}")


def run_linearize(args: argparse.Namespace) -> int:
    """`rbfmu linearize`."""
    from modelsrc.errors import ModelInputError

    scene, values = _checked(args)
    coords = "raw" if args.raw else "attitude"
    if args.step_map is None and (args.method or args.substeps is not None):
        raise ModelInputError("--method and --substeps choose the step map's integration: give --step-map H too")
    if args.step_map is not None:
        from .step_map import step_map

        if not (math.isfinite(args.step_map) and args.step_map > 0):
            raise ModelInputError(f"--step-map: H must be a finite number > 0 (s), got {args.step_map}")
        if args.outputs or args.inputs:
            raise ModelInputError("the step map's outputs are its states and its inputs all the FMU's: leave out "
                                  "--outputs and --inputs")  # fmt: skip
        if args.frame is not None:
            raise ModelInputError(f"--frame {args.frame}: the step map takes its attitude errors about the attitude at "
                                  "the start of the step and about the one at its end (its frame 'step'), no other "
                                  "reference: leave out --frame")  # fmt: skip
        if args.substeps is not None and args.substeps < 1:
            raise ModelInputError(f"--substeps: a whole number >= 1, got {args.substeps}")
        _, point = _point(args, scene, values)
        model = step_map(scene, point, args.step_map, method=args.method, substeps=args.substeps, coordinates=coords)
    else:
        from .linearize import linearize

        fmu, point = _point(args, scene, values)
        model = linearize(
            fmu, point, _names(args.inputs, "--inputs"), _names(args.outputs, "--outputs"), coords, args.frame
        )
    _show(model, scene.name, args.out)
    return 0


def run_trim(args: argparse.Namespace) -> int:
    """`rbfmu trim`."""
    from ..drive.logged_warnings import warn_logged
    from .linearize import linearize
    from .model_exchange import ModelExchange
    from .trim import trim

    scene, values = _checked(args)
    fmu, point = _point(args, scene, values, held=args.unknown)
    with ModelExchange(fmu, point.parameters) as me:
        warn_logged(me)  # its initialisation's; trim and linearize raise those of their own calls
        res = trim(fmu, point, args.unknown, args.equation, instance=me)
        print(res.report())
        sets = " ".join(f"--set '{n}={v!r}'" for n, v in {**res.point.states, **res.point.inputs}.items()
                        if n in res.unknowns or (n.startswith("q[") and "attitude[1]" in res.unknowns))  # fmt: skip
        print(f"the point: {sets}")
        model = linearize(fmu, res.point, _names(args.inputs, "--inputs"), _names(args.outputs, "--outputs"),
                          "raw" if args.raw else "attitude", args.frame, instance=me)  # fmt: skip
    _show(model, scene.name, args.out)
    return 0
