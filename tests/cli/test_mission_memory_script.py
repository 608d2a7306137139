"""scripts/mission_memory.py: the growth fit against an analytic line, and bad input refused
in one line before any run."""

from __future__ import annotations

import numpy as np
import pytest

from tests.support import script_refusal, load_script


def test_fit_growth_recovers_a_known_line():
    mod = load_script("mission_memory")
    t = np.linspace(0.0, 9000.0, 400)
    rss = 300.0 + 5.0 * t / 3600.0 + np.where(t < 600.0, -80.0, 0.0)  # 5 MB/h after a 600 s warm-up
    rss = rss + np.random.default_rng(0).normal(0.0, 0.5, t.size)
    fit = mod.fit_growth(t, rss, 600.0)
    assert fit["slope_mb_per_h"] == pytest.approx(5.0, abs=0.1)
    assert fit["rss_24h_mb"] == pytest.approx(300.0 + 5.0 * 24.0, abs=1.5)
    assert fit["n_samples"] == int(np.sum(t >= 600.0))
    assert fit["fit_window_s"] == pytest.approx(t[-1] - t[t >= 600.0][0]) and not fit["short_window"]
    short = mod.fit_growth(t[t < 2000.0], rss[t < 2000.0], 600.0)  # 1400 s of samples after the warm-up
    assert short["short_window"] and short["fit_window_s"] < mod.MIN_FIT_WINDOW_S
    with pytest.raises(ValueError, match="samples after"):
        mod.fit_growth(t[:10], rss[:10], 600.0)


@pytest.mark.parametrize("argv,culprits", [
    (["--out", "{new}", "--duration-s", "0"], ("--duration-s", "> 0")),
    (["--out", "{new}", "--warmup-s", "-1"], ("--warmup-s", ">= 0")),
    (["--out", "{file}"], ("--out", "exists")),
    (["cssn_lawnmowr", "--out", "{new}"], ("cssn_lawnmowr",)),
    (["--out", "{new}", "--set", "autonomy.guidance.survey.lenght_m=70"], ("lenght_m",)),
    (["--out", "{new}", "--duration-s", "5"], ("--warmup-s 600", "below --duration-s 5")),
    (["--out", "{new}", "--run-arg=--quiet"], ("--run-arg=--quiet", "progress")),
])
def test_mission_memory_refuses(argv, culprits, capsys, tmp_path):
    (tmp_path / "f.txt").write_text("keep")
    argv = [a.format(file=tmp_path / "f.txt", new=tmp_path / "new") for a in argv]
    script_refusal(load_script("mission_memory"), argv, capsys, *culprits)
    assert (tmp_path / "f.txt").read_text() == "keep" and not (tmp_path / "new").exists()


def test_the_tree_rss_counts_child_processes():
    import os
    import subprocess
    import sys
    import time

    mod = load_script("mission_memory")
    child = subprocess.Popen([sys.executable, "-c", "import subprocess, sys, time; "
                              "p = subprocess.Popen([sys.executable, '-c', 'import time; b = bytearray(200_000_000); "
                              "b[::4096] = bytes(len(b[::4096])); time.sleep(30)']); time.sleep(30)"])
    try:
        deadline = time.monotonic() + 20.0
        while time.monotonic() < deadline and (mod._tree_rss_mb(child.pid) or 0.0) - mod._rss_mb(child.pid) < 200.0:
            time.sleep(0.2)
        assert mod._tree_rss_mb(child.pid) - mod._rss_mb(child.pid) >= 200.0  # the grandchild's 200 MB touched
    finally:
        for line in open(f"/proc/{child.pid}/task/{child.pid}/children").read().split():
            os.kill(int(line), 9)
        child.kill()
        child.wait()
    assert mod._tree_rss_mb(child.pid) is None


def test_a_run_argument_the_run_refuses_is_repeated_not_hidden(capsys, tmp_path):
    mod = load_script("mission_memory")
    rc = mod.main(["--out", str(tmp_path / "m"), "--duration-s", "5", "--warmup-s", "0",
                   "--run-arg=--workers=0"])
    err = capsys.readouterr().err
    assert rc == 2 and err.count("\n") == 1 and "--workers: must be a whole number >= 1, got 0" in err
