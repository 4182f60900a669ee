"""Output paths given on the command line, checked before any work: a directory to write into, a file to write.

Each check names the option and says what is allowed: an empty path (the current directory
by accident), a file where a directory is asked for, a directory that does not exist, a
file that cannot be written (tried by opening it, issue 39.9). Used by rbfmu's commands
(fmu.cli) and the sweep's (fmu.sweep.cli) alike.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

from modelsrc.errors import ModelInputError


def output_directory(path: str, option: str) -> Path:
    """An output directory option: refused if empty (it would be the current directory) or
    if it names a file (created if missing later)."""
    if not path.strip():
        raise ModelInputError(f"{option}: an empty path; give a directory (it is created if missing)")
    p = Path(path)
    if p.exists() and not p.is_dir():
        raise ModelInputError(f"{option} {path}: is a file; give a directory (it is created if missing)")
    return p


def output_file(path: str | None, option: str, formats: Sequence[str] = ()) -> None:
    """An output file option: not a directory, in a directory that exists, and (for a plot)
    with a suffix naming a format the writer knows."""
    if path is None:
        return
    p = Path(path)
    if p.is_dir():
        raise ModelInputError(f"{option} {path}: is a directory; give a file name")
    parent = p.resolve().parent
    if parent.exists() and not parent.is_dir():
        raise ModelInputError(f"{option} {path}: {p.parent} is a file, not a directory; give a file in a directory")
    if not parent.is_dir():
        raise ModelInputError(f"{option} {path}: the directory {p.parent} does not exist")
    check_writable(p, option)
    if formats and p.suffix.lower().lstrip(".") not in formats:
        raise ModelInputError(
            f"{option} {path}: the suffix chooses the format; give one of {', '.join('.' + f for f in formats)}"
        )


def check_writable(p: Path, option: str) -> None:
    """ModelInputError naming the option unless the file can be opened for writing now: it
    is opened (created if missing, then removed again), since permission bits alone do not
    tell (root may write anywhere by them, yet not create a file in /proc; issue 39.9)."""
    existed = p.exists()
    try:
        os.close(os.open(p, os.O_WRONLY | os.O_CREAT, 0o666))
    except OSError as e:
        raise ModelInputError(f"{option} {p}: cannot be written ({e.strerror}); give a writable file") from None
    if not existed:
        p.unlink()
