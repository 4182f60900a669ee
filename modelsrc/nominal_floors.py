"""The floors of the states' nominal magnitudes and their overflow check, shared by the body and its features.

`nominals.state_nominals` gathers the nominal of every state vector from the body and
the features (docs/theory.md §5.5); these are the pieces they share: W_FLOOR, the
body's size and the check that a magnitude is finite (the nominals are written into
modelDescription.xml and the C code, which hold finite numbers only).
"""

from __future__ import annotations

import math

import numpy as np

from .errors import ModelInputError
from .scene_data import SceneData

W_FLOOR = 1.0  # rad/s: slower bodies are measured against 1 rad/s, absolute


def body_size(scene: SceneData) -> float:
    """ℓ = sqrt(tr I_cm / m) (m): the body's radius of gyration, its natural length scale."""
    return float(np.sqrt(np.trace(scene.inertia) / scene.mass))


def checked_magnitude(scene: SceneData, what: str, value: float) -> float:
    """value, or a ModelInputError naming `what` when it or its square overflowed (the error
    control squares every nominal, modelsrc.model_functions: nominal² + |x0|²)."""
    if not (math.isfinite(value) and math.isfinite(value * value)):
        raise ModelInputError(
            f"scene file {scene.path}: {what} overflows double precision ({value}), so the FMU's state nominals "
            "(docs/theory.md §5.5) cannot be written: give start vectors whose components stay below 1e154 in "
            "magnitude (their squares must be finite) and a mass with tr I / m below 1e308"
        )
    return value
