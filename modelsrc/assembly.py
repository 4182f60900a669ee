"""The model under construction (`Assembly`): the body's shared symbols, variables, torques and checks.

`model.build_model` creates one per scene and runs the body's and the features'
builders on it (modelsrc.registry, docs/features.md); `model_functions.py` turns the
finished assembly into the generated functions. It holds what the body and several
features share, with names that say what they hold; what only one feature uses lives in
that feature's own record (`feature_state`). It sits below the features so that all of
them import it from below (docs/theory.md §6).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Protocol, TypeVar

import casadi as ca

from .quaternion import Rotation
from .scene_data import SceneData
from .variables import Kind, Variable

T = TypeVar("T")


@dataclass
class StatePart:
    """A block of the state vector after q and ω, in value-reference order: `name` the base
    name of its variables (the key of its nominal, modelsrc.nominals), `symbol` its
    symbols, `rotational` whether it couples with the rotation (its rates then enter the
    step-size bound, docs/theory.md §5.4) and `rate` its time derivative, set by its feature
    once known."""

    name: str
    symbol: ca.SX
    rotational: bool
    rate: ca.SX | None = None


class PrincipalTerm(Protocol):
    """A torque the equations on principal axes take as an angular acceleration with
    coefficients derived once (the gravity gradient, docs/theory.md §9.2)."""

    def torque(self) -> ca.SX:
        """The torque (N·m, body), for equations that are not on principal axes."""
        ...

    def acceleration(self, coeff: ca.SX, prefix: str) -> ca.SX:
        """Its angular acceleration (rad/s², body) from the Euler coefficients `coeff`
        (k_i = (I_j − I_k)/M_i, expressions of p); `prefix` names its derived parameters."""
        ...


# a feature's energy relative to the body added to a total: (assembly, ω, total) -> total (J)
EnergyTerm = Callable[["Assembly", ca.SX, ca.SX], ca.SX]
# a feature's angular momentum relative to the body added to a total: (assembly, total) -> total (N·m·s)
MomentumTerm = Callable[["Assembly", ca.SX], ca.SX]


@dataclass
class Assembly:
    """The model under construction, filled feature by feature.

    quaternion, omega: the state symbols q (body -> world) and ω (rad/s, body);
    rotation: the rotation of q for any |q| as an operator (quaternion.Rotation, three
    products per rotated vector), rotation_matrix: the same as a matrix (outputs);
    state_parts: the states after q and ω (`StatePart`); input_blocks, param_blocks: the
    symbols of u and p in order; inertia: about the point the body turns about (kg·m²,
    body; derived parameters once `model.finish_inertia` ran), inertia_inv its inverse,
    inertia_cm: about the centre of mass; torque: the total torque (N·m, body);
    potential: the potential energy (J) or None; friction_coefficient: the viscous
    friction coefficient's symbol or None, friction_index its position in p; checks:
    (text, expression, strict) evaluated at initialisation; positive_parameters: the names of
    the parameters that, like the mass, are in [POSITIVE_MIN, PARAM_MAX] rather than
    |p| <= PARAM_MAX (a rotor's J; model.add_parameter_ranges). The moving reference point:
    position, velocity (m, m/s, world) its states or None, acceleration (m/s², world);
    force_world: the external forces but the pivot's (N, world), force_body: forces given
    in the body frame (N), summed and turned into the world frame once; mass, gravity (g,
    m/s², world), r_cm (pivot -> centre of mass, m, body), pivot_acceleration (a moving
    pivot's, m/s², world): symbols or None. principal_terms: torques kept out of `torque`
    on principal axes. derived: (symbol, expression of p) of every derived parameter
    (`derive`). energy_terms, momentum_terms: the features' contributions relative to the
    body (`internal_energy`, `internal_momentum`)."""

    scene: SceneData
    quaternion: ca.SX = field(default_factory=lambda: ca.SX.sym("q", 4))
    omega: ca.SX = field(default_factory=lambda: ca.SX.sym("w", 3))
    variables: list[Variable] = field(default_factory=list)
    state_parts: list[StatePart] = field(default_factory=list)
    input_blocks: list[ca.SX] = field(default_factory=list)
    param_blocks: list[ca.SX] = field(default_factory=list)
    checks: list[tuple[str, ca.SX, bool]] = field(default_factory=list)
    positive_parameters: list[str] = field(default_factory=list)
    torque: ca.SX = field(default_factory=lambda: ca.SX.zeros(3))
    inertia: ca.SX = field(default_factory=lambda: ca.SX.zeros(3, 3))  # set by add_inertia
    potential: ca.SX | None = None
    potential_field: str = "uniform gravity"  # the field whose potential it is, as the outputs name it
    friction_coefficient: ca.SX | None = None
    friction_index: int | None = None
    position: ca.SX | None = None
    velocity: ca.SX | None = None
    acceleration: ca.SX = field(default_factory=lambda: ca.SX.zeros(3))
    force_world: ca.SX = field(default_factory=lambda: ca.SX.zeros(3))
    mass: ca.SX | None = None
    gravity: ca.SX | None = None
    r_cm: ca.SX | None = None
    pivot_acceleration: ca.SX | None = None
    h_max_index: int = -1
    method: ca.SX = field(default_factory=lambda: ca.SX.sym("method"))  # the selected method's value
    # forces given in the body frame (N), summed before they are turned into the world frame
    # once (the reference point's acceleration): one rotation per right-hand side, not one per force
    force_body: ca.SX = field(default_factory=lambda: ca.SX.zeros(3))
    principal_terms: list[PrincipalTerm] = field(default_factory=list)
    # ω̇ on principal axes for the steps of a tensor diagonal as set (model.finish_inertia,
    # model_functions.principal_steps), None where there are none
    omega_dot_principal: ca.SX | None = None
    inertia_inv: ca.SX | None = None
    split_axes: ca.SX | None = None
    derived: list[tuple[ca.SX, ca.SX]] = field(default_factory=list)
    off_diagonal: list[int] = field(default_factory=list)  # entries off the diagonals of I_rot, I_rot_inv in d
    # the step-size bound measures the rates in nominal units: a body turning slowly in an
    # orbit (docs/theory.md §9.1, §9.7; model_functions.orbit_scaled_jacobian)
    rates_in_nominal_units: bool = False
    energy_terms: list[EnergyTerm] = field(default_factory=list)
    momentum_terms: list[MomentumTerm] = field(default_factory=list)
    feature_states: dict[str, Any] = field(default_factory=dict)
    # a clock state (angle θ, its rate n as an expression of p and d, and the symbols that
    # stand for sin θ and cos θ in the right-hand side): the orbit angle with the gravity
    # gradient (modelsrc.features.orbit). model_functions substitutes sin θ and cos θ for the
    # symbols everywhere but in the fixed steps, which take them by angle addition
    # (modelsrc.integrators.Clock); None without one
    clock: tuple[ca.SX, ca.SX, ca.SX, ca.SX] | None = None
    # the torque without the dissipative terms (the splittings' kick, docs/theory.md §5.3),
    # set when one is added (add_dissipative_torque)
    _conservative_torque: ca.SX | None = None

    def __post_init__(self) -> None:
        self.rotation = Rotation(self.quaternion)  # a rotation for any |q| (Model Exchange lets |q| drift)
        self.rotation_matrix = self.rotation.matrix  # the same R as a matrix: outputs; the right-hand sides use it
        self.inertia_cm = self.inertia

    def feature_state(self, name: str, make: Callable[[], T]) -> T:
        """The record of feature `name` (its own symbols), made by `make` on first use."""
        if name not in self.feature_states:
            self.feature_states[name] = make()
        state: T = self.feature_states[name]
        return state

    @property
    def states(self) -> ca.SX:
        """The state x: q, ω, then the state parts in order (a moving reference point's
        position and velocity, the rotor rates, the orbit angle)."""
        return ca.vertcat(self.quaternion, self.omega, *[part.symbol for part in self.state_parts])

    @property
    def inputs(self) -> ca.SX:
        """The inputs u, in value-reference order."""
        return ca.vertcat(*self.input_blocks) if self.input_blocks else ca.SX.zeros(0, 1)

    @property
    def params(self) -> ca.SX:
        """The parameters p, in value-reference order."""
        return ca.vertcat(*self.param_blocks)

    @property
    def derived_params(self) -> ca.SX:
        """The derived parameters' symbols d, in order."""
        return ca.vertcat(*[sym for sym, _ in self.derived]) if self.derived else ca.SX.zeros(0, 1)

    @property
    def derived_values(self) -> ca.SX:
        """The derived parameters as expressions of p (what `model_derived` evaluates)."""
        return ca.vertcat(*[e for _, e in self.derived]) if self.derived else ca.SX.zeros(0, 1)

    def derive(self, name: str, expr: ca.SX) -> ca.SX:
        """A symbol of expr's shape standing for expr, a function of the parameters only:
        the equations use the symbol, the FMU evaluates expr once per parameter change."""
        sym = ca.SX.sym(name, expr.shape[0], expr.shape[1])
        self.derived.append((ca.vec(sym), ca.vec(expr)))
        return sym

    def without_derived(self, expr: ca.SX) -> ca.SX:
        """expr with every derived symbol replaced by its expression of p (for the
        validity checks, which run on the parameters as set)."""
        if not self.derived:
            return expr
        return ca.substitute(expr, self.derived_params, self.derived_values)

    def add(self, names: list[str], kind: Kind, starts: list[float | None], unit: str | None, descs: list[str]) -> None:
        """Append one variable per name (value references follow in order)."""
        for n, s, d in zip(names, starts, descs):
            self.variables.append(Variable(n, kind, None if s is None else float(s), unit, d))

    def parameter(
        self, sym: ca.SX, names: list[str], starts, unit: str | None, descs: list[str], kind: Kind = Kind.PARAM_FIXED
    ) -> int:
        """A parameter block: its symbol joins p, its variables the table; returns its offset in p."""
        offset = sum(part.shape[0] for part in self.param_blocks)
        self.param_blocks.append(sym)
        self.add(names, kind, list(starts), unit, descs)
        return offset

    def add_dissipative_torque(self, term: ca.SX) -> None:
        """Add a torque that is not conservative (friction): the splittings damp it exactly
        instead of kicking with it (docs/theory.md §4.3, §5.3)."""
        self._conservative_torque = self.torque
        self.torque = self.torque + term

    @property
    def conservative_torque(self) -> ca.SX:
        """The torque without its dissipative terms (N·m, body): the splittings' kick."""
        return self.torque if self._conservative_torque is None else self._conservative_torque

    def torque_without_friction(self) -> ca.SX:
        """The body torque but viscous friction (N·m): the equations on principal axes take
        friction as the rates c/I_i, computed once (rigid_body.principal_euler_rhs)."""
        c = self.friction_coefficient
        return self.torque if c is None else ca.substitute(self.torque, c, ca.SX(0))

    def internal_energy(self, omega: ca.SX, total: ca.SX | None = None) -> ca.SX:
        """total (default 0) plus the kinetic energy the features carry relative to the body
        at the body rate `omega` (J; the rotors' Σ J Ω (g·ω) + ½ Σ J Ω², docs/theory.md §8.2)."""
        out: ca.SX = ca.SX(0) if total is None else total
        for term in self.energy_terms:
            out = term(self, omega, out)
        return out

    def internal_momentum(self) -> ca.SX:
        """The angular momentum the features carry relative to the body (N·m·s, body; the
        rotors' h = Σ J Ω g, docs/theory.md §8.1), zero without."""
        h: ca.SX = ca.SX.zeros(3)
        for term in self.momentum_terms:
            h = term(self, h)
        return h
