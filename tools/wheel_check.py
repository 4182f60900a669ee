"""CI check that the wheel works outside the checkout: build it, install it into an empty venv, build and run an FMU.

Run from the repository root (`make wheel-check`). Everything happens in a temporary
directory: the wheel is built with `python -m build`, installed with the versions of
constraints.txt into a fresh venv, and that venv's `rbfmu` builds `symmetric_free` (with
its licence file, package data), prints its version, runs it for 1 s and checks the
printed summary, from a working directory that is not the checkout (so nothing can be
imported from the source tree by accident).
"""

from __future__ import annotations

import shutil
import subprocess
import sys
import tempfile
import time
import zipfile
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent


def run(cmd: list[str], cwd: Path) -> str:
    """Run a command, echo it, fail with its output if it fails; return stdout."""
    print("+", " ".join(cmd), flush=True)
    proc = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True)
    if proc.returncode != 0:
        sys.exit(f"wheel check failed: {' '.join(cmd)} exited {proc.returncode}\n{proc.stdout}\n{proc.stderr}")
    return proc.stdout


def main() -> int:
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="rbfmu_wheel_") as tmp:
        work = Path(tmp)
        dist = work / "dist"
        # build from a copy: setuptools writes build/ next to the sources, and build/ is
        # also where FMUs go in the checkout
        src = work / "src"
        anywhere = shutil.ignore_patterns(".git", ".venv", "*.fmu", "__pycache__", "*.egg-info", ".pytest_cache")

        def ignore(folder: str, names: list[str]) -> set[str]:
            # build/, out/ and dist/ of the checkout only: fmu/build/ is the package's build code
            top = {"build", "out", "dist"} if Path(folder) == REPO else set()
            return set(anywhere(folder, names)) | (top & set(names))

        shutil.copytree(REPO, src, ignore=ignore)
        run([sys.executable, "-m", "build", "--wheel", "--outdir", str(dist), str(src)], cwd=work)
        wheels = sorted(dist.glob("rbfmu-*.whl"))
        if len(wheels) != 1:
            sys.exit(f"wheel check failed: expected one wheel in {dist}, found {wheels}")
        venv = work / "venv"
        run([sys.executable, "-m", "venv", str(venv)], cwd=work)
        py = venv / "bin" / "python"
        run([str(py), "-m", "pip", "install", "--quiet", "-c", str(REPO / "constraints.txt"), str(wheels[0])], cwd=work)
        rbfmu = str(venv / "bin" / "rbfmu")
        run([rbfmu, "build", "symmetric_free", "--out", "fmus"], cwd=work)
        if not (work / "fmus" / "symmetric_free.fmu").is_file():
            sys.exit("wheel check failed: rbfmu build wrote no FMU")
        # the package data reached the FMU (licence file) and the version is the wheel's
        with zipfile.ZipFile(work / "fmus" / "symmetric_free.fmu") as z:
            if "documentation/licenses/license.txt" not in z.namelist():
                sys.exit("wheel check failed: the FMU carries no documentation/licenses/license.txt")
        version = run([rbfmu, "--version"], cwd=work).splitlines()[0]
        if version != f"rbfmu {wheels[0].name.split('-')[1]}":
            sys.exit(f"wheel check failed: rbfmu --version printed {version!r} for {wheels[0].name}")
        out = run([rbfmu, "run", "symmetric_free", "--stop-time", "1", "--build-dir", "fmus"], cwd=work)
        if "symmetric_free" not in out or "nan" in out.lower().replace("n/a", ""):
            sys.exit(f"wheel check failed: unexpected summary from rbfmu run:\n{out}")
        print(out)
    print(f"wheel check passed in {time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
