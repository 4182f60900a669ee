"""The co-simulation masters that run an .ssp archive: ECOS (ecospy, the default) and libcosim (libcosimpy).

Both read the archive themselves (SystemStructure.ssd, the FMUs, the .ssv parameter values)
and step every FMU; this module only opens the archive, asks for the communication points
and reads the variables there. What each does differently (docs/user_guide.md, "Systems"):
ECOS steps on a float clock t_{k+1} = t_k + H and applies the .ssv values only when the
parameter set is named at init (every component's set is called `parameters`); libcosim
steps on an integer nanosecond clock (H rounded to 1 ns is refused unless exact) and applies
them itself. ECOS needs libtbb.so.12, which its wheel lacks: the `tbb` wheel puts it in the
environment's lib/, loaded here (RTLD_GLOBAL) before `ecospy` is imported.
"""

from __future__ import annotations

import ctypes
import os
import sys
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from modelsrc.errors import ModelInputError

from ..drive.run import MAX_COMMUNICATION_POINTS
from .archive import SystemArchive

MASTERS = ("ecos", "libcosim")


@dataclass(frozen=True)
class SystemResult:
    """Values at the communication points t_k = k·H, k = 0 … n (t: (n+1,) s): one array per
    'component.variable' (the SSD's connectors: every Real input and output), and their
    units where the SSD gives them."""

    master: str
    t: np.ndarray
    values: dict[str, np.ndarray]
    units: dict[str, str] = field(default_factory=dict)


def load_tbb() -> None:
    """libtbb.so.12 from the tbb wheel (the environment's lib/), loaded globally so that
    ECOS's library finds its soname resolved; absent there, the system's is used."""
    for lib in (Path(sys.prefix) / "lib" / "libtbb.so.12", Path(sys.base_prefix) / "lib" / "libtbb.so.12"):
        if lib.is_file():
            ctypes.CDLL(str(lib), mode=ctypes.RTLD_GLOBAL)
            return


# What libcosim's FMI Library logs (as an error, on fd 1) for each FMU's `time` variable, which
# FMI 2.0 declares without a start value: harmless, and hidden (`_hidden_on_stdout`).
HARMLESS_LIBCOSIM_LINE = (
    "[FMI Library: FMI2XML] Start attribute is required for this causality, variability and initial combination"
)


@contextmanager
def _hidden_on_stdout(harmless: str) -> Iterator[None]:
    """Run the block with file descriptor 1 (where libcosim's C++ log writes) sent to a
    temporary file, then write every line of it that does not contain `harmless` to the
    real stdout: the harmless message is hidden, any other line (a real error) is shown."""
    sys.stdout.flush()
    saved = os.dup(1)
    with tempfile.TemporaryFile() as tmp:
        try:
            os.dup2(tmp.fileno(), 1)
            yield
        finally:
            try:
                libc = ctypes.CDLL(None)
                libc.fflush(None)  # C stdio's buffers, before fd 1 is restored
            except (OSError, AttributeError):
                pass
            os.dup2(saved, 1)
            os.close(saved)
            tmp.seek(0)
            kept = [line for line in tmp.read().splitlines(keepends=True) if harmless.encode() not in line]
            if kept:
                sys.stdout.flush()
                os.write(1, b"".join(kept))


def run_ecos(archive: SystemArchive, n: int) -> SystemResult:
    """n communication steps of H in ECOS; the values after init and after every step."""
    load_tbb()
    try:
        from ecospy.EcosSimulation import EcosSimulation
    except (ImportError, OSError) as exc:
        raise ModelInputError(f"--master ecos: ecospy cannot be loaded ({exc}); install rbfmu's dependencies") from None
    try:
        sim = EcosSimulation(archive.step, ssp_path=str(archive.path))
    except Exception as exc:  # ecospy raises a bare Exception with ECOS's last error
        raise ModelInputError(f"{archive.path}: ECOS cannot load the archive ({exc})") from None
    try:
        named = archive.parameter_set_name
        if not sim.init(parameter_set=named):
            raise ModelInputError(f"{archive.path}: ECOS could not initialise the system")
        names = archive.variables
        ids = [f"{c}::{v}" for c, v in (n_.split(".", 1) for n_ in names)]
        rows = np.empty((n + 1, len(names)))
        t = np.empty(n + 1)
        t[0] = sim.get_time()
        rows[0] = [sim.get_real(i) for i in ids]
        for k in range(1, n + 1):  # counted steps: step_until(T) with a float H can stop one short
            t[k] = sim.step(1)
            rows[k] = [sim.get_real(i) for i in ids]
        sim.terminate()
    finally:
        sim.free()
    return SystemResult("ecos", t, {name: rows[:, j] for j, name in enumerate(names)}, archive.units)


def run_libcosim(archive: SystemArchive, n: int) -> SystemResult:
    """n communication steps of H in libcosim (H in whole nanoseconds)."""
    try:
        from libcosimpy.CosimEnums import CosimVariableType
        from libcosimpy.CosimExecution import CosimExecution
        from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
        from libcosimpy.CosimObserver import CosimObserver
    except (ImportError, OSError) as exc:
        raise ModelInputError(f"--master libcosim: libcosimpy cannot be loaded ({exc})") from None
    step_ns = round(archive.step * 1e9)
    if abs(step_ns - archive.step * 1e9) > 1e-6 or step_ns < 1:
        raise ModelInputError(
            f"--master libcosim: its clock counts whole nanoseconds; H = {archive.step!r} s is not one"
        )
    log_output_level(CosimLogLevel.ERROR)
    try:
        with _hidden_on_stdout(HARMLESS_LIBCOSIM_LINE):  # logged while the FMUs' modelDescriptions are read
            ex = CosimExecution.from_ssp_file(str(archive.path), step_ns)
    except Exception as exc:
        raise ModelInputError(f"{archive.path}: libcosim cannot load the archive ({exc})") from None
    index = {s.name.decode(): s.index for s in ex.slave_infos()}
    refs = {c: {v.name.decode(): v.reference for v in ex.slave_variables(i)} for c, i in index.items()}
    names = archive.variables
    by_comp: dict[str, list[tuple[int, str]]] = {}
    for j, name in enumerate(names):
        c, v = name.split(".", 1)
        by_comp.setdefault(c, []).append((j, v))
    last = CosimObserver.create_last_value()
    # the values after initialisation (step 0); libcosimpy 0.0.6 returns no sample when asked for exactly one
    first = CosimObserver.create_time_series(buffer_size=8)
    ex.add_observer(observer=last)
    ex.add_observer(observer=first)
    for c, items in by_comp.items():
        for _, v in items:
            first.start_time_series(index[c], refs[c][v], CosimVariableType.REAL)
    rows = np.empty((n + 1, len(names)))
    t = np.arange(n + 1) * step_ns / 1e9
    for k in range(1, n + 1):
        if not ex.step():
            raise ModelInputError(f"{archive.path}: libcosim's step {k} failed")
        for c, items in by_comp.items():
            vals = last.last_real_values(index[c], [refs[c][v] for _, v in items])
            rows[k, [j for j, _ in items]] = vals
        if k == 1:
            for c, items in by_comp.items():
                for j, v in items:
                    rows[0, j] = first.time_series_real_samples(index[c], refs[c][v], 0, 2)[2][0]
    return SystemResult("libcosim", t, {name: rows[:, j] for j, name in enumerate(names)}, archive.units)


def _shown(v: float) -> str:
    """v as short as it prints exactly (1e+15, 0.25), else in full (0.30000000000000004)."""
    return f"{v:g}" if float(f"{v:g}") == v else repr(v)


def communication_steps(archive: SystemArchive, stop_time: float | None = None) -> int:
    """The number n of communication steps H to stop_time (default: the archive's
    DefaultExperiment stopTime), checked before anything is allocated or a master started:
    the stop time finite and a positive whole number of steps, n at most
    MAX_COMMUNICATION_POINTS (a run keeps every connector's value at each point). A refusal
    names where the stop time came from: --stop-time, or the archive's DefaultExperiment."""
    if stop_time is None:
        T, given = archive.stop_time, f"{archive.path}: its DefaultExperiment stopTime = {_shown(archive.stop_time)}"
    else:
        T, given = stop_time, f"--stop-time {_shown(stop_time)}"
    H = archive.step
    hint = "; give --stop-time to run to another time" if stop_time is None else ""
    if not (np.isfinite(T) and T > 0):
        raise ModelInputError(
            f"{given}: must be a finite time > 0 s, a whole number of communication steps H = {H} s{hint}"
        )
    ratio = T / H
    if not ratio <= MAX_COMMUNICATION_POINTS:
        raise ModelInputError(
            f"{given} s with the communication step H = {H} s makes {ratio:.3g} communication steps; a run keeps "
            f"every connector's value at each, at most {MAX_COMMUNICATION_POINTS:,}: give a shorter --stop-time, "
            "or build the system with a larger step"
        )
    n = round(ratio)
    if n < 1 or abs(n * H - T) > 1e-9 * max(1.0, T):
        raise ModelInputError(f"{given}: must be a positive whole number of communication steps H = {H} s{hint}")
    return n


def run_system(archive: SystemArchive, master: str = "ecos", stop_time: float | None = None) -> SystemResult:
    """Run the archive to stop_time (default: its DefaultExperiment) in the chosen master."""
    if master not in MASTERS:
        raise ModelInputError(f"--master {master}: choose one of {', '.join(MASTERS)}")
    n = communication_steps(archive, stop_time)
    return run_ecos(archive, n) if master == "ecos" else run_libcosim(archive, n)
