"""``auvsim bench vector``: the batched Survey env timed with and without sonar, memory summed."""

from __future__ import annotations

import pytest

from scenarios.load import load_scenario
from sim.bench import vector


@pytest.mark.slow
def test_vector_bench_reports_rates_memory_and_the_sonar_ratio():
    out = vector.run(load_scenario("cssn_lawnmower", ["duration_s=30"]), workers=2, batch_sizes=(1, 2), env_steps=4)
    assert [r["n_envs"] for r in out["no_sonar"]] == [1, 2] == [r["n_envs"] for r in out["sonar"]]
    assert [r["workers"] for r in out["sonar"]] == [1, 2]
    for key in ("no_sonar", "sonar"):
        for r in out[key]:
            assert r["steps_per_s"] > 0 and r["cpu_ms_per_step"] > 0 and r["env_steps_timed"] >= r["n_envs"] * 2
            assert 50 < r["rss_mb"] < 4000
    # the sonar costs: FLS frames, the CNN and the world model on top of the same step
    for no, so, ratio in zip(out["no_sonar"], out["sonar"], out["sonar_ratio"]):
        assert so["cpu_ms_per_step"] > no["cpu_ms_per_step"]
        assert ratio["ratio"] == pytest.approx(so["steps_per_s"] / no["steps_per_s"], abs=1e-3)
