"""The cosim_slew system (the report's co-simulation loop) in ECOS and libcosim against the delayed scipy loop.

The reference (rbcheck.baselines.rigid_body.closed_loop_scipy) integrates the body's equations
(numpy, written again) between samples with DOP853 at rtol 1e-13, atol 1e-15, and evaluates
rbcheck's AttitudePD (the report's Python controller, cosim_controller) at each sample with the
one sample of delay the Jacobi masters impose (OneSampleDelay: the plant holds law(x_{k−1}) over
[t_k, t_{k+1}], law(x_0) at k = 0), the disturbance 0.02 N·m about world y throughout.
Tolerance 1e-9 (rad in attitude, rad/s in rate) at every communication point: the plant's rk8
keeps a relative error of 1e-10 per second of simulated time (its default tolerance, nominal
values 1 rad, 1 rad/s: ≲ 4e-10 over T = 4 s), DOP853's ≲ 1e-13 per sample; measured 1.6e-15
rad and 4.2e-16 rad/s (ECOS; libcosim 1.5e-15, 3.1e-16). The loop without the delay is up to
3.2e-4 rad away: asserted > 1e-5, four decades above the tolerance, so the test tells the two
loops apart.
"""

from __future__ import annotations

import numpy as np
import pytest

from modelsrc.scene import load_scene
from rbcheck.baselines.rigid_body import OneSampleDelay, closed_loop_scipy
from rbcheck.workprecision.cosim import cosim_controller

TOL = 1e-9


@pytest.fixture(scope="module")
def runs(system_build_dir, tmp_path_factory) -> dict:
    from fmu.system.archive import open_archive
    from fmu.system.build import build_system
    from fmu.system.masters import run_system

    archive = open_archive(build_system("cosim_slew", tmp_path_factory.mktemp("cosim_slew"), system_build_dir))
    return {m: run_system(archive, m) for m in ("ecos", "libcosim")}


def _angles(q: np.ndarray, qr: np.ndarray) -> np.ndarray:
    """The rotation angle of qr* ⊗ q at every row (rad)."""
    vec = qr[:, [0]] * q[:, 1:] - q[:, [0]] * qr[:, 1:] - np.cross(qr[:, 1:], q[:, 1:])
    return 2 * np.arcsin(np.clip(np.linalg.norm(vec, axis=1), 0, 1))


@pytest.mark.slow
def test_both_masters_close_the_delayed_loop_and_not_the_delay_free_one(runs):
    sc = load_scene("torque_driven")
    delayed = closed_loop_scipy(sc, OneSampleDelay(cosim_controller()), 4.0, 1e-3, rtol=1e-13, atol=1e-15)
    free = closed_loop_scipy(sc, cosim_controller(), 4.0, 1e-3, rtol=1e-13, atol=1e-15)
    assert _angles(delayed.q[-1:], delayed.q[:1])[0] > 1.0  # the reference itself slewed
    for r in runs.values():
        assert len(r.t) == len(delayed.time) and np.allclose(r.t, delayed.time, rtol=0, atol=1e-12)
        q = np.column_stack([r.values[f"plant.q[{k}]"] for k in (1, 2, 3, 4)])
        w = np.column_stack([r.values[f"plant.w_body[{k}]"] for k in (1, 2, 3)])
        att, rate = _angles(q, delayed.q).max(), np.abs(w - delayed.w_body).max()
        print(f"{r.master}: max angle {att:.2g} rad, max |w - ref| {rate:.2g} rad/s; "
              f"delay-free: {_angles(q, free.q).max():.2g} rad")  # fmt: skip
        assert att <= TOL and rate <= TOL, (r.master, att, rate)
        assert _angles(q, free.q).max() > 1e-5, r.master
