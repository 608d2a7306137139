"""Import cycles of the project's packages, module- and package-level, from the source alone.

Every ``import`` / ``from ... import`` in ``sim/``, ``autonomy/`` and ``scenarios/`` (at any
level of a module: a function-level import counts, since it still couples the two modules;
``if TYPE_CHECKING:`` imports do not) is an edge between modules (a package's ``__init__``
re-exporting its own modules is not a cycle: a submodule is not taken to import its
package). A module-level cycle is a strongly connected set of modules; a
package-level cycle is one of packages (``sim.features`` -> ``sim.mission`` -> ``sim.features``).

Usage: ``python scripts/import_cycles.py [--functions]`` prints each cycle and the counts;
exit status 1 when there is one. ``--functions`` also lists the function-level imports.
"""

from __future__ import annotations

import argparse
import ast
import sys
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("sim", "autonomy", "scenarios")


def module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _type_checking_blocks(tree: ast.AST) -> set[int]:
    ids = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            for sub in ast.walk(node):
                ids.add(id(sub))
    return ids


def imports(path: Path, modules: set[str]) -> tuple[set[str], list[tuple[int, str]]]:
    """(modules imported, (line, module) of the function-level imports)."""
    tree = ast.parse(path.read_text())
    skip = _type_checking_blocks(tree)
    me = module_name(path)
    pkg = me if path.name == "__init__.py" else me.rpartition(".")[0]
    out: set[str] = set()
    local: list[tuple[int, str]] = []
    funcs = [n for n in ast.walk(tree) if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))]
    in_func = {id(s) for f in funcs for s in ast.walk(f) if s is not f}
    for node in ast.walk(tree):
        if id(node) in skip:
            continue
        names: list[str] = []
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                base = ".".join(pkg.split(".")[: len(pkg.split(".")) - node.level + 1] + ([base] if base else []))
            subs = [f"{base}.{a.name}" for a in node.names]
            # ``from pkg import module`` imports the module (and runs the package's __init__, which
            # is not taken as a dependency, as for any submodule)
            names = subs if all(s in modules for s in subs) else [base, *subs]
        for name in names:
            while name and name not in modules:
                name = name.rpartition(".")[0]
            if name and name != me:
                out.add(name)
                if id(node) in in_func:
                    local.append((node.lineno, name))
    return out, local


def graph() -> tuple[dict[str, set[str]], dict[str, list[tuple[int, str]]]]:
    files = [p for pkg in PACKAGES for p in (ROOT / pkg).rglob("*.py")]
    modules = {module_name(p) for p in files}
    edges: dict[str, set[str]] = {}
    local: dict[str, list[tuple[int, str]]] = {}
    for p in files:
        m = module_name(p)
        edges[m], local[m] = imports(p, modules)
    return edges, local


def cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected sets of more than one node (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []
    sys.setrecursionlimit(10000)

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in edges.get(v, ()):
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
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(edges):
        if v not in index:
            visit(v)
    return out


def package_of(module: str, edges: dict[str, set[str]]) -> str:
    """The package a module lives in (a package's ``__init__`` is its own package)."""
    is_pkg = any(m.startswith(module + ".") for m in edges)
    return module if is_pkg else module.rpartition(".")[0] or module


def package_edges(edges: dict[str, set[str]]) -> dict[str, set[str]]:
    out: dict[str, set[str]] = defaultdict(set)
    for m, targets in edges.items():
        a = package_of(m, edges)
        for t in targets:
            b = package_of(t, edges)
            if a != b and not a.startswith(b + ".") and not b.startswith(a + "."):
                out[a].add(b)
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--functions", action="store_true", help="also list the function-level imports")
    args = ap.parse_args(argv)
    edges, local = graph()
    mod_cycles = cycles(edges)
    pkg_cycles = cycles(package_edges(edges))
    for c in mod_cycles:
        print("module cycle:", " <-> ".join(c))
    for c in pkg_cycles:
        print("package cycle:", " <-> ".join(c))
    if args.functions:
        for m, items in sorted(local.items()):
            for line, target in items:
                print(f"function-level import: {m}:{line} -> {target}")
    print(f"{len(mod_cycles)} module cycles, {len(pkg_cycles)} package cycles "
          f"({len(edges)} modules, {sum(len(v) for v in local.values())} function-level imports)")
    return 1 if mod_cycles or pkg_cycles else 0


if __name__ == "__main__":
    raise SystemExit(main())
