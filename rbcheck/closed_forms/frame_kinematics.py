"""The two-frame arm of MIT 2.003J (notation handout §6), in closed form.

Upper arm A turns at Ω about the vertical J of the body frame B; the forearm F turns at
ω about the upper-arm axis i_A. With ^A r_F = L i_A and ^F r_W = l i_F the wrist has

  v_W = Ω J × L i_A + (Ω J + ω i_A) × l i_F,
  a_W = Ω J × (Ω J × L i_A) + (Ω J × ω i_A) × l i_F + (Ω J + ω i_A) × ((Ω J + ω i_A) × l i_F)

(handout §6, "Solution"). numpy only; no code shared with modelsrc.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray


def _rot(axis: NDArray[np.float64], angle: float) -> NDArray[np.float64]:
    """Rodrigues: right-handed rotation by `angle` (rad) about unit `axis`."""
    k = axis / np.linalg.norm(axis)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * (K @ K)


def arm_wrist(
    t: ArrayLike, Omega: float, omega: float, L: float, l: float, J: ArrayLike, i_A0: ArrayLike, i_F0: ArrayLike
) -> dict[str, NDArray[np.float64]]:
    """Wrist position, velocity, acceleration (m, m/s, m/s²; frame B) over times t (s).

    J: unit vertical of B; i_A0, i_F0: upper-arm and forearm directions at t = 0 (unit).
    The upper arm turns about J by Ωt; the forearm additionally about i_A by ωt.
    """
    t = np.atleast_1d(np.asarray(t, dtype=float))
    J = np.asarray(J, float)
    i_A0, i_F0 = np.asarray(i_A0, float), np.asarray(i_F0, float)
    r, v, a = (np.empty((len(t), 3)) for _ in range(3))
    for k, tk in enumerate(t):
        RA = _rot(J, Omega * tk)
        i_A = RA @ i_A0
        i_F = RA @ _rot(i_A0, omega * tk) @ i_F0  # about i_A in the arm's frame, then with the arm
        wA, wF = Omega * J, Omega * J + omega * i_A
        r[k] = L * i_A + l * i_F
        v[k] = np.cross(wA, L * i_A) + np.cross(wF, l * i_F)
        a[k] = (
            np.cross(wA, np.cross(wA, L * i_A))
            + np.cross(np.cross(wA, omega * i_A), l * i_F)
            + np.cross(wF, np.cross(wF, l * i_F))
        )
    return {"r": r, "v": v, "a": a}
