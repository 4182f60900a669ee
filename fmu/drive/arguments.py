"""Checks of the Python API's arguments (run_fmu, simulate, build_fmu): a bad one is a ModelInputError naming it.

Each check returns the argument in the form the function uses, or raises
modelsrc.errors.ModelInputError naming the argument, the value given and what is accepted
(docs/user_guide.md §4.1 lists every argument), never a raw TypeError or AttributeError from
deep inside the call.
"""

from __future__ import annotations

import os
import zipfile
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from modelsrc.errors import ModelInputError
from modelsrc.scene import Scene, load_scene


def _given(value: object) -> str:
    """The value as an error message shows it: its type and a short repr."""
    text = repr(value)
    return f"{type(value).__name__} {text[:60] + '...' if len(text) > 60 else text}"


def path_arg(value: object, name: str) -> Path:
    """A file system path (str or os.PathLike), else ModelInputError naming `name`."""
    if isinstance(value, bool) or not isinstance(value, (str, os.PathLike)):
        raise ModelInputError(f"{name} must be a path (str or pathlib.Path), got {_given(value)}")
    return Path(value)


def fmu_arg(value: object, name: str = "fmu_path") -> Path:
    """The path of an existing FMU archive (a zip file), else ModelInputError."""
    path = path_arg(value, name)
    if not path.is_file():
        raise ModelInputError(f"{name} {path}: no such file; give the path of an .fmu archive (rbfmu build)")
    if not zipfile.is_zipfile(path):
        raise ModelInputError(f"{name} {path}: not an FMU archive (not a zip file)")
    return path


def scene_arg(value: object, name: str = "scene") -> Scene:
    """A Scene, or a shipped scene's name or a .toml scene file (loaded), else ModelInputError."""
    if isinstance(value, Scene):
        return value
    if isinstance(value, (str, os.PathLike)) and not isinstance(value, bool):
        return load_scene(Path(value))
    raise ModelInputError(
        f"{name} must be a Scene (modelsrc.scene.load_scene), a shipped scene's name or a .toml scene file, "
        f"got {_given(value)}"
    )


def names_arg(value: object, name: str) -> list[str] | None:
    """None, or a list or tuple of variable names (str); a single str is refused (it would be
    read letter by letter)."""
    if value is None:
        return None
    if isinstance(value, (str, bytes)) or not isinstance(value, Sequence):
        raise ModelInputError(f"{name} must be a list of variable names (e.g. ['q[1]', 'E_kin']), got {_given(value)}")
    bad = [n for n in value if not isinstance(n, str)]
    if bad:
        raise ModelInputError(f"{name}: variable names are strings, got {_given(bad[0])}")
    return list(value)


def callable_arg(value: object, name: str) -> Callable[..., Any] | None:
    """None or a callable, else ModelInputError."""
    if value is not None and not callable(value):
        raise ModelInputError(
            f"{name} must be a function (t, outputs) -> {{input name: value}} or None, got {_given(value)}"
        )
    return value


def bool_arg(value: object, name: str) -> bool:
    """True or False (numpy's bool too), else ModelInputError."""
    if type(value).__name__ not in ("bool", "bool_"):
        raise ModelInputError(f"{name} must be True or False, got {_given(value)}")
    return bool(value)


def flags_arg(value: object, name: str) -> list[str]:
    """None (no flags) or a list of compiler flags (str), else ModelInputError."""
    if value is None:
        return []
    if isinstance(value, (str, bytes)) or not isinstance(value, Sequence) or not all(isinstance(f, str) for f in value):
        raise ModelInputError(
            f"{name} must be a list of compiler flags (e.g. ['-fsanitize=address']), got {_given(value)}"
        )
    return list(value)


def platforms_arg(value: object, name: str = "platforms") -> str | list[str] | tuple[str, ...] | None:
    """None, a str ('all', 'host', 'x86_64-linux,...') or a list of platform names, else ModelInputError
    (fmu.build.platforms.resolve_platforms checks the names)."""
    ok = value is None or isinstance(value, str)
    ok = ok or (isinstance(value, (list, tuple)) and all(isinstance(p, str) for p in value))
    if not ok:
        raise ModelInputError(
            f"{name} must be None (the host's binary), 'all', 'host' or platform names (a str or a list), "
            f"got {_given(value)}"
        )
    return value  # type: ignore[return-value]
