"""The layout rules of the C layer: each file calls only the layers below it, arguments by name.

In the C layer, each file calls only the files of the layers below its own (the table at the
top of fmu/c/rbfmu_core.h), and neither the C nor the tests address a generated function's
arguments by position (model_data.h names them: docs/fmi_layer.md).
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


# ---- the C layer: who calls whom, and how the generated functions are called ----

C_DIR = ROOT / "fmu" / "c"


def c_code(text: str, keep_lines: bool = True) -> str:
    """C source with comments and the content of string and character literals blanked out;
    keep_lines: line breaks kept (line numbers stay), else continued macro lines joined."""
    out = re.sub(r"/\*.*?\*/", lambda m: "\n" * m.group().count("\n"), text, flags=re.S)
    out = re.sub(r"//[^\n]*", "", out)
    out = re.sub(r'"(?:\\.|[^"\\\n])*"', '""', out)
    out = re.sub(r"'(?:\\.|[^'\\\n])*'", "' '", out)
    return out if keep_lines else out.replace("\\\n", " ")


def c_layers(header: str) -> dict[str, int]:
    """File -> layer, from the table "Layers:" at the top of rbfmu_core.h (1 is the top)."""
    head = header[: header.index("*/")]
    table = head[head.index("Layers:") :]
    layers = {}
    for m in re.finditer(r"^\s*\*\s+(\d+)((?:\s+rbfmu_\w+\.c)+)", table, re.M):
        layers.update({f: int(m.group(1)) for f in m.group(2).split()})
    return layers


def _functions(code: str) -> dict[str, str]:
    """Name -> body of every function defined at the top level of C code (c_code's, its
    preprocessor lines left out)."""
    code = re.sub(r"^\s*#[^\n]*", "", code, flags=re.M)
    bodies, depth, name, start = {}, 0, None, 0
    for m in re.finditer(r"[{}]", code):
        if m.group() == "{":
            if depth == 0:
                head = re.search(r"\b(\w+)\s*\([^;{}()]*\)\s*$", code[max(0, m.start() - 2000) : m.start()])
                name, start = (head.group(1) if head else None), m.end()
            depth += 1
        else:
            depth -= 1
            if depth == 0 and name:
                bodies[name] = code[start : m.start()]
                name = None
    return bodies


def _called(body: str) -> set[str]:
    return set(re.findall(r"\b(\w+)\s*\(", body))


def c_calls(sources: dict[str, str]) -> tuple[dict[str, str], dict[str, dict[str, set[str]]]]:
    """(rb_ function -> the .c file that defines it, .c file -> {rb_ function it calls -> the
    functions of its own through which it does}). The headers' inline functions and macros are
    expanded where they are used: a call through one counts as the caller's call."""
    codes = {f: c_code(t, keep_lines=False) for f, t in sources.items()}

    def macros(code: str) -> dict[str, set[str]]:  # function-like macro -> what it calls
        return {m[1]: _called(m[3]) for m in re.finditer(r"^\s*#\s*define\s+(\w+)\(([^)]*)\)(.*)$", code, re.M)}

    expand: dict[str, set[str]] = {}  # the headers' inline functions and macros -> what they call
    for f, code in codes.items():
        if f.endswith(".h"):
            expand.update({n: _called(b) for n, b in _functions(code).items()})
            expand.update(macros(code))

    def reached(names: set[str], local: dict[str, set[str]]) -> set[str]:
        seen, todo = set(), list(names)
        while todo:
            n = todo.pop()
            if n not in seen:
                seen.add(n)
                todo += local.get(n, expand.get(n, ()))
        return seen

    defined = {n: f for f, code in codes.items() if f.endswith(".c") for n in _functions(code) if n.startswith("rb_")}
    calls: dict[str, dict[str, set[str]]] = {}
    for f, code in codes.items():
        if f.endswith(".c"):
            local = macros(code)  # a file's own macros expand in it
            for caller, body in _functions(code).items():
                for callee in reached(_called(body), local):
                    if callee.startswith("rb_"):
                        calls.setdefault(f, {}).setdefault(callee, set()).add(caller)
    return defined, calls


def upward_calls(sources: dict[str, str]) -> list[str]:
    """Every call from a .c file to a function defined in a file of its own layer or one above
    (the table of rbfmu_core.h), and every .c file missing from that table."""
    layers = c_layers(sources["rbfmu_core.h"])
    defined, calls = c_calls(sources)
    found = [f"{f} is not in the layer table of rbfmu_core.h" for f in sources if f.endswith(".c") and f not in layers]
    for f, called in sorted(calls.items()):
        for callee, callers in sorted(called.items()):
            home = defined.get(callee)
            if home and home != f and f in layers and home in layers and layers[home] <= layers[f]:
                found.append(
                    f"{f} (layer {layers[f]}) calls {callee} of {home} (layer {layers[home]}), "
                    f"in {', '.join(sorted(callers))}"
                )
    return found


def fmu_c_sources() -> dict[str, str]:
    return {p.name: p.read_text() for p in sorted(C_DIR.glob("rbfmu_*.[ch]"))}


def test_c_files_call_only_the_layers_below():
    sources = fmu_c_sources()
    defined, calls = c_calls(sources)
    assert defined.get("rb_do_step") == "rbfmu_dostep.c", "definitions not read"
    assert "rb_logf" in calls["rbfmu_budget.c"] and "rb_logf" in calls["rbfmu_fmi3_absent.c"], "calls not read"
    found = upward_calls(sources)
    assert not found, "C files calling up or across a layer (rbfmu_core.h, Layers):\n" + "\n".join(found)


def test_layer_rule_sees_calls_up_direct_and_through_the_header():
    header = """/* A layer table.
 * Layers:
 *   1 rbfmu_top.c
 *   2 rbfmu_mid.c rbfmu_peer.c
 *   3 rbfmu_low.c
 */
static inline void rb_inline(void) { rb_mid(); }
#define RB_MACRO(x) rb_top(x)
"""
    sources = {
        "rbfmu_core.h": header,
        "rbfmu_top.c": "void rb_top(int x) { rb_mid(); rb_low(); }",
        "rbfmu_mid.c": 'void rb_mid(void) { rb_low(); /* rb_top() */ puts("rb_top()"); }',
        "rbfmu_peer.c": "void rb_peer(void) { rb_mid(); }",
        "rbfmu_low.c": "#define LOCAL(x) rb_peer()\nvoid rb_low(void) { rb_inline(); RB_MACRO(1); LOCAL(0); }",
        "rbfmu_new.c": "void rb_new(void) { }",
    }
    assert upward_calls(sources) == [
        "rbfmu_new.c is not in the layer table of rbfmu_core.h",
        "rbfmu_low.c (layer 3) calls rb_mid of rbfmu_mid.c (layer 2), in rb_low",
        "rbfmu_low.c (layer 3) calls rb_peer of rbfmu_peer.c (layer 2), in rb_low",
        "rbfmu_low.c (layer 3) calls rb_top of rbfmu_top.c (layer 1), in rb_low",
        "rbfmu_peer.c (layer 2) calls rb_mid of rbfmu_mid.c (layer 2), in rb_peer",
    ]


# arg[N] / res[N] (or step_arg, work.res, ...) with a literal N: a position in a generated
# function's arguments, which model_data.h names (RB_ARG_<function>_<input>, RB_RES_...)
LITERAL_ARGUMENT_INDEX = re.compile(r"\b(?:\w+_)?(?:arg|res)\s*\[\s*\d+\s*\]")


def literal_indices_in_c(text: str) -> list[int]:
    """Lines of C code that index a generated function's argument or result array by number."""
    code = c_code(text)
    return [code.count("\n", 0, m.start()) + 1 for m in LITERAL_ARGUMENT_INDEX.finditer(code)]


def positional_calls_in_python(source: str) -> list[int]:
    """Lines of Python that call a model's generated function (`model.functions[name]`, or a
    name bound to it) with positional arguments: by position, where its inputs have names
    (`f(x=..., u=...)`, which also returns the outputs by name)."""
    tree = ast.parse(source)
    tables, generated = set(), set()  # names bound to a model's `functions`, to one of them

    def is_table(node: ast.AST) -> bool:
        return (isinstance(node, ast.Attribute) and node.attr == "functions") or (
            isinstance(node, ast.Name) and node.id in tables
        )

    def is_generated(node: ast.AST) -> bool:
        return (isinstance(node, ast.Subscript) and is_table(node.value)) or (
            isinstance(node, ast.Name) and node.id in generated
        )

    for node in ast.walk(tree):  # bindings, also `a, b = fs[...], fs[...]`
        if isinstance(node, ast.Assign):
            pairs = []
            for target in node.targets:
                if isinstance(target, ast.Tuple) and isinstance(node.value, ast.Tuple):
                    pairs += zip(target.elts, node.value.elts)
                else:
                    pairs.append((target, node.value))
            for target, value in pairs:
                if isinstance(target, ast.Name) and is_table(value):
                    tables.add(target.id)
    for node in ast.walk(tree):
        if isinstance(node, ast.Assign):
            pairs = []
            for target in node.targets:
                if isinstance(target, ast.Tuple) and isinstance(node.value, ast.Tuple):
                    pairs += zip(target.elts, node.value.elts)
                else:
                    pairs.append((target, node.value))
            generated |= {t.id for t, v in pairs if isinstance(t, ast.Name) and is_generated(v)}
    return sorted(
        node.lineno for node in ast.walk(tree) if isinstance(node, ast.Call) and is_generated(node.func) and node.args
    )


def test_no_literal_index_into_a_generated_functions_arguments():
    found = []
    for path in [*C_DIR.glob("*.c"), *(ROOT / "tests" / "c").glob("*.c")]:
        found += [f"{path.relative_to(ROOT)}:{n}" for n in literal_indices_in_c(path.read_text())]
    for path in (ROOT / "tests").rglob("*.py"):
        found += [f"{path.relative_to(ROOT)}:{n}" for n in positional_calls_in_python(path.read_text())]
    assert not found, (
        "a generated function's arguments by position; use their names (C: RB_ARG_<function>_<input>, "
        "RB_RES_<function>_<output> of model_data.h, RB_BIND_MODEL; Python: f(x=..., u=...)[name]):\n"
        + "\n".join(found)
    )


def test_literal_index_rules_see_positions():
    c = """c->work.arg[0] = x;  /* arg[1] in a comment */
s->res[RB_RES_model_step_est] = &e; step_arg[ 5 ] = k;
printf("res[2]"); argv[1]; rate[0] = 1;
"""
    assert literal_indices_in_c(c) == [1, 2]
    py = """
fs = model.functions
step = model.functions["model_step_rk4"]
full, fixed = fs["a"], fs["b"]
fs["model_rhs"](x, u, p, d)
fs["model_rhs"](x=x, u=u, p=p, d=d)["xdot"]
step(*args)
fixed(**args)
other(x, u)
"""
    assert positional_calls_in_python(py) == [5, 7]


def test_api_functions_take_their_name_from_check():
    # an FMI function's messages name it through CHECK(F)'s fn or __func__, never a literal
    found = []
    for path in sorted(C_DIR.glob("rbfmu_fmi*.c")):
        text = path.read_text()
        for name, body in _functions(re.sub(r"/\*.*?\*/", " ", text, flags=re.S)).items():
            if name.startswith("fmi") and re.search(rf'"{name}\b', body):
                found.append(f"{path.name}: {name}")
    assert not found, "FMI functions that spell their own name:\n" + "\n".join(found)
