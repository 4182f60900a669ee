"""Alias until 0.5.0 (CHANGELOG.md): the code lives in fmu/gendocs/generated_docs.py."""

import sys

from fmu.gendocs.generated_docs import (
    DOCS,
    README,
    ROOT,
    SECTIONS,
    VARIABLES_DOC,
    fill_sections,
    main,
    render_call_rules,
    render_default_method,
    render_features,
    render_layout,
    render_method_limits,
    render_method_values,
    render_methods,
    render_set_rules,
    render_variables,
    rendered_pages,
)

__all__ = [
    "DOCS",
    "README",
    "ROOT",
    "SECTIONS",
    "VARIABLES_DOC",
    "fill_sections",
    "main",
    "render_call_rules",
    "render_default_method",
    "render_features",
    "render_layout",
    "render_method_limits",
    "render_method_values",
    "render_methods",
    "render_set_rules",
    "render_variables",
    "rendered_pages",
]

if __name__ == "__main__":
    sys.exit(main())
