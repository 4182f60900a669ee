"""Linearise a scene's FMU at an operating point from its own directional derivatives (FMI calls only).

`linearize` puts a Model Exchange instance at the point (fmi3SetContinuousStates,
fmi3SetFloat64), reads ẋ there and the Jacobian of (ẋ, y) with respect to (x, u) with one
fmi3GetDirectionalDerivative per state and input (docs/fmi_layer.md), and returns A, B, C,
D with names: in the FMU's own states (coordinates "raw"), or in attitude-error
coordinates (the default, fmu.linear.attitude, docs/theory.md §10), where the quaternion
is replaced by the small rotation δθ and a relative equilibrium is a fixed point.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from modelsrc.errors import ModelInputError

from ..drive.logged_warnings import LoggedWarnings
from .attitude import ATTITUDE, FRAMES, RATE, TURNING_AT, Chart, chart, chart_values, layout
from .linear_model import LinearModel
from .model_exchange import ModelExchange
from .operating_point import OperatingPoint

COORDINATES = ("attitude", "raw")


def expand_names(names: Sequence[str] | None, have: Sequence[str]) -> list[str] | None:
    """Names with a vector's base name standing for all its components ('w_body' ->
    'w_body[1]', 'w_body[2]', 'w_body[3]' when those are in `have`); None stays None."""
    if names is None:
        return None
    out: list[str] = []
    for n in names:
        parts = [h for h in have if h.startswith(f"{n}[")]
        out += parts if n not in have and parts else [n]
    return out


def at_point(me: ModelExchange, point: OperatingPoint, x: np.ndarray | None = None) -> np.ndarray:
    """Put the instance at the point (states, inputs; x: point.x when the caller has it);
    returns ẋ there."""
    if list(point.states) != me.states:
        raise ModelInputError(f"operating point: its states {list(point.states)} are not the FMU's {me.states}")
    me.set_states(point.x if x is None else x)
    me.set_inputs(point.inputs)
    return me.rates()


def raw_jacobians(me: ModelExchange, point: OperatingPoint, inputs: Sequence[str], outputs: Sequence[str]):
    """(A, B, C, D, ẋ₀) in the FMU's states at the point, from fmi3GetDirectionalDerivative."""
    xdot = at_point(me, point)
    out_vrs = me.value_references(outputs, me.outputs, "outputs")
    in_vrs = me.value_references(inputs, me.inputs, "inputs")
    nx = me.nx
    J = me.jacobian(me.derivative_vrs + out_vrs, me.state_vrs + in_vrs)
    return J[:nx, :nx], J[:nx, nx:], J[nx:, :nx], J[nx:, nx:], xdot


@dataclass(frozen=True)
class Plan:
    """What a linearisation of one FMU instance asks for, found once per instance and
    (inputs, outputs, coordinates) and kept in ModelExchange.plans: the names, their value
    references, the unknowns (derivatives, outputs) and knowns (states, inputs) of the
    directional derivatives, the scale of each minimal state (the FMU's nominal; 1 rad
    for δθ), and the buffers a linearisation rewrites per point instead of making them:
    the chart's T (`directions`, nx × nz, the identity in raw coordinates) and S, its
    turning, the seeds (T and the inputs' unit vectors, one column per
    fmi3GetDirectionalDerivative), and the FMI calls made ready on them (`jacobian`, and
    `differences` for the yardstick, fmu.linear.finite_differences). Only the blocks of the
    quaternion change with the point (fmu.linear.attitude.chart_values); iq, iw: the indices
    of q[1] and w_body[1] in x (−1 where the FMU has none, or in raw coordinates)."""

    ins: list[str]
    outs: list[str]
    in_vrs: list[int]
    out_vrs: list[int]
    unknowns: list[int]
    knowns: list[int]
    scale: np.ndarray
    states: tuple[str, ...]
    directions: np.ndarray
    S: np.ndarray
    turning: np.ndarray
    seeds: np.ndarray
    iq: int
    iw: int
    coordinates: str
    chart_at: tuple[np.ndarray, ...]
    seeds_t: np.ndarray
    ins_names: tuple[str, ...]
    outs_names: tuple[str, ...]
    jacobian: Callable[[], np.ndarray]
    differences: Callable[[np.ndarray, np.ndarray, np.ndarray, np.ndarray], np.ndarray]


def plan(me: ModelExchange, inputs: Sequence[str] | None, outputs: Sequence[str] | None, coordinates: str) -> Plan:
    """The Plan of these inputs and outputs (None: all; ModelInputError for a name the FMU
    does not have) in these coordinates, made on the first call and reused."""
    key = (None if inputs is None else tuple(inputs), None if outputs is None else tuple(outputs), coordinates)
    found = me.plans.get(key)
    if isinstance(found, Plan):
        return found
    if coordinates not in COORDINATES:
        raise ModelInputError(f"coordinates must be one of {', '.join(COORDINATES)}, got {coordinates!r}")
    ins = expand_names(inputs, me.inputs) or (list(me.inputs) if inputs is None else [])
    # default: every output but the ZXZ Euler angles, whose derivative does not exist where
    # sin θ = 0 (the identity attitude, where most scenes start): the FMU refuses a non-finite
    # derivative (docs/robustness.md §2), and q already gives the attitude; ask for them by name
    outs = expand_names(outputs, me.outputs) or (
        [o for o in me.outputs if not o.startswith("euler_zxz[")] if outputs is None else []
    )
    out_vrs = me.value_references(outs, me.outputs, "outputs")
    in_vrs = me.value_references(ins, me.inputs, "inputs")
    nx, ni = me.nx, len(ins)
    if coordinates == "raw":
        states, T, S, iq, iw = tuple(me.states), np.eye(nx), np.eye(nx), -1, -1
        scale = me.nominals
    else:
        states, T0, S0, iq = layout(tuple(me.states))
        T, S = T0.copy(), S0.copy()
        iw = me.states.index(RATE[0]) if iq >= 0 and RATE[0] in me.states else -1
        scale = np.array([1.0 if s in ATTITUDE else me.nominals[me.states.index(s)] for s in states])
    nz = len(states)
    seeds = np.zeros((nx + ni, nz + ni), order="F")  # column k: the seed of call k, contiguous
    seeds[:nx, :nz], seeds[nx:, nz:] = T, np.eye(ni)
    unknowns, knowns = me.derivative_vrs + out_vrs, me.state_vrs + in_vrs
    p = Plan(
        ins, outs, in_vrs, out_vrs, unknowns, knowns, scale, states, T, S, np.zeros((nz, nz)), seeds, iq, iw,
        coordinates, chart_indices(nx, nz, ni, iq) if iq >= 0 else (), seeds.T, tuple(ins), tuple(outs),
        me.directional_calls(unknowns, knowns, seeds), me.difference_calls(out_vrs, in_vrs, nz),
    )  # fmt: skip
    me.plans[key] = p
    return p


def at_plan_point(pl: Plan, x0: np.ndarray, frame: str) -> np.ndarray:
    """Rewrite the plan's chart blocks (T, S, turning, the seeds' q block) for the point's
    states x0 in the reference `frame` (fmu.linear.attitude.chart_values, as `chart` does);
    returns ω₀ (zeros in raw coordinates and without a quaternion)."""
    if pl.coordinates == "raw":
        return np.zeros(3)
    if frame not in FRAMES:
        raise ModelInputError(f"frame must be one of {', '.join(FRAMES)}, got {frame!r}")
    if pl.iq < 0:
        return np.zeros(3)
    t_block, s_block, turn, w0 = chart_values(x0, pl.iq, pl.iw if frame == "rotating" else -1)
    at = pl.chart_at
    pl.directions.put(at[0], t_block)
    pl.seeds_t.put(at[1], t_block)  # the seeds' transpose: C order, so that put's flat indices are its own
    pl.S.put(at[2], s_block)
    pl.turning.put(at[3], turn)
    return w0


def chart_indices(nx: int, nz: int, ni: int, iq: int) -> tuple[np.ndarray, ...]:
    """The flat indices (C order) where `at_plan_point` writes fmu.linear.attitude.chart_values:
    T's q block in T (nx × nz) and in the seeds' transpose ((nz + nu) × (nx + nu)), S's
    block in S (nz × nx), the turning entries in turning (nz × nz)."""
    rows, cols = np.divmod(np.arange(12), 3)  # T's block, row-major 4 × 3
    t_at = np.ravel_multi_index((iq + rows, cols), (nx, nz))
    seeds_at = np.ravel_multi_index((cols, iq + rows), (nz + ni, nx + ni))
    r, c = np.divmod(np.arange(12), 4)  # S's block, row-major 3 × 4
    s_at = np.ravel_multi_index((r, iq + c), (nz, nx))
    turn_at = np.ravel_multi_index(tuple(np.array(TURNING_AT).T), (nz, nz))
    return t_at, seeds_at, s_at, turn_at


def state_directions(
    me: ModelExchange, x0: np.ndarray, coordinates: str, frame: str
) -> tuple[np.ndarray, Chart | None]:
    """(directions, chart): the FMU-state directions the Jacobian is taken along (nx × nz:
    the identity in raw coordinates; T = ∂x/∂z of the attitude chart at x0, so that J·T
    comes from nz seeds, one fmi3GetDirectionalDerivative each, instead of nx) and the
    chart (None for raw)."""
    if coordinates == "raw":
        return np.eye(me.nx), None
    ch = chart(me.states, x0, frame)
    return ch.T, ch


def assemble(J: np.ndarray, xdot: np.ndarray, me: ModelExchange, point: OperatingPoint, pl: Plan, w0: np.ndarray,
             frame: str) -> LinearModel:  # fmt: skip
    """The linear model from J = ∂(ẋ, y)/∂(directions, u) ((nx + ny) × (nz + nu), from
    directional derivatives or from differences along the same directions) and ẋ₀, the plan's
    chart at the point (`at_plan_point`, which gave ω₀ = w0): in raw coordinates A, B, C, D
    are its blocks; in the chart's, A_z = S (A_x T) + turning, B_z = S B_x, C_z = C_x T, and
    ż₀ = S ẋ₀ − ω₀ on δθ (docs/theory.md §10.1-10.2; fmu.linear.attitude.Chart.reduce)."""
    nx, nz = me.nx, len(pl.states)
    AT, B, CT, D = J[:nx, :nz], J[:nx, nz:], J[nx:, :nz], J[nx:, nz:]
    ins, outs = pl.ins_names, pl.outs_names
    if pl.coordinates == "raw":
        return LinearModel(A=AT, B=B, C=CT, D=D, states=pl.states, inputs=ins, outputs=outs, point=point,
                           drift=xdot, nominals=pl.scale)  # fmt: skip
    S = pl.S
    zdot = S @ xdot
    if pl.iq >= 0:
        zdot[:3] -= w0
    Az = S @ AT
    Az += pl.turning  # in place: the sum S (A_x T) + turning without a second array
    return LinearModel(A=Az, B=S @ B, C=CT, D=D, states=pl.states, inputs=ins, outputs=outs,
                       point=point, drift=zdot, nominals=pl.scale, coordinates="attitude error",
                       frame=frame)  # fmt: skip


def linearize(
    fmu: str | Path,
    point: OperatingPoint,
    inputs: Sequence[str] | None = None,
    outputs: Sequence[str] | None = None,
    coordinates: str = "attitude",
    frame: str = "rotating",
    instance: ModelExchange | None = None,
) -> LinearModel:
    """The linear model of the FMU at `point`.

    inputs, outputs: the FMU's names (a vector's base name for all its components;
    default: every input and every output but the ZXZ Euler angles, which have no derivative
    at θ = 0 or π and can be asked for by name); coordinates "attitude"
    (δθ in place of q, the orbit's clock left out; docs/theory.md §10) or "raw" (the FMU's
    states); frame: the attitude reference, "rotating" with the point's body rate (a
    steady spin or a body at rest in an orbit frame is then an equilibrium) or "fixed".
    instance: an open Model Exchange instance of this FMU initialised with
    point.parameters, reused (the cost of a linearisation is then its FMI calls alone);
    else one is opened and closed. One fmi3GetDirectionalDerivative per minimal state
    (seeded with the chart's direction ∂x/∂z) and per input. The warnings the FMU logs
    meanwhile (and at the initialisation of an instance opened here) are raised as
    FmuWarnings, as a run's (fmu.drive.logged_warnings).
    """
    if coordinates not in COORDINATES:
        raise ModelInputError(f"coordinates must be one of {', '.join(COORDINATES)}, got {coordinates!r}")
    me = instance if instance is not None else ModelExchange(fmu, point.parameters)
    with LoggedWarnings(me, first=0 if instance is None else None):
        try:
            pl = plan(me, inputs, outputs, coordinates)
            x0 = point.x
            w0 = at_plan_point(pl, x0, frame)
            xdot = at_point(me, point, x0)
            J = pl.jacobian()
        finally:
            if instance is None:
                me.close()
    return assemble(J, xdot, me, point, pl, w0, frame)
