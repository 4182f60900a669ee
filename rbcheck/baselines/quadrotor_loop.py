"""scipy baseline of the quadrotor_hover system: the sampled-data loop of a quadrotor with lagged motors and its law.

Independent of the FMUs (nothing from ``modelsrc`` or ``fmu``; the plant and the law are
passed as numbers). The plant (docs/theory.md §8.1, §8.6, §8.8) written again in numpy, state
y = (q, ω, x, v, Ω_1 … Ω_4): q unit quaternion body -> world (scalar first), ω body angular
velocity (rad/s), x, v the centre of mass (m, m/s, world), Ω_i rotor i's rate relative to the
body about body +z (rad/s); I the whole body's inertia (rotors included, kg·m²), J the rotors'
axial inertia, r_i their positions (m, body), k_f, k_m the thrust and drag coefficients:

    q̇ = ½ q ⊗ (0, ω),   Ω̇_i = (Ω_cmd,i − Ω_i) / τ_m,   ẋ = v,   m v̇ = R Σ k_f Ω_i² e_3 + m g
    I ω̇ = Σ (r_i × k_f Ω_i² e_3 − k_m Ω_i|Ω_i| e_3) − ω × (I ω + Σ J Ω_i e_3) − Σ J Ω̇_i e_3

The law (docs/theory.md §12.2, Lee, Leok, McClamroch 2010 without feed-forward), evaluated at
each sample t_k = k T_s from the plant's state there: a = (k_pxy (x_d − x) − k_dxy v)_{1,2},
a_3 = k_pz (x_d,3 − x_3) − k_dz v_3 + k_iz e, F = m (a − g), R_d from b3_d = F/|F| and the yaw
ψ_d, e_R = ½ vee(R_dᵀ R − Rᵀ R_d), τ = I (−K_R e_R − K_w ω), T = F · R e_3; the mixer solves
(T, τ) = Σ (1, r_i × e_3 − s_i (k_m/k_f) e_3) f_i, clips f_i to [0, k_f Ω_max²], and
Ω_cmd,i = s_i √(f_i/k_f); the height integral e_{k+1} = e_k + T_s (x_d,3 − x_3).

The loop is the one the Jacobi masters (ECOS, libcosim) run: the controller's output computed
at sample j reaches the plant one sample late, so over [t_k, t_{k+1}] the plant holds
Ω_cmd = law(y_{max(k−1, 0)}) (one sample of delay; at k = 0 the law of the start).
Between samples ``solve_ivp`` (DOP853) integrates the plant from the state at t_k.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from ..numerics.rotation_np import quat_to_matrix

E3 = np.array([0.0, 0.0, 1.0])


@dataclass(frozen=True)
class Quadrotor:
    """The plant's numbers: mass (kg), inertia (3×3, kg·m², rotors included), gravity (m/s²,
    world), the rotors' axial inertia J (kg·m²), time constant τ_m (s), positions (4×3 m,
    body), k_f (N·s²), k_m (N·m·s²); every rotor axis is body +z."""

    mass: float
    inertia: np.ndarray
    gravity: np.ndarray
    J: float
    tau_m: float
    positions: np.ndarray
    k_f: float
    k_m: float

    def rhs(self, t: float, y: np.ndarray, cmd: np.ndarray) -> np.ndarray:
        """dy/dt with the commands `cmd` (4, rad/s) held (scalar arithmetic: scipy calls it ~10⁵ times)."""
        q0, q1, q2, q3 = y[0:4]
        wx, wy, wz = y[4:7]
        Om = y[13:17]
        Om_dot = (cmd - Om) / self.tau_m
        f = self.k_f * Om**2
        # the thrust moments Σ r_i × f_i e_3 = Σ f_i (r_y, −r_x, 0)_i; the drag and the reactions along e_3
        tx, ty = float(self.positions[:, 1] @ f), float(-self.positions[:, 0] @ f)
        tz = -self.k_m * float(np.sum(Om * np.abs(Om))) - self.J * float(np.sum(Om_dot))
        L = self.inertia @ y[4:7]
        Lz = L[2] + self.J * float(np.sum(Om))  # + h = Σ J Ω_i e_3
        gyro = (wy * Lz - wz * L[1], wz * L[0] - wx * Lz, wx * L[1] - wy * L[0])  # ω × (I ω + h)
        w_dot = np.linalg.solve(self.inertia, (tx - gyro[0], ty - gyro[1], tz - gyro[2]))
        q_dot = 0.5 * np.array([-q1 * wx - q2 * wy - q3 * wz, q0 * wx + q2 * wz - q3 * wy,
                                q0 * wy + q3 * wx - q1 * wz, q0 * wz + q1 * wy - q2 * wx])  # fmt: skip
        a = float(np.sum(f)) / self.mass  # along body e_3 = R's third column (unit q)
        b3 = (2 * (q1 * q3 + q0 * q2), 2 * (q2 * q3 - q0 * q1), 1 - 2 * (q1 * q1 + q2 * q2))
        v_dot = a * np.array(b3) + self.gravity
        return np.concatenate((q_dot, w_dot, y[10:13], v_dot, Om_dot))


@dataclass(frozen=True)
class HoverLaw:
    """The controller's numbers: gains (dict of k_pxy, k_dxy, k_pz, k_dz, k_iz, k_R, k_w, k_Rz,
    k_wz), the largest rotor speed (rad/s), the target position (m, world) and yaw (rad), the
    sample period (s), the rotors' spin signs s_i."""

    gains: dict[str, float]
    omega_max: float
    x_d: np.ndarray
    yaw: float
    Ts: float
    spin: np.ndarray

    def commands(self, plant: Quadrotor, y: np.ndarray, e_int: float) -> np.ndarray:
        """Ω_cmd (4, rad/s) from the plant's state y and the height integral e_int (m·s)."""
        k = self.gains
        q, w, x, v = y[0:4], y[4:7], y[7:10], y[10:13]
        a = np.array([k["k_pxy"] * (self.x_d[0] - x[0]) - k["k_dxy"] * v[0],
                      k["k_pxy"] * (self.x_d[1] - x[1]) - k["k_dxy"] * v[1],
                      k["k_pz"] * (self.x_d[2] - x[2]) - k["k_dz"] * v[2] + k["k_iz"] * e_int])  # fmt: skip
        F = plant.mass * (a - plant.gravity)
        b3 = F / np.linalg.norm(F)
        b2 = np.cross(b3, [np.cos(self.yaw), np.sin(self.yaw), 0.0])
        b2 /= np.linalg.norm(b2)
        Rd = np.column_stack((np.cross(b2, b3), b2, b3))
        R = quat_to_matrix(q)
        E = 0.5 * (Rd.T @ R - R.T @ Rd)
        e_R = np.array([E[2, 1], E[0, 2], E[1, 0]])
        tau = plant.inertia @ (-np.array([k["k_R"], k["k_R"], k["k_Rz"]]) * e_R
                               - np.array([k["k_w"], k["k_w"], k["k_wz"]]) * w)  # fmt: skip
        mixer = np.vstack([np.ones(4), np.column_stack([np.cross(plant.positions[i], E3)
                                                        - self.spin[i] * plant.k_m / plant.k_f * E3
                                                        for i in range(4)])])  # fmt: skip
        f = np.linalg.solve(mixer, np.concatenate(([F @ R[:, 2]], tau)))
        f = np.clip(f, 0.0, plant.k_f * self.omega_max**2)
        return self.spin * np.sqrt(f / plant.k_f)


def delayed_loop(plant: Quadrotor, law: HoverLaw, y0: np.ndarray, n: int, rtol: float = 1e-12,
                 atol: float = 1e-13) -> np.ndarray:  # fmt: skip
    """The state at t_k = k T_s, k = 0 … n ((n+1)×17): the loop of the module docstring, the
    plant integrated by DOP853 at rtol, atol between samples with the delayed command held."""
    ys = np.empty((n + 1, 17))
    ys[0] = y0
    e_int = 0.0
    cmd_prev = law.commands(plant, y0, e_int)  # what the controller holds from init
    for k in range(n):
        cmd_now = law.commands(plant, ys[k], e_int)  # computed at t_k, reaches the plant at t_{k+1}
        e_int += law.Ts * (law.x_d[2] - ys[k][9])
        sol = solve_ivp(plant.rhs, (0.0, law.Ts), ys[k], method="DOP853", rtol=rtol, atol=atol, args=(cmd_prev,))
        if not sol.success:
            raise RuntimeError(f"solve_ivp failed on the sample interval {k}: {sol.message}")
        ys[k + 1] = sol.y[:, -1]
        cmd_prev = cmd_now
    return ys
