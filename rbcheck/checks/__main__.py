"""Run ``rbfmu check`` as ``python -m rbcheck.checks [--quick] [--scene NAME_OR_PATH] [--fmu-dir DIR]``."""

from .cli import main

raise SystemExit(main())
