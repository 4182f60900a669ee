"""The `rbfmu` command: one argparse parser for all subcommands (scenes, build, run, demo, check, ..., linearize, trim).

`check`, `report` and `sweep` add their own options to their subparser (`add_arguments`
of rbcheck.checks.cli, rbcheck.workprecision.cli and fmu.sweep.cli) and run through
`run(args)`; their modules, which import Exudyn, scipy or dask, are loaded only when that
subcommand is chosen. Bad input of any subcommand ends in one line `rbfmu: error: ...`
and exit status 2; `run` checks its arguments (paths, plot format, --set values, the
number of communication steps) before it builds or allocates anything.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
import time
import warnings
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor
from contextlib import contextmanager, nullcontext
from pathlib import Path

import numpy as np

from modelsrc.controllers.controller_file import is_controller, list_controllers, load_controller
from modelsrc.errors import ModelInputError, ModelInputWarning
from modelsrc.scene import list_scenes, load_scene

from .build.build_fmu import (
    BuildError,
    BuildTask,
    ValidationRunWarning,
    build_fmu,
    ensure_fmu,
    output_dir,
    run_builds,
)
from .build.controller_build import build_controller
from .build.platforms import PLATFORMS
from .build.versions import VersionAction
from .drive.inputs import check_input_hold
from .drive.instance import FmuError, FmuWarning
from .drive.options import parse_set, positive_int
from .drive.output_paths import output_directory as _directory
from .drive.output_paths import output_file as _output_file
from .drive.run import RunResult, experiment, refuse_unused_tolerance, run_fmu
from .drive.summary import format_table, plot_run, summarize, write_csv
from .linear.cli import add_subcommands as add_linear_subcommands
from .system.build import component_builds
from .system.cli import add_subcommands as add_system_subcommands
from .system.demo import demo_system_names, demo_systems
from .system.system_file import read_system

# Subcommands whose options and code live in their own (heavier) modules.
MOUNTED = {
    "check": ("rbcheck.checks.cli", "FMU vs Exudyn vs closed forms, per scene (tables)"),
    "report": ("rbcheck.workprecision.cli", "work-precision report: error against run time of every method"),
    "sweep": ("fmu.sweep.cli", "grids and Monte Carlo runs of a scene's FMU, locally or on a dask cluster"),
}


class _Aliased(argparse.Action):
    """Stores an option that has two names (run's and bench's --build-dir, alias --out) and
    keeps every (name, value) given in `given_<dest>`, so that `_given_once` (in `main`,
    before any command runs) refuses the second: argparse would keep the last without a word."""

    def __call__(self, parser, namespace, values, option_string=None):
        setattr(namespace, self.dest, values)
        given = f"given_{self.dest}"
        setattr(namespace, given, [*getattr(namespace, given, []), (option_string, values)])


def _given_once(args: argparse.Namespace) -> None:
    """ModelInputError when an `_Aliased` option was given more than once."""
    for key, given in vars(args).items():
        if key.startswith("given_") and len(given) > 1:
            (a, x), (b, y) = given[:2]
            raise ModelInputError(f"{a} {x} and {b} {y}: one option under two names (given twice); give it once")


def plot_formats() -> list[str]:
    """File formats matplotlib writes (the suffixes --plot accepts)."""
    from matplotlib.backend_bases import FigureCanvasBase

    return sorted(FigureCanvasBase.get_supported_filetypes())


def cmd_scenes(args: argparse.Namespace) -> int:
    for name in list_scenes():
        sc = load_scene(name)
        feats = ", ".join(sorted(sc.features)) or "torque-free"
        print(f"{name:<16} [{feats}] {sc.description}")
    return 0


def cmd_controllers(args: argparse.Namespace) -> int:
    for name in list_controllers():
        c = load_controller(name)
        print(f"{name:<16} [plant {c.plant}, Ts = {c.sample_period:g} s] {c.description}")
    return 0


def cmd_build(args: argparse.Namespace) -> int:
    out = _directory(args.out, "--out")
    if is_controller(args.scene):  # a controller file (modelsrc/controllers/) builds like a scene
        print(build_controller(args.scene, out, fmi_version=args.fmi_version, platforms=args.platforms))
        return 0
    if not args.scene.endswith(".toml") and args.scene not in list_scenes():
        raise ModelInputError(
            f"unknown scene or controller {args.scene!r}; scenes: {', '.join(list_scenes())}; controllers: "
            f"{', '.join(list_controllers())} (or give a path to a .toml file)"
        )
    print(build_fmu(args.scene, out, fmi_version=args.fmi_version, platforms=args.platforms))
    return 0


def cmd_run(args: argparse.Namespace) -> int:
    sc = load_scene(args.scene)
    # every argument is checked before the FMU is built (seconds) and anything is allocated
    out = _directory(args.build_dir, "--build-dir")
    _output_file(args.csv, "--csv")
    _output_file(args.plot, "--plot", plot_formats() if args.plot else ())
    if args.csv and args.plot and Path(args.csv).resolve() == Path(args.plot).resolve():
        raise ModelInputError(f"--csv {args.csv} and --plot {args.plot}: one file for both; the plot would overwrite "
                              "the table: give two names")  # fmt: skip
    start_values = parse_set(args.set)
    sc.refuse_derived_inputs(start_values, "--set")
    experiment(sc, args.stop_time, args.step)
    if args.input_hold:
        check_input_hold(sc, start_values)
    refuse_unused_tolerance(sc, start_values)
    fmu = ensure_fmu(sc, out)
    inputs = "hold" if args.input_hold else "continuous"
    res = run_fmu(fmu, sc, stop_time=args.stop_time, step=args.step, start_values=start_values, inputs=inputs)
    if args.csv:
        write_csv(res, args.csv)
    if args.plot:
        plot_run(res, args.plot)
    print(format_table([(sc.name, summarize(res))]))
    return 0


def at_rest(res: RunResult) -> bool:
    """True when the attitude q and the body rate w_body (and a free body's x_cm) never changed over the run."""
    bases = [b for b in ("q", "w_body", "x_cm") if f"{b}[1]" in res.values]
    return bool(bases) and all(np.array_equal(v, np.broadcast_to(v[0], v.shape)) for v in map(res.vector, bases))


def _figure(value: float, unit: str) -> str:
    """A closed-loop figure as the demo prints it: 4 significant digits and its unit."""
    if not np.isfinite(value):
        return "not reached within the run"
    return f"{value:.4g} {unit}" if unit != "%" else f"{value:.3g} %"


def _demo_pool(jobs: int) -> ProcessPoolExecutor | nullcontext[None]:
    """The demo's worker processes (none for --jobs 1): they build every FMU, then draw the plots."""
    return ProcessPoolExecutor(max_workers=jobs) if jobs > 1 else nullcontext()


def cmd_demo(args: argparse.Namespace) -> int:
    _directory(args.build_dir, "--build-dir")
    jobs = positive_int(args.jobs, "--jobs")  # before output_dir creates --out
    out = output_dir(_directory(args.out, "--out"))
    rows, still = [], []
    took = {"build": 0.0, "run": 0.0, "plots and CSV": 0.0}  # wall time (s) of each part
    names = list_scenes()
    build_dir = Path(args.build_dir)
    with _demo_pool(jobs) as pool:
        # the scenes' FMUs and the systems' component FMUs in one queue: no core idles
        # while builds are left (the systems' builds used to run alone, after the scenes')
        tasks: list[BuildTask] = [(ensure_fmu, (name, build_dir)) for name in names]
        tasks += [task for system in demo_system_names() for task in component_builds(system, build_dir)]
        tic = time.perf_counter()
        fmus = dict(zip(names, run_builds(tasks, pool)))
        took["build"] = time.perf_counter() - tic
        plots = []
        for name in names:
            sc = load_scene(name)
            tac = time.perf_counter()
            res = run_fmu(fmus[name], sc)  # one run at a time here: its wall time is in the table
            toc = time.perf_counter()
            write_csv(res, out / f"{name}.csv")
            if pool is None:
                plot_run(res, out / f"{name}.png")
            else:  # drawn on the workers while the next scenes and the systems run
                plots.append(pool.submit(plot_run, res, out / f"{name}.png"))
            took["run"] += toc - tac
            took["plots and CSV"] += time.perf_counter() - toc
            rows.append((name, summarize(res)))
            if at_rest(res):
                still.append(name)
        table = format_table(rows)
        print(table)
        tic = time.perf_counter()
        systems, system_plots = demo_systems(build_dir, out, pool=pool)
        took["systems"] = time.perf_counter() - tic
        tic = time.perf_counter()
        for plot in plots + system_plots:
            plot.result()
        took["plots and CSV"] += time.perf_counter() - tic
    closed = {c.source: s.name for s in map(read_system, demo_system_names()) for c in s.components.values()}
    rest = (
        "At rest alone (no input schedule moves it): "
        + ", ".join(f"{n} (its loop is closed in the system {closed[n]} below)" if n in closed else n for n in still)
        + "."
        if still  # a row of zeros is what the scene does, not a failure: say why and where it moves
        else ""
    )
    if rest:
        print(f"\n{rest}")
    sys_lines = [
        f"{r.name} ({r.master}): " + ", ".join(f"{k} {_figure(v, u)}" for k, (v, u) in r.figures.items())
        for r in systems
    ]
    print("\nClosed loops (plant FMU + controller FMU in an SSP archive, stepped by the master):")
    print("\n".join(f"  {line}" for line in sys_lines))
    note = (
        "E and |L| drift: max relative deviation over the run of the conserved energy (E_kin, E_total, or in "
        "an orbit the Jacobi integral E_jacobi) and angular momentum (|L_world|, or in a central field the total "
        "L_total, orbit + spin); n/a where the physics does not conserve them. Wall time: the fmpy "
        "co-simulation loop only. Moving bodies: x_cm, v_cm at the "
        "end (m, m/s, world), the impulse received |p(T) - p(0)| and the momentum balance "
        "max |p - p0 - ∫M a_cm dt| (N·s; n/a where forces vary inside a step)."
    )
    report = [
        "# rbfmu demo",
        "",
        "Every scene built as an FMI 3.0 Co-Simulation FMU and run through fmpy with its default experiment.",
        "",
        "```",
        table,
        "```",
        "",
        note,
        "",
        *([rest, ""] if rest else []),
        "## Closed loops",
        "",
        "Each shipped system (`rbfmu systems`) built as an SSP archive and run in ECOS:",
        "",
        *[f"- {line}" for line in sys_lines],
        "",
        *[f"![{r.name}]({r.name}_{r.master}.png)\n" for r in systems],
    ]
    report += [f"## {name}\n\n![{name}]({name}.png)\n" for name, _ in rows]
    (out / "report.md").write_text("\n".join(report))
    print(f"\n{note}\n")
    print(
        f"FMUs: {args.build_dir}/SCENE.fmu (this machine's binary; `rbfmu build SCENE` adds the other platforms) "
        f"and the systems' components (FMI 2.0), {len(tasks)} in {took['build']:.0f} s with {jobs} parallel "
        "build(s) (a rebuild only where sources changed)"
    )
    print(f"runs: {len(rows)} scenes through fmpy, {took['run']:.0f} s")
    print(
        f"systems: {len(systems)} SSP archives written ({sum(r.build_s for r in systems):.0f} s) and run in ECOS "
        f"({sum(r.run_s for r in systems):.0f} s): {out}/SYSTEM_ecos.csv, {out}/SYSTEM_ecos.png"
    )
    print(
        f"summary, CSV and plots: {out}/report.md, {out}/SCENE.csv, {out}/SCENE.png, {took['plots and CSV']:.0f} s "
        f"(beyond the runs; the plots drawn by {jobs} process(es))"
    )
    return 0


def cmd_bench(args: argparse.Namespace) -> int:
    from .bench.steps import main as bench_main
    from .linear.bench import table as linear_table
    from .system.overhead import main as master_main

    out = str(_directory(args.build_dir, "--build-dir"))
    if args.master:
        return master_main(out)
    if not args.linear:
        status = bench_main(out)
        if status:
            return status
        status = master_main(out)
        if status:
            return status
        print()
    print("linearisation: linearize (directional derivatives) against central differences through the same FMU")
    print(linear_table(build_dir=out))
    return 0


def build_parser(argv: Sequence[str]) -> argparse.ArgumentParser:
    """The parser of every subcommand. A mounted subcommand's module is imported (and its
    options added) only when argv chooses it."""
    ap = argparse.ArgumentParser(prog="rbfmu", description="Rigid-body co-simulation FMUs")
    ap.add_argument("--version", action=VersionAction, help="print the versions of rbfmu and its build tools, exit")
    sub = ap.add_subparsers(dest="cmd", required=True, metavar="COMMAND")
    sub.add_parser("scenes", help="list the scenes").set_defaults(fn=cmd_scenes)
    sub.add_parser("controllers", help="list the controllers").set_defaults(fn=cmd_controllers)

    b = sub.add_parser("build", help="build SCENE.fmu (FMI 3.0) or SCENE_fmi2.fmu (a scene or a controller)")
    b.add_argument("scene", help="a shipped scene or controller name, or a path to a .toml scene or controller file")
    b.add_argument("--out", default="build", help="output directory (default: build)")
    b.add_argument(
        "--fmi-version",
        choices=["2", "3"],
        default="3",
        help="FMI 3.0 (SCENE.fmu) or 2.0 (SCENE_fmi2.fmu); both carry CS and ME",
    )
    b.add_argument(
        "--platforms",
        default="all",
        help=f"comma-separated binaries to build besides the host's, 'host' (only it) or 'all' (default): "
        f"{', '.join(PLATFORMS)} "
        "(FMI 2.0: linux64, win64, darwin64); cross builds use zig cc; compiled objects are cached in "
        "$RBFMU_CACHE_DIR (default: the user's cache directory), within $RBFMU_CACHE_MAX_MB megabytes "
        "(default 512)",
    )
    b.set_defaults(fn=cmd_build)

    r = sub.add_parser("run", help="build if needed and co-simulate a scene through fmpy")
    r.add_argument("scene", help="a shipped scene name or a path to a .toml scene file")
    r.add_argument("--stop-time", type=float, help="s (default: the scene's)")
    r.add_argument("--step", type=float, help="communication step, s (default: the scene's)")
    r.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="start value, parameter or input, e.g. --set 'w_body[3]=200' --set h_max=1e-4 --set method=gauss4; "
        "an input component (--set 'a_pivot[3]=0') is held at the value for the whole run, replacing the scene's "
        "schedule for it",
    )
    r.add_argument(
        "--input-hold",
        action="store_true",
        help="hold every input over a communication step at its mean there (as importers without intermediate "
        "update do) instead of giving the FMU the continuous input inside the step",
    )
    r.add_argument("--csv", help="write every output to this CSV file")
    r.add_argument("--plot", help="write a plot to this PNG file")
    r.add_argument("--build-dir", "--out", dest="build_dir", default="build", action=_Aliased,
                   help="where FMUs are built and cached (default: build; --out: its earlier name)")  # fmt: skip
    r.set_defaults(fn=cmd_run)

    d = sub.add_parser("demo", help="build every scene, run it, print one summary table, write out/")
    d.add_argument("--out", default="out", help="summary, CSV and plots (default: out)")
    d.add_argument("--build-dir", default="build", help="where FMUs are built and cached (default: build)")
    d.add_argument(
        "--jobs",
        default=str(os.cpu_count() or 1),
        help="FMUs built at once, one process each (default: the number of CPUs, %(default)s here)",
    )
    d.set_defaults(fn=cmd_demo)

    for name, (module, help_text) in MOUNTED.items():
        p = sub.add_parser(name, help=help_text, description=help_text)
        if list(argv[:1]) == [name]:
            mod = importlib.import_module(module)
            mod.add_arguments(p)
            p.set_defaults(fn=mod.run)

    be = sub.add_parser("bench", help="benchmark in C: the generated step against a hand-written kernel, doStep's cost")
    be.add_argument(
        "--build-dir",
        "--out",
        dest="build_dir",
        default="build/bench",
        action=_Aliased,
        help="where the benchmark's FMUs are built (default: build/bench; --out: its earlier name)",
    )
    only = be.add_mutually_exclusive_group()
    only.add_argument(
        "--linear",
        action="store_true",
        help="only the linearisation table: CPU ms of linearize and of central differences, their ratio",
    )
    only.add_argument(
        "--master",
        action="store_true",
        help="only the master's overhead: a closed-loop step of the shipped systems in ECOS and libcosim against "
        "the two FMUs' own doSteps (callgrind instructions; CPU time)",
    )
    be.set_defaults(fn=cmd_bench)
    add_linear_subcommands(sub)  # linearize, trim (fmu/linear/cli.py)
    add_system_subcommands(sub)  # systems, system build, system run (fmu/system/cli.py)
    return ap


# At most this many lines of the FMU's warnings per command (a sweep's runs may each warn), then one line saying so.
MAX_FMU_WARNING_LINES = 20
LINE_WARNINGS = (ModelInputWarning, ValidationRunWarning, FmuWarning)


@contextmanager
def warnings_as_lines() -> Iterator[None]:
    """Print each ModelInputWarning (a value almost surely a unit mistake, modelsrc.unit_mistakes),
    ValidationRunWarning (the build's validation run failed) and FmuWarning (the FMU logged a
    warning during a run; at most MAX_FMU_WARNING_LINES) once, as one line `rbfmu: warning: ...`
    on stderr; other warnings as Python prints them."""
    shown: set[str] = set()
    fmu_lines = [0]
    with warnings.catch_warnings():
        for category in LINE_WARNINGS:
            warnings.simplefilter("always", category)  # deduplicated here, by text
        python_show = warnings.showwarning

        def show(message, category, filename, lineno, file=None, line=None):
            if not issubclass(category, LINE_WARNINGS):
                python_show(message, category, filename, lineno, file, line)
                return
            if str(message) in shown:
                return
            shown.add(str(message))
            if issubclass(category, FmuWarning):
                fmu_lines[0] += 1
                if fmu_lines[0] > MAX_FMU_WARNING_LINES:
                    if fmu_lines[0] == MAX_FMU_WARNING_LINES + 1:
                        print("rbfmu: warning: the FMU logged further warnings, not shown", file=sys.stderr)
                    return
            print(f"rbfmu: warning: {message}", file=sys.stderr)

        warnings.showwarning = show
        yield


def main(argv: Sequence[str] | None = None) -> int:
    """Parse argv (default sys.argv[1:]) and run the subcommand; 2 on bad input. Values that
    are almost surely unit mistakes, and the FMU's warnings during a run, are printed on stderr
    (`rbfmu: warning: ...`)."""
    args_list = list(sys.argv[1:] if argv is None else argv)
    args = build_parser(args_list).parse_args(args_list)
    fn: Callable[[argparse.Namespace], int] = args.fn
    try:
        _given_once(args)
        with warnings_as_lines():
            return fn(args)
    except (ModelInputError, FmuError, BuildError) as exc:
        print(f"rbfmu: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # the reader of stdout left (`rbfmu scenes | head`): stop without a word
        # stdout to /dev/null, or the interpreter's own flush at exit fails again on the closed pipe;
        # 141 = 128 + SIGPIPE, the status of a Unix tool stopped by the same
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 141
    except OSError as exc:  # the file system refused (permissions, disk full): its words, one line
        print(f"rbfmu: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:  # Ctrl-C: what was being made is cleaned up on the way out (build_fmu)
        print(f"rbfmu: interrupted ({args.cmd} did not finish)", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
