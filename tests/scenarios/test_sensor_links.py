"""Names that sensors and the tracker refer to are checked at load: a USBL transponder, the
tracker's mover and sensors, the buddy observer's tracker, a sensor's hull site."""

from __future__ import annotations

import pytest

from scenarios.load import ScenarioError, load_scenario


def _error(name: str, *overrides: str) -> str:
    with pytest.raises(ScenarioError) as exc:
        load_scenario(name, list(overrides))
    return str(exc.value)


def test_shipped_tracking_scenarios_load():
    for name in ("track_static_vehicle", "track_moving_vehicle", "diver_follow"):
        assert load_scenario(name).autonomy.tracking.enabled


def test_usbl_transponder_not_in_scene():
    msg = _error("track_static_vehicle", "sensors.usbl.transponder=diverr")
    assert msg.count("\n") == 0, msg  # one problem, one line (no second line on the tracker)
    assert "sensors.usbl.transponder: 'diverr' is not in the scene" in msg
    assert "'beacon'" in msg and "(diver)" in msg


def test_renamed_mover_leaves_both_transponders_dangling():
    msg = _error("track_static_vehicle", "world.movers.0.name=bob")
    assert "sensors.usbl.transponder: 'diver'" in msg
    assert "autonomy.tracking.transponder: 'diver' is not a mover" in msg and "(bob)" in msg


def test_tracker_transponder_must_be_a_mover():
    msg = _error("track_static_vehicle", "autonomy.tracking.transponder=diverr")
    assert "autonomy.tracking.transponder: 'diverr' is not a mover; allowed: a world.movers name (diver)" in msg
    assert "\n" not in msg


def test_usbl_on_the_beacon_while_tracking_the_diver():
    msg = _error("track_static_vehicle", "sensors.usbl.transponder=beacon")
    assert "sensors.usbl.transponder: 'beacon' differs from autonomy.tracking.transponder 'diver'" in msg


@pytest.mark.parametrize("removed,key", [("sensors.usbl", "usbl_sensor"), ("sensors.fls", "sonar_sensor")])
def test_tracker_sensor_missing(removed, key):
    msg = _error("track_static_vehicle", f"{removed}=null")
    assert f"autonomy.tracking.{key}:" in msg and "is not an enabled sensor" in msg


def test_tracker_sensor_of_wrong_kind():
    msg = _error("track_static_vehicle", "autonomy.tracking.usbl_sensor=fls")
    assert "autonomy.tracking.usbl_sensor: 'fls' is a fls sensor; the tracker needs a usbl sensor (enabled: usbl)" in msg


def test_buddy_needs_tracking():
    msg = _error("diver_follow", "autonomy.tracking.enabled=false")
    assert "autonomy.guidance.buddy.enabled: the buddy observer follows the tracker's estimate" in msg


def test_sensor_without_a_hull_site():
    # FeelHippo has no 'usbl' site and the USBL config has no default mount position
    msg = _error("cssn_lawnmower", "sensors.usbl.transponder=beacon")
    assert "sensors.usbl.mount_pos_body_m: the feelhippo hull has no site 'usbl'" in msg
    assert "fls" in msg  # the sites there are
    ok = load_scenario("cssn_lawnmower", ["sensors.usbl.transponder=beacon", "sensors.usbl.mount_pos_body_m=[0, 0, -0.2]"])
    assert ok.sensors.usbl.transponder == "beacon"
    msg = _error("cssn_lawnmower", "sensors.usbl.mount_site=mast", "sensors.usbl.transponder=beacon")
    assert "sensors.usbl.mount_site: the feelhippo hull has no site 'mast'" in msg


def test_unknown_sensor_key_lists_the_kind_keys_and_a_suggestion():
    msg = _error("pool_circular", "sensors.msis.rang_m=10")
    assert "sensors.msis.rang_m" in msg and "unknown key (did you mean range_m?)" in msg
    assert "step_grad" in msg and "sector_width_grad" in msg
    # an entry named unlike its kind: the keys of its kind
    msg = _error("pool_circular", "sensors.ping2.kind=msis", "sensors.ping2.stepgrad=2")
    assert "did you mean step_grad?" in msg


def test_device_limit_message_has_no_pydantic_prefix():
    msg = _error("pool_circular", "sensors.msis.range_m=0.5")
    assert "Value error" not in msg and "range_m >= 1.800 m" in msg


def test_yaml_tab_and_path_form_hints(tmp_path):
    bad = tmp_path / "tab.yaml"
    bad.write_text("name: t\nworld:\n\tseabed: {kind: plane}\n")
    msg = _error(str(bad))
    assert msg == f"{bad}: not valid YAML at line 3, column 1: a tab character; indent with spaces"
    msg = _error(str(tmp_path / "scenarios" / "pool_circular.yaml"))
    assert "scenario file not found (the shipped scenario of that name runs as: pool_circular)" in msg


def test_msis_localization_needs_its_sonar_and_basin():
    msg = _error("pool_circular", "sensors.msis=null")
    assert "autonomy.msis_localization.method: 'circle' needs an enabled msis sensor" in msg
    msg = _error("pool_circular", "autonomy.msis_localization.method=walls")
    assert "'walls' fits a rectangular basin but world.basin.shape is 'circular'; allowed here: 'circle' or 'none'" in msg
    msg = _error("tank_rectangular", "autonomy.msis_localization.method=circle")
    assert "allowed here: 'walls' or 'none'" in msg
    assert load_scenario("pool_circular", ["sensors.msis=null", "autonomy.msis_localization.method=none"])
