"""Results of a sweep on disk and on paper: the table as Parquet or CSV, and the stability map of one figure.

The map of a figure (a column of the sweep's table) over one swept variable is a line;
over two it is a heat map when the runs form a grid (one cell per run) and a scatter
plot otherwise (random samples). Runs where the figure is NaN (a crossing not reached
by the stop time, a failed run) are drawn grey (left out of a line) and counted in the
title, and so are the runs a log colour scale cannot show (values <= 0); with no value
> 0 at all a log colour scale is refused.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from modelsrc.errors import ModelInputError

from .spec import method_names

TABLE_SUFFIXES = (".parquet", ".csv")


def write_table(df: pd.DataFrame, path: str | Path) -> Path:
    """Write the sweep's table: Parquet (pandas + pyarrow, `attrs` kept in its metadata)
    or CSV, chosen by the suffix. Returns the path."""
    p = Path(path)
    if p.suffix not in TABLE_SUFFIXES:
        raise ModelInputError(f"--out {p}: the table is written as .parquet or .csv, got {p.suffix or 'no suffix'!r}")
    p.parent.mkdir(parents=True, exist_ok=True)
    if p.suffix == ".parquet":
        df.to_parquet(p)
    else:
        df.to_csv(p, float_format="%.17g", na_rep="nan")  # "" is an empty error message
    return p


@dataclass(frozen=True)
class TableFile:
    """Where a sweep's table goes, checked before any run: `path`, and `part`, a temporary
    file next to it that the table is written to and then renamed over `path` (one rename
    on the same file system), so an interrupted or failed write never leaves half a table."""

    path: Path
    part: Path

    @classmethod
    def reserve(cls, path: str | Path, overwrite: bool = False) -> TableFile:
        """Check that the table can be written at `path` (.parquet or .csv, not a directory,
        not an existing file unless `overwrite`, its folder creatable and writable) by
        creating the temporary file next to it; ModelInputError naming the path otherwise."""
        p = Path(path)
        if p.suffix not in TABLE_SUFFIXES:
            raise ModelInputError(
                f"--out {p}: the table is written as .parquet or .csv, got {p.suffix or 'no suffix'!r}"
            )
        if p.is_dir():
            raise ModelInputError(f"--out {p}: is a directory; give the table's file name (.parquet or .csv)")
        if p.exists() and not overwrite:
            raise ModelInputError(f"--out {p}: the file exists; give --overwrite to replace it, or another name")
        if p.exists() and not p.is_file():
            raise ModelInputError(f"--out {p}: exists and is not a regular file")
        try:
            p.parent.mkdir(parents=True, exist_ok=True)
            fd, part = tempfile.mkstemp(prefix=f".{p.name}.", suffix=f".part{p.suffix}", dir=p.parent)
        except OSError as exc:
            raise ModelInputError(f"--out {p}: cannot write there: {exc.strerror or exc}") from None
        os.close(fd)
        return cls(p, Path(part))

    def write(self, df: pd.DataFrame) -> Path:
        """Write the table to the temporary file, then rename it to `path`."""
        try:
            write_table(df, self.part)
            os.replace(self.part, self.path)
        finally:
            self.discard()
        return self.path

    def discard(self) -> None:
        """Remove the temporary file (nothing to write, or the write failed)."""
        with contextlib.suppress(FileNotFoundError):
            self.part.unlink()


def read_table(path: str | Path) -> pd.DataFrame:
    """Read a table written by `write_table` (index: the run number)."""
    p = Path(path)
    if p.suffix == ".parquet":
        return pd.read_parquet(p)
    df = pd.read_csv(p, index_col="run", keep_default_na=False, na_values=["nan"], dtype={"error": str})
    return df


def _edges(centres: np.ndarray, log: bool) -> np.ndarray:
    """Cell edges around sorted cell centres: midpoints (in log for log axes), the ends
    extended by half a cell."""
    c = np.log(centres) if log else centres.astype(float)
    if len(c) == 1:
        e = np.array([c[0] - 0.5, c[0] + 0.5])
    else:
        mid = 0.5 * (c[1:] + c[:-1])
        e = np.concatenate([[c[0] - (mid[0] - c[0])], mid, [c[-1] + (c[-1] - mid[-1])]])
    return np.exp(e) if log else e


def _is_grid(df: pd.DataFrame, x: str, y: str) -> bool:
    nx, ny = df[x].nunique(), df[y].nunique()
    return nx * ny == len(df) and not df.duplicated([x, y]).any()


def _axis(ax: Any, which: str, name: str, values: Any, log: bool) -> None:
    getattr(ax, f"set_{which}label")(name)
    if log:
        getattr(ax, f"set_{which}scale")("log")
    if name == "method":
        ticks = np.unique(values)
        getattr(ax, f"set_{which}ticks")(ticks, method_names(ticks.tolist()))


def plot_map(
    df: pd.DataFrame,
    color: str,
    path: str | Path,
    x: str | None = None,
    y: str | None = None,
    log_axes: Sequence[str] = (),
    log_color: bool = False,
    title: str | None = None,
    decorate: Callable[[Any], None] | None = None,
) -> Path:
    """Plot figure `color` (a column of the table) over the swept variable x, or over x and
    y (a heat map for a grid, else a scatter); default axes: the table's swept columns
    (`attrs["swept"]`, one or two). log_axes: variables drawn on a log axis; log_color: a
    log colour scale; decorate(ax): draws extra lines (closed forms, thresholds)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm, Normalize

    if color not in df.columns:
        raise ModelInputError(f"plot: {color!r} is not a column of the table; columns: {', '.join(df.columns)}")
    swept = list(df.attrs.get("swept", []))
    axes = [a for a in (x, y) if a is not None] or swept
    if not 1 <= len(axes) <= 2:
        raise ModelInputError(
            f"plot: a map is over one or two swept variables, this sweep has {len(axes)} ({', '.join(axes)}); "
            "choose them with --plot-axes X[,Y]"
        )
    for a in axes:
        if a not in df.columns:
            raise ModelInputError(f"plot: {a!r} is not a column of the table")
    values = df[color].to_numpy(dtype=float)
    finite = np.isfinite(values)
    positive = finite & (values > 0) if log_color else finite
    n_nan, n_off = int((~finite).sum()), int((finite & ~positive).sum())  # n_off: <= 0, not on a log scale
    if log_color and not positive.any():
        raise ModelInputError(
            f"plot: a log colour scale (--log-color) shows values > 0; {color} has none in the {len(df)} runs "
            f"({n_off} <= 0, {n_nan} NaN): map it without --log-color"
        )
    lo, hi = (values[positive].min(), values[positive].max()) if positive.any() else (1.0, 10.0)
    norm = LogNorm(lo, hi) if log_color else Normalize(lo, hi)
    fig, ax = plt.subplots(figsize=(7.5, 5.5))
    mesh: Any
    cmap = plt.get_cmap("viridis").with_extremes(bad="0.75")
    if len(axes) == 1:
        xs = df[axes[0]].to_numpy(dtype=float)
        order = np.argsort(xs)
        ax.plot(xs[order], values[order], "o-", ms=3)
        ax.set_ylabel(color)
        if log_color:
            ax.set_yscale("log")
        _axis(ax, "x", axes[0], xs, axes[0] in log_axes)
    else:
        xn, yn = axes
        if _is_grid(df, xn, yn):
            table = df.pivot(index=yn, columns=xn, values=color).sort_index().sort_index(axis=1)
            xc, yc = table.columns.to_numpy(dtype=float), table.index.to_numpy(dtype=float)
            z = np.ma.masked_invalid(table.to_numpy(dtype=float))
            if log_color:
                z = np.ma.masked_where(z <= 0, z)
            mesh = ax.pcolormesh(_edges(xc, xn in log_axes), _edges(yc, yn in log_axes), z, cmap=cmap, norm=norm)
        else:
            mesh = ax.scatter(df[xn], df[yn], c=np.where(positive, values, np.nan), cmap=cmap, norm=norm, s=12)
            mesh.cmap.set_bad("0.75")
            if not positive.all():
                label = "NaN or <= 0" if n_off else "NaN"
                ax.plot(df[xn][~positive], df[yn][~positive], "x", color="0.5", ms=4, label=label)
        fig.colorbar(mesh, ax=ax, label=color)
        _axis(ax, "x", xn, df[xn].to_numpy(), xn in log_axes)
        _axis(ax, "y", yn, df[yn].to_numpy(), yn in log_axes)
    if decorate is not None:
        decorate(ax)
    n_failed = int((~df["ok"]).sum()) if "ok" in df.columns else 0
    head = title or f"{df.attrs.get('scene', 'sweep')}: {color}"
    unshown = f"NaN ({n_nan} runs)" + (f", <= 0 off the log scale ({n_off} runs)" if log_color else "")
    where = "not drawn" if len(axes) == 1 else "grey"
    ax.set_title(f"{head}\n{len(df)} runs, {n_failed} failed; {where}: {unshown}", fontsize=10)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="best", fontsize=8)
    fig.tight_layout()
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out
