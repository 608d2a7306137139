"""autonomy/ must import without mujoco, sim or rerun (it is what runs on the vehicle)."""

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
        "for blocked in ('mujoco', 'sim', 'rerun', 'dm_control'):\n"
        "    sys.modules[blocked] = None\n"
        "import importlib\n"
        f"for name in {modules!r}:\n"
        "    importlib.import_module(name)\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=Path(autonomy.__file__).parents[1])
    assert proc.returncode == 0, proc.stderr
