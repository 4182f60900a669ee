"""The layout rules of the code base: small modules that say what they are for, and no import cycles.

Every Python module and C file of the project starts by saying what it is for (its
docstring's or comment's first line), none is longer than MAX_LINES, no chain of
imports between the project's modules leads back to where it started (lazy imports
inside functions and imports only for type checking count too: a type shared by two
modules lives in a third that both import), and no module uses another module's
private names (`from m import _x`, `m._x`).
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


def _resolve(me: str, is_package: bool, node: ast.ImportFrom) -> str:
    """The absolute module name a `from ... import` in module `me` names."""
    if not node.level:
        return node.module or ""
    package = me if is_package else me.rpartition(".")[0]
    base = package.rsplit(".", node.level - 1)[0] if node.level > 1 else package
    return f"{base}.{node.module}" if node.module else base


def _imports(path: Path) -> set[str]:
    """Project modules imported by `path`: at module level, inside functions and under
    `if TYPE_CHECKING:` alike."""
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            out |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom):
            mod = _resolve(module_name(path), path.name == "__init__.py", node)
            out.add(mod)
            out |= {f"{mod}.{a.name}" for a in node.names}  # `from pkg import module`
    return {m for m in out if m.split(".")[0] in PACKAGES}


def _is_private(name: str) -> bool:
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def private_uses(path: Path, modules: set[str]) -> list[str]:
    """Another project module's private names that `path` uses: imported by name
    (`from m import _x`) or reached as an attribute of an imported module (`m._x`)."""
    uses = private_uses_in(path.read_text(), module_name(path), path.name == "__init__.py", modules)
    return [f"{path.relative_to(ROOT)}:{use}" for use in uses]


def private_uses_in(source: str, me: str, is_package: bool, modules: set[str]) -> list[str]:
    """`private_uses` of the source of module `me`: "line: what" per use."""
    tree = ast.parse(source)
    bound: dict[str, str] = {}  # local name -> project module it stands for
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                if a.name.split(".")[0] in PACKAGES:
                    bound[a.asname or a.name.split(".")[0]] = a.name if a.asname else a.name.split(".")[0]
        elif isinstance(node, ast.ImportFrom):
            mod = _resolve(me, is_package, node)
            if mod.split(".")[0] not in PACKAGES:
                continue
            for a in node.names:
                if f"{mod}.{a.name}" in modules:
                    bound[a.asname or a.name] = f"{mod}.{a.name}"
                elif _is_private(a.name) and mod != me:
                    found.append(f"{node.lineno}: from {mod} import {a.name}")
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and _is_private(node.attr):
            chain, base = [], node.value
            while isinstance(base, ast.Attribute):
                chain.append(base.attr)
                base = base.value
            if isinstance(base, ast.Name) and base.id in bound:
                target = ".".join([bound[base.id], *reversed(chain)])
                if target in modules and target != me:
                    found.append(f"{node.lineno}: {target}.{node.attr}")
    return found


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


def test_no_private_names_cross_modules():
    files = [p for p in python_files() if p.relative_to(ROOT).parts[0] in PACKAGES]
    modules = {module_name(p) for p in files}
    found = [use for p in files for use in private_uses(p, modules)]
    assert not found, "private names used from another module (make them public or move them):\n" + "\n".join(found)


def test_private_name_rule_sees_every_form_of_use():
    # the rule itself, on made-up source: imported by name, as an attribute of a module
    # bound by `import`, `import ... as` or `from package import module`; not a module's own
    # names, dunders, or names of modules outside the project
    modules = {"modelsrc", "modelsrc.scene", "modelsrc.model", "fmu", "fmu.cli"}
    source = """
import modelsrc.scene
import modelsrc.model as mm
from modelsrc import scene
from . import _package_helper
from .scene import _Reader, load_scene
from numpy import _private_numpy
from fmu.cli import __doc__
x = modelsrc.scene._parse_file, mm._hidden, scene._SECTION_KEYS, mm.build_model, scene.__name__
"""
    found = private_uses_in(source, "modelsrc.model_functions", False, modules)
    assert found == [
        "5: from modelsrc import _package_helper",
        "6: from modelsrc.scene import _Reader",
        "9: modelsrc.scene._parse_file",
        "9: modelsrc.model._hidden",
        "9: modelsrc.scene._SECTION_KEYS",
    ], found
    assert private_uses_in("from . import _x\n", "modelsrc", True, modules) == []  # a package's own name


def test_code_cites_docs_not_issues():
    # comments and docstrings cite docs sections or equations, never a tracker issue
    offenders = []
    for path in python_files():
        for k, line in enumerate(path.read_text().splitlines(), 1):
            low = line.lower()
            if ("the issue" in low or "issue's" in low or "issue target" in low) and "casadi" not in low:
                offenders.append(f"{path.relative_to(ROOT)}:{k}: {line.strip()}")
    assert not offenders, "\n".join(offenders)


FEATURES_PACKAGE = "modelsrc.features"


def feature_unit(module: str) -> str | None:
    """The feature unit a module belongs to (modelsrc.features.<unit>[.<module>] -> <unit>),
    None for a module outside the units (the package itself included)."""
    parts = module.split(".")
    return parts[2] if module.startswith(FEATURES_PACKAGE + ".") and len(parts) > 2 else None


def foreign_feature_imports(module: str, imports: set[str]) -> list[str]:
    """The modules of other feature units that `module` (a feature unit's) imports."""
    own = feature_unit(module)
    if own is None:
        return []
    return sorted(m for m in imports if feature_unit(m) not in (None, own))


def test_no_feature_imports_another():
    files = [p for p in python_files() if module_name(p).startswith(FEATURES_PACKAGE + ".")]
    assert len({feature_unit(module_name(p)) for p in files}) >= 2, "the feature units were not found"
    found = [
        f"{module_name(p)} (feature {feature_unit(module_name(p))}) imports {m} (feature {feature_unit(m)})"
        for p in files
        for m in foreign_feature_imports(module_name(p), _imports(p))
    ]
    assert not found, "a feature imports another (share through the Assembly or a lower module):\n" + "\n".join(found)


def test_feature_rule_sees_units_and_their_modules():
    # the rule itself, on made-up module names: a unit's own modules and the shared lower
    # modules are allowed, another unit's module (single file or folder) is not
    imports = {
        "modelsrc.assembly",
        "modelsrc.features",
        "modelsrc.features.rotors.scene_file",
        "modelsrc.features.orbit",
        "modelsrc.features.orbit.nadir_body",
    }
    assert foreign_feature_imports("modelsrc.features.rotors.feature", imports) == [
        "modelsrc.features.orbit",
        "modelsrc.features.orbit.nadir_body",
    ]
    assert foreign_feature_imports("modelsrc.features.orbit", imports) == ["modelsrc.features.rotors.scene_file"]
    assert foreign_feature_imports("modelsrc.registry", imports) == []  # not a feature unit
