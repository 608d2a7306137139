"""auvsim/Waypoint-v1 applies its per-episode current: a passive hull drifts with the water."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import sim.envs  # noqa: F401  (registers the ids)
from scenarios import load_scenario
from scenarios.config.world import CurrentConfig
from sim.envs import WAYPOINT_ID
from sim.scene.physics import Physics


def test_passive_hull_drifts_with_the_episode_current():
    env = gym.make(WAYPOINT_ID, options={"current_speed_max_mps": 0.3})
    _, info = env.reset(seed=1)
    physics = env.unwrapped.physics
    start = info["pos_ned"].copy()
    water = np.zeros(3)  # the current's own displacement, integrated from its velocity (trapezoid)
    dt = env.unwrapped.decision_interval_s
    for _ in range(400):  # 40 s, thrusters off
        v0 = physics.current.velocity_ned
        _, _, term, trunc, info = env.step(np.zeros(4, dtype=np.float32))
        water += 0.5 * (v0 + physics.current.velocity_ned) * dt
        assert not (term or trunc)
    drift = info["pos_ned"][:2] - start[:2]
    speed = float(np.linalg.norm(physics.current.velocity_ned[:2]))
    assert 0.2 < speed < 0.3  # this episode's current
    # the hull, started at rest, lags the water by its drag time constant, then moves with it
    assert 0.85 * np.linalg.norm(water[:2]) <= np.linalg.norm(drift) <= np.linalg.norm(water[:2])
    assert np.linalg.norm(drift) > 8.5
    cos = drift @ water[:2] / (np.linalg.norm(drift) * np.linalg.norm(water[:2]))
    assert cos > np.cos(np.radians(5.0))
    np.testing.assert_allclose(physics.truth().vel_ned_mps[:2], physics.current.velocity_ned[:2], atol=5e-3)


def test_current_set_after_construction_acts_and_its_random_part_evolves():
    scn = load_scenario("cssn_lawnmower")
    physics = Physics(scn)
    assert physics.current.is_still
    cfg = CurrentConfig(velocity_ned_mps=(0.2, 0.0, 0.0), gauss_markov_sigma_mps=0.05, gauss_markov_tau_s=20.0)
    physics.set_current(cfg, np.random.default_rng(0))
    physics.reset(np.array([0.0, 17.0, 2.0]), np.zeros(3))
    seen = []
    for _ in range(30):
        physics.advance(np.zeros(physics.params.n_thrusters), int(round(1.0 / physics.dt_s)))
        seen.append(physics.current.velocity_ned[:2].copy())
    seen = np.array(seen)
    assert np.std(seen[:, 1]) > 1e-3  # the Gauss-Markov part is advanced
    assert physics.truth().pos_ned[0] > 3.0  # carried north by the mean current
    physics.reset(np.array([0.0, 17.0, 2.0]), np.zeros(3))
    np.testing.assert_array_equal(physics.current.velocity_ned, [0.2, 0.0, 0.0])  # reset: calm start


def test_retired_ids_say_why():
    for old in ("auvsim/Waypoint-v0", "auvsim/Survey-v0"):
        with pytest.raises(gym.error.DeprecatedEnv, match="retired"):
            gym.make(old)
