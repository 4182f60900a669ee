"""Attitude-error coordinates: the small rotation δθ in place of the quaternion, in a fixed or a rotating reference.

The FMU's state holds the orientation as a unit quaternion q (4 numbers, 3 degrees of
freedom): its raw Jacobian has a direction (the norm |q|) that is no motion of the body,
and a spurious mode along it. The linear models use instead the multiplicative attitude
error of the spacecraft-attitude literature (Markley & Crassidis, "Fundamentals of
Spacecraft Attitude Determination and Control", 2014, §3.2 and §6.2; Lefferts, Markley
& Shuster, "Kalman filtering for spacecraft attitude estimation", 1982):

    q = q₀ ⊗ [1, δθ/2]   (to first order; exactly q₀ ⊗ exp(δθ/2) here),

δθ the small rotation (rad) from the reference attitude q₀, in the body frame; the other
states stay as they are. The maps between the coordinates (docs/theory.md §10.1):
T = ∂x/∂z (x the FMU's states, z = (δθ, the rest)) and S = ∂z/∂x with
δθ = 2 vec(q₀* ⊗ q), so that S T = 1 and A_z = S A_x T, B_z = S B_x, C_z = C_x T.

A relative equilibrium (a steady spin, a body at rest in an orbit's LVLH frame) has a
constant body rate ω₀ and a turning q₀(t) = q₀ ⊗ exp(ω₀ t/2): referred to that rotating
q₀(t) the model is time-invariant, and the reference's own turning adds
∂δθ̇/∂δθ = −½ [ω₀]× to S A_x T (§10.2), so that δθ̇ = δω − ω₀ × δθ. The orbit angle
(state `orbit_angle`, θ = n t: the clock of the orbit, §9.1) is no degree of freedom and
is left out of the minimal coordinates.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

# States that are a clock (their rate is a constant, no dynamics): left out of the minimal
# coordinates (docs/theory.md §9.1, §10.2).
CLOCK_STATES = ("orbit_angle",)
QUATERNION = ("q[1]", "q[2]", "q[3]", "q[4]")
ATTITUDE = ("dtheta[1]", "dtheta[2]", "dtheta[3]")
RATE = ("w_body[1]", "w_body[2]", "w_body[3]")
FRAMES = ("rotating", "fixed")


def quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product a ⊗ b (scalar first)."""
    return left_matrix(a) @ np.asarray(b, dtype=float)


def left_matrix(q: np.ndarray) -> np.ndarray:
    """L(q) with q ⊗ p = L(q) p (4 × 4, scalar first)."""
    w, x, y, z = np.asarray(q, dtype=float).tolist()
    return np.array([[w, -x, -y, -z], [x, w, -z, y], [y, z, w, -x], [z, -y, x, w]])


def skew(v: Sequence[float] | np.ndarray) -> np.ndarray:
    """[v]× with [v]× a = v × a."""
    x, y, z = np.asarray(v, dtype=float).tolist()
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def rotate(q0: np.ndarray, dtheta: np.ndarray) -> np.ndarray:
    """q₀ ⊗ exp(δθ/2): the attitude δθ (rad, body frame) away from q₀ (unit quaternion)."""
    dtheta = np.asarray(dtheta, dtype=float)
    angle = float(np.linalg.norm(dtheta))
    if angle == 0.0:
        return np.array(q0, dtype=float)
    dq = np.concatenate(([np.cos(angle / 2)], np.sin(angle / 2) * dtheta / angle))
    q = quat_mul(q0, dq)
    return q / np.linalg.norm(q)


def attitude_error(q0: np.ndarray, q: np.ndarray) -> np.ndarray:
    """δθ = 2 vec(q₀* ⊗ q) (rad, body frame), the sign of q taken so that the scalar part
    of q₀* ⊗ q is ≥ 0 (q and −q are one attitude)."""
    conj = np.array([q0[0], -q0[1], -q0[2], -q0[3]], dtype=float)
    dq = quat_mul(conj, q)
    return 2.0 * (dq[1:] if dq[0] >= 0 else -dq[1:])


@dataclass(frozen=True)
class Chart:
    """The attitude-error coordinates z of the FMU's states x at one operating point.

    raw: the FMU's state names; states: the names of z; T (nx × nz) = ∂x/∂z and
    S (nz × nx) = ∂z/∂x at the point; turning (nz × nz): the rotating reference's own term
    −½ [ω₀]× on the δθ block (0 in a fixed reference); w0: ω₀ (rad/s, body), the
    reference's rate; frame: "rotating" or "fixed"."""

    raw: tuple[str, ...]
    states: tuple[str, ...]
    T: np.ndarray
    S: np.ndarray
    turning: np.ndarray
    w0: np.ndarray
    frame: str

    def transform(self, A: np.ndarray, B: np.ndarray, C: np.ndarray, xdot: np.ndarray):
        """(A_z, B_z, C_z, ż₀) from the FMU's (A_x, B_x, C_x, ẋ₀): S A T + turning, S B, C T,
        and ż₀ = S ẋ₀ − ω₀ on δθ (the point's rate in z: 0 at a relative equilibrium)."""
        zdot = self.S @ xdot
        if self.states[:3] == ATTITUDE:
            zdot[:3] -= self.w0
        return self.S @ A @ self.T + self.turning, self.S @ B, C @ self.T, zdot

    def reduce(self, AT: np.ndarray, B: np.ndarray, xdot: np.ndarray):
        """(A_z, B_z, ż₀) from A_x T (the rates' derivatives along T's columns), B_x and ẋ₀:
        S (A_x T) + turning, S B, and ż₀ as in `transform` (C_z = C_x T needs nothing)."""
        zdot = self.S @ xdot
        if self.states[:3] == ATTITUDE:
            zdot[:3] -= self.w0
        return self.S @ AT + self.turning, self.S @ B, zdot

    def to_raw(self, x0: np.ndarray, dz: np.ndarray) -> np.ndarray:
        """The FMU's states at z = dz from the point x0 (nonlinear: q₀ ⊗ exp(δθ/2), the rest
        added; a clock state left at its value)."""
        x = np.array(x0, dtype=float)
        dz = np.asarray(dz, dtype=float)
        for k, name in enumerate(self.states):
            if name in ATTITUDE:
                continue
            x[self.raw.index(name)] += dz[k]
        if self.states[:3] == ATTITUDE:
            iq = self.raw.index("q[1]")
            x[iq : iq + 4] = rotate(x0[iq : iq + 4], dz[:3])
        return x

    def from_raw(self, x0: np.ndarray, x: np.ndarray) -> np.ndarray:
        """z of the FMU's states x, relative to the point x0 (inverse of `to_raw`)."""
        z = np.empty(len(self.states))
        for k, name in enumerate(self.states):
            if name not in ATTITUDE:
                i = self.raw.index(name)
                z[k] = x[i] - x0[i]
        if self.states[:3] == ATTITUDE:
            iq = self.raw.index("q[1]")
            z[:3] = attitude_error(x0[iq : iq + 4], x[iq : iq + 4])
        return z


@functools.lru_cache(maxsize=64)
def layout(raw: tuple[str, ...]) -> tuple[tuple[str, ...], np.ndarray, np.ndarray, int]:
    """(the names of z, T and S without the attitude block, the index of q[1] or −1) of
    the FMU's state names: computed once per FMU, so that a linearisation pays only for
    the quaternion's blocks (fmu.linear.bench times it)."""
    has_q = all(n in raw for n in QUATERNION)
    kept = [n for n in raw if n not in CLOCK_STATES and not (has_q and n in QUATERNION)]
    states = (ATTITUDE if has_q else ()) + tuple(kept)
    T = np.zeros((len(raw), len(states)))
    off = 3 if has_q else 0
    for k, name in enumerate(kept):
        T[raw.index(name), off + k] = 1.0
    return states, T, T.T.copy(), raw.index("q[1]") if has_q else -1


def chart(raw: Sequence[str], x0: np.ndarray, frame: str = "rotating") -> Chart:
    """The attitude-error chart of the states `raw` (the FMU's names) at x0: δθ in place of
    q[1..4] (when the FMU has them), the clock states left out, every other state as it is.
    frame "rotating": the reference turns with the point's body rate ω₀ = w_body (a
    relative equilibrium is then a fixed point, docs/theory.md §10.2); "fixed": it does not."""
    if frame not in FRAMES:
        from modelsrc.errors import ModelInputError

        raise ModelInputError(f"frame must be one of {', '.join(FRAMES)}, got {frame!r}")
    raw = tuple(raw)
    x0 = np.asarray(x0, dtype=float)
    states, T0, S0, iq = layout(raw)
    T, S = T0.copy(), S0.copy()
    nz = len(states)
    turning = np.zeros((nz, nz))
    w0 = np.zeros(3)
    if iq >= 0:
        iw = raw.index(RATE[0]) if frame == "rotating" and RATE[0] in raw else -1
        w0 = chart_into(T, S, turning, x0, iq, iw)
    return Chart(raw, states, T, S, turning, w0, frame)


def chart_values(x0: np.ndarray, iq: int, iw: int) -> tuple[list[float], list[float], list[float], np.ndarray]:
    """The entries of the chart that depend on the point x0, as lists: T's block (rows of
    q[1..4], columns of δθ; row-major 4 × 3), S's block (rows of δθ, columns of q; row-major
    3 × 4), the turning's off-diagonal entries at (0, 1), (0, 2), (1, 2), (1, 0), (2, 0),
    (2, 1) of its δθ block, and ω₀ (rad/s, body; 0 in a fixed reference). iq: the index of
    q[1] in x; iw: that of w_body[1] in a rotating reference, −1 in a fixed one. Computed
    once here for `chart` (fresh matrices) and for a linearisation's plan (its buffers,
    fmu.linear.linearize.at_plan_point), so that both give the same bits."""
    q = x0[iq : iq + 4]
    norm = math.sqrt(q.dot(q))  # BLAS's ddot, as q @ q (at_plan_point's, without matmul's ufunc)
    w, x, y, z = (v / norm for v in q.tolist())  # q₀
    # L(q₀)[:, 1:] = [[-x, -y, -z], [w, -z, y], [z, w, -x], [-y, x, w]] (left_matrix), written out:
    hw, hx, hy, hz = 0.5 * w, 0.5 * x, 0.5 * y, 0.5 * z  # T: ½ L1, ∂(q₀ ⊗ [1, δθ/2])/∂δθ
    t_block = [-hx, -hy, -hz, hw, -hz, hy, hz, hw, -hx, -hy, hx, hw]
    dw, dx, dy, dz = 2.0 * w, 2.0 * x, 2.0 * y, 2.0 * z  # S: 2 L1ᵀ, ∂(2 vec(q₀* ⊗ q))/∂q, L(q₀*) = L(q₀)ᵀ
    s_block = [-dx, dw, dz, -dy, -dy, -dz, dw, dx, -dz, dy, -dx, dw]
    if iw < 0:
        return t_block, s_block, [0.0] * 6, np.zeros(3)
    w0 = x0[iw : iw + 3].copy()
    a, b, c = (0.5 * v for v in w0.tolist())
    return t_block, s_block, [c, -b, a, -c, b, -a], w0  # −½ [ω₀]× (skew)


TURNING_AT = ((0, 1), (0, 2), (1, 2), (1, 0), (2, 0), (2, 1))  # the entries of chart_values' turning list
# where a linearisation's plan writes −ω₀ beside the turning (fmu.linear.linearize.Plan's offset,
# nz × (nz + 1): column nz adds −ω₀ to S ẋ₀ on δθ, ż₀ = S ẋ₀ − ω₀, docs/theory.md §10.2)
DRIFT_AT = ((0, -1), (1, -1), (2, -1))

# chart_values' 30 entries (T's block, S's block, the turning's, in its order) and −ω₀ as
# (source, factor): entry = factor · source, source 0..3 the normalised q₀ (w, x, y, z), 4..6 ω₀.
# A linearisation's plan computes them at once from these (fmu.linear.linearize.at_plan_point:
# one gather, one division, one product): each factor is ±½ or ±2, so that the entry is the
# same floating-point number as chart_values' −(½ x) and the like (scaling by a power of two
# is exact, and a negated product is the product of the negated factor), and adding −ω₀ is
# subtracting ω₀; the tests check the two to the bit (tests/linear/test_linearize_bits.py).
CHART_ENTRIES = (
    *((1, -0.5), (2, -0.5), (3, -0.5), (0, 0.5), (3, -0.5), (2, 0.5)),  # T: -hx, -hy, -hz, hw, -hz, hy
    *((3, 0.5), (0, 0.5), (1, -0.5), (2, -0.5), (1, 0.5), (0, 0.5)),  # hz, hw, -hx, -hy, hx, hw
    *((1, -2.0), (0, 2.0), (3, 2.0), (2, -2.0), (2, -2.0), (3, -2.0)),  # S: -dx, dw, dz, -dy, -dy, -dz
    *((0, 2.0), (1, 2.0), (3, -2.0), (2, 2.0), (1, -2.0), (0, 2.0)),  # dw, dx, -dz, dy, -dx, dw
    *((6, 0.5), (5, -0.5), (4, 0.5), (6, -0.5), (5, 0.5), (4, -0.5)),  # turning: c, -b, a, -c, b, -a
    *((4, -1.0), (5, -1.0), (6, -1.0)),  # −ω₀, at DRIFT_AT
)


def chart_into(T: np.ndarray, S: np.ndarray, turning: np.ndarray, x0: np.ndarray, iq: int, iw: int) -> np.ndarray:
    """Write `chart_values` into T (its rows of q, the columns of δθ), S (its rows of δθ, the
    columns of q) and turning (its δθ block), the rest of them being `layout`'s; returns ω₀."""
    t_block, s_block, turn, w0 = chart_values(x0, iq, iw)
    T[iq : iq + 4, :3] = np.reshape(t_block, (4, 3))
    S[:3, iq : iq + 4] = np.reshape(s_block, (3, 4))
    for (i, j), v in zip(TURNING_AT, turn):
        turning[i, j] = v
    return w0
