"""auvsim/Survey-v1 through dm_env: the interface contract (dm_env's own test mixin), the
dict observation spec (with and without the sonar image), seeded determinism, and the
same trajectory as the gymnasium env for the same seed and actions."""

from __future__ import annotations

import numpy as np
import pytest

dm_env = pytest.importorskip("dm_env")  # with dm-control, a core dependency

from absl.testing import absltest  # noqa: E402  (absl-py comes with dm-env)
from dm_env import test_utils  # noqa: E402

from sim.envs import SURVEY_ID  # noqa: E402
from sim.envs.dm import SurveyDmEnv, load  # noqa: E402
from sim.envs.survey_env import NAV_FEATURES, SurveyEnv  # noqa: E402
from sim.envs.world_model_obs import ANCHOR_FEATURES  # noqa: E402

SHORT = {"sonar": False, "max_episode_s": 3.0}  # 3 decisions: the mixin's actions cross episode ends
# Full speed, full left turn from the south-west corner heading north: the vehicle leaves the
# area westwards within a few decisions, a terminal step.
LEAVE = {"sonar": False, "max_episode_s": 30.0, "area_margin_m": 0.0}
SONAR = {"sonar": True, "max_episode_s": 3.0, "sonar_shape": (32, 48)}
CLASSICAL = ("autonomy.atr.detector=classical",)


class SurveyDmEnvContractTest(test_utils.EnvironmentTestMixin, absltest.TestCase):
    def make_object_under_test(self):
        return SurveyDmEnv(options=SHORT, seed=0)

    def make_action_sequence(self):
        rng = np.random.default_rng(0)
        for _ in range(10):
            yield rng.uniform(-1.0, 1.0, 3).astype(np.float32)

    def test_time_limit_is_a_truncation_and_episodes_restart(self):
        env = self.environment
        steps = [env.reset()] + [env.step(np.zeros(3, np.float32)) for _ in range(4)]
        kinds = [s.step_type for s in steps]
        assert kinds == [dm_env.StepType.FIRST, dm_env.StepType.MID, dm_env.StepType.MID, dm_env.StepType.LAST,
                         dm_env.StepType.FIRST]
        assert steps[3].discount == 1.0  # time limit: bootstrap, not a terminal state
        assert env.last_info["t_s"] == pytest.approx(0.0)  # the new episode's reset info


def test_observation_spec_is_the_dict_of_the_gym_spaces_with_sonar_image():
    off = load(SURVEY_ID, options=SHORT, seed=0)
    on = load(SURVEY_ID, options=SONAR, overrides=CLASSICAL, seed=1)
    k = off.task.options.top_k_anchors
    expected = {"nav": ((len(NAV_FEATURES),), np.float32), "anchors": ((k, len(ANCHOR_FEATURES)), np.float32),
                "anchor_mask": ((k,), np.int8), "coverage": ((16, 16), np.float32)}
    assert {key: (s.shape, s.dtype) for key, s in off.observation_spec().items()} == expected
    assert {key: (s.shape, s.dtype) for key, s in on.observation_spec().items()} == {
        **expected, "sonar": ((32, 48), np.uint8)}
    sonar_spec = on.observation_spec()["sonar"]
    assert sonar_spec.minimum.min() == 0 and sonar_spec.maximum.max() == 255
    gym_space = SurveyEnv(options=SONAR, overrides=CLASSICAL).observation_space
    for key, spec in on.observation_spec().items():
        if key != "anchor_mask":  # a MultiBinary in gymnasium
            np.testing.assert_array_equal(spec.minimum, gym_space[key].low)
            np.testing.assert_array_equal(spec.maximum, gym_space[key].high)
    ts = on.reset()
    for _ in range(2):
        ts = on.step(np.zeros(3, np.float32))
        for key, spec in on.observation_spec().items():
            spec.validate(ts.observation[key])
    assert on.task.mission.n_fls_frames >= 5 and ts.observation["sonar"].max() > 0  # a real fan image


def _gym_rollout(env: SurveyEnv, seed: int, actions: np.ndarray, episodes: int):
    obs, rew, flags, infos = [], [], [], []
    for e in range(episodes):
        o, _ = env.reset(seed=seed if e == 0 else None)
        obs.append(o)
        for a in actions:
            o, r, term, trunc, info = env.step(a)
            obs.append(o)
            rew.append(r)
            flags.append((term, trunc))
            infos.append(info)
            if term or trunc:
                break
    return obs, np.array(rew), flags, infos


def _dm_rollout(env: dm_env.Environment, actions: np.ndarray, episodes: int):
    obs, rew, flags, infos = [], [], [], []
    for _ in range(episodes):
        ts = env.reset()
        obs.append(ts.observation)
        for a in actions:
            ts = env.step(a)
            obs.append(ts.observation)
            rew.append(ts.reward)
            flags.append((ts.last() and ts.discount == 0.0, ts.last() and ts.discount == 1.0))
            infos.append(env.last_info)
            if ts.last():
                break
    return obs, np.array(rew), flags, infos


def _assert_same_obs(a: list[dict], b: list[dict]) -> None:
    assert len(a) == len(b)
    for x, y in zip(a, b):
        assert x.keys() == y.keys()
        for key in x:
            assert x[key].dtype == y[key].dtype, key
            np.testing.assert_array_equal(x[key], y[key], err_msg=key)


@pytest.mark.parametrize("options,overrides,turn,end", [
    (SHORT, (), None, "truncated"),
    (LEAVE, (), -1.0, "terminated"),
    (SONAR, CLASSICAL, None, "truncated"),
])
def test_gym_and_dm_env_give_the_same_trajectory_bit_for_bit(options, overrides, turn, end):
    gym_env = SurveyEnv(options=options, overrides=overrides)
    dm = load(SURVEY_ID, options=options, overrides=overrides, seed=11)
    actions = np.random.default_rng(3).uniform(-1.0, 1.0, (30, 3)).astype(np.float32)
    if turn is not None:
        actions[:, 0], actions[:, 1] = 1.0, turn
    g_obs, g_rew, g_flags, g_infos = _gym_rollout(gym_env, 11, actions, episodes=2)
    d_obs, d_rew, d_flags, d_infos = _dm_rollout(dm, actions, episodes=2)
    _assert_same_obs(g_obs, d_obs)
    np.testing.assert_array_equal(g_rew, d_rew)
    assert g_flags == d_flags
    for gi, di in zip(g_infos, d_infos):
        np.testing.assert_array_equal(gi["nav_pos_ned"], di["nav_pos_ned"])
        assert gi["energy"] == di["energy"] and gi["coverage_fraction"] == di["coverage_fraction"]
    ends = [i for i, f in enumerate(g_flags) if f[0] or f[1]]
    assert len(ends) == 2, g_flags
    for i in ends:
        assert g_flags[i] == ((True, False) if end == "terminated" else (False, True))
        if end == "terminated":  # left westwards: beyond the area's western edge, penalised
            assert g_infos[i]["left_area"] and g_infos[i]["nav_pos_ned"][1] < gym_env.area.lo_ne_m[1] + 0.5
            assert g_rew[i] < -0.9 * gym_env.options.reward.leave_area
    u = [o["nav"][NAV_FEATURES.index("u_mps")] for o in g_obs]
    assert np.ptp(u) > 0.1  # the vehicle really moved (surge speed u varied)
    if "sonar" in options and options["sonar"]:
        assert max(int(o["sonar"].max()) for o in g_obs) > 0


def test_seeded_dm_env_is_bit_for_bit_and_seeds_differ():
    actions = np.random.default_rng(5).uniform(-1.0, 1.0, (10, 3)).astype(np.float32)
    envs = [SurveyDmEnv(options=SHORT, seed=s) for s in (4, 4, 5)]
    a, b, c = (_dm_rollout(e, actions, episodes=2) for e in envs)
    _assert_same_obs(a[0], b[0])
    np.testing.assert_array_equal(a[1], b[1])
    # every episode starts from the same corner with the same estimate; from the first step
    # on, sensor noise and current come from the seed, and the second episode draws anew
    np.testing.assert_array_equal(a[0][0]["nav"], c[0][0]["nav"])
    assert len(a[0]) == 8  # two 3-decision episodes: observations 0-3, then 4-7
    assert not np.array_equal(a[0][1]["nav"], c[0][1]["nav"])
    assert not np.array_equal(a[0][1]["nav"], a[0][5]["nav"])
    layouts = []
    for seed in (4, 4, 5):
        env = SurveyDmEnv(options=SHORT, seed=seed)
        env.reset()
        layouts.append(env.task.targets_ned.copy())
    np.testing.assert_array_equal(layouts[0], layouts[1])
    assert not np.allclose(layouts[0], layouts[2])  # another seed: another object layout


def test_bad_arguments_are_refused():
    with pytest.raises(ValueError, match="seed must be"):
        SurveyDmEnv(options=SHORT, seed=-1)
    with pytest.raises(ValueError, match="decision_interval_s"):
        load(SURVEY_ID, options={"sonar": False, "decision_interval_s": 0.25})
    env = SurveyDmEnv(options=SHORT, seed=0)
    env.reset()
    with pytest.raises(ValueError, match="finite"):
        env.step(np.array([np.nan, 0, 0], np.float32))
