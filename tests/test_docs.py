"""The generated docs (variable reference, method tables, FMI state tables) must match the code.

Also: every citation of docs/user_guide.md §N points to a heading that exists, and the guide's
tables of the Python API (§4.1) hold every keyword argument of the functions they document.
"""

import inspect
import re
from pathlib import Path

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


GUIDE = Path(__file__).resolve().parent.parent / "docs" / "user_guide.md"
CITATION = re.compile(r"user_guide(?:\.md)?,? (?:§|section )(\d+(?:\.\d+)*)")


def _guide_sections() -> set[str]:
    return set(re.findall(r"(?m)^#{2,3} §(\d+(?:\.\d+)*)[ :]", GUIDE.read_text()))


def test_every_user_guide_citation_points_to_a_heading_that_exists():
    root = GUIDE.parent.parent
    dirs, kinds = ("modelsrc", "fmu", "rbcheck", "tests", "tools", "docs"), (".py", ".c", ".h", ".md")
    files = [root / "README.md", *(p for d in dirs for p in (root / d).rglob("*") if p.suffix in kinds)]
    cited = {(m.group(1), str(f.relative_to(root))) for f in files for m in CITATION.finditer(f.read_text())}
    assert len(cited) > 20  # the pattern finds the citations (about 40 files cite the guide)
    sections = _guide_sections()
    missing = sorted((n, f) for n, f in cited if n not in sections)
    assert not missing, f"cited sections of docs/user_guide.md without a heading: {missing}"


def _api_functions():
    from fmu.build.build_fmu import build_fmu, ensure_fmu
    from fmu.drive.run import run_fmu, simulate
    from fmu.sweep.api import sample_runs, sweep

    return {
        "fmu.drive.run.run_fmu": run_fmu,
        "fmu.drive.run.simulate": simulate,
        "fmu.build.build_fmu.build_fmu": build_fmu,
        "fmu.build.build_fmu.ensure_fmu": ensure_fmu,
        "fmu.sweep.api.sweep": sweep,
        "fmu.sweep.api.sample_runs": sample_runs,
    }


def test_every_argument_of_the_python_api_is_in_the_guides_tables():
    text = GUIDE.read_text()
    api = text[text.index("## §4.1 ") : text.index("\n## ", text.index("## §4.1 ") + 1)]
    # the tables' first cells: `name` or `a`, `b`, under the function's bold heading
    blocks = re.split(r"(?m)^\*\*`", api)[1:]
    documented: dict[str, set[str]] = {}
    for block in blocks:
        name = block[: block.index("(")]
        cells = re.findall(r"(?m)^\| ([^|]+) \|", block)
        documented[name] = {arg for cell in cells for arg in re.findall(r"`(\w+)`", cell)}
    documented["fmu.build.build_fmu.ensure_fmu"] = documented.get("fmu.build.build_fmu.build_fmu", set())
    for name, fn in _api_functions().items():
        assert name in documented, f"docs/user_guide.md §4.1 has no table for {name}"
        params = set(inspect.signature(fn).parameters)
        missing = sorted(params - documented[name])
        assert not missing, f"{name}: arguments not in docs/user_guide.md §4.1: {missing}"
