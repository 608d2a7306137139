"""The tracking stack in the closed loop: a short track_static_vehicle run writes its plots and
figures, the trackers follow the diver's true trajectory; the navigation filter's beacon
comes from the usbl config."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from scenarios.load import load_scenario
from sim.mission.run import run_mission
from sim.outputs.run_dir import RUN_FILES

SCENARIOS = Path(__file__).resolve().parents[3] / "scenarios"


def test_track_static_vehicle_run_writes_tracking_outputs(tmp_path):
    scn = load_scenario(str(SCENARIOS / "track_static_vehicle.yaml"), ["duration_s=25"])
    metrics = run_mission(scn, tmp_path / "run", rerun=False, progress=False)
    names = {p.name for p in (tmp_path / "run").iterdir()}
    assert {"tracking_error.png", "tracking_boxplot.png", "metrics.json"} <= names
    assert {n for n in names if not n.startswith(".")} <= RUN_FILES
    tr = json.loads((tmp_path / "run" / "metrics.json").read_text())["tracking"]
    assert tr["mode"] == "fused" and set(tr["errors"]) == {"sonar", "sonar_when_available", "usbl", "fused"}
    # the ticks at 10.0, 10.1, ..., 25.0 s scored (the clock is the step count times the
    # step: the tick at 10 s is at 10 s); the diver starts in view 8.5 m ahead: every filter
    # within a metre
    assert tr["errors"]["fused"]["n"] == 151
    for k in ("usbl", "fused"):
        assert tr["errors"][k]["mean_m"] < 1.0, (k, tr["errors"][k])
    assert 0.0 < tr["fused_sonar_step_fraction"] <= 1.0
    assert metrics["tracking"]["min_distance_m"] > 3.0


def test_nav_filter_takes_the_beacon_of_the_usbl_config():
    from sim.features import TrackingFeature
    from sim.mission import Mission

    scn = load_scenario(str(SCENARIOS / "track_static_vehicle.yaml"),
                        ["duration_s=1", "sensors.usbl.transponder=beacon", "sensors.usbl.beacon_pos_ned=[3.0,-2.0,10.0]",
                         "autonomy.tracking.enabled=false", "autonomy.guidance.buddy.enabled=false",
                         "autonomy.atr.detector=none",  # no tracker: the survey's CNN would not take the ARIS fan
                         "autonomy.guidance.mission.safe_depth_max_m=14"])  # the survey (tracking off) flies 13 m deep
    m = Mission(scn, perception=False)
    np.testing.assert_array_equal(m.parts.usbl_beacon_pos_ned, [3.0, -2.0, 10.0])
    m.reset()
    assert m.feature(TrackingFeature) is None
    np.testing.assert_array_equal(m.nav_filter._beacon_ned, [3.0, -2.0, 10.0])
