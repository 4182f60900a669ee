"""Forced scenes in the report: the error of continuous and of held inputs, against the communication step.

For every shipped scene with inputs, its FMU is run at its default settings (rk8, error
control, docs/theory.md §5.5) over [0, T] at several communication steps H, the inputs
given two ways (fmu.drive.inputs): continuous (a harmonic given at every internal node through FMI
3.0 intermediate update, tables switching on communication points) and held (each input
at its mean over the step, as an importer without intermediate update gives it). Both are
measured against one scipy DOP853 reference at rtol 1e-13 that integrates the physical
input (rbcheck.baselines.motion.integrate, inputs "continuous": a harmonic evaluated in
the right-hand side, restarts on the grid). Error: the largest over the common points
(multiples of the largest H) of |ω − ω_ref| / max|ω_ref| (body frame).

A table is constant between communication points, so both ways agree there (the horizon
reaches past the first switch); a harmonic held at its mean over a step leaves an error
that falls only with H (measured about H² on top_on_shaker), whatever the tolerance.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fmu.drive.inputs import communication_points
from fmu.drive.run import run_fmu
from modelsrc.scene import Scene

from ..baselines.motion import integrate

STEPS = (0.01, 0.005, 0.002, 0.001)
HORIZON = 1.0  # s: at most, past a table's first switch
REF_RTOL, REF_ATOL = 1e-13, 1e-15
MODES = ("continuous", "hold")


@dataclass
class SceneHoldResult:
    """One forced scene: stop time (s), communication steps H (s), and per mode
    ("continuous", "hold") the relative ω error at each H."""

    scene: str
    stop_time: float
    steps: tuple[float, ...]
    inputs: str
    errors: dict[str, list[float]] = field(default_factory=dict)


def _input_kinds(scene: Scene) -> str:
    kinds = []
    for name, spec in scene.inputs.items():
        kind = "harmonic" if name in scene.inputs_varying_in_step else ("table" if np.ndim(spec) == 2 else "constant")
        kinds.append(f"{name} {kind}")
    return ", ".join(kinds)


def measure_scene(
    fmu_path: Path, scene: Scene, steps: Sequence[float] = STEPS, horizon: float = HORIZON
) -> SceneHoldResult:
    """Both modes at every H of `steps` (s) over [0, min(stop time, horizon)] against the
    continuous scipy reference (module docstring)."""
    switches = [t for t in scene.switch_times() if t > 0]
    T = min(scene.stop_time, horizon + (switches[0] if switches else 0.0))
    coarse = communication_points(scene, T, max(steps))
    fine = np.unique(np.concatenate([communication_points(scene, T, min(steps)), coarse]))
    ref = integrate(scene, fine, "DOP853", rtol=REF_RTOL, atol=REF_ATOL, inputs="continuous")
    w_ref = ref.w_body[np.searchsorted(fine, coarse)]
    scale = float(np.max(np.linalg.norm(w_ref, axis=1))) or 1.0
    res = SceneHoldResult(scene.name, T, tuple(steps), _input_kinds(scene))
    for mode in MODES:
        res.errors[mode] = []
        for H in steps:
            r = run_fmu(fmu_path, scene, stop_time=T, step=H, inputs=mode, outputs=[f"w_body[{k}]" for k in (1, 2, 3)])
            idx = np.searchsorted(r.time, coarse - 1e-12 * T)
            dw = np.linalg.norm(r.vector("w_body")[idx] - w_ref, axis=1)
            res.errors[mode].append(float(np.max(dw)) / scale)
    return res


def measure_forced_scenes(
    fmus: Mapping[str, Path],
    scenes: Sequence[Scene],
    steps: Sequence[float] = STEPS,
    horizon: float = HORIZON,
    progress: Callable[[str], None] | None = None,
) -> list[SceneHoldResult]:
    """`measure_scene` for every scene with inputs (fmus: scene name -> its FMU)."""
    out = []
    for sc in scenes:
        if not sc.inputs:
            continue
        if progress:
            progress(f"forced scene {sc.name}")
        out.append(measure_scene(fmus[sc.name], sc, steps, horizon))
    return out


def write_forced_scenes(w: Callable[[str], None], results: Sequence[SceneHoldResult]) -> None:
    """Append the table: per scene and H, the continuous and the held error side by side."""
    if not results:
        return
    w("### Continuous and held inputs in the forced scenes\n")
    w(
        "Each scene with inputs at its default settings, the inputs given continuously (a harmonic at every "
        "internal node through FMI 3.0 intermediate update, `rbfmu run`'s default) or held over each "
        "communication step at their mean (`--input-hold`, what an importer without intermediate update does), "
        f"against scipy DOP853 at rtol {REF_RTOL:g} integrating the physical input "
        "(`rbcheck.baselines.motion.integrate`). Error: max |ω − ω_ref| / max|ω_ref| at the multiples of the "
        "largest H. A table switches on communication points, so the two agree; a harmonic held over a step "
        "leaves an error that falls only with H, whatever the tolerance. (The work-precision curves hold the "
        "inputs in the FMU runs and in their scipy reference alike: they measure each method on the input it is "
        "given; this table is the hold's own error.)\n"
    )
    steps = results[0].steps
    w("| scene (inputs, T) | " + " | ".join(f"H = {h:g} s continuous | held" for h in steps) + " |")
    w("|---|" + "---:|---:|" * len(steps))
    for r in results:
        cells = " | ".join(f"{r.errors['continuous'][i]:.1e} | {r.errors['hold'][i]:.1e}" for i in range(len(steps)))
        w(f"| `{r.scene}` ({r.inputs}, T = {r.stop_time:g} s) | {cells} |")
    w("")
