"""Controller files (TOML): read one, list the shipped ones, and hand it to its law's builder.

A controller file names its law, the plant scene it was made for (read at build time with
modelsrc's scene reader: the law takes the plant's inertia, wheel axes and variable names from
it), its sample period and its gains, limits and target (the law's tables; docs/user_guide.md,
"Controllers"). Every error names the file and the field (ModelInputError).
"""

from __future__ import annotations

import tomllib
from collections.abc import Callable
from pathlib import Path
from typing import Any

from ..errors import ModelInputError
from ..scene import Scene, load_scene
from ..scene_reader import SceneReader
from ..shipped_files import shipped_names, shipped_or_toml
from . import attitude_pd, attitude_torque_pd, quadrotor_hover
from .controller import ControllerModel

CONTROLLER_DIR = Path(__file__).resolve().parent
TOP_KEYS = frozenset({"name", "description", "law", "plant", "sample_period", "gains", "limits", "target"})
MAX_CONTROLLER_BYTES = 1_000_000


class ControllerReader(SceneReader):
    """SceneReader whose errors say "controller file <path>: field '<f>': ..."."""

    def fail(self, fld: str, msg: str) -> ModelInputError:
        """The error for field `fld` (dotted path, e.g. 'gains.k_p')."""
        return ModelInputError(f"controller file {self.path}: field '{fld}': {msg}")


# law name -> (the keys its tables take, its builder)
Builder = Callable[[ControllerReader, str, str, Scene, float], ControllerModel]
LAWS: dict[str, tuple[dict[str, frozenset[str]], Builder]] = {
    "attitude_pd": (attitude_pd.SECTION_KEYS, attitude_pd.build),
    "attitude_torque_pd": (attitude_torque_pd.SECTION_KEYS, attitude_torque_pd.build),
    "quadrotor_hover": (quadrotor_hover.SECTION_KEYS, quadrotor_hover.build),
}


def list_controllers() -> list[str]:
    """Names of the controllers shipped in modelsrc/controllers (*.toml)."""
    return shipped_names(CONTROLLER_DIR)


def is_controller(name_or_path: str | Path) -> bool:
    """True when name_or_path is a shipped controller's name or a .toml file whose top level has `law`."""
    p = Path(name_or_path)
    if p.suffix != ".toml":
        return str(name_or_path) in list_controllers()
    try:
        return p.is_file() and "law" in tomllib.loads(p.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError):
        return False


def controller_path(name_or_path: str | Path) -> Path:
    """A shipped controller's file, or the given .toml path; ModelInputError if neither exists."""
    return shipped_or_toml(name_or_path, CONTROLLER_DIR, "controller")


def _parse(path: Path) -> dict[str, Any]:
    try:
        if path.stat().st_size > MAX_CONTROLLER_BYTES:
            raise ModelInputError(f"controller file {path}: more than {MAX_CONTROLLER_BYTES} bytes")
        return tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise ModelInputError(f"controller file {path}: not valid TOML: {exc}") from None
    except UnicodeDecodeError as exc:
        raise ModelInputError(f"controller file {path}: not UTF-8 text (byte {exc.start}), as TOML must be") from None
    except OSError as exc:
        raise ModelInputError(f"controller file {path}: cannot be read: {exc.strerror or exc}") from None


def load_controller(name_or_path: str | Path) -> ControllerModel:
    """Read a controller file (shipped name or path), read its plant scene, build the law's
    CasADi functions and variables. Raises ModelInputError naming the file and field."""
    path = controller_path(name_or_path)
    data = _parse(path)
    law = data.get("law")
    if law not in LAWS:
        raise ModelInputError(
            f"controller file {path}: field 'law': {law!r} is not a law; known laws: {', '.join(LAWS)}"
        )
    keys, build = LAWS[law]
    rd = ControllerReader(path, data, keys)
    unknown = set(data) - TOP_KEYS
    if unknown:
        raise rd.fail(sorted(unknown)[0], f"unknown key; allowed top-level keys: {', '.join(sorted(TOP_KEYS))}")
    name = data.get("name", path.stem)
    if not (isinstance(name, str) and name.isidentifier() and name.isascii() and len(name) <= 64):
        raise rd.fail("name", f"must be an ASCII identifier of at most 64 characters, got {name!r}")
    description = data.get("description", "")
    if not isinstance(description, str):
        raise rd.fail("description", f"must be a string, got {description!r}")
    plant = data.get("plant")
    if not isinstance(plant, str):
        raise rd.fail("plant", f"must name the plant scene (a shipped scene or a .toml path), got {plant!r}")
    try:
        scene = load_scene(plant if plant.endswith(".toml") is False else str((path.parent / plant).resolve()))
    except ModelInputError as exc:
        raise rd.fail("plant", str(exc)) from None
    Ts = rd.number("sample_period", data.get("sample_period"), positive=True)
    return build(rd, name, description, scene, Ts)
