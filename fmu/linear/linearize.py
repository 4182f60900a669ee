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

from ..drive.logged_warnings import LoggedWarnings, warn_logged
from .attitude import ATTITUDE, CHART_ENTRIES, DRIFT_AT, FRAMES, RATE, TURNING_AT, Chart, chart, layout
from .linear_model import LinearModel
from .model_exchange import ModelExchange
from .operating_point import OperatingPoint

COORDINATES = ("attitude", "raw")
# the offset's entries (Plan.chart_turning) in a fixed reference: the turning +0.0, as
# chart_values writes it and the formula adds it, and −ω₀ −0.0, which added leaves every
# number as subtracting ω₀ = +0.0 does (−0.0 too, where adding +0.0 would give +0.0)
NO_TURNING = np.array([0.0] * 6 + [-0.0] * 3)


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
    the chart's T (`directions`, nx × nz, the identity in raw coordinates) and S, the
    offset (nz × (nz + 1): the reference's turning in its first nz columns, −ω₀ on δθ in
    its last, fmu.linear.attitude.CHART_ENTRIES), the seeds (T and the inputs' unit
    vectors, one column per fmi3GetDirectionalDerivative), and the FMI calls made ready on
    them (`jacobian`, and `differences` for the yardstick, fmu.linear.finite_differences),
    whose result J has ẋ₀ as its column nz, between the directions' and the inputs' (so
    that one product reduces the Jacobian and the drift, `assemble`). Only the blocks of
    the quaternion and ω₀ change with the point (fmu.linear.attitude.chart_values); iq,
    iw: the indices of q[1] and w_body[1] in x (−1 where the FMU has none, or in raw
    coordinates). T, the seeds' transpose, S and the offset are views into one array,
    `store`, so that `at_plan_point` writes the point's entries into all four with one
    call: at `chart_at` (flat indices into store) the values x0[chart_from] (q's divided
    by |q|) times chart_factor (CHART_ENTRIES; T's block twice, for T and the seeds).
    chart_buf: where x0[chart_from] is gathered (q[1..4] first, for |q|, then the 45
    entries), with its views chart_q, chart_q_entries (the 36 divided by |q|),
    chart_entries (the 45) and chart_turning (the last 9: turning and −ω₀), made once so
    that a point pays no slicing. fields: the LinearModel's fields that are the same at
    every point, per frame (raw coordinates: under ""), for LinearModel.made_with."""

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
    offset: np.ndarray
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
    nx: int
    nz: int
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
    for asked, what in ((ins, "inputs"), (outs, "outputs")):
        twice = sorted({n for n in asked if asked.count(n) > 1})
        if twice:  # a row or column twice: a model of more inputs or outputs than there are
            raise ModelInputError(f"{what}: {', '.join(twice)} asked for twice; give each once")
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
    sizes = (nx * nz, (nz + ni) * (nx + ni), nz * nx, nz * (nz + 1))  # T, the seeds' transpose, S, offset
    starts = np.cumsum((0, *sizes))
    store = np.zeros(starts[-1])
    T, seeds_t, S, offset = (store[a:b] for a, b in itertools.pairwise(starts))
    T, S, offset = T.reshape(nx, nz), S.reshape(nz, nx), offset.reshape(nz, nz + 1)
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
        ins, outs, in_vrs, out_vrs, unknowns, knowns, scale, states, T, S, offset, seeds, iq, iw,
        coordinates, store, at, source, factor, tuple(ins), tuple(outs), buf, buf[:4], buf[4:40], buf[4:],
        buf[40:], fields, nx, nz, me.directional_calls(unknowns, knowns, seeds, rates_at=nz),
        me.difference_calls(out_vrs, in_vrs, nz, rates_at=True),
    )  # fmt: skip
    me.plans[key] = p
    return p


def at_plan_point(pl: Plan, x0: np.ndarray, frame: str) -> None:
    """Rewrite the plan's chart blocks (T, S, the offset, the seeds' q block) for the
    point's states x0 in the reference `frame`: the entries of
    fmu.linear.attitude.chart_values, to the bit, as `chart` writes them (CHART_ENTRIES: q₀
    = q/|q| and ω₀ times ±½, ±2 or −1; the turning and −ω₀ 0 in a fixed frame or without
    w_body). Nothing to write in raw coordinates, or without a quaternion (iq −1 in both);
    frame: one of FRAMES (`frame_of`)."""
    if pl.iq < 0:
        return
    # into the plan's buffer, q[1..4] first, and into its store (mode "clip": the indices are
    # valid; numpy's default "raise" would gather into a temporary first, or check each index)
    x0.take(pl.chart_from, out=pl.chart_buf, mode="clip")
    q = pl.chart_q
    norm = math.sqrt(q.dot(q))  # ddot, as chart_values' q.dot(q)
    if norm != 1.0:  # q₀ = q/|q|, as chart_values divides (a division by 1.0 would change no bit)
        q_entries = pl.chart_q_entries
        q_entries /= norm
    v = pl.chart_entries
    v *= pl.chart_factor
    if frame != "rotating" or pl.iw < 0:  # no turning in a fixed reference, no ω₀ to subtract
        pl.chart_turning[:] = NO_TURNING
    pl.store.put(pl.chart_at, v, mode="clip")


def frame_of(coordinates: str, frame: str | None) -> str:
    """The attitude reference of a linearisation in `coordinates` with `frame` asked (None:
    "rotating" in attitude-error coordinates, "" in raw ones); ModelInputError for unknown
    coordinates or frame, and for a frame asked in raw coordinates, which have none."""
    if coordinates not in COORDINATES:
        raise ModelInputError(f"coordinates must be one of {', '.join(COORDINATES)}, got {coordinates!r}")
    if coordinates == "raw":
        if frame is not None:
            raise ModelInputError(f"frame {frame!r}: the raw coordinates (the FMU's q[1..4]) have no attitude "
                                  "reference; a frame applies to attitude-error coordinates")  # fmt: skip
        return ""
    if frame is None:
        return "rotating"
    if frame not in FRAMES:
        raise ModelInputError(f"frame must be one of {', '.join(FRAMES)}, got {frame!r}")
    return frame


def set_point(me: ModelExchange, pl: Plan, point: OperatingPoint, frame: str) -> np.ndarray:
    """The plan's chart at the point (`at_plan_point`) and the instance put at it (states,
    inputs), in one call for `linearize` and its yardstick
    (fmu.linear.finite_differences.differences_model) alike; returns x0, the point's states."""
    x0 = point.x
    at_plan_point(pl, x0, frame)
    if point.state_names != me.state_names:
        raise ModelInputError(f"operating point: its states {list(point.states)} are not the FMU's {me.states}")
    me.set_states(x0)
    if point.input_names == me.input_names:  # every input, in the FMU's order: one call of the vector
        me.set_input_vector(point.u)
    else:
        me.set_inputs(point.inputs)
    return x0


def chart_indices(nx: int, nz: int, ni: int, iq: int, iw: int, starts: np.ndarray) -> tuple[np.ndarray, ...]:
    """(at, source, factor) of `at_plan_point`'s 45 entries: T's q block (row-major 4 × 3),
    the same in the seeds' transpose, S's block (row-major 3 × 4), the turning's 6 entries
    and −ω₀ (fmu.linear.attitude.CHART_ENTRIES, TURNING_AT, DRIFT_AT); at: flat indices into
    the plan's store, whose T (nx × nz), seeds' transpose ((nz + nu) × (nx + nu)), S
    (nz × nx) and offset (nz × (nz + 1)) start at `starts`; source: indices into x (q[1..4]
    from iq, ω₀ from iw, 0 where there is no w_body[1]: those entries are then written 0);
    factor: ±½, ±2 or −1."""
    rows, cols = np.divmod(np.arange(12), 3)  # T's block, row-major 4 × 3
    t_at = np.ravel_multi_index((iq + rows, cols), (nx, nz))
    seeds_at = np.ravel_multi_index((cols, iq + rows), (nz + ni, nx + ni))
    r, c = np.divmod(np.arange(12), 4)  # S's block, row-major 3 × 4
    s_at = np.ravel_multi_index((r, iq + c), (nz, nx))
    cells = np.array(TURNING_AT + DRIFT_AT)
    cells[:, 1] %= nz + 1  # DRIFT_AT's column −1: the offset's last
    turn_at = np.ravel_multi_index(tuple(cells.T), (nz, nz + 1))
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


def assemble(J: np.ndarray, me: ModelExchange, point: OperatingPoint, pl: Plan, frame: str) -> LinearModel:
    """The linear model from J = ∂(ẋ, y)/∂(directions, u) ((nx + ny) × (nz + 1 + nu), from
    directional derivatives or from differences along the same directions, with ẋ₀ as its
    column nz) and the plan's chart at the point (`at_plan_point`): in raw coordinates A,
    B, C, D are its blocks and ẋ₀ the drift; in the chart's, A_z = S (A_x T) + turning,
    B_z = S B_x, C_z = C_x T, and ż₀ = S ẋ₀ − ω₀ on δθ (docs/theory.md §10.1-10.2;
    fmu.linear.attitude.Chart.reduce)."""
    nx, nz = pl.nx, pl.nz
    if pl.coordinates == "raw":
        return LinearModel.made_with(pl.fields[""], J[:nx, :nz], J[:nx, nz + 1 :], J[nx:, :nz], J[nx:, nz + 1 :],
                                     point, J[:nx, nz])  # fmt: skip
    # one product for all three: S [A_x T, ẋ₀, B_x] = [S (A_x T), S ẋ₀, S B_x], each entry
    # the dot product BLAS's dgemm makes of its row and column, then one sum adding the
    # turning and −ω₀ (the offset). ndarray.dot, not @: the same BLAS call (dgemm) without
    # the ufunc machinery of matmul, 0.3-0.4 µs less per product
    S_J = pl.S.dot(J[:nx])
    S_J[:, : nz + 1] += pl.offset
    return LinearModel.made_with(pl.fields[frame], S_J[:, :nz], S_J[:, nz + 1 :], J[nx:, :nz], J[nx:, nz + 1 :],
                                 point, S_J[:, nz])  # fmt: skip


def linearize(
    fmu: str | Path,
    point: OperatingPoint,
    inputs: Sequence[str] | None = None,
    outputs: Sequence[str] | None = None,
    coordinates: str = "attitude",
    frame: str | None = None,
    instance: ModelExchange | None = None,
) -> LinearModel:
    """The linear model of the FMU at `point`.

    inputs, outputs: the FMU's names (a vector's base name for all its components;
    default: every input and every output but the ZXZ Euler angles, which have no derivative
    at θ = 0 or π and can be asked for by name); coordinates "attitude"
    (δθ in place of q, the orbit's clock left out; docs/theory.md §10) or "raw" (the FMU's
    states); frame (attitude-error coordinates only): the attitude reference, "rotating"
    with the point's body rate (the default: a steady spin or a body at rest in an orbit
    frame is then an equilibrium) or "fixed"; asked in raw coordinates, it is refused.
    instance: an open Model Exchange instance of this FMU initialised with
    point.parameters, reused (the cost of a linearisation is then its FMI calls alone);
    else one is opened and closed. One fmi3GetDirectionalDerivative per minimal state
    (seeded with the chart's direction ∂x/∂z) and per input. The warnings the FMU logs
    meanwhile (and at the initialisation of an instance opened here) are raised as
    FmuWarnings, as a run's (fmu.drive.logged_warnings).
    """
    frame = frame_of(coordinates, frame)
    me = instance if instance is not None else ModelExchange(fmu, point.parameters)
    first = 0 if instance is None else len(me.warnings)  # an instance opened here: its initialisation's too
    try:
        pl = plan(me, inputs, outputs, coordinates)
        set_point(me, pl, point, frame)
        J = pl.jacobian()
    except BaseException:
        with LoggedWarnings(me, first):  # shown also when the call failed, never hiding its error
            raise
    finally:
        if instance is None:
            me.close()
    if len(me.warnings) > first:  # LoggedWarnings' work, without its object where nothing was logged
        warn_logged(me, first, stacklevel=2)
    return assemble(J, me, point, pl, frame)
