"""Closed-loop rest-to-rest slew with reaction wheels: an importer's PD law and its exact sampled-data reference.

The loop (docs/user_guide.md, "Closing a loop around the FMU"): at every communication
point the importer reads the attitude q (body -> world, scalar first) and the body rate ω
(rad/s, body), computes the body torque of a PD law on the attitude error and the motor
torques u that make the wheels apply it, and holds u over the step (zero-order hold).

With the error quaternion q_e = q_d* ⊗ q (body frame; q_d the target), the wanted body
torque is τ_c = −I_r (k_p sgn(q_e0) q_e,vec + k_d ω), I_r = I − Σ J g gᵀ the inertia the
wheels push against (docs/theory.md §8.1). The body feels −Σ g_i u_i, so with the wheel
axes as columns of G, u = −G⁻¹ τ_c (Wie, "Space Vehicle Dynamics and Control", §7.3: the
quaternion-feedback PD law, globally stable for rest-to-rest slews).

Exact reference (docs/theory.md §8.4): starting at rest with the wheels at rest, the total
angular momentum is 0, so I ω + h = 0 and the gyroscopic term ω × (I ω + h) vanishes; the
body equation is I_r ω̇ = τ_c = −I_r (k_p sin(φ/2) n + k_d ω) for a slew of angle φ about
the eigenaxis n, so the body turns about n alone and, with u held over each step, ω̇ is
constant over the step: φ_{k+1} = φ_k + φ̇_k H + a_k H²/2, φ̇_{k+1} = φ̇_k + a_k H,
a_k = −k_p sin(φ_k/2) − k_d φ̇_k. That recursion is the exact sampled-data solution, which
`eigenaxis_reference` evaluates: no integration error, so the FMU is compared with it to
its own error alone.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..numerics.rotation_np import quat_conj, quat_mul

__all__ = ["SLEW_GAINS", "PDSlew", "eigenaxis_reference", "open_loop_torques", "slew_law"]

# k_p (1/s²), k_d (1/s) of reaction_wheel_slew's loop: ω_n = sqrt(k_p/2) = 0.5 rad/s,
# critically damped (k_d² = 2 k_p)
SLEW_GAINS = (0.5, 1.0)


@dataclass(frozen=True)
class PDSlew:
    """The PD slew law of the module docstring, as an importer's input function.

    I_r: the inertia the wheels push against, I − Σ J g gᵀ (kg·m², body); G: the wheel axes
    as columns (body, invertible); names: the wheels, in G's column order; q_d: target
    attitude (body -> world, scalar first); k_p (1/s²), k_d (1/s): the gains (critically
    damped for small errors when k_d² = 2 k_p: φ̈ = −k_p φ/2 − k_d φ̇)."""

    I_r: NDArray
    G: NDArray
    names: tuple[str, ...]
    q_d: NDArray
    k_p: float
    k_d: float

    def body_torque(self, q: NDArray, w: NDArray) -> NDArray:
        """τ_c (N·m, body) at attitude q and body rate w (rad/s)."""
        qe = quat_mul(quat_conj(self.q_d), q)
        sgn = 1.0 if qe[0] >= 0.0 else -1.0  # the shorter way round
        return -self.I_r @ (self.k_p * sgn * qe[1:] + self.k_d * np.asarray(w, dtype=float))

    def __call__(self, t: float, outputs: Mapping[str, float]) -> dict[str, float]:
        """fmu.drive.run's input_fn: outputs 'q[1..4]', 'w_body[1..3]' -> {'u_<name>': N·m}."""
        q = np.array([outputs[f"q[{k}]"] for k in (1, 2, 3, 4)])
        w = np.array([outputs[f"w_body[{k}]"] for k in (1, 2, 3)])
        u = -np.linalg.solve(self.G, self.body_torque(q, w))
        return {f"u_{n}": float(x) for n, x in zip(self.names, u)}


def slew_law(scene, k_p: float, k_d: float, q_d: NDArray | None = None) -> PDSlew:
    """The PD law for a scene with rotors (modelsrc.scene.Scene): I_r and G from its inertia
    and rotors (three with independent axes), target q_d (default the identity)."""
    if len(scene.rotors) != 3:
        raise ValueError(f"the slew law needs three wheels, the scene has {len(scene.rotors)}")
    G = np.column_stack([r.axis for r in scene.rotors.values()])
    I_r = np.asarray(scene.inertia, dtype=float) - sum(r.J * np.outer(r.axis, r.axis) for r in scene.rotors.values())
    qd = np.array([1.0, 0.0, 0.0, 0.0]) if q_d is None else np.asarray(q_d, dtype=float)
    return PDSlew(I_r, G, tuple(scene.rotors), qd, float(k_p), float(k_d))


def eigenaxis_reference(phi0: float, k_p: float, k_d: float, H: float, n: int) -> tuple[NDArray, NDArray]:
    """(φ (n+1,) rad, φ̇ (n+1,) rad/s) at the communication points kH of the sampled-data
    eigenaxis slew from rest at φ0 (module docstring; exact for u held over each step)."""
    phi, dphi = np.empty(n + 1), np.empty(n + 1)
    phi[0], dphi[0] = phi0, 0.0
    for k in range(n):
        a = -k_p * math.sin(0.5 * phi[k]) - k_d * dphi[k]
        phi[k + 1] = phi[k] + dphi[k] * H + 0.5 * a * H * H
        dphi[k + 1] = dphi[k] + a * H
    return phi, dphi


def open_loop_torques(scene, k_p: float, k_d: float, H: float, n: int) -> dict[str, NDArray]:
    """The PD loop's motor torques as tables for an open-loop run of `scene` (start at rest,
    wheels at rest, target the identity): rows [t_k, u_k] (s, N·m), k = 0 … n−1, u_k the law
    at the exact sampled-data state (`eigenaxis_reference`: φ_k, φ̇_k about the start's axis
    n), so that every integrator fed them sees the loop's inputs without closing it (the
    report's batch mode, whose inputs are known in advance)."""
    law = slew_law(scene, k_p, k_d)
    v0 = np.asarray(scene.q0[1:], dtype=float)
    axis = v0 / np.linalg.norm(v0)
    phi0 = 2.0 * math.atan2(float(np.linalg.norm(v0)), float(scene.q0[0]))
    phi, dphi = eigenaxis_reference(phi0, k_p, k_d, H, n)
    t = np.round(np.arange(n) * H, 12)
    rows = []
    for p, d in zip(phi[:n], dphi[:n]):
        q = [math.cos(0.5 * p), *(math.sin(0.5 * p) * axis)]
        out = {f"q[{i + 1}]": float(x) for i, x in enumerate(q)}
        out.update({f"w_body[{i + 1}]": float(x) for i, x in enumerate(d * axis)})
        rows.append(list(law(0.0, out).values()))
    U = np.array(rows)
    return {f"u_{name}": np.column_stack([t, U[:, j]]) for j, name in enumerate(law.names)}
