"""What `rbfmu run` shows a user, tested: the plot's series as data, the summary of a moving body, a render.

The series: a continuous orientation, the path of a moving body, and forced energy apart
from the invariants."""

from __future__ import annotations

import dataclasses

import numpy as np

from fmu.drive.run import RunResult
from fmu.drive.summary import format_table, plot_run, plot_series, steps_text, summarize
from modelsrc.scene import load_scene


def _result(scene: str, t: np.ndarray, q: np.ndarray, **extra: np.ndarray) -> RunResult:
    """A RunResult made up from arrays: q (n, 4), every other vector (n, 3)."""
    values = {f"q[{k + 1}]": q[:, k] for k in range(4)}
    extra.setdefault("w_body", np.zeros((len(t), 3)))
    for base, arr in extra.items():
        values.update({f"{base}[{k + 1}]": arr[:, k] for k in range(arr.shape[1])} if arr.ndim == 2 else {base: arr})
    return RunResult(load_scene(scene), t, values, wall_time=0.1, n_steps=len(t) - 1)


def _rod_through_vertical(n: int = 401) -> tuple[np.ndarray, np.ndarray]:
    """A rod swinging about the world x axis through the vertical, tilt -0.5 -> 0.5 rad, while
    spinning about its own axis (precession and spin angles are undefined at the vertical)."""
    t = np.linspace(0.0, 1.0, n)
    tilt, spin = -0.5 + t, 7.0 * t
    qx = np.column_stack([np.cos(tilt / 2), np.sin(tilt / 2), 0 * t, 0 * t])  # about world x
    qz = np.column_stack([np.cos(spin / 2), 0 * t, 0 * t, np.sin(spin / 2)])  # about body z
    w1, v1, w2, v2 = qx[:, :1], qx[:, 1:], qz[:, :1], qz[:, 1:]
    q = np.column_stack([w1 * w2 - np.sum(v1 * v2, 1, keepdims=True), w1 * v2 + w2 * v1 + np.cross(v1, v2)])
    return t, q


def test_orientation_series_are_continuous_through_the_vertical():
    t, q = _rod_through_vertical()
    # the z-x-z angles an FMU outputs for this motion jump by pi at the vertical (phi, psi)
    res = _result("heavy_top", t, q, E_total=np.ones_like(t), L_world=np.ones((len(t), 3)))
    panel = plot_series(res)["orientation"]
    step = np.max(np.abs(np.diff(t)))
    for label, y in panel.series.items():
        # every curve moves by at most its largest rate (1 rad/s tilt: unit vector, angle) per sample
        assert np.max(np.abs(np.diff(y))) <= 1.0 * step * (1 + 1e-9), label
    axis = np.column_stack([panel.series[f"body z axis, world {c}"] for c in "xyz"])
    np.testing.assert_allclose(axis, np.column_stack([0 * t, -np.sin(-0.5 + t), np.cos(-0.5 + t)]), atol=1e-14)
    theta = panel.series["θ = tilt of body z from world z [rad]"]
    np.testing.assert_allclose(theta, np.abs(-0.5 + t), atol=1e-7)  # acos-accuracy near 0: ~sqrt(eps)


def test_forced_energy_is_not_an_invariant_and_gets_its_own_axis():
    t = np.linspace(0.0, 1.0, 11)
    q = np.tile([1.0, 0, 0, 0], (len(t), 1))
    res = _result("torque_driven", t, q, E_total=t**2, E_kin=t**2, L_world=np.ones((len(t), 3)))
    panels = plot_series(res)
    assert not any(label.startswith("max |E") or "E_" in label for label in panels["invariants"].series)
    assert "|L|" not in " ".join(panels["invariants"].series)  # torques: L is not conserved either
    assert list(panels["energy"].series) == ["E_total"] and not panels["energy"].log
    # a conserving scene keeps E among the invariants and has no energy panel
    free = plot_series(_result("symmetric_free", t, q, E_kin=1.0 + 1e-15 * t, L_world=np.ones((len(t), 3))))
    assert "max |E−E0|/|E0|" in free["invariants"].series and "energy" not in free
    # a drift of exactly 0 (|L| here, and E at t = 0) is not drawn at a made-up floor: left out, named in the note
    assert "max ||L|−|L0||/|L0|" not in free["invariants"].series
    assert "max ||L|−|L0||/|L0|" in free["invariants"].note and "exactly 0" in free["invariants"].note
    assert np.isnan(free["invariants"].series["max |E−E0|/|E0|"][0])


def _thrown(n: int = 141) -> RunResult:
    """The racket's centre of mass on its parabola (gravity only), M = 0.34 kg."""
    t = np.linspace(0.0, 1.4, n)
    g, v0, x0, m = np.array([0, 0, -9.81]), np.array([1.0, 0, 7.0]), np.array([0, 0, 1.5]), 0.34
    x = x0 + np.outer(t, v0) + 0.5 * np.outer(t**2, g)
    v = v0 + np.outer(t, g)
    q = np.tile([1.0, 0, 0, 0], (n, 1))
    ones = np.ones(n)
    return _result("thrown_racket", t, q, x_cm=x, v_cm=v, a_cm=np.tile(g, (n, 1)), p=m * v, E_total=ones)


def test_translation_scenes_have_a_path_and_a_momentum_summary():
    res = _thrown()
    path = plot_series(res)["path"].series
    assert set(path) == {"x_cm x", "x_cm y", "x_cm z"}
    s = summarize(res)
    assert s["x_cm1"] == 1.4 and abs(s["x_cm3"] - (1.5 + 7 * 1.4 - 0.5 * 9.81 * 1.4**2)) < 1e-12
    assert abs(s["impulse"] - 0.34 * 9.81 * 1.4) < 1e-12
    assert s["p_balance"] < 1e-13  # constant force: the trapezoid rule is exact
    table = format_table([("thrown_racket", s)])
    assert "x_cm(T) z [m]" in table and "p balance" in table


def test_moving_pivot_path_shows_the_pivot_and_renders(tmp_path):
    t = np.linspace(0.0, 0.5, 201)
    q = np.tile([np.cos(0.15), np.sin(0.15), 0, 0], (len(t), 1))
    zp = -5e-4 * np.cos(2 * np.pi * 20 * t)
    xp = np.column_stack([0 * t, 0 * t, zp])
    res = _result("top_on_shaker", t, q, x_pivot=xp, v_pivot=0 * xp, x_cm=xp + [0, -0.012, 0.038],
                  v_cm=0 * xp, E_total=np.sin(t), L_world=np.ones((len(t), 3)))  # fmt: skip
    panels = plot_series(res)
    assert "x_cm z" in panels["path"].series and "x_pivot z" in panels["pivot"].series
    assert "energy" in panels  # the shaker does work
    plot_run(res, tmp_path / "shaker.png")  # smoke render
    assert (tmp_path / "shaker.png").stat().st_size > 10_000


def test_an_orbit_shows_the_jacobi_integral_among_the_invariants():
    # gravity_gradient_boom: E_kin changes (the orbit's field works on the body, docs/theory.md
    # §9.3) while E_jacobi is conserved: its drift goes on the invariants panel and into the
    # summary's E drift; E_kin keeps its own axis, labelled as such.
    t = np.linspace(0.0, 1.0, 11)
    q = np.tile([1.0, 0, 0, 0], (len(t), 1))
    EJ = 2.0 * (1.0 + 1e-12 * t)
    res = _result("gravity_gradient_boom", t, q, E_kin=1.0 + t, E_jacobi=EJ, L_world=np.ones((len(t), 3)))
    panels = plot_series(res)
    drift = panels["invariants"].series["max |E_J−E_J0|/|E_J0|"]
    assert np.isnan(drift[0])  # 0 at the start: not drawn on the log axis
    np.testing.assert_allclose(drift[1:], 1e-12 * t[1:], rtol=1e-3)
    assert "max |E−E0|/|E0|" not in panels["invariants"].series
    assert panels["energy"].ylabel == "E [J] (not conserved; E_jacobi is)"
    assert list(panels["energy"].series) == ["E_kin"]
    assert abs(summarize(res)["E_drift"] - 1e-12) < 1e-15
    # a torque on an orbiting body works as well: no invariant then (none of it claimed)
    forced = dataclasses.replace(res.scene, features=res.scene.features | {"torque_body"})
    res_f = RunResult(forced, t, res.values, wall_time=0.1, n_steps=len(t) - 1)
    assert "max |E_J−E_J0|/|E_J0|" not in plot_series(res_f)["invariants"].series
    assert np.isnan(summarize(res_f)["E_drift"])


def test_a_central_field_names_the_total_angular_momentum_it_conserves():
    # eccentric_orbit: the body's own L_world swings by 68 % over the orbit (the field's
    # gravity-gradient torque) while L_total = m x × v + L_world is conserved (docs/theory.md
    # §9.7): the invariants panel names L_total, not an |L| a reader takes for the body's
    t = np.linspace(0.0, 1.0, 11)
    q = np.tile([1.0, 0, 0, 0], (len(t), 1))
    L_total = np.tile([0.0, 0.0, 5.0], (len(t), 1)) * (1.0 + 1e-13 * t)[:, None]
    L_world = np.column_stack([t, 0 * t, 1.0 + 0 * t])
    res = _result("eccentric_orbit", t, q, E_kin=1.0 + 0 * t, E_total=-3.0 + 0 * t, L_world=L_world, L_total=L_total)
    series = plot_series(res)["invariants"].series
    assert "max ||L_total|−|L_total0||/|L_total0|" in series and "max ||L|−|L0||/|L0|" not in series
    assert abs(summarize(res)["L_drift"] - 1e-13) < 1e-15  # the summary's |L| drift is L_total's


def test_the_plot_title_gives_the_steps_as_taken():
    # eccentric_orbit's period 5828.52 s in steps of 10 s: the title said "583 steps of 10 s" (5830 s)
    t = np.r_[np.arange(0.0, 5828.52, 10.0), 5828.52]
    assert steps_text(t) == "583 steps of 10 s (the last 8.52 s)"
    assert steps_text(np.linspace(0.0, 2.0, 2001)) == "2000 steps of 0.001 s"
    assert steps_text(np.array([0.0, 0.1, 0.15, 0.2, 0.3])) == "4 steps of 0.1 s (2 shorter, down to 0.05 s)"
