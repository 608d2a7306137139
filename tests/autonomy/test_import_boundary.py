"""autonomy/ must import without mujoco, sim, rerun or scenarios (it is what runs on the vehicle)."""

from __future__ import annotations

import pkgutil
import subprocess
import sys
from pathlib import Path

import autonomy


def test_autonomy_imports_without_simulator():
    modules = [m.name for m in pkgutil.walk_packages(autonomy.__path__, "autonomy.")]
    assert modules, "no autonomy modules found"
    code = (
        "import sys\n"
        "for blocked in ('mujoco', 'sim', 'rerun', 'dm_control', 'scenarios'):\n"
        "    sys.modules[blocked] = None\n"
        "import importlib\n"
        f"for name in {modules!r}:\n"
        "    importlib.import_module(name)\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=Path(autonomy.__file__).parents[1])
    assert proc.returncode == 0, proc.stderr


def test_no_autonomy_source_names_the_simulator_or_scenarios():
    """Lazy imports inside functions escape the import test; no source line may import them."""
    import re

    pattern = re.compile(r"^\s*(from|import)\s+(mujoco|sim|rerun|dm_control|scenarios)\b", re.M)
    root = Path(autonomy.__file__).parent
    offenders = [
        f"{path.relative_to(root.parent)}:{text[: m.start()].count(chr(10)) + 1}"
        for path in sorted(root.rglob("*.py"))
        for text in [path.read_text()]
        for m in pattern.finditer(text)
    ]
    assert offenders == [], offenders
