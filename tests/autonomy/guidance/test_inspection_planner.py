"""The inspection planner on hand-made world models, its look model against the flat-seabed
geometry, and its tour against brute force."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pytest

from autonomy.guidance.config import InspectionConfig, SurveyConfig
from autonomy.guidance.inspection import coverage_spacing_m, leg_ranges_m, plan_coverage
from autonomy.guidance.inspection_planner import (
    InspectionPlanner, LookRecord, PlannerParams, SurveyArea, brute_force_order, covariance_from_terms,
    look_covariance, look_information, look_terms, semi_major_2sigma_m, tour_length_m, tour_order)


@dataclass(frozen=True)
class Obj:
    id: int
    pos_ned: np.ndarray
    cov_ned: np.ndarray = field(default_factory=lambda: np.diag([0.04, 0.04, 0.01]))
    class_pmf: np.ndarray = field(default_factory=lambda: np.array([0.999, 0.001]))
    n_detections: int = 50
    existence_probability: float = 0.999

    @property
    def class_name(self) -> str:
        return "target" if self.class_pmf[0] >= 0.5 else "not_target"


AREA = SurveyArea((20.0, -20.0), math.radians(90.0), 40.0, 40.0)  # N 20 .. -20, E -20 .. 20


def planner(**kw) -> InspectionPlanner:
    return InspectionPlanner(PlannerParams(**kw), AREA)


def look_from(p: InspectionPlanner, obj: Obj, bearing_deg: float, ground_range_m: float, frames: int = 30) -> None:
    """Record a look at ``obj`` from ``bearing_deg`` (the line of sight, vehicle -> object)."""
    p.looks.setdefault(obj.id, LookRecord()).add(math.radians(bearing_deg), ground_range_m,
                                                 math.radians(p.params.aspect_bin_deg), frames)


def axis_deg(heading_rad: float) -> float:
    """A heading's axis, 0 .. 180 deg (a look and its opposite carry the same information)."""
    return math.degrees(heading_rad) % 180.0


def test_look_information_matches_the_flat_seabed_geometry():
    """Along the line of sight the ground range g = sqrt(r^2 - h^2) moves by dg/dr = r/g per
    metre of slant range and dg/dh = -h/g per metre of altitude (finite differences here);
    across it the azimuth error moves the point by g per radian."""
    p = PlannerParams(altitude_m=2.0, range_sigma_m=0.05, altitude_sigma_m=0.1, azimuth_sigma_rad=0.01,
                      aspect_sigma_m=0.3)
    g, h = 6.0, 2.0
    r = math.hypot(g, h)
    eps = 1e-6
    dg_dr = (math.sqrt((r + eps) ** 2 - h ** 2) - math.sqrt((r - eps) ** 2 - h ** 2)) / (2 * eps)
    dg_dh = (math.sqrt(r ** 2 - (h + eps) ** 2) - math.sqrt(r ** 2 - (h - eps) ** 2)) / (2 * eps)
    var_along = (dg_dr * 0.05) ** 2 + (dg_dh * 0.1) ** 2 + 0.3 ** 2
    var_across = (g * 0.01) ** 2 + 0.15 ** 2
    cov = np.linalg.inv(look_information(p, 0.0, g))  # bearing north: along = N, across = E
    np.testing.assert_allclose(cov, np.diag([var_along, var_across]), rtol=1e-6, atol=1e-12)
    rot = np.linalg.inv(look_information(p, math.radians(90.0), g))  # bearing east: the axes swap
    np.testing.assert_allclose(rot, np.diag([var_across, var_along]), rtol=1e-6, atol=1e-12)


def test_two_perpendicular_aspects_shrink_the_ellipse_and_repeated_frames_do_not():
    p = PlannerParams()
    one = LookRecord()
    one.add(0.0, 6.0, math.radians(30.0), frames=1)
    many = LookRecord()
    many.add(0.0, 6.0, math.radians(30.0), frames=1)
    many.add(math.radians(10.0), 6.0, math.radians(30.0), frames=500)  # the same aspect, more frames
    two = LookRecord()
    two.add(0.0, 6.0, math.radians(30.0))
    two.add(math.radians(90.0), 6.0, math.radians(30.0))
    s_one, s_many, s_two = (semi_major_2sigma_m(look_covariance(p, r)) for r in (one, many, two))
    assert s_many == pytest.approx(s_one, rel=1e-9)
    assert s_two < 0.6 * s_one


def test_one_uncertain_object_gets_one_leg_across_its_previous_look():
    p = planner()
    seen = Obj(0, np.array([0.0, 0.0, 10.0]))
    done = Obj(1, np.array([10.0, 10.0, 10.0]))
    look_from(p, seen, 90.0, 15.0)  # seen once, looking east from 15 m
    look_from(p, done, 0.0, 6.0)
    look_from(p, done, 90.0, 6.0)
    look_from(p, done, 180.0, 6.0)
    assert p.confident(done) and not p.confident(seen)
    legs = p.plan([seen, done], (-15.0, -15.0))
    assert [leg.object_id for leg in legs] == [0]
    leg = legs[0]
    assert abs(axis_deg(leg.heading_rad) - 0.0) <= 15.0 or abs(axis_deg(leg.heading_rad) - 180.0) <= 15.0
    assert leg.predicted_2sigma_m < leg.now_2sigma_m
    # the leg runs towards the object, from leg_start_range_m to leg_end_range_m of it
    assert math.dist(leg.start_ne_m, leg.object_ne_m) == pytest.approx(p.params.leg_start_range_m)
    assert math.dist(leg.end_ne_m, leg.object_ne_m) == pytest.approx(p.params.leg_end_range_m)


def test_two_objects_needing_opposite_aspects_get_crossing_headings():
    p = planner()
    a = Obj(0, np.array([-5.0, -5.0, 10.0]))
    b = Obj(1, np.array([5.0, 5.0, 10.0]))
    look_from(p, a, 0.0, 10.0)  # a seen looking north
    look_from(p, b, 90.0, 10.0)  # b seen looking east
    legs = {leg.object_id: leg for leg in p.plan([a, b], (0.0, -18.0))}
    assert set(legs) == {0, 1}
    assert abs(axis_deg(legs[0].heading_rad) - 90.0) <= 15.0  # a: look east-west
    ax_b = axis_deg(legs[1].heading_rad)
    assert min(ax_b, 180.0 - ax_b) <= 15.0  # b: look north-south


def test_reference_bias_covariance_matches_monte_carlo_fusion_of_biased_looks():
    """Looks z_k = x + rho u_k + n_k (n_k ~ N(0, I_k^-1), rho ~ N(0, sigma^2) the same for all
    looks at the object: the leading edge a radius before the centre along each line of sight),
    fused with information weights as the world model does: their error covariance is the look
    model's."""
    p = PlannerParams(reference_bias_sigma_m=0.3)
    rec = LookRecord()
    for bearing_deg, g in ((90.0, 12.0), (150.0, 6.0), (200.0, 8.0)):
        rec.add(math.radians(bearing_deg), g, math.radians(30.0))
    b = np.array([a[0] for a in rec.aspects])
    g = np.array([a[1] for a in rec.aspects])
    I_k = look_information(p, b, g)
    u = np.stack([np.cos(b), np.sin(b)], axis=1)
    rng = np.random.default_rng(0)
    n = 100_000
    rho = rng.normal(0.0, 0.3, n)
    noise = np.stack([rng.multivariate_normal(np.zeros(2), np.linalg.inv(I), n) for I in I_k], axis=1)  # (n, k, 2)
    z = rho[:, None, None] * u[None] + noise
    P = np.linalg.inv(I_k.sum(axis=0))
    fused = np.einsum("ij,nj->ni", P, np.einsum("kij,nkj->ni", I_k, z))
    # (the model's 1e-4 m^-2 information floor is negligible against these looks')
    np.testing.assert_allclose(np.cov(fused.T), look_covariance(p, rec), atol=0.01 * np.trace(P))


def test_opposite_looks_cancel_the_reference_bias_and_one_sided_looks_keep_it():
    p = PlannerParams(reference_bias_sigma_m=0.3)
    p0 = PlannerParams(reference_bias_sigma_m=0.0)
    opposite, same_side = LookRecord(), LookRecord()
    opposite.add(0.0, 8.0, math.radians(30.0))
    opposite.add(math.pi, 8.0, math.radians(30.0))
    same_side.add(0.0, 8.0, math.radians(30.0))
    same_side.add(0.0, 8.0, math.radians(30.0), frames=10)
    np.testing.assert_allclose(look_covariance(p, opposite), look_covariance(p0, opposite), atol=1e-12)
    info, bias = look_terms(p, same_side)
    bump = covariance_from_terms(p, info, bias) - covariance_from_terms(p0, info, bias)
    np.testing.assert_allclose(bump, np.diag([0.09, 0.0]), atol=1e-5)  # the whole bias, along the north look (1e-4 floor)


def test_with_a_reference_bias_the_next_leg_looks_from_the_other_side():
    """An object seen looking east: with no bias model the best new look crosses the old one
    (north or south); with the leading-edge bias the planner sends the vehicle round to look
    westwards at it, against the bias (and does not flip the leg back to the nearer side)."""
    obj = Obj(0, np.array([0.0, 0.0, 10.0]))
    plain, biased = planner(), planner(reference_bias_sigma_m=0.3)
    for pl in (plain, biased):
        look_from(pl, obj, 90.0, 10.0)
    leg = plain.plan([obj], (0.0, -15.0))[0]
    assert abs(axis_deg(leg.heading_rad) - 0.0) <= 15.0 or abs(axis_deg(leg.heading_rad) - 180.0) <= 15.0
    leg_b = biased.plan([obj], (0.0, -15.0))[0]
    # E-optimal balances crossing the old look and opposing it: a heading with a westward part
    assert math.sin(leg_b.heading_rad) < -0.4
    assert leg_b.start_ne_m[1] > 0.0  # it starts east of the object, the far side from the vehicle
    assert leg_b.predicted_2sigma_m < leg_b.now_2sigma_m


def test_a_false_alarm_is_never_visited():
    p = planner()
    weak = Obj(0, np.array([0.0, 0.0, 10.0]), n_detections=2, existence_probability=0.99)
    doubtful = Obj(1, np.array([5.0, 0.0, 10.0]), n_detections=40, existence_probability=0.6)
    real = Obj(2, np.array([-5.0, 0.0, 10.0]))
    for o in (weak, doubtful, real):
        look_from(p, o, 90.0, 20.0)
    assert not p.confirmed(weak) and not p.confirmed(doubtful)
    assert [leg.object_id for leg in p.plan([weak, doubtful, real], (0.0, -18.0))] == [2]
    assert p.map_confident([weak, doubtful])  # nothing confirmed, nothing to inspect


@pytest.mark.parametrize("pos_ne", [(19.0, 0.0), (0.0, 19.5), (-19.0, -19.0), (19.5, 19.5)])
def test_legs_stay_inside_the_area(pos_ne):
    p = planner(area_margin_m=1.0)
    obj = Obj(0, np.array([*pos_ne, 10.0]))
    look_from(p, obj, 45.0, 15.0)
    legs = p.plan([obj], (0.0, 0.0))
    assert len(legs) == 1
    for point in (legs[0].start_ne_m, legs[0].end_ne_m):
        assert AREA.contains(np.asarray(point), 1.0 + 1e-9)


def test_an_object_with_no_heading_inside_the_area_gets_no_leg():
    small = SurveyArea((0.0, 0.0), 0.0, 6.0, 6.0)  # too small for a 12 m leg in any direction
    p = InspectionPlanner(PlannerParams(area_margin_m=0.0), small)
    obj = Obj(0, np.array([3.0, 3.0, 5.0]))
    assert p.plan([obj], (0.0, 0.0)) == []


def test_legs_per_object_are_capped():
    p = planner(max_legs_per_object=2)
    obj = Obj(0, np.array([0.0, 0.0, 10.0]))
    look_from(p, obj, 90.0, 20.0)
    p.leg_flown(0)
    assert len(p.plan([obj], (0.0, -18.0))) == 1
    p.leg_flown(0)
    assert p.plan([obj], (0.0, -18.0)) == []


def test_class_and_existence_uncertainty_count():
    p = planner()
    obj = Obj(0, np.array([0.0, 0.0, 10.0]), class_pmf=np.array([0.6, 0.4]), existence_probability=0.95)
    for b in (0.0, 90.0, 180.0):
        look_from(p, obj, b, 6.0)
    assert p.reasons(obj) == ["class", "existence"]


def test_exact_tour_equals_brute_force_and_two_opt_is_no_worse_than_nearest_neighbour():
    rng = np.random.default_rng(7)
    for _ in range(25):
        n = int(rng.integers(2, 8))
        s = rng.uniform(-20, 20, (n, 2))
        e = s + rng.uniform(-8, 8, (n, 2))
        p0 = rng.uniform(-20, 20, 2)
        first = np.linalg.norm(s - p0, axis=1)
        between = np.linalg.norm(e[:, None] - s[None], axis=2)
        exact = tour_length_m(tour_order(p0, s, e, exact_max=8), first, between)
        assert exact == pytest.approx(tour_length_m(brute_force_order(p0, s, e), first, between), abs=1e-9)
        # nearest neighbour, then 2-opt: never worse than nearest neighbour alone
        nn = [int(np.argmin(first))]
        while len(nn) < n:
            nn.append(min(set(range(n)) - set(nn), key=lambda j: between[nn[-1], j]))
        two_opt = tour_length_m(tour_order(p0, s, e, exact_max=0), first, between)
        assert exact - 1e-9 <= two_opt <= tour_length_m(nn, first, between) + 1e-9


def test_coverage_pass_is_centred_and_spaced_from_the_swath():
    survey = SurveyConfig(origin_ne_m=(8.0, 0.0), leg_heading_deg=90.0, length_m=32.0, width_m=16.0)
    one = plan_coverage(survey, coverage_spacing_m(InspectionConfig(), 53.7))
    assert one.n_legs == 1
    np.testing.assert_allclose(one.leg_starts_ne_m[0], (0.0, 0.0), atol=1e-9)  # the centre line, N = 0
    two = plan_coverage(survey, 8.0)
    assert two.n_legs == 2
    np.testing.assert_allclose(sorted(two.leg_starts_ne_m[:, 0]), (-4.0, 4.0), atol=1e-9)  # bands' middles
    with pytest.raises(ValueError, match="coverage_spacing_m"):
        coverage_spacing_m(InspectionConfig(), None)


def test_config_refuses_legs_that_end_before_they_start():
    with pytest.raises(ValueError, match="leg_start_range_m"):
        InspectionConfig(leg_start_range_m=4.0, leg_end_range_m=5.0)
    with pytest.raises(ValueError, match="give both in m"):
        InspectionConfig(leg_start_range_m="from_beam", leg_end_range_m=5.0)


def test_leg_ranges_from_the_beam_put_the_object_a_quarter_beam_either_side_of_the_boresight():
    cfg = InspectionConfig(leg_start_range_m="from_beam", leg_end_range_m="from_beam")
    start, end = leg_ranges_m(cfg, 2.0, math.radians(15.0), math.radians(20.0))
    assert math.degrees(math.atan2(2.0, start)) == pytest.approx(10.0)  # depression at the leg's start
    assert math.degrees(math.atan2(2.0, end)) == pytest.approx(20.0)
    assert leg_ranges_m(InspectionConfig(), 2.0, 0.2, 0.3) == (12.0, 5.0)
    with pytest.raises(ValueError, match="from_beam"):
        leg_ranges_m(cfg, 2.0, math.radians(3.0), math.radians(20.0))  # the far edge looks above the horizon


def test_the_navigation_part_of_an_ellipse_does_not_call_for_a_leg():
    """A world-model ellipse of 2-sigma 1.2 m (above position_2sigma_m = 1.0) is uncertain in
    position while the navigation is exact; when 0.5 m of its 0.6 m sigma is the vehicle's own
    navigation error now (shared by every look), what looks can shrink is 2 sqrt(0.36 - 0.25)
    = 0.66 m, and position is no reason for a leg."""
    p = planner()
    obj = Obj(0, np.array([0.0, 0.0, 10.0]), cov_ned=np.diag([0.36, 0.36, 0.01]))
    for bearing in (0.0, 90.0, 180.0, 270.0):
        look_from(p, obj, bearing, 6.0)
    assert p.reasons(obj) == ["position"]
    p.set_navigation_covariance(np.diag([0.25, 0.25, 0.04]))
    assert p.reducible_2sigma_m(obj) == pytest.approx(2.0 * math.sqrt(0.11))
    assert p.reasons(obj) == []
    p.reset()
    assert p.reducible_2sigma_m(obj) == pytest.approx(1.2)


def test_an_object_beyond_the_survey_area_is_neither_inspected_nor_waited_for():
    """A confirmed, uncertain object 5 m outside the area (a basin wall's echo) gets no leg and
    does not keep the map from being confident; moved inside, it gets one."""
    p = planner()
    outside = Obj(0, np.array([0.0, 25.0, 10.0]), class_pmf=np.array([0.5, 0.5]))  # E 25 > 20 + 2
    assert p.confirmed(outside) and not p.in_area(outside) and not p.confident(outside)
    assert p.plan([outside], (0.0, 0.0)) == [] and p.map_confident([outside])
    inside = Obj(0, np.array([0.0, 15.0, 10.0]), class_pmf=np.array([0.5, 0.5]))
    assert [leg.object_id for leg in p.plan([inside], (0.0, 0.0))] == [0] and not p.map_confident([inside])
