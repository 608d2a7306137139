"""The dm_control build of the tasks (sim.envs.dm): a ``control.Environment`` of
``AuvPhysics`` (a ``dm_control.mujoco.Physics`` over the simulation's own MjData) and a
``control.Task``; checked against independently stepped gymnasium envs, bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

dm_env = pytest.importorskip("dm_env")

from absl.testing import absltest  # noqa: E402
from dm_env import test_utils  # noqa: E402

from sim.envs import SURVEY_ID, WAYPOINT_ID  # noqa: E402
from sim.envs.dm import AuvPhysics, SurveyDmEnv, WaypointDmEnv, _time_limit_s, load  # noqa: E402  (imports dm_control quietly)

from dm_control import mujoco as dm_mujoco  # noqa: E402
from dm_control.rl import control  # noqa: E402
from sim.envs.survey_env import SurveyEnv  # noqa: E402
from sim.envs.time_limit import reached_time_limit, time_limit_steps  # noqa: E402
from sim.envs.waypoint_env import WaypointEnv  # noqa: E402

WP_SHORT = {"max_episode_s": 1.0}  # 10 decisions of 0.1 s
SV_SHORT = {"sonar": False, "max_episode_s": 3.0}  # 3 decisions of 1 s
# setpoint mode at full speed straight ahead in a tight area: leaves it (a terminal step)
WP_LEAVE = {"action_mode": "setpoint", "max_episode_s": 30.0, "area_margin_m": 0.0, "speed_range_mps": (0.9, 1.0)}


class WaypointControlContractTest(test_utils.EnvironmentTestMixin, absltest.TestCase):
    def make_object_under_test(self):
        return WaypointDmEnv(options=WP_SHORT, seed=0)

    def make_action_sequence(self):
        rng = np.random.default_rng(1)
        for _ in range(25):  # crosses two episode ends
            yield rng.uniform(-1.0, 1.0, 4).astype(np.float32)


class SurveyControlContractTest(test_utils.EnvironmentTestMixin, absltest.TestCase):
    def make_object_under_test(self):
        return SurveyDmEnv(options=SV_SHORT, seed=0)

    def make_action_sequence(self):
        rng = np.random.default_rng(1)
        for _ in range(8):  # crosses two episode ends
            yield rng.uniform(-1.0, 1.0, 3).astype(np.float32)


def _vehicle_joint(physics: AuvPhysics) -> str:
    names = [n for n in physics.named.data.qpos.axes.row.names if n.endswith("vehicle_free")]
    assert len(names) == 1, names
    return names[0]


def test_the_env_is_a_dm_control_environment_of_an_auv_physics_over_the_simulations_mjdata():
    env = load(WAYPOINT_ID, options=WP_SHORT, seed=2)
    assert isinstance(env, control.Environment)
    assert isinstance(env.task, control.Task)
    physics = env.physics
    assert isinstance(physics, AuvPhysics) and isinstance(physics, dm_mujoco.Physics)
    shared = env.task.shared
    assert env.task.options is shared.options  # attributes read through to the shared task
    assert isinstance(env.task.rng, np.random.Generator)
    sim = shared.sim_physics
    assert physics.sim is sim and physics.data.ptr is sim.data and physics.model.ptr is sim.model
    assert physics.timestep() == env.control_timestep() == shared.decision_interval_s == pytest.approx(0.1)
    assert physics.model.opt.timestep == pytest.approx(1.0 / 50.0)  # MuJoCo's step is the physics rate's

    env.reset()
    joint = _vehicle_joint(physics)
    q0 = physics.named.data.qpos[joint].copy()
    np.testing.assert_array_equal(q0[:3], shared.pos_ned)  # free joint: CO position in NED
    np.testing.assert_array_equal(physics.pos_ned(), shared.pos_ned)
    t_mj0 = float(physics.data.time)
    env.step(np.array([1.0, 0.0, 0.5, 0.3], np.float32))
    q1 = physics.named.data.qpos[joint].copy()
    assert not np.array_equal(q0, q1)  # the env's step moved the very MjData dm_control reads
    np.testing.assert_array_equal(q1[:3], shared.pos_ned)
    np.testing.assert_array_equal(physics.data.qpos, sim.data.qpos)
    np.testing.assert_array_equal(physics.pos_ned(), shared.pos_ned)
    np.testing.assert_array_equal(physics.rpy_rad(), shared.rpy_rad)
    assert physics.depth_m() == shared.pos_ned[2]
    assert physics.time() == physics.time_s() == shared.t_s == pytest.approx(0.1)
    assert float(physics.data.time) - t_mj0 == pytest.approx(0.1)  # five MuJoCo steps of 0.02 s
    obs = env.task.get_observation(physics)
    nu = physics.nu_body()
    assert nu.shape == (6,)
    np.testing.assert_array_equal(obs[11:17], nu.astype(np.float32))  # [u v w p q r] FRD of the observation
    np.testing.assert_array_equal(physics.velocity_body_mps(), nu[:3])
    assert physics.altitude_m() == pytest.approx(float(obs[18]), abs=1e-5)
    with pytest.raises(NotImplementedError):
        physics.copy()


def test_the_survey_physics_wraps_each_episodes_mission():
    env = load(SURVEY_ID, options=SV_SHORT, seed=3)
    physics = env.physics
    env.reset()
    first = env.task.mission.physics
    assert physics.sim is first and physics.data.ptr is first.data and physics.model.ptr is first.model
    joint = _vehicle_joint(physics)
    q0 = physics.named.data.qpos[joint].copy()
    env.step(np.array([1.0, 0.0, 0.0], np.float32))
    q1 = physics.named.data.qpos[joint].copy()
    assert not np.array_equal(q0, q1)
    truth = first.truth()
    np.testing.assert_array_equal(physics.pos_ned(), truth.pos_ned)
    np.testing.assert_array_equal(q1[:3], truth.pos_ned)
    assert physics.time() == env.task.t_s == pytest.approx(1.0)
    env.reset()
    second = env.task.mission.physics
    assert second is not first  # a new mission (and MjData) per episode, and the physics follows
    assert physics.sim is second and physics.data.ptr is second.data and physics.model.ptr is second.model
    np.testing.assert_array_equal(physics.named.data.qpos[joint], second.data.qpos)


def _gym_rollout(env, seed: int, actions: np.ndarray, episodes: int):
    """Observations, rewards, (terminated, truncated) and the simulation's qpos per step."""
    obs, rew, flags, qpos = [], [], [], []
    for e in range(episodes):
        o, _ = env.reset(seed=seed if e == 0 else None)
        obs.append(o)
        qpos.append(env.unwrapped.task.sim_physics.data.qpos.copy())
        for a in actions:
            o, r, term, trunc, _ = env.step(a)
            obs.append(o)
            rew.append(r)
            flags.append((term, trunc))
            qpos.append(env.unwrapped.task.sim_physics.data.qpos.copy())
            if term or trunc:
                break
    return obs, rew, flags, qpos


def _dm_rollout(env: control.Environment, actions: np.ndarray, episodes: int):
    """As :func:`_gym_rollout`, the qpos read through dm_control's named indexer, and the
    named readouts called every step (they must not change the trajectory)."""
    obs, rew, flags, qpos, discounts = [], [], [], [], []
    for _ in range(episodes):
        ts = env.reset()
        obs.append(ts.observation)
        qpos.append(np.asarray(env.physics.named.data.qpos).copy())
        for a in actions:
            env.physics.pos_ned(), env.physics.nu_body(), env.physics.altitude_m()
            ts = env.step(a)
            obs.append(ts.observation)
            rew.append(ts.reward)
            discounts.append(ts.discount)
            flags.append((ts.last() and ts.discount == 0.0, ts.last() and ts.discount == 1.0))
            qpos.append(np.asarray(env.physics.named.data.qpos).copy())
            if ts.last():
                break
    return obs, rew, flags, qpos, discounts


def _assert_equal_obs(a, b) -> None:
    assert len(a) == len(b)
    for x, y in zip(a, b):
        if isinstance(x, dict):
            assert x.keys() == y.keys()
            for key in x:
                assert x[key].dtype == y[key].dtype and np.array_equal(x[key], y[key]), key
        else:
            assert x.dtype == y.dtype == np.float32 and np.array_equal(x, y)


@pytest.mark.parametrize("env_id,gym_cls,options,n_act,end", [
    (WAYPOINT_ID, WaypointEnv, {"max_episode_s": 2.0}, 4, "truncated"),
    (WAYPOINT_ID, WaypointEnv, WP_LEAVE, 3, "terminated"),
    (SURVEY_ID, SurveyEnv, SV_SHORT, 3, "truncated"),
    (SURVEY_ID, SurveyEnv, {"sonar": False, "max_episode_s": 30.0, "area_margin_m": 0.0}, 3, "terminated"),
])
def test_dm_control_and_gymnasium_give_the_same_trajectory_bit_for_bit(env_id, gym_cls, options, n_act, end):
    actions = np.random.default_rng(7).uniform(-1.0, 1.0, (400, n_act)).astype(np.float32)
    if end == "terminated":  # full speed; Survey: full left turn out of the south-west corner
        actions[:, 0] = 1.0
        actions[:, 1] = 0.0 if env_id == WAYPOINT_ID else -1.0
    gym_env = gym_cls(options=options)
    dm = load(env_id, options=options, seed=21)
    g_obs, g_rew, g_flags, g_qpos = _gym_rollout(gym_env, 21, actions, episodes=2)
    d_obs, d_rew, d_flags, d_qpos, d_disc = _dm_rollout(dm, actions, episodes=2)
    _assert_equal_obs(g_obs, d_obs)
    assert np.array_equal(np.array(g_rew), np.array(d_rew))
    assert g_flags == d_flags
    assert len(g_qpos) == len(d_qpos) and all(np.array_equal(g, d) for g, d in zip(g_qpos, d_qpos))
    ends = [i for i, f in enumerate(g_flags) if f[0] or f[1]]
    assert len(ends) == 2, g_flags
    for i in ends:
        assert g_flags[i] == ((True, False) if end == "terminated" else (False, True))
        assert d_disc[i] == (0.0 if end == "terminated" else 1.0)
    assert all(d == 1.0 for i, d in enumerate(d_disc) if i not in ends)
    if end == "truncated":  # the episode lengths are the time limit, in decisions
        first = ends[0] + 1
        assert first == dm.time_limit_steps == dm.task.time_limit_steps
        assert ends[1] - ends[0] == first
    assert not np.array_equal(g_qpos[0], g_qpos[ends[0] + 1])  # the second episode is a new draw


def test_a_limit_with_rounding_truncates_at_the_gym_envs_decision():
    # 0.9 s of 0.06 s decisions: 0.9 / 0.06 = 15.000000000000002, so a plain time_limit=0.9
    # would let dm_control run a 16th step; the gym env truncates at the 15th.
    opts = {"max_episode_s": 0.9, "decision_interval_s": 0.06}
    gym_env = WaypointEnv(options=opts)
    dm = WaypointDmEnv(options=opts, seed=0)
    assert 0.9 / dm.control_timestep() > 15 and dm.time_limit_steps == 15
    zeros = np.zeros(4, np.float32)
    gym_env.reset(seed=0)
    g_trunc = [gym_env.step(zeros)[3] for _ in range(15)]
    dm.reset()
    d_steps = [dm.step(zeros) for _ in range(15)]
    assert g_trunc == [False] * 14 + [True]
    assert [ts.last() for ts in d_steps] == g_trunc and d_steps[-1].discount == 1.0


def test_a_terminal_step_on_the_time_limits_decision_has_discount_0():
    actions = np.tile(np.array([1.0, 0.0, 0.0], np.float32), (400, 1))
    probe = WaypointEnv(options=WP_LEAVE)
    probe.reset(seed=5)
    for k in range(1, 401):
        _, _, term, trunc, _ = probe.step(actions[k - 1])
        if term or trunc:
            break
    assert term and k > 3
    opts = {**WP_LEAVE, "max_episode_s": k * probe.decision_interval_s}  # the limit falls on that decision
    gym_env = WaypointEnv(options=opts)
    gym_env.reset(seed=5)
    dm = WaypointDmEnv(options=opts, seed=5)
    assert dm.time_limit_steps == k
    dm.reset()
    for i in range(k):
        _, g_r, g_term, g_trunc, _ = gym_env.step(actions[i])
        ts = dm.step(actions[i])
        assert ts.reward == g_r
    assert (g_term, g_trunc) == (True, False)
    assert ts.last() and ts.discount == 0.0  # control.Environment alone would give the limit's 1.0


@pytest.mark.parametrize("interval_s", [0.1, 0.02, 0.06, 0.3, 1.0 / 3.0, 0.05, 1.0, 0.25])
@pytest.mark.parametrize("limit_s", [0.3, 0.7, 0.9, 1.0, 1.1, 2.7, 2.9, 7.3, 60.0, 120.0, 0.01])
def test_the_environments_step_limit_is_the_tasks_truncation_decision(interval_s, limit_s):
    n = time_limit_steps(interval_s, limit_s)
    first = next(k for k in range(1, 100000) if reached_time_limit(k, interval_s, limit_s))
    assert n == first
    step_limit = _time_limit_s(n, interval_s) / interval_s  # control.Environment's formula
    assert next(k for k in range(1, 100000) if k >= step_limit) == n


def test_the_task_draws_from_its_generator():
    rng = np.random.Generator(np.random.PCG64(np.random.SeedSequence(9)))
    env = WaypointDmEnv(options=WP_SHORT, seed=rng)
    assert env.task.rng is rng
    before = rng.bit_generator.state["state"]["state"]
    env.reset()
    assert rng.bit_generator.state["state"]["state"] != before  # the episode was drawn from it
    gym_env = WaypointEnv(options=WP_SHORT)
    o, _ = gym_env.reset(seed=9)
    ts = WaypointDmEnv(options=WP_SHORT, seed=9).reset()
    np.testing.assert_array_equal(o, ts.observation)
