"""The eigenvalue table of a linear model: frequency, damping, time constant and the states that dominate each mode.

One row per real eigenvalue or complex pair (the one with Im λ ≥ 0), slowest first. For
a discrete map (Φ over a step dt) the continuous eigenvalue s = ln(z)/dt is shown. The
dominant states are those with the largest participation factors p_ki = |v_ki w_ik| (right
and left eigenvectors, w v = 1; Pérez-Arriaga, Verghese & Schweppe, IEEE Trans. PAS 101,
1982): dimensionless and independent of the states' units. Where the eigenvectors are
nearly dependent (a defective A: the double integrators of a body at rest, cond(V) above
1e8) the left eigenvectors are meaningless, and the right eigenvector's entries over the
states' nominal scales stand in, which the table says.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .linear_model import LinearModel

# Eigenvalues of a defective A (Jordan blocks: a double integrator) are computed only to
# about √ε ‖A‖ (a perturbation δ of the matrix moves them by δ^(1/2)): a real part below
# this is not told apart from 0 and the mode is called marginal.
MARGIN = math.sqrt(np.finfo(float).eps)
DOMINANT_SHARE = 0.1  # a state is listed when its share is at least this fraction of the largest


@dataclass(frozen=True)
class Mode:
    """One mode: eigenvalue s (1/s; for a discrete map ln(z)/dt, as computed), natural
    frequency |s| (rad/s), damping ratio −Re s/|s| (nan for s = 0), time constant −1/Re s
    (s; inf for Re s = 0, negative for a growing mode), kind ("stable", "unstable",
    "marginal") and the dominant states with their shares (0..1). A marginal mode's Re s
    is not told apart from 0 (MARGIN), so its frequency, damping and time constant are
    those of Re s = 0: |Im s| (0 when |s| is below MARGIN too), damping 0 (nan for s = 0),
    time constant inf; computed from the round-off in Re s they would be noise (a damping of
    1 and a time constant of 1e134 s for s = −2e-135)."""

    eigenvalue: complex
    frequency: float
    damping: float
    time_constant: float
    kind: str
    dominant: tuple[tuple[str, float], ...]


def continuous(model: LinearModel) -> tuple[np.ndarray, np.ndarray]:
    """(s, V): the eigenvalues as continuous rates and A's right eigenvectors."""
    z, V = np.linalg.eig(model.A)
    if model.dt is None:
        return z, V
    with np.errstate(divide="ignore"):
        return np.log(z.astype(complex)) / model.dt, V


def shares(model: LinearModel, V: np.ndarray) -> tuple[np.ndarray, str]:
    """Per mode (column) the states' shares: participation factors, or scaled eigenvector
    entries where V is nearly singular; and which of the two it is."""
    if np.linalg.cond(V) < 1e8:
        W = np.linalg.inv(V)
        P = np.abs(V * W.T)
        how = "participation factors"
    else:
        scale = model.nominals if len(model.nominals) == len(model.states) else np.ones(len(model.states))
        P = np.abs(V) / scale[:, None]
        how = "eigenvector over the states' nominals (A is defective)"
    return P / np.maximum(P.sum(axis=0), 1e-300), how


def modes(model: LinearModel) -> tuple[list[Mode], str]:
    """The modes of the model, slowest first, and how the dominant states were found."""
    s, V = continuous(model)
    P, how = shares(model, V)
    tol = MARGIN * max(1.0 if model.dt is None else 1.0 / model.dt, float(np.abs(s[np.isfinite(s)]).max(initial=0.0)))
    out = []
    for k in np.argsort(np.abs(s), kind="stable"):
        lam = complex(s[k])
        if lam.imag < 0 and np.any(np.isclose(s, lam.conjugate(), rtol=1e-9, atol=tol)):
            continue  # its pair is listed
        kind = "unstable" if lam.real > tol else "stable" if lam.real < -tol else "marginal"
        # a marginal mode's Re s, and its Im s below the same margin, are round-off: taken as 0
        rate = 0.0 if kind == "marginal" else lam.real
        imag = 0.0 if kind == "marginal" and abs(lam.imag) <= tol else lam.imag
        mag = abs(complex(rate, imag))
        order = np.argsort(-P[:, k])
        top = P[order[0], k]
        dom = tuple((model.states[i], float(P[i, k])) for i in order if P[i, k] >= DOMINANT_SHARE * top)[:4]
        out.append(
            Mode(
                eigenvalue=lam,
                frequency=mag,
                damping=(-rate / mag) + 0.0 if mag > 0 else math.nan,
                time_constant=-1.0 / rate if rate != 0 else math.inf,
                kind=kind,
                dominant=dom,
            )
        )
    return out, how


def table(model: LinearModel) -> str:
    """The eigenvalue table as text (one row per mode)."""
    ms, how = modes(model)
    head = f"{'eigenvalue (1/s)':<28} {'freq (rad/s)':>12} {'damping':>8} {'tau (s)':>10}  {'kind':<9} dominant states"
    rows = [head]
    for m in ms:
        lam = m.eigenvalue
        # a marginal mode as its other columns take it (Mode): Re s 0, Im s its frequency
        re, im = (0.0, m.frequency) if m.kind == "marginal" else (lam.real, abs(lam.imag))
        ev = f"{re:.6g}" + (f" ± {im:.6g}j" if im != 0 else "")
        damp = "-" if math.isnan(m.damping) else f"{m.damping:.3g}"
        tau = "inf" if math.isinf(m.time_constant) else f"{m.time_constant:.4g}"
        dom = ", ".join(f"{n} {p:.0%}" for n, p in m.dominant)
        rows.append(f"{ev:<28} {m.frequency:>12.6g} {damp:>8} {tau:>10}  {m.kind:<9} {dom}")
    kind = "discrete map: s = ln(z)/dt" if model.dt is not None else "continuous"
    rows.append(
        f"({kind}; dominant states by {how}; marginal: |Re s| below √ε times the largest |s|, not told apart "
        "from 0, shown as 0 with damping 0 and tau inf)"
    )
    return "\n".join(rows)
