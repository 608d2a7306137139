"""Ground truth against hand-made echoes and analytic occlusion geometry."""

from __future__ import annotations

import numpy as np
import pytest

from autonomy.sonar_frame import ray_directions_sonar, sonar_to_body_rotation
from sim.sensors.analytic_caster import AnalyticBox, AnalyticCaster, AnalyticSphere
from sim.sensors.raycast import BACKGROUND_ID
from sim.sensors.sonar.echo_lines import EchoSegments
from sim.sensors.sonar.ground_truth import centroid_polar, label_bins, visible_fraction


def test_label_bins_takes_the_strongest_object():
    """Line 1: object 3 spreads 2 units over bins 10-19 (0.2 per bin), object 5 one unit over
    15-29 (1/15 per bin): 3 wins 10-19, 5 wins 20-29. Line 0: seabed only."""
    segs = EchoSegments(line=np.array([1, 1, 0, 1]), u0=np.array([10.0, 15.0, 0.0, 0.0]),
                        u1=np.array([20.0, 30.0, 40.0, 40.0]), energy=np.array([2.0, 1.0, 5.0, 5.0]),
                        obj=np.array([3, 5, BACKGROUND_ID, BACKGROUND_ID]))
    mask, extents = label_bins(segs, 3, 40)
    want = np.full((3, 40), BACKGROUND_ID)
    want[1, 10:20] = 3
    want[1, 20:30] = 5
    np.testing.assert_array_equal(mask, want)
    assert mask.dtype == np.int16
    assert extents == {3: (1, 1, 10, 19), 5: (1, 1, 20, 29)}


def test_label_bins_point_echo_and_empty():
    segs = EchoSegments(np.array([2]), np.array([7.3]), np.array([7.3]), np.array([1.0]), np.array([0]))
    mask, extents = label_bins(segs, 4, 20)
    assert extents == {0: (2, 2, 7, 7)} and np.count_nonzero(mask >= 0) == 1
    none = EchoSegments(*(np.zeros(0, dtype=t) for t in (np.intp, float, float, float, np.int64)))
    mask, extents = label_bins(none, 4, 20)
    assert extents == {} and (mask == BACKGROUND_ID).all()


def test_centroid_polar_hand_computed():
    R_ns = sonar_to_body_rotation(np.deg2rad([0.0, 30.0, 0.0]))  # level vehicle, sonar tilted 30 deg down
    origin = np.array([1.0, 2.0, 3.0])
    # 10 m along the boresight, then 10 m along the starboard axis
    r, a, e = centroid_polar(origin + [10 * np.sqrt(3) / 2, 0.0, 5.0], origin, R_ns)
    assert (r, a, e) == pytest.approx((10.0, 0.0, 0.0), abs=1e-12)
    r, a, e = centroid_polar(origin + [0.0, 10.0, 0.0], origin, R_ns)
    assert (r, a, e) == pytest.approx((10.0, np.pi / 2, 0.0), abs=1e-12)
    r, a, e = centroid_polar(origin + [0.0, 0.0, 4.0], origin, R_ns)  # straight down: 60 deg below boresight
    assert (r, a, e) == pytest.approx((4.0, 0.0, np.deg2rad(60.0)), abs=1e-12)


def _ray_grid(half_deg: float, n: int) -> np.ndarray:
    a, e = np.meshgrid(np.deg2rad(np.linspace(-half_deg, half_deg, n)), np.deg2rad(np.linspace(-half_deg, half_deg, n)))
    return ray_directions_sonar(a.ravel(), e.ravel())


@pytest.mark.parametrize("edge_y_m", [0.0, 0.3, -0.3])
def test_visible_fraction_behind_a_wall_edge(edge_y_m):
    """A sphere (R 1 m, 15 m ahead) behind a wall at 8 m whose edge runs at y = edge: the rays
    see the part of its angular disc beyond the edge's angle, a circular segment."""
    D, R, wall_x = 15.0, 1.0, 8.0
    sphere = AnalyticSphere(np.array([D, 0.0, 0.0]), R, 1)
    wall = AnalyticBox(np.array([wall_x, edge_y_m - 5.0, 0.0]), np.array([0.05, 5.0, 5.0]), 2)
    caster = AnalyticCaster(None, spheres=(sphere,), boxes=(wall,))
    dirs = _ray_grid(6.0, 241)
    first = caster.cast(np.zeros(3), dirs, 50.0).object_id
    n_hit = int(np.count_nonzero(first == 1))
    frac = visible_fraction(caster, 1, np.zeros(3), dirs, first, n_hit, 1.0, 30.0, 50.0, np.deg2rad(0.05))
    rho = np.arcsin(R / D)  # angular radius of the disc
    t = np.clip(np.arctan2(edge_y_m, wall_x) / rho, -1.0, 1.0)  # edge, in disc radii
    visible_area = (np.arccos(t) - t * np.sqrt(1 - t * t)) / np.pi  # segment beyond the edge / disc
    assert frac == pytest.approx(visible_area, abs=0.02)


def test_visible_fraction_limits():
    sphere = AnalyticSphere(np.array([10.0, 0.0, 0.0]), 0.5, 1)
    caster = AnalyticCaster(None, spheres=(sphere,))
    dirs = _ray_grid(5.0, 101)
    first = caster.cast(np.zeros(3), dirs, 50.0).object_id
    n = int(np.count_nonzero(first == 1))
    assert visible_fraction(caster, 1, np.zeros(3), dirs, first, n, 1.0, 30.0, 50.0, 0.001) == 1.0
    assert visible_fraction(caster, 1, np.zeros(3), dirs, first, 0, 1.0, 30.0, 50.0, 0.001) == 0.0
    # wholly beyond the range window: nothing to see
    assert visible_fraction(caster, 1, np.zeros(3), dirs, first, n, 1.0, 5.0, 50.0, 0.001) == 0.0
    assert np.isnan(visible_fraction(object(), 1, np.zeros(3), dirs, first, n, 1.0, 30.0, 50.0, 0.001))


def test_visible_fraction_over_a_row_subset_matches_the_copied_subset():
    """Counting only ``rows`` of the full ray table (with the sphere given) equals passing a copy
    of those rows (with the sphere asked of the caster)."""
    sphere = AnalyticSphere(np.array([15.0, 0.0, 0.0]), 1.0, 1)
    wall = AnalyticBox(np.array([8.0, 0.3 - 5.0, 0.0]), np.array([0.05, 5.0, 5.0]), 2)
    caster = AnalyticCaster(None, spheres=(sphere,), boxes=(wall,))
    dirs = _ray_grid(6.0, 121)
    first = caster.cast(np.zeros(3), dirs, 50.0).object_id
    rows = np.random.default_rng(3).random(len(dirs)) < 0.6
    n_hit = int(np.count_nonzero(first[rows] == 1))
    ref = visible_fraction(caster, 1, np.zeros(3), dirs[rows], first[rows], n_hit, 1.0, 30.0, 50.0, 0.001)
    got = visible_fraction(caster, 1, np.zeros(3), dirs, first, n_hit, 1.0, 30.0, 50.0, 0.001, rows=rows,
                           sphere=caster.object_bounding_sphere(1))
    assert 0.1 < ref < 0.9 and got == ref


class _CountingCaster:
    """Forwards to an analytic caster, counting the rays cast against one object alone."""

    def __init__(self, caster):
        self.caster, self.n_isolated = caster, 0

    def cast(self, origin, dirs, max_range_m):
        return self.caster.cast(origin, dirs, max_range_m)

    def cast_isolated(self, origin, dirs, max_range_m, object_id):
        self.n_isolated += len(dirs)
        return self.caster.cast_isolated(origin, dirs, max_range_m, object_id)

    def object_bounding_sphere(self, object_id):
        return self.caster.object_bounding_sphere(object_id)


@pytest.mark.parametrize("far_m", [30.0, 15.2, 14.7])
def test_visible_fraction_with_first_hit_ranges_casts_fewer_rays_for_the_same_fraction(far_m):
    """Rays whose isolated answer the first hit gives (past the bounding sphere, beyond the window,
    missing it) are not cast again; the fraction is the one every candidate ray gives. The object
    is two balls (bounding sphere 2 m about 15 m ahead), one half hidden by a plate inside that
    sphere (rays stopped there must still be cast), with a floor behind; a far window edge
    cutting the object (15.2 m, 14.7 m) exercises the window tests."""
    balls = (AnalyticSphere(np.array([15.0, -1.5, 0.0]), 0.5, 1), AnalyticSphere(np.array([15.0, 1.5, 0.0]), 0.5, 1))
    plate = AnalyticBox(np.array([14.2, 1.5, -0.5]), np.array([0.05, 0.6, 0.5]), 2)
    floor = AnalyticBox(np.array([15.0, 0.0, 0.45 + 5.0]), np.array([20.0, 20.0, 5.0]), -1)
    caster = _CountingCaster(AnalyticCaster(None, spheres=balls, boxes=(plate, floor)))
    dirs = _ray_grid(9.0, 181)
    hits = caster.cast(np.zeros(3), dirs, 50.0)
    first, dist = hits.object_id, hits.dist_m
    n_hit = int(np.count_nonzero((first == 1) & (dist <= far_m)))
    ref = visible_fraction(caster, 1, np.zeros(3), dirs, first, n_hit, 1.0, far_m, 50.0, 0.01)
    n_ref, caster.n_isolated = caster.n_isolated, 0
    got = visible_fraction(caster, 1, np.zeros(3), dirs, first, n_hit, 1.0, far_m, 50.0, 0.01, first_dist=dist)
    assert 0.05 < ref < 0.95 and got == ref
    assert caster.n_isolated < 0.75 * n_ref
