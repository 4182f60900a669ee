"""The systems part of `rbfmu demo`: every shipped system built, run in ECOS, and the figures a control engineer reads.

For a system closed by `attitude_pd` (docs/theory.md §12.1) the figures are those of a
rest-to-rest slew: the attitude error angle φ(t) = 2 atan2(|q_e,vec|, |q_e0|), q_e = q_d* ⊗ q
(rad), its settling time (the first communication point after which φ stays within 2 % of
φ(0)) and its overshoot (the largest turn past the target about the slew's start axis, in %
of φ(0)). For a system closed by `quadrotor_hover` (§12.2): the height and yaw errors at the
end (m, rad; yaw ψ = atan2(2(q0 q3 + q1 q2), 1 − 2(q2² + q3²)), heading of body x about
world z), the horizontal drift (m) and the height's 2 % settling time. The targets are read
from the controller (its file's values, overridden by the system's parameters), never
assumed.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from concurrent.futures import Executor, Future
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from modelsrc.controllers.controller import CKind, ControllerModel

from .archive import open_archive
from .build import BuiltSystem, check_built, write_built
from .masters import SystemResult, run_system
from .results import plot_result, write_result_csv
from .system_file import Component, list_systems

__all__ = ["SystemFigures", "demo_systems", "hover_figures", "settling_time", "slew_figures"]

SETTLE_BAND = 0.02  # the 2 % band of the settling time (a control textbook's usual choice)


@dataclass(frozen=True)
class SystemFigures:
    """One shipped system's run in the demo: its name, the master, what moved and its figures
    (label -> (value, unit)), the wall time of its build and of its run (s)."""

    name: str
    master: str
    figures: dict[str, tuple[float, str]]
    build_s: float
    run_s: float


def settling_time(t: np.ndarray, err: np.ndarray, band: float) -> float:
    """First time t_k (s) after which |err| stays ≤ band; inf if the run ends outside it."""
    outside = np.nonzero(np.abs(err) > band)[0]
    if outside.size == 0:
        return float(t[0])
    k = int(outside[-1]) + 1
    return float(t[k]) if k < t.size else math.inf


def _targets(comp: Component, ctl: ControllerModel) -> dict[str, float]:
    """The controller's tunable parameters: its file's values, then the system's overrides."""
    values = {v.name: float(v.start) for v in ctl.variables if v.kind == CKind.PARAM_TUNABLE and v.start is not None}
    values.update(comp.parameters)
    return values


def _vector(result: SystemResult, base: str, n: int) -> np.ndarray:
    return np.column_stack([result.values[f"{base}[{i}]"] for i in range(1, n + 1)])


def slew_figures(result: SystemResult, plant: str, targets: dict[str, float]) -> dict[str, tuple[float, str]]:
    """Error angle at start and end, settling time and overshoot of a slew (module docstring)."""
    q = _vector(result, f"{plant}.q", 4)
    qd = np.array([targets[f"q_d[{i}]"] for i in range(1, 5)])
    # q_e = q_d* ⊗ q (scalar first): its scalar part q_d·q, its vector part q_d0 q_v − q0 q_d,v − q_d,v × q_v
    qe0 = q @ qd
    qev = qd[0] * q[:, 1:] - np.outer(q[:, 0], qd[1:]) - np.cross(qd[1:], q[:, 1:])
    phi = 2.0 * np.arctan2(np.linalg.norm(qev, axis=1), np.abs(qe0))
    axis = qev[0] * np.sign(qe0[0]) / np.linalg.norm(qev[0])  # the slew's start axis
    signed = 2.0 * np.arctan2(qev @ axis * np.sign(qe0), np.abs(qe0))  # < 0: past the target
    return {
        "start error": (float(phi[0]), "rad"),
        "end error": (float(phi[-1]), "rad"),
        "settling (2 %)": (settling_time(result.t, phi, SETTLE_BAND * phi[0]), "s"),
        "overshoot": (100.0 * max(0.0, -float(signed.min())) / float(phi[0]), "%"),
    }


def hover_figures(result: SystemResult, plant: str, targets: dict[str, float]) -> dict[str, tuple[float, str]]:
    """Height and yaw errors at the end, horizontal drift and the height's settling time."""
    x = _vector(result, f"{plant}.x_cm", 3)
    q = _vector(result, f"{plant}.q", 4)
    xd = np.array([targets[f"x_d[{i}]"] for i in range(1, 4)])
    yaw = np.arctan2(2.0 * (q[:, 0] * q[:, 3] + q[:, 1] * q[:, 2]), 1.0 - 2.0 * (q[:, 2] ** 2 + q[:, 3] ** 2))
    dz = x[:, 2] - xd[2]
    yaw_err = math.remainder(float(yaw[-1]) - targets["psi_d"], 2.0 * math.pi)
    return {
        "height error": (float(dz[-1]), "m"),
        "yaw error": (yaw_err, "rad"),
        "horizontal drift": (float(np.max(np.linalg.norm(x[:, :2] - xd[:2], axis=1))), "m"),
        "height settling (2 %)": (settling_time(result.t, dz, SETTLE_BAND * abs(dz[0])), "s"),
    }


# which figures a system gets, by the law of its controller
FIGURES: dict[str, Callable[[SystemResult, str, dict[str, float]], dict[str, tuple[float, str]]]] = {
    "attitude_pd": slew_figures,
    "quadrotor_hover": hover_figures,
}


def _figures(built: BuiltSystem, result: SystemResult) -> dict[str, tuple[float, str]]:
    """The figures of a system's run, by the law of each of its controllers (FIGURES; the
    controllers as the build loaded them)."""
    components = built.system.components
    plants = [c.name for c in components.values() if c.kind == "scene"]
    out: dict[str, tuple[float, str]] = {}
    for name, ctl in built.controllers.items():
        fn = FIGURES.get(ctl.name)
        if fn is not None and len(plants) == 1:
            out.update(fn(result, plants[0], _targets(components[name], ctl)))
    return out


# shipped systems `make demo` leaves out: cosim_slew is the report's measurement loop (4000 steps of
# a slew the `slew` system already shows), and its two FMUs would take ~15 s of the demo's 2 minutes
NOT_IN_DEMO = ("cosim_slew",)


def demo_system_names() -> list[str]:
    """The shipped systems `make demo` builds and runs (list_systems without NOT_IN_DEMO)."""
    return [n for n in list_systems() if n not in NOT_IN_DEMO]


def demo_systems(
    build_dir: Path, out: Path, master: str = "ecos", pool: Executor | None = None
) -> tuple[list[SystemFigures], list[Future[None]]]:
    """Build every shipped system of the demo (demo_system_names) into build_dir, run it in
    `master`, write OUT/NAME_MASTER.csv and .png; return each system's figures (module
    docstring) and the plots still being drawn on `pool`'s processes (none without a pool: each
    is drawn here before the next system)."""
    rows, plots = [], []
    for name in demo_system_names():
        tic = time.perf_counter()
        built = check_built(name, build_dir)
        ssp = write_built(built, build_dir)
        tac = time.perf_counter()
        archive = open_archive(ssp)
        result = run_system(archive, master)
        toc = time.perf_counter()
        stem = out / f"{name}_{master}"
        write_result_csv(result, stem.with_suffix(".csv"))
        plot = (stem.with_suffix(".png"), archive.sources or None)
        if pool is None:
            plot_result(result, *plot)
        else:
            plots.append(pool.submit(plot_result, result, *plot))
        rows.append(SystemFigures(name, master, _figures(built, result), tac - tic, toc - tac))
    return rows, plots
