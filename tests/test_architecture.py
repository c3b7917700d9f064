"""The architecture of ``flexnet_fe`` as a test (issue 14, "Done when"), read from the source
with ``ast`` — nothing of ours is imported, so it runs in well under a second.

Rules (the layers come from the README's "Code layout" table, their one home):
  (a) no function or method longer than ``MAX_LINES`` lines (``def`` to its last line);
  (b) no numba-compiled function (``@njit``, ``@numba.njit``, ``@jit``, …) with more than
      ``MAX_KERNEL_POSITIONAL`` positional parameters — a kernel takes model/state records;
  (c) no import cycle between modules, nor between the physics packages;
  (d) layering, base → physics → run → report → interface, every import points down:
      - the base imports nothing of ours but ``flexnet_fe.errors``;
      - a physics package never imports the run layer, the report or the interface, with one
        stated exception: ``flexnet_fe.runs`` (the run-directory contract; stdlib and base only)
        for the file names its stage writes;
      - the report reads the run directory: it imports no physics package;
      - the run layer never imports the report or the interface;
  (e) every run-directory file name of ``flexnet_fe.runs`` is written there once: no other module
      spells it as a string literal (it imports the constant);
  (f) no function body written twice: two functions whose bodies (docstring aside) are the same
      syntax tree, beyond a few lines, are one law or loop in two homes. (Copies with renamed
      variables are the ``duplicates`` tool's to find, see /work/.library; this is the floor.)
Every import counts, also one inside a function (a lazy import is still an arrow).

Known violations sit in the allowlists below, each with the helper who owns the file; the lead
removes an entry when the owner's branch lands. A stale entry (the violation is gone) fails too,
so the lists only shrink.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PKG = ROOT / "flexnet_fe"

MAX_LINES = 80
MAX_KERNEL_POSITIONAL = 8
LAYERS = ("base", "physics", "run", "report", "interface")
RUN_CONTRACT = "flexnet_fe.runs"
BASE_ALLOWED = {"flexnet_fe.errors"}

LONG_FUNCTIONS: dict[str, str] = {
    # "module:qualname": "owner — why"  (none today)
}

WIDE_KERNELS: dict[str, str] = {
}

UPWARD_IMPORTS: dict[tuple[str, str], str] = {
}

FILE_NAME_LITERALS: dict[tuple[str, str], str] = {
}

TWIN_FUNCTIONS: dict[frozenset, str] = {
}
MIN_TWIN_NODES = 40
"""Smallest body (AST nodes) counted as a twin: about four lines of arithmetic."""


# --------------------------------------------------------------------------- the source tree


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES: dict[str, Path] = {_module_name(p): p for p in sorted(PKG.rglob("*.py"))}
TREES: dict[str, ast.Module] = {m: ast.parse(p.read_text(), filename=str(p)) for m, p in MODULES.items()}


def _imports(module: str) -> set[str]:
    """Modules of ours that ``module`` imports (``from pkg import sub`` → ``pkg.sub`` when sub is
    a module, else ``pkg``), anywhere in the file."""
    is_pkg = MODULES[module].name == "__init__.py"
    here = module.split(".") if is_pkg else module.split(".")[:-1]
    out: set[str] = set()
    for node in ast.walk(TREES[module]):
        if isinstance(node, ast.Import):
            out |= {a.name for a in node.names if a.name.split(".")[0] == "flexnet_fe"}
        elif isinstance(node, ast.ImportFrom):
            base = ".".join(here[:len(here) - node.level + 1] + [node.module or ""]).strip(".") if node.level \
                else (node.module or "")
            if base.split(".")[0] != "flexnet_fe":
                continue
            for a in node.names:
                out.add(f"{base}.{a.name}" if f"{base}.{a.name}" in MODULES else base)
    out.discard(module)
    return {m for m in out if m in MODULES}


GRAPH = {m: _imports(m) for m in MODULES}


def _layer_table() -> dict[str, str]:
    """README "Code layout": path prefix (``flexnet_fe/net/``, ``flexnet_fe/io.py``) → layer."""
    section = (ROOT / "README.md").read_text().split("## Code layout", 1)[1].split("\n## ", 1)[0]
    table = {}
    for line in section.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) >= 2 and cells[0].lower() in LAYERS:
            for path in re.findall(r"`(flexnet_fe/[\w/.]+)`", cells[1]):
                table[path] = cells[0].lower()
    return table


LAYER_OF_PATH = _layer_table()


def layer(module: str) -> str:
    """The README layer of a module: its own row, or its top-level package's row."""
    parts = module.split(".")
    if len(parts) == 1:
        return "base"  # the package's __init__ (version only)
    for key in (f"flexnet_fe/{parts[1]}.py", f"flexnet_fe/{parts[1]}/"):
        if key in LAYER_OF_PATH:
            return LAYER_OF_PATH[key]
    raise AssertionError(f"{module}: no layer in the README's code layout table (add a row)")


def _functions():
    """(module, qualified name, node) of every function and method."""
    def walk(module, node, prefix):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
                yield module, prefix + child.name, child
                yield from walk(module, child, prefix + child.name + ".")
            elif isinstance(child, ast.ClassDef):
                yield from walk(module, child, prefix + child.name + ".")
            else:
                yield from walk(module, child, prefix)
    for m, tree in TREES.items():
        yield from walk(m, tree, "")


def _is_jit(decorator: ast.expr) -> bool:
    target = decorator.func if isinstance(decorator, ast.Call) else decorator
    name = target.attr if isinstance(target, ast.Attribute) else getattr(target, "id", "")
    return name in {"njit", "jit", "generated_jit", "vectorize", "guvectorize", "cfunc"}


def _check_allowlist(found: dict, allow: dict, what: str) -> None:
    new = sorted(set(found) - set(allow))
    stale = sorted(set(allow) - set(found))
    assert not new, f"{what}:\n  " + "\n  ".join(f"{k}: {found[k]}" for k in new)
    assert not stale, f"allowlist entries no longer needed (remove them): {stale}"


# --------------------------------------------------------------------------- the rules


def test_no_function_longer_than_80_lines():
    found = {f"{m}:{q}": f"{n.end_lineno - n.lineno + 1} lines ({MODULES[m].relative_to(ROOT)}:{n.lineno})"
             for m, q, n in _functions() if n.end_lineno - n.lineno + 1 > MAX_LINES}
    _check_allowlist(found, LONG_FUNCTIONS, f"functions over {MAX_LINES} lines")


def test_no_compiled_kernel_with_more_than_8_positional_parameters():
    found = {}
    for m, q, n in _functions():
        npos = len(n.args.posonlyargs) + len(n.args.args)
        if any(_is_jit(d) for d in n.decorator_list) and npos > MAX_KERNEL_POSITIONAL:
            found[f"{m}:{q}"] = f"{npos} positional parameters ({MODULES[m].relative_to(ROOT)}:{n.lineno})"
    _check_allowlist(found, WIDE_KERNELS, f"numba kernels with more than {MAX_KERNEL_POSITIONAL} positional "
                                          "parameters (pass model/state records)")


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one node, or a self-loop (Tarjan)."""
    index, low, stack, on, out, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1 or v in graph.get(v, ()):
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_no_import_cycle_between_modules():
    assert not _cycles(GRAPH), f"import cycles: {_cycles(GRAPH)}"


def test_no_import_cycle_between_physics_packages():
    pkg = lambda m: ".".join(m.split(".")[:2])
    graph: dict[str, set[str]] = {}
    for m, deps in GRAPH.items():
        if layer(m) == "physics":
            graph.setdefault(pkg(m), set()).update(pkg(d) for d in deps if layer(d) == "physics" and pkg(d) != pkg(m))
    assert not _cycles(graph), f"physics packages import each other in a cycle: {_cycles(graph)}"


def _violations() -> dict[tuple[str, str], str]:
    rank = {name: i for i, name in enumerate(LAYERS)}
    bad = {}
    for m, deps in GRAPH.items():
        lm = layer(m)
        for d in sorted(deps):
            ld = layer(d)
            if lm == "base" and d not in BASE_ALLOWED and m != "flexnet_fe":
                bad[(m, d)] = f"the base imports {ld} module {d}"
            elif d == RUN_CONTRACT and lm == "physics":
                continue  # the stated exception: run-directory file names
            elif lm == "report" and ld == "physics":
                bad[(m, d)] = "the report imports a physics module (read the run directory instead)"
            elif rank[ld] > rank[lm]:
                bad[(m, d)] = f"upward import: {lm} → {ld}"
    return bad


def test_layering():
    _check_allowlist(_violations(), UPWARD_IMPORTS, "imports against the layering")


def test_run_contract_and_package_root_stay_at_the_bottom():
    """``runs`` may be imported by physics only because it imports nothing above the base; the
    package root imports nothing of ours."""
    assert {layer(d) for d in GRAPH[RUN_CONTRACT]} <= {"base"}, GRAPH[RUN_CONTRACT]
    assert not GRAPH["flexnet_fe"], GRAPH["flexnet_fe"]


def test_every_module_has_a_layer():
    for m in MODULES:
        layer(m)


def test_run_directory_file_names_have_one_home():
    names = {n.value.value: n.targets[0].id for n in TREES[RUN_CONTRACT].body
             if isinstance(n, ast.Assign) and isinstance(n.value, ast.Constant) and isinstance(n.value.value, str)
             and re.fullmatch(r"[\w.]+\.[a-z0-9]+", n.value.value)}
    assert {"summary.json", "status.json", "history.csv", "fin_contacts.npz"} <= set(names)
    found = {(m, n.value): f"literal {n.value!r} at {MODULES[m].relative_to(ROOT)}:{n.lineno} (runs.{names[n.value]})"
             for m, tree in TREES.items() if m != RUN_CONTRACT for n in ast.walk(tree)
             if isinstance(n, ast.Constant) and isinstance(n.value, str) and n.value in names}
    _check_allowlist(found, FILE_NAME_LITERALS, "run-directory file names spelled outside flexnet_fe.runs")


def test_no_function_body_written_twice():
    bodies: dict[str, list[str]] = {}
    for m, q, n in _functions():
        body = n.body[1:] if ast.get_docstring(n) is not None else n.body
        tree = ast.Module(body=body, type_ignores=[])
        if sum(1 for _ in ast.walk(tree)) >= MIN_TWIN_NODES:
            bodies.setdefault(ast.dump(tree), []).append(f"{m}:{q}")
    found = {frozenset(v): "the same body in " + ", ".join(sorted(v)) for v in bodies.values() if len(v) > 1}
    _check_allowlist(found, TWIN_FUNCTIONS, "functions written twice (keep one, import it)")
