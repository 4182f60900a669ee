"""A controller designed on a linear model and run through the FMU: the discrete LQR of reaction_wheel_slew.

The design uses only this package's API: the step map of one communication step
(H = 0.1 s, rk8) at the target attitude with the body and wheels at rest, in attitude-error
coordinates; the wheel rates are left out (`LinearModel.select`: at rest they do not act on
the attitude and the body rate, so the smaller model is exact to first order); the
discrete algebraic Riccati equation (scipy) gives the gain K of u[k] = −K z[k], z = (δθ, ω),
which the importer applies at every communication point from the FMU's outputs q and
w_body, held over the step (fmu.drive.run.run_fmu's input_fn). Discrete because the loop is:
the step map is the exact sampled-data plant, so the closed loop's eigenvalues are those
of Φ − Γ K (docs/user_guide.md §6.4).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.linalg

from modelsrc.scene import Scene, load_scene

from .attitude import ATTITUDE, RATE, attitude_error
from .linear_model import LinearModel
from .operating_point import start_point
from .step_map import step_map

# Bryson's rule (Bryson & Ho, "Applied Optimal Control", §5.7): Q and R the inverse squares
# of the largest acceptable attitude error (rad), body rate (rad/s) and motor torque (N m).
THETA_MAX, RATE_MAX, TORQUE_MAX = 0.1, 0.05, 0.5
TARGET = np.array([1.0, 0.0, 0.0, 0.0])


@dataclass(frozen=True)
class Design:
    """K (3 × 6, N m per rad and per rad/s), the plant Φ, Γ (z = (δθ, ω)), the closed
    loop's eigenvalues z_i of Φ − Γ K and their continuous rates ln(z_i)/H (1/s)."""

    K: np.ndarray
    plant: LinearModel
    closed_loop: np.ndarray
    rates: np.ndarray


def design(fmu: str | Path, scene: Scene | None = None) -> Design:
    """The discrete LQR of the slew at the target attitude (module docstring)."""
    scene = scene or load_scene("reaction_wheel_slew")
    point = start_point(fmu, {"q[1]": 1.0, "q[2]": 0.0, "q[3]": 0.0, "q[4]": 0.0})
    full = step_map(scene, point, scene.step, method="rk8")
    plant = full.select(states=[*ATTITUDE, *RATE], outputs=[*ATTITUDE, *RATE])
    Q = np.diag([THETA_MAX**-2] * 3 + [RATE_MAX**-2] * 3)
    R = np.diag([TORQUE_MAX**-2] * 3)
    Phi, Gamma = plant.A, plant.B
    P = scipy.linalg.solve_discrete_are(Phi, Gamma, Q, R)
    K = np.linalg.solve(R + Gamma.T @ P @ Gamma, Gamma.T @ P @ Phi)
    zs = np.linalg.eigvals(Phi - Gamma @ K)
    return Design(K, plant, zs, np.log(zs.astype(complex)) / scene.step)


def controller(K: np.ndarray, inputs: tuple[str, ...]):
    """input_fn(t, outputs) -> the motor torques u = −K (δθ, ω), δθ = 2 vec(q_d* ⊗ q)."""

    def law(t: float, y) -> dict[str, float]:
        q = np.array([y[f"q[{k}]"] for k in (1, 2, 3, 4)])
        w = np.array([y[n] for n in RATE])
        u = -K @ np.concatenate((attitude_error(TARGET, q), w))
        return dict(zip(inputs, map(float, u)))

    return law


def attitude_angle(q: np.ndarray) -> np.ndarray:
    """The rotation angle (rad) of each row q from the target (the identity)."""
    return 2.0 * np.arctan2(np.linalg.norm(q[:, 1:], axis=1), np.abs(q[:, 0]))


def run(fmu: str | Path, scene: Scene | None = None) -> dict[str, float]:
    """The designed loop closed around the FMU over the scene's run: final attitude error
    (rad), the first time it stays below 1 mrad (s), the largest motor torque (N m), wheel
    rate (rad/s) and |L_world| (N m s), and the slowest closed-loop rate (1/s)."""
    from ..drive.run import run_fmu

    scene = scene or load_scene("reaction_wheel_slew")
    d = design(fmu, scene)
    res = run_fmu(fmu, scene, input_fn=controller(d.K, d.plant.inputs))
    angle = attitude_angle(res.vector("q"))
    above = np.nonzero(angle >= 1e-3)[0]
    settle = float(res.time[above[-1] + 1]) if len(above) and above[-1] + 1 < len(angle) else float("nan")
    z = np.hstack((np.array([attitude_error(TARGET, q) for q in res.vector("q")]), res.vector("w_body")))
    torque = np.abs(z @ d.K.T).max()
    wheels = max(np.abs(res.values[f"Omega_abs_{n}"] - res.vector("w_body")[:, k]).max()
                 for k, n in enumerate(scene.rotors))  # fmt: skip
    return {
        "final_angle": float(angle[-1]),
        "settle_1mrad": settle,
        "max_torque": float(torque),
        "max_wheel_rate": float(wheels),
        "max_L_world": float(np.abs(res.vector("L_world")).max()),
        "slowest_rate": float(np.max(d.rates.real)),
    }
