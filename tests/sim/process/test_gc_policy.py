"""The garbage-collector thresholds the simulator runs with (sim.process.gc_policy)."""

import gc
import subprocess
import sys

import sim.cli.app as app
from sim.process.gc_policy import LOOP_GC_THRESHOLDS


def test_cli_runs_commands_with_loop_thresholds_and_restores_the_callers(monkeypatch):
    seen = []
    monkeypatch.setattr(app, "_dispatch", lambda func, args, debug, prog: seen.append(gc.get_threshold()) or 0)
    before = gc.get_threshold()
    assert before != LOOP_GC_THRESHOLDS
    assert app.main(["scenarios"]) == 0
    assert seen == [LOOP_GC_THRESHOLDS]
    assert gc.get_threshold() == before


def test_pipeline_worker_processes_start_with_loop_thresholds():
    code = ("import gc; from sim.process.sonar_workers import _worker_start; _worker_start(); "
            "print(tuple(gc.get_threshold()))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120)
    assert out.stdout.strip() == repr(tuple(LOOP_GC_THRESHOLDS))
