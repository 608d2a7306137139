"""A short full-mode run: the MuJoCo hull flies the first leg of ``mcm_survey_full`` with the
side-scan sonar; tiles close at the right times and the detections of M1 lie where its true
position is in the tile frame of the true pose."""

from __future__ import annotations

import numpy as np
import pytest

from autonomy.mapping.spa_mapper import rotate_to_local
from scenarios.load import load_scenario
from sim.mcm.full_mode import McmFullObserver
from sim.mission import Mission

PERIOD_S = 15.0
DURATION_S = 62.0


@pytest.fixture(scope="module")
def short_run():
    # the first leg from N 30 m past M1 (N 60 m, 30 m to starboard), coarser sonar to keep the test short
    scn = load_scenario("mcm_survey_full", [f"duration_s={DURATION_S}", f"mcm.tile.tile_period_s={PERIOD_S}",
                                            "vehicle.initial_pos_ned=[30.0, 20.0, 12.0]",
                                            "autonomy.guidance.mission.start_delay_s=1.0",
                                            "autonomy.guidance.survey.origin_ne_m=[30.0, 20.0]",
                                            "sensors.sss.n_bins=600", "sensors.sss.elevation_rays=32",
                                            "mcm.mapper.n_particles=50", "mcm.mapper.tile_length_m=13"])
    obs = McmFullObserver(scn)
    mission = Mission(scn, observers=[obs])
    mission.reset()
    mission.run(progress=False)
    return scn, obs, mission


def test_tiles_close_every_period(short_run):
    scn, obs, _ = short_run
    rate = scn.sensors.enabled()["sss"].rate_hz
    idx = [t.tile_index for t in obs.tiles]
    assert idx == list(range(1, len(idx) + 1)) and len(idx) == int(DURATION_S // PERIOD_S)
    for tile in obs.tiles:  # its last ping is the last one at or before k T
        assert tile.tile_index * PERIOD_S - 1.0 / rate - 1e-6 <= tile.t_s <= tile.tile_index * PERIOD_S + 1e-6


def test_detections_in_the_tile_frame_against_labels(short_run):
    scn, obs, _ = short_run
    pos, cls = obs.truth_objects()
    m1 = [t.name for t in scn.world.targets].index("M1")
    hits = []
    for tile in obs.tiles:
        true = obs._true_at(np.array([tile.t_s]))[0]
        ell_true = rotate_to_local(pos[m1] - true[:2], np.array(true[5]))
        for ell in tile.ell_m:
            hits.append(np.linalg.norm(ell - ell_true))
    assert min(hits) < 2.0  # M1 detected where it is
    score = obs.detector_score()
    assert score["labelled"] >= 1 and score["detected"] >= 1 and score["clutter_per_tile"] <= 0.5
    res = obs.results(scn.seed)
    assert res["mode"] == "full" and res["n_tiles"] == len(obs.tiles)
    for mode in scn.mcm.modes:
        assert len(res[mode]["gospa"]) == len(obs.tiles) and len(res[mode]["correct"]) == 20
    assert res["clairvoyant"]["auv_rmse_m"] == pytest.approx(0.0, abs=1e-9)


def test_run_full_is_deterministic_in_its_seed(short_run):
    scn, obs, _ = short_run
    a = obs.results(scn.seed)
    b = obs.results(scn.seed)
    assert a["spa"]["gospa"] == b["spa"]["gospa"] and a["lambda0_rad"] == b["lambda0_rad"]
    with pytest.raises(ValueError, match="no side-scan tile"):
        McmFullObserver(scn).results(0)


def test_sweep_takes_full_mode_scenarios_only():
    from sim.sweep.runner import SweepError, SweepSpec, sweep_parts

    build = sweep_parts("mcm_survey_full")[0]
    assert build(SweepSpec("mcm_survey_full", 1, 4, {"duration_s": 60})).seed == 4
    with pytest.raises(SweepError, match="mcm.mode is 'off'"):
        sweep_parts("cssn_lawnmower")[0](SweepSpec("cssn_lawnmower", 1, 0, {}))
    with pytest.raises(SweepError, match="tile_period_s"):
        build(SweepSpec("mcm_survey_full", 1, 0, {"mcm.tile.tile_period_s": -1}))


def test_full_mode_needs_its_side_scan():
    from scenarios.load import ScenarioError

    with pytest.raises(ScenarioError, match="mcm.sensor"):
        load_scenario("mcm_survey_full", ["sensors.sss.enabled=false"])
    with pytest.raises(ScenarioError, match="mcm.sensor"):
        load_scenario("mcm_survey_full", ["mcm.sensor=imu"])
