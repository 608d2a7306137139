"""The repository's shape: sim/ in rooms with no import cycle, tests mirroring the packages,
and shared test helpers in one support module (no test module imports another)."""

from __future__ import annotations

import ast
import importlib.util
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _cycles_script():
    spec = importlib.util.spec_from_file_location("import_cycles", ROOT / "scripts" / "import_cycles.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_no_module_or_package_import_cycle():
    ic = _cycles_script()
    edges, _ = ic.graph()
    assert len(edges) > 200  # the scan saw the packages
    assert ic.cycles(edges) == []
    assert ic.cycles(ic.package_edges(edges)) == []


def test_the_cycle_scan_finds_a_cycle_when_there_is_one():
    ic = _cycles_script()
    edges = {"sim.a.x": {"sim.b.y"}, "sim.b.y": {"sim.a.z"}, "sim.a.z": set(), "sim.a": set(), "sim.b": set()}
    assert ic.cycles(edges) == []
    assert ic.cycles(ic.package_edges(edges)) == [["sim.a", "sim.b"]]


def test_every_function_level_import_defers_a_costly_package():
    ic = _cycles_script()
    edges, local, third = ic.graph(with_third=True)
    rows = ic.audit(edges, local, third)
    assert len(rows) > 30  # the scan saw the lazy imports (CLI commands, workers, optional extras)
    idle = [f"{m}:{line} -> {target}" for m, line, target, deferred in rows if not deferred]
    assert idle == [], "function-level imports that defer nothing (move them to the module's top): " + ", ".join(idle)


def test_the_import_audit_sees_what_a_lazy_import_defers():
    ic = _cycles_script()
    edges = {"sim.a": {"sim.b", "sim.c"}, "sim.b": set(), "sim.c": set(), "sim": set()}
    local = {"sim.a": [(10, "sim.b"), (20, "sim.c")], "sim.b": [], "sim.c": [], "sim": []}
    third = {"sim.a": {"numpy"}, "sim.b": {"torch"}, "sim.c": {"numpy", "json"}, "sim": set()}
    assert [(m, t, d) for m, _, t, d in ic.audit(edges, local, third)] == [
        ("sim.a", "sim.b", {"torch"}), ("sim.a", "sim.c", set())]


def test_sim_has_rooms_not_flat_modules():
    flat = sorted(p.name for p in (ROOT / "sim").glob("*.py"))
    assert flat == ["__init__.py", "rng.py"], flat  # rng: the seed streams every room draws from


def test_tests_mirror_the_packages():
    for d in (ROOT / "tests" / "sim").iterdir():
        if d.is_dir() and d.name != "__pycache__":
            assert (ROOT / "sim" / d.name).is_dir(), f"tests/sim/{d.name}/ has no sim/{d.name}/"
    assert not list((ROOT / "tests" / "sim").glob("test_*.py")), "tests/sim/ holds tests of no room"


def test_no_test_module_imports_another():
    offenders = []
    for path in (ROOT / "tests").rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("tests."):
                if node.module != "tests.support":
                    offenders.append(f"{path.relative_to(ROOT)}: from {node.module}")
    assert not offenders, offenders
