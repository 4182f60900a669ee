"""The generated docs (variable reference, method tables, FMI state tables) must match the code."""

from fmu.gendocs.generated_docs import SECTIONS, rendered_pages


def test_generated_docs_are_current():
    stale = [str(p) for p, text in rendered_pages().items() if p.read_text() != text]
    assert not stale, f"stale generated docs: {stale}; run `python -m fmu.gendocs`"


def test_every_generated_section_is_used():
    # a table nobody embeds is a table nobody reads
    used = "".join(p.read_text() for p in rendered_pages())
    for name in SECTIONS:
        assert f"<!-- begin generated: {name} -->" in used, name


def test_default_method_statements_come_from_the_method_rule():
    """Issue 24.5: docs/importing.md said the default method was "rk4 unless the scene says
    otherwise" while the FMUs default to rk8 or exact_free. Every page that states the default
    embeds the section generated from modelsrc.scene.default_method (test_generated_docs_are_current
    keeps it current), and no page states another default in words."""
    import re

    from fmu.gendocs.generated_docs import DOCS, README

    for page in ("importing.md", "user_guide.md"):
        assert "<!-- begin generated: default-method -->" in (DOCS / page).read_text(), page
    wrong = re.compile(r"(rk4|rk8|gauss\d|splitting|implicit_midpoint)\s+unless the scene|default method (is )?rk4")
    for page in [README, *DOCS.glob("*.md")]:
        assert not wrong.search(page.read_text()), page


def test_the_accuracy_promise_states_what_it_covers():
    """Issue 24.4: docs/user_guide.md §2.2 promised the tolerance "whatever the communication step,
    the spin or the forcing"; with inputs held over a step a forcing that varies within it is
    integrated to first order in the step. §2.2 says so next to the promise, and states the
    estimate's floor and the importer's tolerance (issue 24.2, 24.3)."""
    from fmu.gendocs.generated_docs import DOCS

    text = (DOCS / "user_guide.md").read_text()
    section = text[text.index("## §2.2") : text.index("## §3")]
    assert "or the forcing" not in section
    for needed in ("**What the promise covers.**", "first order", "intermediate update", "input derivatives",
                   "**The estimate's floor.**", "tolerance_effective", "**The importer's tolerance.**"):  # fmt: skip
        assert needed in section, needed
