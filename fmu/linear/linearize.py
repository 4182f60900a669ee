"""Linearise a scene's FMU at an operating point from its own directional derivatives (FMI calls only).

`linearize` puts a Model Exchange instance at the point (fmi3SetContinuousStates,
fmi3SetFloat64), reads ẋ there and the Jacobian of (ẋ, y) with respect to (x, u) with one
fmi3GetDirectionalDerivative per state and input (docs/fmi_layer.md), and returns A, B, C,
D with names: in the FMU's own states (coordinates "raw"), or in attitude-error
coordinates (the default, fmu.linear.attitude, docs/theory.md §10), where the quaternion
is replaced by the small rotation δθ and a relative equilibrium is a fixed point.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from modelsrc.errors import ModelInputError

from .attitude import ATTITUDE, Chart, chart, layout
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


def at_point(me: ModelExchange, point: OperatingPoint) -> np.ndarray:
    """Put the instance at the point (states, inputs); returns ẋ there."""
    if list(point.states) != me.states:
        raise ModelInputError(f"operating point: its states {list(point.states)} are not the FMU's {me.states}")
    me.set_states(point.x)
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
    directional derivatives, and the scale of each minimal state (the FMU's nominal; 1 rad
    for δθ)."""

    ins: list[str]
    outs: list[str]
    in_vrs: list[int]
    out_vrs: list[int]
    unknowns: list[int]
    knowns: list[int]
    scale: np.ndarray


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
    if coordinates == "raw":
        scale = me.nominals
    else:
        names = layout(tuple(me.states))[0]
        scale = np.array([1.0 if s in ATTITUDE else me.nominals[me.states.index(s)] for s in names])
    p = Plan(ins, outs, in_vrs, out_vrs, me.derivative_vrs + out_vrs, me.state_vrs + in_vrs, scale)
    me.plans[key] = p
    return p


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


def assemble(J: np.ndarray, xdot: np.ndarray, me: ModelExchange, point: OperatingPoint, pl: Plan,
             ch: Chart | None) -> LinearModel:  # fmt: skip
    """The linear model from J = ∂(ẋ, y)/∂(directions, u) ((nx + ny) × (nz + nu), from
    directional derivatives or from differences along the same directions) and ẋ₀: in raw
    coordinates A, B, C, D are its blocks; in the chart's, A_z = S (A_x T) + turning,
    B_z = S B_x, C_z = C_x T (docs/theory.md §10.1-10.2)."""
    nx, nz = me.nx, J.shape[1] - len(pl.ins)
    AT, B, CT, D = J[:nx, :nz], J[:nx, nz:], J[nx:, :nz], J[nx:, nz:]
    ins, outs = tuple(pl.ins), tuple(pl.outs)
    if ch is None:
        return LinearModel(A=AT, B=B, C=CT, D=D, states=tuple(me.states), inputs=ins, outputs=outs, point=point,
                           drift=xdot, nominals=pl.scale)  # fmt: skip
    Az, Bz, zdot = ch.reduce(AT, B, xdot)
    return LinearModel(A=Az, B=Bz, C=CT, D=D, states=ch.states, inputs=ins, outputs=outs, point=point, drift=zdot,
                       nominals=pl.scale, coordinates="attitude error", frame=ch.frame)  # fmt: skip


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
    (seeded with the chart's direction ∂x/∂z) and per input.
    """
    if coordinates not in COORDINATES:
        raise ModelInputError(f"coordinates must be one of {', '.join(COORDINATES)}, got {coordinates!r}")
    me = instance if instance is not None else ModelExchange(fmu, point.parameters)
    try:
        pl = plan(me, inputs, outputs, coordinates)
        xdot = at_point(me, point)
        x0 = point.x
        directions, ch = state_directions(me, x0, coordinates, frame)
        nx, nd, ni = me.nx, directions.shape[1], len(pl.in_vrs)
        seeds = np.zeros((nx + ni, nd + ni))
        seeds[:nx, :nd] = directions
        seeds[nx:, nd:] = np.eye(ni)
        J = me.jacobian(pl.unknowns, pl.knowns, seeds)
    finally:
        if instance is None:
            me.close()
    return assemble(J, xdot, me, point, pl, ch)
