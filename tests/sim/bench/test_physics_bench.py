"""The physics benchmark runs the scenario's scene and reports consistent figures."""

from __future__ import annotations

import pytest

from sim.bench.physics import run


def test_bench_physics_reports_rates(cssn_scenario):
    out = run(cssn_scenario, sim_time_s=2.0)
    for key in ("steps_per_s", "real_time_factor", "sim_time_s", "wall_time_s", "rate_hz"):
        assert key in out
    assert out["rate_hz"] == pytest.approx(cssn_scenario.physics.rate_hz)
    assert out["sim_time_s"] == pytest.approx(2.0)
    assert out["n_steps"] == 400
    assert out["steps_per_s"] == pytest.approx(out["n_steps"] / out["wall_time_s"])
    assert out["real_time_factor"] == pytest.approx(out["steps_per_s"] / out["rate_hz"])
    assert out["mujoco_warnings"] == 0
    with pytest.raises(ValueError, match="sim_time_s"):
        run(cssn_scenario, sim_time_s=0.0)
