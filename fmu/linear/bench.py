"""CPU time of a linearisation of every shipped scene, and its ratio to central differences through the same FMU.

`table()` builds each scene's FMU (host binary), opens one Model Exchange instance at the
scene's start point and times, on that instance and alternately (A B A B ...: one
disturbance of this shared machine hits both), two ways to the same linear model in
attitude-error coordinates: `linearize` (nz + nu calls of fmi3GetDirectionalDerivative,
seeded along the chart's directions ∂x/∂z and the inputs) and `differences_model` (central
differences along the same directions: 2 (nz + nu) evaluations of fmi3SetContinuousStates
or fmi3SetFloat64, fmi3GetContinuousStateDerivatives and fmi3GetFloat64). Both go through
the same untyped ctypes calls with their arguments and buffers made once per plan
(fmu.linear.linearize.Plan), the same code setting the point and the chart, and the same
assembly, so that the ratio compares the FMI calls plus a shared part: setting the point
(three FMI calls), the chart's blocks, three small matrix products and the LinearModel.
CPU time of the process (time.process_time), the median over the repetitions; opening the
instance (extracting the archive, loading the library, initialising) is timed once and
shown apart: it is paid once per FMU, not per linearisation. `python -m fmu.linear.bench`
and `rbfmu bench --linear` print it.
"""

from __future__ import annotations

import statistics
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from modelsrc.scene import list_scenes, load_scene

from .finite_differences import differences_model
from .linearize import at_plan_point, at_point, linearize, plan
from .model_exchange import ModelExchange
from .operating_point import start_point

REPEATS = 15  # samples, alternating between the ways timed
BATCH = 20  # calls per sample: a sample then lasts milliseconds, far above the clock's resolution


def _sample(fn) -> float:
    t = time.process_time()
    for _ in range(BATCH):
        fn()
    return (time.process_time() - t) / BATCH


def measure(fmu: Path, repeats: int = REPEATS) -> dict[str, float]:
    """CPU seconds per call (medians over `repeats` samples of BATCH calls, the four ways
    alternating) of one linearisation (`linearize`) and one central-difference model
    (`differences_model`) of the FMU at its start point in attitude-error coordinates, and
    of their FMI calls alone (ModelExchange.jacobian and .central_differences with the
    seeds, directions and steps made beforehand); the instance's opening; the sizes."""
    point = start_point(fmu)
    t0 = time.process_time()
    me = ModelExchange(fmu)
    opened = time.process_time() - t0
    with me:
        pl = plan(me, None, None, "attitude")
        x0, u0 = point.x, point.u
        at_plan_point(pl, x0, "rotating")
        at_point(me, point)
        directions = pl.directions
        nd, ni = directions.shape[1], len(pl.in_vrs)
        h = 1e-6 * np.concatenate((np.maximum(np.abs(directions.T @ x0), pl.scale), np.maximum(np.abs(u0), 1.0)))
        ways = {
            "linearize": lambda: linearize(fmu, point, instance=me),
            "differences": lambda: differences_model(me, point),
            "jacobian calls": pl.jacobian,
            "difference calls": lambda: pl.differences(x0, u0, directions, h),
        }
        for fn in ways.values():  # warm-up: first calls resolve ctypes and fill caches
            fn()
        samples: dict[str, list[float]] = {k: [] for k in ways}
        for _ in range(repeats):
            for k, fn in ways.items():
                samples[k].append(_sample(fn))
        return {
            **{k: statistics.median(v) for k, v in samples.items()},
            "open": opened,
            "nx": me.nx,
            "nz": nd,
            "nu": ni,
            "ny": len(me.outputs),
        }


def table(scenes: Sequence[str] | None = None, build_dir: str | Path = "build/bench") -> str:
    """The table of `measure` for every shipped scene (or `scenes`), as text."""
    from ..build.build_fmu import ensure_fmu

    rows = [
        f"{'scene':<22}{'nx':>4}{'nz':>4}{'nu':>4}{'ny':>4}{'linearize ms':>14}{'central FD ms':>15}{'ratio':>8}"
        f"{'FMI calls ms':>14}{'ratio':>8}{'open ms':>9}"
    ]
    worst_t, worst_r, worst_c = 0.0, 0.0, 0.0
    for name in scenes or list_scenes():
        fmu = ensure_fmu(load_scene(name), Path(build_dir))
        m = measure(fmu)
        ratio = m["linearize"] / m["differences"]
        calls = m["jacobian calls"] / m["difference calls"]
        worst_t, worst_r, worst_c = max(worst_t, m["linearize"]), max(worst_r, ratio), max(worst_c, calls)
        rows.append(
            f"{name:<22}{m['nx']:>4}{m['nz']:>4}{m['nu']:>4}{m['ny']:>4}{m['linearize'] * 1e3:>14.3f}"
            f"{m['differences'] * 1e3:>15.3f}{ratio:>8.3f}"
            f"{m['jacobian calls'] * 1e3:>7.3f}/{m['difference calls'] * 1e3:<6.3f}{calls:>8.3f}{m['open'] * 1e3:>9.1f}"
        )
    rows.append(
        f"CPU time of the process per call, median of {REPEATS} samples of {BATCH} calls alternating on one open "
        "Model Exchange instance at the scene's start point, in attitude-error coordinates (nz minimal states). "
        "linearize: nz + nu fmi3GetDirectionalDerivative; central FD: 2 (nz + nu) evaluations along the same "
        "directions through the same ctypes calls and assembly. FMI calls: those calls alone (directional "
        "derivatives / differences), without the shared work (setting the point, the chart, the assembly). "
        f"Worst linearisation {worst_t * 1e3:.3f} ms (target <= 20), worst ratio {worst_r:.3f} (target <= 1/3), "
        f"of the FMI calls alone {worst_c:.3f}. open: extracting, loading and initialising the instance, once per FMU."
    )
    return "\n".join(rows)


if __name__ == "__main__":
    print(table())
