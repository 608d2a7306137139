"""scripts/speed_table.py: the README's speed table is the one made from the saved benchmark JSON."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[3]
_spec = importlib.util.spec_from_file_location("speed_table", ROOT / "scripts" / "speed_table.py")
speed_table = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(speed_table)


def _save(json_dir: Path, key: str, result: dict) -> None:
    json_dir.mkdir(exist_ok=True)
    (json_dir / f"{key}.json").write_text(json.dumps({
        "command": f"auvsim bench {key} --json", "measured": "2026-01-01 00:00 UTC", "cpu_count": 2,
        "load_avg_1min_before": 0.5, "load_avg_1min_after": 1.25, "result": result}))


def test_readme_table_is_the_saved_json():
    text = (ROOT / "README.md").read_text()
    assert speed_table.table() in text
    assert text.count(speed_table.BEGIN) == 1


def test_table_rows_come_from_the_json_and_readme_is_rewritten_between_markers(tmp_path):
    json_dir = tmp_path / "speed"
    _save(json_dir, "mission", {"real_time_factor": 9.04, "cpu_real_time_factor": 10.2,
                                "workers": {"real_time_factor": 13.5, "workers_speedup": 1.49,
                                            "serial_real_time_factor": 9.06}})
    _save(json_dir, "mission_one_core", {"real_time_factor": 8.44, "cpu_real_time_factor": 8.5})
    _save(json_dir, "tracking", {"p50_ms": 0.091, "p99_ms": 1.5})
    table = speed_table.table(json_dir)
    rows = table.splitlines()
    assert rows[0] == speed_table.BEGIN and rows[-1] == speed_table.END
    assert len(rows) == 2 + 2 + 3 + 1  # markers, header, three mission rows, one tracking row
    assert "pinned to one core | 8.4x real time (8.5x per CPU second) | >= 20x (stretch 30x) |" in table
    assert "serial (one process, free to use OpenCV's threads) | 9.0x real time (10.2x per CPU second) |  |" in table
    assert "13.5x real time, 1.49x the serial loop of the same run (9.1x)" in table
    assert "p50 0.09 ms, p99 1.50 ms" in table
    assert "2 cores, load 0.5-1.2" in table
    readme = tmp_path / "README.md"
    readme.write_text(f"intro\n{speed_table.BEGIN}\nold | table\n{speed_table.END}\nafter\n")
    assert speed_table.rewrite_readme(readme, json_dir)
    assert readme.read_text() == f"intro\n{table}\nafter\n"
    assert not speed_table.rewrite_readme(readme, json_dir)
    readme.write_text("no markers\n")
    with pytest.raises(ValueError, match="markers"):
        speed_table.rewrite_readme(readme, json_dir)


def test_dataset_row_reads_both_runs_and_start_up(tmp_path):
    json_dir = tmp_path / "speed"
    _save(json_dir, "dataset", {
        "n_frames": 96, "workers": 2, "seed": 0, "workers_speedup": 1.62, "cpu_per_frame_ratio": 1.2,
        "one_worker": {"workers": 1, "wall_s": 6.2, "cpu_s": 6.1, "frames_per_s": 15.41, "cpu_frames_per_s": 15.69},
        "n_workers": {"workers": 2, "wall_s": 3.8, "cpu_s": 7.3, "frames_per_s": 25.0, "cpu_frames_per_s": 13.1},
        "startup": {"wall_s": 1.3, "cpu_s": 1.25}, "identical_across_workers": True})
    rows = speed_table.table(json_dir).splitlines()
    assert len(rows) == 2 + 2 + 1
    assert rows[3].startswith("| `dataset` labelled FLS frames")
    assert ("| 15.4 frames/s with 1 worker process (15.7 per CPU second); 2 workers 25.0 frames/s (13.1 per CPU "
            "second), 1.62x one worker; 96 frames, start-up included (1.25 CPU s a worker) | >= 30 per core, linear "
            "in workers |") in rows[3]


@pytest.mark.skipif(not hasattr(__import__("os"), "sched_setaffinity"), reason="CPU pinning is Linux-only")
def test_pinned_benchmark_runs_on_one_cpu_and_says_so(tmp_path, monkeypatch):
    import os
    import subprocess

    seen = {}

    def fake_run(cmd, **kw):
        seen["cmd"], seen["preexec_fn"] = cmd, kw.get("preexec_fn")
        return subprocess.CompletedProcess(cmd, 0, stdout='{"real_time_factor": 1.0, "cpu_real_time_factor": 1.0}\n')

    monkeypatch.setattr(speed_table.subprocess, "run", fake_run)
    rec = speed_table.run_bench("mission_one_core", tmp_path)
    cpu = min(os.sched_getaffinity(0))
    assert rec["command"] == f"taskset -c {cpu} auvsim bench mission --json"
    assert seen["cmd"][-3:] == ["bench", "mission", "--json"] and seen["preexec_fn"] is not None
    rec = speed_table.run_bench("tracking", tmp_path)
    assert rec["command"] == "auvsim bench tracking --json" and seen["preexec_fn"] is None
