"""The attitude_torque_pd controller FMU: its law against rbcheck's AttitudePD, its limit, its refusals.

Built once per module (host binary only), FMI 3.0 and 2.0. The law is compared with rbcheck's
independent numpy AttitudePD (rbcheck.baselines.rigid_body, the report's Python co-simulation
controller), whose body torque it must be.
"""

from __future__ import annotations

import numpy as np
import pytest

from fmu.build.controller_build import build_controller
from modelsrc.controllers.controller_file import load_controller
from modelsrc.errors import ModelInputError
from rbcheck.baselines.rigid_body import AttitudePD
from rbcheck.workprecision.cosim import cosim_controller

from ..harness.slave import Slave

TAU = [f"tau_body[{i}]" for i in (1, 2, 3)]


@pytest.fixture(scope="module")
def ctrl_fmus(tmp_path_factory):
    out = tmp_path_factory.mktemp("controllers")
    return {v: build_controller("attitude_torque_pd", out, fmi_version=v) for v in (3, 2)}


def inputs(q, w) -> dict[str, float]:
    d = {f"q[{i + 1}]": float(q[i]) for i in range(4)}
    d.update({f"w_body[{i + 1}]": float(w[i]) for i in range(3)})
    return d


def test_the_shipped_file_is_the_reports_python_controller():
    """Gains and target of attitude_torque_pd.toml are those of the report's AttitudePD (cosim_controller)."""
    ctrl, c = load_controller("attitude_torque_pd"), cosim_controller()
    start = {v.name: v.start for v in ctrl.variables}
    assert (start["k_p"], start["k_d"]) == (c.kp, c.kd)
    qd = np.array([start[f"q_d[{i}]"] for i in (1, 2, 3, 4)])
    np.testing.assert_allclose(qd, c.qt_conj * [1, -1, -1, -1], rtol=0, atol=1e-16)
    assert ctrl.sample_period == 1e-3


@pytest.mark.parametrize("version", [3, 2])
def test_the_outputs_are_rbchecks_attitude_pd_at_the_current_inputs(ctrl_fmus, version):
    """500 random (q, ω) (q of any norm near 1, either sign of q_e0, k_p = 1.3, k_d = 0.7, a random
    unit target) at t = 0, a sample point: the outputs are AttitudePD's tau_body (numpy, written
    out in scalars); asserted ≤ 1e-14 N·m (round-off of |τ| ~ 3)."""
    rng = np.random.default_rng(11)
    qd = rng.normal(size=4)
    qd /= np.linalg.norm(qd)
    start = {"k_p": 1.3, "k_d": 0.7, **{f"q_d[{i + 1}]": float(qd[i]) for i in range(4)}}
    c = Slave(ctrl_fmus[version], version, start)
    law = AttitudePD(qd, kp=1.3, kd=0.7)
    worst = 0.0
    for _ in range(500):
        q = rng.normal(size=4)
        q *= (1 + 1e-3 * rng.normal()) / np.linalg.norm(q)
        w = 2.0 * rng.normal(size=3)
        c.set(inputs(q, w))
        ref = law(0.0, inputs(q, w))
        worst = max(worst, float(np.max(np.abs(c.get(TAU) - np.array([ref[k] for k in TAU])))))
    c.close()
    print(f"FMI {version}: max |tau_body - AttitudePD| = {worst:.3g} N m")
    assert worst <= 1e-14


def test_each_component_is_clipped_to_the_torque_limit_and_held_between_samples(ctrl_fmus):
    """tau_max = 0.3 N·m: the outputs are AttitudePD's torques clipped to ±0.3 (some clipped, some
    not); at t = 0.0005 s (between samples, Ts = 1 ms) new inputs leave them as latched."""
    c = Slave(ctrl_fmus[3], 3, {"tau_max": 0.3})
    law = cosim_controller()
    rng = np.random.default_rng(5)
    clipped = free = 0
    for _ in range(200):
        q, w = rng.normal(size=4), 0.3 * rng.normal(size=3)
        q /= np.linalg.norm(q)
        c.set(inputs(q, w))
        raw = np.array([law(0.0, inputs(q, w))[k] for k in TAU])
        clipped += int(np.sum(np.abs(raw) > 0.3))
        free += int(np.sum(np.abs(raw) < 0.3))
        np.testing.assert_allclose(c.get(TAU), np.clip(raw, -0.3, 0.3), rtol=0, atol=1e-14)
    held = c.get(TAU)
    c.step(0.0, 5e-4)
    c.set(inputs([0.1, 0.9, 0.3, 0.2], [1.0, -1.0, 0.5]))
    assert np.array_equal(c.get(TAU), held)
    c.close()
    assert clipped > 50 and free > 50


BASE = 'law = "attitude_torque_pd"\nplant = "torque_driven"\nsample_period = 0.001\n'


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (BASE + "[gains]\nk_p = -0.5\n", r"field 'gains.k_p': must be >= 0, got -0.5"),
        (BASE + "[gains]\nk_d = nan\n", r"field 'gains.k_d': must be finite, got nan"),
        (BASE + "[gains]\nk_i = 1\n", r"field 'gains.k_i'"),
        (BASE.replace("0.001", "0.0"), r"field 'sample_period': must be > 0, got 0.0"),
        (
            BASE.replace("torque_driven", "free_asymmetric"),
            r"field 'plant': scene 'free_asymmetric' has no body torque",
        ),
        (BASE + "[limits]\ntorque = 0\n", r"field 'limits.torque': must be in"),
        (BASE + "[target]\nq = [1.0, 0.1, 0.0, 0.0]\n", r"field 'target.q': must be a unit quaternion"),
    ],
)
def test_a_bad_controller_file_is_refused_naming_the_value(tmp_path, text, message):
    p = tmp_path / "c.toml"
    p.write_text(text)
    with pytest.raises(ModelInputError, match=message):
        load_controller(p)


def test_a_bad_value_set_on_the_fmu_is_refused_and_undone(ctrl_fmus):
    """In Step Mode a negative gain, a zero torque limit, a non-unit target fail the parameter
    check and are undone; Ts (fixed) cannot be set."""
    c = Slave(ctrl_fmus[3], 3)
    for name, bad, text in (("k_d", -1.0, "k_d >= 0"), ("tau_max", 0.0, "tau_max > 0"), ("q_d[2]", 0.5, "|q_d| - 1")):
        old = c.get([name])[0]
        with pytest.raises(Exception, match="status 3"):
            c.set({name: bad})
        assert c.get([name])[0] == old
        assert any(text in m for m in c.log), (text, c.log)
    with pytest.raises(Exception, match="status 3"):
        c.set({"Ts": 0.2})
    assert any("'Ts' is a fixed parameter" in m for m in c.log), c.log
    c.close()
