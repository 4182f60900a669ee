"""CPU time of a linearisation of every shipped scene, and its ratio to central differences through the same FMU.

`table()` builds each scene's FMU (host binary), opens one Model Exchange instance at the
scene's start point and times, on that instance and alternately (A B A B ...: one
disturbance of this shared machine hits both), two ways to the same linear model in
attitude-error coordinates: `linearize` (nz + nu calls of fmi3GetDirectionalDerivative,
seeded along the chart's directions ∂x/∂z and the inputs) and `differences_model` (central
differences along the same directions: 2 (nz + nu) evaluations of fmi3SetContinuousStates
or fmi3SetFloat64, fmi3GetContinuousStateDerivatives and fmi3GetFloat64). Both go through
the same ctypes calls with preallocated buffers and the same assembly, so that the ratio
compares the FMI calls. CPU time of the process (time.process_time), the median over the
repetitions; opening the instance (extracting the archive, loading the library,
initialising) is timed once and shown apart: it is paid once per FMU, not per
linearisation. `python -m fmu.linear.bench` and `rbfmu bench --linear` print it.
"""

from __future__ import annotations

import statistics
import time
from collections.abc import Sequence
from pathlib import Path

from modelsrc.scene import list_scenes, load_scene

from .finite_differences import differences_model
from .linearize import linearize
from .model_exchange import ModelExchange
from .operating_point import start_point

REPEATS = 15


def measure(fmu: Path, repeats: int = REPEATS) -> dict[str, float]:
    """CPU seconds (medians) of one linearisation and one central-difference Jacobian of
    the FMU at its start point, the instance's opening, and the sizes."""
    point = start_point(fmu)
    t0 = time.process_time()
    me = ModelExchange(fmu)
    opened = time.process_time() - t0
    with me:
        linearize(fmu, point, instance=me)  # warm-up: first calls resolve ctypes and fill caches
        differences_model(me, point)
        lin, fd = [], []
        for _ in range(repeats):
            t = time.process_time()
            linearize(fmu, point, instance=me)
            lin.append(time.process_time() - t)
            t = time.process_time()
            differences_model(me, point)
            fd.append(time.process_time() - t)
        return {
            "linearize": statistics.median(lin),
            "differences": statistics.median(fd),
            "open": opened,
            "nx": me.nx,
            "nu": len(me.inputs),
            "ny": len(me.outputs),
        }


def table(scenes: Sequence[str] | None = None, build_dir: str | Path = "build/bench") -> str:
    """The table of `measure` for every shipped scene (or `scenes`), as text."""
    from ..build.build_fmu import ensure_fmu

    rows = [
        f"{'scene':<22}{'nx':>4}{'nu':>4}{'ny':>4}{'linearize ms':>14}{'central FD ms':>15}{'ratio':>8}{'open ms':>9}"
    ]
    worst_t, worst_r = 0.0, 0.0
    for name in scenes or list_scenes():
        fmu = ensure_fmu(load_scene(name), Path(build_dir))
        m = measure(fmu)
        ratio = m["linearize"] / m["differences"]
        worst_t, worst_r = max(worst_t, m["linearize"]), max(worst_r, ratio)
        rows.append(
            f"{name:<22}{m['nx']:>4}{m['nu']:>4}{m['ny']:>4}{m['linearize'] * 1e3:>14.3f}"
            f"{m['differences'] * 1e3:>15.3f}{ratio:>8.3f}{m['open'] * 1e3:>9.1f}"
        )
    rows.append(
        f"CPU time of the process, median of {REPEATS} alternating repetitions on one open Model Exchange "
        f"instance at the scene's start point; worst linearisation {worst_t * 1e3:.2f} ms (target <= 20), worst "
        f"ratio to central differences {worst_r:.3f} (target <= 1/3). open: extracting, loading and initialising "
        "the instance, once per FMU."
    )
    return "\n".join(rows)


if __name__ == "__main__":
    print(table())
