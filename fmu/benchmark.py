"""Benchmark (a script that prints a table, not a timed test).

Per scene: ns per internal RK4 step of the generated step function in a C loop, the
same through fmi3DoStep (one long step, the layer's own overhead included), and µs
per doStep + getFloat64 of all outputs through fmpy at the scene's communication step.
Timings are from one run on this machine; compare them as ratios.
"""

from __future__ import annotations

import shutil
import subprocess
import tempfile
import time
import zipfile
from pathlib import Path

import numpy as np

from modelsrc.scene import list_scenes, load_scene

from .build_fmu import CFLAGS, GENERATED_EXTRA, build_fmu, c_sources
from .run import FmuInstance

HARNESS = Path(__file__).resolve().parent / "c" / "bench_step.c"
TARGET_NS = 150.0  # docs/report/report.md targets: <= 150 ns per RK4 internal step of the 7-state body


def c_step_ns(fmu: Path, n: int = 4_000_000) -> tuple[float, float]:
    """(raw generated step, step through fmi3DoStep) in ns per internal step."""
    with tempfile.TemporaryDirectory() as tmp:
        with zipfile.ZipFile(fmu) as z:
            z.extractall(tmp)
        src = Path(tmp) / "sources"
        exe = Path(tmp) / "bench"
        cmd = [
            "gcc",
            *[f for f in CFLAGS if f != "-fPIC"],
            *GENERATED_EXTRA,
            "-I",
            str(src),
            str(HARNESS),
            *(str(src / f) for f in c_sources(3)),
            "-o",
            str(exe),
            "-lm",
        ]
        proc = subprocess.run(cmd, capture_output=True, text=True)
        if proc.returncode != 0:
            raise RuntimeError(f"benchmark harness failed to compile:\n{proc.stderr}")
        out = subprocess.run([str(exe), str(n)], check=True, capture_output=True, text=True).stdout.split()
    return float(out[0]), float(out[1])


def fmpy_step_us(fmu: Path, h: float, n: int = 20000) -> float:
    """Median over 5 repeats of µs per doStep(h) + getFloat64(all outputs) through fmpy."""
    with FmuInstance(fmu) as inst:
        outs = [v.valueReference for v in inst.md.modelVariables if v.causality == "output"]
        inst.initialize()
        t, times = 0.0, []
        for _ in range(5):
            t0 = time.perf_counter()
            for _ in range(n):
                inst.step(t, h)
                inst.get_float64(outs)
                t += h
            times.append((time.perf_counter() - t0) / n)
    return float(np.median(times)) * 1e6


def main(out_dir: str = "build/bench") -> int:
    out = Path(out_dir)
    if shutil.which("gcc") is None:
        print("gcc is needed for the benchmark")
        return 1
    rows = []
    for name in list_scenes():
        sc = load_scene(name)
        fmu = build_fmu(sc, out)
        raw, fmi = c_step_ns(fmu)
        sub = max(1, int(np.ceil(sc.step / sc.h_max - 1e-9)))
        us = fmpy_step_us(fmu, sc.step)
        rows.append((name, raw, fmi, fmi / raw, sub, us, us * 1e3 / sub))
    print(
        f"{'scene':<16}{'raw C ns/step':>14}{'FMI ns/step':>12}{'FMI/raw':>9}{'substeps':>9}"
        f"{'fmpy us/doStep':>15}{'fmpy ns/substep':>16}"
    )
    for r in rows:
        print(f"{r[0]:<16}{r[1]:14.1f}{r[2]:12.1f}{r[3]:9.3f}{r[4]:9d}{r[5]:15.2f}{r[6]:16.1f}")
    worst = max(r[2] for r in rows)
    print(
        f"\ntarget <= {TARGET_NS:.0f} ns per RK4 internal step: worst scene {worst:.1f} ns "
        f"({'met' if worst <= TARGET_NS else 'NOT met'})"
    )
    return 0
