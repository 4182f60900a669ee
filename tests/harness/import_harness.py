"""The C importer tests/c/fmi_import_harness.c built for the host or a cross platform (tests, tools/)."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

from fmu.build.cross_compile import run_zig
from fmu.build.platforms import PLATFORMS

HARNESS = Path(__file__).resolve().parent.parent / "c" / "fmi_import_harness.c"
# Debian's cross compilers, preferred where installed: an importer built by another
# toolchain than the FMU's (zig)
CROSS_GCC = {"aarch64-linux": "aarch64-linux-gnu-gcc", "x86_64-windows": "x86_64-w64-mingw32-gcc"}


def compile_harness(sources: Path, platform: str | None, exe: Path) -> subprocess.CompletedProcess[str]:
    """Compile the harness against the FMI headers in `sources` (an FMU's sources/ folder)
    into `exe`: for the host with gcc (platform None), else for `platform` with Debian's
    cross gcc where installed, otherwise zig cc. Returns the compiler's process (check
    its returncode and stderr)."""
    flags = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-I", str(sources), str(HARNESS), "-o", str(exe)]
    if platform is None:
        return subprocess.run(["gcc", *flags, "-ldl"], capture_output=True, text=True)
    libs = ["-ldl"] if "linux" in platform else []
    gcc = shutil.which(CROSS_GCC[platform])
    if gcc:
        return subprocess.run([gcc, *flags, *libs], capture_output=True, text=True)
    return run_zig("cc", "-target", PLATFORMS[platform].zig_target, *flags, *libs)
