"""What ``auvsim run`` tells a user on the console beyond the figures: ``--workers N`` on a
mission the pipeline does not take, a tracking run too short to score, a buddy mission's
progress (its survey state machine stays idle), a deep-water sea trial whose USBL fixes
wait for a surface slot long enough for their travel time."""

from __future__ import annotations

import json
import re

import pytest

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
    printed = dict(re.findall(r"(sonar|usbl|fused) ([0-9.]+)", line.split("overconfident):")[1]))
    assert set(printed) == {"sonar", "usbl", "fused"}
    for k, text in printed.items():  # two decimals of the value metrics.json keeps (itself rounded)
        assert len(text.split(".")[1]) == 2 and abs(float(text) - nees[k]["mean"]) <= 0.005 + 1e-3


DEEP_ARGS = ["run", "cssn_sea_trial", "--no-rerun", "--no-scoring", "--detector", "none", "--set", "duration_s=6",
             "--set", "world.seabed.depth_m=400", "--set", "world.basin.shape=none",
             "--set", "world.seabed.extent_m=200",
             "--set", "world.targets=[]", "--set", "vehicle.initial_pos_ned=[8,0,380]",
             "--set", "autonomy.guidance.mission.safe_depth_max_m=399"]


def test_deep_water_sea_trial_runs_and_says_why_its_fixes_wait(tmp_path, capsys):
    """400 m of water: the USBL fixes of the AUV at ~380 m (version 2 carries the depth) are
    made, and none goes into the AUV's slot: the 0.3 s surface slot carries a 38-byte fix at
    8 kbit/s only to 1500 * (0.3 - 0.054 - 0.05 multipath - 0.05 guard) = 219 m."""
    code = main([*DEEP_ARGS, "--out", str(tmp_path / "d")])
    out, err = capsys.readouterr()
    assert code == 0, err
    link = json.loads((tmp_path / "d" / "metrics.json").read_text())["link"]
    reach_m = 1500.0 * (0.3 - (38 + 16) * 8 / 8000.0 - 0.05 - 0.05)
    assert link["message_version"] == 2 and link["unencodable"] == 0 and link["usbl_fixes_made"] >= 4
    assert link["tdma"]["surface_reach_m"] == pytest.approx(reach_m)
    assert link["downlink_usbl_fixes"]["sent"] == 0 and link["all"]["lost_half_duplex"] == 0
    held = link["usbl_fixes_superseded"] + link["usbl_fixes_unsent_at_end"]
    assert held == link["usbl_fixes_made"]
    assert f"link: {held} of {held} USBL fixes not sent" in out and f"carries a fix to {reach_m:.0f} m" in out


def test_deep_water_fixes_arrive_through_a_surface_slot_that_reaches_them(tmp_path, capsys):
    """A 0.5 s surface slot reaches 1500 * (0.5 - 0.154) = 519 m: the fixes of the AUV
    ~380 m below go down and are decoded, none lost to half duplex."""
    code = main([*DEEP_ARGS, "--out", str(tmp_path / "d"), "--set", "comms.surface.surface_slot_s=0.5"])
    out, err = capsys.readouterr()
    assert code == 0, err
    link = json.loads((tmp_path / "d" / "metrics.json").read_text())["link"]
    down = link["downlink_usbl_fixes"]
    assert link["usbl_fixes_received"] >= 3 and down["delivered"] == link["usbl_fixes_received"]
    assert link["all"]["lost_half_duplex"] == 0 and "USBL fixes not sent" not in out
