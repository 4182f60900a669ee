"""The demo's closed-loop figures (fmu.system.demo) against trajectories whose figures are known in closed form."""

from __future__ import annotations

import math

import numpy as np

from fmu.system.demo import hover_figures, settling_time, slew_figures
from fmu.system.masters import SystemResult
from rbcheck.closed_forms.slew import eigenaxis_reference


def test_settling_time_is_the_first_point_after_which_the_error_stays_in_the_band() -> None:
    t = np.arange(6.0)
    assert settling_time(t, np.array([1.0, 0.5, 0.01, 0.03, 0.01, 0.0]), 0.02) == 4.0
    assert settling_time(t, np.full(6, 0.01), 0.02) == 0.0
    assert settling_time(t, np.array([1.0, 0.0, 0.0, 0.0, 0.0, 0.5]), 0.02) == math.inf


def _slew_result(phi: np.ndarray, axis: np.ndarray, H: float) -> SystemResult:
    """A result whose attitude turns by φ_k about a fixed axis (target: the identity)."""
    q = np.column_stack([np.cos(phi / 2), np.outer(np.sin(phi / 2), axis)])
    values = {f"plant.q[{i + 1}]": q[:, i] for i in range(4)}
    return SystemResult("test", np.arange(phi.size) * H, values)


def test_slew_figures_read_the_eigenaxis_angle() -> None:
    # the exact sampled-data slew, gains chosen underdamped so that it overshoots
    phi, _ = eigenaxis_reference(math.pi / 2, 0.5, 0.3, 0.1, 600)
    axis = np.array([1.0, 2.0, 2.0]) / 3.0
    figs = slew_figures(
        _slew_result(phi, axis, 0.1), "plant", {"q_d[1]": 1.0, "q_d[2]": 0.0, "q_d[3]": 0.0, "q_d[4]": 0.0}
    )
    assert abs(figs["start error"][0] - math.pi / 2) < 1e-15
    assert abs(figs["end error"][0] - abs(phi[-1])) < 1e-12
    assert abs(figs["overshoot"][0] - 100.0 * max(0.0, -phi.min()) / phi[0]) < 1e-9
    assert figs["overshoot"][0] > 1.0  # the case really overshoots: the figure is not 0 by construction
    t = np.arange(phi.size) * 0.1
    assert figs["settling (2 %)"][0] == settling_time(t, np.abs(phi), 0.02 * phi[0])


def test_hover_figures_read_height_yaw_and_drift() -> None:
    t = np.arange(11) * 0.1
    z = 2.0 - np.exp(-t)  # height from 1 m towards 2 m
    psi = 0.5 * (1.0 - np.exp(-t))  # yaw towards 0.5 rad
    values = {"plant.x_cm[1]": 0.1 * t, "plant.x_cm[2]": np.zeros_like(t), "plant.x_cm[3]": z}
    q = np.column_stack([np.cos(psi / 2), 0 * t, 0 * t, np.sin(psi / 2)])
    values.update({f"plant.q[{i + 1}]": q[:, i] for i in range(4)})
    figs = hover_figures(
        SystemResult("test", t, values), "plant", {"x_d[1]": 0.0, "x_d[2]": 0.0, "x_d[3]": 2.0, "psi_d": 0.5}
    )
    assert abs(figs["height error"][0] + math.exp(-1.0)) < 1e-15
    assert abs(figs["yaw error"][0] + 0.5 * math.exp(-1.0)) < 1e-15
    assert abs(figs["horizontal drift"][0] - 0.1) < 1e-15
    assert figs["height settling (2 %)"][0] == math.inf  # e^-1 is outside 2 % of the 1 m step
