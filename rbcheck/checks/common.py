"""Plumbing shared by the checks: load a scene, run its FMU, run Exudyn, start values.

Of the project this module imports only the FMU driver (``fmu.drive.run``) and the scene
reader (``modelsrc.scene``, read as data); no physics of ``modelsrc`` is used. Units SI;
``w`` = body angular velocity [rad/s]; ``q`` = unit quaternion (w, x, y, z) body -> world.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import Any

import numpy as np
from fmpy import read_model_description
from numpy.typing import ArrayLike, NDArray

from fmu.drive.run import RunResult, run_fmu
from modelsrc.scene import Scene, load_scene

from ..closed_forms.of_scene import is_principal_diag
from ..exudyn.motion import simulate

__all__ = [
    "NotApplicable",
    "exudyn_run",
    "frictionless",
    "is_principal_diag",
    "load",
    "method_codes",
    "run",
    "start_values",
    "tilted_quaternion",
]


class NotApplicable(ValueError):
    """A check that does not apply to the scene; the message says why (it is printed
    in the table as "not applicable: <message>")."""


def load(scene_or_name: Scene | str | Path) -> Scene:
    """The scene itself, or the scene read from a shipped name or a .toml path."""
    return load_scene(scene_or_name) if isinstance(scene_or_name, (str, Path)) else scene_or_name


def run(fmu_path: str | Path, scene: Scene, **kw: Any) -> RunResult:
    """Co-simulate the scene's FMU through fmpy (``fmu.drive.run.run_fmu``; keywords as there)."""
    return run_fmu(fmu_path, scene, **kw)


def method_codes(fmu_path: str | Path) -> dict[str, int]:
    """Integrator name -> value of the FMU's ``method`` enumeration, read from its
    modelDescription.xml (so the check does not depend on ``modelsrc``)."""
    md = read_model_description(str(fmu_path))
    for td in md.typeDefinitions:
        if td.type == "Enumeration" and td.name == "Method":
            return {it.name: int(it.value) for it in td.items}
    raise ValueError(f"{fmu_path}: the FMU has no 'Method' enumeration type")


def start_values(w: ArrayLike | None = None, q: ArrayLike | None = None, **extra: float) -> dict[str, float]:
    """FMU start values: body rate w [rad/s], attitude q (body -> world) and any other
    named parameter (``h_max`` [s], ``c_friction`` [N m s/rad], ...). A given h_max means
    fixed steps of h_max (``tolerance`` 0, docs/theory.md §5.4) unless a tolerance is given."""
    sv: dict[str, float] = {}
    if w is not None:
        sv.update({f"w_body[{k + 1}]": float(x) for k, x in enumerate(np.asarray(w, dtype=float))})
    if q is not None:
        sv.update({f"q[{k + 1}]": float(x) for k, x in enumerate(np.asarray(q, dtype=float))})
    sv.update({k: float(v) for k, v in extra.items()})
    if "h_max" in sv:
        sv.setdefault("tolerance", 0.0)
    return sv


def exudyn_run(
    scene: Scene,
    w: ArrayLike | None = None,
    q: ArrayLike | None = None,
    stop_time: float | None = None,
    step: float | None = None,
    h: float | None = None,
    solver: str | None = None,
) -> dict[str, Any]:
    """Exudyn run of the scene (``rbcheck.exudyn.motion.simulate``: the models of
    ``rbcheck.exudyn.models``, or of ``rbcheck.exudyn.motion`` when the reference point
    moves) with another start state w [rad/s, body], q, horizon stop_time [s],
    communication step [s] or internal step h [s]; the scene is copied, not changed.
    solver: default RK67 (the moving pivot: TrapezoidalIndex2, its joint needs an
    implicit solver)."""
    changes: dict[str, Any] = {}
    if w is not None:
        changes["w0"] = np.asarray(w, dtype=float)
    if q is not None:
        changes["q0"] = np.asarray(q, dtype=float)
    if stop_time is not None:
        changes["stop_time"] = float(stop_time)
    if step is not None:
        changes["step"] = float(step)
    sc = dataclasses.replace(scene, **changes) if changes else scene
    if solver is None and not sc.moves:
        solver = "RK67"
    return simulate(sc, solver=solver, h=h)


def tilted_quaternion(theta: float) -> NDArray[np.float64]:
    """Rotation by theta [rad] about world x: figure axis tilted theta from z (phi = psi = 0)."""
    return np.array([math.cos(0.5 * theta), math.sin(0.5 * theta), 0.0, 0.0])


def frictionless(sc: Scene) -> tuple[Scene, dict[str, float]]:
    """The scene without friction (for the frictionless closed forms) and the FMU start
    values that switch its friction off (c_friction = 0; empty for a frictionless scene)."""
    if not sc.has("friction"):
        return sc, {}
    return dataclasses.replace(sc, features=sc.features - {"friction"}, c_friction=0.0), {"c_friction": 0.0}


def upward_crossing_period(t: NDArray[np.float64], x: NDArray[np.float64], imag_tol: float = 1e-12) -> float:
    """Mean period (s) between the first and last upward zero crossings of x(t) (t in s),
    each located by the cubic through the four samples around it (a root counts as real
    when its imaginary part is below imag_tol)."""
    ups = [i for i in range(1, len(x) - 2) if x[i] <= 0.0 < x[i + 1]]
    if len(ups) < 2:
        raise ValueError("fewer than two upward zero crossings: lengthen the run")

    def crossing(i: int) -> float:
        c = np.polyfit(t[i - 1 : i + 3] - t[i], x[i - 1 : i + 3], 3)
        roots = [r.real for r in np.roots(c) if abs(r.imag) < imag_tol and 0.0 <= r.real <= t[i + 1] - t[i]]
        return t[i] + roots[0]

    return (crossing(ups[-1]) - crossing(ups[0])) / (len(ups) - 1)
