"""The recorder sets mimalloc's purge options before rerun's bindings load (they are read when
the library loads): nothing on the way to the recorder imports rerun or pyarrow first, and a
value the user put in the environment is kept."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]

_PROBE = """
import os, sys
import sim.cli.app, sim.mission.run, sim.mission
early = sorted(m for m in ("rerun", "rerun_bindings", "pyarrow") if m in sys.modules)
import sim.outputs.rerun_recording as r
print(early, "rerun_bindings" in sys.modules, os.environ["MIMALLOC_PURGE_DELAY"], os.environ["MIMALLOC_PURGE_DECOMMITS"])
"""


def _probe(env_extra: dict[str, str]) -> str:
    env = {k: v for k, v in os.environ.items() if not k.startswith("MIMALLOC_")}
    env.update(env_extra, PYTHONPATH=str(ROOT))
    return subprocess.run([sys.executable, "-c", _PROBE], env=env, cwd=ROOT, capture_output=True, text=True,
                          check=True).stdout.split("\n")[-2]


def test_mimalloc_options_set_before_rerun_loads_and_user_values_kept():
    assert _probe({}) == "[] False 0 1"
    assert _probe({"MIMALLOC_PURGE_DELAY": "10"}) == "[] False 10 1"
