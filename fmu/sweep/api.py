"""The Python API of sweeps: `sweep(fmu_or_scene, grid_or_samples, outputs, client=None) -> DataFrame`.

One row per run, indexed by the run number: the swept values (columns named as the FMU's
variables, `method` as its enumeration value), the figures (fmu.sweep.figures: the final
state, those asked for, the invariant drifts), `ok` and `error` (the FMU's message for a
run it refused), and the run's timings on its worker (`loop_s`, `run_s`, s). The
table's `attrs` record the scene, the FMU's SHA-256, the experiment, the fixed values and
the seed of random samples, and `wall_s`: the time (s) from the workers being ready to the
last row (building the FMU and starting a cluster excluded), with `workers`, their threads.
"""

from __future__ import annotations

import secrets
import time
from collections import Counter
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from modelsrc import unit_mistakes
from modelsrc.errors import ModelInputError
from modelsrc.scene import Scene, list_scenes, load_scene

from ..build.build_fmu import archive_build_key, build_key, ensure_fmu
from ..drive.arguments import bool_arg, names_arg, path_arg, scene_arg
from ..drive.inputs import check_input_hold, input_mode
from ..drive.logged_warnings import warn_counts
from ..drive.run import experiment
from .engine import (
    MAX_CHUNK,
    SweepInterrupted,
    check_workers,
    chunk_size_for,
    cluster_client,
    run_here,
    run_on_cluster,
    split,
    worker_threads,
)
from .figures import SUMMARY_COLUMNS, figures_for, outputs_to_read
from .spec import (
    Variables,
    check_fixed,
    check_runs,
    fmi3_model_description,
    grid,
    model_description,
    parse_sample,
    samples,
)
from .worker import STATUS_COLUMNS, TIMING_COLUMNS, WARNINGS, Job, archive_key


def scene_of_fmu(fmu_path: Path) -> Scene:
    """The shipped scene an rbfmu archive was built from (its recorded build key matches),
    else a ModelInputError asking for the scene. An archive that is no FMU, or not FMI 3.0
    (which sweeps take), is refused as such first."""
    fmi3_model_description(fmu_path)
    key = archive_build_key(fmu_path)
    for name in list_scenes():
        sc = load_scene(name)
        if key is not None and key == build_key(sc):
            return sc
    raise ModelInputError(
        f"{fmu_path}: not built from a shipped scene by this rbfmu, so its scene is unknown; sweep the scene "
        "itself (its .toml file) instead of the .fmu, or in Python give it as sweep(..., scene=...)"
    )


def check_scene_of_fmu(fmu_path: Path, sc: Scene) -> None:
    """ModelInputError unless the archive was built from a scene of `sc`'s name (its
    modelName, which the build takes from the scene): the scene gives the sweep its
    experiment, input tables and the table's label, so another scene's would run the
    archive's body with them and label the table wrongly."""
    built_from = model_description(fmu_path).modelName
    if built_from != sc.name:
        raise ModelInputError(
            f"{fmu_path} was built from scene {built_from!r}, not from the given scene {sc.name!r}; "
            f"pass scene={built_from!r} (or the .toml it was built from)"
        )


def resolve(
    fmu_or_scene: Scene | str | Path, scene: Scene | str | Path | None, build_dir: str | Path | None
) -> tuple[Path, Scene]:
    """(FMU archive, scene): a scene (object, shipped name, .toml path) is built into
    `build_dir` (None: "build") if needed (content-keyed cache); an .fmu path is used as it
    is, and a build_dir given with it refused (nothing is built, it would be ignored)."""
    if isinstance(fmu_or_scene, (str, Path)) and str(fmu_or_scene).endswith(".fmu"):
        if build_dir is not None:
            raise ModelInputError(f"build_dir {str(build_dir)!r}: an .fmu archive is swept as it is, nothing is "
                                  "built; leave build_dir out")  # fmt: skip
        path = path_arg(fmu_or_scene, "fmu_or_scene")
        if not path.is_file():
            raise ModelInputError(f"FMU {path} does not exist")
        if scene is None:
            return path, scene_of_fmu(path)
        fmi3_model_description(path)
        sc = scene_arg(scene)
        check_scene_of_fmu(path, sc)
        return path, sc
    sc = scene_arg(fmu_or_scene, "fmu_or_scene")
    return ensure_fmu(sc, path_arg("build" if build_dir is None else build_dir, "build_dir")), sc


def warn_unit_mistakes(runs: pd.DataFrame) -> None:
    """Warn (ModelInputWarning, modelsrc.unit_mistakes) for a swept column whose values are
    almost surely in the wrong unit, as `rbfmu run --set` warns for one value: its largest
    |value| checked once per column (the checks flag values too large: degrees for radians,
    a period for a rate)."""
    for name in runs.columns:
        values = pd.to_numeric(runs[name], errors="coerce").to_numpy(dtype=float)
        values = values[np.isfinite(values)]
        if len(values):
            largest = float(values[np.argmax(np.abs(values))])
            unit_mistakes.start_value(f"--param/--sample {name} (its largest value)", str(name), largest)


def sample_runs(distributions: Mapping[str, tuple[str, float, float]], n: int, seed: int | None = None) -> pd.DataFrame:
    """n random runs: {name: (kind, a, b)} with kind uniform (LOW, HIGH), normal (MEAN,
    STD) or loguniform (LOW, HIGH); `attrs["seed"]` is the seed used (drawn if None)."""
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, (int, np.integer))):
        raise ModelInputError(f"seed must be a whole number or None, got {seed!r}")
    seed = secrets.randbits(32) if seed is None else int(seed)
    if not isinstance(distributions, Mapping):
        raise ModelInputError(
            f"distributions must be a mapping name -> (kind, a, b), got {type(distributions).__name__}"
        )
    dists = []
    for name, spec in distributions.items():
        numbers = isinstance(spec, (tuple, list)) and len(spec) == 3
        if not (numbers and all(isinstance(x, (int, float, np.number)) and not isinstance(x, bool) for x in spec[1:])):
            raise ModelInputError(
                f"distributions[{name!r}] must be (kind, a, b) with kind uniform, normal or loguniform and numbers "
                f"a, b, got {spec!r}"
            )
        kind, a, b = spec
        dists.append(parse_sample(f"{name}={kind}({float(a)!r}, {float(b)!r})"))
    runs = samples(dists, n, seed)
    runs.attrs["seed"] = seed
    return runs


def sweep(
    fmu_or_scene: Scene | str | Path,
    grid_or_samples: pd.DataFrame | Mapping[str, Sequence[float | str]],
    outputs: Sequence[str] = (),
    client: Any = None,
    *,
    scene: Scene | str | Path | None = None,
    fixed: Mapping[str, float | str] | None = None,
    stop_time: float | None = None,
    step: float | None = None,
    workers: int | None = None,
    chunk_size: int | None = None,
    build_dir: str | Path | None = None,
    progress: bool = False,
    inputs: str = "continuous",
    dashboard: str | None = None,
) -> pd.DataFrame:
    """Run the FMU once per row of `grid_or_samples` and return one row of results per run.

    fmu_or_scene: a Scene, a shipped scene name, a .toml scene file (built into
    `build_dir`, default "build", if needed) or an .fmu archive (with `scene=` unless it
    is a shipped scene's; a build_dir given with it is refused). grid_or_samples: a
    DataFrame with one row per run and one column per variable (start values,
    parameters, inputs held constant, `method` by name or value), or a mapping name ->
    values taken as a grid (Cartesian product).
    outputs: figures, e.g. "max(euler_zxz[2])", "cross(w_body[2], 0)", "E_kin" (its
    final value). client: a dask.distributed Client to run on; without one, a
    LocalCluster of `workers` processes (None: one per core) is started for this sweep,
    and `workers` = 0 runs everything in this process instead (at most
    fmu.sweep.engine.max_workers(): 4 per core); the LocalCluster listens on 127.0.0.1
    only, its dashboard at `dashboard` (HOST:PORT, default 127.0.0.1 on a free port).
    fixed: values set for every run.
    stop_time, step: s (default: the scene's experiment). chunk_size: runs per task
    (default: fmu.sweep.engine.chunk_size_for). inputs: "continuous" (the scene's
    harmonic inputs given to the FMU inside each step, FMI 3.0 intermediate update) or
    "hold" (each input held over a step at its mean there), as fmu.drive.run.run_fmu.
    The FMU's warnings during the runs come back with their rows from the workers and are
    raised here as FmuWarnings, each distinct message once with the number of runs that
    logged it (`warn_runs`; `rbfmu sweep` prints them as `rbfmu: warning: ...` lines).
    """
    check_workers(workers)
    if client is not None and not hasattr(client, "submit"):
        raise ModelInputError(f"client must be a dask.distributed.Client or None, got {type(client).__name__}")
    if dashboard is not None and not isinstance(dashboard, str):
        raise ModelInputError(f"dashboard must be HOST:PORT (a str) or None, got {dashboard!r}")
    if fixed is not None and not isinstance(fixed, Mapping):
        raise ModelInputError(f"fixed must be a mapping variable name -> value, got {type(fixed).__name__}")
    outputs, progress = names_arg(outputs, "outputs") or [], bool_arg(progress, "progress")
    _check_table(grid_or_samples)
    if dashboard is not None and (client is not None or workers == 0):
        raise ModelInputError(
            "dashboard: sets the dashboard of the LocalCluster this call starts; there is none "
            "with a client given or workers = 0"
        )
    fmu_path, sc = resolve(fmu_or_scene, scene, build_dir)
    T, H = experiment(sc, stop_time, step)
    variables = Variables.of(fmu_path)
    table = grid_or_samples if isinstance(grid_or_samples, pd.DataFrame) else grid(grid_or_samples)
    runs = check_runs(table, variables)
    columns = tuple(str(c) for c in runs.columns)
    warn_unit_mistakes(runs)
    fixed_values = check_fixed(dict(fixed or {}), variables, columns)
    sc.refuse_derived_inputs(columns, "--param/--sample (a swept variable)")  # the driver would replace them
    sc.refuse_derived_inputs(fixed_values, "--set (a fixed value)")
    if input_mode(inputs) == "hold":  # refused where it would change nothing: every input constant in every run
        check_input_hold(sc, {**fixed_values, **dict.fromkeys(columns, 0.0)})
    figures = figures_for(list(outputs), variables)
    fmu_bytes = fmu_path.read_bytes()
    job = Job(
        fmu_key=archive_key(fmu_bytes),
        scene=sc,
        stop_time=T,
        step=H,
        fixed=fixed_values,
        columns=columns,
        inputs=frozenset(c for c in columns if c in variables.inputs),
        figures=figures,
        read=outputs_to_read(figures, variables),
        input_mode=input_mode(inputs),
    )
    numbered = [(i, tuple(float(x) for x in row)) for i, row in enumerate(runs.itertuples(index=False))]
    if chunk_size is not None and (isinstance(chunk_size, bool) or int(chunk_size) != chunk_size or chunk_size < 1):
        raise ModelInputError(f"chunk size must be a whole number >= 1, got {chunk_size}")
    tic = time.perf_counter()
    try:
        if client is None and workers == 0:
            chunks = split(numbered, int(chunk_size or MAX_CHUNK))
            rows = run_here(fmu_bytes, job, chunks, progress)
            timing = {"wall_s": time.perf_counter() - tic, "workers": 0}
        elif client is None:
            with cluster_client(None, workers, dashboard) as local:
                rows, timing = _on(local, fmu_bytes, job, numbered, chunk_size, progress)
        else:
            rows, timing = _on(client, fmu_bytes, job, numbered, chunk_size, progress)
    except SweepInterrupted as stop:  # the completed runs' table goes with the interrupt
        warn_runs(stop.rows, fmu_path.name)
        stop.table = _table(stop.rows, job, table, sc, fmu_path)
        stop.table.attrs.update(wall_s=time.perf_counter() - tic, interrupted=True, planned_runs=len(numbered))
        raise
    warn_runs(rows, fmu_path.name)
    df = _table(rows, job, table, sc, fmu_path)
    df.attrs.update(timing)
    return df


def warn_runs(rows: list[dict[str, Any]], source: str) -> None:
    """Raise the FMU's warnings that the runs' rows brought back from the workers (each
    row's WARNINGS, removed from it) as a run's are raised (fmu.drive.logged_warnings): one
    FmuWarning per distinct message, in the order of the runs, with the number of runs that
    logged it; they point at the caller of `sweep`."""
    runs: Counter[str] = Counter()
    for row in sorted(rows, key=lambda r: r["run"]):
        runs.update(list(dict.fromkeys(row.pop(WARNINGS, ()))))  # each message once per run
    warn_counts(source, runs, lambda n: f" (in {n} of the sweep's {len(rows)} runs)", stacklevel=4)


def _check_table(grid_or_samples: object) -> None:
    """ModelInputError unless a DataFrame or a mapping name -> a list of values."""
    if isinstance(grid_or_samples, pd.DataFrame):
        return
    ok = isinstance(grid_or_samples, Mapping) and all(
        isinstance(v, (Sequence, np.ndarray)) and not isinstance(v, (str, bytes)) for v in grid_or_samples.values()
    )
    if not ok:
        raise ModelInputError(
            "grid_or_samples must be a DataFrame (one row per run) or a mapping variable name -> a list of values "
            f"(a grid), got {grid_or_samples!r:.80}"
        )


def _on(
    client: Any, fmu_bytes: bytes, job: Job, numbered: list, chunk_size: int | None, progress: bool
) -> tuple[list, dict[str, float]]:
    """Rows of the runs on the cluster, and the wall time (s) from the cluster being
    ready to the last row, with its number of worker threads."""
    threads = worker_threads(client)
    size = chunk_size or chunk_size_for(len(numbered), threads)
    tic = time.perf_counter()
    rows = run_on_cluster(client, fmu_bytes, job, split(numbered, int(size)), progress)
    return rows, {"wall_s": time.perf_counter() - tic, "workers": threads}


def _table(rows: list[dict[str, Any]], job: Job, source: pd.DataFrame, sc: Scene, fmu_path: Path) -> pd.DataFrame:
    figure_columns = [f.column for f in job.figures] + list(SUMMARY_COLUMNS)
    order = ["run", *job.columns, *figure_columns, *STATUS_COLUMNS, *TIMING_COLUMNS]
    df = pd.DataFrame(rows, columns=order).sort_values("run").set_index("run")
    df["ok"] = df["ok"].astype(bool)
    df["error"] = df["error"].fillna("").astype(str)
    df[figure_columns] = df[figure_columns].astype(float)
    df.attrs.update(
        scene=sc.name,
        fmu=str(fmu_path),
        fmu_sha256=job.fmu_key,
        stop_time=job.stop_time,
        step=job.step,
        fixed=dict(job.fixed),
        swept=list(job.columns),
        figures=figure_columns,
    )
    if "seed" in source.attrs:
        df.attrs["seed"] = source.attrs["seed"]
    if "log_axes" in source.attrs:
        df.attrs["log_axes"] = list(source.attrs["log_axes"])
    assert len(df) == len(set(df.index)), "a run came back twice"
    df.index = df.index.astype(np.int64)
    return df
