"""Instructions per step of a C loop, counted by callgrind: a run of 2N steps minus one of N.

Instruction counts do not depend on the machine's load, where times on a shared machine
vary by ±30 % (docs/report/report.md, Internal step cost in C): the benchmark compares
kernels by them and confirms with times. The difference of two runs cancels what the
program does once (loading, parsing its arguments, instantiating an FMU), leaving the
loop's own cost per step, the loop's call and bookkeeping included. valgrind is optional:
without it the counts are None and `rbfmu bench` says so in its tables.
"""

from __future__ import annotations

import re
import shutil
import subprocess
from collections.abc import Callable, Mapping, Sequence

# what `rbfmu bench` prints in place of the counts when valgrind is absent
MISSING = "valgrind not found on PATH: no instruction counts (install valgrind; times only, which vary with the load)"


def have_valgrind() -> bool:
    """True when `valgrind` is on PATH."""
    return shutil.which("valgrind") is not None


def instructions(cmd: list[str], options: Sequence[str] = (), env: Mapping[str, str] | None = None) -> int:
    """Instructions the program `cmd` executes (callgrind's Ir, the whole run, or only inside
    the functions callgrind `options` such as --toggle-collect=FN name); `env`: the program's
    environment (None: this process's)."""
    proc = subprocess.run(
        ["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null", *options, *cmd],
        capture_output=True,
        text=True,
        env=None if env is None else dict(env),
    )
    found = re.findall(r"Collected : (\d+)", proc.stderr)
    if proc.returncode != 0 or not found:
        raise RuntimeError(f"callgrind failed on {cmd[0]} (exit {proc.returncode}):\n{proc.stderr[-2000:]}")
    return int(found[-1])


def per_step(command: Callable[[int], list[str]], n: int) -> float | None:
    """Instructions per step of the program that `command(k)` runs for k steps: (I(2n) −
    I(n)) / n; None without valgrind."""
    if not have_valgrind():
        return None
    return (instructions(command(2 * n)) - instructions(command(n))) / n
