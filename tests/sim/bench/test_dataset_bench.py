"""``auvsim bench dataset``: one worker against N in fresh processes, start-up apart, same frames."""

from __future__ import annotations

import pytest

from sim.bench import dataset as bench_dataset
from sim.cli import main


def test_tiny_run_reports_both_runs_start_up_and_identical_frames():
    # three scenes (a flat bed, then two rippled ones): the two-worker run's parent renders the
    # first, its two workers one rippled scene each
    r = bench_dataset.run(seed=6, workers=2, n_frames=12)
    assert set(r) == {"n_frames", "workers", "seed", "one_worker", "n_workers", "workers_speedup",
                      "cpu_per_frame_ratio", "startup", "identical_across_workers"}
    assert r["n_frames"] == 12 and r["workers"] == 2 and r["identical_across_workers"] is True
    for key, w in (("one_worker", 1), ("n_workers", 2)):
        run = r[key]
        assert set(run) == {"workers", "wall_s", "cpu_s", "frames_per_s", "cpu_frames_per_s"} and run["workers"] == w
        assert run["frames_per_s"] == pytest.approx(12 / run["wall_s"], rel=1e-2)
        assert run["cpu_frames_per_s"] == pytest.approx(12 / run["cpu_s"], rel=1e-2)
        assert run["cpu_s"] > r["startup"]["cpu_s"] > 0  # the run pays at least one process's start-up
    # the two-worker run's CPU time includes its workers' (the two rippled scenes, each a terrain
    # mesh to compile, are over a third of the work: were they left out it would fall well below
    # the one-worker run's; forked workers add little of their own)
    assert r["n_workers"]["cpu_s"] > 0.85 * r["one_worker"]["cpu_s"]
    assert r["workers_speedup"] == pytest.approx(r["one_worker"]["wall_s"] / r["n_workers"]["wall_s"], rel=1e-2)


def test_bad_counts_are_refused():
    with pytest.raises(ValueError, match="n_frames must be >= 1"):
        bench_dataset.run(n_frames=0)


def test_cli_refuses_no_sonar_for_dataset(capsys):
    assert main(["bench", "dataset", "--no-sonar"]) == 2
    err = capsys.readouterr().err
    assert "--no-sonar: only for bench mission, not dataset" in err and "Traceback" not in err
