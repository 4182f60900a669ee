"""Build a scene's FMU: generate C, compile it for each platform, document it, zip the archive.

SCENE.fmu (FMI 3.0) or SCENE_fmi2.fmu (FMI 2.0) holds modelDescription.xml,
binaries/<platform>/SCENE.<so|dll|dylib> for the host (gcc, or zig cc when other platforms
are built too) and any other platform of fmu.build.platforms (zig cc, fmu/build/cross_compile.py), sources/ as a source FMU (the C,
buildDescription.xml, CMakeLists.txt: fmu/build/source_fmu.py), documentation/index.html
(fmu/build/archive_docs.py, with figures measured on the host binary: fmu/build/build_check.py),
the licence file (fmu/build/licensing.py) and the icon (fmu/build/icon.py).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import shutil
import tempfile
import uuid
import warnings
import zipfile
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import casadi as ca
import fmpy
from fmpy.model_description import ValidationError

from modelsrc.errors import ModelInputError
from modelsrc.model import build_model
from modelsrc.scene import Scene, load_scene
from modelsrc.scene_limits import check_scene_limits

from ..drive.arguments import flags_arg, path_arg, platforms_arg, scene_arg

from .archive_docs import index_html
from .build_check import BuildCheck, ValidationRunWarning, check_build
from .codegen import generate_c
from .compile import ADAPTERS, C_DIR, CFLAGS, CORE, CORE_SOURCES, GENERATED_EXTRA, BuildError, c_sources, compile_native
from .cross_compile import binary_name, build_cross, zig_version
from .icon import write_icon
from .licensing import LICENSE_MEMBER, archive_license
from .model_data import write_model_data
from .model_description import (
    build_description_xml,
    check_attribute_values,
    fmi2_model_description,
    fmi3_model_description,
)
from .platforms import PLATFORMS, binary_folder, host_platform, resolve_platforms
from .source_fmu import cmake_lists

if TYPE_CHECKING:
    from concurrent.futures import Executor

# per FMI version: the standard's headers (shipped in fmpy), the model description, where the icon goes
VERSIONS = {
    "3": (("fmi3Functions.h", "fmi3FunctionTypes.h", "fmi3PlatformTypes.h"), fmi3_model_description,
          "terminalsAndIcons/icon.png"),
    "2": (("fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h"), fmi2_model_description, "model.png"),
}  # fmt: skip
DOCUMENTATION_MEMBER = "documentation/index.html"

# Where the archive records the build key (FMI 3.0 §2.5: extra/ holds tool-specific
# files in a reverse-domain folder; FMI 2.0 importers ignore unknown folders).
BUILD_KEY_MEMBER = "extra/org.rbfmu/build_key.txt"
FMU_DIR = Path(__file__).resolve().parent.parent  # fmu/: the C layer, the build, the driver
PACKAGE_DIRS = (FMU_DIR, FMU_DIR.parent / "modelsrc")


def _scene_fingerprint(scene: Scene) -> str:
    """The parsed scene as canonical JSON: its content, not its file name or time."""

    def plain(v: object) -> object:
        if hasattr(v, "tolist"):
            return v.tolist()
        if isinstance(v, (set, frozenset)):
            return sorted(v)
        if isinstance(v, dict):
            return {k: plain(x) for k, x in sorted(v.items())}
        if isinstance(v, (list, tuple)):
            return [plain(x) for x in v]
        return v

    fields = {f.name: plain(getattr(scene, f.name)) for f in dataclasses.fields(scene) if f.name != "path"}
    return json.dumps(fields, sort_keys=True, default=repr)


def build_key(
    scene: Scene,
    fmi_version: str | int = 3,
    extra_cflags: list[str] | None = None,
    platforms: str | list[str] | tuple[str, ...] | None = None,
) -> str:
    """What the FMU is a function of: the parsed scene, every source file of the model and
    of the FMU layer (.py, .c, .h), the build options (platforms included) and the tool
    versions (zig's when cross-compiling). Two builds with equal keys are
    interchangeable; `ensure_fmu` reuses an archive only then."""
    plats = resolve_platforms(platforms, fmi_version)
    digest = hashlib.sha256(_scene_fingerprint(scene).encode())
    for d in PACKAGE_DIRS:
        for f in sorted(d.rglob("*")):
            if f.suffix in (".py", ".c", ".h") and "__pycache__" not in f.parts:
                digest.update(f.relative_to(d.parent).as_posix().encode() + b"\0" + f.read_bytes())
    digest.update(repr((str(fmi_version), list(extra_cflags or []), CFLAGS, fmpy.__version__, plats)).encode())
    if len(plats) > 1:
        digest.update(zig_version().encode())
    digest.update(ca.__version__.encode())  # type: ignore[attr-defined]
    digest.update(archive_license(fmi_version, plats).encode())  # its texts are package data, not .py
    return digest.hexdigest()


def fmu_file_name(scene_name: str, fmi_version: str | int = 3) -> str:
    """SCENE.fmu (FMI 3.0) or SCENE_fmi2.fmu (FMI 2.0)."""
    return f"{scene_name}.fmu" if str(fmi_version) == "3" else f"{scene_name}_fmi2.fmu"


def archive_build_key(fmu_path: Path) -> str | None:
    """The build key recorded in an FMU archive, or None (not an rbfmu archive, unreadable)."""
    try:
        with zipfile.ZipFile(fmu_path) as z:
            return z.read(BUILD_KEY_MEMBER).decode().strip()
    except (OSError, KeyError, zipfile.BadZipFile):
        return None


def ensure_fmu(
    scene: Scene | str | Path,
    out_dir: str | Path = "build",
    fmi_version: str | int = 3,
    platforms: str | list[str] | tuple[str, ...] | None = None,
) -> Path:
    """The scene's FMU in out_dir, rebuilt unless the archive there was built from the
    same content (`build_key`): a same-named scene from another file, a changed source
    (.py, .c or .h) or other build options (platforms too) all rebuild."""
    sc, platforms = scene_arg(scene), platforms_arg(platforms)
    path = path_arg(out_dir, "out_dir") / fmu_file_name(sc.name, fmi_version)
    if path.is_file() and archive_build_key(path) == build_key(sc, fmi_version, platforms=platforms):
        return path
    return build_fmu(sc, out_dir, fmi_version=fmi_version, platforms=platforms)


def output_dir(out_dir: str | Path) -> Path:
    """out_dir, created if missing; ModelInputError if it is a file or cannot be created."""
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise ModelInputError(f"output directory {out} is a file; give a directory (it is created if missing)")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ModelInputError(f"output directory {out} cannot be created: {exc.strerror or exc}") from None
    return out


def platform_tuple(fmi_version: str = "3") -> str:
    """Binaries folder of the host's binary: FMI 3.0 platform tuple (x86_64-linux) or FMI 2.0 (linux64)."""
    return binary_folder(host_platform(), fmi_version)


def _write_sources(model, src: Path, version: str, key: str) -> str:
    """Write sources/ (generated C, the hand-written layer, the standard's headers,
    model_data.h, buildDescription.xml, CMakeLists.txt); return the instantiation token."""
    sc = model.scene
    sizes = generate_c(model, src)
    for f in (*CORE, *ADAPTERS[version]):
        shutil.copy(C_DIR / f, src / f)
    headers = Path(fmpy.__file__).parent / "c-code"
    for h in VERSIONS[version][0]:
        shutil.copy(headers / h, src / h)
    # The token identifies this exact build: a hash of the generated code, the variables
    # and the build key (scene content, default method, sources, options), so that a
    # modelDescription and a binary of two different builds never pass as a pair.
    digest = hashlib.sha256((src / "model_funcs.c").read_bytes())
    digest.update(repr([(v.name, int(v.kind), v.start, v.unit) for v in model.variables]).encode())
    digest.update(key.encode())
    token = "{" + str(uuid.UUID(bytes=digest.digest()[:16])) + "}"
    write_model_data(model, token, sizes, src / "model_data.h")
    (src / "buildDescription.xml").write_bytes(build_description_xml(sc.name, c_sources(version), version + ".0"))
    (src / "CMakeLists.txt").write_text(cmake_lists(sc.name, version))
    return token


def _zip(root: Path, path: Path) -> None:
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
        for member in sorted(root.rglob("*")):
            if member.is_file():
                z.write(member, member.relative_to(root).as_posix())


def _write_build_log(path: Path, diagnostics: str) -> None:
    """Keep the compiler's diagnostics beside the FMU only when there are some; an empty
    log next to every FMU says nothing, and a previous build's log would be stale."""
    if diagnostics.strip():
        path.write_text(diagnostics)
    else:
        path.unlink(missing_ok=True)


def build_fmu(
    scene: Scene | str | Path,
    out_dir: str | Path = "build",
    extra_cflags: list[str] | None = None,
    fmi_version: str | int = 3,
    platforms: str | list[str] | tuple[str, ...] | None = None,
) -> Path:
    """Build the scene's FMU (Co-Simulation and Model Exchange) into out_dir; return its path.

    Every argument is listed in docs/user_guide.md §4.1; a bad type or value is a
    ModelInputError naming it.

    fmi_version 3 writes SCENE.fmu, 2 writes SCENE_fmi2.fmu. platforms: None builds the
    host's binary only (gcc, for this machine's C library); "all" or names of
    fmu.build.platforms.PLATFORMS build every binary with zig cc, the host's included, each for
    the oldest C library of its platform (glibc 2.17 on Linux). extra_cflags are added to the host's compile and
    link (e.g. sanitizers for tests); such a build is not run to measure the
    documentation's validation figures (an instrumented library cannot be loaded here).
    The compiler diagnostics of every binary go to out_dir/STEM.build.log, written only
    when there are any (a warning-free build leaves none, and removes a stale one).
    When the validation run fails (fmu.build.build_check: e.g. a doStep refused by the work
    limit in a stiff scene), the FMU is still written and a ValidationRunWarning says so
    (docs/user_guide.md §3.2).
    """
    version = str(fmi_version)
    if version not in VERSIONS or isinstance(fmi_version, bool):
        raise ModelInputError(f"fmi_version must be 2 or 3, got {fmi_version!r}")
    extra_cflags = flags_arg(extra_cflags, "extra_cflags")
    plats = resolve_platforms(platforms_arg(platforms), version)
    host = plats[0]
    _, describe, icon_member = VERSIONS[version]
    sc = scene_arg(scene)
    out_dir = path_arg(out_dir, "out_dir")
    if shutil.which("gcc") is None:
        raise BuildError("gcc not found on PATH: it is needed to compile the FMU")
    # also checked by load_scene; a Scene may be made in code
    check_scene_limits(sc.path, len(sc.force_points), sc.inputs, len(sc.rotors))
    model = build_model(sc)
    check_attribute_values(model)
    out_dir = output_dir(out_dir)
    stem = fmu_file_name(sc.name, version)[: -len(".fmu")]
    fmu_path = out_dir / f"{stem}.fmu"
    # Nothing of a failed or interrupted build stays behind: the build folder is a
    # TemporaryDirectory (removed on any exception, KeyboardInterrupt included), the
    # archive in progress is removed here, and out_dir gets the archive and its log only
    # once the build succeeded (a previous build's pair stays until then).
    tmp_zip = fmu_path.with_suffix(".fmu.part")
    try:
        with tempfile.TemporaryDirectory(prefix="rbfmu_build_") as tmp:
            root = Path(tmp) / "fmu"
            src = root / "sources"
            key = build_key(sc, version, extra_cflags, plats)
            token = _write_sources(model, src, version, key)
            (root / "modelDescription.xml").write_bytes(describe(model, token, c_sources(version)))
            key_file = root / BUILD_KEY_MEMBER
            key_file.parent.mkdir(parents=True)
            key_file.write_text(key + "\n")
            binaries = {p: root / "binaries" / binary_folder(p, version) / binary_name(sc.name, p) for p in plats}
            binaries[host].parent.mkdir(parents=True)
            # A multi-platform (shipped) archive carries zig's binary for the host too: it pins
            # the oldest glibc (platforms.py); gcc's links against this machine's (fast, local use).
            portable = len(plats) > 1 and host in PLATFORMS and not extra_cflags
            diagnostics = (
                "" if portable else compile_native(src, binaries[host], version, extra_cflags or [])
            )
            if len(plats) > 1:
                for p, (diag, _) in build_cross(src, version, plats[int(not portable) :], binaries, sc.name).items():
                    diagnostics += f"[{p}]\n{diag}" if diag else ""
            write_icon(sc, root / icon_member)
            license_file = root / LICENSE_MEMBER[version]
            license_file.parent.mkdir(parents=True, exist_ok=True)
            license_file.write_text(archive_license(version, plats))
            _zip(root, tmp_zip)
            check: BuildCheck | None = None
            if not extra_cflags:
                try:
                    check = check_build(tmp_zip, sc, model.methods, model.default_method)
                except ValidationError as exc:  # check_attribute_values should have refused the scene
                    problems = exc.problems
                    raise BuildError(
                        f"the generated modelDescription.xml is not valid ({len(problems)} problems, the first: "
                        f"{problems[0] if problems else '?'}); this is a bug of rbfmu's checks, please report it"
                    ) from None
            if check is not None and check.error:  # the FMU is written: it may be right, the scene stiff
                warnings.warn(
                    f"{check.error}; {fmu_path.name} was written, its documentation says the figures were not "
                    "measured (docs/user_guide.md §3.2)",
                    ValidationRunWarning,
                    stacklevel=2,
                )
            with zipfile.ZipFile(tmp_zip, "a", zipfile.ZIP_DEFLATED) as z:
                z.writestr(DOCUMENTATION_MEMBER, index_html(model, version, plats, host, check))
            tmp_zip.replace(fmu_path)
            _write_build_log(out_dir / f"{stem}.build.log", diagnostics)
    except BaseException:
        tmp_zip.unlink(missing_ok=True)
        raise
    return fmu_path


# One build: a function making an FMU (ensure_fmu, ensure_controller) and its arguments,
# plain values (names, paths) so that it can be sent to another process.
BuildTask = tuple[Callable[..., Path], tuple[object, ...]]


def run_builds(tasks: Sequence[BuildTask], pool: Executor | None = None) -> list[Path]:
    """Each task's FMU, in order: fn(*args) on the pool's processes when one is given (every
    task submitted at once, so that no core waits while builds are left), else one after the
    other here."""
    if pool is None:
        return [fn(*args) for fn, args in tasks]
    futures = [pool.submit(fn, *args) for fn, args in tasks]
    return [f.result() for f in futures]


def build_all(
    names: Sequence[str] | None = None, out_dir: str | Path = "build", jobs: int = 1, pool: Executor | None = None
) -> dict[str, Path]:
    """Scene name -> its FMU (FMI 3.0, this machine's binary) in out_dir (`ensure_fmu`: an
    archive built from the same content is kept), for the named scenes (default: every
    shipped one), built by `jobs` processes at once (or on `pool`'s): each build is one gcc
    run after another, and the scenes are independent, so two cores build two at a time."""
    from modelsrc.scene import list_scenes

    names = list(list_scenes() if names is None else names)
    tasks: list[BuildTask] = [(ensure_fmu, (name, out_dir)) for name in names]
    if pool is not None or jobs == 1 or len(names) < 2:
        return dict(zip(names, run_builds(tasks, pool), strict=True))
    from concurrent.futures import ProcessPoolExecutor

    with ProcessPoolExecutor(max_workers=min(jobs, len(names))) as own:
        return dict(zip(names, run_builds(tasks, own), strict=True))


__all__ = [
    "CFLAGS",
    "CORE_SOURCES",
    "GENERATED_EXTRA",
    "BuildError",
    "BuildTask",
    "ModelInputError",
    "ValidationRunWarning",
    "build_all",
    "build_fmu",
    "build_key",
    "c_sources",
    "ensure_fmu",
    "platform_tuple",
    "run_builds",
]
