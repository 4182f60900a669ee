"""The `rbfmu` command: list, build, run scenes; the demo; the benchmark."""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from modelsrc.errors import ModelInputError
from modelsrc.scene import list_scenes, load_scene

from .build_fmu import BuildError, build_fmu, ensure_fmu
from .run import FmuError, run_fmu
from .summary import format_table, plot_run, summarize, write_csv


def _parse_set(items: list[str]) -> dict[str, float]:
    values = {}
    for item in items:
        name, sep, val = item.partition("=")
        if not sep or not name:
            raise ModelInputError(f"--set {item!r}: expected NAME=VALUE, e.g. --set 'w_body[3]=200'")
        try:
            v = float(val)
        except ValueError:
            from modelsrc.methods import METHODS

            if name.strip() == "method" and val.strip() in METHODS:  # --set method=gauss4
                values["method"] = float(METHODS[val.strip()].value)
                continue
            raise ModelInputError(f"--set {item!r}: value {val!r} is not a number") from None
        if not math.isfinite(v):
            raise ModelInputError(f"--set {item!r}: value must be finite, got {v}")
        values[name.strip()] = v
    return values


def cmd_scenes(args) -> int:
    for name in list_scenes():
        sc = load_scene(name)
        feats = ", ".join(sorted(sc.features)) or "torque-free"
        print(f"{name:<16} [{feats}] {sc.description}")
    return 0


def cmd_build(args) -> int:
    print(build_fmu(args.scene, Path(args.out), fmi_version=args.fmi_version))
    return 0


def cmd_run(args) -> int:
    sc = load_scene(args.scene)
    fmu = ensure_fmu(sc, Path(args.out))
    res = run_fmu(fmu, sc, stop_time=args.stop_time, step=args.step, start_values=_parse_set(args.set))
    if args.csv:
        write_csv(res, args.csv)
    if args.plot:
        plot_run(res, args.plot)
    print(format_table([(sc.name, summarize(res))]))
    return 0


def cmd_demo(args) -> int:
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for name in list_scenes():
        sc = load_scene(name)
        fmu = build_fmu(sc, Path(args.build_dir))
        res = run_fmu(fmu, sc)
        write_csv(res, out / f"{name}.csv")
        plot_run(res, out / f"{name}.png")
        rows.append((name, summarize(res)))
    table = format_table(rows)
    print(table)
    note = (
        "E and |L| drift: max relative deviation over the run; n/a where the physics does not "
        "conserve them. Wall time: the fmpy co-simulation loop only."
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
    ]
    report += [f"## {name}\n\n![{name}]({name}.png)\n" for name, _ in rows]
    (out / "report.md").write_text("\n".join(report))
    print(f"\n{note}\nFMUs in {args.build_dir}/; report, CSV and plots in {out}/ (out/report.md)")
    return 0


def cmd_check(args) -> int:
    from rbcheck.cross_check import main as check_main

    return check_main(args.rest)


def cmd_report(args) -> int:
    from rbcheck.report import main as report_main

    return report_main(args.rest)


def cmd_bench(args) -> int:
    from .benchmark import main as bench_main

    return bench_main(args.out)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="rbfmu", description="Rigid-body rotation co-simulation FMUs")
    sub = ap.add_subparsers(dest="cmd", required=True)
    sub.add_parser("scenes", help="list the scenes").set_defaults(fn=cmd_scenes)
    b = sub.add_parser("build", help="build SCENE.fmu")
    b.add_argument("scene")
    b.add_argument("--out", default="build")
    b.add_argument(
        "--fmi-version",
        choices=["2", "3"],
        default="3",
        help="FMI 3.0 (SCENE.fmu) or 2.0 (SCENE_fmi2.fmu); both carry CS and ME",
    )
    b.set_defaults(fn=cmd_build)
    r = sub.add_parser("run", help="build if needed and co-simulate a scene through fmpy")
    r.add_argument("scene")
    r.add_argument("--stop-time", type=float)
    r.add_argument("--step", type=float, help="communication step (s)")
    r.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="start value or parameter, e.g. --set 'w_body[3]=200' --set h_max=1e-4",
    )
    r.add_argument("--csv")
    r.add_argument("--plot")
    r.add_argument("--out", default="build", help="where FMUs are built")
    r.set_defaults(fn=cmd_run)
    d = sub.add_parser("demo", help="build every scene, run it, print one summary table")
    d.add_argument("--out", default="out")
    d.add_argument("--build-dir", default="build")
    d.set_defaults(fn=cmd_demo)
    sub.add_parser(
        "report",
        help="work-precision report -> docs/report/ (options: --quick, --out DIR, "
        "--scenes NAME..., --skip PART; see rbfmu report --help)",
    )
    sub.add_parser(
        "check",
        help="FMU vs Exudyn vs closed forms for every scene (tables); options: --quick, --scene NAME, --fmu-dir DIR",
    )
    be = sub.add_parser("bench", help="benchmark: ns per internal step in C, us per doStep via fmpy")
    be.add_argument("--out", default="build/bench")
    be.set_defaults(fn=cmd_bench)
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv[:1] == ["check"]:  # its options belong to rbcheck.cross_check's own parser
        args = argparse.Namespace(fn=cmd_check, rest=argv[1:])
    elif argv[:1] == ["report"]:  # likewise rbcheck.report's
        args = argparse.Namespace(fn=cmd_report, rest=argv[1:])
    else:
        args = ap.parse_args(argv)
    try:
        return args.fn(args)
    except (ModelInputError, FmuError, BuildError) as exc:
        print(f"rbfmu: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
