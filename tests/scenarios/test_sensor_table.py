"""The scenario's sensor table: named entries typed by kind, defaults, removal, errors."""

from __future__ import annotations

import pytest

from scenarios import ScenarioError, list_scenarios, load_scenario
from scenarios.config.fls import FlsConfig
from scenarios.config.nav_sensors import DvlConfig, ImuConfig
from scenarios.schema import Scenario, SensorsConfig

DEFAULTS = ["imu", "dvl", "depth", "altimeter", "gps", "fls"]


@pytest.mark.parametrize("name", sorted(list_scenarios()))
def test_shipped_files_load_unchanged_with_the_default_suite(name):
    scn = load_scenario(name)
    if "msis" in scn.sensors:  # the scanning-sonar pool and tank scenarios replace the FLS
        dvl_free = scn.autonomy.navigation.velocity_source == "speed_model"  # the pool also drops the DVL
        removed = {"fls", "dvl"} if dvl_free else {"fls"}
        if scn.world.indoor:  # indoors: no GPS
            removed.add("gps")
        assert list(scn.sensors) == [d for d in DEFAULTS if d not in removed] + ["msis"]
        dump = scn.model_dump()
        # a dump lists the entries kept; the removed defaults need their nulls again
        assert Scenario.model_validate({**dump, "sensors": {**dump["sensors"], **dict.fromkeys(removed)}}) == scn
        return
    if scn.mcm.mode == "full":  # the MCM full mode replaces the FLS with a side-scan sonar
        assert list(scn.sensors) == [d for d in DEFAULTS if d != "fls"] + ["sss"]
        dump = scn.model_dump()
        assert Scenario.model_validate({**dump, "sensors": {**dump["sensors"], "fls": None}}) == scn
        return
    tracking = scn.autonomy.tracking.enabled  # the diver-tracking scenarios add a USBL, an ARIS window
    assert list(scn.sensors) == DEFAULTS + (["usbl"] if tracking else [])
    assert all(cfg.kind == entry for entry, cfg in scn.sensors.items())
    if not tracking:
        assert scn.sensors.fls.range_window_m == (1.0, 30.0) and scn.sensors.imu.rate_hz == 50.0
    assert Scenario.model_validate(scn.model_dump()) == scn  # a dump reloads as the same scenario


def test_entries_are_typed_by_kind_and_may_be_added_or_removed():
    table = SensorsConfig({"sonar_port": {"kind": "fls", "tilt_deg": 20.0}, "fls": None,
                           "imu": {"heading_source": "ahrs"}})
    assert list(table) == ["imu", "dvl", "depth", "altimeter", "gps", "sonar_port"]
    assert isinstance(table["sonar_port"], FlsConfig) and table.sonar_port.tilt_deg == 20.0
    assert isinstance(table.imu, ImuConfig) and table.imu.heading_source == "ahrs"
    assert isinstance(table.first_of_kind("dvl"), DvlConfig) and table.first_of_kind("fls") is table.sonar_port
    two = SensorsConfig({"fls_b": {"kind": "fls"}})
    assert [c.kind for c in two.enabled().values()].count("fls") == 2
    assert "fls" not in SensorsConfig({"fls": None})
    assert "fls" not in SensorsConfig({"fls": {"enabled": False}}).enabled()


def test_errors_name_the_entry_and_field():
    with pytest.raises(ScenarioError, match=r"sensors\.fls\.rate_hz"):
        load_scenario("cssn_lawnmower", ["sensors.fls.rate_hz=-3"])
    with pytest.raises(ScenarioError, match=r"sensors\.extra is no entry of the scenario.*needs kind"):
        load_scenario("cssn_lawnmower", ["sensors.extra.rate_hz=4"])
    with pytest.raises(ScenarioError, match=r"sensors\.extra.*'sonar9'"):
        load_scenario("cssn_lawnmower", ["sensors.extra.kind=sonar9"])
    with pytest.raises(ScenarioError, match=r"sensors\.dvl\.bogus"):
        load_scenario("cssn_lawnmower", ["sensors.dvl.bogus=1"])
    with pytest.raises(ScenarioError, match="tilt_deg"):
        load_scenario("cssn_lawnmower", ["sensors.fls.mount_rpy_deg=[0, 5, 0]"])
