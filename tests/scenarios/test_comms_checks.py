"""Load-time checks of the acoustic link: a scenario whose messages could carry a depth the
chosen message version cannot hold, or whose slots cannot carry a packet at all, is refused
with one line naming the keys (exit 2 from the CLI); the deep-water sea trial loads."""

from __future__ import annotations

import math

import pytest

from scenarios.load import ScenarioError, load_scenario
from sim.cli import main

#: the sea trial moved to 400 m of water (no basin walls, a 200 m patch, the AUV at 380 m)
DEEP = ["world.seabed.depth_m=400", "world.basin.shape=none", "world.seabed.extent_m=200", "world.targets=[]",
        "vehicle.initial_pos_ned=[8,0,380]", "autonomy.guidance.mission.safe_depth_max_m=399"]


def _usbl_depth_margin_m(depth_m):
    """The buoy USBL's (cssn_sea_trial: 0.1 m + 1 % of range, outliers 5 m longer) fix error
    from straight above: the outlier excess plus 4 range sigmas."""
    return 5.0 + 4.0 * (0.1 + 0.01 * depth_m)


def test_shipped_sea_trial_and_its_deep_water_variant_load():
    assert load_scenario("cssn_sea_trial").comms.surface.message_version == 2
    load_scenario("cssn_sea_trial", ["comms.surface.message_version=1"])  # 4 m of water: version 1 holds it
    load_scenario("cssn_sea_trial", DEEP)


def test_version_1_in_deep_water_is_refused_naming_the_keys():
    with pytest.raises(ScenarioError) as err:
        load_scenario("cssn_sea_trial", [*DEEP, "comms.surface.message_version=1"])
    msg = str(err.value)
    assert "\n" not in msg
    reach = 400.0 + _usbl_depth_margin_m(400.0)  # 421.4 m
    assert (f"comms.surface.message_version: version 1 carries depths -327.68 to 327.67 m, and this scenario's "
            f"messages can reach {reach:.1f} m (world.seabed.depth_m plus") in msg
    assert "message_version 2 carries 83886.07 m" in msg


def test_a_slope_deepening_past_the_field_is_refused():
    """300 m at the centre, 10 deg down towards north over a 200 m patch: the deepest corners
    (both northern ones) are at 300 + 100 tan 10 deg = 317.6 m."""
    base = ["world.basin.shape=none", "world.seabed.extent_m=200", "world.targets=[]",
            "vehicle.initial_pos_ned=[8,0,280]", "autonomy.guidance.mission.safe_depth_max_m=299",
            "world.seabed.center_ne_m=[0,0]", "world.seabed.kind=slope", "world.seabed.slope_azimuth_deg=0",
            "comms.surface.message_version=1", "world.seabed.depth_m=300"]
    deepest = 300.0 + 100.0 * math.tan(math.radians(10.0))
    assert deepest + _usbl_depth_margin_m(deepest) > 327.67 > 300.0 + _usbl_depth_margin_m(300.0)
    load_scenario("cssn_sea_trial", [*base, "world.seabed.slope_deg=0"])  # the level bed fits
    with pytest.raises(ScenarioError, match=rf"can reach {deepest + _usbl_depth_margin_m(deepest):.1f} m "
                                            r"\(world.seabed.depth_m, slope_deg and extent_m plus"):
        load_scenario("cssn_sea_trial", [*base, "world.seabed.slope_deg=10"])


def test_slots_that_cannot_carry_a_packet_at_all_are_refused():
    """At 100 bit/s a 38-byte fix with 16 bytes of framing lasts 4.32 s: no 0.3 s slot holds it."""
    with pytest.raises(ScenarioError) as err:
        load_scenario("cssn_sea_trial", ["comms.acoustic.bit_rate_bps=100"])
    lines = str(err.value).splitlines()
    assert lines[0].endswith("impossible scenario (2 problems)")
    fix_s, det_s = (38 + 16) * 8 / 100.0, (33 + 16) * 8 / 100.0
    assert lines[1].strip().startswith(f"comms.surface.surface_slot_s: the 0.3 s slot cannot carry a USBL fix even "
                                       f"at zero range: it lasts {fix_s:.3f} s at comms.acoustic.bit_rate_bps 100")
    assert lines[2].strip().startswith("comms.surface.cycle_s minus surface_slot_s: the 0.7 s slot cannot carry a "
                                       f"detection report even at zero range: it lasts {det_s:.3f} s")
    # without the fixes (and detections), nothing needs the slots
    load_scenario("cssn_sea_trial", ["comms.acoustic.bit_rate_bps=100", "comms.surface.usbl_fixes=false",
                                     "comms.surface.detections=false"])


def test_cli_refuses_the_unencodable_scenario_with_exit_2(tmp_path, capsys):
    code = main(["run", "cssn_sea_trial", "--out", str(tmp_path / "r"), "--no-rerun",
                 *[a for kv in DEEP for a in ("--set", kv)], "--set", "comms.surface.message_version=1"])
    _, err = capsys.readouterr()
    assert code == 2
    assert len(err.strip().splitlines()) == 1 and "comms.surface.message_version: version 1" in err
    assert "Traceback" not in err and not (tmp_path / "r").exists()
