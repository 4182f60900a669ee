"""Build a scene's FMU: generate C, compile with gcc, zip the archive (FMI 3.0 layout).

SCENE.fmu holds modelDescription.xml, binaries/<platform>/SCENE.so, and sources/ with
buildDescription.xml so that an importer can rebuild it on another platform.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import platform
import shutil
import subprocess
import tempfile
import uuid
import zipfile
from pathlib import Path

import casadi as ca
import fmpy

from modelsrc.errors import ModelInputError
from modelsrc.model import build_model
from modelsrc.scene import Scene, load_scene

from .codegen import generate_c
from .model_data import write_model_data
from .model_description import build_description_xml, fmi2_model_description, fmi3_model_description

C_DIR = Path(__file__).resolve().parent / "c"
# The hand-written, version-independent core (docs/fmi_layer.md); every FMU carries all of it.
CORE_SOURCES = ("rbfmu_core.c", "rbfmu_step.c", "rbfmu_budget.c", "rbfmu_exchange.c", "rbfmu_snapshot.c")
CORE = (*CORE_SOURCES, "rbfmu_core.h")
# per FMI version: the API adapter, the standard's headers (shipped in fmpy), the model description
VERSIONS = {
    "3": ("rbfmu_fmi3.c", ("fmi3Functions.h", "fmi3FunctionTypes.h", "fmi3PlatformTypes.h"), fmi3_model_description),
    "2": ("rbfmu_fmi2.c", ("fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h"), fmi2_model_description),
}
CFLAGS = ["-O2", "-std=c99", "-fPIC", "-fvisibility=hidden", "-Wall", "-Wextra"]
# The hand-written layer must be warning-free (-Werror). CasADi's generated functions
# have a fixed signature (arg, res, iw, w, mem) whose unused arguments trip
# -Wunused-parameter, a known property of its code generator (casadi issue #2014);
# that single warning is disabled for the generated file only, all others stay on.
GENERATED_EXTRA = ["-Wno-unused-parameter"]


# Where the archive records the build key (FMI 3.0 §2.5: extra/ holds tool-specific
# files in a reverse-domain folder; FMI 2.0 importers ignore unknown folders).
BUILD_KEY_MEMBER = "extra/org.rbfmu/build_key.txt"
PACKAGE_DIRS = (Path(__file__).resolve().parent, Path(__file__).resolve().parent.parent / "modelsrc")


class BuildError(RuntimeError):
    """gcc failed or warned on the hand-written layer."""


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


def build_key(scene: Scene, fmi_version: str | int = 3, extra_cflags: list[str] | None = None) -> str:
    """What the FMU is a function of: the parsed scene, every source file of the model and
    of the FMU layer (.py, .c, .h), the build options and the tool versions. Two builds
    with equal keys are interchangeable; `ensure_fmu` reuses an archive only then."""
    digest = hashlib.sha256(_scene_fingerprint(scene).encode())
    for d in PACKAGE_DIRS:
        for f in sorted(d.rglob("*")):
            if f.suffix in (".py", ".c", ".h") and "__pycache__" not in f.parts:
                digest.update(f.relative_to(d.parent).as_posix().encode() + b"\0" + f.read_bytes())
    digest.update(repr((str(fmi_version), list(extra_cflags or []), CFLAGS, fmpy.__version__)).encode())
    digest.update(ca.__version__.encode())  # type: ignore[attr-defined]
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


def ensure_fmu(scene: Scene | str | Path, out_dir: str | Path = "build", fmi_version: str | int = 3) -> Path:
    """The scene's FMU in out_dir, rebuilt unless the archive there was built from the
    same content (`build_key`): a same-named scene from another file, a changed source
    (.py, .c or .h) or other build options all rebuild."""
    sc = scene if isinstance(scene, Scene) else load_scene(scene)
    path = Path(out_dir) / fmu_file_name(sc.name, fmi_version)
    if path.is_file() and archive_build_key(path) == build_key(sc, fmi_version):
        return path
    return build_fmu(sc, out_dir, fmi_version=fmi_version)


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


def c_sources(fmi_version: str | int = 3) -> list[str]:
    """The C files of an FMU's binary, as named in its sources/ folder: the API adapter of
    the FMI version, the core, and the generated model functions."""
    return [VERSIONS[str(fmi_version)][0], *CORE_SOURCES, "model_funcs.c"]


def platform_tuple(fmi_version: str = "3") -> str:
    """Binaries folder name: FMI 3.0 platform tuple (x86_64-linux) or FMI 2.0 (linux64)."""
    arch = {"AMD64": "x86_64", "arm64": "aarch64"}.get(platform.machine(), platform.machine())
    system = platform.system().lower()
    if fmi_version == "2":
        return {"linux": "linux", "darwin": "darwin", "windows": "win"}.get(system, system) + (
            "64" if arch in ("x86_64", "aarch64") else "32"
        )
    return f"{arch}-{system}"


def _compile(src_dir: Path, obj_dir: Path, out: Path, adapter: str, extra_flags: list[str]) -> str:
    """Compile and link; return gcc's diagnostics (empty when warning-free)."""
    objs, diagnostics = [], ""
    units = [(adapter, ["-Werror"]), *((c, ["-Werror"]) for c in CORE_SOURCES), ("model_funcs.c", GENERATED_EXTRA)]
    for src, flags in units:
        obj = obj_dir / (src + ".o")
        proc = subprocess.run(
            ["gcc", *CFLAGS, *flags, *extra_flags, "-I", str(src_dir), "-c", str(src_dir / src), "-o", str(obj)],
            capture_output=True,
            text=True,
        )
        if proc.returncode != 0:
            raise BuildError(f"gcc failed on {src}:\n{proc.stderr}")
        diagnostics += proc.stderr
        objs.append(str(obj))
    proc = subprocess.run(
        ["gcc", "-shared", *extra_flags, "-o", str(out), *objs, "-lm"], capture_output=True, text=True
    )
    if proc.returncode != 0:
        raise BuildError(f"linking {out.name} failed:\n{proc.stderr}")
    return diagnostics + proc.stderr


def build_fmu(
    scene: Scene | str | Path,
    out_dir: str | Path = "build",
    extra_cflags: list[str] | None = None,
    fmi_version: str | int = 3,
) -> Path:
    """Build the scene's FMU (Co-Simulation and Model Exchange) into out_dir; return its path.

    fmi_version 3 writes SCENE.fmu, 2 writes SCENE_fmi2.fmu. extra_cflags are added to
    compile and link (e.g. sanitizers for tests).
    """
    version = str(fmi_version)
    if version not in VERSIONS:
        raise ModelInputError(f"fmi_version must be 2 or 3, got {fmi_version!r}")
    adapter, headers_needed, describe = VERSIONS[version]
    sc = scene if isinstance(scene, Scene) else load_scene(scene)
    if shutil.which("gcc") is None:
        raise BuildError("gcc not found on PATH: it is needed to compile the FMU")
    out_dir = output_dir(out_dir)
    model = build_model(sc)
    with tempfile.TemporaryDirectory(prefix="rbfmu_build_") as tmp:
        root = Path(tmp) / "fmu"
        src = root / "sources"
        sizes = generate_c(model, src)
        for f in (*CORE, adapter):
            shutil.copy(C_DIR / f, src / f)
        headers = Path(fmpy.__file__).parent / "c-code"
        for h in headers_needed:
            shutil.copy(headers / h, src / h)
        # The token identifies this exact build: a hash of the generated code, the variables
        # and the build key (scene content, default method, sources, options), so that a
        # modelDescription and a binary of two different builds never pass as a pair.
        key = build_key(sc, version, extra_cflags)
        digest = hashlib.sha256((src / "model_funcs.c").read_bytes())
        digest.update(repr([(v.name, int(v.kind), v.start, v.unit) for v in model.variables]).encode())
        digest.update(key.encode())
        token = "{" + str(uuid.UUID(bytes=digest.digest()[:16])) + "}"
        write_model_data(model, token, sizes, src / "model_data.h")
        (src / "buildDescription.xml").write_bytes(build_description_xml(sc.name, c_sources(version), version + ".0"))
        (root / "modelDescription.xml").write_bytes(describe(model, token))
        key_file = root / BUILD_KEY_MEMBER
        key_file.parent.mkdir(parents=True)
        key_file.write_text(key + "\n")
        bin_dir = root / "binaries" / platform_tuple(version)
        bin_dir.mkdir(parents=True)
        stem = fmu_file_name(sc.name, version)[: -len(".fmu")]
        diagnostics = _compile(src, Path(tmp), bin_dir / f"{sc.name}.so", adapter, extra_cflags or [])
        (out_dir / f"{stem}.build.log").write_text(diagnostics)
        fmu_path = out_dir / f"{stem}.fmu"
        tmp_zip = fmu_path.with_suffix(".fmu.part")
        with zipfile.ZipFile(tmp_zip, "w", zipfile.ZIP_DEFLATED) as z:
            for member in sorted(root.rglob("*")):
                if member.is_file():
                    z.write(member, member.relative_to(root).as_posix())
        tmp_zip.replace(fmu_path)
    return fmu_path


def build_all(out_dir: str | Path = "build", fmi_version: str | int = 3) -> list[Path]:
    """Build every shipped scene; return the FMU paths."""
    from modelsrc.scene import list_scenes

    return [build_fmu(name, out_dir, fmi_version=fmi_version) for name in list_scenes()]


__all__ = ["BuildError", "ModelInputError", "build_all", "build_fmu", "build_key", "ensure_fmu", "platform_tuple"]
