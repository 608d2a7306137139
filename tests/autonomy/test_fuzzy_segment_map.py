"""The persistent fuzzy-segment map ([P002] eqs. 12, 16-19) against hand-computed fuzzy-set cases."""

import math

import numpy as np
import pytest

from autonomy.msis.fuzzy_segments import FuzzySegment, FuzzySegmentMap, matching_degree


def _seg(rho: float, y0: float, y1: float, rho1: float = 0.1, rho0: float = 0.2) -> FuzzySegment:
    """The line ``x = rho`` (normal +x) from y0 to y1."""
    return FuzzySegment(0.0, rho, 0.01, rho1, rho0, np.array([rho, y0]), np.array([rho, y1]), 0.0)


def test_matching_degree_of_two_trapezoids_and_of_a_rectangle_and_a_triangle():
    # (0, 1, 2) and (3, 1, 2): the ramps cross at 1.5 at height 1/2, a triangle of area 1/4; each area 3
    assert matching_degree(0.0, 1.0, 2.0, 3.0, 1.0, 2.0) == pytest.approx(0.25 / 3.0, abs=1e-4)
    # rectangle [-1, 1] (area 2) and a triangle centred at 1 of half width 1 (area 1): the triangle's
    # left half (area 1/2) lies inside the rectangle
    assert matching_degree(0.0, 1.0, 1.0, 1.0, 0.0, 1.0) == pytest.approx(0.5, abs=1e-3)  # grid of 4001


def test_move_shifts_by_the_motion_and_grows_by_the_bounded_sum_of_motion_and_age():
    m = FuzzySegmentMap(motion_growth=0.1, age_growth_mps=0.002, max_area_m=10.0)
    m.add(FuzzySegment(0.0, 5.0, 0.01, 0.02, 0.04, np.array([5.0, -2.0]), np.array([5.0, 1.0]), 0.0))
    m.move(np.array([1.0, 2.0]), 10.0)
    (s,) = m.segments
    g0 = 0.1 * math.sqrt(5.0) + 0.002 * 10.0
    assert s.theta_rad == 0.0 and s.rho_m == pytest.approx(4.0)
    assert np.allclose(s.end_a, [4.0, -4.0]) and np.allclose(s.end_b, [4.0, -1.0])
    assert s.rho0_m == pytest.approx(0.04 + g0) and s.rho1_m == pytest.approx(0.02 + g0 / 1.96)


def test_moving_past_a_line_turns_its_normal_and_keeps_rho_positive():
    m = FuzzySegmentMap(motion_growth=0.0, age_growth_mps=0.0)
    m.add(_seg(5.0, -1.0, 1.0))
    m.move(np.array([6.0, 0.0]), 1.0)
    (s,) = m.segments
    assert abs(s.theta_rad) == pytest.approx(math.pi) and s.rho_m == pytest.approx(1.0)
    assert np.allclose(s.end_a, [-1.0, -1.0])


def test_segments_above_the_area_threshold_are_removed():
    m = FuzzySegmentMap(motion_growth=0.1, age_growth_mps=0.0, max_area_m=0.5)
    m.add(_seg(5.0, -1.0, 1.0))  # area 0.3
    m.move(np.array([0.0, 1.0]), 1.0)  # area 0.3 + 0.1 (1 + 1/1.96) = 0.451
    assert len(m.segments) == 1 and m.segments[0].area_m == pytest.approx(0.3 + 0.1 * (1 + 1 / 1.96))
    m.move(np.array([0.0, 0.5]), 1.0)  # + 0.0755: 0.527 > 0.5
    assert m.segments == []


def test_a_segment_between_two_fuses_with_both_in_a_chain():
    # a (rho 5.0) and b (5.2), cuts (0.1, 0.2): matching degree 0.1 / 0.3 = 1/3 < 0.4, kept apart
    m = FuzzySegmentMap(max_angle_rad=math.radians(2), min_match=0.4, motion_growth=0.0, age_growth_mps=0.0)
    m.add(_seg(5.0, -2.0, 0.0))
    m.add(_seg(5.2, 1.0, 3.0))
    assert len(m.segments) == 2
    # new (5.1) matches both with degree 0.2 / 0.3 = 2/3: fused with a (the first of equals):
    # rho 5.05, cuts (0.1, 0.2) / sqrt 2; that matches b with degree 0.10607 / 0.21213 = 1/2: fused
    # again with weights 1 / rho0^2 = 50 and 25: rho 5.1, rho0 75^-1/2, rho1 300^-1/2
    m.add(_seg(5.1, 0.0, 1.0))
    (s,) = m.segments
    assert s.rho_m == pytest.approx(5.1, abs=1e-9) and s.theta_rad == pytest.approx(0.0, abs=1e-12)
    assert s.rho0_m == pytest.approx(75 ** -0.5) and s.rho1_m == pytest.approx(300 ** -0.5)
    assert min(s.end_a[1], s.end_b[1]) == pytest.approx(-2.0) and max(s.end_a[1], s.end_b[1]) == pytest.approx(3.0)


def test_a_new_segment_fuses_with_the_best_matching_one_and_opposite_normals_are_the_same_line():
    m = FuzzySegmentMap(max_angle_rad=math.radians(2), min_match=0.05, motion_growth=0.0, age_growth_mps=0.0)
    m.add(_seg(5.0, -1.0, 1.0))
    m.add(_seg(5.4, -1.0, 1.0))  # supports [4.8, 5.2] and [5.2, 5.6] touch: degree 0
    assert len(m.segments) == 2
    # the line x = 5.3 written with the normal -x (theta = pi, rho = -5.3): degree 0.025 / 0.3
    # with the first (ramps crossing at 5.15, height 1/2) and 0.2 / 0.3 with the second
    new = FuzzySegment(math.pi, -5.3, 0.01, 0.1, 0.2, np.array([5.3, 1.0]), np.array([5.3, 2.0]), 0.0)
    assert m.segments[0].matching_degree(new, math.radians(2)) == pytest.approx(0.025 / 0.3, abs=1e-3)
    assert m.segments[1].matching_degree(new, math.radians(2)) == pytest.approx(0.2 / 0.3, abs=1e-3)
    m.add(new)
    assert len(m.segments) == 2 and m.segments[0].rho_m == 5.0
    assert m.segments[1].theta_rad == 0.0 and m.segments[1].rho_m == pytest.approx(5.35)


def test_rotating_the_map_turns_normals_and_ends_about_the_vehicle_and_keeps_rho():
    m = FuzzySegmentMap()
    m.add(_seg(5.0, -1.0, 1.0))
    m.rotate(math.pi / 2)  # x = 5 becomes y = 5
    (s,) = m.segments
    assert s.theta_rad == pytest.approx(math.pi / 2) and s.rho_m == 5.0
    assert np.allclose(s.end_a, [1.0, 5.0]) and np.allclose(s.end_b, [-1.0, 5.0])
