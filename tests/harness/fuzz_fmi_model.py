"""The fuzz test's independent model of the FMI 3.0 layer: the state table, the checks, the values drawn.

Written from docs/fmi_layer.md and the FMI 3.0 standard, not from the C: tests/robustness/test_fuzz_fmi.py
predicts every call's outcome with it, and tests/fmi/test_fmi_rules.py compares its tables with
the masks of fmu/c/rbfmu_fmi3.c and rbfmu_core.c.
"""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass, field

from modelsrc.methods import METHODS, WORK_LIMIT_MAX

from .fmi3_ctypes import ModelInfo

INST, INIT, STEP, EVENT, CONT, TERM, ERR, IUM = (
    "Instantiated",
    "InitializationMode",
    "StepMode",
    "EventMode",
    "ContinuousTimeMode",
    "Terminated",
    "Error",
    "IntermediateUpdateMode",
)
ALL_STATES = (INST, INIT, STEP, EVENT, CONT, TERM, ERR, IUM)
# IntermediateUpdateMode exists only inside doStep while the importer's intermediateUpdate
# callback runs (FMI 3.0 §4.2.3): it admits setting inputs (and SetDebugLogging), nothing else.
ANY = {INST, INIT, STEP, EVENT, CONT, TERM, ERR}
CS_STATES = (INST, INIT, STEP, TERM, ERR)
ME_STATES = (INST, INIT, EVENT, CONT, TERM, ERR)
GETTERS = {INIT, STEP, EVENT, CONT, TERM, ERR}

# Where each function may be called: docs/fmi_layer.md for the Co-Simulation states; the
# Model Exchange and FMU-state rows follow rbfmu_fmi3.c (the docs table predates them).
ALLOWED = {
    "fmi3EnterInitializationMode": {INST},
    "fmi3ExitInitializationMode": {INIT},
    "fmi3SetFloat64": {INST, INIT, STEP, EVENT, CONT, IUM},  # and per variable kind: SETTABLE
    "fmi3GetFloat64": GETTERS,
    "fmi3SetInt64": {INST, INIT, STEP, EVENT},
    "fmi3GetInt64": GETTERS,
    "fmi3DoStep": {STEP},
    "fmi3Terminate": {STEP, EVENT, CONT},
    "fmi3Reset": set(ANY),
    "fmi3SetDebugLogging": ANY | {IUM},
    "fmi3EnterEventMode": {EVENT, CONT},
    "fmi3EnterStepMode": set(),  # Co-Simulation without event mode: never
    "fmi3EnterContinuousTimeMode": {EVENT},
    "fmi3CompletedIntegratorStep": {CONT},
    "fmi3SetTime": {EVENT, CONT},
    "fmi3SetContinuousStates": {CONT},
    "fmi3GetContinuousStates": {INIT, EVENT, CONT, TERM, ERR},
    "fmi3GetContinuousStateDerivatives": {INIT, EVENT, CONT, TERM, ERR},
    "fmi3UpdateDiscreteStates": {EVENT},
    "fmi3GetFMUState": GETTERS,
    "fmi3SetFMUState": GETTERS,
    "fmi3FreeFMUState": set(ANY),
    "fmi3SerializedFMUStateSize": set(ANY),
    "fmi3SerializeFMUState": set(ANY),
    "fmi3DeserializeFMUState": set(ANY),
    "fmi3GetNumberOfContinuousStates": set(ANY),
}
SETTABLE = {
    "state": {INST, INIT},
    "fixed": {INST, INIT},
    "input": {INST, INIT, STEP, EVENT, CONT, IUM},
    "tunable": {INST, INIT, STEP, EVENT},
    "independent": set(),
    "output": set(),
    "derivative": set(),
    "local": set(),  # the step report (internal_steps, ...): doStep writes it
}

# Validity checks of exitInitializationMode (generated model_checks): a fragment of each
# message, as written in modelsrc/model.py and modelsrc/inertia.py.
CHK_PD = "inertia must be positive definite"
CHK_TRIANGLE = "principal moments must satisfy I_i + I_j >= I_k"
CHK_MASS = "mass must be > 0"
CHK_FRICTION = "c_friction must be >= 0"
CHK_HMAX = "h_max must be >= 0"
CHK_TOL = "tolerance must be >= 0"
CHK_WORK = "work_limit must be > 0"
CHK_WORK_MAX = "work_limit must be <= 1e+15"  # modelsrc/methods.py WORK_LIMIT_MAX (issue 23.1)
CHK_SPLIT = "method splitting needs principal axes"
CHK_EXACT = "method exact_free needs principal axes"
CHK_QUAT = "quaternion q must have unit norm"
# the rotors, the orbit and the central field (modelsrc/model.py add_parameter_ranges,
# modelsrc/features/orbit.py, central_gravity.py; docs/robustness.md §2, ranges)
ROTOR_NAMES = ("wheel", "p1", "p2", "p3", "p4")  # the rotors of the fuzzed FMUs
CHK_J = {f"J_{r}": f"J_{r} must be in [1e-100, 1e+100]" for r in ROTOR_NAMES}
CHK_ORBIT_RATE = "n_orbit must be > 0"
CHK_ORBIT_ANGLE = "|orbit_angle| must be <= 1e+06 rad"
CHK_MU = "mu must be > 0"
CHK_CENTRAL = "|x_cm| must be > the body's size sqrt(tr I / m)"
CHK_ROTOR_PD = "I - sum J g g^T (the inertia without the rotors' axial parts) must be positive definite"
# The rotors' axes (body frame) of the fuzzed FMUs, by model identifier (the scenes:
# modelsrc/scenes/quadrotor.toml, tests/harness/fuzz_scenes.py)
ROTOR_AXES = {
    "quadrotor": {r: (0.0, 0.0, 1.0) for r in ("p1", "p2", "p3", "p4")},
    "offaxis_wheel": {"wheel": (0.6, 0.8, 0.0)},
    "central_wheel": {"wheel": (0.0, 0.0, 1.0)},
}
ALL_CHECKS = (
    CHK_PD, CHK_TRIANGLE, CHK_MASS, CHK_FRICTION, CHK_TOL, CHK_HMAX, CHK_WORK, CHK_WORK_MAX, CHK_SPLIT, CHK_EXACT,
    CHK_QUAT, *CHK_J.values(), CHK_ORBIT_RATE, CHK_ORBIT_ANGLE, CHK_MU, CHK_CENTRAL, CHK_ROTOR_PD,
)  # fmt: skip
PARAM_MAX, POSITIVE_MIN = 1e100, 1e-100  # modelsrc/scene_reader.py
ORBIT_ANGLE_MAX = 1e6  # rad, modelsrc/features/orbit.py
# A rotor's speed at which its energy J Omega^2 / 2 overflows (J >= 0.05 drawn): refused at
# exitInitializationMode because an output would be non-finite, not by a check.
OMEGA_OVERFLOW = 1e155
REL_TOL = 1e-12  # modelsrc/inertia.py REL_TOL (docs/theory.md §3.4)
QUAT_NORM_TOL = 1e-6  # modelsrc/scene.py QUAT_NORM_TOL
# Work of one internal step in right-hand-side evaluations, per method name: the table the
# work_limit counts with (docs/fmi_layer.md, Work limit; its one source, modelsrc/methods.py).
COST = {m.name: m.cost for m in METHODS.values()}

# Values the fuzzer draws: (valid, invalid) per variable. Valid values keep every doStep
# cheap and predictable (|w| <= 10 rad/s, torques <= 100 N m: stiffness rate <= ~1e3 1/s);
# invalid ones hit each check. All are exact binary fractions or far from a check's
# boundary, so the model's floating-point evaluation of the checks agrees with the C.
# h_max = 1e-12 passes the checks but makes every doStep exceed the work limit: at least
# 1e9 internal steps of >= 4 evaluations against work_limit <= 1e9. With the other values
# a doStep needs at most a few hundred internal steps (|w| grows to ~300 rad/s under the
# largest torque), < 1e6 evaluations even for gauss6: the h_max part alone decides.
VALUES = {
    "I_principal": ((1.5, 2.0, 2.5, 3.0, 1.0), (-1.0, 0.0, 10.0)),
    "c_friction": ((0.0, 0.1, 2.0), (-0.1,)),
    "h_max": ((1e-3, 1e-2, 2.5e-2, 0.0), (-1e-3, 1e-12)),
    # fixed steps only (0): the work of an error-controlled doStep is not predicted here
    "tolerance": ((0.0,), (-1e-6,)),
    # huge limits: 9e20 made a doStep loop forever (k - 1 == k beyond 2^53; issue 23.1), now
    # refused above WORK_LIMIT_MAX = 1e15 (not drawn as valid: with h_max = 1e-12 a limit of
    # 1e15 would admit a doStep of 1e10 internal steps)
    "work_limit": ((5e7, 1e6, 1e9), (0.0, -1.0, 9e20, 1.3e21, 2.0**53, 1e300)),
    "q": ((1.0, 0.0, 0.6, 0.8), (2.0, 1.000002, 0.5)),
    "w_body": ((0.0, 1.0, -2.0, 10.0, 0.3), ()),
    "tau_body": ((0.0, 1.0, -5.0, 100.0), ()),
    "mass": ((0.5, 2.0), (0.0, -0.5)),
    "r_cm": ((0.0, 0.04, -0.02), ()),
    "g": ((0.0, -9.81, 3.0), ()),
    # rotors: a rotor's axial inertia J_<name> (5e-324: issue 39.7), a wheel's speed
    # Omega_<name> (a state; 1e200 overflows E_kin) and motor torque u_<name>, a speed-mode
    # propeller's speed Omega_<name> and its rate Omega_dot_<name> (inputs)
    # (valid J < 1 <= the valid I: I - sum J g g^T stays positive definite with a margin far
    # above round-off, so that the model's minors agree with the C's in sign)
    "J": ((0.05, 0.2, 0.5), (0.0, -1.0, 5e-324)),
    "Omega": ((0.0, 10.0, -50.0, 442.9), (1e200,)),
    "Omega_dot": ((0.0, 80.0, -40.0), ()),
    "u": ((0.0, 0.1, -0.5), ()),
    # the orbit: rate and angle (1e17: issue 39.6)
    "n_orbit": ((1e-3, 2e-3), (0.0, -1e-3)),
    "orbit_angle": ((0.0, 1.0, -3.0, 1e5), (1e17, -2e6)),
    # the centre of mass (central field: |x_cm| = 25..64 m against a size <= ~8 m; 0 and
    # 0.1 put it at the central body, issue 39.2/39.8) and the central body's mu
    "x_cm": ((0.0, 40.0, -30.0, 25.0), (0.1,)),
    "v_cm": ((0.0, 1.0, -2.0), ()),
    "mu": ((40.0, 10.0), (0.0, -40.0)),
}


def values_of(
    name: str, kind: str | None = None, default: tuple[float, ...] = (0.0, 1.0, -3.0)
) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """(valid, invalid) values of a variable: VALUES by its base name, a rotor's by its
    prefix (J_, Omega_dot_, Omega_, u_; not Omega_abs_, an output); (default, ()) else. A
    speed-mode propeller's Omega_<name> (kind "input") takes only the valid speeds: an input
    is not checked before the doStep that would overflow with it."""
    base = name.split("[")[0]
    for prefix in ("J_", "Omega_dot_", "Omega_", "u_"):
        if base.startswith(prefix) and base[len(prefix) :] in ROTOR_NAMES:
            valid, invalid = VALUES[prefix[:-1]]
            return (valid, ()) if kind == "input" else (valid, invalid)
    return VALUES.get(base, (default, ()))


def _ratio(a: float, b: float) -> float:
    """a / b as the C computes it (IEEE: x/0 = ±inf, 0/0 = NaN)."""
    if b == 0:
        return math.nan if a == 0 or math.isnan(a) else math.copysign(math.inf, a) * math.copysign(1.0, b)
    return a / b


# Unit quaternions set as a whole (the last is within the 1e-6 tolerance: normalised).
UNIT_QUATERNIONS = (
    (1.0, 0.0, 0.0, 0.0),
    (0.6, 0.8, 0.0, 0.0),
    (0.5, 0.5, 0.5, -0.5),
    (0.0, 0.0, 0.6, 0.8),
    (1.0000005, 0.0, 0.0, 0.0),
)
P_NON_FINITE, P_INVALID = 0.04, 0.10
NON_FINITE = (math.nan, math.inf, -math.inf)
STEP_SIZES = (1e-3, 1e-2, 5e-2)
# 1e308: from t = 0 the work limit refuses it, from t = 1.5e308 the time would overflow
BAD_STEP_SIZES = (0.0, -1e-2, math.nan, math.inf, 1e308)
# 1.5e308: every doStep from there is below the resolution of the time (or overflows it)
START_TIMES = (0.0, 1.5, -2.0, 1e6, 1.5e308)
METHOD_VALUES_BAD = (0, 7, -1, 2**40)


def classify(info: ModelInfo) -> dict[str, str]:
    """Variable kind by name from modelDescription.xml: independent, state (output with
    a start value), output (calculated), derivative (local der(x)), input, fixed, tunable."""
    kinds = {}
    for name in info.vr:
        if name in info.int64_vrs:
            continue
        c = info.causality[name]
        if c == "independent":
            kinds[name] = "independent"
        elif c == "output":
            kinds[name] = "state" if name in info.start else "output"
        elif c == "local" and name.startswith("der("):
            kinds[name] = "derivative"
        elif c == "local":
            kinds[name] = "local"
        elif c == "input":
            kinds[name] = "input"
        elif c == "parameter":
            kinds[name] = "tunable" if info.variability[name] == "tunable" else "fixed"
        else:
            raise AssertionError(f"unexpected variable {name} (causality {c!r}): extend the fuzzer's model")
    return kinds


@dataclass
class ModelState:
    """The part of the model an FMU state snapshot saves and restores."""

    state: str = INST
    values: dict = field(default_factory=dict)
    method: int = 1
    states_known: bool = True  # states exactly predicted (false after a doStep)
    valid_run: bool = False  # passed exitInitializationMode since the last reset


class FmuModel:
    """Python model of one instance: its state, variable values and method."""

    def __init__(self, info: ModelInfo):
        self.info = info
        self.kinds = classify(info)
        self.name_of = {vr: n for n, vr in info.vr.items()}
        self.nv = 1 + max(vr for n, vr in info.vr.items() if n not in info.int64_vrs)
        self.method_vr = info.int64_vrs["method"]
        self.method_names = dict(info.enum_items)  # enumeration value -> method name
        self.nx = sum(1 for k in self.kinds.values() if k == "derivative")  # one der(x) per state
        self.me = False
        self.s = ModelState()
        self.reset()

    def reset(self) -> None:
        values = {
            n: self.info.start.get(n, 0.0) for n, k in self.kinds.items() if k not in ("output", "derivative", "local")
        }
        values["time"] = 0.0
        self.s = ModelState(INST, values, self.info.int64_start["method"], True, False)

    # ---- the generated checks, evaluated like the C (same formulas) ----
    def violated(self) -> set[str]:
        v, bad = self.s.values, set()
        I = [v["I_principal[1]"], v["I_principal[2]"], v["I_principal[3]"]]
        if not (I[0] > 0 and I[0] * I[1] > 0 and I[0] * (I[1] * I[2]) > 0):  # Sylvester
            bad.add(CHK_PD)
        tr = I[0] + I[1] + I[2]
        J = [0.5 * tr - x for x in I]  # tr(I)/2 - I >= 0 <=> triangle inequality (theory §3.4)
        tri = [J[k] + REL_TOL * tr >= 0 for k in range(3)]
        tri += [J[i] * J[j] + REL_TOL * tr**2 >= 0 for i, j in ((0, 1), (0, 2), (1, 2))]
        tri.append(J[0] * J[1] * J[2] + REL_TOL * tr**3 >= 0)
        if not all(tri):
            bad.add(CHK_TRIANGLE)
        if "mass" in v and not v["mass"] > 0:
            bad.add(CHK_MASS)
        if "c_friction" in v and not v["c_friction"] >= 0:
            bad.add(CHK_FRICTION)
        if not v["h_max"] >= 0:
            bad.add(CHK_HMAX)
        if not v["tolerance"] >= 0:
            bad.add(CHK_TOL)
        if not v["work_limit"] > 0:
            bad.add(CHK_WORK)
        if not v["work_limit"] <= WORK_LIMIT_MAX:
            bad.add(CHK_WORK_MAX)
        method_name = self.method_names.get(self.s.method)
        if method_name in ("splitting", "exact_free") and "mass" in v:  # both need a diagonal pivot inertia
            m, r = v["mass"], [v["r_cm[1]"], v["r_cm[2]"], v["r_cm[3]"]]
            trp = tr + 2.0 * m * (r[0] ** 2 + r[1] ** 2 + r[2] ** 2)  # trace about the pivot
            off = max(abs(m * r[0] * r[1]), abs(m * r[0] * r[2]), abs(m * r[1] * r[2]))
            if not 1e-12 * trp - off >= 0:
                bad.add(CHK_SPLIT if method_name == "splitting" else CHK_EXACT)
        qn = math.sqrt(sum(v[f"q[{k}]"] ** 2 for k in range(1, 5)))
        if not QUAT_NORM_TOL - abs(qn - 1) >= 0:
            bad.add(CHK_QUAT)
        axes = ROTOR_AXES.get(self.info.model_identifier, {})
        if axes:  # the leading minors of I - sum J g g^T, formed as modelsrc/features/rotors/feature.py does
            M = [[I[i] if i == j else 0.0 for j in range(3)] for i in range(3)]
            for r, g in axes.items():
                for i in range(3):
                    for j in range(3):
                        M[i][j] = M[i][j] - v[f"J_{r}"] * (g[i] * g[j])
            m2 = M[0][0] * M[1][1] - M[0][1] * M[1][0]
            m3 = (
                M[0][0] * (M[1][1] * M[2][2] - M[1][2] * M[2][1])
                - M[0][1] * (M[1][0] * M[2][2] - M[1][2] * M[2][0])
                + M[0][2] * (M[1][0] * M[2][1] - M[1][1] * M[2][0])
            )
            if not (M[0][0] > 0 and m2 > 0 and m3 > 0):
                bad.add(CHK_ROTOR_PD)
        for name, chk in CHK_J.items():
            if name in v and not min(v[name] - POSITIVE_MIN, PARAM_MAX - v[name]) >= 0:
                bad.add(chk)
        if "n_orbit" in v and not v["n_orbit"] > 0:
            bad.add(CHK_ORBIT_RATE)
        if "orbit_angle" in v and not ORBIT_ANGLE_MAX - abs(v["orbit_angle"]) >= 0:
            bad.add(CHK_ORBIT_ANGLE)
        if "mu" in v:
            if not v["mu"] > 0:
                bad.add(CHK_MU)
            x2 = sum(v[f"x_cm[{k}]"] ** 2 for k in range(1, 4))
            if not x2 - _ratio(tr, v["mass"]) > 0:
                bad.add(CHK_CENTRAL)
        return bad

    def overflows(self) -> str | None:
        """The name of a rotor speed at which the outputs overflow (refused at
        exitInitializationMode after the checks pass: 'would be'), else None."""
        v = self.s.values
        for name, kind in self.kinds.items():
            if kind == "state" and name.startswith("Omega_") and abs(v[name]) >= OMEGA_OVERFLOW:
                return name
        return None


@dataclass
class Expect:
    """The predicted outcome of one call: ok, and for a refusal the fragments the logged
    messages must contain; for failed validity checks, exactly these check categories."""

    ok: bool
    fragments: tuple[str, ...] = ()
    checks: frozenset[str] | None = None
    status: int = 3  # of a refusal: fmi3Error, or fmi3Discard (2) for SetContinuousStates out of the domain


@dataclass
class Stats:
    """What the fuzzer exercised: sequences, calls, (function, state, outcome) counts."""

    sequences: int = 0
    calls: int = 0
    refused: int = 0
    transitions: Counter = field(default_factory=Counter)
    max_sequence_time: float = 0.0
    attacks: Counter = field(default_factory=Counter)  # tests/harness/fuzz_fmi_attacks.py: kind -> calls

    def as_dict(self) -> dict:
        return {
            "sequences": self.sequences,
            "calls": self.calls,
            "refused": self.refused,
            "max_sequence_time": self.max_sequence_time,
            "transitions": {"|".join(k): n for k, n in sorted(self.transitions.items())},
            "attacks": dict(self.attacks),
        }
