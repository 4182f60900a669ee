"""Entry point of `rbfmu sweep`: its options, the sweep, the table, the map and a one-paragraph summary.

Mounted in fmu.cli (MOUNTED): `add_arguments` fills the subparser, `run` runs it. Bad
input raises ModelInputError, which the CLI prints as one line `rbfmu: error: ...`.
"""

from __future__ import annotations

import argparse
import secrets
import sys
import time

import pandas as pd

from modelsrc.errors import ModelInputError
from modelsrc.scene import load_scene

from ..drive.inputs import check_input_hold
from ..drive.options import parse_set
from ..drive.output_paths import output_directory as _directory
from ..drive.output_paths import output_file as _output_file
from .api import sweep
from .engine import (
    DEFAULT_DASHBOARD,
    MAX_WORKERS_PER_CORE,
    SweepInterrupted,
    check_dashboard,
    check_workers,
    cluster_client,
    local_cores,
)
from .figures import STATE_BASES, SUMMARY_COLUMNS, parse_figure
from .results import TableFile, plot_map
from .spec import check_seed, parse_param, parse_sample, plan


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The options of `rbfmu sweep` (docs/user_guide.md §3.1)."""
    p.add_argument("scene", help="a shipped scene name, a .toml scene file, or an .fmu built from a shipped scene")
    p.add_argument(
        "--param",
        action="append",
        default=[],
        metavar="NAME=START:STOP:N",
        help="grid axis: N values from START to STOP (add :log for log spacing), or NAME=V1,V2,... "
        "(method=rk4,gauss4); several --param make the Cartesian product",
    )
    p.add_argument(
        "--sample",
        action="append",
        default=[],
        metavar="NAME=DIST(A,B)",
        help="random variable: uniform(LOW, HIGH), normal(MEAN, STD) or loguniform(LOW, HIGH)",
    )
    p.add_argument("--samples", type=int, help="number of random runs (with --sample; at every grid point)")
    p.add_argument("--seed", type=int, help="seed of the random runs (default: drawn and printed)")
    p.add_argument(
        "--set", action="append", default=[], metavar="NAME=VALUE", help="value for every run, e.g. --set method=gauss4"
    )
    p.add_argument(
        "--record",
        action="append",
        default=[],
        metavar="FIGURE",
        help="figure per run besides the final state and drifts: end(NAME), max(NAME), min(NAME), "
        "cross(NAME, LEVEL) (first time NAME reaches LEVEL, s) or NAME",
    )
    p.add_argument(
        "--input-hold",
        action="store_true",
        help="hold every input over a communication step at its mean there (as importers without intermediate "
        "update do) instead of giving the FMU the continuous input inside the step",
    )
    p.add_argument("--stop-time", type=float, help="s (default: the scene's)")
    p.add_argument("--step", type=float, help="communication step, s (default: the scene's)")
    p.add_argument("--scheduler", help="address of a running dask scheduler, e.g. tcp://host:8786")
    p.add_argument(
        "--workers",
        type=int,
        help="without --scheduler: LocalCluster worker processes (default: one per core, at most "
        f"{MAX_WORKERS_PER_CORE} per core); 0: run in this process",
    )
    p.add_argument(
        "--dashboard",
        metavar="HOST:PORT",
        help=f"address of the LocalCluster's dask dashboard (default: {DEFAULT_DASHBOARD}, this machine only, a free "
        "port); 0.0.0.0:PORT opens it to the network",
    )
    p.add_argument("--chunk-size", type=int, help="runs per dask task (default: about 8 tasks per worker)")
    p.add_argument("--out", default="sweep.parquet", help="the table, .parquet or .csv (default: sweep.parquet)")
    p.add_argument("--overwrite", action="store_true", help="replace the file --out if it exists (else refused)")
    p.add_argument("--plot", help="write the map of one figure to this PNG file")
    p.add_argument("--plot-figure", help="the column to map (default: the first --record)")
    p.add_argument("--plot-axes", help="X or X,Y: the swept variables of the map (default: the swept ones)")
    p.add_argument("--log-color", action="store_true", help="log colour scale for the map")
    p.add_argument(
        "--build-dir", help="where a scene's FMU is built and cached (default: build; not with an .fmu file)"
    )
    p.add_argument("--no-progress", action="store_true", help="no progress bar")


def runs_from_args(args: argparse.Namespace) -> pd.DataFrame:
    """The table of runs of --param, --sample, --samples and --seed (seed in attrs)."""
    axes = [parse_param(t) for t in args.param]
    dists = [parse_sample(t) for t in args.sample]
    if args.samples is not None and args.samples < 1:
        raise ModelInputError(f"--samples must be >= 1, got {args.samples}")
    if args.seed is not None:
        check_seed(args.seed, "--seed")
    seed = args.seed if args.seed is not None else (secrets.randbits(32) if dists else None)
    runs = plan(axes, dists, args.samples, seed)
    if dists:
        runs.attrs["seed"] = seed
    runs.attrs["log_axes"] = [a.name for a in axes if a.log] + [d.name for d in dists if d.kind == "loguniform"]
    return runs


def summary_text(df: pd.DataFrame, total: float, where: str) -> str:
    """What a user reads after the sweep: runs, rate, failures (the commonest message)."""
    n, failed, wall = len(df), int((~df["ok"]).sum()), df.attrs["wall_s"]
    lines = [
        f"{n} runs of {df.attrs['scene']} ({where}) in {wall:.2f} s: {n / wall:.1f} runs/s, {failed} failed "
        f"({total:.1f} s with building the FMU and starting workers)"
    ]
    if failed:
        top = df.loc[~df["ok"], "error"].value_counts()
        lines.append(f"most common failure ({top.iloc[0]} runs): {top.index[0]}")
    if "seed" in df.attrs:
        lines.append(f"random runs drawn with --seed {df.attrs['seed']} (give it to reproduce them)")
    return "\n".join(lines)


def plot_choice(args: argparse.Namespace, runs: pd.DataFrame) -> tuple[str, list[str]]:
    """(column to map, its axes) of --plot, checked before any run: a figure the sweep
    records and one or two swept variables."""
    recorded = [parse_figure(r).column for r in args.record]
    if args.plot_figure is None:
        color = recorded[0] if recorded else "qnorm_err"
    elif args.plot_figure in SUMMARY_COLUMNS:
        color = args.plot_figure
    else:
        fig = parse_figure(args.plot_figure)
        color = fig.column
        if color not in recorded and not (fig.kind == "end" and fig.name.split("[")[0] in STATE_BASES):
            raise ModelInputError(
                f"--plot-figure {args.plot_figure}: not recorded; give it as --record too, "
                f"or map one of {', '.join(recorded + list(SUMMARY_COLUMNS))}"
            )
    axes = [a.strip() for a in args.plot_axes.split(",")] if args.plot_axes is not None else list(runs.columns)
    if not 1 <= len(axes) <= 2 or any(a not in runs.columns for a in axes):
        raise ModelInputError(
            f"--plot: the map is over one or two swept variables (--plot-axes X[,Y]); swept: {', '.join(runs.columns)}"
        )
    return color, axes


# What each option that names something takes, for the refusal of an empty value.
NON_EMPTY = {
    "scheduler": "the address of a running dask scheduler (e.g. tcp://host:8786), or leave --scheduler out",
    "dashboard": "HOST:PORT, or leave --dashboard out",
    "out": "the table's file name (.parquet or .csv), or leave --out out (default: sweep.parquet)",
    "build_dir": "a directory, or leave --build-dir out (default: build)",
    "plot": "the map's file name (.png), or leave --plot out",
    "plot_figure": "a figure (e.g. E_kin, max(NAME)), or leave --plot-figure out",
    "plot_axes": "X or X,Y (swept variables), or leave --plot-axes out",
}


def refuse_empty(args: argparse.Namespace) -> None:
    """An option given as '' (or blanks) is refused, not taken as absent: '' would run locally
    (--scheduler), write no map (--plot), map the default axes (--plot-axes) or write into the
    current directory (--build-dir)."""
    for dest, allowed in NON_EMPTY.items():
        value = getattr(args, dest)
        if value is not None and not value.strip():
            raise ModelInputError(f"--{dest.replace('_', '-')} {value!r}: empty; give {allowed}")


def run(args: argparse.Namespace) -> int:
    """Run `rbfmu sweep`: check every option before any run, sweep, write, summarise."""
    refuse_empty(args)
    runs = runs_from_args(args)
    if args.plot is not None:
        if not args.plot.endswith(".png"):
            raise ModelInputError(f"--plot {args.plot}: the map is written as a .png file")
        _output_file(args.plot, "--plot")  # a writable file in a directory that exists, before any run
    # settings that would change nothing are refused, not ignored
    if args.seed is not None and not args.sample:
        raise ModelInputError(
            "--seed draws the random runs of --sample; there is none: give --sample or leave --seed out"
        )
    unplotted = [o for o, v in (("--plot-figure", args.plot_figure), ("--plot-axes", args.plot_axes),
                                ("--log-color", args.log_color)) if v]  # fmt: skip
    if unplotted and args.plot is None:
        raise ModelInputError(f"{unplotted[0]} sets the map of --plot FILE.png; give --plot or leave it out")
    check_workers(args.workers)
    if args.scheduler and args.workers is not None:
        raise ModelInputError("--workers starts a local cluster; with --scheduler the cluster's workers are used")
    if args.dashboard is not None:
        check_dashboard(args.dashboard)
        if args.scheduler or args.workers == 0:
            raise ModelInputError(
                "--dashboard sets the dashboard of the local cluster; there is none with "
                + ("--scheduler (the cluster's scheduler has its own)" if args.scheduler else "--workers 0")
            )
    if args.build_dir is not None:
        if str(args.scene).endswith(".fmu"):
            raise ModelInputError(
                f"--build-dir {args.build_dir}: an .fmu file is swept as it is, nothing is built; "
                "leave --build-dir out (it is where a scene given by name or .toml file is built)"
            )
        _directory(args.build_dir, "--build-dir")
    fixed = parse_set(args.set)
    if not str(args.scene).endswith(".fmu"):  # before the build (the API checks an .fmu's scene)
        sc = load_scene(args.scene)
        sc.refuse_derived_inputs([str(c) for c in runs.columns], "--param/--sample (a swept variable)")
        sc.refuse_derived_inputs(fixed, "--set (a fixed value)")
        if args.input_hold:
            check_input_hold(sc, {**fixed, **dict.fromkeys(runs.columns, 0.0)})
    color, axes = plot_choice(args, runs) if args.plot is not None else ("", [])
    table = TableFile.reserve(args.out, args.overwrite)  # last check: it creates the temporary file
    try:
        return _sweep_and_report(args, runs, fixed, color, axes, table)
    finally:
        table.discard()


def _interrupted(stop: SweepInterrupted, table: TableFile) -> int:
    """Ctrl-C: keep the completed runs' table (if any) and say so; exit status 130 (SIGINT)."""
    df = stop.table
    planned = df.attrs.get("planned_runs", "?") if df is not None else "?"
    if df is None or len(df) == 0:
        print(
            f"rbfmu: interrupted before any run completed; nothing was saved (no {table.path} written)", file=sys.stderr
        )
    else:
        out = table.write(df)
        print(f"rbfmu: interrupted: the {len(df)} completed runs of {planned} are saved in {out}", file=sys.stderr)
    return 130


def _sweep_and_report(
    args: argparse.Namespace, runs: pd.DataFrame, fixed: dict, color: str, axes: list[str], table: TableFile
) -> int:
    tic = time.perf_counter()
    kwargs = dict(
        fixed=fixed,
        stop_time=args.stop_time,
        step=args.step,
        chunk_size=args.chunk_size,
        build_dir=args.build_dir,
        progress=not args.no_progress,
        inputs="hold" if args.input_hold else "continuous",
    )
    try:
        if args.scheduler:
            with cluster_client(args.scheduler) as client:
                df = sweep(args.scene, runs, args.record, client, **kwargs)
            where = f"dask cluster at {args.scheduler}"
        else:
            df = sweep(args.scene, runs, args.record, workers=args.workers, dashboard=args.dashboard, **kwargs)
            n = local_cores() if args.workers is None else args.workers
            where = "in this process" if n == 0 else f"LocalCluster of {n} worker processes"
    except SweepInterrupted as stop:
        return _interrupted(stop, table)
    except KeyboardInterrupt:
        print("rbfmu: interrupted before any run completed; nothing was saved", file=sys.stderr)
        return 130
    wall = time.perf_counter() - tic
    out = table.write(df)
    print(summary_text(df, wall, where))
    print(f"table: {out}")
    if args.plot:
        path = plot_map(
            df,
            color,
            args.plot,
            x=axes[0],
            y=axes[1] if len(axes) > 1 else None,
            log_axes=runs.attrs["log_axes"],
            log_color=args.log_color,
        )
        print(f"map of {color}: {path}")
    return 0
