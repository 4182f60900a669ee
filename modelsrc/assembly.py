"""The model under construction (`Assembly`): symbols, FMI variables, torques and checks that the feature builders fill.

`model.build_model` creates one per scene and runs the builders of `model.py` and
`free_motion.py` on it; `model_functions.py` turns the finished assembly into the
generated functions. It lives in a module of its own so that all three import it
from below (docs/theory.md §6).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca

from .quaternion import Rotation
from .scene import Scene
from .variables import Kind, Variable


@dataclass
class Assembly:
    """The model under construction, filled feature by feature.

    q, w: state symbols; R: rotation body -> world of q (any |q|), rot: the same as an
    operator (quaternion.Rotation, three products per rotated vector); I: inertia about the
    point the body turns about (kg·m², body), I_inv its inverse (derived parameters once
    `finish_inertia` ran); I_cm: about the centre of mass;
    tau: total torque (N·m, body); tau_conservative: all but friction (the splittings'
    kick); V: potential energy (J) or None; c: friction coefficient symbol or None,
    c_index its position in p; checks: (text, expression, strict) evaluated at
    initialisation. The moving reference point (free_motion.py): pos, vel (m, m/s,
    world) its states or None; accel (m/s², world) its acceleration; force: the sum of
    the external forces but the pivot's (N, world); mass, g, r_cm, a_pivot: symbols or
    None; force_inputs: force point name -> its input symbol (N, in its frame);
    derived: (symbol, expression of p) of every derived parameter (`derive`)."""

    scene: Scene
    q: ca.SX = field(default_factory=lambda: ca.SX.sym("q", 4))
    w: ca.SX = field(default_factory=lambda: ca.SX.sym("w", 3))
    variables: list[Variable] = field(default_factory=list)
    u_parts: list[ca.SX] = field(default_factory=list)
    p_parts: list[ca.SX] = field(default_factory=list)
    checks: list[tuple[str, ca.SX, bool]] = field(default_factory=list)
    tau: ca.SX = field(default_factory=lambda: ca.SX.zeros(3))
    I: ca.SX = field(default_factory=lambda: ca.SX.zeros(3, 3))  # set by add_inertia
    V: ca.SX | None = None
    c: ca.SX | None = None
    c_index: int | None = None
    r_sensor: ca.SX | None = None
    pos: ca.SX | None = None
    vel: ca.SX | None = None
    accel: ca.SX = field(default_factory=lambda: ca.SX.zeros(3))
    force: ca.SX = field(default_factory=lambda: ca.SX.zeros(3))
    mass: ca.SX | None = None
    g: ca.SX | None = None
    r_cm: ca.SX | None = None
    a_pivot: ca.SX | None = None
    force_inputs: dict[str, ca.SX] = field(default_factory=dict)
    h_max_index: int = -1
    method: ca.SX = field(default_factory=lambda: ca.SX.sym("method"))  # the selected method's value
    # forces given in the body frame (N), summed before they are turned into the world frame
    # once (free_motion.reference_acceleration): one rotation per right-hand side, not one per force
    force_body: ca.SX = field(default_factory=lambda: ca.SX.zeros(3))
    # the gravity gradient on principal axes (modelsrc.orbit): ĉ, the nadir in the body frame,
    # kept out of tau: the angular acceleration takes it as 3 n² (I_3 − I_2)/I_1 ĉ_2 ĉ_3 (cyclic)
    nadir: ca.SX | None = None
    # ω̇ on principal axes for the steps of a tensor diagonal as set (model.finish_inertia,
    # model_functions.principal_steps), None where there are none
    w_dot_principal: ca.SX | None = None
    I_inv: ca.SX | None = None
    split_axes: ca.SX | None = None
    derived: list[tuple[ca.SX, ca.SX]] = field(default_factory=list)
    off_diagonal: list[int] = field(default_factory=list)  # d's entries off the diagonals of I_rot, I_rot_inv
    # the rotors (modelsrc.rotors, docs/theory.md §8), one entry per rotor in scene order: states
    # Omega (rad/s), inputs u (N·m), axial inertias J (kg·m²) and unit axes g (body, constants);
    # rotor_M_inv: the derived (I − Σ J g gᵀ)⁻¹
    # rotor_rates and rotor_torques: the torque-mode rotors' states and inputs only; rotor_speed,
    # rotor_accel: every rotor's Ω by name (a state or, in speed mode, an input) and the
    # speed-mode rotors' input Ω̇ (§8.5)
    rotor_rates: list[ca.SX] = field(default_factory=list)
    rotor_torques: list[ca.SX] = field(default_factory=list)
    rotor_inertias: list[ca.SX] = field(default_factory=list)
    rotor_axes: list[ca.DM] = field(default_factory=list)
    rotor_M_inv: ca.SX | None = None
    rotor_inv_J: list[ca.SX] = field(default_factory=list)  # the derived 1/J of the torque-mode rotors
    # a diagonal I − Σ J g gᵀ: (the gyroscopic coefficients (I_2 − I_3) M⁻¹_1 ... as expressions
    # of p, the derived M⁻¹_i), else None (rotors.principal_gyrostat_rates)
    rotor_principal: tuple[ca.SX, ca.SX] | None = None
    rotor_speed: dict[str, ca.SX] = field(default_factory=dict)
    rotor_accel: dict[str, ca.SX] = field(default_factory=dict)
    # the circular orbit (modelsrc.orbit, docs/theory.md §9): the orbit angle state θ (rad)
    # and the rate n (rad/s), None without features.orbit
    orbit_angle: ca.SX | None = None
    n_orbit: ca.SX | None = None

    def __post_init__(self) -> None:
        self.rot = Rotation(self.q)  # a rotation for any |q| (Model Exchange lets |q| drift)
        self.R = self.rot.matrix  # the same R as a matrix: outputs; the right-hand sides use rot
        self.tau_conservative = self.tau
        self.I_cm = self.I

    @property
    def x(self) -> ca.SX:
        """The state: q, w, then the reference point's (pos, vel) if it moves, then the rotor
        rates, then the orbit angle in an orbit."""
        motion = [] if self.pos is None or self.vel is None else [self.pos, self.vel]
        orbit = [] if self.orbit_angle is None else [self.orbit_angle]
        return ca.vertcat(self.q, self.w, *motion, *self.rotor_rates, *orbit)

    @property
    def u(self) -> ca.SX:
        return ca.vertcat(*self.u_parts) if self.u_parts else ca.SX.zeros(0, 1)

    @property
    def p(self) -> ca.SX:
        return ca.vertcat(*self.p_parts)

    @property
    def d(self) -> ca.SX:
        """The derived parameters' symbols, in order."""
        return ca.vertcat(*[sym for sym, _ in self.derived]) if self.derived else ca.SX.zeros(0, 1)

    @property
    def d_expr(self) -> ca.SX:
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
        return ca.substitute(expr, self.d, self.d_expr)

    def add(self, names: list[str], kind: Kind, starts: list[float | None], unit: str | None, descs: list[str]) -> None:
        """Append one variable per name (value references follow in order)."""
        for n, s, d in zip(names, starts, descs):
            self.variables.append(Variable(n, kind, None if s is None else float(s), unit, d))

    def parameter(
        self, sym: ca.SX, names: list[str], starts, unit: str | None, descs: list[str], kind: Kind = Kind.PARAM_FIXED
    ) -> int:
        """A parameter block: its symbol joins p, its variables the table; returns its offset in p."""
        offset = sum(part.shape[0] for part in self.p_parts)
        self.p_parts.append(sym)
        self.add(names, kind, list(starts), unit, descs)
        return offset
