"""The shipped sea trial: the AUV, the buoy following on its own USBL fixes, detections up
and USBL fixes down over the acoustic link, in a short closed-loop run."""

from __future__ import annotations

import json

import numpy as np
import pytest

from scenarios.load import ScenarioError, load_scenario
from sim.mission.run import run_mission


@pytest.fixture(scope="module")
def short_run(tmp_path_factory):
    """35 s: 20 s at the surface (GPS), then the dive towards the first leg with OPIs in view."""
    scn = load_scenario("cssn_sea_trial", ["duration_s=35"])
    out = tmp_path_factory.mktemp("sea") / "run"
    metrics = run_mission(scn, out, rerun=False, progress=False)
    return metrics, out


def test_shipped_scenario_has_the_buoy_and_the_link():
    scn = load_scenario("cssn_sea_trial")
    buoy = scn.vehicles["buoy"]
    assert buoy.behaviour == "follow" and buoy.usbl is not None and buoy.usbl.transponder == "auv"
    assert scn.comms.acoustic.enabled and scn.comms.surface.vehicle == "buoy"
    assert scn.autonomy.guidance.survey.speed_mps == 0.5  # paper 000's trial speed: the buoy keeps up
    assert scn.world.targets == load_scenario("cssn_lawnmower").world.targets


def test_messages_cross_both_ways_without_contact(short_run):
    metrics, _ = short_run
    link = metrics["link"]
    up, down = link["uplink_detections"], link["downlink_usbl_fixes"]
    assert up["delivered"] > 50 and down["delivered"] > 10
    assert up["sent"] == up["delivered"] + up["lost"] + up["pending"]
    assert link["detections_queued"] == (up["sent"] + link["detections_dropped_stale"]
                                         + link["detections_unsent_at_end"])
    assert 0.0 < up["mean_latency_s"] < up["p95_latency_s"] < 1.0  # queue + 48 ms packets + travel
    assert link["usbl_fixes_fused"] > 5
    assert link["surface_world_model"]["reports_received"] == up["delivered"]
    assert metrics["vehicles"]["contact_periods"] == {}
    assert metrics["vehicles"]["min_separation_m"]["buoy"] > 2.0


def test_both_world_models_are_written_in_ned_and_lat_lon(short_run):
    metrics, out = short_run
    assert {"world_model.json", "surface_world_model.json", "map.png", "metrics.json"} <= {p.name for p in out.iterdir()}
    surface = json.loads((out / "surface_world_model.json").read_text())
    assert surface["objects"], "the surface world model holds the OPIs seen on the dive"
    for obj in surface["objects"]:
        assert abs(obj["lat_deg"] - 44.0935) < 0.001 and abs(obj["lon_deg"] - 9.86) < 0.001
        assert obj["depth_m"] == pytest.approx(obj["pos_ned"][2], abs=0.01)
    assert metrics["surface_world_model"]["matched"] >= 1
    assert np.isfinite(metrics["surface_world_model"]["gospa"])


def test_link_without_its_surface_vehicle_is_one_clear_error():
    with pytest.raises(ScenarioError, match="comms.acoustic.enabled: the link needs a surface vehicle and vehicles has none"):
        load_scenario("cssn_lawnmower", ["comms.acoustic.enabled=true"])


def test_pipelined_loop_gives_the_serial_link_and_surface_model(short_run, tmp_path):
    """--workers 2 hands detections to the modem at the step the serial loop does."""
    metrics, out = short_run
    piped = run_mission(load_scenario("cssn_sea_trial", ["duration_s=35"]), tmp_path / "run", rerun=False,
                        progress=False, workers=2)
    assert metrics["link"]["uplink_detections"]["sent"] > 0
    assert piped["link"] == metrics["link"]
    assert piped["surface_world_model"] == metrics["surface_world_model"]
    assert (tmp_path / "run" / "surface_world_model.json").read_text() == (out / "surface_world_model.json").read_text()


def test_link_errors_name_the_key_and_the_set_that_caused_them():
    with pytest.raises(ScenarioError) as err:
        load_scenario("cssn_sea_trial", ["comms.surface.vehicle=boat"])
    assert str(err.value).endswith("comms.surface.vehicle 'boat' is not a key of vehicles (allowed: 'buoy') "
                                   "(from --set comms.surface.vehicle=boat)")
    assert "(top level)" not in str(err.value)
    with pytest.raises(ScenarioError, match=r"comms.acoustic.enabled: the link needs a surface vehicle .* "
                                            r"\(from --set vehicles=\{\}\)"):
        load_scenario("cssn_sea_trial", ["vehicles={}"])
