"""Every shipped scenario with every AUV preset compiles and steps 1 s with no MuJoCo warning
(surface-vessel presets are extra vehicles, not the scenario's ``vehicle``)."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from scenarios import list_scenarios, load_scenario
from sim.scene.physics import Physics
from scenarios.vehicle_params import load_params_file

PRESETS = sorted(p.parent.name for p in (Path(__file__).parents[3] / "sim" / "assets").glob("*/params.yaml")
                 if load_params_file(p).motion == "free_6dof")


def test_presets_are_found():
    assert {"feelhippo", "remus100", "bluerov2_heavy"} <= set(PRESETS) and "surface_buoy" not in PRESETS


@pytest.mark.parametrize("preset", PRESETS)
@pytest.mark.parametrize("name", sorted(list_scenarios()))
def test_scene_compiles_and_steps_one_second_without_warnings(name, preset):
    scn = load_scenario(name, [f"vehicle.model={preset}"])
    physics = Physics(scn)
    physics.reset(np.asarray(scn.vehicle.initial_pos_ned), np.deg2rad(scn.vehicle.initial_rpy_deg))
    cmd = np.full(physics.params.n_thrusters, 0.3)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        n = int(round(1.0 / physics.dt_s))
        physics.advance(cmd, n)
    assert physics.t_s == pytest.approx(1.0)
    assert physics.warnings() == 0, [(i, int(w.number)) for i, w in enumerate(physics.data.warning) if w.number]
    truth = physics.truth()
    assert np.all(np.isfinite(truth.pos_ned)) and np.all(np.isfinite(truth.nu))
    assert np.linalg.norm(truth.nu[:3]) > 0.01  # the thrusters moved the hull
