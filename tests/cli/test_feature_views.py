"""What `rbfmu run` shows per feature (issue 34 item 2): rotor, orbit and multirotor panels, inputs, table, CSV.

Made-up runs (fmu.drive.run.RunResult from arrays) hold the plot's series and the summary to
what each feature's users look at (fmu.drive.feature_views); one real run of the quadrotor
holds the recorded inputs to the scene's schedule.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from fmu.drive.run import RunResult, run_fmu
from fmu.drive.summary import draw_run, format_table, plot_series, summarize, write_csv
from modelsrc.scene import load_scene

from ..harness.scenes import shared_fmu


def _result(scene: str, t: np.ndarray, q: np.ndarray, inputs=None, **extra: np.ndarray) -> RunResult:
    """A RunResult made up from arrays: q (n, 4), vectors (n, k), scalars (n,)."""
    values = {f"q[{k + 1}]": q[:, k] for k in range(4)}
    extra.setdefault("w_body", np.zeros((len(t), 3)))
    for base, arr in extra.items():
        values.update({f"{base}[{k + 1}]": arr[:, k] for k in range(arr.shape[1])} if arr.ndim == 2 else {base: arr})
    return RunResult(load_scene(scene), t, values, wall_time=0.1, n_steps=len(t) - 1, inputs=inputs or {})


T = np.linspace(0.0, 10.0, 101)
Q0 = np.tile([1.0, 0.0, 0.0, 0.0], (len(T), 1))


def test_a_wheel_scene_shows_its_speeds_momenta_and_motor_torque():
    wheel = {"Omega_wheel": 100.0 + T, "Omega_abs_wheel": 101.0 + T, "h_wheel": 101.0 + T}
    res = _result("dual_spin", T, Q0, inputs={"u_wheel": 0.5 * np.ones_like(T)}, E_kin=np.ones_like(T), **wheel)
    panels = plot_series(res)
    assert set(panels["rotor speeds"].series) == {"Ω wheel (relative)", "Ω wheel absolute"}
    np.testing.assert_array_equal(panels["rotor momenta"].series["h wheel"], 101.0 + T)
    np.testing.assert_array_equal(panels["inputs"].series["u_wheel"], 0.5)
    s = summarize(res)
    assert s["Omega_wheel [rad/s]"] == 110.0 and s["h_wheel [N m s]"] == 111.0
    assert "dual_spin: Omega_wheel = 110 rad/s, h_wheel = 111 N m s" in format_table([("dual_spin", s)])


def test_an_orbit_shows_roll_pitch_yaw_in_lvlh_instead_of_the_inertial_tilt():
    n = 2 * math.pi / 5400
    rpy = 1e-3 * np.column_stack([np.sin(n * T), np.cos(n * T), -np.sin(n * T)])
    EJ = 2000.002219 + 1e-12 * T  # the values of issue 34: an offset axis would read "1e-6+2.00002219e3"
    res = _result("gravity_gradient_boom", T, Q0, rpy_lvlh=rpy, w_lvlh=np.zeros((len(T), 3)), E_jacobi=EJ,
                  E_kin=1.0 + T, L_world=np.ones((len(T), 3)))  # fmt: skip
    panels = plot_series(res)
    assert "rates" not in panels and "orientation" not in panels  # inertial ω and the sawtooth tilt
    assert list(panels["attitude in LVLH"].series) == ["roll (LVLH)", "pitch (LVLH)", "yaw (LVLH)"]
    np.testing.assert_array_equal(panels["attitude in LVLH"].series["pitch (LVLH)"], rpy[:, 1])
    np.testing.assert_allclose(panels["Jacobi integral"].series["E_jacobi − E_jacobi(0)"], 1e-12 * T, atol=1e-12)
    s = summarize(res)
    assert s["pitch LVLH [rad]"] == rpy[-1, 1] and s["E_jacobi [J]"] == EJ[-1]
    fig = draw_run(res)
    fig.canvas.draw()
    for ax in fig.axes:
        # a scale factor (1e−3) may stand above an axis, an offset ("1e−6+2.00002219e3") may not
        assert "+" not in ax.yaxis.get_offset_text().get_text(), ax.get_ylabel()
        if ax.get_yscale() == "linear":
            assert not ax.yaxis.get_major_formatter().get_useOffset()
    labels = [tk.get_text() for ax in fig.axes for tk in ax.get_yticklabels() if ax.get_ylabel().startswith("E [J]")]
    assert labels and not any("e" in label for label in labels)  # plain values, no offset, no exponent
    import matplotlib.pyplot as plt

    plt.close(fig)


def test_a_multirotor_shows_height_heading_and_rotor_speeds():
    yaw = 0.3 * T  # about world z, more than 2π by the end: unwrapped
    q = np.column_stack([np.cos(yaw / 2), 0 * T, 0 * T, np.sin(yaw / 2)])
    x = np.column_stack([0 * T, 0 * T, 1.0 + 0.1 * T])
    omega = {f"Omega_p{k}": (-1) ** (k + 1) * (442.9 + np.sin(T)) for k in range(1, 5)}
    res = _result("quadrotor", T, q, inputs=omega, x_cm=x, v_cm=0 * x, a_cm=0 * x, p=0 * x, E_total=T)
    panels = plot_series(res)
    np.testing.assert_allclose(panels["height"].series["height"], 1.0 + 0.1 * T, rtol=1e-15)
    np.testing.assert_allclose(panels["heading"].series["heading"], yaw, atol=1e-12)
    np.testing.assert_array_equal(panels["rotor speeds"].series["Ω p2 (relative)"], omega["Omega_p2"])
    assert "inputs" not in panels  # the speed commands are the rotor speeds, not drawn twice
    s = summarize(res)
    assert s["height [m]"] == pytest.approx(2.0) and s["heading [rad]"] == pytest.approx(3.0)


def test_summary_columns_never_run_together():
    long = "a_scene_name_much_longer_than_twenty_characters"
    s = {"t_end": 16200.0, "steps": 1620, "wall_s": 12345.678, "w1": -7317.95505, "w2": -123456.5, "w3": 0.0,
         "E_drift": np.nan, "L_drift": -1.5e-300, "qnorm_err": 2.2e-16}  # fmt: skip
    table = format_table([(long, s), ("gravity_gradient_boom", s)]).splitlines()
    head = re.split(r"\s{2,}", table[0].strip())  # columns are at least two spaces apart
    assert len(head) == 10
    for line in table[2:4]:
        cells = re.split(r"\s{2,}", line.strip())
        assert len(cells) == len(head), line
        assert cells[0] in (long, "gravity_gradient_boom") and cells[1] == "16200.00" and cells[3] == "-7317.95505"


def test_the_run_csv_holds_the_inputs(tmp_path):
    res = _result("dual_spin", T, Q0, inputs={"u_wheel": np.sin(T)}, E_kin=np.ones_like(T))
    write_csv(res, tmp_path / "run.csv")
    data = np.genfromtxt(tmp_path / "run.csv", delimiter=",", names=True)
    np.testing.assert_array_equal(data["u_wheel"], np.sin(T))


def test_a_run_records_the_quadrotors_commanded_rotor_speeds(build_dir):
    sc = load_scene("quadrotor")
    res = run_fmu(shared_fmu(build_dir, "quadrotor"), sc, stop_time=0.5)
    for k in range(1, 5):
        want = np.array([sc.input_at(f"Omega_p{k}", t)[0] for t in res.time])
        np.testing.assert_array_equal(res.inputs[f"Omega_p{k}"], want)
    held = run_fmu(shared_fmu(build_dir, "quadrotor"), sc, stop_time=0.5, start_values={"Omega_p1": 400.0})
    np.testing.assert_array_equal(held.inputs["Omega_p1"], 400.0)  # a value set for an input holds it


def test_a_momentum_that_starts_at_zero_gets_its_absolute_drift():
    # reaction_wheel_slew: the motors' torques are internal, L_world is conserved and starts at 0:
    # no relative drift (n/a), so the summary gives max |L| (N m s) instead of nothing
    L = np.outer(np.sin(T), [1e-16, 0.0, 0.0])
    res = _result("reaction_wheel_slew", T, Q0, E_kin=np.ones_like(T), L_world=L)
    s = summarize(res)
    assert np.isnan(s["L_drift"]) and s["max |L| over the run (L(0) = 0) [N m s]"] == pytest.approx(
        1e-16 * np.max(np.sin(T))
    )
    assert "max |L| over the run (L(0) = 0) = 9.99923e-17 N m s" in format_table([("reaction_wheel_slew", s)])


def test_a_held_rate_shows_the_bearing_torque():
    # skewed_bar's answer is the torque the bearings supply (docs/theory.md §4.4): its own panel
    # (components and |τ|, world) and the largest |τ| at the end; the plot had ω and the tilt only
    tau = np.column_stack([0 * T, 3.6 * np.sin(10 * T), -3.6 * np.cos(10 * T)])
    res = _result("skewed_bar", T, Q0, tau_bearing=tau, E_kin=np.ones_like(T))
    panel = plot_series(res)["bearing torque"]
    assert panel.ylabel == "bearing torque (world) [N m]"
    np.testing.assert_allclose(panel.series["|tau_bearing|"], 3.6, rtol=1e-15)
    np.testing.assert_array_equal(panel.series["tau_bearing y"], tau[:, 1])
    s = summarize(res)
    assert math.isclose(s["max |tau_bearing| [N m]"], 3.6, rel_tol=1e-15)
    assert "skewed_bar: max |tau_bearing| = 3.6 N m" in format_table([("skewed_bar", s)])


def test_a_sensor_point_shows_its_position_velocity_and_acceleration():
    # two_frame_arm is about its wrist (a sensor point): its r, v, a panels (world) and |v|, |a| at T
    r = np.column_stack([0.25 * np.cos(T), 0.25 * np.sin(T), 0.3 + 0 * T])
    v = np.column_stack([-0.25 * np.sin(T), 0.25 * np.cos(T), 0 * T])
    a = -np.column_stack([0.25 * np.cos(T), 0.25 * np.sin(T), 0 * T])
    res = _result("two_frame_arm", T, Q0, sensor_r=r, sensor_v=v, sensor_a=a, E_kin=np.ones_like(T))
    panels = plot_series(res)
    assert panels["sensor position"].ylabel == "sensor position (world) [m]"
    np.testing.assert_allclose(panels["sensor velocity"].series["|sensor_v|"], 0.25, rtol=1e-15)
    np.testing.assert_allclose(panels["sensor acceleration"].series["|sensor_a|"], 0.25, rtol=1e-15)
    s = summarize(res)
    assert math.isclose(s["|sensor_v(T)| [m/s]"], 0.25) and math.isclose(s["|sensor_a(T)| [m/s2]"], 0.25)
    # a scene without the output has no such panels
    assert not any(k.startswith("sensor") for k in plot_series(_result("free_asymmetric", T, Q0)))
