"""A scenario written out fully resolved (``auvsim validate``, a run's ``scenario.yaml``) reads
back to the same scenario, and a run folder's ``scenario.yaml`` flies the same run again."""

from __future__ import annotations

import pytest

from scenarios.load import list_scenarios, load_scenario, scenario_yaml


@pytest.mark.parametrize("name", sorted(list_scenarios()))
def test_every_shipped_scenario_reads_back_equal(name, tmp_path):
    scn = load_scenario(name, ["seed=7"])
    path = tmp_path / "s.yaml"
    path.write_text(scenario_yaml(scn))
    again = load_scenario(path)
    assert again.model_dump(mode="json") == scn.model_dump(mode="json")
    assert list(again.sensors) == list(scn.sensors)  # removed default entries stay removed


def test_a_run_folder_holds_the_scenario_it_flew_and_it_flies_again(tmp_path):
    from sim.mission.run import run_mission

    scn = load_scenario("cssn_lawnmower", ["duration_s=4", "seed=5", "autonomy.atr.detector=classical",
                                           "sensors.fls.formation.pulse_length_m=0.02"])
    run_mission(scn, tmp_path / "a", rerun=False, progress=False)
    written = load_scenario(tmp_path / "a" / "scenario.yaml")
    assert written.seed == 5 and written.sensors.fls.formation.pulse_length_m == 0.02
    run_mission(written, tmp_path / "b", rerun=False, progress=False)
    assert (tmp_path / "a" / "trajectory.csv").read_bytes() == (tmp_path / "b" / "trajectory.csv").read_bytes()


def test_a_misspelt_sensor_entry_in_an_override_is_named_with_the_closest():
    from scenarios.load import ScenarioError

    with pytest.raises(ScenarioError, match="did you mean fls"):
        load_scenario("cssn_lawnmower", ["sensors.fsl.formation.pulse_length_m=0.012"])


def test_an_override_that_adds_a_sensor_entry_says_so():
    notes: list[str] = []
    scn = load_scenario("cssn_lawnmower", ["sensors.sss.range_max_m=30"], notes=notes)
    assert "sss" in scn.sensors
    assert any("adds a sensor entry sss" in n for n in notes)
    notes.clear()
    load_scenario("cssn_lawnmower", ["sensors.fls.tilt_deg=20"], notes=notes)
    assert not notes
