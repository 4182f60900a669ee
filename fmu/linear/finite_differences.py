"""Central finite differences of a scene's FMU through FMI calls: the yardstick of the exact linearisation.

`raw_differences` perturbs one state (fmi3SetContinuousStates) or input (fmi3SetFloat64) at
a time by ±h and reads ẋ and y, 2 (nx + nu) evaluations: what an importer without
directional derivatives does. `differences_model` gives the model `linearize` gives, from
differences along the same directions through the same ctypes calls and assembly: what
`fmu.linear.bench` times against `linearize`. `chart_differences` does the same as
`raw_differences` in attitude-error coordinates, the states moved along the chart
(q₀ ⊗ exp(δθ/2)) and the rate read back through it, so that the minimal A, B, C, D are
checked as they are. The step h_j = rel·max(|v_j|, nominal_j): the central
difference then errs by O(h²|f'''|) (truncation) plus O(ε|f|/h) (round-off), which
`fd_error` estimates from the differences at h and 2h.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .attitude import ATTITUDE, Chart, quat_mul
from .linear_model import LinearModel
from .linearize import Plan, assemble, at_point, frame_of, plan, set_point
from .model_exchange import ModelExchange
from .operating_point import OperatingPoint

EPS = float(np.finfo(float).eps)
HALF = np.array([0.5])  # the step of ẋ₀'s column in Plan.differences: (ẋ₀ − 0) / (2 · ½) = ẋ₀


def _evaluate(me: ModelExchange, out_vrs: list[int]) -> np.ndarray:
    return np.concatenate((me.rates(), me.get(out_vrs) if out_vrs else np.zeros(0)))


def raw_differences(
    me: ModelExchange, point: OperatingPoint, inputs: Sequence[str], outputs: Sequence[str], rel: float = 1e-6
) -> tuple[np.ndarray, np.ndarray]:
    """(J, f0): central differences of (ẋ, y) over (x, u) in the FMU's states, J = [[A, B],
    [C, D]], and the values (ẋ, y) at the point."""
    at_point(me, point)
    out_vrs = me.value_references(outputs, me.outputs, "outputs")
    f0 = _evaluate(me, out_vrs)
    x0, u0 = point.x, np.array([point.inputs[n] for n in inputs])
    nx = me.nx
    scale = np.concatenate((np.maximum(np.abs(x0), me.nominals), np.maximum(np.abs(u0), 1.0)))
    J = np.empty((len(f0), nx + len(inputs)))
    for j in range(nx + len(inputs)):
        h = rel * scale[j]
        vals = []
        for sgn in (1.0, -1.0):
            if j < nx:
                x = x0.copy()
                x[j] += sgn * h
                me.set_states(x)
            else:
                me.set_inputs({inputs[j - nx]: u0[j - nx] + sgn * h})
            vals.append(_evaluate(me, out_vrs))
        if j < nx:
            me.set_states(x0)
        else:
            me.set_inputs({inputs[j - nx]: u0[j - nx]})
        J[:, j] = (vals[0] - vals[1]) / (2 * h)
    return J, f0


def differences_model(
    me: ModelExchange,
    point: OperatingPoint,
    inputs: Sequence[str] | None = None,
    outputs: Sequence[str] | None = None,
    coordinates: str = "attitude",
    frame: str | None = None,
    rel: float = 1e-6,
) -> LinearModel:
    """The linear model `linearize` gives, from central differences instead: along the same
    state directions (the chart's ∂x/∂z, the identity in raw coordinates) and inputs,
    2 (nz + nu) evaluations through the same ctypes calls, made ready once per plan as the
    directional derivatives are (Plan.differences, ModelExchange.difference_calls), at the
    point set by the same code and assembled by the same code. Steps h = rel ·
    max(|direction·x₀|, scale) per direction, rel · max(|u₀|, 1) per input. What an importer
    without directional derivatives does; fmu.linear.bench times it against `linearize`."""
    frame = frame_of(coordinates, frame)
    pl = plan(me, inputs, outputs, coordinates)
    x0 = set_point(me, pl, point, frame)
    u0 = np.array([point.inputs[n] for n in pl.ins])
    J = pl.differences(x0, u0, pl.directions, steps(pl, x0, u0, rel))
    return assemble(J, me, point, pl, frame)


def steps(pl: Plan, x0: np.ndarray, u0: np.ndarray, rel: float = 1e-6) -> np.ndarray:
    """The steps h of `differences_model` (Plan.differences') at the states x0 and inputs u0
    (the plan's): rel · max(|direction·x₀|, scale) per direction, ½ for ẋ₀'s column
    (fmu.linear.model_exchange.difference_calls), rel · max(|u₀|, 1) per input."""
    return np.concatenate((rel * np.maximum(np.abs(pl.directions.T @ x0), pl.scale), HALF,
                           rel * np.maximum(np.abs(u0), 1.0)))  # fmt: skip


def chart_rate(ch: Chart, x0: np.ndarray, x: np.ndarray, xdot: np.ndarray) -> np.ndarray:
    """ż at the FMU state x with rate ẋ (exact, not linearised): S ẋ, and on δθ the rotating
    reference's own term vec([0, −ω₀] ⊗ q₀* ⊗ q) (docs/theory.md §10.2)."""
    zdot = ch.S @ xdot
    if ch.states[:3] == ATTITUDE:
        iq = ch.raw.index("q[1]")
        q0 = x0[iq : iq + 4] / np.linalg.norm(x0[iq : iq + 4])
        dq = quat_mul(np.array([q0[0], -q0[1], -q0[2], -q0[3]]), x[iq : iq + 4])
        zdot[:3] += quat_mul(np.concatenate(([0.0], -ch.w0)), dq)[1:]
    return zdot


def chart_differences(
    me: ModelExchange,
    point: OperatingPoint,
    ch: Chart,
    inputs: Sequence[str],
    outputs: Sequence[str],
    nominals: np.ndarray,
    rel: float = 1e-6,
) -> np.ndarray:
    """Central differences of (ż, y) over (z, u) in the chart's coordinates: [[A, B], [C, D]]."""
    at_point(me, point)
    out_vrs = me.value_references(outputs, me.outputs, "outputs")
    x0, u0 = point.x, np.array([point.inputs[n] for n in inputs])
    nz = len(ch.states)

    def value(x: np.ndarray) -> np.ndarray:
        me.set_states(x)
        xdot = me.rates()
        return np.concatenate((chart_rate(ch, x0, x, xdot), me.get(out_vrs) if out_vrs else np.zeros(0)))

    scale = np.concatenate((nominals, np.maximum(np.abs(u0), 1.0)))
    J = np.empty((nz + len(out_vrs), nz + len(inputs)))
    for j in range(nz + len(inputs)):
        h = rel * scale[j]
        vals = []
        for sgn in (1.0, -1.0):
            if j < nz:
                dz = np.zeros(nz)
                dz[j] = sgn * h
                vals.append(value(ch.to_raw(x0, dz)))
            else:
                me.set_inputs({inputs[j - nz]: u0[j - nz] + sgn * h})
                vals.append(value(x0))
        me.set_inputs({n: point.inputs[n] for n in inputs})
        J[:, j] = (vals[0] - vals[1]) / (2 * h)
    me.set_states(x0)
    return J


def fd_error(J_h: np.ndarray, J_2h: np.ndarray, f_scale: np.ndarray, h_scale: np.ndarray) -> np.ndarray:
    """Entrywise error bound of the central difference J_h: its truncation error, estimated
    as |J_h − J_2h|/3 (the difference's h² term: Richardson), plus round-off of a few ε|f|/h
    (f_scale: the size of each row's function values and of its terms; h_scale: each
    column's step h)."""
    return np.abs(J_h - J_2h) / 3 + 8 * EPS * f_scale[:, None] / h_scale[None, :]
