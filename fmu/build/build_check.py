"""The validation figures an FMU's documentation shows: measured at build time on the freshly built binary.

Two Co-Simulation runs of the scene's default experiment through fmpy (FMI 3.0 or 2.0,
the archive's own version), inputs given as fmu.drive.run.run_fmu gives them by default: the
tables set per communication step (they switch on communication points), a harmonic
(modelsrc.scene_inputs) given at every internal node through FMI 3.0 intermediate update,
or in FMI 2.0 as its value and first MAX_INPUT_ORDER derivatives at the step's start
(fmi2SetRealInputDerivatives: a Taylor polynomial over the step, error O(H⁴) per step):
- the FMU's defaults: its default method, tolerance and h_max (docs/theory.md §5.5);
- a reference: rk8 (else the highest-order method compiled in) error-controlled at a
  thousandth of the default tolerance, else (no error estimate, or tolerance 0) with fixed
  steps of a quarter of the scene's fixed step.
Reported: the difference of the two at the stop time (ω in rad/s, body frame; q
dimensionless), which estimates the default run's error when the reference is far more
accurate; max ||q| − 1|; and the drift of E and |L_world| where the physics conserves
them (Scene.conserves_energy, Scene.torque_free) and the scene outputs them. The outputs
are sampled at COMMUNICATION_POINTS points at most; the error control ends its internal
steps on every communication point, so this changes the default run little.

When a run fails (an FMI call returns an error: most often a doStep refused by the work
limit, in a stiff scene or one given in the wrong unit), the figures are not measured: the
BuildCheck's `error` says, in one sentence that starts "the build's validation run", which
run, which call, at what time and with what method, with the FMU's own message. The FMU's
log of both runs is collected, never printed bare ("[ERROR] fmi3DoStep ..." read as the
build's own failure). The build goes on and warns (`ValidationRunWarning`): the FMU may be
right and the scene stiff, and `rbfmu run --set work_limit=...` must be able to build it
(docs/user_guide.md §3.2).
"""

from __future__ import annotations

import contextlib
import io
import shutil
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from fmpy import extract, instantiate_fmu, read_model_description
from fmpy.fmi3 import FMU3Slave

from modelsrc.methods import METHODS, error_controlled
from modelsrc.scene import Scene
from modelsrc.scene_inputs import Harmonic, component_names

from .model_data import MAX_INPUT_ORDER
from ..drive.inputs import communication_points, node_values

COMMUNICATION_POINTS = 200


class ValidationRunWarning(UserWarning):
    """The build's validation run failed: the FMU was written, its documentation says the
    figures were not measured and why (the message starts "the build's validation run")."""


class ValidationRunError(RuntimeError):
    """A validation run's FMI call failed: `call` ('fmi3DoStep'), `time` (s, the
    communication point the call started from), `log` (the FMU's messages, or fmpy's words)."""

    def __init__(self, call: str, time: float, log: str):
        super().__init__(f"{call} at t = {time:g} s: {log}")
        self.call, self.time, self.log = call, time, log


def _sentence(text: str) -> str:
    """text without trailing periods and spaces: it is placed inside a sentence."""
    return text.strip().rstrip(".").rstrip()


@dataclass(frozen=True)
class BuildCheck:
    """Figures of one build check. method/reference: method names; settings/ref_settings:
    the tolerance and h_max of each run, in words; step (s): communication step of both;
    stop_time (s);
    w_diff: ‖ω(T) − ω_ref(T)‖∞ (rad/s, body); q_diff: ‖q(T) − q_ref(T)‖∞ (1); w_scale:
    max ‖ω‖∞ over the run (rad/s); qnorm: max ||q| − 1|; E_drift, L_drift: max relative
    deviation over the run, None where not conserved or not output; wall_s: wall time of
    both runs (s, this machine); error: why the check could not run ('' when it ran)."""

    method: str
    reference: str
    settings: str
    ref_settings: str
    step: float
    stop_time: float
    w_diff: float = float("nan")
    q_diff: float = float("nan")
    w_scale: float = float("nan")
    qnorm: float = float("nan")
    E_drift: float | None = None
    L_drift: float | None = None
    wall_s: float = 0.0
    error: str = ""


def reference_method(methods: tuple[str, ...] | list[str]) -> str:
    """rk8 when compiled in, else the highest-order method (ties: the first)."""
    return "rk8" if "rk8" in methods else max(methods, key=lambda m: METHODS[m].order)


def _run(
    unzipdir: str,
    md,
    scene: Scene,
    method: str,
    settings: dict[str, float],
    step: float,
    names: list[str],
    quiet: bool = False,
) -> np.ndarray:
    """One co-simulation with the method and parameter values `settings` (name -> value);
    returns the named outputs at every communication point (rows). The FMU's log messages
    are collected (FMI 2.0: fmpy's logger prints them, caught here); a failed FMI call
    raises ValidationRunError with them. quiet: warnings are dropped, else printed once
    each on stderr as the build's validation run's."""
    log: list[tuple[int, str]] = []  # (fmi status, message)
    stdout = io.StringIO()  # FMI 2.0: fmpy's logger prints "[LABEL] message" lines
    where = ["fmi3InstantiateCoSimulation" if md.fmiVersion.startswith("3") else "fmi2Instantiate", 0.0]
    try:
        with contextlib.redirect_stdout(stdout):
            return _co_simulate(unzipdir, md, scene, method, settings, step, names, log, where)
    except Exception as exc:  # fmpy raises plain Exception on FMI errors
        printed = [line for line in stdout.getvalue().splitlines() if line.startswith(("[ERROR]", "[FATAL]"))]
        errors = [m for status, m in log if status >= FMI_ERROR] + printed
        raise ValidationRunError(str(where[0]), float(where[1]), "; ".join(errors) or _sentence(str(exc) or repr(exc)))
    finally:
        if not quiet:
            lines = [m for status, m in log if status == FMI_WARNING] + [
                line.removeprefix("[WARNING] ")
                for line in stdout.getvalue().splitlines()
                if line.startswith("[WARNING]")
            ]
            for line in dict.fromkeys(lines):
                print(f"rbfmu: the build's validation run ({method}) logged a warning: {line}", file=sys.stderr)


FMI_WARNING, FMI_ERROR = 1, 3  # fmi3Status / fmi2Status: OK 0, Warning 1, Discard 2, Error 3, Fatal 4


def _co_simulate(
    unzipdir: str,
    md,
    scene: Scene,
    method: str,
    settings: dict[str, float],
    step: float,
    names: list[str],
    log: list[tuple[int, str]],
    where: list,
) -> np.ndarray:
    """The loop of `_run`; `log` collects the FMU's messages (FMI 3.0), `where` holds the
    FMI call under way and the communication point it started from (s)."""
    vr = {v.name: v.valueReference for v in md.modelVariables}
    fmi3 = md.fmiVersion.startswith("3")
    varying = [b for b in scene.inputs_varying_in_step if component_names(b)[0] in vr]
    node_names = [c for b in varying for c in component_names(b)]

    # the FMU's log messages are collected (FMI 3.0; the reference run at a thousandth of the
    # default tolerance meets the estimate's round-off floor by design, and says so)
    def collect(env, status, category, message):
        log.append((int(status), message.decode("utf-8", "replace")))

    log3 = {"logMessage": collect}
    if fmi3 and varying:  # asked at every internal node (FMI 3.0 intermediate update)
        fmu = FMU3Slave(guid=md.guid, unzipDirectory=unzipdir, modelIdentifier=md.coSimulation.modelIdentifier)
        node_vrs, at_node = [vr[n] for n in node_names], node_values(scene, node_names)

        def update(env, t, set_requested, get_allowed, finished, can_return, early, early_time):
            fmu.setFloat64(node_vrs, at_node(t))

        fmu.instantiate(intermediateUpdate=update, requiredIntermediateVariables=node_vrs, **log3)
    elif fmi3:
        fmu = FMU3Slave(guid=md.guid, unzipDirectory=unzipdir, modelIdentifier=md.coSimulation.modelIdentifier)
        fmu.instantiate(**log3)
    else:
        # FMI 2.0 keeps fmpy's logger: a logger given to fmpy becomes the process-wide target
        # of its native proxy (fmpy.logging.addLoggerProxy), left dangling once this run's
        # callbacks are freed, and a later FMI 2.0 instance that logs through it crashes
        fmu = instantiate_fmu(unzipdir, md, fmi_type="CoSimulation")
    set_real = fmu.setFloat64 if fmi3 else fmu.setReal
    get_real = fmu.getFloat64 if fmi3 else fmu.getReal
    set_int = fmu.setInt64 if fmi3 else fmu.setInteger
    inputs = [(base, [vr[c] for c in component_names(base)]) for base in scene.inputs if component_names(base)[0] in vr]
    out_vrs = [vr[n] for n in names]
    grid = communication_points(scene, scene.stop_time, step)  # the table switches land on points
    n = len(grid) - 1
    rows = np.empty((n + 1, len(names)))
    try:
        where[0] = "fmi3EnterInitializationMode" if fmi3 else "fmi2EnterInitializationMode"
        if fmi3:
            fmu.enterInitializationMode(startTime=0.0, stopTime=scene.stop_time)
        else:
            fmu.setupExperiment(startTime=0.0, stopTime=scene.stop_time)
            fmu.enterInitializationMode()
        if settings:
            set_real([vr[k] for k in settings], list(settings.values()))
        set_int([vr["method"]], [METHODS[method].value])
        where[0] = "fmi3ExitInitializationMode" if fmi3 else "fmi2ExitInitializationMode"
        fmu.exitInitializationMode()
        rows[0] = get_real(out_vrs)
        for i in range(n):
            for base, vrs in inputs:
                set_real(vrs, [float(x) for x in scene.input_at(base, grid[i])])
                if not fmi3 and base in varying:  # FMI 2.0: the Taylor polynomial over the step
                    spec = scene.inputs[base]
                    assert isinstance(spec, Harmonic)  # varies_in_step: only a harmonic does
                    for order in range(1, MAX_INPUT_ORDER + 1):
                        d = [float(x) for x in spec.derivative(grid[i], order)]
                        fmu.setRealInputDerivatives(vrs, [order] * len(vrs), d)
            where[:] = ["fmi3DoStep" if fmi3 else "fmi2DoStep", grid[i]]
            fmu.doStep(grid[i], grid[i + 1] - grid[i])
            rows[i + 1] = get_real(out_vrs)
        fmu.terminate()
    finally:
        fmu.freeInstance()
    return rows


def check_build(fmu_path: Path, scene: Scene, methods: tuple[str, ...] | list[str], default_method: str) -> BuildCheck:
    """Run the two co-simulations of the module docstring on the archive at fmu_path."""
    ref = reference_method(methods)
    step = max(scene.step, scene.stop_time / COMMUNICATION_POINTS)
    md = read_model_description(str(fmu_path))
    outputs = {v.name for v in md.modelVariables if v.causality == "output"}
    names = [f"q[{k}]" for k in (1, 2, 3, 4)] + [f"w_body[{k}]" for k in (1, 2, 3)]
    energy = next((e for e in ("E_total", "E_kin") if e in outputs), None)
    track_E = energy is not None and scene.conserves_energy
    track_L = scene.torque_free and "L_world[1]" in outputs
    names += ([energy] if track_E and energy else []) + ([f"L_world[{k}]" for k in (1, 2, 3)] if track_L else [])
    if error_controlled(ref) and scene.tolerance > 0:
        ref_settings = {"tolerance": scene.tolerance * 1e-3}
        ref_words = f"tolerance {scene.tolerance * 1e-3:g} 1/s"
    else:
        ref_settings = {"tolerance": 0.0, "h_max": scene.fixed_step / 4}
        ref_words = f"fixed steps of {scene.fixed_step / 4:g} s"
    settings = (
        f"tolerance {scene.tolerance:g} 1/s"
        if error_controlled(default_method) and scene.tolerance > 0
        else "fixed steps"
    ) + (f", h_max {scene.h_max:g} s" if scene.h_max > 0 else "")
    unzipdir = extract(str(fmu_path))
    t0 = time.perf_counter()
    run = ""
    try:
        run = f"{default_method}, {settings}"
        y = _run(unzipdir, md, scene, default_method, {}, step, names)
        run = f"the reference: {ref}, {ref_words}"
        y_ref = _run(unzipdir, md, scene, ref, ref_settings, step, names, quiet=True)
    except ValidationRunError as exc:  # the docs say what failed, in one sentence
        why = (
            f"the build's validation run ({exc.call} at t = {exc.time:g} s, method {run}) failed: {_sentence(exc.log)}"
        )
        return BuildCheck(default_method, ref, settings, ref_words, step, scene.stop_time, error=why)
    finally:
        shutil.rmtree(unzipdir, ignore_errors=True)
    q, w = y[:, 0:4], y[:, 4:7]
    E_drift = L_drift = None
    if track_E:
        E = y[:, 7]
        E_drift = float(np.max(np.abs(E - E[0])) / max(abs(E[0]), 1e-300))
    if track_L:
        nL = np.linalg.norm(y[:, -3:], axis=1)
        L_drift = float(np.max(np.abs(nL - nL[0])) / max(nL[0], 1e-300))
    return BuildCheck(
        default_method,
        ref,
        settings,
        ref_words,
        step,
        scene.stop_time,
        w_diff=float(np.max(np.abs(w[-1] - y_ref[-1, 4:7]))),
        q_diff=float(np.max(np.abs(q[-1] - y_ref[-1, 0:4]))),
        w_scale=float(np.max(np.abs(w))),
        qnorm=float(np.max(np.abs(np.linalg.norm(q, axis=1) - 1.0))),
        E_drift=E_drift,
        L_drift=L_drift,
        wall_s=time.perf_counter() - t0,
    )
