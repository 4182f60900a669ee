"""`rbfmu system build`: the components' FMI 2.0 FMUs (fmu.build), the system's checks, then the .ssp archive.

Order: the system file is read and checked for form, each component's scene or controller
is loaded (an unknown one is refused by name), its FMU is built into the build cache (or
reused: `ensure_fmu`), the system is checked against the FMUs' interfaces
(`fmu.system.checks`), and only then is OUT/NAME.ssp written; a refused system writes no
archive.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from modelsrc.controllers.controller import ControllerModel
from modelsrc.controllers.controller_file import load_controller
from modelsrc.errors import ModelInputError
from modelsrc.scene import Scene, load_scene

from ..build.build_fmu import BuildTask, ensure_fmu
from ..build.controller_build import ensure_controller
from .checks import Link, check_system, warn_unit_mistakes
from .interface import Interface, read_interface, scene_feedthrough
from .ssp import write_ssp
from .system_file import Component, System, read_system

FMI_VERSION = 2  # what both masters run (fmu.system.ssp's docstring)


@dataclass(frozen=True)
class BuiltSystem:
    """A checked system: its file's content, each component's FMU and interface, the scalar links,
    and each controller component's loaded controller (by component name: loaded once, for the build
    and for whoever reads its law or targets after, fmu.system.demo)."""

    system: System
    fmus: dict[str, Path]
    interfaces: dict[str, Interface]
    links: list[Link]
    controllers: dict[str, ControllerModel]


def _scene(comp: Component) -> Scene:
    try:
        return load_scene(comp.source)
    except ModelInputError as exc:
        raise ModelInputError(f"component {comp.name}: {exc}") from None


def _controller(comp: Component) -> ControllerModel:
    try:
        return load_controller(comp.source)
    except ModelInputError as exc:
        raise ModelInputError(f"component {comp.name}: {exc}") from None


def _loaded(system: System) -> dict[str, Scene | ControllerModel]:
    """Each component's scene or controller, loaded (by component name); an unknown one is
    refused naming the component."""
    return {c.name: _scene(c) if c.kind == "scene" else _controller(c) for c in system.components.values()}


def _component_fmu(loaded: Scene | ControllerModel, build_dir: Path) -> tuple[Path, Interface]:
    """The FMU of a component's loaded scene or controller (built or reused) and its interface."""
    if isinstance(loaded, ControllerModel):  # its modelDescription declares its outputs' dependencies
        path = ensure_controller(loaded, build_dir, fmi_version=FMI_VERSION)
        return path, read_interface(path)
    scene = loaded
    fmu = ensure_fmu(scene, build_dir, fmi_version=FMI_VERSION)
    iface = read_interface(fmu)
    # rbfmu's FMUs declare no output dependencies (FMI: all inputs); the model says which (interface.py)
    feed = scene_feedthrough(scene)
    return fmu, Interface(iface.ports, iface.fmi_version, {**iface.feedthrough, **feed}, iface.default_step)


def component_builds(name_or_path: str | Path, build_dir: str | Path = "build") -> list[BuildTask]:
    """The builds of the system's component FMUs (FMI 2.0) into build_dir, as tasks that
    fmu.build.build_fmu.run_builds may run on other processes beside other builds (`rbfmu
    demo`); `build_system` then finds the FMUs built (`ensure_fmu`, `ensure_controller`)."""
    system = read_system(name_or_path)
    _loaded(system)  # unknown scenes and controllers are refused before any build
    make = {"scene": ensure_fmu, "controller": ensure_controller}
    return [(make[c.kind], (c.source, Path(build_dir), FMI_VERSION)) for c in system.components.values()]


def check_built(name_or_path: str | Path, build_dir: str | Path = "build") -> BuiltSystem:
    """Read the system, build (or reuse) its components' FMUs and check it; nothing else written."""
    system = read_system(name_or_path)
    warn_unit_mistakes(system)  # a value almost surely in the wrong unit (a period for n_orbit): warned, built
    loaded = _loaded(system)  # each component loaded once, all before any build
    fmus, interfaces = {}, {}
    for name, model in loaded.items():
        fmus[name], interfaces[name] = _component_fmu(model, Path(build_dir))
    links = check_system(system, interfaces)
    controllers = {name: m for name, m in loaded.items() if isinstance(m, ControllerModel)}
    return BuiltSystem(system, fmus, interfaces, links, controllers)


def build_system(name_or_path: str | Path, out_dir: str | Path = "build", build_dir: str | Path = "build") -> Path:
    """Build OUT/NAME.ssp from a shipped system's name or a system file; return its path."""
    return write_built(check_built(name_or_path, build_dir), out_dir)


def write_built(built: BuiltSystem, out_dir: str | Path = "build") -> Path:
    """Write OUT/NAME.ssp of a checked system (`check_built`); return its path."""
    path = Path(out_dir) / f"{built.system.name}.ssp"
    return write_ssp(built.system, built.interfaces, built.links, built.fmus, path)
