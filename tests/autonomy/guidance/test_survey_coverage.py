"""The shipped CSSN survey plan: the FLS sees every OPI several times, within the time budget."""

from __future__ import annotations

import math

import numpy as np
import pytest

from autonomy.frames import rot_y
from autonomy.guidance.survey import plan_from_config
from scenarios.load import load_scenario

FLS_FOV_RAD = math.radians(130.0)
FLS_VERTICAL_RAD = math.radians(20.0)
FLS_WINDOW_M = (1.0, 30.0)
FRAME_RATE_HZ = 3.0


def _kinematic_track(waypoints_ne: np.ndarray, speed_mps: float, rate_hz: float):
    """Samples (pos_ne, heading) every 1/rate_hz s moving along the polyline at speed."""
    seg = np.diff(waypoints_ne, axis=0)
    seg_len = np.linalg.norm(seg, axis=1)
    cum = np.concatenate([[0.0], np.cumsum(seg_len)])
    s = np.arange(0.0, cum[-1], speed_mps / rate_hz)
    k = np.clip(np.searchsorted(cum, s, side="right") - 1, 0, len(seg) - 1)
    pos = waypoints_ne[k] + seg[k] * ((s - cum[k]) / seg_len[k])[:, None]
    heading = np.arctan2(seg[k, 1], seg[k, 0])
    return pos, heading, k


@pytest.mark.parametrize("tilt_deg", [20.0, 30.0])
def test_fls_sees_every_opi_many_times_on_several_legs(tilt_deg):
    sc = load_scenario("cssn_lawnmower")
    survey = sc.autonomy.guidance.survey
    plan = plan_from_config(survey)
    seabed = sc.world.seabed.depth_m
    depth = seabed - survey.altitude_m
    pos, heading, seg_idx = _kinematic_track(plan.waypoints_ne_m, survey.speed_mps, FRAME_RATE_HZ)
    leg_of_segment = np.cumsum(plan.on_leg)[1:]  # leg number each segment belongs to/after
    R_sb = rot_y(-math.radians(tilt_deg)).T  # body-level -> sonar (boresight pitched down)
    for target in sc.world.targets:
        top = np.array([target.pos_ned[0], target.pos_ned[1], target.pos_ned[2] - target.radius_m])
        rel = np.stack([top[0] - pos[:, 0], top[1] - pos[:, 1], np.full(len(pos), top[2] - depth)], axis=1)
        c, s = np.cos(heading), np.sin(heading)
        body = np.stack([c * rel[:, 0] + s * rel[:, 1], -s * rel[:, 0] + c * rel[:, 1], rel[:, 2]], axis=1)
        son = body @ R_sb.T
        r = np.linalg.norm(son, axis=1)
        az = np.arctan2(son[:, 1], son[:, 0])
        el = np.arcsin(son[:, 2] / r)
        seen = ((np.abs(az) <= FLS_FOV_RAD / 2) & (np.abs(el) <= FLS_VERTICAL_RAD / 2)
                & (r >= FLS_WINDOW_M[0]) & (r <= FLS_WINDOW_M[1]))
        assert seen.sum() >= 50, f"{target.name} seen in only {seen.sum()} frames"
        legs = np.unique(leg_of_segment[seg_idx[seen]])
        assert len(legs) >= 3, f"{target.name} seen on legs {legs}"
        # the track passes over or near it (within one leg spacing / 2 + 1 m)
        assert np.min(np.linalg.norm(pos - top[:2], axis=1)) <= 0.5 * plan.leg_spacing_m + 1.0


def test_survey_fits_in_twelve_minutes():
    sc = load_scenario("cssn_lawnmower")
    survey = sc.autonomy.guidance.survey
    plan = plan_from_config(survey)
    start = np.asarray(sc.vehicle.initial_pos_ned[:2])
    transit = np.linalg.norm(plan.waypoints_ne_m[0] - start)
    assert (plan.path_length_m() + transit) / survey.speed_mps < 10 * 60.0
