"""Lawnmower planner geometry and FLS swath width against analytic cases."""

from __future__ import annotations

import math

import numpy as np
import pytest

from autonomy.guidance.config import SurveyConfig
from autonomy.guidance.lawnmower import fls_swath_width_m, plan_lawnmower
from autonomy.guidance.survey import plan_from_config


def test_legs_parallel_alternating_and_evenly_spaced():
    heading = math.radians(90.0)  # legs run east
    plan = plan_lawnmower((4.0, -2.0), 34.0, 16.0, heading, 4.0, turn="corner")
    assert plan.n_legs == 5
    along = np.array([0.0, 1.0])
    for k in range(plan.n_legs):
        d = plan.leg_ends_ne_m[k] - plan.leg_starts_ne_m[k]
        assert np.linalg.norm(d) == pytest.approx(34.0)
        np.testing.assert_allclose(d / 34.0, along if k % 2 == 0 else -along, atol=1e-12)
    # starboard of east is south: legs at N = 4, 0, -4, -8, -12
    np.testing.assert_allclose(plan.leg_starts_ne_m[:, 0], [4, 0, -4, -8, -12], atol=1e-12)
    assert plan.leg_spacing_m == 4.0
    # corner turns: waypoints are exactly the leg ends in order
    expected = np.concatenate([[s, e] for s, e in zip(plan.leg_starts_ne_m, plan.leg_ends_ne_m)])
    np.testing.assert_allclose(plan.waypoints_ne_m, expected)
    assert plan.path_length_m() == pytest.approx(5 * 34.0 + 4 * 4.0)


def test_spacing_shrinks_to_cover_width_exactly_and_port_turn():
    plan = plan_lawnmower((0.0, 0.0), 10.0, 10.0, 0.0, 3.0, first_turn="port")
    assert plan.n_legs == 5  # ceil(10 / 3) + 1
    assert plan.leg_spacing_m == pytest.approx(2.5)
    # port of north is west (negative east)
    np.testing.assert_allclose(plan.leg_starts_ne_m[:, 1], [0.0, -2.5, -5.0, -7.5, -10.0])


def test_run_in_extends_legs():
    plan = plan_lawnmower((0.0, 0.0), 10.0, 0.0, 0.0, 3.0, run_in_m=2.0)
    assert plan.n_legs == 1
    np.testing.assert_allclose(plan.waypoints_ne_m, [[-2.0, 0.0], [12.0, 0.0]])


def test_arc_turns_are_semicircles_turning_towards_the_next_leg():
    plan = plan_lawnmower((0.0, 0.0), 20.0, 8.0, 0.0, 4.0, turn="arc", arc_points=8)
    wps = plan.waypoints_ne_m
    leg_end_idx = np.flatnonzero(plan.on_leg)
    for k in range(plan.n_legs - 1):
        i0 = leg_end_idx[k]
        arc = wps[i0 : i0 + 9]  # leg end + 8 arc points, the last being the next leg start
        np.testing.assert_allclose(arc[-1], plan.leg_starts_ne_m[k + 1])
        centre = 0.5 * (plan.leg_ends_ne_m[k] + plan.leg_starts_ne_m[k + 1])
        np.testing.assert_allclose(np.linalg.norm(arc - centre, axis=1), 2.0, atol=1e-9)
        # leg 0 heads north and turns to starboard (clockwise from above: cross < 0 in NE)
        d1, d2 = arc[1] - arc[0], arc[2] - arc[1]
        cross_ne = d1[0] * d2[1] - d1[1] * d2[0]
        assert (cross_ne > 0) == (k % 2 == 0)  # NE axes: clockwise seen from above is +
        # the arc bulges beyond the leg end, outside the area
        assert np.all(arc[:, 0] >= 20.0 - 1e-9) if k % 2 == 0 else np.all(arc[:, 0] <= 1e-9)
    # arcs tighter than min_turn_radius fall back to corners
    corner = plan_lawnmower((0.0, 0.0), 20.0, 8.0, 0.0, 4.0, turn="arc", min_turn_radius_m=2.5)
    assert len(corner.waypoints_ne_m) == 2 * corner.n_legs


@pytest.mark.parametrize("kwargs", [dict(length_m=0.0), dict(leg_spacing_m=-1.0), dict(turn="loop"),
                                    dict(first_turn="left")])
def test_bad_plan_arguments(kwargs):
    args = dict(origin_ne_m=(0.0, 0.0), length_m=10.0, width_m=4.0, leg_heading_rad=0.0, leg_spacing_m=2.0)
    args.update(kwargs)
    with pytest.raises(ValueError):
        plan_lawnmower(**args)


def test_swath_looking_straight_down_is_2h_tan_half_fov():
    h, fov = 2.0, math.radians(60.0)
    w = fls_swath_width_m(h, math.radians(90.0), fov, math.radians(1.0), 0.0, 100.0, n_samples=721)
    assert w == pytest.approx(2.0 * h * math.tan(0.5 * fov), rel=2e-3)


def test_swath_level_sonar_is_limited_by_max_range():
    # Tilt 0: rays below the horizon hit the seabed; the widest reach is at max range and
    # the largest azimuth: half-swath = sin(fov/2) * sqrt(R^2 - h^2).
    h, R, fov = 2.0, 30.0, math.radians(130.0)
    w = fls_swath_width_m(h, 0.0, fov, math.radians(20.0), 0.5, R, n_samples=721)
    expected = 2.0 * math.sin(0.5 * fov) * math.sqrt(R * R - h * h)
    assert w == pytest.approx(expected, rel=5e-3)


def test_swath_matches_independent_ray_casting():
    # Cast rays through rotation matrices and intersect with z = h (independent code path).
    from autonomy.frames import rot_y

    h, tilt, fov, vb, rmin, rmax = 2.0, math.radians(25.0), math.radians(130.0), math.radians(20.0), 1.0, 30.0
    best = 0.0
    R = rot_y(-tilt)  # pitch down by tilt (FRD: positive pitch is nose up)
    for a in np.linspace(-fov / 2, fov / 2, 261):
        for phi in np.linspace(-vb / 2, vb / 2, 81):
            d_sonar = np.array([math.cos(a) * math.cos(phi), math.sin(a) * math.cos(phi), math.sin(phi)])
            d = R @ d_sonar
            if d[2] <= 0:
                continue
            r = h / d[2]
            if rmin <= r <= rmax:
                best = max(best, abs(r * d[1]))
    w = fls_swath_width_m(h, tilt, fov, vb, rmin, rmax, n_samples=261)
    assert w == pytest.approx(2 * best, rel=1e-2)
    assert fls_swath_width_m(h, math.radians(-40.0), fov, vb, rmin, rmax) == 0.0  # looking up


def test_leg_spacing_from_swath_config():
    cfg = SurveyConfig(leg_spacing_m="from_swath", swath_overlap=0.25, width_m=30.0, length_m=10.0)
    plan = plan_from_config(cfg, swath_width_m=8.0)
    # spacing 6 m -> 6 legs exactly 6 m apart
    assert plan.n_legs == 6
    assert plan.leg_spacing_m == pytest.approx(6.0)
    with pytest.raises(ValueError, match="from_swath"):
        plan_from_config(cfg)
