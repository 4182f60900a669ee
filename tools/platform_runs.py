"""Run shipped scenes' FMUs on every platform this machine can execute and compare with the host.

    python tools/platform_runs.py [SCENE ...]     (default: the rotor and orbit scenes)

For each scene: build the FMI 3.0 FMU with every platform (`platforms="all"`), then drive
each runnable binary with the C importer tests/c/fmi_import_harness.c (the one
tests/platforms/test_platforms.py uses on its small scene): the host's natively, aarch64-linux
under qemu-aarch64 (Debian qemu-user + libc6-arm64-cross), x86_64-windows under wine
(Debian wine64). Prints, per scene and platform, the largest difference of q and w_body
(and the rotor rates Omega_*) from the host binary over the scene's default experiment,
relative to the largest |value|; "bit-identical" when every printed bit agrees. A
platform whose runner is missing is reported as not run, with the reason. The macOS
binaries cannot run here (lief inspection only: tests/platforms/test_platforms.py).

Inputs are held constant over the run (the scene's start values, or SETTINGS below where
those would leave the body at rest): this checks that each binary computes the same
model, not the scene's schedule.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

import numpy as np
from fmpy import read_model_description

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from fmu.build.build_fmu import build_fmu  # noqa: E402
from fmu.build.platforms import host_platform  # noqa: E402
from modelsrc.scene import load_scene  # noqa: E402
from tests.harness.import_harness import compile_harness  # noqa: E402

DEFAULT_SCENES = ("reaction_wheel_slew", "dual_spin", "quadrotor", "gravity_gradient_boom")
# Inputs set to constants for the run (the harness holds them): without them the slew
# (wheels and body at rest, u = 0) and the hovering quadrotor would not move and the
# comparison would be blind. N m (motor torques) and rad/s (rotor speeds, rad/s^2 rates).
SETTINGS = {
    "reaction_wheel_slew": {"u_x": 0.01, "u_y": -0.02, "u_z": 0.015},
    "quadrotor": {"Omega_p1": 450.0, "Omega_p2": -440.0, "Omega_p3": 445.0, "Omega_p4": -438.0,
                  "Omega_dot_p1": 0.0, "Omega_dot_p2": 0.0, "Omega_dot_p3": 0.0, "Omega_dot_p4": 0.0},
}  # fmt: skip
PRINTED = ("q[", "w_body[", "Omega_", "x_cm[", "v_cm[")
AARCH64_SYSROOT = Path("/usr/aarch64-linux-gnu")


def _harness_args(d: Path, library: str, steps: int, step: float, settings: dict[str, float]) -> list[str]:
    md = read_model_description(str(d))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    sets = [f"{vr[name]}={value!r}" for name, value in settings.items()]
    vrs = [str(v.valueReference) for v in md.modelVariables if v.name.startswith(PRINTED) and v.type == "Float64"]
    return [library, md.instantiationToken, str(steps), repr(step), *sets, *vrs]


def _compile(d: Path, platform: str | None, exe: Path) -> None:
    """The harness for the host (platform None) or a cross platform (tests/harness/import_harness.py)."""
    proc = compile_harness(d / "sources", platform, exe)
    if proc.returncode != 0:
        raise RuntimeError(f"the harness did not compile for {platform or 'the host'}:\n{proc.stderr}")


def _parse(stdout: str) -> np.ndarray:
    return np.array([[float(x) for x in line.split()] for line in stdout.replace("\r", "").strip().splitlines()])


def run_scene(name: str, out: Path) -> list[tuple[str, str]]:
    """(platform, result) rows for one scene: the largest relative difference from the host."""
    scene = load_scene(name)
    fmu = build_fmu(scene, out, fmi_version="3", platforms="all")
    d = out / f"{name}_unpacked"
    with zipfile.ZipFile(fmu) as z:
        z.extractall(d)
    steps = round(scene.stop_time / scene.step)
    host_exe = out / f"{name}_harness"
    _compile(d, None, host_exe)
    host_lib = d / "binaries" / host_platform() / f"{name}.so"
    settings = SETTINGS.get(name, {})
    args = _harness_args(d, str(host_lib), steps, scene.step, settings)
    ref = _parse(subprocess.run([str(host_exe), *args], capture_output=True, text=True, check=True).stdout)
    moved = float(np.max(np.abs(ref[:, 1:] - ref[0, 1:])))  # 0: a run at rest, which would compare nothing
    shape = f"{ref.shape[0]} rows x {ref.shape[1] - 1} values"
    rows = [(host_platform(), f"reference: {shape}, largest change {moved:.3g}")]

    def compare(platform: str, stdout: str) -> None:
        got = _parse(stdout)
        if got.shape != ref.shape:
            rows.append((platform, f"FAILED: {got.shape} values against {ref.shape}"))
            return
        diff = float(np.max(np.abs(got - ref)) / max(float(np.max(np.abs(ref))), 1e-300))
        rows.append((platform, "bit-identical" if diff == 0.0 else f"max relative difference {diff:.1e}"))

    def run_cross(label: str, platform: str, lib: str, launcher: list[str], timeout: float, env: dict | None) -> None:
        """Compile the harness for `platform`, run it on that platform's binary through
        `launcher` (qemu or wine), compare with the host's run."""
        exe = out / (f"{name}_harness_{platform}" + (".exe" if "windows" in platform else ""))
        _compile(d, platform, exe)
        args = _harness_args(d, lib, steps, scene.step, settings)
        proc = subprocess.run([*launcher, str(exe), *args], capture_output=True, text=True, timeout=timeout, env=env)
        if proc.returncode == 0:
            compare(label, proc.stdout)
        else:
            rows.append((label, f"FAILED: {proc.stderr[-300:]}"))

    qemu = shutil.which("qemu-aarch64")
    if qemu and (AARCH64_SYSROOT / "lib").is_dir():
        lib = str(d / "binaries" / "aarch64-linux" / f"{name}.so")
        run_cross("aarch64-linux (qemu)", "aarch64-linux", lib, [qemu, "-L", str(AARCH64_SYSROOT)], 600, None)
    else:
        rows.append(("aarch64-linux", "not run: qemu-aarch64 or libc6-arm64-cross missing"))
    wine = shutil.which("wine") or shutil.which("wine64")
    if wine:
        lib = "Z:" + str(d / "binaries" / "x86_64-windows" / f"{name}.dll").replace("/", "\\")
        env = {**os.environ, "WINEDEBUG": "-all", "WINEDLLOVERRIDES": "mscoree,mshtml="}  # no Mono/Gecko prompts
        run_cross("x86_64-windows (wine)", "x86_64-windows", lib, [wine], 900, env)
    else:
        rows.append(("x86_64-windows", "not run: wine missing"))
    return rows


def main(argv: list[str]) -> int:
    names = argv or list(DEFAULT_SCENES)
    failed = False
    with tempfile.TemporaryDirectory() as tmp:
        for name in names:
            for platform, result in run_scene(name, Path(tmp)):
                print(f"{name:24s} {platform:24s} {result}", flush=True)
                failed |= result.startswith("FAILED")
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
