"""A system run's results: a CSV of every connector at every communication point, a plot of the driving signals."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from .masters import SystemResult

MAX_PANELS = 8


def write_result_csv(result: SystemResult, path: str | Path) -> None:
    """time (s) and one column per 'component.variable' (SI units of the FMUs), header row."""
    names = list(result.values)
    data = np.column_stack([result.t] + [result.values[n] for n in names])
    np.savetxt(path, data, delimiter=",", header=",".join(["time", *names]), comments="", fmt="%.17g")


def _groups(names: list[str]) -> dict[str, list[str]]:
    """'component.base' -> its elements ('plant.q' -> plant.q[1..4]; 'pd.u_x' -> pd.u_x..u_z;
    'ctl.Omega_cmd_p*' -> ctl.Omega_cmd_p1..p4, a set numbered in its name)."""
    groups: dict[str, list[str]] = {}
    for n in names:
        key = re.sub(r"\[\d+\]$", "", n)
        key = re.sub(r"_[xyz]$", "", key)
        key = re.sub(r"(?<=[A-Za-z_])\d+$", "*", key)
        groups.setdefault(key, []).append(n)
    return groups


def group_label(result: SystemResult, title: str, names: list[str]) -> str:
    """A panel's axis label: the group's name and its unit ('plant.w_body [rad/s]'), the unit
    from the SSD where every member has the same one, else none (q, a dimensionless group)."""
    units = {result.units.get(n, "") for n in names}
    unit = units.pop() if len(units) == 1 else ""
    return f"{title} [{unit}]" if unit else title


def plot_result(result: SystemResult, path: str | Path, signals: list[str] | None = None) -> None:
    """One panel per signal group (a vector, or a wheel triple u_x, u_y, u_z) of `signals`
    (default: every variable), at most MAX_PANELS; written to `path` (format from the suffix)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    groups = list(_groups(signals or list(result.values)).items())[:MAX_PANELS]
    height = 1.9 * len(groups) + 0.6  # inches
    fig, axes = plt.subplots(len(groups), 1, figsize=(8, height), sharex=True, squeeze=False)
    for ax, (title, names) in zip(axes[:, 0], groups):
        for n in names:
            ax.plot(result.t, result.values[n], label=n.split(".", 1)[1])
        ax.set_ylabel(group_label(result, title, names), fontsize=8)
        ax.legend(fontsize=7, loc="upper right", ncol=min(4, len(names)))
        ax.grid(alpha=0.3)
    axes[-1, 0].set_xlabel("t (s)")
    fig.suptitle(f"{Path(path).stem}: run in {result.master}", fontsize=10)
    fig.tight_layout(rect=(0.0, 0.0, 1.0, 1.0 - 0.35 / height))  # 0.35 in above the panels for the title
    fig.savefig(path, dpi=90)
    plt.close(fig)
