"""The layout rules of the code base: small modules that say what they are for, and no import cycles.

Every Python module and C file of the project starts by saying what it is for (its
docstring's or comment's first line), none is longer than MAX_LINES, and no chain of
imports between the project's modules leads back to where it started (lazy imports
inside functions count too; imports only for type checking do not).
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PACKAGES = ("modelsrc", "fmu", "rbcheck")
MAX_LINES = 600


def python_files() -> list[Path]:
    files = [p for d in (*PACKAGES, "tests", "tools") for p in (ROOT / d).rglob("*.py")]
    return sorted(p for p in files if "__pycache__" not in p.parts)


def c_files() -> list[Path]:
    return sorted([*(ROOT / "fmu" / "c").glob("*.[ch]"), *(ROOT / "tests" / "c").glob("*.c")])


def module_name(path: Path) -> str:
    rel = path.relative_to(ROOT).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


@pytest.mark.parametrize("path", python_files() + c_files(), ids=lambda p: str(p.relative_to(ROOT)))
def test_module_is_small_and_says_what_it_is_for(path):
    text = path.read_text()
    n = text.count("\n")
    assert n <= MAX_LINES, f"{path.name} has {n} lines (at most {MAX_LINES}): split it by concern"
    if path.suffix == ".py":
        doc = ast.get_docstring(ast.parse(text), clean=False)
        first = (doc or "").strip().splitlines()[0] if doc and doc.strip() else ""
    else:
        first = text.lstrip().removeprefix("/*").strip().splitlines()[0].rstrip("*/ ") if text.startswith("/*") else ""
    assert len(first) >= 20 and first.endswith("."), (
        f"{path.name}: the first line must be a sentence saying what the module is for, got {first!r}"
    )


def _imports(path: Path) -> set[str]:
    """Project modules imported by `path` (module level and inside functions; not those
    under `if TYPE_CHECKING:`)."""
    tree = ast.parse(path.read_text())
    skip: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            skip |= {id(n) for n in ast.walk(node)}
    me = module_name(path)
    package = me if path.name == "__init__.py" else me.rpartition(".")[0]
    out = set()
    for node in ast.walk(tree):
        if id(node) in skip:
            continue
        if isinstance(node, ast.Import):
            out |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.rsplit(".", node.level - 1)[0] if node.level > 1 else package
                mod = f"{base}.{node.module}" if node.module else base
            else:
                mod = node.module or ""
            out.add(mod)
            out |= {f"{mod}.{a.name}" for a in node.names}  # `from pkg import module`
    return {m for m in out if m.split(".")[0] in PACKAGES}


def import_graph() -> dict[str, set[str]]:
    files = [p for p in python_files() if p.relative_to(ROOT).parts[0] in PACKAGES]
    modules = {module_name(p): p for p in files}
    graph = {}
    for name, path in modules.items():
        graph[name] = {m for m in _imports(path) if m in modules and m != name}
    return graph


def test_no_import_cycles():
    graph = import_graph()
    assert graph.get("fmu.cli"), "the import graph was not read"
    # Tarjan's strongly connected components: any component with two or more modules is a cycle
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    cycles: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                cycles.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    assert not cycles, f"import cycles: {cycles}"


def test_code_cites_docs_not_issues():
    # comments and docstrings cite docs sections or equations, never a tracker issue
    offenders = []
    for path in python_files():
        for k, line in enumerate(path.read_text().splitlines(), 1):
            low = line.lower()
            if ("the issue" in low or "issue's" in low or "issue target" in low) and "casadi" not in low:
                offenders.append(f"{path.relative_to(ROOT)}:{k}: {line.strip()}")
    assert not offenders, "\n".join(offenders)
