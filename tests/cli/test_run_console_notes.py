"""What ``auvsim run`` tells a user on the console beyond the figures: ``--workers N`` on a
mission the pipeline does not take, a tracking run too short to score, a buddy mission's
progress (its survey state machine stays idle)."""

from __future__ import annotations

import json

from sim.cli import main


def test_tracking_run_too_short_to_score_says_so_and_buddy_progress_names_the_behaviour(tmp_path, capsys):
    code = main(["run", "diver_follow", "--out", str(tmp_path / "r"), "--workers", "2", "--no-rerun",
                 "--set", "duration_s=2"])
    out, err = capsys.readouterr()
    assert code == 0
    assert "--workers 2: this mission runs the serial loop" in err  # a tracker needs each frame in the loop
    assert "buddy follow" in err and ", idle," not in err
    metrics = json.loads((tmp_path / "r" / "metrics.json").read_text())
    scored_from = metrics["tracking"]["scored_from_s"]
    assert scored_from > 2 and f"nothing scored (errors count from {scored_from:g} s" in out


def test_tracking_consistency_is_printed_with_what_a_consistent_filter_gives(tmp_path, capsys):
    code = main(["run", "track_static_vehicle", "--out", str(tmp_path / "r"), "--no-rerun", "--quiet",
                 "--set", "duration_s=14"])
    out, _ = capsys.readouterr()
    assert code == 0
    nees = json.loads((tmp_path / "r" / "metrics.json").read_text())["tracking"]["nees_horizontal"]
    assert set(nees) == {"sonar", "usbl", "fused"}
    for v in nees.values():
        assert v["consistent_mean"] == 2.0 and v["consistent_above_95_fraction"] == 0.05
    assert 0 < nees["fused"]["n"] <= 4 * 100 + 1  # ticks scored from 10 s to 14 s
    line = next(ln for ln in out.splitlines() if ln.startswith("tracking consistency"))
    assert "(2 if the filter's covariance is right" in line
    assert f"fused {nees['fused']['mean']:.2f}" in line and f"usbl {nees['usbl']['mean']:.2f}" in line
