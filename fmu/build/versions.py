"""The version of rbfmu and of the tools it builds FMUs with (CasADi, fmpy, gcc, zig), for `rbfmu --version`."""

from __future__ import annotations

import argparse
import subprocess
import sys
from importlib import metadata

from .. import __version__

# A tool that does not answer within this time is reported as such (`rbfmu --version`
# must stay quick: `zig version` answers in about 0.2 s here).
TOOL_TIMEOUT_S = 10.0


def _distribution(name: str) -> str:
    """The installed version of a Python distribution, or why there is none."""
    try:
        return metadata.version(name)
    except metadata.PackageNotFoundError:
        return "not installed"


def _tool(cmd: list[str]) -> str:
    """The first line a version command prints, or why it printed none (missing, failed, too slow)."""
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=TOOL_TIMEOUT_S)
    except OSError as exc:
        return f"not available ({exc.strerror or exc})"
    except subprocess.TimeoutExpired:
        return f"no answer within {TOOL_TIMEOUT_S:g} s"
    first = (proc.stdout.strip() or proc.stderr.strip()).splitlines()[:1]
    if proc.returncode != 0:
        return f"not available ({first[0] if first else f'exit status {proc.returncode}'})"
    return first[0] if first else "unknown"


def version_lines() -> list[str]:
    """One line per component: rbfmu's version, then each tool's and what rbfmu uses it for."""
    ziglang = _distribution("ziglang")
    zig = _tool([sys.executable, "-m", "ziglang", "version"]) if ziglang != "not installed" else ziglang
    return [
        f"rbfmu {__version__}",
        f"CasADi {_distribution('casadi')} (generates the model's C)",
        f"fmpy {_distribution('fmpy')} (the FMI headers; runs the FMUs)",
        f"gcc {_tool(['gcc', '-dumpfullversion'])} (compiles the host's binary)",
        f"zig {zig} (ziglang {ziglang}; cross-compiles the other platforms' binaries)",
    ]


class VersionAction(argparse.Action):
    """`rbfmu --version`: prints version_lines() and exits; the tools are asked only when
    the option is given (zig runs as a subprocess), not whenever the parser is built."""

    def __init__(self, option_strings: list[str], dest: str, help: str | None = None) -> None:
        super().__init__(option_strings, dest, nargs=0, default=argparse.SUPPRESS, help=help)

    def __call__(self, parser, namespace, values, option_string=None) -> None:
        print("\n".join(version_lines()))
        parser.exit()
