"""What each feature's users look at in a run: its plot panels and summary figures, one table keyed by feature.

`VIEWS` holds, per capability of a scene (a sensor point, a held rate's bearing torque, the
rotors, the orbit, a multirotor, the inputs),
the panels `rbfmu run --plot` draws for it, the generic panels they replace (an orbit's
inertial ω and tilt say little: its roll, pitch and yaw relative to LVLH do), and the figures
the summary prints at the end of the run. Each view reads only the run's recorded outputs and
inputs (fmu.drive.run.RunResult) and skips what a run did not record (a sweep's few outputs).
Units SI; angles in rad; frames as the outputs' (docs/variables.md).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from modelsrc.scene import Scene

from .run import RunResult


@dataclass
class Panel:
    """One axis of the run's plot: its label, its curves (label -> values at result.time)
    whether the y axis is logarithmic, and a note (what is left out, and why)."""

    ylabel: str
    series: dict[str, np.ndarray]
    log: bool = False
    note: str = ""


@dataclass(frozen=True)
class FeatureView:
    """A feature's part of a run's plot and summary: `applies` to the scene, its `panels`
    (name -> Panel), the generic panels it `replaces`, and its end-of-run `figures`
    (label with unit -> value)."""

    name: str
    applies: Callable[[Scene], bool]
    panels: Callable[[RunResult], dict[str, Panel]]
    figures: Callable[[RunResult], dict[str, float]]
    replaces: tuple[str, ...] = ()


def _series(result: RunResult, names: dict[str, str]) -> dict[str, np.ndarray]:
    """label -> the output or input named, for those the run recorded."""
    rec = {**result.inputs, **result.values}
    return {label: rec[name] for label, name in names.items() if name in rec}


def _rotor_panels(result: RunResult) -> dict[str, Panel]:
    rotors = result.scene.rotors
    out = {}
    # Omega_NAME: the relative rate Ω, a state output in torque mode, the input in speed mode
    speeds = _series(result, {f"Ω {r} (relative)": f"Omega_{r}" for r in rotors})
    speeds.update(_series(result, {f"Ω {r} absolute": f"Omega_abs_{r}" for r in rotors}))
    if speeds:
        out["rotor speeds"] = Panel("rotor speed [rad/s]", speeds)
    momenta = _series(result, {f"h {r}": f"h_{r}" for r in rotors})
    if momenta:
        out["rotor momenta"] = Panel("rotor momentum J(g·ω+Ω) [N m s]", momenta)
    return out


def _rotor_figures(result: RunResult) -> dict[str, float]:
    rotors = result.scene.rotors
    names = {f"Omega_{r} [rad/s]": f"Omega_{r}" for r in rotors}
    names.update({f"h_{r} [N m s]": f"h_{r}" for r in rotors})
    return {label: float(v[-1]) for label, v in _series(result, names).items()}


_RPY = ("roll", "pitch", "yaw")


def _orbit_panels(result: RunResult) -> dict[str, Panel]:
    out = {}
    rpy = _series(result, {f"{a} (LVLH)": f"rpy_lvlh[{k + 1}]" for k, a in enumerate(_RPY)})
    if rpy:
        out["attitude in LVLH"] = Panel("roll, pitch, yaw rel. LVLH [rad]", rpy)
    w = _series(result, {f"ω{k + 1} rel. LVLH": f"w_lvlh[{k + 1}]" for k in range(3)})
    if w:
        out["rates in LVLH"] = Panel("ω rel. LVLH, body [rad/s]", w)
    if "E_jacobi" in result.values:
        E = result.values["E_jacobi"]
        out["Jacobi integral"] = Panel("E_jacobi − E_jacobi(0) [J]", {"E_jacobi − E_jacobi(0)": E - E[0]})
    return out


def _orbit_figures(result: RunResult) -> dict[str, float]:
    names = {f"{a} LVLH [rad]": f"rpy_lvlh[{k + 1}]" for k, a in enumerate(_RPY)}
    out = {label: float(v[-1]) for label, v in _series(result, names).items()}
    if "E_jacobi" in result.values:
        out["E_jacobi [J]"] = float(result.values["E_jacobi"][-1])
    return out


def _is_multirotor(scene: Scene) -> bool:
    """A free body lifted by propellers (rotors with thrust k_f > 0)."""
    return scene.moves and any(r.k_f > 0 for r in scene.rotors.values())


def _up(scene: Scene) -> np.ndarray:
    """The world's up: against gravity g, world z where g is 0 or the scene has no gravity."""
    g = np.asarray(scene.g, dtype=float)
    if scene.has("gravity") and np.linalg.norm(g) > 0:
        return -g / np.linalg.norm(g)
    return np.array([0.0, 0.0, 1.0])


def height_and_heading(result: RunResult) -> tuple[np.ndarray, np.ndarray] | None:
    """Height x_cm·up (m) and heading (rad, unwrapped): the angle about up from the world
    axis nearest the horizontal to the body x axis projected on the horizontal plane."""
    if "x_cm[1]" not in result.values:
        return None
    up = _up(result.scene)
    height = result.vector("x_cm") @ up
    q = result.vector("q")
    w, x, y, z = (q / np.linalg.norm(q, axis=1, keepdims=True)).T
    bx = np.column_stack([1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y)])  # R e_x
    e1 = np.eye(3)[int(np.argmin(np.abs(up)))]
    e1 = e1 - (e1 @ up) * up
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(up, e1)
    return height, np.unwrap(np.arctan2(bx @ e2, bx @ e1))


def _multirotor_panels(result: RunResult) -> dict[str, Panel]:
    hh = height_and_heading(result)
    if hh is None:
        return {}
    return {"height": Panel("height [m]", {"height": hh[0]}), "heading": Panel("heading [rad]", {"heading": hh[1]})}


def _multirotor_figures(result: RunResult) -> dict[str, float]:
    hh = height_and_heading(result)
    return {} if hh is None else {"height [m]": float(hh[0][-1]), "heading [rad]": float(hh[1][-1])}


def _input_panels(result: RunResult) -> dict[str, Panel]:
    shown = {f"Omega_{r}" for r in result.scene.rotors}  # speed-mode rates: in the rotor speeds panel
    series = {name: v for name, v in result.inputs.items() if name not in shown}
    return {"inputs": Panel("inputs as driven", series)} if series else {}


def _bearing_panels(result: RunResult) -> dict[str, Panel]:
    # the torque that holds a prescribed rate (docs/theory.md §4.4): the skewed bar's answer
    if "tau_bearing[1]" not in result.values:
        return {}
    tau = result.vector("tau_bearing")
    series = {f"tau_bearing {c}": tau[:, k] for k, c in enumerate("xyz")}
    series["|tau_bearing|"] = np.linalg.norm(tau, axis=1)
    return {"bearing torque": Panel("bearing torque (world) [N m]", series)}


def _bearing_figures(result: RunResult) -> dict[str, float]:
    if "tau_bearing[1]" not in result.values:
        return {}
    return {"max |tau_bearing| [N m]": float(np.max(np.linalg.norm(result.vector("tau_bearing"), axis=1)))}


def _sensor_panels(result: RunResult) -> dict[str, Panel]:
    # the body point a sensor sits on (docs/theory.md §1.4, §7.2): the arm's wrist
    out = {}
    for key, what, unit in (("r", "position", "m"), ("v", "velocity", "m/s"), ("a", "acceleration", "m/s²")):
        name = f"sensor_{key}"
        if f"{name}[1]" in result.values:
            x = result.vector(name)
            series = {f"{name} {c}": x[:, k] for k, c in enumerate("xyz")}
            if key != "r":
                series[f"|{name}|"] = np.linalg.norm(x, axis=1)
            out[f"sensor {what}"] = Panel(f"sensor {what} (world) [{unit}]", series)
    return out


def _sensor_figures(result: RunResult) -> dict[str, float]:
    return {
        f"|sensor_{key}(T)| [{unit}]": float(np.linalg.norm(result.vector(f"sensor_{key}")[-1]))
        for key, unit in (("v", "m/s"), ("a", "m/s2"))
        if f"sensor_{key}[1]" in result.values
    }


VIEWS = (
    FeatureView("sensor", lambda sc: "sensor" in sc.outputs, _sensor_panels, _sensor_figures),
    FeatureView("prescribed rate", lambda sc: sc.has("prescribed_rate"), _bearing_panels, _bearing_figures),
    FeatureView("rotors", lambda sc: bool(sc.rotors), _rotor_panels, _rotor_figures),
    FeatureView("multirotor", _is_multirotor, _multirotor_panels, _multirotor_figures),
    FeatureView("orbit", lambda sc: sc.has("orbit"), _orbit_panels, _orbit_figures, replaces=("rates", "orientation")),
    FeatureView("inputs", lambda sc: bool(sc.input_names), _input_panels, lambda result: {}),
)


def views(scene: Scene) -> list[FeatureView]:
    """The views that apply to the scene, in VIEWS order."""
    return [v for v in VIEWS if v.applies(scene)]


def feature_figures(result: RunResult) -> dict[str, float]:
    """Every applying view's end-of-run figures (label with unit -> value)."""
    out: dict[str, float] = {}
    for v in views(result.scene):
        out.update(v.figures(result))
    return out
