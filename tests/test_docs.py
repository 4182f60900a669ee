"""The generated docs (variable reference, method tables, FMI state tables) must match the code."""

from fmu.generated_docs import SECTIONS, rendered_pages


def test_generated_docs_are_current():
    stale = [str(p) for p, text in rendered_pages().items() if p.read_text() != text]
    assert not stale, f"stale generated docs: {stale}; run `python -m fmu.generated_docs`"


def test_every_generated_section_is_used():
    # a table nobody embeds is a table nobody reads
    used = "".join(p.read_text() for p in rendered_pages())
    for name in SECTIONS:
        assert f"<!-- begin generated: {name} -->" in used, name
