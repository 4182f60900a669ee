"""The docs that are generated must match the code."""

from fmu.variable_doc import DOC, render


def test_variable_reference_is_current():
    assert DOC.read_text() == render(), "docs/variables.md is stale: run `python -m fmu.variable_doc`"
