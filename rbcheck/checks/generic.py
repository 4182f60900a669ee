r"""Generic checks run for every scene: closed-form trajectory, FMU vs Exudyn, drifts, input balances.

Each decides from the scene's data whether it applies and otherwise raises
:class:`NotApplicable` with the reason, which the table prints:

1. closed-form trajectory — for a body held at its rate (``prescribed_rate``: the uniform
   rotation of :mod:`rbcheck.closed_forms.uniform_rotation` and, where the scene outputs it,
   the bearing torque R (ω × I ω), docs/theory.md §4.4), for a torque-free body in principal axes
   (``Scene.torque_free``; I1 == I2: :mod:`rbcheck.closed_forms.free_symmetric`, else
   :mod:`rbcheck.closed_forms.free_asymmetric`, docs/theory.md §2.3) and for the frictionless
   Lagrange top (gravity only, ``Scene.conserves_energy``; :mod:`rbcheck.closed_forms.heavy_top`, §4.2):
   final body rate and the largest rate [rad/s] and attitude [rad] deviations; for a
   free body without force inputs also the parabola of its centre of mass [m, m/s]
   (:func:`rbcheck.closed_forms.free_flight.parabola`, §7.1);
2. FMU vs Exudyn trajectories — :func:`rbcheck.checks.trajectories.fmu_vs_exudyn`;
3. conserved-quantity drift — :func:`rbcheck.checks.trajectories.conserved_drifts`, the
   scene's default method and settings first, then DRIFT_METHODS at fixed steps;
4. input balances — for a scene whose inputs, forces, friction or moving pivot do work
   (no conserved quantity to watch) and that has no check of its own: the balances of
   :mod:`rbcheck.checks.balances` generated from its features (work against the inputs'
   power, momentum against the impulse of the forces, angular momentum about the centre
   of mass, the pivot force against M (a_cm − g)), with its default method and settings.

All run over :func:`rbcheck.checks.registry.horizon` (the scene's stop_time, shorter
under ``--quick`` for the shipped scenes).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from modelsrc.scene import Scene

from ..closed_forms.free_flight import parabola
from ..closed_forms.of_scene import NoClosedForm, closed_rotation
from ..exudyn.coverage import covers as exudyn_covers
from ..numerics.rotation_np import quat_to_matrix
from .bounds import allowed
from .common import NotApplicable, exudyn_run, method_codes, run
from .feature_checks import halved_balance_rows
from .registry import GenericOutcome, Row, final_rows, generic_check, has_specific_check, horizon, trajectory_rows
from .trajectories import conserved_drifts, drift_plan, fmu_vs_exudyn

__all__ = [
    "DRIFT_METHODS",
    "balance_check",
    "closed_form_check",
    "closed_form_trajectory",
    "drift_check",
    "exudyn_check",
]

# Methods whose drifts are tabulated: explicit order 4, implicit order 4 (keeps the
# quadratic invariants), the order-2 splitting (exact |L|) (docs/theory.md §5).
DRIFT_METHODS = ("rk4", "gauss4", "splitting")


def closed_form_trajectory(scene: Scene, t: NDArray) -> tuple[NDArray, NDArray, str]:
    """Closed-form body rate w [rad/s] (n, 3) and attitude q (n, 4, body -> world) of
    the scene at times t [s], and the name of the closed form
    (rbcheck.closed_forms.of_scene.closed_rotation); NotApplicable (with the reason) when
    no closed form of rbcheck covers the scene."""
    try:
        w, q, name = closed_rotation(scene, t)
    except NoClosedForm as exc:
        raise NotApplicable(str(exc)) from None
    return w, q, f"closed form: {name}"


@generic_check("closed-form trajectory")
def closed_form_check(fmu_path: Path, scene: Scene, quick: bool) -> GenericOutcome:
    """Final body rate and the largest deviations of the FMU and Exudyn runs from the
    closed-form trajectory (:func:`closed_form_trajectory`) over the check horizon (the
    Exudyn column empty where no Exudyn model has the scene's physics, rbcheck.exudyn.coverage)."""
    T = horizon(scene, quick)
    closed_form_trajectory(scene, np.zeros(1))  # NotApplicable before any run
    r = run(fmu_path, scene, stop_time=T)
    no_exudyn = exudyn_covers(scene)
    e = exudyn_run(scene, stop_time=T) if no_exudyn is None else None
    w_cf, q_cf, name = closed_form_trajectory(scene, r.time)
    rows = final_rows(r, e, w_cf) + trajectory_rows(r, e, w_cf, q_cf)
    # tolerances (rbcheck.checks.bounds): the rate's rows at the size of the closed-form rate,
    # the attitude angle at 2 (twice the error of the unit quaternion), over the run of T
    W = float(np.max(np.abs(w_cf)))
    for row, size in zip(rows, (W, W, W, W, 2.0), strict=True):
        row.tol = allowed(scene, T, size)
    if scene.has("prescribed_rate") and "tau_bearing" in scene.outputs:
        # the torque that holds the rate, R (I ω̇ + ω × I ω) with ω̇ = 0 (§4.4): a constant body
        # vector turned by R, so it errs as the attitude does, at most 2 |τ| times the angle
        w0 = np.asarray(scene.w0, dtype=float)
        tau_cf = quat_to_matrix(q_cf) @ np.cross(w0, np.asarray(scene.inertia, dtype=float) @ w0)
        size = 2.0 * float(np.max(np.linalg.norm(tau_cf, axis=1)))
        dev = float(np.max(np.abs(r.vector("tau_bearing") - tau_cf)))
        rows.append(Row("max_t |tau_bearing - R (w x I w)|", "N.m", dev, float("nan"), 0.0, allowed(scene, T, size)))
    if no_exudyn is not None:
        name += f"; no Exudyn run: {no_exudyn}"
    if scene.has("translation"):
        if scene.features & {"force_body", "force_world"} or scene.force_points:
            name += "; no parabola: forces act on the centre of mass"
        else:
            g = scene.g if scene.has("gravity") else np.zeros(3)
            x_cf, v_cf = parabola(scene.x0, scene.v0, g, r.time)
            for key, unit, ref in (("x_cm", "m", x_cf), ("v_cm", "m/s", v_cf)):
                dev = (float(np.max(np.abs(r.vector(key) - ref))), float(np.max(np.abs(e[key] - ref))))
                size = float(np.max(np.abs(ref)))  # the largest coordinate of the parabola's position or velocity
                rows.append(Row(f"max_t |{key} - parabola|", unit, *dev, 0.0, allowed(scene, T, size)))
            name += " + parabola (rbcheck.closed_forms.free_flight)"
    return GenericOutcome(rows=rows, note=name)


@generic_check("FMU vs Exudyn trajectories")
def exudyn_check(fmu_path: Path, scene: Scene, quick: bool) -> GenericOutcome:
    """:func:`fmu_vs_exudyn` over the check horizon (NotApplicable for features the
    Exudyn model lacks)."""
    return GenericOutcome(comparison=fmu_vs_exudyn(fmu_path, scene, stop_time=horizon(scene, quick)))


@generic_check("conserved-quantity drift")
def drift_check(fmu_path: Path, scene: Scene, quick: bool) -> GenericOutcome:
    """:func:`conserved_drifts` of DRIFT_METHODS at h_max and 10 h_max over the check
    horizon; the note says which balances and which methods the FMU lacks."""
    T = horizon(scene, quick)
    plan = drift_plan(scene, T)  # NotApplicable before any run
    missing = [m for m in DRIFT_METHODS if m not in method_codes(fmu_path)]
    notes = [plan.note] if plan.note else []
    if missing:
        notes.append(f"{', '.join(missing)} not compiled into this FMU (scene methods)")
    notes.insert(0, f"first row: the scene's defaults ({_settings(scene)})")
    return GenericOutcome(
        drifts=conserved_drifts(fmu_path, scene, methods=DRIFT_METHODS, stop_time=T, scene_defaults=True),
        drift_note="; ".join(notes),
    )


def _settings(scene: Scene) -> str:
    """The scene's default method and settings, in words."""
    tol = f"tolerance {scene.tolerance:g} 1/s" if scene.tolerance > 0 else "fixed steps"
    return f"{scene.method}, {tol}" + (f", h_max {scene.h_max:g} s" if scene.h_max > 0 else "")


# The outputs the balances read (rbcheck.checks.balances), per feature.
BALANCE_OUTPUTS = ("q", "w_world", "E_kin", "E_total")


@generic_check("input balances")
def balance_check(fmu_path: Path, scene: Scene, quick: bool) -> GenericOutcome:
    """The balances of rbcheck.checks.balances for a scene whose inputs, forces, friction or
    moving pivot do work, on a run with its default method and settings over the check
    horizon (a scene with a check of its own measures them there)."""
    if scene.has("gravity_gradient"):
        raise NotApplicable(
            "in an orbit the gravity-gradient torque does work and turns L_world, which these balances do not count; "
            "the Jacobi integral E_jacobi of the orbit's checks holds instead (docs/theory.md §9.3)"
        )
    if not (scene.input_names or scene.has("friction") or scene.has("moving_pivot")):
        raise NotApplicable(
            "the scene has no inputs, friction or moving pivot that do work: there is no work to balance"
        )
    if has_specific_check(scene):
        raise NotApplicable(f"the check registered for {scene.name!r} measures its balances itself")
    if any(r.speed for r in scene.rotors.values()):
        raise NotApplicable(
            "speed-mode rotors: the balances hold the inputs over each step, and a rotor rate held with its "
            "derivative is not a motion (docs/theory.md §8.5)"
        )
    if any(r.mode == "command" for r in scene.rotors.values()):
        raise NotApplicable(
            "command-mode rotors: their motor power u Omega has u an output, which the balances (built on the "
            "inputs' power) do not read; their world angular momentum is checked in tests (docs/theory.md §8.8)"
        )
    moving = scene.has("translation") or scene.has("moving_pivot")
    potential = scene.has("gravity") or scene.has("central_gravity")
    need = [o for o in BALANCE_OUTPUTS if o != "E_total" or potential]  # E_kin is E without gravity
    need += [*(["p"] if moving else []), *(["L_world"] if scene.has("translation") else [])]
    need += ["f_pivot", "a_cm"] if scene.has("moving_pivot") else []
    missing = [o for o in need if o not in scene.outputs]
    if missing:
        raise NotApplicable(f"the balances need the outputs {', '.join(missing)}; add them to the scene's outputs")
    rows = halved_balance_rows(fmu_path, scene, horizon(scene, quick), prefix="")
    note = (
        f"balances: rbcheck.checks.balances (Simpson per step) at the scene's defaults ({_settings(scene)}), "
        "at its step H and at H/2 (judged: the quadrature's residual falls 16-fold)"
    )
    return GenericOutcome(rows=rows, note=note)
