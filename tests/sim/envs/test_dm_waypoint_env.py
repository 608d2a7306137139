"""auvsim/Waypoint-v1 through dm_env: the interface contract (dm_env's own test mixin),
seeded determinism, and the same trajectory as the gymnasium env for the same actions."""

from __future__ import annotations

import numpy as np
import pytest

dm_env = pytest.importorskip("dm_env")  # with dm-control, a core dependency

from absl.testing import absltest  # noqa: E402  (absl-py comes with dm-env)
from dm_env import test_utils  # noqa: E402

from sim.envs import WAYPOINT_ID  # noqa: E402
from sim.envs.dm import WaypointDmEnv, load  # noqa: E402
from sim.envs.waypoint_env import WaypointEnv  # noqa: E402

SHORT = {"max_episode_s": 1.0}  # 10 decisions: the mixin's action sequence crosses episode ends


class WaypointDmEnvContractTest(test_utils.EnvironmentTestMixin, absltest.TestCase):
    def make_object_under_test(self):
        return WaypointDmEnv(options=SHORT, seed=0)

    def make_action_sequence(self):
        rng = np.random.default_rng(0)
        for _ in range(35):
            yield rng.uniform(-1.0, 1.0, 4).astype(np.float32)

    def test_time_limit_is_a_truncation_and_episodes_restart(self):
        env = self.environment
        steps = [env.reset()] + [env.step(np.zeros(4, np.float32)) for _ in range(11)]
        kinds = [s.step_type for s in steps]
        assert kinds[0] is dm_env.StepType.FIRST and kinds[10] is dm_env.StepType.LAST
        assert all(k is dm_env.StepType.MID for k in kinds[1:10])
        assert steps[10].discount == 1.0  # time limit: bootstrap, not a terminal state
        assert kinds[11] is dm_env.StepType.FIRST


def _gym_rollout(env: WaypointEnv, seed: int, actions: np.ndarray, episodes: int):
    obs, rew, flags = [], [], []
    for e in range(episodes):
        o, _ = env.reset(seed=seed if e == 0 else None)
        obs.append(o)
        for a in actions:
            o, r, term, trunc, _ = env.step(a)
            obs.append(o)
            rew.append(r)
            flags.append((term, trunc))
            if term or trunc:
                break
    return np.array(obs), np.array(rew), flags


def _dm_rollout(env: dm_env.Environment, actions: np.ndarray, episodes: int):
    obs, rew, flags = [], [], []
    for _ in range(episodes):
        ts = env.reset()
        obs.append(ts.observation)
        for a in actions:
            ts = env.step(a)
            obs.append(ts.observation)
            rew.append(ts.reward)
            flags.append((ts.last() and ts.discount == 0.0, ts.last() and ts.discount == 1.0))
            if ts.last():
                break
    return np.array(obs), np.array(rew), flags


@pytest.mark.parametrize("mode,options", [
    ("wrench", {"max_episode_s": 4.0}),
    # a tight area: the vehicle leaves it, a terminal step (discount 0 / terminated)
    ("setpoint", {"max_episode_s": 30.0, "area_margin_m": 0.0, "speed_range_mps": (0.9, 1.0)}),
])
def test_gym_and_dm_env_give_the_same_trajectory_bit_for_bit(mode, options):
    opts = {"action_mode": mode, **options}
    gym_env = WaypointEnv(options=opts)
    dm = load(WAYPOINT_ID, options=opts, seed=11)
    n_act = gym_env.n_act
    actions = np.random.default_rng(3).uniform(-1.0, 1.0, (300, n_act)).astype(np.float32)
    if mode == "setpoint":
        actions[:, 0] = 1.0  # full speed, straight out
        actions[:, 1] = 0.0
    g_obs, g_rew, g_flags = _gym_rollout(gym_env, 11, actions, episodes=2)
    d_obs, d_rew, d_flags = _dm_rollout(dm, actions, episodes=2)
    assert g_obs.dtype == d_obs.dtype == np.float32
    np.testing.assert_array_equal(g_obs, d_obs)
    np.testing.assert_array_equal(g_rew, d_rew)
    assert g_flags == d_flags
    ends = [f for f in g_flags if f[0] or f[1]]
    assert len(ends) == 2 and all(f[0] if mode == "setpoint" else f[1] for f in ends), ends
    assert np.ptp(g_obs[:, 11]) > 0.05  # the vehicle really moved (surge speed u varied)


def test_seeded_dm_env_is_bit_for_bit_and_seeds_differ():
    actions = np.random.default_rng(5).uniform(-1.0, 1.0, (25, 4)).astype(np.float32)
    a = _dm_rollout(WaypointDmEnv(options={"max_episode_s": 2.0}, seed=4), actions, episodes=2)
    b = _dm_rollout(WaypointDmEnv(options={"max_episode_s": 2.0}, seed=4), actions, episodes=2)
    c = _dm_rollout(WaypointDmEnv(options={"max_episode_s": 2.0}, seed=5), actions, episodes=2)
    np.testing.assert_array_equal(a[0], b[0])
    np.testing.assert_array_equal(a[1], b[1])
    assert not np.array_equal(a[0][0], c[0][0])
    assert not np.array_equal(a[0][0], a[0][21])  # the second episode is a new draw


def test_bad_arguments_are_refused():
    with pytest.raises(ValueError, match="no dm_env version"):
        load("auvsim/Nope-v0")
    with pytest.raises(ValueError, match="seed must be"):
        WaypointDmEnv(seed=-1)
    env = WaypointDmEnv(options=SHORT, seed=0)
    env.reset()
    with pytest.raises(ValueError, match="finite"):
        env.step(np.array([np.nan, 0, 0, 0], np.float32))
    with pytest.raises(ValueError, match="finite"):
        env.step(np.array([np.inf, 0, 0, 0], np.float32))  # refused, not clipped to 1
    for bad in (np.zeros(3), np.zeros((1, 4)), np.zeros((2, 2)), 0.5, None, "abcd"):
        with pytest.raises(ValueError, match="action must"):
            env.step(bad)
