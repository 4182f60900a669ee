"""CPU time of a linearisation of every shipped scene, and its ratio to central differences through the same FMU.

`table()` builds each scene's FMU (host binary), opens one Model Exchange instance and times,
on that instance and interleaved (A B A B ...: one disturbance of this shared machine hits
both), two ways to the same linear model in attitude-error coordinates: `linearize` (nz + nu
calls of fmi3GetDirectionalDerivative, seeded along the chart's directions ∂x/∂z and the
inputs) and `differences_model` (central differences along the same directions: 2 (nz + nu)
evaluations of fmi3SetContinuousStates or fmi3SetFloat64, fmi3GetContinuousStateDerivatives
and fmi3GetFloat64). Both go through the same untyped ctypes calls with their arguments and
buffers made once per plan (fmu.linear.linearize.Plan), the same code setting the point and
the chart, and the same assembly, so that the ratio compares the FMI calls (each way's with
one fmi3GetContinuousStateDerivatives for ẋ₀) plus a shared part: setting the point (two
FMI calls), the chart's blocks, the matrix product and the LinearModel.

Consecutive calls alternate between two operating points, the scene's start point and a
moved one (`moved_point`): the FMU keeps its Jacobian while x, u, p and the method stay
(docs/fmi_layer.md, Directional and adjoint derivatives), so that a linearisation repeated
at one point would skip the Jacobian's evaluation, which a user linearising once per point
pays. The column "one point" times that repetition, to show what the alternation removes.
CPU time of the process (time.process_time_ns), per way the median over `repeats` samples of
BATCH calls, the ratio per round of interleaved samples, its median and range over ROUNDS
rounds; opening the instance (extracting the archive, loading the library, initialising) is
timed once and shown apart: it is paid once per FMU, not per linearisation.
`python -m fmu.linear.bench` and `rbfmu bench --linear` print it.
"""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np

from modelsrc.scene import list_scenes, load_scene

from .finite_differences import differences_model, steps
from .linearize import at_plan_point, at_point, linearize, plan
from .model_exchange import ModelExchange
from .operating_point import OperatingPoint, start_point

ROUNDS = 5  # rounds of interleaved samples: a ratio per round, reported as median and range
REPEATS = 9  # samples per way and round
BATCH = 20  # calls per sample (even: half at each point): a sample lasts milliseconds, far above the clock's resolution
MOVE = 1e-3  # the moved point: each state moved by MOVE · max(|x|, nominal) · cos(k) (k its index)


def moved_point(point: OperatingPoint, nominals: np.ndarray) -> OperatingPoint:
    """The point with every state moved by MOVE · max(|x_k|, nominal_k) · cos(k) (a spread
    of signs and sizes, every state changed), the quaternion q[1..4] normalised again; the
    inputs and parameters as they are."""
    x = point.x
    x = x + MOVE * np.maximum(np.abs(x), nominals) * np.cos(np.arange(len(x)))
    names = list(point.states)
    if "q[1]" in names:
        i = names.index("q[1]")
        x[i : i + 4] /= np.linalg.norm(x[i : i + 4])
    return point.with_values(states=dict(zip(names, map(float, x))), source=f"{point.source}, moved")


def _sample(fns: tuple[Callable[[], object], Callable[[], object]]) -> int:
    """CPU ns per call of BATCH calls alternating between the two functions (points)."""
    a, b = fns
    t = time.process_time_ns()
    for _ in range(BATCH // 2):
        a()
        b()
    return (time.process_time_ns() - t) // BATCH


def measure(fmu: Path, repeats: int = REPEATS, rounds: int = ROUNDS) -> dict[str, float]:
    """CPU seconds per call (medians over all samples of BATCH calls, the ways interleaved,
    consecutive calls at the start point and `moved_point` alternately) of one linearisation
    (`linearize`), one central-difference model (`differences_model`) in attitude-error
    coordinates, their FMI calls alone (the plan's directional derivatives and differences,
    each after setting the point's states), and a linearisation repeated at the start point
    alone ("one point", which the FMU's kept Jacobian serves); "ratio" and "calls ratio": the
    median over rounds of each round's ratio of medians, with their range ("ratio min",
    "ratio max", ...); the instance's opening; the sizes."""
    p0 = start_point(fmu)
    t0 = time.process_time_ns()
    me = ModelExchange(fmu)
    opened = (time.process_time_ns() - t0) * 1e-9
    with me:
        p1 = moved_point(p0, me.nominals)
        pl = plan(me, None, None, "attitude")
        directions = pl.directions
        nd, ni = directions.shape[1], len(pl.in_vrs)
        u0 = p0.u
        xs = (p0.x, p1.x)
        at_plan_point(pl, xs[0], "rotating")
        at_point(me, p0)
        h = steps(pl, xs[0], u0)

        def calls_at(x: np.ndarray, fn: Callable[[], object]) -> Callable[[], object]:
            def run() -> object:
                me.set_states(x)
                return fn()

            return run

        ways: dict[str, tuple[Callable[[], object], Callable[[], object]]] = {
            "linearize": (lambda: linearize(fmu, p0, instance=me), lambda: linearize(fmu, p1, instance=me)),
            "differences": (lambda: differences_model(me, p0), lambda: differences_model(me, p1)),
            "jacobian calls": (calls_at(xs[0], pl.jacobian), calls_at(xs[1], pl.jacobian)),
            "difference calls": (
                calls_at(xs[0], lambda: pl.differences(xs[0], u0, directions, h)),
                calls_at(xs[1], lambda: pl.differences(xs[1], u0, directions, h)),
            ),
            "one point": (lambda: linearize(fmu, p0, instance=me), lambda: linearize(fmu, p0, instance=me)),
        }
        for a, b in ways.values():  # warm-up: first calls resolve ctypes and fill caches
            a(), b()
        samples: dict[str, list[int]] = {k: [] for k in ways}
        ratios: dict[str, list[float]] = {"ratio": [], "calls ratio": []}
        for _ in range(rounds):
            now: dict[str, list[int]] = {k: [] for k in ways}
            for _ in range(repeats):
                for k, fns in ways.items():
                    now[k].append(_sample(fns))
            med = {k: statistics.median(v) for k, v in now.items()}
            ratios["ratio"].append(med["linearize"] / med["differences"])
            ratios["calls ratio"].append(med["jacobian calls"] / med["difference calls"])
            for k, v in now.items():
                samples[k] += v
        out: dict[str, float] = {k: statistics.median(v) * 1e-9 for k, v in samples.items()}
        for k, r in ratios.items():
            out |= {k: statistics.median(r), f"{k} min": min(r), f"{k} max": max(r)}
        return out | {"open": opened, "nx": me.nx, "nz": nd, "nu": ni, "ny": len(me.outputs)}


def table(scenes: Sequence[str] | None = None, build_dir: str | Path = "build/bench") -> str:
    """The table of `measure` for every shipped scene (or `scenes`), as text."""
    from ..build.build_fmu import ensure_fmu

    rows = [
        f"{'scene':<22}{'nx':>4}{'nz':>4}{'nu':>4}{'ny':>4}{'linearize µs':>13}{'central FD µs':>14}"
        f"{'ratio (range)':>21}{'FMI calls ratio (range)':>25}{'one point µs':>13}{'open ms':>9}"
    ]
    worst_t, worst_r, worst_c = 0.0, 0.0, 0.0
    for name in scenes or list_scenes():
        fmu = ensure_fmu(load_scene(name), Path(build_dir))
        m = measure(fmu)
        worst_t, worst_r = max(worst_t, m["linearize"]), max(worst_r, m["ratio"])
        worst_c = max(worst_c, m["calls ratio"])
        rows.append(
            f"{name:<22}{m['nx']:>4}{m['nz']:>4}{m['nu']:>4}{m['ny']:>4}{m['linearize'] * 1e6:>13.1f}"
            f"{m['differences'] * 1e6:>14.1f}{m['ratio']:>8.3f} ({m['ratio min']:.3f}..{m['ratio max']:.3f})"
            f"{m['calls ratio']:>12.3f} ({m['calls ratio min']:.3f}..{m['calls ratio max']:.3f})"
            f"{m['one point'] * 1e6:>13.1f}{m['open'] * 1e3:>9.1f}"
        )
    rows.append(
        f"CPU time of the process per call, median of {ROUNDS} x {REPEATS} samples of {BATCH} calls, the ways "
        "interleaved on one open Model Exchange instance, consecutive calls alternating between the scene's start "
        "point and a moved one (the FMU evaluates its Jacobian anew at each), in attitude-error coordinates (nz "
        "minimal states). linearize: nz + nu fmi3GetDirectionalDerivative; central FD: 2 (nz + nu) evaluations "
        "along the same directions through the same ctypes calls and assembly. ratio: linearize / central FD, the "
        f"median of {ROUNDS} rounds' ratios and their range. FMI calls: those calls alone (directional derivatives / "
        "differences after setting the states), without the rest of the shared work (the inputs, the chart, the "
        "assembly). one point: linearize repeated at the start point, where the FMU's kept Jacobian spares its "
        f"evaluation. Worst linearisation {worst_t * 1e3:.3f} ms (target <= 20), worst ratio {worst_r:.3f} (target "
        f"<= 1/3), of the FMI calls alone {worst_c:.3f}. open: extracting, loading and initialising the instance, "
        "once per FMU."
    )
    return "\n".join(rows)


if __name__ == "__main__":
    import sys

    print(table(sys.argv[1:] or None))
