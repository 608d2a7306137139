"""The batched Survey env: gymnasium's vector API, next-step autoreset, and per-env
determinism whatever N, the order of the envs and the number of worker processes."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import sim.envs  # noqa: F401  (registers the ids)
from sim.envs.survey_env import SurveyEnv
from sim.envs.survey_vector import SurveyVectorEnv
from sim.features import shared_detector
from sim.features.survey_perception import SurveyPerceptionFeature

FAST = {"sonar": False, "max_episode_s": 6.0}  # six 1 s decisions per episode


def _actions(n_steps: int, n_envs: int, seed: int = 0) -> np.ndarray:
    return np.random.default_rng(seed).uniform(-1, 1, (n_steps, n_envs, 3)).astype(np.float32)


def test_make_vec_spaces_and_next_step_autoreset():
    venv = gym.make_vec("auvsim/Survey-v1", num_envs=2, vectorization_mode="vector_entry_point", options=FAST)
    try:
        assert isinstance(venv, SurveyVectorEnv)
        assert venv.action_space.shape == (2, 3)
        assert venv.observation_space["nav"].shape == (2, venv.single_observation_space["nav"].shape[0])
        obs, info = venv.reset(seed=3)
        assert venv.observation_space.contains(obs)
        assert info["t_s"].shape == (2,) and info["_t_s"].all()
        acts = _actions(8, 2)
        ends = []
        for a in acts:
            obs, rew, term, trunc, info = venv.step(a)
            assert venv.observation_space.contains(obs)
            ends.append((term | trunc).copy())
            if len(ends) > 1 and ends[-2].any():  # the step after an end is the reset: t = 0, reward 0
                done = ends[-2]
                assert np.all(info["t_s"][done] == 0.0) and np.all(rew[done] == 0.0)
                assert not np.any(term[done] | trunc[done])
        assert np.array(ends)[5].all()  # truncated at 6 s
    finally:
        venv.close()


def test_env_trajectory_depends_only_on_its_seed_and_actions():
    acts = _actions(9, 3, seed=1)  # crosses an autoreset
    ref = SurveyVectorEnv(3, options=FAST)
    ref.reset(seed=10)  # envs seeded 10, 11, 12
    traj = [ref.step(a)[:2] for a in acts]
    ref.close()
    # env 1 alone (a single SurveyEnv with next-step autoreset by hand)
    single = SurveyEnv(options=FAST)
    single.reset(seed=11)
    done = False
    for a, (obs, rew) in zip(acts, traj):
        if done:
            o, _ = single.reset()
            r = 0.0
            done = False
        else:
            o, r, te, tr, _ = single.step(a[1])
            done = te or tr
        np.testing.assert_array_equal(o["nav"], obs["nav"][1])
        assert r == rew[1]
    # permuted, in two worker processes
    perm = [2, 0, 1]
    venv = SurveyVectorEnv(3, options=FAST, workers=2)
    try:
        venv.reset(seed=[12, 10, 11])
        for a, (obs, rew) in zip(acts, traj):
            o, r, *_ = venv.step(a[perm])
            for k in obs:
                np.testing.assert_array_equal(o[k], obs[k][perm])
            np.testing.assert_array_equal(r, rew[perm])
    finally:
        venv.close()


def test_sonar_envs_share_one_detector_and_keep_their_own_frames():
    opts = {"sonar": True, "max_episode_s": 3.0}
    venv = SurveyVectorEnv(2, options=opts)
    try:
        obs, _ = venv.reset(seed=[4, 4])
        a = np.tile(np.array([0.5, 0.0, 0.0], np.float32), (2, 1))
        for _ in range(2):
            obs, *_ = venv.step(a)
        feats = [e.mission.feature(SurveyPerceptionFeature) for e in venv.envs]
        assert all(f is not None for f in feats)
        dets = {id(f.perception.detector) for f in feats}
        np.testing.assert_array_equal(obs["sonar"][0], obs["sonar"][1])  # same seed, same frames
        assert obs["sonar"][0].any()
    finally:
        venv.close()
    assert len(dets) == 1
    assert len(shared_detector._DETECTORS) >= 1


def test_bad_arguments_are_refused():
    with pytest.raises(ValueError, match="num_envs"):
        SurveyVectorEnv(0, options=FAST)
    with pytest.raises(ValueError, match="workers"):
        SurveyVectorEnv(2, options=FAST, workers=3)
    with pytest.raises(ValueError, match="num_envs"):
        SurveyVectorEnv(True, options=FAST)
    with pytest.raises(ValueError, match="overrides must be a tuple"):
        SurveyVectorEnv(2, options=FAST, overrides="seed=3")
    with pytest.raises(ValueError, match="unknown option 'max_episode' .did you mean 'max_episode_s'"):
        SurveyVectorEnv(2, options={"max_episode": 3.0})
    for bad, says in (({"sonar": "no"}, "sonar must be True or False"), ({"max_episode_s": "10"}, "must be a number"),
                      (["sonar"], "options must be")):
        with pytest.raises(ValueError, match=says):
            SurveyVectorEnv(1, options=bad)
    venv = SurveyVectorEnv(2, options=FAST)
    try:
        with pytest.raises(gym.error.ResetNeeded):
            venv.step(np.zeros((2, 3), np.float32))
        with pytest.raises(ValueError, match="1 seeds for 2 envs"):
            venv.reset(seed=[1])
        for bad in (1.5, -1, [0, "a"]):
            with pytest.raises(ValueError, match="seed"):
                venv.reset(seed=bad)
        venv.reset(seed=0)
        with pytest.raises(ValueError, match="shape"):
            venv.step(np.zeros((3, 3), np.float32))
    finally:
        venv.close()
    venv.close()  # twice: nothing
    with pytest.raises(gym.error.ClosedEnvironmentError):
        venv.reset(seed=0)
    venv = SurveyVectorEnv(2, options=FAST, workers=2)
    try:
        venv.reset(seed=0)
        bad = np.zeros((2, 3), np.float32)
        bad[1, 0] = np.nan
        with pytest.raises(ValueError, match="worker 1: ValueError") as err:  # an env's check, from its worker
            venv.step(bad)
        assert "\n" not in str(err.value)  # one line, as with workers=1
        with pytest.raises(ValueError, match="actions must be numbers"):
            venv.step("go")
        with pytest.raises(ValueError, match="reset takes none"):
            venv.reset(options={"foo": 1})
    finally:
        venv.close()


def test_stable_baselines3_ppo_runs_on_the_batched_env():
    """The Stable-Baselines3 adapter: PPO's rollouts and updates run, episodes end with
    their final observation in ``terminal_observation`` and a time limit marked as such."""
    pytest.importorskip("stable_baselines3", reason="the train extra (stable-baselines3) is not installed")
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import VecMonitor

    from sim.envs.sb3_vec import Sb3SurveyVecEnv

    env = Sb3SurveyVecEnv(2, options={**FAST, "max_episode_s": 4.0}, seed=3)
    try:
        obs = env.reset()
        assert obs["nav"].shape == (2, env.observation_space["nav"].shape[0])
        ends, first_obs = [], None
        for _ in range(5):
            env.step_async(np.zeros((2, 3), np.float32))
            obs, rew, done, infos = env.step_wait()
            ends += [i for i, d in zip(infos, done) if d]
            if done.all():
                first_obs = obs["nav"].copy()
        assert len(ends) == 2  # both envs truncated at 4 s, reset in the same step (SAME_STEP)
        for info in ends:
            assert info["TimeLimit.truncated"] is True
            assert set(info["terminal_observation"]) == set(obs)
            assert info["terminal_observation"]["nav"][-2] == 1.0  # the final observation: the whole time limit
        assert np.all(first_obs[:, -2] == 0.0)  # returned with it: the new episodes' first, no time elapsed
        model = PPO("MultiInputPolicy", VecMonitor(env), n_steps=16, batch_size=32, n_epochs=1, seed=0, device="cpu")
        model.learn(total_timesteps=64)
        assert len(model.ep_info_buffer) >= 2
    finally:
        env.close()


def test_stable_baselines3_seeds_and_infos_as_its_own_vector_envs():
    """``seed(s)`` (what ``PPO(seed=s)`` calls) seeds the next reset; at an episode's end the
    step's info is the ending step's and the new episode's first is in ``reset_infos``."""
    pytest.importorskip("stable_baselines3", reason="the train extra (stable-baselines3) is not installed")
    from sim.envs.sb3_vec import Sb3SurveyVecEnv

    with pytest.raises(ValueError, match="seed"):
        Sb3SurveyVecEnv(1, options=FAST, seed=-1)
    runs = []
    for _ in range(2):
        env = Sb3SurveyVecEnv(2, options={**FAST, "max_episode_s": 3.0})
        try:
            assert env.seed(5) == [5, 6]
            first = env.reset()["nav"].copy()
            ends = []
            for _ in range(3):
                env.step_async(np.zeros((2, 3), np.float32))
                _, _, done, infos = env.step_wait()
                ends += [(i, info) for i, (info, d) in enumerate(zip(infos, done)) if d]
            runs.append(first)
            assert len(ends) == 2
            for i, info in ends:
                assert info["t_s"] == 3.0 and "complete" in info  # the ending step's info
                assert env.reset_infos[i]["t_s"] == 0.0  # the new episode's first
        finally:
            env.close()
    np.testing.assert_array_equal(runs[0], runs[1])
    single = SurveyEnv(options=FAST)
    np.testing.assert_array_equal(single.reset(seed=6)[0]["nav"], runs[0][1])
