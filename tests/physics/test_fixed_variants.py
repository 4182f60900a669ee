"""The step functions of fixed stepping (no error estimate) give the same next state as the error-controlled ones."""

from __future__ import annotations

import numpy as np
import pytest

from modelsrc.integrators import FIXED_VARIANTS
from modelsrc.model import build_model
from modelsrc.scene import load_scene


@pytest.mark.parametrize("scene", ["heavy_top", "thrown_racket", "torque_driven"])
def test_fixed_variant_has_the_same_next_state_and_no_estimate(scene):
    model = build_model(load_scene(scene))
    fs = model.functions
    rng = np.random.default_rng(3)
    for m in FIXED_VARIANTS:
        full, fixed = fs[f"model_step_{m}"], fs[f"model_step_{m}_fixed"]
        # x, U, p, h, d, k1 by name: any numbers; the comparison is of two graphs, not of physics
        args = {name: rng.uniform(-1, 1, full.size1_in(name)) for name in full.name_in()}
        args["x"][:4] /= np.linalg.norm(args["x"][:4])  # a unit quaternion
        args["h"] = np.array([1e-3])
        args["d"] = np.asarray(fs["model_derived"](p=args["p"])["d"]).ravel()  # d of these parameters
        a, b = full(**args), fixed(**args)
        # the same expression graph for x_next, k_next, dx: equal to the bit
        for k in ("x_next", "k_next", "dx"):
            assert np.array_equal(np.asarray(a[k]), np.asarray(b[k])), (m, k)
        assert float(b["est"]) == 0.0 and float(a["est"]) > 0.0  # only the full step estimates its error
