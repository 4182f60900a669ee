"""Scene-file rules of the moving reference point: free flight, forces at body points, the moving pivot.

Reads the parts of a scene file that concern the motion of the centre of mass (feature
``translation``, docs/theory.md §7.1) or of the pivot (``moving_pivot``, §7.3): which
features go together, the start position and velocity and the named force points of
``[forces.<name>]``. Called by ``modelsrc.scene.load_scene`` through the descriptor
(feature.py) with its reader, so every error names the file, the field and what is
allowed. `ForcePoint` is part of the scene's data (modelsrc.scene_data), so this module
imports nothing of the model.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ...scene_reader import SceneReader

# feature -> the features it needs (all of them) and those it excludes
NEEDS = {
    "force_body": ("translation",),
    "force_world": ("translation",),
    "moving_pivot": ("gravity",),
}
EXCLUDES = {
    "translation": ("moving_pivot", "prescribed_rate"),
}
FRAMES = ("body", "world")
# Names a force point may not take: its input f_<name> and parameter r_<name> would
# clash with other variables.
RESERVED_POINT_NAMES = frozenset({"body", "world", "pivot", "cm", "sensor"})


@dataclass(frozen=True)
class ForcePoint:
    """A named point of application of a force input: point (m, body frame, from the
    centre of mass) and frame ("body" or "world") of its input f_<name> (N)."""

    point: np.ndarray
    frame: str


def check_feature_rules(rd: SceneReader, features: frozenset[str]) -> None:
    """Refuse feature combinations without a meaning, naming the feature and why."""
    why = {
        "force_body": "f_body pushes the centre of mass, which moves only in free flight",
        "force_world": "f_world pushes the centre of mass, which moves only in free flight",
        "moving_pivot": "the pivot of a heavy top moves: it needs the top ([gravity] r_cm and g)",
    }
    for feat, needed in NEEDS.items():
        if feat in features:
            for n in needed:
                if n not in features:
                    raise rd.fail(f"features.{feat}", f"needs features.{n} = true ({why[feat]})")
    for feat, excluded in EXCLUDES.items():
        if feat in features:
            for x in excluded:
                if x in features:
                    raise rd.fail(
                        f"features.{feat}",
                        f"excludes features.{x}: a free body has no pivot, and its rate is not held "
                        "(use moving_pivot for a top whose pivot moves)",
                    )


def read_start(rd: SceneReader, features: frozenset[str], init: dict[str, Any]) -> dict[str, np.ndarray]:
    """Start position x0 (m) and velocity v0 (m/s), world frame, of the centre of mass
    (initial.x_cm, v_cm) or of the pivot (initial.x_pivot, v_pivot); zero when not given."""
    out: dict[str, np.ndarray] = {}
    for feat, (xk, vk) in (("translation", ("x_cm", "v_cm")), ("moving_pivot", ("x_pivot", "v_pivot"))):
        for key, target in ((xk, "x0"), (vk, "v0")):
            if key in init:
                if feat not in features:
                    raise rd.fail(f"initial.{key}", f"given but features.{feat} is not true")
                out[target] = rd.vector(f"initial.{key}", init[key], 3)
    return out


def read_force_points(rd: SceneReader, features: frozenset[str], reserved: frozenset[str]) -> dict[str, ForcePoint]:
    """[forces.<name>] tables: point (m, body frame, from the centre of mass) and frame
    ("body" or "world") of the force input f_<name> (N). Needs features.translation."""
    sec = rd.data.get("forces", {})
    if not isinstance(sec, dict):
        raise rd.fail("forces", f"must be tables [forces.<name>], got {sec!r}")
    if sec and "translation" not in features:
        raise rd.fail("forces", "force points push the centre of mass: they need features.translation = true")
    points: dict[str, ForcePoint] = {}
    for name, spec in sec.items():
        fld = f"forces.{name}"
        if not (name.isidentifier() and name.isascii()) or name in reserved:
            raise rd.fail(
                fld, f"the point name must be an identifier other than {', '.join(sorted(reserved))}, got {name!r}"
            )
        if not isinstance(spec, dict) or set(spec) != {"point", "frame"}:
            raise rd.fail(
                fld,
                "must be a table with point = [x, y, z] (m, body, from the centre of mass) and "
                f'frame = "body" or "world", got {spec!r}',
            )
        if spec["frame"] not in FRAMES:
            raise rd.fail(
                f"{fld}.frame", f'must be "body" or "world" (frame of the force input), got {spec["frame"]!r}'
            )
        points[name] = ForcePoint(rd.vector(f"{fld}.point", spec["point"], 3), spec["frame"])
    return points
