"""What a run shows a user: final state, invariant drift, wall time; a plot."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .run import RunResult


def conserved(result: RunResult) -> dict[str, bool]:
    """Which invariants the scene's physics conserves (docs/theory.md §2.3, §4.2)."""
    sc = result.scene
    return {"energy": sc.conserves_energy, "L": sc.torque_free}


def summarize(result: RunResult) -> dict[str, float]:
    """Scalars of a run: final ω (rad/s, body), relative drifts of E and |L| (max over the
    run, NaN where the physics does not conserve them), max ||q| − 1|, wall time (s)."""
    cons = conserved(result)
    E = result.values.get("E_total", result.values.get("E_kin"))
    out = {"t_end": float(result.time[-1]), "steps": result.n_steps, "wall_s": result.wall_time}
    w = result.vector("w_body")[-1]
    out.update({f"w{k + 1}": float(w[k]) for k in range(3)})
    out["E_drift"] = float(np.max(np.abs(E - E[0])) / abs(E[0])) if cons["energy"] and E is not None else np.nan
    if cons["L"] and "L_world[1]" in result.values:
        L = result.vector("L_world")
        nL = np.linalg.norm(L, axis=1)
        out["L_drift"] = float(np.max(np.abs(nL - nL[0])) / nL[0])
    else:
        out["L_drift"] = np.nan
    out["qnorm_err"] = float(np.max(np.abs(np.linalg.norm(result.vector("q"), axis=1) - 1.0)))
    return out


def format_table(rows: list[tuple[str, dict[str, float]]]) -> str:
    """A fixed-width table of `summarize` rows, one per scene."""
    head = (
        f"{'scene':<20}{'t_end':>7}{'steps':>7}{'w1':>11}{'w2':>11}{'w3':>11}"
        f"{'E drift':>10}{'|L| drift':>10}{'max||q|-1|':>12}{'wall [s]':>10}"
    )
    lines = [head, "-" * len(head)]
    f = lambda v: "       n/a" if np.isnan(v) else f"{v:10.1e}"
    for name, s in rows:
        lines.append(
            f"{name:<20}{s['t_end']:7.2f}{s['steps']:7d}{s['w1']:11.5f}{s['w2']:11.5f}{s['w3']:11.5f}"
            f"{f(s['E_drift'])}{f(s['L_drift'])}{s['qnorm_err']:12.1e}{s['wall_s']:10.3f}"
        )
    return "\n".join(lines)


def write_csv(result: RunResult, path: str | Path) -> None:
    """All recorded outputs, one column each, with a header row."""
    names = list(result.values)
    data = np.column_stack([result.time] + [result.values[n] for n in names])
    np.savetxt(path, data, delimiter=",", header=",".join(["time", *names]), comments="", fmt="%.17g")


def plot_run(result: RunResult, path: str | Path) -> None:
    """Three panels: ω (body), z-x-z Euler angles, invariant drift (log scale)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = result.time
    fig, ax = plt.subplots(3, 1, figsize=(8, 9), sharex=True)
    w = result.vector("w_body")
    for k in range(3):
        ax[0].plot(t, w[:, k], label=f"ω{k + 1}")
    ax[0].set_ylabel("ω body [rad/s]")
    ax[0].legend(loc="upper right")
    if "euler_zxz[1]" in result.values:
        e = result.vector("euler_zxz").copy()
        e[:, 0], e[:, 2] = np.unwrap(e[:, 0]), np.unwrap(e[:, 2])
        for k, lab in enumerate(("φ", "θ", "ψ")):
            ax[1].plot(t, e[:, k], label=lab)
        ax[1].legend(loc="upper right")
    ax[1].set_ylabel("Euler z-x-z [rad] (φ, ψ unwrapped)")
    cons = conserved(result)
    E = result.values.get("E_total", result.values.get("E_kin"))
    tiny = 1e-18
    runmax = np.maximum.accumulate  # drift so far: readable where raw round-off flickers
    if E is not None and cons["energy"]:
        ax[2].semilogy(t, runmax(np.abs(E - E[0]) / abs(E[0])) + tiny, label="max |E−E0|/E0")
    elif E is not None:  # driven or damped: show the energy itself on a linear axis
        ax_e = ax[2].twinx()
        ax_e.plot(t, E, "k--", label="E (not conserved)")
        ax_e.set_ylabel("E [J]")
        ax_e.legend(loc="lower right")
    if cons["L"] and "L_world[1]" in result.values:
        nL = np.linalg.norm(result.vector("L_world"), axis=1)
        ax[2].semilogy(t, runmax(np.abs(nL - nL[0]) / nL[0]) + tiny, label="max ||L|−|L0||/|L0|")
    ax[2].semilogy(t, runmax(np.abs(np.linalg.norm(result.vector("q"), axis=1) - 1)) + tiny, label="max ||q|−1|")
    ax[2].set_ylabel("invariants")
    ax[2].set_xlabel("t [s]")
    ax[2].legend(loc="upper right")
    fig.suptitle(f"{result.scene.name}: {result.n_steps} steps of {result.scene.step:g} s")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
