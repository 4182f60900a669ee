r"""Work, momentum and angular-momentum balances of a moving body's inputs, measured on its FMU.

The exact balances of a body whose reference point moves (docs/theory.md §7), each
integrated over every communication step with Simpson's rule on the FMU's own outputs:

* work: E_total(t) − E_total(0) = ∫ P dt, P the power of all inputs: a force F (world)
  at a body point r contributes F · (v_cm + ω × R r) (MIT 2.003J: v = v_B + ω × r), a
  torque τ contributes τ · ω, friction −c |ω|², a moving pivot f_pivot · v_pivot
  (gravity, uniform or central, is in E_total's potential), a rotor's motor u Ω with Ω its rate RELATIVE to the
  body (docs/theory.md §8.2: the motor torque +u g on the rotor and −u g on the body do the
  work u g·(ω + Ω g) − u g·ω = u Ω; E includes the rotors');
* linear momentum (free body, and a top on a moving pivot, whose pivot force f_pivot is
  then one of the forces): p(t) − p(0) = ∫ (Σ F + M g) dt, Σ F with the central field's
  force (docs/theory.md §9.7), and τ below with its gravity-gradient torque;
* angular momentum about the centre of mass (free body), or about the fixed point of a
  body turning without gravity: L(t) − L(0) = ∫ Σ (R r × F + τ) dt; L_world includes the
  rotors' momentum and the motor torques, internal, drop out (§8.1);
* the pivot force at every sample (moving pivot): f_pivot = M (a_cm − g).

Every balance holds for any scene with these features, so :func:`balances` serves the
shipped scenes' checks and the generic check of any scene file (rbcheck.checks.generic).

:func:`held_run` drives the FMU with the scene's inputs held over each communication
step [t_k, t_k + H] (their mean there, ``Scene.input_mean``) and reads the outputs at
t_k just after setting the step's input, at t_k + H/2 and at t_k + H just before the
next input: the integrand is smooth on each step (the inputs jump only between steps),
so Simpson's rule per step errs by H⁵ |P⁗|/2880. Units SI.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from fmu.drive.instance import FmuInstance
from modelsrc.scene import Scene
from modelsrc.scene_inputs import component_names, input_width

from ..baselines.motion import central_field
from ..baselines.rigid_body import comm_grid
from ..numerics.rotation_np import quat_to_matrix

__all__ = ["Balances", "HeldRun", "balances", "held_run"]


@dataclass
class HeldRun:
    """Outputs of a held-input run: grid (n+1,) s; start[k], mid[k], end[k]: output name
    -> value at t_k (after setting input k), t_k + H/2 and t_{k+1} (before input k+1);
    inputs[name]: (n, width) the input held over each step (width 3, or 1 for a rotor's u)."""

    grid: NDArray
    start: dict[str, NDArray]
    mid: dict[str, NDArray]
    end: dict[str, NDArray]
    inputs: dict[str, NDArray]

    def simpson(self, f: dict[str, NDArray]) -> NDArray:
        """Cumulative ∫ of an integrand given as {"start", "mid", "end"} -> (n, ...) arrays
        over the steps: (n+1, ...) values at the grid points, 0 at t_0."""
        H = np.diff(self.grid).reshape((-1,) + (1,) * (f["start"].ndim - 1))
        steps = H / 6.0 * (f["start"] + 4.0 * f["mid"] + f["end"])
        return np.concatenate([np.zeros((1,) + steps.shape[1:]), np.cumsum(steps, axis=0)])


def held_run(
    fmu_path: str | Path, scene: Scene, stop_time: float, step: float | None = None, start_values=None
) -> HeldRun:
    """Run the scene's FMU over [0, stop_time] s with communication step `step` (default
    the scene's), every input held at its mean over each step, sampling each step at its
    start, middle and end (see the module docstring)."""
    H = scene.step if step is None else float(step)
    grid = comm_grid(scene, stop_time, H)
    in_names = scene.input_names
    with FmuInstance(fmu_path) as inst:
        outs = [v.name for v in inst.md.modelVariables if v.causality == "output"]
        vrs = inst.value_references(outs)
        in_vrs = inst.value_references([c for n in in_names for c in component_names(n)])
        inst.set(dict(start_values or {}))
        inst.initialize(0.0, stop_time)
        rows: dict[str, list[list[float]]] = {"start": [], "mid": [], "end": []}
        held: list[NDArray] = []
        for t0, t1 in itertools.pairwise(grid):
            u = np.concatenate([scene.input_mean(n, t0, t1) for n in in_names]) if in_names else np.zeros(0)
            if in_names:
                inst.set_float64(in_vrs, list(u))
            held.append(u)
            rows["start"].append(inst.get_float64(vrs))
            inst.step(t0, 0.5 * (t1 - t0))
            rows["mid"].append(inst.get_float64(vrs))
            inst.step(t0 + 0.5 * (t1 - t0), 0.5 * (t1 - t0))
            rows["end"].append(inst.get_float64(vrs))
    U = np.asarray(held).reshape(len(grid) - 1, -1)

    def split(rs: list[list[float]]) -> dict[str, NDArray]:
        Y = np.asarray(rs)
        out: dict[str, NDArray] = {}
        for j, name in enumerate(outs):
            base, _, idx = name.partition("[")
            if idx:
                out.setdefault(base, np.empty((len(Y), 0)))
                out[base] = np.column_stack([out[base], Y[:, j]])
            else:
                out[name] = Y[:, j]
        return out

    ends = np.cumsum([0] + [input_width(n) for n in in_names])
    inputs = {n: U[:, ends[i] : ends[i + 1]] for i, n in enumerate(in_names)}
    return HeldRun(grid, split(rows["start"]), split(rows["mid"]), split(rows["end"]), inputs)


@dataclass
class Balances:
    """Largest residual over the run of each balance: work [J] (scale: the largest
    E_kin), linear momentum [N s] and angular momentum [N m s] about the centre of mass
    (nan where not applicable), and the work done by the inputs [J] over the run."""

    work: float
    momentum: float
    angular_momentum: float
    work_done: float
    E_scale: float
    pivot_force: float = float("nan")  # max |f_pivot − M (a_cm − g)| [N] over the samples (moving pivot)
    p_scale: float = float("nan")  # the largest |p| and |impulse| [N s] (the momentum balance's size)
    L_scale: float = float("nan")  # the largest |L_world| and |angular impulse| [N m s]
    f_scale: float = float("nan")  # the largest |f_pivot| [N]


def _forces(
    scene: Scene, run: HeldRun, y: dict[str, NDArray], motor_power: bool = True
) -> tuple[NDArray, NDArray, NDArray]:
    """(Σ F world (n, 3) N, Σ torque world about the centre of mass (n, 3) N m, input
    power (n,) W) at one sample of each step (y = run.start, run.mid or run.end);
    motor_power False leaves the rotors' motor power out (only to show that the balance
    then fails)."""
    R = quat_to_matrix(y["q"])
    w = y["w_world"]
    n = len(R)
    F, tau, P = np.zeros((n, 3)), np.zeros((n, 3)), np.zeros(n)
    v_cm = y.get("v_cm", np.zeros((n, 3)))
    for name, r_body, frame in [("f_body", np.zeros(3), "body"), ("f_world", np.zeros(3), "world")] + [
        (f"f_{p}", fp.point, fp.frame) for p, fp in scene.force_points.items()
    ]:
        if name not in run.inputs:
            continue
        f = run.inputs[name]
        f_w = np.einsum("nij,nj->ni", R, f) if frame == "body" else f
        r_w = R @ r_body
        F += f_w
        tau += np.cross(r_w, f_w)
        P += np.einsum("ni,ni->n", f_w, v_cm + np.cross(w, r_w))  # F · (v_cm + ω × r)
    for name in ("tau_body", "tau_world"):
        if name in run.inputs:
            t_w = np.einsum("nij,nj->ni", R, run.inputs[name]) if name == "tau_body" else run.inputs[name]
            tau += t_w
            P += np.einsum("ni,ni->n", t_w, w)
    if scene.has("friction"):
        tau += -scene.c_friction * w
        P += -scene.c_friction * np.einsum("ni,ni->n", w, w)
    if scene.has("moving_pivot"):
        P += np.einsum("ni,ni->n", y["f_pivot"], y["v_pivot"])
    if scene.has("central_gravity"):  # its force and torque; its power is in E_total's potential (§9.7)
        I = np.asarray(scene.inertia, dtype=float)
        for k in range(n):
            F_c, tau_c = central_field(scene.mu, float(scene.mass), I, R[k], y["x_cm"][k])
            F[k] += F_c
            tau[k] += R[k] @ tau_c
    if motor_power:
        for name in (n for n, r in scene.rotors.items() if not r.speed):  # u Ω_rel (docs/theory.md §8.2)
            P += run.inputs[f"u_{name}"][:, 0] * y[f"Omega_{name}"]
    return F, tau, P


def balances(scene: Scene, run: HeldRun, motor_power: bool = True) -> Balances:
    """The work, momentum and angular-momentum balances of a held run (module docstring).
    E is E_total, or E_kin without gravity (then the same); the angular-momentum balance
    needs the output L_world (nan without it). motor_power: see `_forces`."""
    parts = {k: _forces(scene, run, getattr(run, k), motor_power) for k in ("start", "mid", "end")}
    W = run.simpson({k: v[2] for k, v in parts.items()})
    key = "E_total" if "E_total" in run.start or scene.has("gravity") else "E_kin"
    E = np.concatenate([run.start[key][:1], run.end[key]])
    E_scale = float(np.max(np.abs(np.concatenate([run.start["E_kin"], run.end["E_kin"]]))))
    work = float(np.max(np.abs(E - E[0] - W)))
    mom = ang = pivot = p_scale = L_scale = f_scale = float("nan")
    g = np.asarray(scene.g, dtype=float) if scene.has("gravity") else np.zeros(3)
    M = float(scene.mass)
    pivot_force = scene.has("moving_pivot")
    if scene.has("translation") or pivot_force:
        imp = run.simpson(
            {k: v[0] + M * g + (getattr(run, k)["f_pivot"] if pivot_force else 0.0) for k, v in parts.items()}
        )
        p = np.vstack([run.start["p"][:1], run.end["p"]])
        mom = float(np.max(np.linalg.norm(p - p[0] - imp, axis=1)))
        p_scale = float(max(np.max(np.linalg.norm(p, axis=1)), np.max(np.linalg.norm(imp, axis=1))))
    fixed_point = not scene.features & {"gravity", "moving_pivot", "prescribed_rate"}  # no unlisted torque
    if "L_world" in run.start and (scene.has("translation") or fixed_point):
        ang_imp = run.simpson({k: v[1] for k, v in parts.items()})
        L = np.vstack([run.start["L_world"][:1], run.end["L_world"]])
        ang = float(np.max(np.linalg.norm(L - L[0] - ang_imp, axis=1)))
        L_scale = float(max(np.max(np.linalg.norm(L, axis=1)), np.max(np.linalg.norm(ang_imp, axis=1))))
    if pivot_force and "a_cm" in run.start:
        pivot = max(float(np.max(np.abs(y["f_pivot"] - M * (y["a_cm"] - g)))) for y in (run.start, run.mid, run.end))
        f_scale = max(float(np.max(np.abs(y["f_pivot"]))) for y in (run.start, run.mid, run.end))
    return Balances(work, mom, ang, float(W[-1]), E_scale, pivot, p_scale, L_scale, f_scale)
