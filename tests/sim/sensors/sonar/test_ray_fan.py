"""Ray sampling against hand-computed directions and analytic ray-surface geometry."""

from __future__ import annotations

import numpy as np
import pytest

from sim.sensors.analytic_caster import AnalyticBox, AnalyticCaster, AnalyticSphere
from sim.sensors.sonar.ray_fan import RayFan, same_surface


def test_layout_is_column_major_with_hand_computed_directions():
    fan = RayFan(np.deg2rad([-30.0, 30.0]), np.deg2rad([-10.0, 0.0, 10.0]))
    assert fan.n_rays == 6 and fan.n_cols == 2 and fan.n_el == 3
    np.testing.assert_array_equal(fan.ray_col, [0, 0, 0, 1, 1, 1])
    c10, s10 = np.cos(np.deg2rad(10)), np.sin(np.deg2rad(10))
    c30, s30 = np.sqrt(3) / 2, 0.5
    want = [[c30 * c10, -s30 * c10, -s10], [c30, -s30, 0.0], [c30 * c10, -s30 * c10, s10],
            [c30 * c10, s30 * c10, -s10], [c30, s30, 0.0], [c30 * c10, s30 * c10, s10]]
    np.testing.assert_allclose(fan.dirs_sonar, want, atol=1e-15)
    assert fan.elevation_step_rad == pytest.approx(np.deg2rad(10.0))
    with pytest.raises(ValueError, match="elevations"):
        RayFan([0.0], [0.1])


def test_single_beam_and_side_scan_layouts():
    single = RayFan([0.0], np.linspace(-0.2, 0.2, 9))  # one column, e.g. a scanning sonar's beam
    assert single.n_rays == 9 and np.allclose(single.dirs_sonar[:, 1], 0.0)
    both_sides = RayFan(np.deg2rad([-90.0, 90.0]), np.linspace(0.0, 1.0, 5))
    np.testing.assert_allclose(both_sides.dirs_sonar[:5, 1], -np.cos(np.linspace(0.0, 1.0, 5)), atol=1e-15)


def test_flat_seabed_ranges_and_range_slope():
    """Sonar h above a flat bed, level: ray at elevation phi meets it at h / sin(phi), and
    dr/dphi = -h cos(phi) / sin(phi)^2 (any azimuth)."""
    h = 3.0
    phi = np.deg2rad(np.linspace(-4.0, 40.0, 12))
    fan = RayFan(np.deg2rad([-50.0, 0.0, 20.0]), phi)
    rays, hits = fan.cast(AnalyticCaster(seabed_depth_m=h), np.zeros(3), np.eye(3), 100.0)
    with np.errstate(divide="ignore"):
        want = np.where(fan.ray_phi > 0.0, h / np.sin(fan.ray_phi), np.inf)
    want[want > 100.0] = np.inf
    np.testing.assert_allclose(rays.dist, want, rtol=1e-12)
    assert hits.dist_m is rays.dist
    slope = fan.range_slope(rays, np.eye(3))
    hit = np.isfinite(want)
    np.testing.assert_allclose(slope[hit], -h * np.cos(fan.ray_phi[hit]) / np.sin(fan.ray_phi[hit]) ** 2,
                               rtol=1e-10)
    assert np.all(slope[~hit] == 0.0)


def test_same_surface_tells_a_plane_from_a_step():
    d = np.array([[0.3, 0.0, 1.0], [0.35, 0.0, 1.0]])  # steep rays onto a bed 3 m down
    d /= np.linalg.norm(d, axis=1)[:, None]
    up = np.array([[0.0, 0.0, -1.0]] * 2)
    h = 3.0
    r = h / d[:, 2]
    raised = np.array([(h - 1.0) / d[1, 2]])  # the second lands on a 1 m high ledge
    ids = np.array([-1, -1])
    on_plane = same_surface(r[:1], up[:1], ids[:1], d[:1], r[1:], up[1:], ids[1:], d[1:])
    step = same_surface(r[:1], up[:1], ids[:1], d[:1], raised, up[1:], ids[1:], d[1:])
    other_obj = same_surface(r[:1], up[:1], ids[:1], d[:1], r[1:], up[1:], np.array([3]), d[1:])
    miss = same_surface(r[:1], up[:1], ids[:1], d[:1], np.array([np.inf]), up[1:], ids[1:], d[1:])
    assert on_plane.tolist() == [True] and step.tolist() == [False]
    assert other_obj.tolist() == [False] and miss.tolist() == [False]


@pytest.mark.parametrize("iters", [3, 6, 9])
def test_edge_refinement_finds_a_sphere_silhouette(iters):
    """One column at azimuth 0 through a sphere of radius R at distance D: its silhouette is at
    elevation +-asin(R / D); bisection pins it within step / 2^iters."""
    D, R = 10.0, 1.0
    step = np.deg2rad(2.0)
    phi = np.arange(-10, 11) * step + 0.3 * step
    fan = RayFan([0.0], phi)
    caster = AnalyticCaster(None, spheres=(AnalyticSphere(np.array([D, 0.0, 0.0]), R, 4),))
    base, _ = fan.cast(caster, np.zeros(3), np.eye(3), 50.0)
    rays, segs = fan.refine_edges(caster, np.zeros(3), np.eye(3), base, 50.0, 30.0, iters)
    edge = np.arcsin(R / D)
    on = rays.obj == 4
    assert np.sum(on) > np.sum(base.obj == 4)  # refinement rays added on the sphere
    assert abs(rays.phi[on].max() - edge) <= step / 2 ** iters
    assert abs(rays.phi[on].min() + edge) <= step / 2 ** iters
    assert rays.phi[on].max() <= edge and rays.phi[on].min() >= -edge
    # the intervals tile the column: every base interval is kept or split into three
    assert len(segs.a) == len(phi) - 1 + 2 * 2
    assert np.all(rays.phi[segs.b] > rays.phi[segs.a])
    assert segs.connected.sum() == np.sum(base.obj == 4) - 1 + 2  # on-sphere intervals only


def test_no_refinement_of_a_continuous_seabed():
    fan = RayFan([0.0, 0.3], np.deg2rad(np.linspace(5.0, 25.0, 9)))
    base, _ = fan.cast(AnalyticCaster(seabed_depth_m=2.0), np.zeros(3), np.eye(3), 100.0)
    rays, segs = fan.refine_edges(AnalyticCaster(seabed_depth_m=2.0), np.zeros(3), np.eye(3), base, 100.0, 30.0, 6)
    assert len(rays.dist) == fan.n_rays and segs.connected.all() and len(segs.a) == 2 * 8


def test_box_face_is_one_surface_its_edge_is_not():
    box = AnalyticBox(np.array([8.0, 0.0, 0.0]), np.array([0.5, 2.0, 1.0]), 2)
    fan = RayFan([0.0], np.deg2rad(np.linspace(-12.0, 12.0, 25)))
    base, _ = fan.cast(AnalyticCaster(None, boxes=(box,)), np.zeros(3), np.eye(3), 50.0)
    same = base.same_surface(np.arange(24), np.arange(1, 25))
    on_face = np.isfinite(base.dist[:-1]) & np.isfinite(base.dist[1:])
    np.testing.assert_array_equal(same, on_face)


def test_strip_rays_sample_a_small_sphere_between_base_rays():
    """A 0.2 m sphere 20 m ahead between two base rays 1.33 deg apart and two columns 0.36 deg
    apart: the columns its azimuth extent overlaps become sub-columns whose weights sum to one,
    and about rays_across rays hit it each way."""
    el = np.linspace(np.deg2rad(-10), np.deg2rad(10), 16)
    cols = np.deg2rad(np.arange(-5, 6) * 0.36)
    fan = RayFan(cols, el)
    mid = 0.5 * (el[8] + el[9])
    centre = 20.0 * np.array([np.cos(mid) * np.cos(0.003), np.cos(mid) * np.sin(0.003), np.sin(mid)])
    caster = AnalyticCaster(None, spheres=(AnalyticSphere(centre, 0.1, 5),))
    base, _ = fan.cast(caster, np.zeros(3), np.eye(3), 50.0)
    assert not (base.obj == 5).any()  # the base rays miss it
    strips = fan.strip_rays([(5, centre, 0.1)], 8)
    beta = np.arcsin(0.1 / 20.0)
    az_c = np.arctan2(centre[1], centre[0])
    overlap = np.abs(cols - az_c) <= np.arcsin(np.sin(beta) / np.cos(mid)) + 0.5 * fan.column_width_rad
    np.testing.assert_array_equal(strips.columns, np.flatnonzero(overlap))
    for c in strips.columns:
        on = strips.col == c
        subs, first = np.unique(strips.az[on], return_index=True)
        assert strips.weight[on][first].sum() == pytest.approx(1.0)
        assert np.all(np.abs(subs - cols[c]) <= 0.5 * fan.column_width_rad)
    rays = fan.cast_rays(caster, np.zeros(3), np.eye(3), strips.col, strips.az, strips.phi, strips.weight, 50.0)
    hit = rays.obj == 5
    assert hit.any() and np.all(strips.owner[hit] == 5)
    n_sub_across = len(np.unique(rays.az[hit]))
    n_el_across = np.bincount(np.unique(rays.az[hit], return_inverse=True)[1]).max()
    assert 6 <= n_sub_across <= 10 and 6 <= n_el_across <= 10
    # a sphere the base rays already sample densely needs none
    assert fan.strip_rays([(6, np.array([5.0, 0.0, 0.0]), 1.0)], 8).empty


def _bisect_one_edge(fan, caster, lo_phi, hi_phi, col_az, far_m, iters):
    """Reference: bisect one interval with one single-ray cast per level (the plain algorithm)."""
    lo = fan.cast_rays(caster, np.zeros(3), np.eye(3), np.array([0]), np.array([col_az]), np.array([lo_phi]),
                       np.ones(1), 50.0)
    hi = fan.cast_rays(caster, np.zeros(3), np.eye(3), np.array([0]), np.array([col_az]), np.array([hi_phi]),
                       np.ones(1), 50.0)
    for _ in range(iters):
        if min(lo.dist[0], hi.dist[0]) > far_m:
            break
        mid = fan.cast_rays(caster, np.zeros(3), np.eye(3), np.array([0]), np.array([col_az]),
                            0.5 * (lo.phi + hi.phi), np.ones(1), 50.0)
        with_lo = same_surface(lo.dist, lo.normal, lo.obj, lo.dirs, mid.dist, mid.normal, mid.obj, mid.dirs)
        if with_lo[0] or (not np.isfinite(lo.dist[0]) and not np.isfinite(mid.dist[0])):
            lo = mid
        else:
            hi = mid
    return lo, hi


def test_batched_bisection_matches_one_edge_at_a_time():
    """All edges of a fan bisected together (one cast per level, edges dropping out once beyond
    the window) give, row for row, the rays of bisecting each edge alone."""
    spheres = (AnalyticSphere(np.array([10.0, 0.0, 0.5]), 1.0, 4), AnalyticSphere(np.array([25.0, 1.5, 2.0]), 2.0, 5),
               AnalyticSphere(np.array([6.0, -1.0, 1.4]), 0.4, 6))
    caster = AnalyticCaster(seabed_depth_m=3.0, spheres=spheres)
    fan = RayFan(np.deg2rad(np.linspace(-12.0, 12.0, 13)), np.deg2rad(np.linspace(-8.0, 30.0, 17)))
    base, _ = fan.cast(caster, np.zeros(3), np.eye(3), 50.0)
    far_m = 20.0
    pa = fan._pair_a
    pb = pa + 1
    refine = ~base.same_surface(pa, pb) & ~(~np.isfinite(base.dist[pa]) & ~np.isfinite(base.dist[pb]))
    ia, ib = pa[refine], pb[refine]
    assert len(ia) >= 10
    lo, hi = fan.bisect(caster, np.zeros(3), np.eye(3), base, ia, ib, 50.0, far_m, 6)
    for j, (a, b) in enumerate(zip(ia, ib)):
        ref_lo, ref_hi = _bisect_one_edge(fan, caster, base.phi[a], base.phi[b], base.az[a], far_m, 6)
        for got, ref in ((lo, ref_lo), (hi, ref_hi)):
            assert got.phi[j] == ref.phi[0] and got.col[j] == base.col[a]
            # same decisions at every level; the casts agree to round-off (a batch of one ray
            # is rotated by a different BLAS kernel than a batch of many)
            assert got.obj[j] == ref.obj[0] and got.refl[j] == ref.refl[0]
            np.testing.assert_allclose(got.dist[j], ref.dist[0], rtol=1e-12)
            np.testing.assert_allclose(got.normal[j], ref.normal[0], atol=1e-12)
            np.testing.assert_allclose(got.dirs[j], ref.dirs[0], atol=1e-12)


def test_cast_rays_per_block_rotation_matches_each_sonar_alone():
    """Two sonars at one origin (a side-scan's port and starboard, depressed 20 deg) cast
    together with one rotation per column block give each sonar's own cast, row for row."""
    from autonomy.sonar_frame import sonar_to_body_rotation

    fan = RayFan([0.0], np.linspace(-0.3, 1.2, 12))
    R = np.stack([sonar_to_body_rotation((0.0, np.deg2rad(20.0), yaw)) for yaw in (-0.5 * np.pi, 0.5 * np.pi)])
    caster = AnalyticCaster(seabed_depth_m=4.0, spheres=(AnalyticSphere(np.array([0.0, 5.0, 3.0]), 0.8, 7),))
    origin = np.zeros(3)
    phi = np.tile(fan.elevations_rad, 2)
    col = np.repeat([0, 1], fan.n_el)  # column 1 = the starboard sonar's column 0
    az, w = np.zeros(2 * fan.n_el), np.ones(2 * fan.n_el)
    both = fan.cast_rays(caster, origin, R, col, az, phi, w, 50.0)
    for side in (0, 1):
        rows = col == side
        alone = fan.cast_rays(caster, origin, R[side], col[rows], az[rows], phi[rows], w[rows], 50.0)
        for f in ("dirs", "dist", "normal", "obj"):
            np.testing.assert_array_equal(getattr(both, f)[rows], getattr(alone, f))
    # only the starboard sonar sees the sphere to starboard
    assert (both.obj[col == 1] == 7).any() and not (both.obj[col == 0] == 7).any()
