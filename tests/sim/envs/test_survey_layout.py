"""auvsim/Survey-v1 episodes: an area larger than the sonar's reach, targets placed per
episode from the seed and out of view at the start, so the first step cannot end the task."""

from __future__ import annotations

import numpy as np
import pytest

from autonomy.localization import fls_visibility
from sim.envs.survey_env import SurveyEnv, SurveyEnvOptions
from scenarios.fls_presets import resolve_geometry


@pytest.fixture(scope="module")
def env():
    return SurveyEnv(options=SurveyEnvOptions(sonar=False, max_episode_s=5.0))


def test_area_exceeds_the_sonar_reach_and_targets_are_placed_per_seed(env):
    reach = resolve_geometry(env.base_scenario.sensors.fls).window_far_m
    size = env.area.hi_ne_m - env.area.lo_ne_m
    assert np.all(size > 2.0 * reach)
    layouts = {}
    for seed in (0, 1, 0):
        env.reset(seed=seed)
        t = env.targets_ned.copy()
        layouts.setdefault(seed, []).append(t)
        assert len(t) == len(env.base_scenario.world.targets)
        assert np.all(t[:, :2] >= env.area.lo_ne_m) and np.all(t[:, :2] <= env.area.hi_ne_m)
        start = env.scenario.vehicle.initial_pos_ned
        assert np.min(np.hypot(*(t[:, :2] - start[:2]).T)) >= reach  # beyond the sonar's reach
        np.testing.assert_allclose(t[:, 2], env.seabed.depth_at(t[:, 0], t[:, 1]))  # resting on the seabed
        pairs = np.hypot(*(t[:, None, :2] - t[None, :, :2]).transpose(2, 0, 1))
        assert np.min(pairs[np.triu_indices(len(t), 1)]) >= env.options.min_target_spacing_m
    np.testing.assert_array_equal(layouts[0][0], layouts[0][1])  # same seed, same layout
    assert not np.allclose(layouts[0][0], layouts[1][0])  # another seed, another layout


def test_no_target_is_in_the_sonar_fan_at_the_start(env):
    env.reset(seed=3)
    fls = env.scenario.sensors.fls
    g = resolve_geometry(fls)
    scn = env.scenario
    visible = fls_visibility(np.asarray(scn.vehicle.initial_pos_ned), np.deg2rad(scn.vehicle.initial_rpy_deg),
                             env.mission.physics.site_pos_body("fls"), np.deg2rad([0.0, fls.tilt_deg, 0.0]),
                             range_min_m=g.window_near_m, range_max_m=g.window_far_m, fov_rad=g.fov_rad,
                             vertical_fov_rad=g.vertical_beamwidth_rad)
    assert not np.any(visible(env.targets_ned))


def test_with_sonar_the_first_steps_do_not_end_the_episode():
    e = SurveyEnv(options=SurveyEnvOptions(sonar=True, max_episode_s=600.0),
                  overrides=("autonomy.atr.detector=classical",))
    e.reset(seed=2)
    for _ in range(3):
        _, r, term, trunc, info = e.step(np.array([0.0, 0.0, 0.0], dtype=np.float32))
        assert not (term or trunc) and info["targets_found"] == 0
    assert e.mission.n_fls_frames >= 6


def test_area_smaller_than_the_reach_is_rejected():
    with pytest.raises(ValueError, match="reach"):
        SurveyEnv(options=SurveyEnvOptions(sonar=False, area_size_ne_m=(20.0, 80.0)))
