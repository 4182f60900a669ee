"""The FMU's icon (FMI 3.0 terminalsAndIcons/icon.png, FMI 2.0 model.png), drawn from the scene's body.

The body is drawn as its equivalent uniform ellipsoid (the solid ellipsoid with the same
principal moments about the centre of mass: semi-axes a_i ∝ √(I_j + I_k − I_i),
docs/theory.md §3.3), turned to the start orientation q0 (body → world), with the start
angular velocity ω0 as an arrow and, with gravity, the pivot and the rod to the centre
of mass. Schematic: the ellipsoid's largest semi-axis is drawn at unit length.
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


def write_icon(scene: Scene, path: Path) -> None:
    """Draw the scene's body into the PNG file `path` (ICON_PIXELS square, transparent)."""
    # matplotlib is imported here, not with the module: its C++ extensions cannot load in
    # a process that preloads AddressSanitizer's runtime (tests/test_fuzz_fmi.py runs the
    # FMU that way and imports the build module, never drawing)
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    R = np.array(ca.evalf(rotation_matrix(ca.SX(ca.DM(scene.q0)))))  # body -> world (docs/theory.md §1.1)
    semi, axes = ellipsoid_axes(scene.inertia)
    u, v = np.meshgrid(np.linspace(0, 2 * np.pi, 40), np.linspace(0, np.pi, 20))
    sphere = np.stack([np.cos(u) * np.sin(v), np.sin(u) * np.sin(v), np.cos(v)])
    body_points = np.einsum("ij,j,jkl->ikl", axes, semi, sphere)
    centre = np.zeros(3)
    if scene.has("gravity") and np.linalg.norm(scene.r_cm) > 0:
        centre = 1.3 * R @ (scene.r_cm / np.linalg.norm(scene.r_cm))  # schematic rod length
    world = np.einsum("ij,jkl->ikl", R, body_points) + centre[:, None, None]
    fig = Figure(figsize=(2.56, 2.56), dpi=ICON_PIXELS / 2.56)
    FigureCanvasAgg(fig)
    ax: Any = fig.add_axes((0.0, 0.0, 1.0, 1.0), projection="3d")  # an Axes3D
    ax.plot_surface(*world, color="#4a7bb7", shade=True, linewidth=0, antialiased=True, alpha=0.95)
    if scene.has("gravity"):
        ax.plot(*np.column_stack([np.zeros(3), centre]), color="#333333", linewidth=3)
        ax.scatter([0.0], [0.0], [0.0], color="#c0392b", s=40, depthshade=False)
    extent = [world.reshape(3, -1), np.zeros((3, 1))]
    w = R @ scene.w0
    if np.linalg.norm(w) > 0:
        tip = 1.6 * w / np.linalg.norm(w)
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
