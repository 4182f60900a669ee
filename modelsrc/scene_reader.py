"""Reads a parsed scene file's tables and numbers, with errors that name the file, the field and what is allowed.

`scene.load_scene` makes one `SceneReader` per file and hands it to the readers of the
scene's parts (`scene_body`, the features' readers), so every error message has the same form:
"scene file <path>: field '<field>': <what is wrong>".
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Set
from pathlib import Path
from typing import Any

import numpy as np

from .errors import ModelInputError

# One rule for a unit vector or quaternion in a scene file (a rotor axis, initial.q): within
# this of unit length (relative) it is normalised silently, as printed decimals round it;
# farther off it is refused, so that a typo is not silently turned into another value.
UNIT_LENGTH_TOL = 1e-6
# The parameter ranges of docs/user_guide.md §2.3 (their reasons: modelsrc.model,
# add_parameter_ranges): |p| <= PARAM_MAX, a positive one (mass, inertia, a rotor's J) >= POSITIVE_MIN.
PARAM_MAX = 1e100
POSITIVE_MIN = 1e-100


class SceneReader:
    """Typed access to the parsed TOML with errors that name file and field.

    section_keys: for each table the scene format knows, the keys it allows."""

    def __init__(self, path: Path, data: dict[str, Any], section_keys: Mapping[str, Set[str]]):
        self.path, self.data, self.section_keys = path, data, section_keys

    def fail(self, fld: str, msg: str) -> ModelInputError:
        """The error for field `fld` (dotted path, e.g. 'body.mass')."""
        return ModelInputError(f"scene file {self.path}: field '{fld}': {msg}")

    def section(self, name: str, extra_keys: frozenset[str] = frozenset()) -> dict[str, Any]:
        """Table [name] (empty when absent); refuses keys not in section_keys[name] | extra_keys."""
        sec = self.data.get(name, {})
        if not isinstance(sec, dict):
            raise self.fail(name, f"must be a table [{name}], got {sec!r}")
        allowed = self.section_keys[name] | extra_keys
        unknown = set(sec) - allowed
        if unknown:
            raise self.fail(
                f"{name}.{sorted(unknown)[0]}",
                f"unknown key; allowed keys of [{name}]: {', '.join(sorted(allowed))}",
            )
        return sec

    def feature_section(self, feature: str, features: Set[str], excluded: Mapping[str, str]) -> dict[str, Any] | None:
        """Table [feature] of a feature with its own table (orbit, central_gravity): None when
        features.<feature> is not true (refusing the table given without it), else the table
        (empty when absent), after refusing each feature in `excluded` (feature -> why)."""
        sec = self.section(feature)
        if feature not in features:
            if sec:
                raise self.fail(feature, f"given but features.{feature} is not true")
            return None
        for feat, why in excluded.items():
            if feat in features:
                raise self.fail(f"features.{feature}", f"excludes features.{feat}: {why}")
        return sec

    def number(self, fld: str, value: Any, positive: bool = False, nonneg: bool = False) -> float:
        """value as a finite float (a TOML integer or float, not a boolean), > 0 if positive, >= 0 if nonneg."""
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise self.fail(fld, f"must be a number, got {value!r}")
        v = float(value)
        if not math.isfinite(v):
            raise self.fail(fld, f"must be finite, got {v}")
        if positive and not v > 0:
            raise self.fail(fld, f"must be > 0, got {v}")
        if nonneg and not v >= 0:
            raise self.fail(fld, f"must be >= 0, got {v}")
        return v

    def parameter(self, fld: str, value: Any, positive: bool = False, nonneg: bool = False) -> float:
        """`number`, in the parameter ranges of docs/user_guide.md §2.3: |value| <= PARAM_MAX,
        and >= POSITIVE_MIN when positive (a constant baked into the equations, such as a
        propeller's k_f, is held to the range of the parameters it multiplies)."""
        v = self.number(fld, value, nonneg=nonneg)
        if positive and not POSITIVE_MIN <= v <= PARAM_MAX:
            raise self.fail(fld, f"must be in [{POSITIVE_MIN:g}, {PARAM_MAX:g}] (docs/user_guide.md §2.3), got {v!r}")
        if not abs(v) <= PARAM_MAX:
            raise self.fail(fld, f"|value| must be <= {PARAM_MAX:g} (docs/user_guide.md §2.3), got {v!r}")
        return v

    def vector(self, fld: str, value: Any, n: int) -> np.ndarray:
        """A list of n numbers as an array (each checked by `number`)."""
        if not isinstance(value, list) or len(value) != n:
            raise self.fail(fld, f"must be a list of {n} numbers, got {value!r}")
        return np.array([self.number(f"{fld}[{i + 1}]", v) for i, v in enumerate(value)])
