"""The C layer binds the generated functions' arguments by name: reordered, they give the same results to the bit.

fmu/build/model_data.py writes where each generated function the C layer calls takes each input
and output (RB_ARG_<function>_<input>, RB_RES_<function>_<output>, from the CasADi
Functions' own names) and the layer binds by those names (fmu/c/rbfmu_core.h). Here every
such function of a model is rebuilt with its inputs and its outputs in reverse order (the
same expressions, the same names) and the FMU built from it must run exactly as the one
built from the model as it is; a function that takes other arguments than the layer binds
must fail to compile, with a message that says so.
"""

from __future__ import annotations

import ctypes
import re
import shutil
import subprocess
from pathlib import Path

import casadi as ca
import fmpy
import numpy as np
import pytest

import fmu.build.build_fmu
from fmu.build.build_fmu import build_fmu
from fmu.build.codegen import CS_FUNCTIONS, generate_c, step_function_names
from fmu.build.compile import C_DIR, CFLAGS, CORE
from fmu.build.model_data import write_model_data
from modelsrc.model import build_model
from modelsrc.scene import load_scene
from tests.harness.fmi3_ctypes import Fmi3Library, extract_fmu

# torque inputs (so that u and U are read), explicit (SX) and implicit (MX, a Newton solve)
# steps, fixed and error-controlled
SCENE = """
name = "reordered"
description = "Free body I = diag(1, 2, 3) driven by body and world torque inputs."
outputs = ["q", "w_body", "w_world", "euler_zxz", "E_kin", "L_world", "L_body"]
[features]
torque_body = true
torque_world = true
[body]
principal_moments = [1.0, 2.0, 3.0]
[initial]
w_body = [0.1, 0.2, 1.0]
[experiment]
stop_time = 1.0
step = 0.01
methods = ["rk4", "rk8", "gauss4", "splitting"]
"""


def reversed_arguments(f: ca.Function) -> ca.Function:
    """f with its inputs and its outputs in reverse order: the same expressions (f's own graph,
    inlined) under the same names and the same function name."""
    sym = f.sx_in() if f.is_a("SXFunction") else f.mx_in()
    out = f.call(sym, True, False)  # always_inline: no call of a function of the same name
    return ca.Function(f.name(), sym[::-1], out[::-1], f.name_in()[::-1], f.name_out()[::-1])


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    path = tmp_path_factory.mktemp("scene") / "reordered.toml"
    path.write_text(SCENE)
    return load_scene(path)


def reordered_model(scene):
    model = build_model(scene)
    for name in [*CS_FUNCTIONS, *step_function_names(model)]:
        model.functions[name] = reversed_arguments(model.functions[name])
    return model


@pytest.fixture(scope="module")
def builds(scene, tmp_path_factory):
    """{"as is": extracted FMU, "reordered": extracted FMU of the reordered model}."""
    root = tmp_path_factory.mktemp("builds")
    as_is = build_fmu(scene, root / "as_is")
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(fmu.build.build_fmu, "build_model", lambda sc: reordered_model(sc))
        reordered = build_fmu(scene, root / "reordered")
    return {"as is": extract_fmu(as_is, root / "x_as_is"), "reordered": extract_fmu(reordered, root / "x_reordered")}


def indices(unzipdir: Path) -> dict[str, int]:
    text = (unzipdir / "sources" / "model_data.h").read_text()
    return {m[0]: int(m[1]) for m in re.findall(r"#define (RB_(?:ARG|RES)_model_\w+) (\d+)", text)}


def test_the_reordered_build_names_other_positions(builds):
    a, b = indices(builds["as is"]), indices(builds["reordered"])
    # the scene has no clock: the steps' constants family (model_step_constants) has no function
    # to reorder, its positions are model_data.CONSTANTS_SIGNATURE's in both builds
    a, b = ({k: v for k, v in i.items() if "model_step_constants" not in k} for i in (a, b))
    assert a.keys() == b.keys() and len(a) > 40
    assert (a["RB_ARG_model_rhs_x"], b["RB_ARG_model_rhs_x"]) == (0, 3)
    assert (a["RB_ARG_model_step_k1"], b["RB_ARG_model_step_k1"]) == (5, 1)  # of x, U, p, h, d, k1, e
    assert (a["RB_RES_model_step_x_next"], b["RB_RES_model_step_x_next"]) == (0, 4)
    assert (a["RB_ARG_model_output_rates_u1"], b["RB_ARG_model_output_rates_u1"]) == (4, 1)
    moved = [k for k in a if a[k] != b[k]]  # all but the middle of an odd count and the one-in-one-out
    assert len(moved) > 0.75 * len(a), sorted(set(a) - set(moved))


def run(unzipdir: Path, method: str, tolerance: float, h_max: float) -> dict[str, np.ndarray]:
    """50 doSteps of 0.01 s with torque inputs varying inside the steps (intermediate update,
    at every node of every internal step), then everything the generated functions give:
    all variables, the output derivatives (model_output_rates) and, in Model Exchange at the
    end state, the derivatives (model_rhs) and a directional derivative (model_jac)."""
    lib = Fmi3Library(unzipdir)
    info = lib.info
    taus = [n for n in info.vr if n.startswith("tau_")]
    inputs = [info.vr[n] for n in taus]
    inst = None

    def torque(t: float) -> None:
        inst.set_float64(inputs, [0.3 * np.sin(3 * t + k) for k in range(len(inputs))])

    inst = lib.instantiate(intermediate_update=torque, required=inputs)
    assert inst.enter_initialization_mode() == 0
    names = ["tolerance", "h_max"]
    assert inst.set_float64([info.vr[n] for n in names], [tolerance, h_max]) == 0
    assert inst.set_int64([info.int64_vrs["method"]], [next(v for v, n in info.enum_items.items() if n == method)]) == 0
    assert inst.exit_initialization_mode() == 0, inst.log
    t = 0.0
    for _ in range(50):
        status, t = inst.do_step(t, 0.01)
        assert status == 0, inst.log
    every = sorted(v for n, v in info.vr.items() if n not in info.int64_vrs)  # the Float64 ones: 0, 1, ...
    status, values = inst.get_float64(every)
    assert status == 0 and every == list(range(len(every)))
    out = {"values": np.array(values)}
    rates = [info.vr[n] for n in info.causality if info.causality[n] == "output"]
    out["rates"] = np.array([inst.get_output_derivatives(rates, [k] * len(rates))[1] for k in (1, 2)])
    x = out["values"][[info.vr[f"q[{k}]"] for k in range(1, 5)] + [info.vr[f"w_body[{k}]"] for k in range(1, 4)]]
    inst.free()
    me = lib.instantiate(model_exchange=True)
    assert me.enter_initialization_mode() == 0 and me.exit_initialization_mode() == 0
    assert me.enter_continuous_time_mode() == 0 and me.set_continuous_states(list(x)) == 0
    out["derivatives"] = np.array(me.get_derivatives(len(x))[1])
    unknowns, knowns = [info.vr["w_world[1]"], info.vr["E_kin"]], [info.vr["w_body[2]"], inputs[0]]
    seed, sens, vrs = (ctypes.c_double * 2)(1.0, -0.5), (ctypes.c_double * 2)(), ctypes.c_uint32 * 2
    status = lib.dll.fmi3GetDirectionalDerivative(me.handle, vrs(*unknowns), 2, vrs(*knowns), 2, seed, 2, sens, 2)
    assert status == 0
    out["directional"] = np.array(list(sens))
    me.free()
    return out


@pytest.mark.parametrize(
    "method, tolerance, h_max",
    [("rk4", 0.0, 1e-3), ("rk8", 1e-10, 0.0), ("gauss4", 1e-9, 0.0), ("splitting", 0.0, 1e-3)],
)
def test_the_reordered_model_runs_to_the_bit(builds, method, tolerance, h_max):
    a = run(builds["as is"], method, tolerance, h_max)
    b = run(builds["reordered"], method, tolerance, h_max)
    assert np.abs(a["values"]).max() > 0.1 and np.abs(a["rates"]).max() > 0  # the body moved, the rates are read
    for key in a:
        assert np.array_equal(a[key], b[key]), (key, a[key] - b[key])


def compile_core(model, tmp: Path) -> subprocess.CompletedProcess:
    """Generate model_funcs and model_data.h of `model` into tmp and compile rbfmu_core.c there."""
    sizes = generate_c(model, tmp)
    write_model_data(model, "{token}", sizes, tmp / "model_data.h")
    for f in CORE:
        shutil.copy(C_DIR / f, tmp / f)
    for h in (Path(fmpy.__file__).parent / "c-code").glob("fmi3*.h"):
        shutil.copy(h, tmp / h.name)
    cmd = ["gcc", *CFLAGS, "-Werror", "-I", str(tmp), "-c", str(tmp / "rbfmu_core.c"), "-o", str(tmp / "core.o")]
    return subprocess.run(cmd, capture_output=True, text=True)


def test_a_function_with_an_argument_the_layer_does_not_bind_fails_to_compile(scene, tmp_path):
    model = build_model(scene)
    assert compile_core(model, tmp_path / "as_is").returncode == 0
    rhs = model.functions["model_rhs"]
    x, u, p, d = rhs.sx_in()
    t = ca.SX.sym("t")
    model.functions["model_rhs"] = ca.Function("model_rhs", [x, u, p, d, t], [rhs(x=x, u=u, p=p, d=d)["xdot"] * t],
                                               ["x", "u", "p", "d", "t"], ["xdot"])  # fmt: skip
    proc = compile_core(model, tmp_path / "extra")
    assert proc.returncode != 0
    assert "model_rhs, model_rate, model_outputs and model_jac must take exactly x, u, p, d" in proc.stderr


def test_a_renamed_argument_fails_to_compile_naming_it(scene, tmp_path):
    model = build_model(scene)
    rhs = model.functions["model_rhs"]
    model.functions["model_rhs"] = ca.Function(
        "model_rhs", rhs.sx_in(), rhs.call(rhs.sx_in()), ["state", "u", "p", "d"], ["xdot"]
    )
    proc = compile_core(model, tmp_path / "renamed")
    assert proc.returncode != 0 and "RB_ARG_model_rhs_x" in proc.stderr


def test_steps_that_differ_in_their_arguments_are_refused_by_name(scene, tmp_path):
    model = build_model(scene)
    step = model.functions["model_step_rk8"]
    model.functions["model_step_rk8"] = reversed_arguments(step)
    with pytest.raises(ValueError, match=r"model_step_rk8 takes .* but model_step_rk4 takes .* one table"):
        write_model_data(model, "{token}", {"sz_arg": 6, "sz_res": 5, "sz_iw": 0, "sz_w": 0}, tmp_path / "h")
