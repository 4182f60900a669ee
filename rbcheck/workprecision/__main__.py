"""Command-line entry of the work-precision report: ``python -m rbcheck.workprecision [--quick] [--out DIR]``."""

from __future__ import annotations

import sys

from .cli import main

if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
