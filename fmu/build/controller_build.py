"""Build a controller's FMU (FMI 3.0 or 2.0 Co-Simulation) with the scenes' pipeline: CasADi → C, a generic C layer.

NAME.fmu (FMI 3.0) or NAME_fmi2.fmu (FMI 2.0) holds modelDescription.xml
(fmu/build/controller_description.py), binaries/<platform>/NAME.<so|dll|dylib> for the host
and any other platform of fmu.build.platforms (as a scene's: fmu/build/cross_compile.py),
sources/ (the generated ctrl_funcs.c and controller_data.h, the hand-written sampled-data
layer fmu/c/rbctl_*.c, the standard's headers, buildDescription.xml, CMakeLists.txt), documentation/index.html
and the licence file. The law is only the generated C; the layer is generic.
"""

from __future__ import annotations

import hashlib
import html
import shutil
import tempfile
import uuid
import zipfile
from pathlib import Path

import casadi as ca
import fmpy

from modelsrc.controllers.controller import ControllerModel
from modelsrc.controllers.controller_file import load_controller
from modelsrc.errors import ModelInputError

from .build_fmu import BUILD_KEY_MEMBER, DOCUMENTATION_MEMBER, VERSIONS, archive_build_key, fmu_file_name, output_dir
from .compile import C_DIR, CFLAGS, GENERATED_EXTRA, HANDWRITTEN_EXTRA, BuildError, compile_native
from .controller_data import BASENAME, controller_data_h, generate_controller_c
from .controller_description import fmi2_controller_description, fmi3_controller_description
from .cross_compile import binary_name, build_cross, zig_version
from .licensing import LICENSE_MEMBER, archive_license
from .model_description import build_description_xml
from .platforms import PLATFORMS, binary_folder, resolve_platforms
from .source_fmu import cmake_lists

CORE = ("rbctl_core.c",)
HEADERS = ("rbctl_core.h", "rbfmu_build.h")
ADAPTERS = {"3": "rbctl_fmi3.c", "2": "rbctl_fmi2.c"}
GENERATED = f"{BASENAME}.c"
PACKAGE_FILES = (C_DIR, Path(__file__).resolve().parent, Path(__file__).resolve().parents[2] / "modelsrc")


def controller_sources(fmi_version: str | int = 3) -> list[str]:
    """The C files of a controller FMU's binary, as named in its sources/ folder."""
    return [ADAPTERS[str(fmi_version)], *CORE, GENERATED]


def controller_units(fmi_version: str | int = 3) -> list[tuple[str, list[str]]]:
    """(source file, its extra flags): the hand-written layer under -Werror, the generated file as a scene's."""
    return [(s, GENERATED_EXTRA if s == GENERATED else HANDWRITTEN_EXTRA) for s in controller_sources(fmi_version)]


def controller_build_key(ctrl: ControllerModel, fmi_version: str, plats: list[str]) -> str:
    """What the controller FMU is a function of: its variables, checks and functions, every source
    of the model and of the layer (.py, .c, .h), the options and the tool versions."""
    digest = hashlib.sha256(repr((ctrl.name, ctrl.description, ctrl.plant, ctrl.sample_period, ctrl.variables,
                                  ctrl.check_texts, ctrl.feedthrough)).encode())  # fmt: skip
    for f in ctrl.functions.values():
        digest.update(f.serialize().encode())
    for d in PACKAGE_FILES:
        for p in sorted(d.rglob("*")):
            if p.suffix in (".py", ".c", ".h") and "__pycache__" not in p.parts:
                digest.update(p.name.encode() + b"\0" + p.read_bytes())
    digest.update(repr((fmi_version, CFLAGS, fmpy.__version__, plats, ca.__version__)).encode())  # type: ignore[attr-defined]
    if len(plats) > 1:
        digest.update(zig_version().encode())
    return digest.hexdigest()


def _index_html(ctrl: ControllerModel, version: str, plats: list[str]) -> str:
    rows = "".join(
        f"<tr><td><code>{html.escape(v.name)}</code></td><td>{v.kind.value}</td>"
        f"<td>{'' if v.start is None else v.start}</td>"
        f"<td>{v.unit or ''}</td><td>{html.escape(v.description)}</td></tr>"
        for v in ctrl.variables
    )
    return (
        f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{ctrl.name}</title></head><body>"
        f"<h1>{ctrl.name}</h1><p>{html.escape(ctrl.description)}</p>"
        f"<p>FMI {version}.0 Co-Simulation controller for the plant scene <code>{ctrl.plant}</code>; sample period "
        f"Ts = {ctrl.sample_period} s (samples at t_start + k Ts, each must be a communication point). "
        "At a sample point the outputs are the law at the current inputs (direct feedthrough); "
        "they are held until the next sample point (zero-order hold), and the discrete states update "
        "at the doStep that leaves a sample point. "
        f"Platforms: {', '.join(plats)}. The law: docs/theory.md §12.</p>"
        f"<table><tr><th>name</th><th>kind</th><th>start</th><th>unit</th><th>description</th></tr>{rows}</table>"
        "</body></html>"
    )


def build_controller(
    controller: ControllerModel | str | Path,
    out_dir: str | Path = "build",
    fmi_version: str | int = 3,
    platforms: str | list[str] | tuple[str, ...] | None = None,
) -> Path:
    """Build the controller's FMU into out_dir; return its path (NAME.fmu or NAME_fmi2.fmu).

    platforms as for a scene (fmu.build.build_fmu.build_fmu): None the host's binary (gcc),
    "all" or names every binary with zig cc."""
    version = str(fmi_version)
    if version not in VERSIONS:
        raise ModelInputError(f"fmi_version must be 2 or 3, got {fmi_version!r}")
    plats = resolve_platforms(platforms, version)
    host = plats[0]
    ctrl = controller if isinstance(controller, ControllerModel) else load_controller(controller)
    if shutil.which("gcc") is None:
        raise BuildError("gcc not found on PATH: it is needed to compile the FMU")
    out = output_dir(out_dir)
    fmu_path = out / fmu_file_name(ctrl.name, version)
    key = controller_build_key(ctrl, version, plats)
    tmp_zip = fmu_path.with_suffix(".fmu.part")
    try:
        with tempfile.TemporaryDirectory(prefix="rbfmu_ctrl_") as tmp:
            root = Path(tmp) / "fmu"
            src = root / "sources"
            sizes = generate_controller_c(ctrl, src)
            for f in (*CORE, *HEADERS, ADAPTERS[version]):
                shutil.copy(C_DIR / f, src / f)
            headers = Path(fmpy.__file__).parent / "c-code"
            for h in VERSIONS[version][0]:
                shutil.copy(headers / h, src / h)
            digest = hashlib.sha256((src / GENERATED).read_bytes())
            digest.update(key.encode())
            token = "{" + str(uuid.UUID(bytes=digest.digest()[:16])) + "}"
            (src / "controller_data.h").write_text(controller_data_h(ctrl, token, sizes))
            sources = controller_sources(version)
            (src / "buildDescription.xml").write_bytes(build_description_xml(ctrl.name, sources, version + ".0"))
            (src / "CMakeLists.txt").write_text(cmake_lists(ctrl.name, version, sources, GENERATED))
            md = (
                fmi3_controller_description(ctrl, token)
                if version == "3"
                else fmi2_controller_description(ctrl, token, sources)
            )
            (root / "modelDescription.xml").write_bytes(md)
            (root / BUILD_KEY_MEMBER).parent.mkdir(parents=True)
            (root / BUILD_KEY_MEMBER).write_text(key + "\n")
            binaries = {p: root / "binaries" / binary_folder(p, version) / binary_name(ctrl.name, p) for p in plats}
            binaries[host].parent.mkdir(parents=True)
            portable = len(plats) > 1 and host in PLATFORMS
            unit_list = controller_units(version)
            diagnostics = "" if portable else compile_native(src, binaries[host], version, [], unit_list)
            if len(plats) > 1:
                built = build_cross(src, version, plats[int(not portable) :], binaries, ctrl.name, unit_list)
                diagnostics += "".join(f"[{p}]\n{d}" for p, (d, _) in built.items() if d)
            (root / LICENSE_MEMBER[version]).parent.mkdir(parents=True, exist_ok=True)
            (root / LICENSE_MEMBER[version]).write_text(archive_license(version, plats))
            (root / DOCUMENTATION_MEMBER).parent.mkdir(parents=True, exist_ok=True)
            (root / DOCUMENTATION_MEMBER).write_text(_index_html(ctrl, version, plats))
            with zipfile.ZipFile(tmp_zip, "w", zipfile.ZIP_DEFLATED) as z:
                for member in sorted(root.rglob("*")):
                    if member.is_file():
                        z.write(member, member.relative_to(root).as_posix())
            tmp_zip.replace(fmu_path)
            log = out / f"{fmu_path.stem}.build.log"
            if diagnostics.strip():
                log.write_text(diagnostics)
            else:
                log.unlink(missing_ok=True)
    except BaseException:
        tmp_zip.unlink(missing_ok=True)
        raise
    return fmu_path


def ensure_controller(
    controller: ControllerModel | str | Path,
    out_dir: str | Path = "build",
    fmi_version: str | int = 3,
    platforms: str | list[str] | tuple[str, ...] | None = None,
) -> Path:
    """The controller's FMU in out_dir, rebuilt unless the archive there has the same build key."""
    ctrl = controller if isinstance(controller, ControllerModel) else load_controller(controller)
    version = str(fmi_version)
    path = Path(out_dir) / fmu_file_name(ctrl.name, version)
    if path.is_file() and archive_build_key(path) == controller_build_key(
        ctrl, version, resolve_platforms(platforms, version)
    ):
        return path
    return build_controller(ctrl, out_dir, version, platforms)
