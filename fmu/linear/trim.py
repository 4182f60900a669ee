"""Trim: the inputs (and, where asked, states) that make chosen derivatives zero and outputs take given values.

Newton's method on the FMU's exact derivatives (fmi3GetDirectionalDerivative, one call per
unknown), with a backtracking line search on the scaled residual (Dennis & Schnabel,
"Numerical Methods for Unconstrained Optimization and Nonlinear Equations", §6.3), least
squares where there are more equations than unknowns. Unknowns: inputs, states other
than the quaternion, and `attitude` (the three components of a rotation δθ of the start
attitude, body frame: q = q₀ ⊗ exp(δθ/2), docs/theory.md §10.1). Equations: `der(STATE)`
(that derivative is 0; not of q, whose rate at a relative equilibrium is not 0), `OUTPUT`
(the output is 0) or `OUTPUT=VALUE`. It says when there is no trim point (the residual
stops falling above the tolerance) or the point found is not unique (the scaled Jacobian
there is singular: a family of trim points through it), and refuses more unknowns than
equations.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from modelsrc.errors import ModelInputError, finite_number
from modelsrc.features.rotors.scene_file import speed_of_rate

from ..drive.logged_warnings import LoggedWarnings
from .attitude import QUATERNION, left_matrix, rotate
from .linearize import at_point, expand_names
from .model_exchange import ModelExchange
from .operating_point import OperatingPoint

ATTITUDE_UNKNOWN = "attitude"
# Converged when every equation's residual is below TOLERANCE times its scale (its
# terms' size at the start): round-off of the FMU's derivatives is a few ε of that.
TOLERANCE = 1e-12
# The scaled Jacobian is singular (the solution not unique) below this ratio of its
# smallest to its largest singular value: far above round-off (ε ~ 2e-16 relative), far
# below any physical conditioning of these models.
SINGULAR = 1e-9
MAX_ITERATIONS = 50


class TrimError(ModelInputError):
    """No trim point, or not a unique one; `result` holds where Newton ended."""

    def __init__(self, message: str, result: TrimResult):
        super().__init__(message)
        self.result = result


@dataclass(frozen=True)
class TrimResult:
    """point: the trimmed operating point; unknowns, values: the unknowns' names (attitude
    as attitude[1..3]) and their values (attitude: the rotation from the start, rad, body
    frame); equations, residual: the equations and what is left of them; iterations;
    singular_values: of the scaled Jacobian at the point (the smallest over the largest
    below SINGULAR: not unique)."""

    point: OperatingPoint
    unknowns: tuple[str, ...]
    values: np.ndarray
    equations: tuple[str, ...]
    residual: np.ndarray
    iterations: int
    singular_values: np.ndarray

    def report(self) -> str:
        """The trim point as text."""
        rows = [f"trim point after {self.iterations} Newton iterations:"]
        rows += [f"  {n} = {v:.15g}" for n, v in zip(self.unknowns, self.values)]
        rows += [f"  residual {e}: {r:.3g}" for e, r in zip(self.equations, self.residual)]
        sv = self.singular_values
        rows.append(f"  scaled Jacobian: smallest / largest singular value {sv[-1] / sv[0]:.3g} (unique)")
        return "\n".join(rows)


@dataclass(frozen=True)
class Equation:
    """der(state) = 0 (kind "der", index into the derivatives) or output = target."""

    text: str
    kind: str
    name: str
    target: float = 0.0


def parse_equations(texts: Sequence[str], me: ModelExchange) -> list[Equation]:
    """The equations given as text (a vector's base name for all its components)."""
    out: list[Equation] = []
    for text in texts:
        head, eq, value = text.partition("=")
        head = head.strip()
        target = finite_number(value, f"--equation {text!r}", "target") if eq else 0.0
        if head.startswith("der(") and head.endswith(")"):
            if eq:
                raise ModelInputError(f"--equation {text!r}: a derivative is trimmed to 0; give der(NAME) alone")
            for name in expand_names([head[4:-1]], me.states) or []:
                if name not in me.states:
                    raise ModelInputError(
                        f"--equation {text!r}: {name} is not a state of the FMU: {', '.join(me.states)}"
                    )
                if name in QUATERNION:
                    raise ModelInputError(
                        f"--equation {text!r}: the quaternion's rate is not 0 at a relative equilibrium (a spin); "
                        "trim der(w_body) and outputs such as w_lvlh instead"
                    )
                out.append(Equation(f"der({name})", "der", name))
        else:
            for name in expand_names([head], me.outputs) or []:
                if name not in me.outputs:
                    raise ModelInputError(
                        f"--equation {text!r}: {name!r} is neither der(STATE) nor an output of the FMU: "
                        f"{', '.join(me.outputs)}"
                    )
                out.append(Equation(f"{name} = {target:g}", "output", name, target))
    seen: set[tuple[str, str]] = set()
    for e in out:  # an equation twice would count twice against the unknowns
        if (e.kind, e.name) in seen:
            raise ModelInputError(f"--equation: {e.text} is asked for twice; give each equation once")
        seen.add((e.kind, e.name))
    return out


def parse_unknowns(names: Sequence[str], me: ModelExchange) -> list[str]:
    """The unknowns: inputs, states but q, and `attitude` (three unknowns)."""
    out: list[str] = []
    allowed = [*me.inputs, *(s for s in me.states if s not in QUATERNION)]
    if all(q in me.states for q in QUATERNION):
        allowed.append(ATTITUDE_UNKNOWN)
    for name in expand_names(names, allowed) or []:
        if name not in allowed:
            raise ModelInputError(f"--unknown {name!r}: allowed are the inputs, the states but q, and attitude: "
                                  f"{', '.join(allowed)}")  # fmt: skip
        out += [f"attitude[{k}]" for k in (1, 2, 3)] if name == ATTITUDE_UNKNOWN else [name]
    if len(set(out)) != len(out):
        raise ModelInputError(f"--unknown: each unknown once, got {', '.join(out)}")
    return out


def refuse_moving_rotors(start: OperatingPoint, unknowns: Sequence[str]) -> None:
    """ModelInputError for a speed-mode rotor whose speed changes at the start point
    (Omega_dot_<name> != 0) or is asked for as an unknown: a trim point holds every input, so
    a rotor's speed is constant there and its derivative 0; with Omega_dot_<name> ≠ 0 the
    point found would balance the reaction torque of an acceleration that does not go on,
    which is no trim point."""
    for name in unknowns:
        if speed_of_rate(name) is not None:
            raise ModelInputError(f"--unknown {name!r}: a trim point holds the rotor speeds, so {name} is 0 there; "
                                  f"ask for {speed_of_rate(name)} instead")  # fmt: skip
    for name, value in start.inputs.items():
        speed = speed_of_rate(name)
        if speed is not None and value != 0.0:
            raise ModelInputError(
                f"trim: {name} = {value:g} rad/s^2 at the start point, but a trim point holds every input, so "
                f"{speed} is constant there: --set '{name}=0', or hold {speed} (--set '{speed}=VALUE', or make it "
                "an --unknown), which makes its derivative 0"
            )


class Problem:
    """The trim equations at a point on an open instance: residual and Jacobian in the unknowns."""

    def __init__(self, me: ModelExchange, start: OperatingPoint, unknowns: list[str], equations: list[Equation]):
        self.me, self.start, self.unknowns, self.equations = me, start, unknowns, equations
        self.iq = me.states.index("q[1]") if "attitude[1]" in unknowns else -1
        self.out_vrs = me.value_references([e.name for e in equations if e.kind == "output"], me.outputs, "outputs")
        self.der_rows = [me.states.index(e.name) for e in equations if e.kind == "der"]
        self.targets = np.array([e.target for e in equations if e.kind == "output"])
        self.knowns = me.state_vrs + me.value_references(me.inputs, me.inputs, "inputs")

    def point(self, v: np.ndarray) -> OperatingPoint:
        """The operating point of the unknowns' values v."""
        states: dict[str, float] = {}
        inputs: dict[str, float] = {}
        x0 = self.start.x
        for name, value in zip(self.unknowns, v):
            if name.startswith("attitude["):
                continue
            (inputs if name in self.start.inputs else states)[name] = float(value)
        if self.iq >= 0:
            q = rotate(x0[self.iq : self.iq + 4], v[[self.unknowns.index(f"attitude[{k}]") for k in (1, 2, 3)]])
            states.update(zip(QUATERNION, map(float, q)))
        return self.start.with_values(states, inputs, source="trim")

    def residual(self, p: OperatingPoint) -> np.ndarray:
        xdot = at_point(self.me, p)
        y = self.me.get(self.out_vrs) if self.out_vrs else np.zeros(0)
        return np.concatenate((xdot[self.der_rows], y - self.targets))

    def jacobian(self, p: OperatingPoint) -> np.ndarray:
        """∂(residual)/∂(unknowns) at p (the instance at p): one directional derivative per
        unknown; attitude[k] seeds the quaternion with ∂q/∂δθ_k = ½ q ⊗ e_k (§10.1)."""
        me = self.me
        rows = [me.derivative_vrs[i] for i in self.der_rows] + self.out_vrs
        L = left_matrix(p.x[self.iq : self.iq + 4]) if self.iq >= 0 else None
        seeds = np.zeros((len(self.knowns), len(self.unknowns)))
        for j, name in enumerate(self.unknowns):
            if name.startswith("attitude["):
                seeds[self.iq : self.iq + 4, j] = 0.5 * L[:, int(name[9])]  # type: ignore[index]
            else:
                seeds[self.knowns.index(me.vr[name]), j] = 1.0
        return me.jacobian(rows, self.knowns, seeds)


def trim(
    fmu: str | Path,
    start: OperatingPoint,
    unknowns: Sequence[str],
    equations: Sequence[str],
    instance: ModelExchange | None = None,
) -> TrimResult:
    """Newton from `start` for the unknowns that satisfy the equations (module docstring).
    TrimError when there is no trim point reachable from the start or it is not unique;
    ModelInputError for more unknowns than equations or names the FMU does not have.
    instance: an open Model Exchange instance of this FMU, reused; else one is opened and
    closed. The warnings the FMU logs meanwhile (and at the initialisation of an instance
    opened here) are raised as FmuWarnings, as a run's (fmu.drive.logged_warnings)."""
    me = instance if instance is not None else ModelExchange(fmu, start.parameters)
    with LoggedWarnings(me, first=0 if instance is None else None):
        return _trim(me, start, unknowns, equations, close=instance is None)


def _trim(me: ModelExchange, start: OperatingPoint, unknowns: Sequence[str], equations: Sequence[str],
          close: bool) -> TrimResult:  # fmt: skip
    """`trim` on its instance, closed at the end if `close`."""
    try:
        eqs = parse_equations(equations, me)
        unk = parse_unknowns(unknowns, me)
        if not unk or not eqs:
            raise ModelInputError("trim needs at least one --unknown and one --equation")
        if len(unk) > len(eqs):
            raise ModelInputError(
                f"trim: {len(unk)} unknowns ({', '.join(unk)}) but {len(eqs)} equations "
                f"({', '.join(e.text for e in eqs)}): "
                "more unknowns than equations leave a family of solutions; add equations or fix unknowns with --set"
            )
        refuse_moving_rotors(start, unk)
        return newton(Problem(me, start, unk, eqs))
    finally:
        if close:
            me.close()


def newton(pb: Problem) -> TrimResult:
    """Damped Newton (least squares when overdetermined) on the scaled equations."""
    v = np.array([0.0 if n.startswith("attitude[") else {**pb.start.inputs, **pb.start.states}[n] for n in pb.unknowns])
    col = np.array([1.0 if n.startswith("attitude[") else max(abs(x), 1.0) for n, x in zip(pb.unknowns, v)])
    p = pb.point(v)
    r = pb.residual(p)
    J = pb.jacobian(p)
    row = np.maximum(np.abs(r) + np.abs(J) @ col, 1e-300)  # each equation's scale: its terms at the start
    it = 0
    while True:
        Js, rs = J * col / row[:, None], r / row
        sv = np.linalg.svd(Js, compute_uv=False)
        result = TrimResult(p, tuple(pb.unknowns), v.copy(), tuple(e.text for e in pb.equations), r, it, sv)
        if np.max(np.abs(rs)) <= TOLERANCE:
            if sv[-1] <= SINGULAR * sv[0]:
                raise TrimError(
                    "trim point found but not unique: the equations do not fix the unknowns "
                    f"({', '.join(pb.unknowns)}) "
                    f"there (scaled Jacobian's singular values {sv[0]:.3g} ... {sv[-1]:.3g}): a family of trim points; "
                    "fix some unknowns with --set or add equations",
                    result,
                )
            return result
        if it >= MAX_ITERATIONS:
            worst = np.max(np.abs(rs))
            raise TrimError(f"no trim point reached in {it} Newton iterations: scaled residual {worst:.3g} "
                            f"(tolerance {TOLERANCE:g})", result)  # fmt: skip
        step = np.linalg.lstsq(Js, -rs, rcond=None)[0] * col
        size, t = float(np.linalg.norm(rs)), 1.0
        while t > 1e-6:
            trial = pb.point(v + t * step)
            r_new = pb.residual(trial)
            if np.linalg.norm(r_new / row) < size:
                break
            t /= 2
        else:
            raise TrimError(
                "no trim point reachable from this start: the scaled residual stops falling at "
                f"{np.max(np.abs(rs)):.3g} "
                f"(tolerance {TOLERANCE:g}) after {it} Newton iterations, where the equations' least-squares gradient "
                f"is {np.linalg.norm(Js.T @ rs):.3g}; the equations have no solution near here",
                result,
            )
        v, p, r, it = v + t * step, trial, r_new, it + 1
        J = pb.jacobian(p)
