"""Scene files a test makes up, and the shipped scenes' FMUs shared by the xdist workers of one run."""

from __future__ import annotations

import fcntl
from pathlib import Path

from fmu.build.build_fmu import ensure_fmu
from modelsrc.scene import load_scene


def shared_fmu(build_dir: Path, name: str) -> Path:
    """The shipped scene's FMU in the run's shared build directory: built under a per-scene
    lock by the first xdist worker that needs it, reused by the others (ensure_fmu)."""
    with open(build_dir / f"{name}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file closes
        return ensure_fmu(load_scene(name), build_dir)


def write_scene(tmp_path: Path, text: str, name: str = "custom") -> Path:
    """Write a scene file and return its path (for scenes made up by a test)."""
    p = tmp_path / f"{name}.toml"
    p.write_text(text)
    return p
