"""Explicit steps too large for the instruction cache call their right-hand side instead of inlining it.

modelsrc/integrators.py, `compact`; docs/fmi_layer.md, Step cost.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from fmu.build.codegen import generate_c
from modelsrc.integrators import INLINE_LIMIT, _rk4, _rk8, called
from modelsrc.model import build_model
from modelsrc.model_functions import step_name
from modelsrc.scene import list_scenes, load_scene

SCENES = list_scenes()


@pytest.mark.parametrize("scene", SCENES)
def test_every_explicit_step_stays_within_the_inline_limit(scene):
    fs = build_model(load_scene(scene)).functions
    names = [step_name(m, fixed) for m in ("rk4", "rk8") for fixed in (False, True)]
    sizes = {n: fs[n].n_instructions() for n in names if n in fs}
    assert sizes and all(s <= INLINE_LIMIT for s in sizes.values()), sizes


def _one_norm(x0, *errors) -> list:
    # one block with scale 1: enough to compare two graphs of the same estimate
    return [(*(ca.sumsqr(e) for e in errors), 1.0)]


@pytest.mark.parametrize("build", [_rk4, _rk8])
def test_calling_the_right_hand_side_gives_the_inlined_step_to_the_bit(build):
    fs = build_model(load_scene("sleeping_top")).functions
    rhs, project, nd = fs["model_rhs"], fs["model_project"], fs["model_derived"].size1_out(0)
    inlined = build(rhs, project, _one_norm, nd, "inlined", True)
    calling = build(called(rhs), project, _one_norm, nd, "calling", True)
    if build is _rk8:  # the step that outgrows the limit inlined (3,100 instructions)
        assert inlined.n_instructions() > INLINE_LIMIT >= calling.n_instructions()
    rng = np.random.default_rng(5)
    for _ in range(5):
        args = {name: rng.uniform(-1, 1, inlined.size1_in(name)) for name in inlined.name_in()}
        args["x"][:4] /= np.linalg.norm(args["x"][:4])  # a unit quaternion
        args["h"] = np.array([rng.uniform(1e-4, 1e-2)])
        args["d"] = np.asarray(fs["model_derived"](p=args["p"])["d"]).ravel()  # d of these parameters
        a, b = inlined(**args), calling(**args)
        for k in inlined.name_out():  # x_next, err, est, k_next, dx
            assert np.array_equal(np.asarray(a[k]), np.asarray(b[k])), k


def test_the_called_right_hand_side_is_generated_once(tmp_path):
    # top_on_shaker's rk8 steps with and without estimate (3,553 and 3,075 instructions inlined)
    # call the same right-hand side, and the controlled one for a diagonal inertia (3,181) its
    # own: one copy each in the C, not one per step
    model = build_model(load_scene("top_on_shaker"))
    assert sum(n.startswith("model_step_rk8") and not n.endswith("_principal") for n in model.functions) == 2
    generate_c(model, tmp_path)
    text = (tmp_path / "model_funcs.c").read_text()
    assert text.count("/* model_rhs_called:") == 1
    assert text.count("/* model_rhs_principal_called:") == 1
