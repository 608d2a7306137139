"""Import cycles of the project's packages, module- and package-level, from the source alone.

Every ``import`` / ``from ... import`` in ``sim/``, ``autonomy/`` and ``scenarios/`` (at any
level of a module: a function-level import counts, since it still couples the two modules;
``if TYPE_CHECKING:`` imports do not) is an edge between modules (a package's ``__init__``
re-exporting its own modules is not a cycle: a submodule is not taken to import its
package). A module-level cycle is a strongly connected set of modules; a
package-level cycle is one of packages (``sim.features`` -> ``sim.mission`` -> ``sim.features``).

Usage: ``python scripts/import_cycles.py [--functions] [--audit]`` prints each cycle and the
counts; exit status 1 when there is one. ``--functions`` also lists the function-level
imports. ``--audit`` says, for each function-level import of a project module, which of the
costly third-party packages (:data:`COSTLY`) a module-level import would load in addition to
those the importing module already loads (its start-up time: the reason for importing inside
the function), or the reason it is kept (:data:`KEPT`, :data:`WORKER_MODULES`); one that
defers none is listed as ``defers nothing`` (exit status 1: it belongs at the top of its
module).
"""

from __future__ import annotations

import argparse
import ast
import sys
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("sim", "autonomy", "scenarios")
#: Third-party packages whose import costs start-up time (tens of ms to seconds) or that an
#: optional extra provides: a function-level import that keeps one of them out of a module's
#: start-up is justified.
COSTLY = frozenset({
    "bluerobotics_ping", "brping", "cv2", "dm_control", "dm_env", "gymnasium", "matplotlib",
    "mcap", "mujoco", "numba", "onnx", "onnxruntime", "pycocotools", "pydantic", "pyproj", "pyxtf", "rasterio",
    "ray", "rerun", "rosbags", "scipy", "skimage", "sklearn", "torch", "tqdm", "trimesh", "yaml",
})
#: Third-party packages whose subpackages load separately and cost differently (``scipy.special``
#: is light, ``scipy.stats`` is not): a module loads ``scipy.stats``, not ``scipy``.
SUBPACKAGES = frozenset({"scipy"})


def _third_party_name(module: str) -> str:
    parts = module.split(".")
    return ".".join(parts[:2]) if parts[0] in SUBPACKAGES and len(parts) > 1 else parts[0]


def is_costly(name: str) -> bool:
    """Whether loading third-party ``name`` (a package, or a subpackage of :data:`SUBPACKAGES`)
    costs start-up time."""
    return name.split(".")[0] in COSTLY and name not in LIGHT


#: Subpackages of costly packages that cost little.
LIGHT = frozenset({"scipy.special", "scipy.linalg"})

#: Function-level imports kept for another reason than a costly third-party package: (module,
#: target) -> why.
KEPT = {
    ("sim.cli", "sim.cli.app"): "inside main's KeyboardInterrupt guard: Ctrl-C while the libraries load exits 130",
}
#: Modules whose function-level imports keep a spawned worker's start-up to what its job needs
#: (project modules too: a dataset worker loads no navigation filter, estimation role or target
#: mesh it does not use; ``tests/sim/dataset/test_worker_imports.py`` checks what they load).
WORKER_MODULES = {
    "sim.dataset.generate": "dataset driver and workers: each job imports only its sensor's modules",
    "sim.dataset.randomization": "dataset driver: target meshes only in the jobs that build them",
    "sim.dataset.scene_render": "dataset workers: the scene and ray caster only in the FLS jobs",
    "sim.dataset.sss_generate": "dataset workers: the scene and ray caster only in the side-scan jobs",
    "sim.process.sonar_workers": "sonar pipeline workers: each worker imports only its stage's modules",
}


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


def lazy_attributes(path: Path) -> dict[str, str]:
    """Attribute -> submodule of a package whose ``__init__`` resolves names on first use
    (``lazy_loader.attach(__name__, submod_attrs={...})``): ``from pkg import name`` then imports
    ``pkg.submodule``."""
    out: dict[str, str] = {}
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Call) and ast.unparse(node.func).endswith("attach"):
            for kw in node.keywords:
                if kw.arg == "submod_attrs" and isinstance(kw.value, ast.Dict):
                    for k, v in zip(kw.value.keys, kw.value.values):
                        for name in ast.literal_eval(v):
                            out[name] = ast.literal_eval(k)
    return out


#: package -> its lazily resolved attributes (filled by :func:`graph`).
_LAZY: dict[str, dict[str, str]] = {}


def imports(path: Path, modules: set[str]) -> tuple[set[str], list[tuple[int, str]], set[str]]:
    """(modules imported, (line, module) of the function-level imports, top-level names of the
    third-party packages imported at module level)."""
    tree = ast.parse(path.read_text())
    skip = _type_checking_blocks(tree)
    me = module_name(path)
    pkg = me if path.name == "__init__.py" else me.rpartition(".")[0]
    out: set[str] = set()
    local: list[tuple[int, str]] = []
    third: set[str] = set()
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
            lazy = _LAZY.get(base, {})
            subs = [f"{base}.{lazy[a.name]}" if a.name in lazy else f"{base}.{a.name}" for a in node.names]
            # ``from pkg import module`` imports the module (and runs the package's __init__, which
            # is not taken as a dependency, as for any submodule)
            names = subs if all(s in modules for s in subs) else [base, *subs]
        if id(node) not in in_func:
            if isinstance(node, ast.Import):
                third.update(_third_party_name(a.name) for a in node.names)
            elif isinstance(node, ast.ImportFrom) and not node.level and node.module:
                if node.module in SUBPACKAGES:
                    third.update(f"{node.module}.{a.name}" for a in node.names)
                else:
                    third.add(_third_party_name(node.module))
        for name in names:
            while name and name not in modules:
                name = name.rpartition(".")[0]
            if name and name != me:
                out.add(name)
                if id(node) in in_func:
                    local.append((node.lineno, name))
    return out, local, third - set(PACKAGES)


def graph(with_third: bool = False):
    """Module -> modules it imports, module -> its function-level imports (and, with
    ``with_third``, module -> third-party packages it imports at module level)."""
    files = [p for pkg in PACKAGES for p in (ROOT / pkg).rglob("*.py")]
    modules = {module_name(p) for p in files}
    _LAZY.update({module_name(p): lazy_attributes(p) for p in files if p.name == "__init__.py"})
    edges: dict[str, set[str]] = {}
    local: dict[str, list[tuple[int, str]]] = {}
    third: dict[str, set[str]] = {}
    for p in files:
        m = module_name(p)
        edges[m], local[m], third[m] = imports(p, modules)
    return (edges, local, third) if with_third else (edges, local)


def _parents(module: str) -> list[str]:
    """The packages whose ``__init__`` runs when ``module`` is imported (``a``, ``a.b`` for ``a.b.c``)."""
    parts = module.split(".")
    return [".".join(parts[:i]) for i in range(1, len(parts))]


def startup_closure(module: str, edges: dict[str, set[str]], local: dict[str, list[tuple[int, str]]],
                    third: dict[str, set[str]]) -> set[str]:
    """Third-party packages loaded by importing ``module`` (its module-level imports, its parent
    packages' and theirs, transitively; function-level imports not followed)."""
    seen: set[str] = set()
    todo = [module]
    out: set[str] = set()
    while todo:
        m = todo.pop()
        if m in seen or m not in edges:
            continue
        seen.add(m)
        out |= third.get(m, set())
        lazy = {t for _, t in local.get(m, ())}
        todo.extend(t for t in edges[m] if t not in lazy)
        todo.extend(_parents(m))
    return out


def audit(edges, local, third) -> list[tuple[str, int, str, set[str]]]:
    """(module, line, target, costly packages the import defers) of every function-level import
    of a project module; an empty set: it defers nothing."""
    cache: dict[str, set[str]] = {}

    def closure(m: str) -> set[str]:
        if m not in cache:
            cache[m] = startup_closure(m, edges, local, third)
        return cache[m]

    out = []
    for m, items in sorted(local.items()):
        mine = closure(m)
        for line, target in sorted(set(items)):
            kept = KEPT.get((m, target)) or WORKER_MODULES.get(m)
            out.append((m, line, target, {kept} if kept else {n for n in closure(target) - mine if is_costly(n)}))
    return out


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
    ap.add_argument("--audit", action="store_true",
                    help="say what each function-level import defers (exit 1 on one that defers nothing)")
    args = ap.parse_args(argv)
    edges, local, third = graph(with_third=True)
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
    bad = []
    if args.audit:
        print("function-level imports: MODULE:LINE -> IMPORTED: the costly packages a module-level import would "
              "add to MODULE's start-up (or why it is kept)")
        for m, line, target, deferred in audit(edges, local, third):
            print(f"{m}:{line} -> {target}: " + (", ".join(sorted(deferred)) if deferred else "defers nothing"))
            if not deferred:
                bad.append((m, line, target))
        print(f"{len(bad)} function-level imports without a reason (each should defer a costly package or be kept)")
    print(f"{len(mod_cycles)} module cycles, {len(pkg_cycles)} package cycles "
          f"({len(edges)} modules, {sum(len(set(v)) for v in local.values())} function-level imports)")
    return 1 if mod_cycles or pkg_cycles or bad else 0


if __name__ == "__main__":
    raise SystemExit(main())
