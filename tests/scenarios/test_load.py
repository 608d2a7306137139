"""Scenario loading, validation errors, overrides and the CLI front end."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from scenarios import ScenarioError, list_scenarios, load_scenario
from sim.cli import main


def _write(tmp_path: Path, data: dict) -> Path:
    path = tmp_path / "scn.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def test_shipped_scenarios_load_and_are_listed():
    shipped = list_scenarios()
    assert "cssn_lawnmower" in shipped and shipped["cssn_lawnmower"]
    for name in shipped:
        scn = load_scenario(name)
        assert scn.name == name


def test_cssn_matches_paper_table_iii():
    scn = load_scenario("cssn_lawnmower")
    pos = {t.name: t.pos_ned for t in scn.world.targets}
    assert pos == {
        "OPI1": (0.0, 10.0, 4.0), "OPI2": (0.0, 20.0, 4.0), "OPI3": (0.0, 25.0, 4.0),
        "OPI4": (-8.0, 10.0, 4.0), "OPI5": (-7.0, 15.0, 4.0), "OPI6": (-8.0, 22.0, 4.0),
    }
    assert all(t.shape == "half_sphere" for t in scn.world.targets)
    assert scn.world.seabed.depth_m == pytest.approx(4.0)
    assert scn.autonomy.guidance.survey.speed_mps == pytest.approx(0.5)


def test_scenario_is_frozen():
    scn = load_scenario("cssn_lawnmower")
    with pytest.raises(Exception):
        scn.seed = 3  # type: ignore[misc]


def test_overrides_apply_with_yaml_types():
    scn = load_scenario("cssn_lawnmower", ["vehicle.mass_kg=36", "seed=3", "world.targets.0.radius_m=0.7"])
    assert scn.vehicle.mass_kg == 36.0 and scn.seed == 3
    assert scn.world.targets[0].radius_m == pytest.approx(0.7)


def test_unknown_key_names_file_path_and_allowed(tmp_path):
    path = _write(tmp_path, {"name": "x", "vehicle": {"mas_kg": 3}})
    with pytest.raises(ScenarioError) as exc:
        load_scenario(path)
    msg = str(exc.value)
    assert str(path) in msg and "vehicle.mas_kg" in msg and "mass_kg" in msg


def test_bad_type_names_key(tmp_path):
    path = _write(tmp_path, {"name": "x", "physics": {"rate_hz": "fast"}})
    with pytest.raises(ScenarioError) as exc:
        load_scenario(path)
    assert "physics.rate_hz" in str(exc.value) and "valid number" in str(exc.value)


def test_out_of_range_names_bound(tmp_path):
    path = _write(tmp_path, {"name": "x", "world": {"targets": [
        {"name": "a", "shape": "half_sphere", "pos_ned": [0, 0, 4], "reflectivity": 1.5}]}})
    with pytest.raises(ScenarioError) as exc:
        load_scenario(path)
    msg = str(exc.value)
    assert "world.targets.0.reflectivity" in msg and "less than or equal to 1" in msg


def test_bad_literal_lists_allowed_values():
    with pytest.raises(ScenarioError) as exc:
        load_scenario("cssn_lawnmower", ["world.seabed.kind=lumpy"])
    assert "world.seabed.kind" in str(exc.value) and "'rough'" in str(exc.value)


def test_missing_file_says_so(tmp_path):
    with pytest.raises(ScenarioError, match="not found"):
        load_scenario(tmp_path / "nope.yaml")
    with pytest.raises(ScenarioError, match="no such scenario"):
        load_scenario("no_such_scenario")


def test_bad_override_syntax():
    with pytest.raises(ScenarioError, match="key.path=value"):
        load_scenario("cssn_lawnmower", ["seed"])


def test_cli_validate_prints_resolved(capsys):
    assert main(["validate", "cssn_lawnmower", "--set", "seed=7"]) == 0
    out = yaml.safe_load(capsys.readouterr().out)
    assert out["seed"] == 7 and out["world"]["targets"][0]["name"] == "OPI1"


def test_cli_errors_without_traceback(tmp_path):
    path = _write(tmp_path, {"name": "x", "bogus": 1})
    proc = subprocess.run([sys.executable, "-m", "sim.cli", "validate", str(path)],
                          capture_output=True, text=True)
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr and "bogus" in proc.stderr and str(path) in proc.stderr


def test_cli_lists_scenarios(capsys):
    assert main(["scenarios"]) == 0
    assert "cssn_lawnmower" in capsys.readouterr().out


@pytest.mark.parametrize("override, allowed", [
    ("autonomy.guidance.survey.leg_spacing_m=from_swat", "allowed: a number or 'from_swath' (got 'from_swat')"),
    ("autonomy.guidance.inspection.coverage_spacing_m=-3", "allowed: a number (greater than 0) or 'from_swath' (got -3)"),
])
def test_a_value_failing_every_member_of_a_union_is_one_line(override, allowed):
    with pytest.raises(ScenarioError) as err:
        load_scenario("cssn_inspect", [override])
    text = str(err.value)
    assert "\n" not in text and allowed in text and "constrained-float" not in text
    assert override.split("=")[0] in text
