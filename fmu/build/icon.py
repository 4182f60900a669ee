"""The FMU's icon (FMI 3.0 terminalsAndIcons/icon.png, FMI 2.0 model.png), drawn from the scene's body.

The body is drawn as its equivalent uniform ellipsoid (the solid ellipsoid with the same
principal moments about the centre of mass: semi-axes a_i ∝ √(I_j + I_k − I_i),
docs/theory.md §3.3), turned to the start orientation q0 (body → world), with the start
angular velocity ω0 as an arrow and, with gravity, the pivot and the rod to the centre
of mass; a moving pivot stands on a shaker table with the arrow of its motion, each force
point carries the arrow of its force, the sensor is a green dot. Schematic: the
ellipsoid's largest semi-axis is drawn at unit length, the scene's points at that scale.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np

from modelsrc.quaternion import rotation_matrix
from modelsrc.scene import Scene

ICON_PIXELS = 256


def ellipsoid_axes(inertia: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(semi-axes scaled to a largest of 1, principal directions as columns, body frame)
    of the uniform ellipsoid with the inertia tensor `inertia` (kg·m², about the centre
    of mass): I_1 = m (b² + c²)/5, so a² ∝ I_2 + I_3 − I_1."""
    moments, axes = np.linalg.eigh(np.asarray(inertia, dtype=float))
    squares = np.maximum(moments.sum() - 2.0 * moments, 0.0)  # I_j + I_k - I_i
    semi = np.sqrt(squares)
    semi = semi / semi.max() if semi.max() > 0 else np.ones(3)
    return np.maximum(semi, 0.03), axes  # a flat plate (I3 = I1 + I2) is drawn thin, not invisible


def _direction(spec: object) -> np.ndarray | None:
    """Unit direction of an input's first nonzero value (a constant, a table's rows
    [t, x, y, z], or a harmonic's amplitude), or None when it is zero throughout."""
    values = np.atleast_2d(np.asarray(getattr(spec, "amplitude", spec), dtype=float))
    values = values[:, -3:]  # a table's rows without their time
    for v in values:
        if np.linalg.norm(v) > 0:
            return v / np.linalg.norm(v)
    return None


def body_scale(scene: Scene) -> float:
    """Icon units per metre: the equivalent ellipsoid's largest semi-axis (a_i² =
    5 (I_j + I_k − I_i) / (2 m), docs/theory.md §3.3) is drawn at unit length, and the
    scene's points (force points, the sensor) at the same scale."""
    moments = np.linalg.eigvalsh(np.asarray(scene.inertia, dtype=float))
    largest = np.sqrt(max(float(np.max(moments.sum() - 2.0 * moments)), 0.0) * 5.0 / (2.0 * scene.mass))
    return 1.0 / largest if largest > 0 else 1.0


def icon_features(scene: Scene) -> dict[str, tuple[np.ndarray, np.ndarray | None]]:
    """What the icon draws besides the body, in icon units (world frame, at the start
    orientation): name -> (where, arrow or None). "centre": the centre of mass; "pivot":
    the point a heavy or shaken body turns about (not in free flight); "shaker": the table
    under a moving pivot, with the arrow of its motion; "force <name>": each force point,
    with the arrow of its force's first nonzero value; "sensor": the sensor point;
    "omega": the start angular velocity's arrow from the centre (absent when ω0 = 0)."""
    R = np.array(ca.evalf(rotation_matrix(ca.SX(ca.DM(scene.q0)))))  # body -> world (docs/theory.md §1.1)
    scale = body_scale(scene)
    centre = np.zeros(3)
    if scene.has("gravity") and np.linalg.norm(scene.r_cm) > 0:
        centre = 1.3 * R @ (scene.r_cm / np.linalg.norm(scene.r_cm))  # schematic rod length
    drawn: dict[str, tuple[np.ndarray, np.ndarray | None]] = {"centre": (centre, None)}
    if (scene.has("gravity") and not scene.has("translation")) or scene.has("moving_pivot"):
        drawn["pivot"] = (np.zeros(3), None)
    if scene.has("moving_pivot"):
        motion = _direction(scene.inputs.get("a_pivot", np.zeros(3)))
        drawn["shaker"] = (np.array([0.0, 0.0, -0.35]), 0.6 * (motion if motion is not None else np.array([0, 0, 1.0])))
    for name, fp in scene.force_points.items():
        force = _direction(scene.inputs.get(f"f_{name}", np.zeros(3)))
        if force is not None and fp.frame == "body":
            force = R @ force
        at = centre + R @ (scale * np.asarray(fp.point, dtype=float))
        drawn[f"force {name}"] = (at, None if force is None else 0.9 * force)
    if "sensor" in scene.outputs:
        drawn["sensor"] = (centre + R @ (scale * np.asarray(scene.sensor_point, dtype=float)), None)
    w = R @ scene.w0
    if np.linalg.norm(w) > 0:
        drawn["omega"] = (centre, 1.6 * w / np.linalg.norm(w))
    return drawn


def write_icon(scene: Scene, path: Path) -> None:
    """Draw the scene's body and icon_features into the PNG file `path` (ICON_PIXELS
    square, transparent)."""
    # matplotlib is imported here, not with the module: its C++ extensions cannot load in
    # a process that preloads AddressSanitizer's runtime (tests/robustness/test_fuzz_fmi.py runs the
    # FMU that way and imports the build module, never drawing)
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    R = np.array(ca.evalf(rotation_matrix(ca.SX(ca.DM(scene.q0)))))  # body -> world (docs/theory.md §1.1)
    semi, axes = ellipsoid_axes(scene.inertia)
    u, v = np.meshgrid(np.linspace(0, 2 * np.pi, 40), np.linspace(0, np.pi, 20))
    sphere = np.stack([np.cos(u) * np.sin(v), np.sin(u) * np.sin(v), np.cos(v)])
    body_points = np.einsum("ij,j,jkl->ikl", axes, semi, sphere)
    drawn = icon_features(scene)
    centre = drawn["centre"][0]
    world = np.einsum("ij,jkl->ikl", R, body_points) + centre[:, None, None]
    fig = Figure(figsize=(2.56, 2.56), dpi=ICON_PIXELS / 2.56)
    FigureCanvasAgg(fig)
    # drawn in the order added: the table and the rod under the body, points and arrows over it
    # (a thruster inside the body's equivalent ellipsoid stays visible)
    ax: Any = fig.add_axes((0.0, 0.0, 1.0, 1.0), projection="3d", computed_zorder=False)  # an Axes3D
    extent = [world.reshape(3, -1), np.zeros((3, 1))]
    if "shaker" in drawn:  # a square table under the pivot, its motion as a double arrow
        base, arrow = drawn["shaker"]
        motion = arrow if arrow is not None else np.zeros(3)
        corners = np.array([[-0.6, -0.6], [0.6, -0.6], [0.6, 0.6], [-0.6, 0.6], [-0.6, -0.6]]).T
        ax.plot(corners[0], corners[1], np.full(5, base[2]), color="#555555", linewidth=3)
        ax.plot(*np.column_stack([base, np.zeros(3)]), color="#555555", linewidth=2)
        beside = base + np.array([0.9, 0.0, 0.0])  # the double arrow beside the table
        for sign in (1.0, -1.0):
            ax.quiver(*beside, *(sign * motion), color="#8e44ad", linewidth=2.5, arrow_length_ratio=0.35)
        table = np.vstack([corners, np.full((1, 5), base[2])])
        extent += [(beside - motion)[:, None], (beside + motion)[:, None], table]
    if "pivot" in drawn:
        ax.plot(*np.column_stack([np.zeros(3), centre]), color="#333333", linewidth=3)
        ax.scatter([0.0], [0.0], [0.0], color="#c0392b", s=40, depthshade=False)
    ax.plot_surface(*world, color="#4a7bb7", shade=True, linewidth=0, antialiased=True, alpha=0.95)
    for name, (at, arrow) in drawn.items():
        if name.startswith("force "):  # force points: a dot, and the force as an arrow onto it
            ax.scatter(*at[:, None], color="#c0392b", s=30, depthshade=False)
            if arrow is not None:
                ax.quiver(*(at - arrow), *arrow, color="#c0392b", linewidth=2.5, arrow_length_ratio=0.3)
                extent.append((at - arrow)[:, None])
            extent.append(at[:, None])
    if "sensor" in drawn:  # the sensor: a green dot on a thin line from the body's centre
        at = drawn["sensor"][0]
        ax.plot(*np.column_stack([centre, at]), color="#27ae60", linewidth=1.5)
        ax.scatter(*at[:, None], color="#27ae60", s=45, marker="D", depthshade=False)
        extent.append(at[:, None])
    tip = drawn.get("omega", (centre, None))[1]
    if tip is not None:
        ax.quiver(*centre, *tip, color="#e67e22", linewidth=2.5, arrow_length_ratio=0.25)
        extent.append((centre + tip)[:, None])
    # a cube around everything drawn, so that the body fills the icon at equal scales
    pts = np.hstack(extent)
    mid, half = (pts.max(axis=1) + pts.min(axis=1)) / 2, (pts.max(axis=1) - pts.min(axis=1)).max() / 2
    ax.set(xlim=(mid[0] - half, mid[0] + half), ylim=(mid[1] - half, mid[1] + half),
           zlim=(mid[2] - half, mid[2] + half))  # fmt: skip
    ax.set_box_aspect((1, 1, 1), zoom=1.5)
    ax.set_axis_off()
    fig.patch.set_alpha(0.0)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, transparent=True)
