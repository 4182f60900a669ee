"""The shipped sweep examples: the tennis-racket flip-time, sleeping-top and dual-spin stability maps (docs/sweeps/).

Run `python -m fmu.sweep.examples [--out docs/sweeps] [--tables out/sweeps] [--workers N]
[--quick] [--map NAME ...]`; each map is a sweep of a shipped scene through `fmu.sweep.sweep`, its PNG
(closed form drawn on top) written to --out and its table (Parquet) to --tables:

- tennis racket (free_asymmetric, I = (1, I2, 3) kg·m², exact_free): the time to the
  first flip, cross(w_body[2], 0), over I2 and the spin axis's offset ω1/ω2 from the
  intermediate axis (start ω = (ω1, 1, 0) rad/s). Closed form (docs/theory.md §2.3;
  rbcheck.closed_forms.free_asymmetric's elliptic solution): t = K(m)/λ with
  m = I2(3 − I2) / (I2(3 − I2) + 2ω1²), λ² = (I2 − 1)(I2(3 − I2) + 2ω1²) / (3 I2).
- sleeping top (sleeping_top, friction off): the largest tilt θ over 3 s from 1 mrad,
  max(euler_zxz[2]), over the spin ω3 and the centre-of-mass height l, with the
  threshold ω3² = 4 M g l I1 / I3² (I1 about the pivot, docs/theory.md §4.2) on top.
- dual spin (dual_spin, u_wheel = 0): the largest tilt θ of the body's spin axis z from
  world z, max(euler_zxz[2]), over 60 s from a transverse rate ω1 = 0.01 rad/s, over the
  wheel's relative speed Ω (h_w = J Ω) and the spin rate ω3, with the boundary of the
  gyrostat condition (I3 ω3 + h_w − I1 ω3)(I3 ω3 + h_w − I2 ω3) > 0 (docs/theory.md §8.3)
  on top: the two lines h_w = (I1 − I3) ω3 and h_w = (I2 − I3) ω3.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from modelsrc.scene import load_scene

from .api import sweep
from .results import plot_map, write_table

ROOT = Path(__file__).resolve().parent.parent.parent
OUT = ROOT / "docs" / "sweeps"
RACKET_FIGURE = "cross(w_body[2], 0)"
TOP_FIGURE = "max(euler_zxz[2])"
DUAL_SPIN_FIGURE = "max(euler_zxz[2])"


def racket_flip_time(i2: np.ndarray, w1: np.ndarray) -> np.ndarray:
    """Closed-form time (s) to the first zero of ω2 for I = (1, i2, 3) kg·m² and start
    ω = (w1, 1, 0) rad/s (body frame): K(m)/λ (the quarter period of the elliptic solution)."""
    from scipy.special import ellipk

    a = i2 * (3.0 - i2)
    m = a / (a + 2.0 * w1**2)
    lam = np.sqrt((i2 - 1.0) * (a + 2.0 * w1**2) / (3.0 * i2))
    return ellipk(m) / lam


def tennis_racket(out: Path, tables: Path, workers: int | None, quick: bool, build_dir: str | Path) -> pd.DataFrame:
    """The flip-time map of free_asymmetric: out/tennis_racket.png, tables/tennis_racket.parquet."""
    i2 = np.linspace(2.02, 2.98, 7 if quick else 25)
    w1 = np.geomspace(1e-6, 1e-1, 6 if quick else 21)
    df = sweep(
        "free_asymmetric",
        {"I_principal[2]": i2, "w_body[1]": w1},
        [RACKET_FIGURE],
        workers=workers,
        fixed={"method": "exact_free", "w_body[3]": 0.0},
        stop_time=60.0,
        step=0.01,
        build_dir=build_dir,
        progress=True,
    )

    def closed_form(ax: Any) -> None:
        x, y = np.meshgrid(np.linspace(i2[0], i2[-1], 200), np.geomspace(w1[0], w1[-1], 200))
        cs = ax.contour(x, y, racket_flip_time(x, y), levels=[5, 10, 20, 40], colors="w", linestyles="--")
        ax.clabel(cs, fmt="%g s", fontsize=8)
        ax.plot([], [], "w--", label="closed form K(m)/λ")
        ax.set_xlabel("I_principal[2] = I2 (kg·m²); I1 = 1, I3 = 3")
        ax.set_ylabel("w_body[1] = ω1 (rad/s): spin axis offset ≈ ω1/ω2 rad")

    write_table(df, tables / "tennis_racket.parquet")
    plot_map(
        df,
        RACKET_FIGURE,
        out / "tennis_racket.png",
        log_axes=["w_body[1]"],
        title="Tennis racket: time to the first flip (s), I = (1, I2, 3), ω0 = (ω1, 1, 0), exact_free",
        decorate=closed_form,
    )
    return df


def sleeping_threshold(l: np.ndarray, scene_name: str = "sleeping_top") -> np.ndarray:
    """ω3 (rad/s) at the sleeping threshold ω3² = 4 M g l I1 / I3² of the scene's body
    with its centre of mass at height l (m), I1 = I1,cm + M l² about the pivot."""
    sc = load_scene(scene_name)
    i1 = sc.inertia[0, 0] + sc.mass * l**2
    return np.sqrt(4.0 * sc.mass * abs(sc.g[2]) * l * i1) / sc.inertia[2, 2]


def sleeping_top(out: Path, tables: Path, workers: int | None, quick: bool, build_dir: str | Path) -> pd.DataFrame:
    """The tilt map of sleeping_top without friction: out/sleeping_top.png, tables/sleeping_top.parquet."""
    w3 = np.linspace(40.0, 200.0, 9 if quick else 33)
    l = np.linspace(0.01, 0.08, 8 if quick else 29)
    df = sweep(
        "sleeping_top",
        {"w_body[3]": w3, "r_cm[3]": l},
        [TOP_FIGURE],
        workers=workers,
        fixed={"c_friction": 0.0},
        stop_time=3.0,
        build_dir=build_dir,
        progress=True,
    )

    def threshold(ax: Any) -> None:
        ll = np.linspace(l[0], l[-1], 200)
        ax.plot(sleeping_threshold(ll), ll, "w--", lw=2, label="ω3² = 4 M g l I1 / I3²")
        ax.set_xlim(w3[0] - 2.5, w3[-1] + 2.5)
        ax.set_xlabel("w_body[3] = ω3 (rad/s)")
        ax.set_ylabel("r_cm[3] = l (m): pivot to centre of mass")

    write_table(df, tables / "sleeping_top.parquet")
    plot_map(
        df,
        TOP_FIGURE,
        out / "sleeping_top.png",
        log_color=True,
        title="Sleeping top: largest tilt θ (rad) in 3 s from θ0 = 1 mrad, no friction",
        decorate=threshold,
    )
    return df


def dual_spin_inertia(scene_name: str = "dual_spin") -> tuple[np.ndarray, float]:
    """(I_1, I_2, I_3) (kg·m², whole body, principal) and the wheel's axial inertia J (kg·m²)
    of a gyrostat scene with one wheel along body z (the map's spin axis)."""
    sc = load_scene(scene_name)
    (rotor,) = sc.rotors.values()
    if not np.allclose(rotor.axis, [0.0, 0.0, 1.0]):
        raise ValueError(f"{scene_name}: the map needs its one wheel along body z, not {rotor.axis}")
    return np.diag(sc.inertia).copy(), float(rotor.J)


def dual_spin_boundary(w3: np.ndarray, scene_name: str = "dual_spin") -> tuple[np.ndarray, np.ndarray]:
    """The two wheel speeds Ω (rad/s, relative to the body) where the spin ω3 (rad/s) about
    body z of the scene's gyrostat changes stability: h_w = J Ω = (I_t − I3) ω3 for t = 1, 2,
    the zeros of the factors of (I3 ω3 + h_w − I1 ω3)(I3 ω3 + h_w − I2 ω3) (docs/theory.md
    §8.3)."""
    inertia, j = dual_spin_inertia(scene_name)
    return (inertia[0] - inertia[2]) * w3 / j, (inertia[1] - inertia[2]) * w3 / j


def dual_spin_stable(omega: np.ndarray, w3: np.ndarray, scene_name: str = "dual_spin") -> np.ndarray:
    """True where the gyrostat condition (I3 ω3 + h_w − I1 ω3)(I3 ω3 + h_w − I2 ω3) > 0 holds
    for wheel speed Ω (rad/s, h_w = J Ω) and spin ω3 (rad/s) (docs/theory.md §8.3)."""
    b1, b2 = dual_spin_boundary(np.asarray(w3, dtype=float), scene_name)
    return np.asarray((np.asarray(omega) - b1) * (np.asarray(omega) - b2) > 0.0)


def dual_spin(out: Path, tables: Path, workers: int | None, quick: bool, build_dir: str | Path) -> pd.DataFrame:
    """The stability map of dual_spin: out/dual_spin.png, tables/dual_spin.parquet."""
    omega = np.linspace(-250.0, 250.0, 9 if quick else 41)
    w3 = np.linspace(0.1, 2.5, 6 if quick else 25)
    df = sweep(
        "dual_spin",
        {"Omega_wheel": omega, "w_body[3]": w3},
        [DUAL_SPIN_FIGURE],
        workers=workers,
        fixed={"w_body[1]": 0.01, "w_body[2]": 0.0, "u_wheel": 0.0},
        stop_time=60.0,
        step=0.05,
        build_dir=build_dir,
        progress=True,
    )
    (i1, i2, i3), j = dual_spin_inertia()

    def boundary(ax: Any) -> None:
        ww = np.linspace(w3[0], w3[-1], 200)
        b1, b2 = dual_spin_boundary(ww)
        ax.plot(b1, ww, "w--", lw=2, label="(I3 ω3 + h_w − I1 ω3)(I3 ω3 + h_w − I2 ω3) = 0")
        ax.plot(b2, ww, "w--", lw=2)
        # where the axial momentum I3 ω3 + h_w vanishes the perturbation's transverse momentum
        # is all of L, so even a stable spin's axis swings far from world z
        ax.plot(-i3 * ww / j, ww, "w:", lw=1, label="I3 ω3 + h_w = 0")
        ax.text(0.0, 0.8 * w3[-1], "unstable", color="w", ha="center")
        ax.set_xlim(omega[0] - 6.25, omega[-1] + 6.25)
        ax.set_xlabel(f"Omega_wheel = Ω (rad/s), h_w = J Ω, J = {j:g} kg·m²")
        ax.set_ylabel("w_body[3] = ω3 (rad/s): spin about body z")

    write_table(df, tables / "dual_spin.parquet")
    plot_map(
        df,
        DUAL_SPIN_FIGURE,
        out / "dual_spin.png",
        log_color=True,
        title=f"Dual spin: largest tilt θ (rad) in 60 s from ω1 = 0.01 rad/s, I = ({i1:g}, {i2:g}, {i3:g}) kg·m²",
        decorate=boundary,
    )
    return df


MAPS = {"tennis_racket": tennis_racket, "sleeping_top": sleeping_top, "dual_spin": dual_spin}


def main(argv: Sequence[str] | None = None) -> int:
    """Write the maps (PNGs to --out, tables to --tables): all of them, or those named by --map."""
    ap = argparse.ArgumentParser(prog="python -m fmu.sweep.examples", description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(OUT), help=f"output directory (default: {OUT})")
    ap.add_argument("--tables", default="out/sweeps", help="where the tables go (default: out/sweeps)")
    ap.add_argument("--workers", type=int, help="LocalCluster processes (default: one per core; 0: this process)")
    ap.add_argument("--quick", action="store_true", help="coarse grids (a smoke test)")
    ap.add_argument("--build-dir", default="build", help="where FMUs are built and cached (default: build)")
    ap.add_argument(
        "--map", action="append", choices=sorted(MAPS), help="draw only this map (repeatable; default: all)"
    )
    args = ap.parse_args(argv)
    out = Path(args.out)
    for name in args.map or MAPS:
        fn = MAPS[name]
        df = fn(out, Path(args.tables), args.workers, args.quick, args.build_dir)
        rate = len(df) / df.attrs["wall_s"]
        print(f"{name}: {len(df)} runs, {int((~df['ok']).sum())} failed, {rate:.1f} runs/s -> {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
