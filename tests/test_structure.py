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


def module_name(path: Path, root: Path = ROOT) -> str:
    rel = path.relative_to(root).with_suffix("")
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


def _imports(path: Path, root: Path = ROOT) -> set[str]:
    """Project modules imported by `path` (a file under `root`): at module level, inside
    functions and under `if TYPE_CHECKING:` alike."""
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            out |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom):
            mod = _resolve(module_name(path, root), path.name == "__init__.py", node)
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


# ---- rooms (docs/architecture.md): what a package's top level holds, aliases, package order ----

# The modules a package's top level holds; everything else lives in a room (a sub-package).
TOP_LEVEL = {
    "fmu": ("__init__", "cli"),
    "rbcheck": ("__init__",),
    "tests": ("__init__", "conftest", "test_structure", "test_structure_c", "test_docs"),
}
ROOMS = {
    "fmu": ("build", "drive", "bench", "gendocs", "sweep", "linear", "system", "terminal"),
    "rbcheck": ("closed_forms", "exudyn", "baselines", "numerics", "checks", "workprecision"),
    "tests": ("harness", "physics", "fmi", "robustness", "build", "cli", "checks", "report", "sweep", "platforms",
              "linear", "system"),
}  # fmt: skip
# Old module paths kept until 0.5.0 (CHANGELOG.md, "Unreleased"): old module -> where its code lives.
# rbcheck.baselines is also the package of the baselines: its __init__ is the alias.
ALIASES = {
    "fmu.archive_docs": ("fmu.build.archive_docs",),
    "fmu.benchmark": ("fmu.bench.benchmark", "fmu.bench.reference", "fmu.bench.steps"),
    "fmu.build_check": ("fmu.build.build_check",),
    "fmu.build_fmu": ("fmu.build.build_fmu",),
    "fmu.codegen": ("fmu.build.codegen",),
    "fmu.compile": ("fmu.build.compile",),
    "fmu.cross_compile": ("fmu.build.cross_compile",),
    "fmu.fmi_rules": ("fmu.gendocs.fmi_rules",),
    "fmu.generated_docs": ("fmu.gendocs.generated_docs",),
    "fmu.icon": ("fmu.build.icon",),
    "fmu.licensing": ("fmu.build.licensing",),
    "fmu.model_data": ("fmu.build.model_data",),
    "fmu.model_description": ("fmu.build.model_description",),
    "fmu.options": ("fmu.drive.options",),
    "fmu.platforms": ("fmu.build.platforms",),
    "fmu.progress": ("fmu.terminal.progress",),
    "fmu.run": ("fmu.drive.run", "fmu.drive.instance", "fmu.drive.inputs"),
    "fmu.source_fmu": ("fmu.build.source_fmu",),
    "fmu.summary": ("fmu.drive.summary",),
    "fmu.versions": ("fmu.build.versions",),
    "rbcheck.baselines": ("rbcheck.baselines.rigid_body",),
    "rbcheck.baselines_gyrostat": ("rbcheck.baselines.gyrostat",),
    "rbcheck.baselines_motion": ("rbcheck.baselines.motion",),
    "rbcheck.dual_spin": ("rbcheck.closed_forms.dual_spin",),
    "rbcheck.exudyn_models": ("rbcheck.exudyn.models",),
    "rbcheck.exudyn_motion": ("rbcheck.exudyn.motion",),
    "rbcheck.exudyn_orbit": ("rbcheck.exudyn.orbit",),
    "rbcheck.exudyn_rotors": ("rbcheck.exudyn.rotors",),
    "rbcheck.frame_kinematics": ("rbcheck.closed_forms.frame_kinematics",),
    "rbcheck.free_asymmetric": ("rbcheck.closed_forms.free_asymmetric",),
    "rbcheck.free_flight": ("rbcheck.closed_forms.free_flight",),
    "rbcheck.free_symmetric": ("rbcheck.closed_forms.free_symmetric",),
    "rbcheck.gravity_gradient": ("rbcheck.closed_forms.gravity_gradient", "rbcheck.baselines.orbit"),
    "rbcheck.heavy_top": ("rbcheck.closed_forms.heavy_top",),
    "rbcheck.kepler": ("rbcheck.closed_forms.kepler",),
    "rbcheck.motion_fits": ("rbcheck.numerics.motion_fits",),
    "rbcheck.rotation_np": ("rbcheck.numerics.rotation_np",),
    "rbcheck.skewed_bar": ("rbcheck.closed_forms.skewed_bar", "rbcheck.exudyn.skewed_bar"),
    "rbcheck.slew": ("rbcheck.closed_forms.slew",),
}
# The package order: a room imports only rooms of a lower rank (rooms of one rank are
# independent). The references of rbcheck import no modelsrc and no fmu, only references of
# a lower REFERENCE_RANKS rank; the comparisons (checks, workprecision) may use any of them.
RANKS = {"modelsrc": 0, "fmu": 0, "fmu.terminal": 0, "fmu.drive": 1, "fmu.build": 2, "fmu.bench": 3,
         "fmu.gendocs": 3, "fmu.sweep": 3, "fmu.linear": 3, "fmu.system": 4, "rbcheck.checks": 5,
         "rbcheck.workprecision": 5, "fmu.cli": 6}  # fmt: skip
REFERENCE_RANKS = {"rbcheck": 0, "rbcheck.numerics": 0, "rbcheck.closed_forms": 1, "rbcheck.exudyn": 1,
                   "rbcheck.baselines": 2}  # fmt: skip
# A test module at tests/'s top level: the test room of the project room it imports most.
TEST_ROOM_OF = {"fmu.build": "build", "fmu.drive": "fmi", "fmu.bench": "report", "fmu.sweep": "sweep",
                "fmu.linear": "linear", "fmu.system": "system", "fmu.cli": "cli", "rbcheck.checks": "checks",
                "rbcheck.closed_forms": "checks", "rbcheck.exudyn": "checks", "rbcheck.baselines": "checks",
                "rbcheck.workprecision": "report", "modelsrc": "physics"}  # fmt: skip


def room_of(module: str) -> str:
    """The room of a project module: modelsrc, a package itself, a top-level module, or pkg.room."""
    parts = module.split(".")
    if parts[0] == "modelsrc" or len(parts) == 1:
        return parts[0]
    return ".".join(parts[:2])


def suggested_room(path: Path, package: str, root: Path = ROOT) -> str:
    """Where a module found at `package`'s top level belongs: the room whose modules it imports
    most (for tests: the test room of that project room), else the list of the rooms."""
    votes: dict[str, int] = {}
    for m in _imports(path, root):
        r = room_of(m)
        room = TEST_ROOM_OF.get(r) if package == "tests" else r.partition(".")[2] if r.startswith(package) else None
        if room in ROOMS[package]:
            votes[room] = votes.get(room, 0) + 1
    if votes:
        return f"{package}/{max(sorted(votes), key=votes.__getitem__)}/"
    return "one of " + ", ".join(f"{package}/{r}/" for r in ROOMS[package] if (root / package / r).is_dir())


def top_level_strays(root: Path = ROOT) -> list[str]:
    """Modules at a package's top level that are neither in TOP_LEVEL nor an alias, with their room."""
    found = []
    for package, kept in TOP_LEVEL.items():
        for path in sorted((root / package).glob("*.py")):
            if path.stem not in kept and f"{package}.{path.stem}" not in ALIASES:
                found.append(
                    f"{path.relative_to(root)}: {package}/ holds only {', '.join(kept)} and the aliases at its top "
                    f"level; put it in the room of its job: {suggested_room(path, package, root)} "
                    "(docs/architecture.md)"
                )
    return found


def alias_imports(path: Path, source: str) -> list[str]:
    """Imports of an alias (ALIASES) in `source`: the project uses the new paths itself. Importing
    a submodule of a package that is also an alias (rbcheck.baselines.gyrostat) is not one."""
    me = module_name(path)
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            mod = _resolve(me, path.name == "__init__.py", node)
            names = [mod] if any(f"{mod}.{a.name}" not in _submodules(mod) for a in node.names) else []
            names += [f"{mod}.{a.name}" for a in node.names]
        else:
            continue
        found += [
            f"{path.name}:{node.lineno}: imports {n} (now {', '.join(ALIASES[n])})" for n in names if n in ALIASES
        ]
    return found


def _submodules(package: str) -> set[str]:
    """The modules and sub-packages of a project package (none for a module)."""
    d = ROOT.joinpath(*package.split("."))
    if not d.is_dir():
        return set()
    return {f"{package}.{p.stem}" for p in d.glob("*.py")} | {f"{package}.{p.name}" for p in d.iterdir() if p.is_dir()}


def order_violations(graph: dict[str, set[str]]) -> list[str]:
    """Imports between rooms against the package order (RANKS, REFERENCE_RANKS); aliases are not rooms."""
    found = []
    for a in sorted(graph):
        if a in ALIASES:
            continue
        for b in sorted(graph[a]):
            ra, rb = room_of(a), room_of(b)
            if ra == rb or b in ALIASES:
                continue
            if ra in REFERENCE_RANKS:
                ok = rb in REFERENCE_RANKS and REFERENCE_RANKS[rb] < REFERENCE_RANKS[ra]
            elif ra in RANKS:
                uses_reference = rb in REFERENCE_RANKS and ra.startswith("rbcheck.")
                ok = uses_reference or (rb in RANKS and RANKS[rb] < RANKS[ra])
            else:
                found.append(f"{a}: its room {ra} is not in the package order (RANKS, docs/architecture.md)")
                continue
            if not ok:
                found.append(f"{a} imports {b}: {ra} may not use {rb} (the package order, docs/architecture.md)")
    return found


def test_package_top_levels_hold_only_their_modules_and_aliases():
    strays = top_level_strays()
    assert not strays, "\n".join(strays)


def test_aliases_are_thin_listed_and_not_used_inside_the_project():
    changelog = (ROOT / "CHANGELOG.md").read_text()
    unreleased = changelog[changelog.index("## Unreleased") : changelog.index("\n## [")]
    bad = []
    for old, new in ALIASES.items():
        path = ROOT.joinpath(*old.split(".")).with_suffix(".py")
        path = path if path.exists() else path.with_suffix("") / "__init__.py"
        tree = ast.parse(path.read_text())
        first = (ast.get_docstring(tree) or "").splitlines()[0]
        sources = {node.module for node in tree.body if isinstance(node, ast.ImportFrom) and node.level == 0}
        if "alias" not in first.lower() or sources - {"sys"} != set(new):
            bad.append(f"{old}: an alias says so in its first line and re-exports {new} only")
        if f"`{old}`" not in unreleased:
            bad.append(f"{old}: not listed under CHANGELOG.md's Unreleased heading")
    alias_files = {ROOT.joinpath(*old.split(".")).with_suffix(".py") for old in ALIASES}
    alias_files.add(ROOT / "rbcheck" / "baselines" / "__init__.py")
    for path in python_files():
        if path not in alias_files:
            bad += [f"{path.relative_to(ROOT)}: {use}" for use in alias_imports(path, path.read_text())]
    assert not bad, "\n".join(bad)


def test_packages_import_only_down_their_order():
    found = order_violations(import_graph())
    assert not found, "\n".join(found)


def test_room_rules_see_what_they_are_for(tmp_path):
    # the rules on made-up cases: a stray module named with its room, an alias import, an upward import
    (tmp_path / "fmu").mkdir()
    (tmp_path / "fmu" / "build").mkdir()
    (tmp_path / "fmu" / "packer.py").write_text('"""Packs."""\nfrom fmu.build.build_fmu import build_fmu\n')
    strays = top_level_strays(tmp_path)
    assert len(strays) == 1 and "put it in the room of its job: fmu/build/" in strays[0], strays
    uses = alias_imports(ROOT / "fmu" / "cli.py", "from fmu.run import run_fmu\nimport rbcheck.exudyn_models\n")
    assert [u.split(": ")[1] for u in uses] == [
        "imports fmu.run (now fmu.drive.run, fmu.drive.instance, fmu.drive.inputs)",
        "imports rbcheck.exudyn_models (now rbcheck.exudyn.models)",
    ], uses
    assert alias_imports(ROOT / "fmu" / "cli.py", "from rbcheck.baselines import gyrostat, motion\n") == []
    graph = {
        "fmu.drive.run": {"fmu.build.build_fmu", "modelsrc.scene"},
        "rbcheck.exudyn.models": {"fmu.drive.run"},
        "fmu.sweep.api": {"rbcheck.checks.common", "fmu.bench.benchmark"},
        "fmu.build.icon": {"fmu.drive.run"},
    }
    assert [v.split(":")[0] for v in order_violations(graph)] == [
        "fmu.drive.run imports fmu.build.build_fmu",
        "fmu.sweep.api imports fmu.bench.benchmark",
        "fmu.sweep.api imports rbcheck.checks.common",
        "rbcheck.exudyn.models imports fmu.drive.run",
    ]


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


def test_every_package_is_in_the_repository():
    """A folder of Python modules has an __init__.py that git tracks, or a fresh clone lacks the package.

    (An ignore pattern once kept fmu/build/__init__.py out of the repository while every
    test passed in the working copy that had it.)"""
    import shutil
    import subprocess

    if shutil.which("git") is None or not (ROOT / ".git").exists():
        pytest.skip("not a git checkout: which files git tracks cannot be read here")
    tracked = set(
        subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True, check=True).stdout.split()
    )
    folders = {p.parent for p in python_files() if p.parent != ROOT / "tools"}
    missing = [
        str((d / "__init__.py").relative_to(ROOT))
        for d in sorted(folders)
        if any(str(p.relative_to(ROOT)) in tracked for p in d.glob("*.py"))
        and str((d / "__init__.py").relative_to(ROOT)) not in tracked
    ]
    assert not missing, f"packages whose __init__.py git does not track: {missing}"
