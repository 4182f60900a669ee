"""The generated header model_data.h: everything model-specific the C layer reads.

Sizes, buffer offsets, the variable table (names, kinds, start values), the texts of
the validity checks and the instantiation token. Data only, no equations.
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import casadi as ca

from modelsrc.integrators import INCREMENT_METHODS, constants_name, stage_nodes
from modelsrc.methods import ESTIMATE_FLOOR, METHODS, NEWTON_ACCEPT, rotation_limit
from modelsrc.model import RigidBodyModel
from modelsrc.model_functions import step_name
from modelsrc.variables import Kind

from .codegen import CS_FUNCTIONS, step_constant_names, step_function_names

# FMI 2.0 input derivatives the FMU takes (fmi2SetRealInputDerivatives: orders 1..3, a cubic
# over the communication step) and output derivatives it gives (orders 1 and 2: the
# modelDescription's maxOutputDerivativeOrder), docs/fmi_layer.md.
MAX_INPUT_ORDER = 3
MAX_OUTPUT_ORDER = 2


def _c_str(s: str) -> str:
    return json.dumps(s, ensure_ascii=True)  # a valid C string literal for ASCII text


def _c_double(v: float) -> str:
    if math.isnan(v):
        return "NAN"
    return repr(float(v)) if math.isfinite(v) else ("INFINITY" if v > 0 else "-INFINITY")


# The step functions are called through one table (rb_step_fns ...): their arguments are
# named once, as this family (RB_ARG_model_step_x ...), and must agree across the methods.
STEP_FAMILY = "model_step"
# The fixed steps' constants (modelsrc.integrators.step_constants), called through their own table;
# the positions of a model without any are this signature's (the C layer then never calls one).
CONSTANTS_FAMILY = "model_step_constants"
CONSTANTS_SIGNATURE = (("p", "h", "d"), ("e",))


def argument_names(f: ca.Function) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """(input names, output names) of a CasADi Function whose arguments the C binds by name
    (RB_ARG_<function>_<name>, RB_RES_<function>_<name> in model_data.h and controller_data.h),
    checked to be distinct C identifiers (ValueError naming the function and the name)."""
    names_in, names_out = tuple(f.name_in()), tuple(f.name_out())
    for kind, names in (("input", names_in), ("output", names_out)):
        for name in names:
            if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", name):
                raise ValueError(
                    f"{f.name()}: {kind} name {name!r} is not a C identifier; the C names every argument "
                    "(RB_ARG_<function>_<name>), so give the CasADi Function names of letters, digits and _"
                )
        if len(set(names)) != len(names):
            raise ValueError(f"{f.name()}: {kind} names {names} repeat a name; each must be unique")
    return names_in, names_out


def argument_indices(model: RigidBodyModel) -> list[str]:
    """The #defines of where every generated function the C layer calls takes each argument:
    RB_ARG_<function>_<input> and RB_RES_<function>_<output> (positions in its arg[] and res[]),
    RB_N_ARG_<function> and RB_N_RES_<function> (how many), from the CasADi Functions' own
    names (Function.name_in/name_out), so that the C binds by name (rbfmu_core.h). The step
    functions of every method form one family, STEP_FAMILY: ValueError if two differ in their
    arguments, since the C calls them all through one table."""
    signatures = {name: argument_names(model.functions[name]) for name in CS_FUNCTIONS}
    steps = step_function_names(model)
    first = argument_names(model.functions[steps[0]])
    for name in steps[1:]:
        sig = argument_names(model.functions[name])
        if sig != first:
            raise ValueError(
                f"{name} takes {sig[0]} and returns {sig[1]}, but {steps[0]} takes {first[0]} and returns "
                f"{first[1]}: the C layer calls every step through one table (rb_step_fns), so all steps need "
                "the same argument names in the same order"
            )
    signatures[STEP_FAMILY] = first
    # the fixed steps' constants (p, h, d) -> e, one family too (rb_step_constants_fns); its
    # positions are written also for a model without any, where the C layer never calls one
    constants = step_constant_names(model)
    own = [argument_names(model.functions[name]) for name in constants]
    signatures[CONSTANTS_FAMILY] = own[0] if own else CONSTANTS_SIGNATURE
    for name, sig in zip(constants, own):
        if sig != signatures[CONSTANTS_FAMILY] or sorted(sig[0]) != sorted(CONSTANTS_SIGNATURE[0]) or sig[1] != ("e",):
            raise ValueError(
                f"{name} takes {sig[0]} and returns {sig[1]}: the C layer calls every step's constants through one "
                f"table (rb_step_constants_fns) with the arguments {CONSTANTS_SIGNATURE[0]} (in one order) and e"
            )
    lines = [
        "/* where each generated function the C layer calls takes its arguments, by name (fmu/build/model_data.py) */"
    ]
    for name, (names_in, names_out) in signatures.items():
        lines.append(f"#define RB_N_ARG_{name} {len(names_in)}")
        lines.append(f"#define RB_N_RES_{name} {len(names_out)}")
        lines += [f"#define RB_ARG_{name}_{arg} {i}" for i, arg in enumerate(names_in)]
        lines += [f"#define RB_RES_{name}_{res} {i}" for i, res in enumerate(names_out)]
    return lines


def write_model_data(model: RigidBodyModel, token: str, sizes: dict[str, int], path: Path) -> None:
    """Write model_data.h for `model`."""
    off = model.offsets
    nv = len(model.variables)
    exact_flow = model.scene.exact_flow
    nodes = {m: stage_nodes(m) for m in model.methods}
    max_nodes = max(len(n) for n in nodes.values())

    def steps(fixed: bool, principal: bool) -> str:  # the step functions of the methods, in order
        names = [step_name(m, fixed, principal) for m in model.methods]
        # a method without a variant for a diagonal inertia (principal_steps) keeps its step
        return ", ".join(n if n in model.functions else step_name(m, fixed) for m, n in zip(model.methods, names))

    lines = [
        "/* Generated by fmu/model_data.py: do not edit. */",
        "#ifndef RB_MODEL_DATA_H",
        "#define RB_MODEL_DATA_H",
        "#include <math.h>",
        f"#define RB_INSTANTIATION_TOKEN {_c_str(token)}",
        f"#define RB_NX {model.nx}",
        f"#define RB_NU {model.nu}",
        f"#define RB_NP {model.np_}",
        f"#define RB_NY {model.ny}",
        f"#define RB_NL {model.nl}",
        f"#define RB_ND {model.nd}",
        f"#define RB_NV {nv}",
        f"#define RB_NC {len(model.checks)}",
        f"#define RB_OFF_X {off['x']}",
        f"#define RB_OFF_U {off['u']}",
        f"#define RB_OFF_P {off['p']}",
        f"#define RB_OFF_L {off['l']}",
        f"#define RB_OFF_Y {off['y']}",
        f"#define RB_OFF_DX {off['dx']}",
        f"#define RB_VR_HMAX {model.h_max_index}",
        f"#define RB_VR_WORK_LIMIT {model.vr('work_limit')}",
        f"#define RB_VR_TOLERANCE {model.vr('tolerance')}",
        f"#define RB_MAX_INPUT_ORDER {MAX_INPUT_ORDER}",
        f"#define RB_MAX_OUTPUT_ORDER {MAX_OUTPUT_ORDER}",
        f"#define RB_ESTIMATE_FLOOR {ESTIMATE_FLOOR!r}",
        f"#define RB_SZ_ARG {sizes['sz_arg']}",
        f"#define RB_SZ_RES {sizes['sz_res']}",
        f"#define RB_SZ_IW {sizes['sz_iw']}",
        f"#define RB_SZ_W {sizes['sz_w']}",
        *argument_indices(model),
        f"#define RB_KIND_INDEPENDENT {int(Kind.INDEPENDENT)}",
        f"#define RB_KIND_STATE {int(Kind.STATE)}",
        f"#define RB_KIND_INPUT {int(Kind.INPUT)}",
        f"#define RB_KIND_PARAM_FIXED {int(Kind.PARAM_FIXED)}",
        f"#define RB_KIND_PARAM_TUNABLE {int(Kind.PARAM_TUNABLE)}",
        f"#define RB_KIND_OUTPUT {int(Kind.OUTPUT)}",
        f"#define RB_KIND_DERIVATIVE {int(Kind.DERIVATIVE)}",
        f"#define RB_KIND_LOCAL {int(Kind.LOCAL)}",
        "static const double rb_start[RB_NV] = {"
        + ", ".join(_c_double(v.start if v.start is not None else 0.0) for v in model.variables)
        + "};",
        "static const unsigned char rb_kind[RB_NV] = {" + ", ".join(str(int(v.kind)) for v in model.variables) + "};",
        "static const double rb_nominal[RB_NX] = {"
        + ", ".join(_c_double(v.nominal or 1.0) for v in model.variables[off["x"] : off["x"] + model.nx])
        + "};",
        "static const char *const rb_names[RB_NV] = {" + ", ".join(_c_str(v.name) for v in model.variables) + "};",
        "static const char *const rb_check_text[RB_NC] = {" + ", ".join(_c_str(t) for t, _ in model.checks) + "};",
        "static const unsigned char rb_check_strict[RB_NC] = {"
        + ", ".join("1" if s else "0" for _, s in model.checks)
        + "};",
        f"#define RB_NMETHODS {len(model.methods)}",
        f"#define RB_NEWTON_ACCEPT {NEWTON_ACCEPT!r}",
        "static const double rb_method_rate_limit[RB_NMETHODS] = {"
        + ", ".join(_c_double(METHODS[m].rate_limit) for m in model.methods)
        + "};",
        "static const double rb_method_cost[RB_NMETHODS] = {"
        + ", ".join(_c_double(METHODS[m].cost) for m in model.methods)
        + "};",
        "static const double rb_method_rotation_limit[RB_NMETHODS] = {"
        + ", ".join(_c_double(rotation_limit(m, exact_flow)) for m in model.methods)
        + "};",
        f"#define RB_MAX_NODES {max_nodes}",
        "static const int rb_method_nnodes[RB_NMETHODS] = {"
        + ", ".join(str(len(nodes[m])) for m in model.methods)
        + "};",
        "static const double rb_method_nodes[RB_NMETHODS][RB_MAX_NODES] = {"
        + ", ".join("{" + ", ".join(_c_double(c) for c in nodes[m]) + "}" for m in model.methods)
        + "};",
        "/* which of them the step of fixed stepping reads (the Gauss steps' companion is not run) */",
        "static const unsigned char rb_fixed_node_read[RB_NMETHODS][RB_MAX_NODES] = {"
        + ", ".join(
            "{" + ", ".join("1" if c in stage_nodes(m, estimate=False) else "0" for c in nodes[m]) + "}"
            for m in model.methods
        )
        + "};",
        # the Runge-Kutta and Gauss steps return their increment dx (compensated summation in C)
        "static const int rb_method_increment[RB_NMETHODS] = {"
        + ", ".join("1" if m in INCREMENT_METHODS else "0" for m in model.methods)
        + "};",
        "#define RB_NQ 4 /* the first four states are the quaternion, projected after every step */",
        "static const int rb_method_estimate_order[RB_NMETHODS] = {"
        + ", ".join(str(METHODS[m].estimate_order or 0) for m in model.methods)
        + "};",
        f"#define RB_VR_METHOD {nv}",
        f"#define RB_DEFAULT_METHOD {METHODS[model.default_method].value}",
        "static const long long rb_method_values[RB_NMETHODS] = {"
        + ", ".join(str(METHODS[m].value) for m in model.methods)
        + "};",
        "static const char *const rb_method_names[RB_NMETHODS] = {"
        + ", ".join(_c_str(m) for m in model.methods)
        + "};",
        "typedef int (*rb_step_fn)(const casadi_real **, casadi_real **, casadi_int *, casadi_real *, int);",
        "static const rb_step_fn rb_step_fns[RB_NMETHODS] = {" + steps(False, False) + "};",
        "/* fixed stepping: the same step without its error estimate where generated */",
        "static const rb_step_fn rb_fixed_step_fns[RB_NMETHODS] = {" + steps(True, False) + "};",
        "/* the steps for an inertia about the rotation point that is diagonal as set, used when",
        " * the entries rb_off_diagonal of d are all 0 (modelsrc/model_functions.py, principal_steps) */",
        f"#define RB_NOFFDIAG {len(model.principal_test)}",
        "static const int rb_off_diagonal[RB_NOFFDIAG > 0 ? RB_NOFFDIAG : 1] = {"
        + (", ".join(str(k) for k in model.principal_test) or "0")
        + "};",
        "static const rb_step_fn rb_principal_step_fns[RB_NMETHODS] = {" + steps(False, True) + "};",
        "static const rb_step_fn rb_principal_fixed_step_fns[RB_NMETHODS] = {" + steps(True, True) + "};",
        "/* the constants of the fixed steps with a clock, (p, h, d) -> e, once per step size (0: none;",
        " * modelsrc/integrators.py, step_constants): both the steps above and the principal ones take them */",
        f"#define RB_NE {max([model.functions[n].size1_out(0) for n in step_constant_names(model)], default=0)}",
        "static const rb_step_fn rb_step_constants_fns[RB_NMETHODS] = {"
        + ", ".join(
            constants_name(m) if constants_name(m) in model.functions else "0"
            for m in model.methods
        )
        + "};",
        "#endif",
        "",
    ]
    path.write_text("\n".join(lines))
