"""Alias until 0.5.0 (CHANGELOG.md): the code lives in fmu/build/icon.py."""

from fmu.build.icon import (
    ICON_PIXELS,
    body_scale,
    ellipsoid_axes,
    icon_features,
    write_icon,
)

__all__ = [
    "ICON_PIXELS",
    "body_scale",
    "ellipsoid_axes",
    "icon_features",
    "write_icon",
]
