"""Inertia tensors (docs/theory.md §3).

All tensors are 3×3 in kg·m², expressed in the body frame, about the point the
function names (centre of mass unless said otherwise). The defining integral is
I_αβ = ∫ ρ (r² δ_αβ − r_α r_β) dV (lecture notes "Inertia tensor"; Goldstein §5.3).

The validity conditions are written once, symbolically (`inertia_conditions`); the
FMU evaluates the generated C of the same expressions at initialisation, and
`validate_inertia` evaluates them here for scene files.
"""

from __future__ import annotations

from collections.abc import Sequence

import casadi as ca
import numpy as np

from .errors import ModelInputError

# Relative tolerance of the validity conditions: a flat plate exactly at I3 = I1 + I2
# is valid and must pass despite round-off in the sum (docs/theory.md §3.4).
REL_TOL = 1e-12


def point_masses(masses: Sequence[float], positions: Sequence[Sequence[float]]) -> np.ndarray:
    """Inertia (kg·m²) about the origin of point masses (kg) at positions (m, body frame).

    I = Σ m_i (|r_i|² 1 − r_i r_iᵀ)  (lecture notes, discrete form of the inertia tensor).
    """
    m = np.asarray(masses, dtype=float)
    r = np.asarray(positions, dtype=float).reshape(-1, 3)
    if m.shape != (r.shape[0],):
        raise ModelInputError(f"point_masses: {m.size} masses but {r.shape[0]} positions")
    r2 = np.einsum("ij,ij->i", r, r)
    return np.einsum("i,i->", m, r2) * np.eye(3) - np.einsum("i,ij,ik->jk", m, r, r)


def solid_cylinder(mass: float, radius: float, height: float) -> np.ndarray:
    """Solid cylinder about its centre, symmetry axis = body z (kg·m²).

    I11 = I22 = m(3R² + h²)/12, I33 = mR²/2; height 0 gives the thin disc
    I11 = I22 = mR²/4, I33 = mR²/2 of the lecture notes.
    """
    a = mass * (3 * radius**2 + height**2) / 12.0
    return np.diag([a, a, mass * radius**2 / 2.0])


def solid_disc(mass: float, radius: float) -> np.ndarray:
    """Thin solid disc about its centre, axis = body z: diag(mR²/4, mR²/4, mR²/2) (kg·m²)."""
    return solid_cylinder(mass, radius, 0.0)


def thin_rod(mass: float, length: float) -> np.ndarray:
    """Thin rod along body z about its centre: diag(mL²/12, mL²/12, 0) (kg·m²).

    The axial moment is 0, so the tensor is only positive semidefinite: as a body on
    its own it is rejected by `validate_inertia`; it is meant to be summed with others.
    """
    a = mass * length**2 / 12.0
    return np.diag([a, a, 0.0])


def cuboid(mass: float, a: float, b: float, c: float) -> np.ndarray:
    """Solid cuboid with edges a, b, c (m) along body x, y, z, about its centre (kg·m²)."""
    return mass / 12.0 * np.diag([b**2 + c**2, a**2 + c**2, a**2 + b**2])


def solid_sphere(mass: float, radius: float) -> np.ndarray:
    """Solid sphere about its centre: (2/5) m R² 1 (kg·m²)."""
    return 0.4 * mass * radius**2 * np.eye(3)


def parallel_axis_shift(inertia_cm, mass, r):
    """Inertia about a point P given the inertia about the centre of mass.

    I_P = I_cm + m (|r|² 1 − r rᵀ), r = vector from P to the centre of mass (m, body
    frame). Works on numpy arrays and on CasADi SX/MX alike (the heavy top uses it
    symbolically). Parallel-axis theorem, lecture notes "Change of the origin".
    """
    if isinstance(r, (ca.SX, ca.MX)) or isinstance(inertia_cm, (ca.SX, ca.MX)):
        r = ca.reshape(r, 3, 1)
        return inertia_cm + mass * (ca.dot(r, r) * ca.DM.eye(3) - r @ r.T)
    r = np.asarray(r, dtype=float).reshape(3)
    return np.asarray(inertia_cm, dtype=float) + mass * (r @ r * np.eye(3) - np.outer(r, r))


def rotate_inertia(inertia: np.ndarray, rotation: np.ndarray) -> np.ndarray:
    """Express an inertia tensor in a rotated frame: I' = R I Rᵀ.

    `rotation` maps coordinates of the old frame into the new one (v' = R v).
    """
    R = np.asarray(rotation, dtype=float)
    return R @ np.asarray(inertia, dtype=float) @ R.T


def principal_axes(inertia: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Principal moments (ascending, kg·m²) and a right-handed principal frame.

    Returns (moments, R) with R's columns the principal axes in the given frame,
    det R = +1, and Rᵀ I R = diag(moments).
    """
    I = np.asarray(inertia, dtype=float)
    moments, R = np.linalg.eigh(0.5 * (I + I.T))
    if np.linalg.det(R) < 0:
        R[:, 2] = -R[:, 2]
    return moments, R


def inertia_conditions(I: ca.SX, names: Sequence[str]) -> list[tuple[str, ca.SX, bool]]:
    """Validity conditions of an inertia tensor as (text, expression, strict) triples.

    A condition holds when expression > 0 (strict) or ≥ 0 (not strict). `I` is a 3×3
    CasADi matrix, `names` the 9 parameter names of its entries (row major), used in
    the texts. The conditions (docs/theory.md §3.4):
    - symmetry I_ij = I_ji (to REL_TOL·tr I);
    - positive definiteness: Sylvester's leading minors > 0;
    - the triangle inequality I_i + I_j ≥ I_k of the principal moments, which holds iff
      J = tr(I)/2·1 − I = ∫ρ r rᵀ dV is positive semidefinite: all its principal
      minors ≥ −REL_TOL·tr(I)^k.
    """
    n = lambda i, j: names[3 * i + j]
    tr = I[0, 0] + I[1, 1] + I[2, 2]
    conds: list[tuple[str, ca.SX, bool]] = []
    for i, j in ((0, 1), (0, 2), (1, 2)):
        conds.append(
            (
                f"inertia must be symmetric: {n(i, j)} = {n(j, i)}",
                REL_TOL * ca.fabs(tr) - ca.fabs(I[i, j] - I[j, i]),
                False,
            )
        )
    Is = 0.5 * (I + I.T)
    conds.append((f"inertia must be positive definite: {n(0, 0)} > 0", Is[0, 0], True))
    conds.append(
        ("inertia must be positive definite: leading 2x2 minor > 0", Is[0, 0] * Is[1, 1] - Is[0, 1] ** 2, True)
    )
    conds.append(("inertia must be positive definite: det(I) > 0", ca.det(Is), True))
    J = 0.5 * tr * ca.DM.eye(3) - Is
    for k in range(3):
        conds.append(
            (
                f"principal moments must satisfy I_i + I_j >= I_k (diagonal {k + 1} of tr(I)/2 - I >= 0)",
                J[k, k] + REL_TOL * tr,
                False,
            )
        )
    for i, j in ((0, 1), (0, 2), (1, 2)):
        conds.append(
            (
                f"principal moments must satisfy I_i + I_j >= I_k (minor {i + 1}{j + 1} of tr(I)/2 - I >= 0)",
                J[i, i] * J[j, j] - J[i, j] ** 2 + REL_TOL * tr**2,
                False,
            )
        )
    conds.append(
        ("principal moments must satisfy I_i + I_j >= I_k (det(tr(I)/2 - I) >= 0)", ca.det(J) + REL_TOL * tr**3, False)
    )
    return conds


_FULL_NAMES = [f"I[{i},{j}]" for i in range(1, 4) for j in range(1, 4)]


def _conditions_function() -> tuple[ca.Function, list[tuple[str, bool]]]:
    I = ca.SX.sym("I", 3, 3)
    conds = inertia_conditions(I, _FULL_NAMES)
    f = ca.Function("inertia_conditions", [I], [ca.vertcat(*[c[1] for c in conds])])
    return f, [(c[0], c[2]) for c in conds]


_COND_FUN, _COND_META = _conditions_function()


def validate_inertia(inertia, what: str = "inertia") -> np.ndarray:
    """Check an inertia tensor (3×3, or 3 principal moments) and return it as 3×3.

    Raises ModelInputError naming the tensor, its principal moments and the first
    violated condition of `inertia_conditions`.
    """
    I = np.asarray(inertia, dtype=float)
    if I.shape == (3,):
        I = np.diag(I)
    if I.shape != (3, 3):
        raise ModelInputError(f"{what}: expected 3 principal moments or a 3x3 tensor, got shape {I.shape}")
    if not np.all(np.isfinite(I)):
        raise ModelInputError(f"{what}: entries must be finite numbers, got {I.tolist()}")
    values = np.array(_COND_FUN(I)).ravel()
    for (text, strict), v in zip(_COND_META, values):
        ok = v > 0 if strict else v >= 0
        if not ok:
            moments = np.linalg.eigvalsh(0.5 * (I + I.T))
            raise ModelInputError(
                f"{what} = {I.tolist()} kg*m^2 is not a valid inertia tensor: {text} "
                f"(value {v:.6g}); principal moments {moments.tolist()}"
            )
    return I
