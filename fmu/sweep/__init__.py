"""Sweeps and Monte Carlo runs of a scene's FMU, in this process or on a dask.distributed cluster.

`sweep(fmu_or_scene, grid_or_samples, outputs, client=None) -> DataFrame` (fmu.sweep.api)
runs the FMU once per row of a grid or of random samples and returns one row of figures
per run; `rbfmu sweep` (fmu.sweep.cli) is the command. The parts: spec (grids, samples,
what may be set), figures (what a run records), worker (one reused FMU instance per
worker process), engine (this process, a LocalCluster or any dask cluster; progress),
results (Parquet/CSV, stability maps), examples (the shipped maps of docs/sweeps/),
bench (throughput and scaling).
"""

from .api import sample_runs, sweep
from .spec import grid

__all__ = ["grid", "sample_runs", "sweep"]
