"""Indoors (a roofed pool or tank) there is no sky view, so no GPS: the default suite leaves
it out, an enabled one is refused at load, and the estimate is not thrown off by a fix."""

from __future__ import annotations

import pytest

from scenarios import ScenarioError, load_scenario
from sim.cli import main


@pytest.mark.parametrize("name", ["pool_circular", "tank_rectangular"])
def test_indoor_scenarios_carry_no_gps(name):
    scn = load_scenario(name)
    assert scn.world.indoor
    assert all(cfg.kind != "gps" for _, cfg in scn.sensors.items())
    assert "gps" in load_scenario(name, ["world.indoor=false"]).sensors  # the default suite outdoors


def test_outdoor_scenarios_keep_the_default_gps():
    scn = load_scenario("cssn_lawnmower")
    assert not scn.world.indoor and scn.sensors.gps.enabled


@pytest.mark.parametrize("overrides", [["sensors.gps.noise_m=0.5"], ["sensors.gnss.kind=gps"]])
def test_an_enabled_gps_indoors_is_refused_naming_the_keys(overrides):
    with pytest.raises(ScenarioError) as err:
        load_scenario("pool_circular", overrides)
    msg = str(err.value)
    assert len(msg.splitlines()) == 1
    assert "world.indoor" in msg and "no fix indoors" in msg and "--set" in msg
    entry = overrides[0].split(".")[1]
    assert f"sensors.{entry}" in msg


def test_a_disabled_gps_entry_indoors_loads():
    scn = load_scenario("tank_rectangular", ["sensors.gps.enabled=false"])
    assert scn.sensors.first_of_kind("gps") is None


def test_validate_refuses_a_gps_indoors_with_exit_2(capsys):
    assert main(["validate", "pool_circular", "--set", "world.indoor=true", "--set", "sensors.gps.rate_hz=2"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("auvsim validate: error: pool_circular") and "sensors.gps" in err
    assert "Traceback" not in err


def test_the_pool_start_is_not_thrown_off_by_a_surface_fix():
    """The pool starts at 0.3 m depth, its antenna at the surface: a default-suite GPS fix there
    (1 m noise) threw the estimate about 1 m off before the first circle fix (4.5 s). Without
    one, 4 s of AHRS + speed-model dead reckoning from the known start stays within 0.2 m."""
    from sim.mission import Mission
    from sim.features import MsisLocalizationFeature

    mission = Mission(load_scenario("pool_circular", ["duration_s=4"]))
    obs = mission.feature(MsisLocalizationFeature).error_observer()
    mission.observers.append(obs)
    mission.run(progress=False)
    assert "gps" not in mission.summary().messages_delivered
    assert max(obs.err_fused_m) < 0.2 and max(obs.err_dr_m) < 0.2
