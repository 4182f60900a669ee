"""Shipped TOML files by name, or a user's .toml file by path: the one rule of scenes, controllers and systems.

A name without the .toml suffix is looked up among the shipped files of its kind (NAME.toml in
their directory); a path ending in .toml is the user's own file. Either must exist, else a
ModelInputError names the value and lists the shipped names. `modelsrc.scene.scene_path`,
`modelsrc.controllers.controller_file.controller_path` and `fmu.system.system_file.system_path`
are this rule with their directory.
"""

from __future__ import annotations

from pathlib import Path

from .errors import ModelInputError


def shipped_names(directory: Path) -> list[str]:
    """The names of the shipped files in `directory` (the stems of its *.toml), sorted."""
    return sorted(p.stem for p in directory.glob("*.toml"))


def shipped_or_toml(name_or_path: str | Path, directory: Path, kind: str) -> Path:
    """The user's file when name_or_path ends in .toml, else the shipped file
    directory/NAME.toml; ModelInputError when it does not exist, naming it and (for a name)
    the shipped names. kind: what the files hold ('scene', 'controller', 'system'), for the messages."""
    p = Path(name_or_path)
    if p.suffix == ".toml":
        if not p.is_file():
            raise ModelInputError(f"{kind} file {p} does not exist")
        return p
    candidate = directory / f"{name_or_path}.toml"
    if not candidate.is_file():
        known = ", ".join(shipped_names(directory)) or "none"
        raise ModelInputError(
            f"unknown {kind} {str(name_or_path)!r}; known {kind}s: {known} (or give a path to a .toml file)"
        )
    return candidate
