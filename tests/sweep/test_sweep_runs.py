"""Sweeps in this process: the same bits as fresh runs, failures recorded, and figures against closed forms."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from scipy.optimize import brentq

from fmu.drive.inputs import scene_input
from fmu.drive.run import run_fmu
from fmu.sweep import sweep
from fmu.sweep.results import plot_map, read_table, write_table
from fmu.sweep.worker import extraction_count
from modelsrc.errors import ModelInputError
from modelsrc.methods import METHODS
from modelsrc.scene import load_scene
from rbcheck.closed_forms import free_asymmetric, heavy_top


def test_reused_instance_gives_the_bits_of_a_fresh_run(fmus):
    # fmi3Reset + start values must give exactly what a freshly instantiated FMU gives
    # (fmu.drive.run.run_fmu, through fmpy), for every method and start value swept.
    sc = load_scene("heavy_top")
    before = extraction_count()
    df = sweep(
        fmus["heavy_top"],
        {"w_body[3]": [120.0, 180.0], "method": ["rk4", "gauss4"]},
        ["max(euler_zxz[2])", "min(E_kin)"],
        scene="heavy_top",
        workers=0,
        stop_time=0.2,
        chunk_size=1,
    )
    assert extraction_count() == before + 1  # 4 chunks, one instance
    assert df["ok"].all() and len(df) == 4
    for run, row in df.iterrows():
        ref = run_fmu(
            fmus["heavy_top"],
            sc,
            stop_time=0.2,
            start_values={"w_body[3]": row["w_body[3]"], "method": row["method"]},
        )
        v = ref.values
        assert row["method"] == METHODS[["rk4", "gauss4"][run % 2]].value
        for k in range(1, 5):
            assert row[f"end(q[{k}])"] == v[f"q[{k}]"][-1]
        for k in range(1, 4):
            assert row[f"end(w_body[{k}])"] == v[f"w_body[{k}]"][-1]
        assert row["max(euler_zxz[2])"] == v["euler_zxz[2]"].max()
        assert row["min(E_kin)"] == v["E_kin"].min()
        assert row["E_drift"] == np.max(np.abs(v["E_total"] - v["E_total"][0])) / abs(v["E_total"][0])
        assert math.isnan(row["L_drift"])  # gravity: |L| is not conserved (Scene.torque_free)


def test_swept_input_is_held_constant_over_the_table(fmus):
    # torque_driven's tau_body is a table; a swept tau_body[3] replaces its third column.
    sc = load_scene("torque_driven")
    df = sweep(
        fmus["torque_driven"], {"tau_body[3]": [0.0, 0.5]}, ["E_kin"], scene="torque_driven", workers=0, stop_time=5.0
    )
    for _, row in df.iterrows():

        def held(t, _outputs, value=row["tau_body[3]"]):
            u = {f"tau_world[{k + 1}]": x for k, x in enumerate(scene_input(sc, "tau_world", t, t))}
            tb = scene_input(sc, "tau_body", t, t)  # the table row in force at t
            u.update({"tau_body[1]": tb[0], "tau_body[2]": tb[1], "tau_body[3]": value})
            return u

        ref = run_fmu(fmus["torque_driven"], sc, stop_time=5.0, input_fn=held)
        assert row["end(E_kin)"] == ref.values["E_kin"][-1]
        assert row["end(w_body[3])"] == ref.values["w_body[3]"][-1]
    assert df["end(E_kin)"].iloc[0] != df["end(E_kin)"].iloc[1]


def test_failed_runs_are_recorded_and_do_not_stop_the_sweep(fmus):
    runs = pd.DataFrame({"I_principal[1]": [1.0, -1.0, 1.0, 1.0], "w_body[2]": [1.0, 1.0, 1e150, 1.0]})
    df = sweep(
        fmus["free_asymmetric"],
        runs,
        ["max(E_kin)"],
        scene="free_asymmetric",
        workers=0,
        stop_time=0.5,
        fixed={"method": "gauss4", "tolerance": 0.0},
    )
    assert df["ok"].tolist() == [True, False, False, True]
    assert "exitInitializationMode failed" in df.loc[1, "error"] and "I_principal[1] > 0" in df.loc[1, "error"]
    # a spin of 1e150 rad/s: gauss4 (fixed steps) would need more steps than work_limit admits
    assert "doStep(t=0.0" in df.loc[2, "error"] and "more than work_limit" in df.loc[2, "error"]
    assert df.loc[1:2, "max(E_kin)"].isna().all()
    # the run after two failures is the first run again, to the bit: reset restored everything
    figures = [c for c in df.attrs["figures"]]
    assert df.loc[3, figures].equals(df.loc[0, figures])


def _first_zero_of_w2(I, w0, t_end, h):
    """First zero (s) of ω2 on [0, t_end] from the closed form (rbcheck.closed_forms.free_asymmetric),
    |ω2'| there and max |ω2''| within h of it (for the interpolation bound); None if none."""
    t = np.linspace(0.0, t_end, 30_001)  # 1 ms: brackets the zero for brentq
    w2 = free_asymmetric.omega(I, w0, t)[:, 1]
    idx = np.flatnonzero(np.sign(w2) != np.sign(w2[0]))
    if idx.size == 0:
        return None
    i = int(idx[0])
    tz = brentq(lambda s: free_asymmetric.omega(I, w0, s)[0, 1], t[i - 1], t[i], xtol=1e-14)
    near = np.linspace(tz - h, tz + h, 41)
    d = near[1] - near[0]
    w = free_asymmetric.omega(I, w0, near)[:, 1]
    return tz, abs(w[21] - w[19]) / (2 * d), np.max(np.abs(np.diff(w, 2))) / d**2


def test_tennis_racket_flip_time_matches_the_closed_form(fmus):
    # Time to the first flip (ω2 through 0) of a body spun about its intermediate axis,
    # docs/theory.md §2.3; exact_free integrates the torque-free body exactly, so what is
    # left is the linear interpolation between communication points (step H): the zero
    # of the chord misses the true zero by at most H² max|ω2''| / (8 |ω2'|) (max over the
    # step around it; ω2'' vanishes at the zero itself), plus rounding (1e-12 s).
    T, H = 30.0, 0.01
    df = sweep(
        fmus["free_asymmetric"],
        {"I_principal[2]": [2.2, 2.5, 2.99], "w_body[1]": [1e-3, 1e-1]},
        ["cross(w_body[2], 0)"],
        scene="free_asymmetric",
        workers=0,
        stop_time=T,
        step=H,
        fixed={"method": "exact_free", "w_body[3]": 0.0},
    )
    assert df["ok"].all()
    for _, row in df.iterrows():
        I, w0 = [1.0, row["I_principal[2]"], 3.0], [row["w_body[1]"], 1.0, 0.0]
        ref = _first_zero_of_w2(I, w0, T, H)
        got = row["cross(w_body[2], 0)"]
        if ref is None:  # slow growth near I2 = I3: no flip before T, NaN in the table
            assert math.isnan(got), (I, w0, got)
            continue
        tz, d1, d2 = ref
        tol = H**2 * d2 / (8 * d1) + 1e-12
        assert abs(got - tz) <= tol, (I, w0, got, tz, tol)
    assert df["cross(w_body[2], 0)"].isna().sum() >= 1 and df["cross(w_body[2], 0)"].notna().sum() >= 4


def test_sleeping_top_max_tilt_matches_the_closed_form(fmus):
    # Frictionless sleeping top started 1 mrad from the vertical (docs/theory.md §4.2):
    # the tilt nutates between θ0 and arccos(u1) (u1: lowest root of f(u)); the table's
    # max(euler_zxz[2]) samples θ every H, so it can miss the peak by |θ''| (H/2)² / 2,
    # plus RK4's error at h_max = 1e-4 s (< 1e-8 rad here, far below the sampling term).
    sc = load_scene("sleeping_top")
    I1 = sc.inertia[0, 0] + sc.mass * sc.r_cm[2] ** 2  # about the pivot (docs/theory.md §3.2)
    params = heavy_top.TopParams(I1, sc.inertia[2, 2], sc.mass, 9.81, sc.r_cm[2])
    w_c = heavy_top.sleeping_threshold(params.I1, params.I3, params.M, params.g, params.l)
    spins = [0.6 * w_c, 0.98 * w_c, 1.02 * w_c, 1.5 * w_c]
    refs = []
    for w3 in spins:
        init = heavy_top.init_from_state(sc.q0, [0.0, 0.0, w3])
        top = heavy_top.HeavyTop(params, init)
        t = np.linspace(0.0, top.period, 20001)
        theta = top.angles(t)[0]
        refs.append((math.acos(top.u1), top.period, np.max(np.abs(np.gradient(np.gradient(theta, t), t)))))
    T, H = 1.05 * max(r[1] for r in refs), 1e-3
    df = sweep(
        fmus["sleeping_top"],
        {"w_body[3]": spins},
        ["max(euler_zxz[2])"],
        scene="sleeping_top",
        workers=0,
        stop_time=T,
        step=H,
        fixed={"c_friction": 0.0},
    )
    for (theta_max, _, d2), got in zip(refs, df["max(euler_zxz[2])"]):
        tol = d2 * (H / 2) ** 2 / 2 + 1e-8
        assert theta_max - tol <= got <= theta_max + 1e-8, (got, theta_max, tol)
    tilt = df["max(euler_zxz[2])"].to_numpy()
    assert tilt[1] > 0.3 and tilt[2] < 0.1  # falls just below the threshold, sleeps just above


def test_table_round_trips_and_maps_are_drawn(fmus, tmp_path):
    df = sweep(
        fmus["symmetric_free"],
        {"w_body[1]": [0.2, 0.4, 0.8], "w_body[3]": [1.0, 2.0]},
        ["max(euler_zxz[2])"],
        scene="symmetric_free",
        workers=0,
        stop_time=0.5,
    )
    for name in ("t.parquet", "t.csv"):
        back = read_table(write_table(df, tmp_path / name))
        pd.testing.assert_frame_equal(back, df, check_exact=True, check_dtype=False)
    assert read_table(tmp_path / "t.parquet").attrs["swept"] == ["w_body[1]", "w_body[3]"]
    heat = plot_map(df, "max(euler_zxz[2])", tmp_path / "heat.png")
    line = plot_map(df[df["w_body[3]"] == 1.0], "max(euler_zxz[2])", tmp_path / "line.png", x="w_body[1]")
    assert heat.stat().st_size > 10_000 and line.stat().st_size > 10_000
    with pytest.raises(ModelInputError, match="not a column"):
        plot_map(df, "max(E_kin)", tmp_path / "x.png")


def test_an_fmu_names_its_scene_by_its_build_key(fmus, tmp_path):
    import zipfile

    from fmu.build.build_fmu import BUILD_KEY_MEMBER
    from fmu.sweep.api import scene_of_fmu

    assert scene_of_fmu(fmus["heavy_top"]).name == "heavy_top"
    other = tmp_path / "heavy_top.fmu"  # the same archive with another build key: not identifiable
    with zipfile.ZipFile(fmus["heavy_top"]) as src, zipfile.ZipFile(other, "w") as dst:
        for item in src.infolist():
            dst.writestr(item, b"0" * 64 if item.filename == BUILD_KEY_MEMBER else src.read(item))
    with pytest.raises(ModelInputError, match=r"its scene is unknown; sweep the scene itself \(its .toml file\)"):
        sweep(other, {"w_body[3]": [100.0]}, workers=0)
    df = sweep(other, {"w_body[3]": [100.0]}, scene="heavy_top", workers=0, stop_time=0.01)
    assert df["ok"].all()


def test_dual_spin_map_matches_the_gyrostat_condition(fmus):
    # The stability map of dual_spin (fmu.sweep.examples.dual_spin, docs/theory.md §8.3): the
    # drawn boundary agrees with rbcheck.closed_forms.dual_spin's condition k1 k2 > 0 everywhere off it,
    # and the FMU's largest tilt in 60 s from ω1 = 0.01 rad/s classifies cells 30 % of the
    # boundary's speed on either side of each line as the condition does. Unstable cells
    # there grow at λ = sqrt(−k1 k2 / (I1 I2)) ≥ 0.17 /s, a factor e^10 in 60 s, so they tip
    # over (θ > 1 rad); stable ones nutate with θ of the order of ω1 / ω3 (θ < 0.2 rad).
    from fmu.sweep.examples import DUAL_SPIN_FIGURE, dual_spin_boundary, dual_spin_inertia, dual_spin_stable
    from rbcheck.closed_forms import dual_spin

    inertia, j = dual_spin_inertia()
    omega, w3 = np.meshgrid(np.linspace(-250.0, 250.0, 41), np.linspace(0.1, 2.5, 25))
    drawn = dual_spin_stable(omega, w3)
    ref = np.vectorize(lambda o, w: dual_spin.stable(inertia, 2, w, j * o))(omega, w3)
    assert np.array_equal(drawn, ref) and 0 < drawn.sum() < drawn.size
    cells = []
    for w in (1.0, 2.0):
        for b in dual_spin_boundary(np.array(w)):
            cells += [(float(b) - 0.3 * abs(float(b)), w), (float(b) + 0.3 * abs(float(b)), w)]
    df = sweep(
        fmus["dual_spin"],
        pd.DataFrame(cells, columns=["Omega_wheel", "w_body[3]"]),
        [DUAL_SPIN_FIGURE],
        scene="dual_spin",
        workers=0,
        stop_time=60.0,
        step=0.05,
        fixed={"w_body[1]": 0.01, "w_body[2]": 0.0, "u_wheel": 0.0},
    )
    assert df["ok"].all()
    for (o, w), tilt in zip(cells, df[DUAL_SPIN_FIGURE]):
        if dual_spin.stable(inertia, 2, w, j * o):
            assert tilt < 0.2, (o, w, tilt)
        else:
            assert dual_spin.growth_rate(inertia, 2, w, j * o) >= 0.17
            assert tilt > 1.0, (o, w, tilt)
