"""What a run shows a user: final state, invariant drift, the path of a moving body, wall time; a plot."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from modelsrc.scene import WORKING_FEATURES

from .feature_views import Panel, feature_figures, views
from .run import RunResult

if TYPE_CHECKING:  # matplotlib is imported where a figure is drawn
    from matplotlib.figure import Figure

__all__ = ["Panel", "body_axis_world", "conserved", "draw_run", "format_table", "plot_run", "plot_series", "summarize"]
__all__ += ["steps_text", "translation_summary", "write_csv"]


def conserved(result: RunResult) -> dict[str, bool]:
    """Which invariants the scene's physics conserves (docs/theory.md §2.3, §4.2): energy
    (E_total or E_kin), |L|, and in an orbit the Jacobi integral E_jacobi, conserved when
    nothing but the gravity gradient works on the body (docs/theory.md §9.3); in a central
    field (§9.7) |L| is the total angular momentum L_total (orbit + spin), conserved when
    the energy is (no inputs work on the body)."""
    sc = result.scene
    jacobi = (
        sc.has("orbit")
        and "E_jacobi" in result.values
        and not (sc.features & (WORKING_FEATURES - {"gravity_gradient"}))
        and not sc.force_points
    )
    central = sc.has("central_gravity") and sc.conserves_energy and not sc.input_names
    return {"energy": sc.conserves_energy, "L": sc.torque_free or central, "jacobi": jacobi}


def _L(result: RunResult) -> np.ndarray | None:
    """The conserved angular momentum's samples (n, 3): L_total in a central field (§9.7),
    else L_world; None when the run has not output it."""
    for name in ("L_total", "L_world"):
        if f"{name}[1]" in result.values:
            return result.vector(name)
    return None


def steps_text(t: np.ndarray) -> str:
    """The communication steps of a run at the times t (s), as taken (a run's step may be set
    apart from the scene's; the last step ends at the stop time, an input table's switch
    adds a point): "N steps of H s", with the shorter ones named."""
    d = np.diff(np.asarray(t, dtype=float))
    if d.size == 0:
        return "no steps"
    H = float(np.max(d))
    short = d < H * (1.0 - 1e-9)
    text = f"{d.size} steps of {H:.6g} s"
    if not np.any(short):
        return text
    if np.count_nonzero(short) == 1 and short[-1]:
        return f"{text} (the last {d[-1]:.6g} s)"
    return f"{text} ({np.count_nonzero(short)} shorter, down to {float(np.min(d)):.3g} s)"


def _drift(x: np.ndarray) -> float:
    """max |x − x(0)| / |x(0)|; NaN (n/a) for a quantity that starts at 0 (a body at rest, a
    reaction-wheel slew's total momentum): it has no scale to be relative to."""
    return float(np.max(np.abs(x - x[0])) / abs(x[0])) if x[0] != 0.0 else np.nan


def _drift_so_far(x: np.ndarray) -> np.ndarray | None:
    """max over [0, t] of |x − x(0)| / |x(0)| at every sample; None for a quantity that
    starts at 0 (as _drift: no scale to be relative to, nothing to plot)."""
    return np.maximum.accumulate(np.abs(x - x[0]) / abs(x[0])) if x[0] != 0.0 else None


def summarize(result: RunResult) -> dict[str, float]:
    """Scalars of a run: final ω (rad/s, body), relative drifts of E (E_jacobi in an orbit)
    and |L| (max over the run, NaN where the physics does not conserve them), max ||q| − 1|,
    wall time (s); for a scene whose centre of mass or pivot moves also `translation_summary`'s entries."""
    cons = conserved(result)
    E = result.values.get("E_total", result.values.get("E_kin"))
    out = {"t_end": float(result.time[-1]), "steps": result.n_steps, "wall_s": result.wall_time}
    w = result.vector("w_body")[-1]
    out.update({f"w{k + 1}": float(w[k]) for k in range(3)})
    if cons["jacobi"] and not cons["energy"]:  # in an orbit: the Jacobi integral (§9.3)
        E = result.values["E_jacobi"]
    out["E_drift"] = _drift(E) if (cons["energy"] or cons["jacobi"]) and E is not None else np.nan
    L = _L(result)
    if cons["L"] and L is not None:
        out["L_drift"] = _drift(np.linalg.norm(L, axis=1))
        if np.isnan(out["L_drift"]):  # L(0) = 0 (a slew from rest): no relative drift, the absolute one
            out["max |L| over the run (L(0) = 0) [N m s]"] = float(np.max(np.linalg.norm(L, axis=1)))
    else:
        out["L_drift"] = np.nan
    out["qnorm_err"] = float(np.max(np.abs(np.linalg.norm(result.vector("q"), axis=1) - 1.0)))
    if result.scene.moves and "x_cm[1]" in result.values:
        out.update(translation_summary(result))
    out.update(feature_figures(result))  # each feature's own (fmu.drive.feature_views), label with unit
    return out


def translation_summary(result: RunResult) -> dict[str, float]:
    """Final x_cm (m) and v_cm (m/s), world frame; the impulse received p(T) − p(0) (N·s,
    its norm); and the momentum balance max_t |p(t) − p(0) − ∫₀ᵗ M a_cm dt| (N·s), NaN
    unless it can be evaluated exactly from the recorded outputs.

    M a_cm = ΣF (docs/theory.md §7.1), so the balance is the integral of the recorded a_cm.
    The trapezoid rule over the communication points is exact only when every force is
    constant in time: gravity alone. Inputs held over a step, forces that turn with the
    body or a pivot's force vary inside a step, and the recorded a_cm is the left limit at
    an input switch, so for such scenes the quadrature, not the FMU, would set the figure:
    NaN there rather than a number that measures the quadrature."""
    x, v = result.vector("x_cm"), result.vector("v_cm")
    out = {f"x_cm{k + 1}": float(x[-1, k]) for k in range(3)}
    out.update({f"v_cm{k + 1}": float(v[-1, k]) for k in range(3)})
    out["impulse"] = out["p_balance"] = np.nan
    if "p[1]" in result.values:
        p = result.vector("p")
        out["impulse"] = float(np.linalg.norm(p[-1] - p[0]))
        sc = result.scene  # a central field varies along the path: no exact quadrature (§9.7)
        constant_forces = not sc.inputs and not sc.has("moving_pivot") and not sc.has("central_gravity")
        if constant_forces and "a_cm[1]" in result.values:
            vv = float(np.sum(v * v))
            mass = float(np.sum(p * v)) / vv if vv > 0 else result.scene.mass  # p = M v_cm, M as run
            a, t = result.vector("a_cm"), result.time
            steps = 0.5 * (a[1:] + a[:-1]) * np.diff(t)[:, None]
            impulse = mass * np.vstack([np.zeros(3), np.cumsum(steps, axis=0)])
            out["p_balance"] = float(np.max(np.linalg.norm(p - p[0] - impulse, axis=1)))
    return out


def _columns(head: list[str], rows: list[list[str]], left: int = 1) -> list[str]:
    """Lines of a table whose columns are as wide as their widest cell and two spaces apart,
    so that no two cells run together whatever their length; the first `left` columns
    left-aligned, the others right-aligned; a rule under the head."""
    widths = [max(len(c) for c in col) for col in zip(head, *rows)]

    def line(cells: list[str]) -> str:
        return "  ".join(c.ljust(w) if k < left else c.rjust(w) for k, (c, w) in enumerate(zip(cells, widths)))

    lines = [line(head)]
    return [*lines, "-" * len(lines[0]), *(line(r).rstrip() for r in rows)]


def _g(v: float, fmt: str) -> str:
    """A number in `fmt`, "n/a" for NaN."""
    return "n/a" if np.isnan(v) else format(v, fmt)


def _figure(label: str, value: float) -> str:
    """'name [unit]', v -> 'name = v unit' (6 significant digits)."""
    name, _, unit = label.partition(" [")
    return f"{name} = {value + 0.0:.6g} {unit.rstrip(']')}".rstrip()  # + 0.0: an exact 0 prints as 0, not -0


def format_table(rows: list[tuple[str, dict[str, float]]]) -> str:
    """A table of `summarize` rows, one per scene; below it a table of the rows whose centre
    of mass or pivot moves (`translation_summary`) and, per scene, its features' figures
    (fmu.drive.feature_views). Columns are as wide as their widest cell, two spaces apart."""
    head = ["scene", "t_end", "steps", "w1", "w2", "w3", "E drift", "|L| drift", "max||q|-1|", "wall [s]"]
    body = [
        [name, f"{s['t_end']:.2f}", f"{s['steps']:d}", *(f"{s[f'w{k}']:.5f}" for k in (1, 2, 3)),
         _g(s["E_drift"], ".1e"), _g(s["L_drift"], ".1e"), f"{s['qnorm_err']:.1e}", f"{s['wall_s']:.3f}"]
        for name, s in rows
    ]  # fmt: skip
    lines = _columns(head, body)
    moving = [(name, s) for name, s in rows if "x_cm1" in s]
    if moving:
        head = ["scene", *(f"x_cm(T) {c} [m]" for c in "xyz"), *(f"v_cm(T) {c} [m/s]" for c in "xyz")]
        head += ["|p(T)-p(0)|", "p balance"]
        body = [
            [name, *(f"{s[f'{b}{k}']:.4g}" for b in ("x_cm", "v_cm") for k in (1, 2, 3)),
             _g(s["impulse"], ".1e"), _g(s["p_balance"], ".1e")]
            for name, s in moving
        ]  # fmt: skip
        lines += ["", *_columns(head, body)]
    base = {"t_end", "steps", "wall_s", "w1", "w2", "w3", "E_drift", "L_drift", "qnorm_err", "impulse", "p_balance"}
    featured = [(name, {k: v for k, v in s.items() if "[" in k and k not in base}) for name, s in rows]
    featured = [(name, f) for name, f in featured if f]
    if featured:
        lines += ["", "at the end of the run, per feature:"]
        lines += [f"  {name}: " + ", ".join(_figure(k, v) for k, v in f.items()) for name, f in featured]
    return "\n".join(lines)


def write_csv(result: RunResult, path: str | Path) -> None:
    """All recorded outputs, then the inputs as driven (`RunResult.inputs`), one column each,
    with a header row."""
    names = list(result.values)
    inputs = [n for n in result.inputs if n not in result.values]
    data = np.column_stack([result.time] + [result.values[n] for n in names] + [result.inputs[n] for n in inputs])
    np.savetxt(path, data, delimiter=",", header=",".join(["time", *names, *inputs]), comments="", fmt="%.17g")


def body_axis_world(q: np.ndarray) -> np.ndarray:
    """The body z axis (the figure axis of the tops) in the world frame, (n, 3): the third
    column of R(q) (docs/theory.md §1.1), q scalar first, normalised here."""
    w, x, y, z = (q / np.linalg.norm(q, axis=1, keepdims=True)).T
    return np.column_stack([2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)])


def plot_series(result: RunResult) -> dict[str, Panel]:
    """The panels of `plot_run`, in order, as data.

    rates: ω (rad/s, body). orientation: the body z axis in the world frame (its x, y, z
    components) and its tilt θ = atan2(√(a_x² + a_y²), a_z) from the world z axis (rad):
    continuous through the vertical, where the z-x-z angles φ, ψ are undefined and jump by
    π (docs/theory.md §1.3). path and pivot (a centre of mass or a pivot that moves):
    x_cm and x_pivot (m, world). Then each feature's panels (fmu.drive.feature_views: rotor
    speeds and momenta, height and heading of a multirotor, roll, pitch, yaw and ω relative to
    LVLH in an orbit, which replace rates and orientation, the inputs as driven). invariants
    (log): the running maximum of the relative drift of each quantity the scene conserves (E,
    |L|, E_jacobi in an orbit) and of ||q| − 1|; an exact 0 has no place on a log axis: it is
    left out (a drift that stays exactly 0 is named in the panel's note). energy: E (J) where
    the scene does not conserve it (forcing, friction): a quantity that changes, on its own axis.
    """
    panels = {"rates": Panel("ω body [rad/s]", {f"ω{k + 1}": result.vector("w_body")[:, k] for k in range(3)})}
    axis = body_axis_world(result.vector("q"))
    theta = np.arctan2(np.hypot(axis[:, 0], axis[:, 1]), axis[:, 2])
    orientation = {f"body z axis, world {c}": axis[:, k] for k, c in enumerate("xyz")}
    orientation["θ = tilt of body z from world z [rad]"] = theta
    panels["orientation"] = Panel("body z axis (world) / θ [rad]", orientation)
    if result.scene.moves:  # the pivot on its own axis: a shaker's 0.5 mm beside a 4 cm lever
        for key, base, what in (("path", "x_cm", "centre of mass"), ("pivot", "x_pivot", "pivot")):
            if f"{base}[1]" in result.values:
                xyz = result.vector(base)
                panels[key] = Panel(f"{what} (world) [m]", {f"{base} {c}": xyz[:, k] for k, c in enumerate("xyz")})
    for view in views(result.scene):
        own = view.panels(result)
        if own:  # a view replaces the generic panels only where it has its own to show
            for key in view.replaces:
                panels.pop(key, None)
            panels.update(own)
    cons = conserved(result)
    E = result.values.get("E_total", result.values.get("E_kin"))
    # drift so far (running maximum): readable where raw round-off flickers
    drifts = {}
    if E is not None and cons["energy"]:
        drifts["max |E−E0|/|E0|"] = _drift_so_far(E)
    L = _L(result)
    if cons["L"] and L is not None:  # named L_total where it is that (a central field, §9.7)
        label = "max ||L_total|−|L_total0||/|L_total0|" if "L_total[1]" in result.values else "max ||L|−|L0||/|L0|"
        drifts[label] = _drift_so_far(np.linalg.norm(L, axis=1))
    if cons["jacobi"]:  # in an orbit: the energy relative to the orbit frame (§9.3)
        drifts["max |E_J−E_J0|/|E_J0|"] = _drift_so_far(result.values["E_jacobi"])
    q_norm = np.linalg.norm(result.vector("q"), axis=1)
    drifts["max ||q|−1|"] = np.maximum.accumulate(np.abs(q_norm - 1))
    inv, zero = {}, []
    for name, d in drifts.items():
        if d is None:
            continue
        if not np.any(d > 0):
            zero.append(name)
        else:
            inv[name] = np.where(d > 0, d, np.nan)  # 0 (at the start, at least) is not drawn on a log axis
    note = f"exactly 0 over the run, not drawn: {', '.join(zero)}" if zero else ""
    panels["invariants"] = Panel("invariants (drift so far)", inv, log=True, note=note)
    if E is not None and not cons["energy"]:
        name = "E_total" if "E_total" in result.values else "E_kin"
        # in an orbit the field works on the body: E_jacobi is what stays (invariants panel)
        note = "not conserved; E_jacobi is" if cons["jacobi"] else "not conserved"
        panels["energy"] = Panel(f"E [J] ({note})", {name: E})
    return panels


def draw_run(result: RunResult) -> Figure:
    """The panels of `plot_series`, one above the other, sharing the time axis; linear axes
    without an offset (the values as they are, not "1e-6 + 2.00002e3"), each panel's note
    above it. A matplotlib Figure on the Agg backend (the caller closes it)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import ScalarFormatter

    panels = plot_series(result)
    t = result.time
    height = 2.4 * len(panels) + 1  # inches
    fig, axes = plt.subplots(len(panels), 1, figsize=(10, height), sharex=True, squeeze=False)
    for ax, panel in zip(axes[:, 0], panels.values()):
        for label, y in panel.series.items():
            style = {"color": "k", "ls": "--"} if label.startswith("θ") else {}
            (ax.semilogy if panel.log else ax.plot)(t, y, label=label, **style)
        if not panel.log:
            ax.yaxis.set_major_formatter(ScalarFormatter(useOffset=False))
        ax.set_ylabel(panel.ylabel)
        if panel.note:
            ax.set_title(panel.note, fontsize="small", loc="left")
        if panel.series:
            ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize="small")  # beside, not over, the curves
    axes[-1, 0].xaxis.set_major_formatter(ScalarFormatter(useOffset=False))
    axes[-1, 0].set_xlabel("t [s]")
    fig.suptitle(f"{result.scene.name}: {steps_text(result.time)}")
    fig.tight_layout(rect=(0.0, 0.0, 1.0, 1.0 - 0.45 / height))  # 0.45 in above the panels for the title
    return fig


def plot_run(result: RunResult, path: str | Path) -> None:
    """`draw_run`'s figure written to `path` (its format from the suffix)."""
    import matplotlib.pyplot as plt

    fig = draw_run(result)
    fig.savefig(path, dpi=90)
    plt.close(fig)
