"""Linearise a scene's FMU at an operating point from its own directional derivatives (FMI calls only).

`linearize` puts a Model Exchange instance at the point (fmi3SetContinuousStates,
fmi3SetFloat64), reads ẋ there and the Jacobian of (ẋ, y) with respect to (x, u) with one
fmi3GetDirectionalDerivative per state and input (docs/fmi_layer.md), and returns A, B, C,
D with names: in the FMU's own states (coordinates "raw"), or in attitude-error
coordinates (the default, fmu.linear.attitude, docs/theory.md §10), where the quaternion
is replaced by the small rotation δθ and a relative equilibrium is a fixed point.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from modelsrc.errors import ModelInputError

from ..drive.logged_warnings import LoggedWarnings
from .attitude import ATTITUDE, CHART_ENTRIES, FRAMES, RATE, TURNING_AT, Chart, chart, layout
from .linear_model import LinearModel
from .model_exchange import ModelExchange
from .operating_point import OperatingPoint

COORDINATES = ("attitude", "raw")
ZERO3 = np.zeros(3)  # ω₀ where there is none: shared, so read-only
ZERO3.flags.writeable = False


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
    of q[1] and w_body[1] in x (−1 where the FMU has none, or in raw coordinates). T, the
    seeds' transpose, S and turning are views into one array, `store`, so that
    `at_plan_point` writes the point's entries into all four with one call: at `chart_at`
    (flat indices into store) the values x0[chart_from] (q's divided by |q|) times
    chart_factor (fmu.linear.attitude.CHART_ENTRIES; T's block twice, for T and the seeds).
    chart_buf: where x0[chart_from] is gathered (q[1..4] first, for |q|, then the 42
    entries), with its views chart_q, chart_q_entries (the 36 divided by |q|), chart_entries
    (the 42) and chart_turning (the last 6), made once so that a point pays no slicing.
    fields: the LinearModel's fields that are the same at every point, per frame
    (raw coordinates: under ""), for LinearModel.made_with."""

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
    store: np.ndarray
    chart_at: np.ndarray
    chart_from: np.ndarray
    chart_factor: np.ndarray
    ins_names: tuple[str, ...]
    outs_names: tuple[str, ...]
    chart_buf: np.ndarray
    chart_q: np.ndarray
    chart_q_entries: np.ndarray
    chart_entries: np.ndarray
    chart_turning: np.ndarray
    fields: dict[str, dict]
    jacobian: Callable[[], np.ndarray]
    differences: Callable[[np.ndarray, np.ndarray, np.ndarray, np.ndarray], np.ndarray]


def plan(me: ModelExchange, inputs: Sequence[str] | None, outputs: Sequence[str] | None, coordinates: str) -> Plan:
    """The Plan of these inputs and outputs (None: all; ModelInputError for a name the FMU
    does not have) in these coordinates, made on the first call and reused."""
    if inputs is None and outputs is None:  # the common call: no tuples to build
        key: tuple = (None, None, coordinates)
    else:
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
        states, T0, S0, iq, iw = tuple(me.states), np.eye(nx), np.eye(nx), -1, -1
        scale = me.nominals
    else:
        states, T0, S0, iq = layout(tuple(me.states))
        iw = me.states.index(RATE[0]) if iq >= 0 and RATE[0] in me.states else -1
        scale = np.array([1.0 if s in ATTITUDE else me.nominals[me.states.index(s)] for s in states])
    nz = len(states)
    sizes = (nx * nz, (nz + ni) * (nx + ni), nz * nx, nz * nz)  # T, the seeds' transpose, S, turning
    starts = np.cumsum((0, *sizes))
    store = np.zeros(starts[-1])
    T, seeds_t, S, turning = (store[a:b] for a, b in itertools.pairwise(starts))
    T, S, turning = T.reshape(nx, nz), S.reshape(nz, nx), turning.reshape(nz, nz)
    seeds_t = seeds_t.reshape(nz + ni, nx + ni)  # row k: the seed of call k, contiguous
    T[:], S[:], seeds_t[:nz, :nx], seeds_t[nz:, nx:] = T0, S0, T0.T, np.eye(ni)
    seeds = seeds_t.T  # Fortran order: column k the seed of call k
    unknowns, knowns = me.derivative_vrs + out_vrs, me.state_vrs + in_vrs
    at, source, factor = chart_indices(nx, nz, ni, iq, iw, starts[:-1]) if iq >= 0 else (np.zeros(0, int),) * 3
    if iq >= 0:  # q[1..4] gathered first, for |q|
        source = np.concatenate((np.arange(iq, iq + 4), source))
    buf = np.zeros(len(source))
    names = {"states": states, "inputs": tuple(ins), "outputs": tuple(outs), "nominals": scale}
    fields = (
        {"": LinearModel.fields_with(**names)}
        if coordinates == "raw"
        else {f: LinearModel.fields_with(**names, coordinates="attitude error", frame=f) for f in FRAMES}
    )
    p = Plan(
        ins, outs, in_vrs, out_vrs, unknowns, knowns, scale, states, T, S, turning, seeds, iq, iw,
        coordinates, store, at, source, factor, tuple(ins), tuple(outs), buf, buf[:4], buf[4:40], buf[4:],
        buf[40:], fields, me.directional_calls(unknowns, knowns, seeds), me.difference_calls(out_vrs, in_vrs, nz),
    )  # fmt: skip
    me.plans[key] = p
    return p


def at_plan_point(pl: Plan, x0: np.ndarray, frame: str) -> np.ndarray:
    """Rewrite the plan's chart blocks (T, S, turning, the seeds' q block) for the point's
    states x0 in the reference `frame`: the entries of fmu.linear.attitude.chart_values, to
    the bit, as `chart` writes them (CHART_ENTRIES: q₀ = q/|q| and ω₀ times ±½ or ±2; the
    turning 0 in a fixed frame); returns ω₀ (a view of x0; ZERO3, read-only zeros, in raw
    coordinates, without a quaternion and in a fixed frame)."""
    if pl.coordinates == "raw":
        return ZERO3
    if frame not in FRAMES:
        raise ModelInputError(f"frame must be one of {', '.join(FRAMES)}, got {frame!r}")
    if pl.iq < 0:
        return ZERO3
    # into the plan's buffer, q[1..4] first, and into its store (mode "clip": the indices are
    # valid; numpy's default "raise" would gather into a temporary first, or check each index)
    x0.take(pl.chart_from, out=pl.chart_buf, mode="clip")
    q, q_entries = pl.chart_q, pl.chart_q_entries
    q_entries /= math.sqrt(q.dot(q))  # q₀, as chart_values divides (ddot, as its q.dot(q))
    v = pl.chart_entries
    v *= pl.chart_factor
    if frame == "rotating" and pl.iw >= 0:
        pl.store.put(pl.chart_at, v, mode="clip")
        return x0[pl.iw : pl.iw + 3]
    pl.chart_turning.fill(0.0)  # no turning in a fixed reference (+0.0, as chart_values writes it)
    pl.store.put(pl.chart_at, v, mode="clip")
    return ZERO3


def set_point(me: ModelExchange, pl: Plan, point: OperatingPoint, frame: str) -> tuple[np.ndarray, ...]:
    """(x0, ω₀, ẋ₀): the plan's chart at the point (`at_plan_point`) and the instance put at
    it (`at_point`: states, inputs, then ẋ₀), in one call for `linearize` and its yardstick
    (fmu.linear.finite_differences.differences_model) alike."""
    x0 = point.x
    w0 = at_plan_point(pl, x0, frame)
    if list(point.states) != me.states:
        raise ModelInputError(f"operating point: its states {list(point.states)} are not the FMU's {me.states}")
    me.set_states(x0)
    me.set_inputs(point.inputs)
    return x0, w0, me.rates()


def chart_indices(nx: int, nz: int, ni: int, iq: int, iw: int, starts: np.ndarray) -> tuple[np.ndarray, ...]:
    """(at, source, factor) of `at_plan_point`'s 42 entries: T's q block (row-major 4 × 3),
    the same in the seeds' transpose, S's block (row-major 3 × 4), the turning's 6 entries
    (fmu.linear.attitude.CHART_ENTRIES, TURNING_AT); at: flat indices into the plan's store,
    whose T (nx × nz), seeds' transpose ((nz + nu) × (nx + nu)), S (nz × nx) and turning
    (nz × nz) start at `starts`; source: indices into x (q[1..4] from iq, ω₀ from iw, 0
    where there is no w_body[1]: those entries are then written 0); factor: ±½ or ±2."""
    rows, cols = np.divmod(np.arange(12), 3)  # T's block, row-major 4 × 3
    t_at = np.ravel_multi_index((iq + rows, cols), (nx, nz))
    seeds_at = np.ravel_multi_index((cols, iq + rows), (nz + ni, nx + ni))
    r, c = np.divmod(np.arange(12), 4)  # S's block, row-major 3 × 4
    s_at = np.ravel_multi_index((r, iq + c), (nz, nx))
    turn_at = np.ravel_multi_index(tuple(np.array(TURNING_AT).T), (nz, nz))
    at = np.concatenate((t_at + starts[0], seeds_at + starts[1], s_at + starts[2], turn_at + starts[3]))
    entries = np.array(CHART_ENTRIES)
    entries = np.concatenate((entries[:12], entries))  # T's block for T and for the seeds
    kind = entries[:, 0].astype(int)
    source = np.where(kind < 4, iq + kind, max(iw, 0) + kind - 4)
    return at, source, entries[:, 1].copy()


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
    if pl.coordinates == "raw":
        return LinearModel.made_with(pl.fields[""], J[:nx, :nz], J[:nx, nz:], J[nx:, :nz], J[nx:, nz:], point, xdot)
    S = pl.S
    # one product for both: S [A_x T, B_x] = [S (A_x T), S B_x], each entry the same dot
    # product of BLAS's dgemm as in two products (the same bits, checked by
    # tests/linear/test_linearize_bits.py); ż₀ stays a product of its own (dgemv), whose
    # sums may round otherwise. ndarray.dot, not @: the same BLAS calls (dgemm, dgemv) without
    # the ufunc machinery of matmul, 0.3-0.4 µs less per product
    SAB = S.dot(J[:nx])
    Az = SAB[:, :nz]
    Az += pl.turning  # in place: the sum S (A_x T) + turning without a second array
    zdot = S.dot(xdot)
    if pl.iq >= 0:
        zdot[:3] -= w0
    return LinearModel.made_with(pl.fields[frame], Az, SAB[:, nz:], J[nx:, :nz], J[nx:, nz:], point, zdot)


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
            _, w0, xdot = set_point(me, pl, point, frame)
            J = pl.jacobian()
        finally:
            if instance is None:
                me.close()
    return assemble(J, xdot, me, point, pl, w0, frame)
