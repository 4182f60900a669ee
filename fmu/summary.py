"""Alias until 0.5.0 (CHANGELOG.md): the code lives in fmu/drive/summary.py."""

from fmu.drive.summary import (
    Panel,
    body_axis_world,
    conserved,
    format_table,
    plot_run,
    plot_series,
    summarize,
    translation_summary,
    write_csv,
)

__all__ = [
    "Panel",
    "body_axis_world",
    "conserved",
    "format_table",
    "plot_run",
    "plot_series",
    "summarize",
    "translation_summary",
    "write_csv",
]
