"""Entry point of the work-precision report: its options, and one run that measures every part and writes report.md.

`add_arguments` and `run` let another command (``rbfmu report``) put these options on
its own parser; `main` is the standalone command (``python -m rbcheck.workprecision``).
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from fmu.bench.benchmark import c_step_ns_all
from fmu.build.build_fmu import build_all
from fmu.drive.options import positive_int
from fmu.terminal.progress import progress_bar
from modelsrc.errors import ModelInputError
from modelsrc.scene import list_scenes, load_scene

from .batch import SceneResult, batch_scene, batch_units, count_batch_units
from .config import DEFAULT_OUT, DEFAULT_SCENES, PARTS, QUICK_SAME, SHORT_PARTS, SHORT_RUNGS, Config
from .cosim import CosimResult, cosim, count_cosim_units
from .cosim_ecos import count_ecos_units, ecos_cosim
from .forced_inputs import measure_inputs
from .harness import advance, map_scenes, show
from .long_horizon import LongRun, long_horizon
from .markdown import write_markdown
from .measurable import has_scipy_reference, measurable_scenes
from .plots import plot_cosim, plot_long, plot_scene
from .tolerance import count_tolerance_units, tolerance_scenes
from .tolerance_report import TolerancePart, tolerance_part

if TYPE_CHECKING:
    from tqdm import tqdm

Bench = dict[str, dict[str, tuple[float, float]]]  # scene -> method -> (raw ns, fmi3DoStep ns) per internal step


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the report's options to `parser`: --out, --scenes, --short, --quick, --skip,
    --parts, --jobs, --build-dir."""
    parser.add_argument(
        "--out",
        default=str(DEFAULT_OUT),
        help=f"output folder, relative to the current directory (default {DEFAULT_OUT}; "
        "`make report-docs` writes docs/report)",
    )
    parser.add_argument(
        "--scenes",
        nargs="+",
        default=None,
        help=f"scenes (shipped names or scene files) of the batch part (default {' '.join(DEFAULT_SCENES)}) and of "
        "the error-control part "
        "(default: every shipped scene with a scipy reference)",
    )
    length = parser.add_mutually_exclusive_group()
    length.add_argument(
        "--short",
        action="store_true",
        help=f"the short report of `make demo`: {SHORT_RUNGS} rungs per ladder, the {', '.join(SHORT_PARTS)} part "
        "only, labelled as such (`make report` writes the full one)",
    )
    length.add_argument(
        "--quick",
        action="store_true",
        help="tiny ladders (smoke test), not a real report: no C step cost (bench) part, the error-control part on "
        "the scenes it can measure; the inputs part as without it",
    )
    parser.add_argument("--skip", nargs="*", default=[], choices=list(PARTS), help="parts to leave out")
    parser.add_argument("--parts", nargs="+", default=None, choices=list(PARTS), help="only these parts")
    parser.add_argument(
        "--jobs",
        default=str(os.cpu_count() or 1),
        help="scenes measured at once in the batch and error-control parts, one per process (default: the number "
        "of CPUs); 1 times every run alone",
    )
    parser.add_argument(
        "--build-dir",
        default=None,
        help="build the FMUs of every part (the inputs part's too) into this directory, reusing the ones there "
        "built from the same sources (`make demo` passes its own build/); default: a temporary directory",
    )


def main(argv: Sequence[str] | None = None) -> int:
    """The standalone command: parse `argv` (default sys.argv[1:]) and `run`; 2 on bad
    arguments (argparse's message on stderr)."""
    parser = argparse.ArgumentParser(
        prog="rbfmu report",
        description="Work-precision report: error against run time of the FMU's integrators, Exudyn and scipy "
        "(report.md and PNG diagrams).",
    )
    add_arguments(parser)
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:
        return int(exc.code or 0)
    return run(args)


def run(args: argparse.Namespace) -> int:
    """Regenerate the report from parsed options (see `add_arguments`); returns 0 on
    success, 2 on bad input (message on stderr). Progress bar on stderr, total time on
    stdout."""
    t_start = time.perf_counter()
    try:
        jobs = positive_int(str(getattr(args, "jobs", 1)), "--jobs")
    except ModelInputError as exc:
        print(f"rbfmu report: {exc}", file=sys.stderr)
        return 2
    scenes = tuple(args.scenes) if args.scenes else DEFAULT_SCENES
    known = list_scenes()
    bad = [s for s in scenes if s not in known and not Path(s).is_file()]
    if bad:
        what = "no such scene file" if bad[0].endswith(".toml") else "unknown scene"
        print(f"rbfmu report: {what} {bad[0]!r}; known scenes: {', '.join(known)} (or a scene file)", file=sys.stderr)
        return 2
    try:  # a scene file is measured under its own name: two scenes of one name would share an FMU and a section
        named = [load_scene(s).name for s in scenes]
    except ModelInputError as exc:
        print(f"rbfmu report: {exc}", file=sys.stderr)
        return 2
    twice = sorted({n for n in named if named.count(n) > 1})
    if twice:
        print(
            f"rbfmu report: two of the scenes are named {twice[0]!r}; give each scene a name of its own",
            file=sys.stderr,
        )
        return 2
    if args.quick:
        cfg = Config.quick(scenes)
    elif getattr(args, "short", False):
        cfg = Config.short(scenes)
    else:
        cfg = replace(Config(), scenes=scenes, tol_scenes=tuple(args.scenes) if args.scenes else None)
    parts = getattr(args, "parts", None) or (SHORT_PARTS if cfg.short_rungs else None)
    skip = set(args.skip) | (set(PARTS) - set(parts) if parts else set())
    refused = _refused_combination(args, cfg, skip)
    if refused:
        print(f"rbfmu report: {refused}", file=sys.stderr)
        return 2
    skip |= set(nothing_to_measure(cfg))  # not asked for by name (else refused above): left out
    out = Path(args.out)
    if not str(args.out).strip() or (out.exists() and not out.is_dir()):
        why = "an empty path" if not str(args.out).strip() else "is a file"
        print(f"rbfmu report: --out {args.out!r}: {why}; give a directory (it is created if missing)", file=sys.stderr)
        return 2
    out.mkdir(parents=True, exist_ok=True)
    timings: dict[str, float] = {"load0": os.getloadavg()[0], "jobs": jobs}

    import rbcheck.exudyn.models  # noqa: F401 - load Exudyn once, before the forked children

    need = needed_scenes(cfg, skip)
    methods = {s: load_scene(s).methods for s in need}
    bar = progress_bar(count_units(cfg, skip, methods), desc="rbfmu report")
    build_dir = Path(args.build_dir) if getattr(args, "build_dir", None) else None
    try:
        with tempfile.TemporaryDirectory(prefix="rbfmu_report_") as tmp:
            results, bench, cos, longs, tol = measure(cfg, skip, need, Path(tmp), out, bar, timings, build_dir, jobs)
    except ModelInputError as exc:
        bar.close()
        print(f"rbfmu report: {exc}", file=sys.stderr)
        return 2
    bar.close()
    try:
        forced = None if "inputs" in skip else measure_inputs(timings, build_dir=build_dir)
    except ModelInputError as exc:
        print(f"rbfmu report: {exc}", file=sys.stderr)
        return 2
    timings["total"] = time.perf_counter() - t_start
    write_markdown(out / "report.md", cfg, results, bench, cos, longs, timings, forced=forced, tolerance=tol)
    kind = (
        f"short report ({cfg.short_rungs} rungs per ladder)"
        if cfg.short_rungs
        else "quick report (smoke test)"
        if cfg.quick_report
        else "report"
    )
    print(
        f"{kind} written to {out / 'report.md'} in {timings['total']:.0f} s "
        f"(parts: {', '.join(f'{k} {v:.0f} s' for k, v in timings.items() if k not in ('total', 'load0', 'jobs'))})"
    )
    return 0


def nothing_to_measure(cfg: Config) -> dict[str, str]:
    """The parts that would measure nothing under `cfg`, each with the reason."""
    kind = "quick report" if cfg.quick_report else "short report" if cfg.short_rungs else "report"
    empty = {}
    if not cfg.bench_scenes:
        empty["bench"] = f"the {kind} has no C bench scenes (it measures no C step cost)"
    if not tolerance_scenes(cfg) and not cfg.spin_rates:
        empty["tolerance"] = (
            f"the {kind} has no scene the error-control part can measure (a scipy reference that turns) "
            "and no fast spin"
        )
    return empty


def _refused_combination(args: argparse.Namespace, cfg: Config, skip: set[str]) -> str:
    """Why the options cannot all take effect together ('' when they can): a setting that
    would be silently ignored is refused instead, and so is a part asked for (--parts, or
    the only ones --skip leaves) that would measure nothing (`nothing_to_measure`)."""
    if not set(PARTS) - skip:
        return "--parts/--skip leave no part to run; allowed parts: " + ", ".join(PARTS)
    if args.scenes and {"batch", "tolerance"} <= skip:
        return (
            "--scenes chooses the scenes of the batch and error-control parts, and neither is run (--parts/--skip): "
            "leave --scenes out or run one of them"
        )
    if args.scenes and "tolerance" not in skip:
        bad = [s for s in args.scenes if not has_scipy_reference(load_scene(s))]
        if bad:
            return (
                f"scene {bad[0]!r} has no scipy reference for the error-control part (tolerance): leave it out of "
                "--scenes or skip that part; with one: " + ", ".join(measurable_scenes(list_scenes()))
            )
    empty = nothing_to_measure(cfg)
    left = set(PARTS) - skip
    measuring = left - set(empty)
    asked = [p for p in PARTS if p in left and p in empty and (getattr(args, "parts", None) or not measuring)]
    if asked:
        length = " with --quick" if cfg.quick_report else " with --short" if cfg.short_rungs else ""
        others = [p for p in PARTS if p not in empty]
        return (
            f"the {asked[0]} part{length} would measure nothing: {empty[asked[0]]}; "
            + ("leave out --quick for it, or " if cfg.quick_report else "")
            + "ask for parts that measure: "
            + ", ".join(others)
        )
    if cfg.quick_report and measuring <= set(QUICK_SAME):
        return (
            f"--quick does not change the {', '.join(sorted(measuring))} part (it has no quick form: its runs take "
            "seconds as they are): leave out --quick, or add a part it shortens: "
            + ", ".join(p for p in PARTS if p not in QUICK_SAME and p not in empty)
        )
    if cfg.short_rungs and set(PARTS) - skip != set(SHORT_PARTS):
        return (
            f"--short is the {', '.join(SHORT_PARTS)} part only (the short report of `make demo`); "
            f"other parts asked for: {', '.join(sorted(set(PARTS) - skip - set(SHORT_PARTS)))} "
            "(leave out --short for them)"
        )
    return ""


def needed_scenes(cfg: Config, skip: set[str]) -> set[str]:
    """The scenes whose FMU the parts not in `skip` use."""
    need = set(cfg.scenes if "batch" not in skip else ())
    if "cosim" not in skip:
        need.add(cfg.cosim_scene)
    if "long" not in skip:
        need.add(cfg.long_scene)
    if "bench" not in skip:
        need.update(cfg.bench_scenes)
    if "tolerance" not in skip:
        need.update(tolerance_scenes(cfg))
        if cfg.spin_rates:
            need.add(cfg.spin_scene)
    return need


def count_units(cfg: Config, skip: set[str], methods: dict[str, Sequence[str]]) -> int:
    """Progress units of the whole run: one per FMU built, plus each part's own units
    (methods: scene -> the methods compiled into its FMU)."""
    return (
        len(methods)
        + (count_batch_units(cfg, methods) if "batch" not in skip else 0)
        + (count_cosim_units(methods[cfg.cosim_scene]) + count_ecos_units() if "cosim" not in skip else 0)
        + (len(methods[cfg.long_scene]) if "long" not in skip else 0)
        + (len(cfg.bench_scenes) if "bench" not in skip else 0)
        + (count_tolerance_units(cfg, methods) if "tolerance" not in skip else 0)
    )


def measure(
    cfg: Config,
    skip: set[str],
    need: set[str],
    tmp: Path,
    out: Path,
    bar: tqdm[Any],
    timings: dict[str, float],
    build_dir: Path | None = None,
    jobs: int = 1,
) -> tuple[list[SceneResult], Bench, CosimResult | None, list[LongRun], TolerancePart | None]:
    """Build the FMUs into `tmp` (or into `build_dir`, reusing those built there from the
    same sources), then run the parts not in `skip` in order (C step cost, batch,
    co-simulation, long horizon, error control), writing their diagrams to `out` and each
    part's wall time (s) to `timings`; the batch and error-control parts measure `jobs`
    scenes at once (harness.map_scenes), the others one run at a time."""
    tic = time.perf_counter()
    # on every core at once (the builds are independent, and nothing is timed while they run:
    # every measured part below starts after the last build)
    fmus: dict[str, Path] = {}
    if need:  # none for the inputs part alone, which builds its own (forced_inputs.measure_inputs)
        show(bar, f"building {len(need)} FMUs")
        fmus = build_all(sorted(need), tmp if build_dir is None else build_dir, jobs=jobs)
        for name in sorted(need):
            advance(bar, f"built {name}")
        timings["build"] = time.perf_counter() - tic
    bench: Bench = {}
    if "bench" not in skip:
        tic = time.perf_counter()
        for name in cfg.bench_scenes:
            show(bar, f"C step cost {name}")
            bench[name] = c_step_ns_all(fmus[name], cfg.bench_n_explicit, cfg.bench_n_implicit)
            advance(bar, f"C step cost {name}")
        timings["C bench"] = time.perf_counter() - tic
    results: list[SceneResult] = []
    if "batch" not in skip:
        methods = {name: load_scene(name).methods for name in cfg.scenes}
        units = {name: batch_units(cfg, name, methods[name]) for name in cfg.scenes}
        for _, res, wall in map_scenes(batch_scene, cfg.scenes, fmus, cfg, bar, jobs, units.__getitem__):
            plot_scene(res, out / f"{res.label}.png")
            results.append(res)
            timings[f"batch {res.label}"] = wall
    cos = None
    if "cosim" not in skip:
        tic = time.perf_counter()
        # fmi3DoStep ns per internal step of each method, for the C estimate of the loop's compute
        per = bench.get(cfg.cosim_scene)
        if per is None:
            per = c_step_ns_all(fmus[cfg.cosim_scene], cfg.bench_n_explicit, cfg.bench_n_implicit)
        cos = cosim(fmus[cfg.cosim_scene], cfg, {m: v[1] for m, v in per.items()}, bar)
        cos.ecos = ecos_cosim(cfg, tmp if build_dir is None else build_dir, bar)
        plot_cosim(cos, out / "cosim.png")
        timings["co-simulation"] = time.perf_counter() - tic
    longs: list[LongRun] = []
    if "long" not in skip:
        tic = time.perf_counter()
        longs = long_horizon(fmus[cfg.long_scene], cfg, bar)
        plot_long(longs, out / "long_horizon.png")
        timings["long horizon"] = time.perf_counter() - tic
    tol = None
    if "tolerance" not in skip:
        tic = time.perf_counter()
        tol = tolerance_part(cfg, fmus, out, bar, jobs)
        timings["error control"] = time.perf_counter() - tic
    return results, bench, cos, longs, tol
