"""Progress bars for long jobs (report, checks, sweeps) that read well on a terminal and in a log file.

On a terminal this is a plain tqdm bar redrawn in place. When stderr is a file or a pipe
(CI logs, `make demo > log`), tqdm's carriage-return redraws would pile up into one
enormous line, so the bar is instead written as whole lines, at most one every
`log_interval` seconds, plus the final state.
"""

from __future__ import annotations

import sys
from typing import IO, Any

from tqdm import tqdm


class _LineWriter:
    """A file-like target for tqdm that turns each redraw ('\\r' + bar) into one line."""

    def __init__(self, stream: IO[str]):
        self.stream = stream

    def write(self, text: str) -> None:
        line = text.replace("\r", "").rstrip()
        if line:
            self.stream.write(line + "\n")

    def flush(self) -> None:
        self.stream.flush()


class _LogBar(tqdm):
    """In a log, a new description or postfix waits for the next timed line."""

    def set_postfix_str(self, s: str = "", refresh: bool = True) -> None:
        super().set_postfix_str(s, refresh=False)

    def set_description_str(self, desc: str | None = None, refresh: bool = True) -> None:
        super().set_description_str(desc, refresh=False)


def progress_bar(
    total: int | None, desc: str = "", unit: str = "it", stream: IO[str] | None = None, log_interval: float = 10.0
) -> tqdm[Any]:
    """A tqdm progress bar on `stream` (default stderr): live on a terminal, one line per
    `log_interval` seconds otherwise. Use `.update(n)`, `.set_postfix_str(...)`, `.close()`."""
    out = sys.stderr if stream is None else stream
    if out.isatty():
        return tqdm(total=total, desc=desc, unit=unit, file=out, dynamic_ncols=True, leave=True)
    return _LogBar(
        total=total,
        desc=desc,
        unit=unit,
        file=_LineWriter(out),
        mininterval=log_interval,
        maxinterval=log_interval * 6,
        ncols=110,
        leave=True,
    )
