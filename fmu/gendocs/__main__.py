"""Entry point of `python -m fmu.gendocs`: rewrite the generated parts of docs/ and the README."""

import sys

from .generated_docs import main

sys.exit(main())
