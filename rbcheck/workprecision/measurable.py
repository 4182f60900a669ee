"""Which scenes the error-control part can measure: those with a scipy reference that turns.

Kept apart from rbcheck.workprecision.tolerance, which measures them, so that the report's
configuration (rbcheck.workprecision.config, Config.quick) chooses its scenes without
importing the part's machinery.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from modelsrc.scene import Scene, load_scene

from ..baselines.gyrostat import covers as gyrostat_covers


def measurable_scenes(names: Iterable[str]) -> tuple[str, ...]:
    """The scenes of `names` (shipped names or scene files) the part can measure: those that
    have a scipy reference (rbcheck.baselines.motion.integrate; rotors:
    rbcheck.baselines.gyrostat) and turn from their start (`has_scipy_reference`; the rotor
    scenes starting at rest are checked against the jointed Exudyn model by `rbfmu check`,
    not in this part)."""
    return tuple(name for name in names if has_scipy_reference(load_scene(name)))


def has_scipy_reference(sc: Scene) -> bool:
    """The scene has a scipy reference with an error scale: rbcheck.baselines.gyrostat.covers
    it, and a scene with rotors turns from its start, ω0 ≠ 0 (reaction_wheel_slew without its
    loop stays at rest: max |ω| = 0, no scale for the error, references.make_reference refuses
    it; quadrotor, which starts at rest, is left out of these parts with it: the batch part
    runs both in a variant, rbcheck.workprecision.report_scenes)."""
    return gyrostat_covers(sc) and (not sc.rotors or bool(np.any(sc.w0 != 0.0)))
