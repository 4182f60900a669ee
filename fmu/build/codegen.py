"""CasADi code generation of a model's functions (the physics of the FMU is only this C)."""

from __future__ import annotations

from pathlib import Path

import casadi as ca

from modelsrc.model import RigidBodyModel
from modelsrc.integrators import constants_name
from modelsrc.model_functions import step_name

# Functions the C core calls (plus model_step_<method> for each method).
CS_FUNCTIONS = (
    "model_outputs",
    "model_checks",
    "model_project",
    "model_rate",
    "model_rate_rhs",
    "model_rhs",
    "model_jac",
    "model_derived",
    "model_output_rates",
)


def generate_c(model: RigidBodyModel, out_dir: Path, basename: str = "model_funcs") -> dict[str, int]:
    """Write out_dir/model_funcs.c and .h; return the work-array sizes the C layer needs.

    Returns {"sz_arg", "sz_res", "sz_iw", "sz_w"}: the maxima over the generated
    functions, so the instance can hold the work arrays statically.
    """
    names = list(CS_FUNCTIONS) + step_function_names(model) + step_constant_names(model)
    return generate_functions([model.functions[n] for n in names], out_dir, basename)


def generate_functions(functions: list[ca.Function], out_dir: Path, basename: str) -> dict[str, int]:
    """Write out_dir/BASENAME.c and .h with these CasADi functions (a scene's model or a
    controller's law) and the build header; return the work-array sizes {"sz_arg", "sz_res",
    "sz_iw", "sz_w"}, the maxima over the functions, so the instance holds them statically."""
    # with_export False: no export attribute on the generated functions, so that a DLL
    # (where CasADi would mark them __declspec(dllexport)) exports only the FMI API
    gen = ca.CodeGenerator(f"{basename}.c", {"with_header": True, "casadi_int": "long long int", "with_export": False})
    sizes = {"sz_arg": 1, "sz_res": 1, "sz_iw": 0, "sz_w": 0}
    for f in functions:
        gen.add(f)
        sizes["sz_arg"] = max(sizes["sz_arg"], f.sz_arg())
        sizes["sz_res"] = max(sizes["sz_res"], f.sz_res())
        sizes["sz_iw"] = max(sizes["sz_iw"], f.sz_iw())
        sizes["sz_w"] = max(sizes["sz_w"], f.sz_w())
    out_dir.mkdir(parents=True, exist_ok=True)
    gen.generate(str(out_dir) + "/")
    prepend_build_header(out_dir / f"{basename}.c")
    return sizes


# The generated C is not edited, only preceded by this line: rbfmu_build.h (fmu/c/) makes any
# compiler with any flags hide its symbols and keep FP contraction off (docs/importing.md).
BUILD_HEADER_LINE = '#include "rbfmu_build.h" /* prepended by rbfmu (fmu/codegen.py): hidden symbols, no FMA */\n'


def prepend_build_header(c_file: Path) -> None:
    """Put BUILD_HEADER_LINE before CasADi's output in c_file (its text otherwise unchanged)."""
    c_file.write_text(BUILD_HEADER_LINE + c_file.read_text())


def step_function_names(model: RigidBodyModel) -> list[str]:
    """The generated step functions of the model's methods: model_step_<m>, the variant
    without error estimate model_step_<m>_fixed that fixed stepping calls where there is one
    (modelsrc.integrators.FIXED_VARIANTS), and both again as <...>_principal where the model
    has steps for a diagonal inertia (modelsrc.model_functions.principal_steps)."""
    names = [
        step_name(m, fixed, principal) for principal in (False, True) for fixed in (False, True) for m in model.methods
    ]
    return [n for n in dict.fromkeys(names) if n in model.functions]


def step_constant_names(model: RigidBodyModel) -> list[str]:
    """The generated functions of the fixed steps' constants (modelsrc.integrators.step_constants,
    constants_name) of the methods that have them (a model with a clock), in the order of the
    methods."""
    return [constants_name(m) for m in model.methods if constants_name(m) in model.functions]
