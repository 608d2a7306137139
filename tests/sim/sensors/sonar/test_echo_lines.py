"""Echo lines: range binning against numerical integration, and a sphere's range extremum."""

from __future__ import annotations

import numpy as np
import pytest

from sim.sensors.analytic_caster import AnalyticCaster, AnalyticSphere
from sim.sensors.sonar.echo_lines import echo_segments, ray_strength, row_cumsum, spread_segments
from autonomy.sonar_frame import sonar_to_body_rotation
from sim.sensors.sonar.ray_fan import RayFan


def test_spread_segments_matches_integration(rng):
    n_rows, n_bins = 3, 40
    row = rng.integers(0, n_rows, 200)
    ua = rng.uniform(-5, 45, 200)
    ub = ua + rng.exponential(4.0, 200) * rng.choice([-1, 1], 200)
    ub[:20] = ua[:20]  # points
    e = rng.uniform(0.1, 2.0, 200)
    got = spread_segments(n_rows, n_bins, row, ua, ub, e)
    want = np.zeros((n_rows, n_bins))
    for r, a, b, w in zip(row, ua, ub, e):
        lo, hi = min(a, b), max(a, b)
        if hi - lo < 1e-9:
            if 0 <= np.floor(lo) < n_bins:
                want[r, int(np.floor(lo))] += w
            continue
        for k in range(n_bins):
            overlap = max(0.0, min(hi, k + 1) - max(lo, k))
            want[r, k] += w * overlap / (hi - lo)
    assert np.allclose(got, want, atol=1e-9)


def test_spread_segments_float32_matches_float64(rng):
    row = rng.integers(0, 4, 300)
    ua = rng.uniform(-5, 60, 300)
    ub = ua + rng.exponential(5.0, 300)
    e = rng.uniform(0.1, 2.0, 300)
    f64 = spread_segments(4, 50, row, ua, ub, e)
    f32 = spread_segments(4, 50, row, ua, ub, e, dtype=np.float32)
    assert f32.dtype == np.float32 and np.allclose(f32, f64, rtol=1e-6, atol=1e-6)
    assert (f64 >= 0.0).all()


def test_row_cumsum_matches_numpy(rng):
    a = rng.standard_normal((57, 130)) * rng.uniform(0.1, 1e3, (57, 1))
    got = row_cumsum(a, 120)
    assert got.shape == (57, 120) and got.dtype == np.float64
    assert np.allclose(got, np.cumsum(a, axis=1)[:, :120], rtol=0.0, atol=1e-12 * np.abs(a).sum(axis=0).max())
    assert row_cumsum(a, 120, np.float32).dtype == np.float32


def test_ray_strength_is_lambert_times_the_elevation_pattern():
    """Level sonar 2 m above a flat bed: the ray at 30 deg down meets it at incidence 60 deg
    (cos 0.5); on the beam axis the two-way pattern is 1 and at half the beam width 1/4."""
    bw = np.deg2rad(60.0)
    fan = RayFan([0.0], np.deg2rad([0.0, 30.0]))
    rays, _ = fan.cast(AnalyticCaster(seabed_depth_m=2.0, seabed_reflectivity=0.4), np.zeros(3), np.eye(3), 50.0)
    s = ray_strength(rays, 2.0, bw, fan.elevation_step_rad)
    assert s[0] == 0.0  # the horizontal ray hits nothing
    assert s[1] * fan.elevation_step_rad == pytest.approx(0.4 * 0.5 ** 2 * 0.25, rel=1e-3)


@pytest.mark.parametrize("offset", [0.4, 0.5, 0.65])
def test_sphere_cap_range_found_between_rays(offset):
    """Rays 12 deg apart straddle a 3 m sphere 10 m ahead: no ray hits its nearest point (7 m),
    the nearest ray hit lies 8-20 cm beyond it; the echo still starts within a bin of 7 m."""
    dr = 0.0254
    step = np.deg2rad(12.0)
    fan = RayFan([0.0], (np.arange(-3, 3) + offset) * step)
    caster = AnalyticCaster(None, spheres=(AnalyticSphere(np.array([10.0, 0.0, 0.0]), 3.0, 1),))
    base, _ = fan.cast(caster, np.zeros(3), np.eye(3), 50.0)
    rays, segs = fan.refine_edges(caster, np.zeros(3), np.eye(3), base, 50.0, 30.0, 6)
    assert np.min(base.dist) - 7.0 > 2 * dr  # the rays alone would put the echo bins late
    strength = ray_strength(rays, 1.0, np.deg2rad(80.0), fan.elevation_step_rad)
    e = echo_segments(rays, segs, strength, fan.range_slope(rays, np.eye(3)), 1.0, dr)
    first_m = 1.0 + dr * min(e.u0.min(), e.u1.min())
    assert abs(first_m - 7.0) <= dr
    assert set(e.obj.tolist()) == {1} and (e.energy > 0).all()
    # energy kept: per column, the binned line holds the segments' energy
    lines = e.lines(1, int(30.0 / dr))
    assert lines.sum() == pytest.approx(e.energy.sum(), rel=1e-5)


def test_fold_extremum_is_bounded_by_the_end_tangents():
    """A range r(t) = r0 + A (t - t0)^2 over an interval: its true minimum r0 lies within the
    bound and is kept; a wild extremum below is raised to where the end tangents cross, which
    for a parabola is t = 1/2, r0 + A (t0^2 - t0) (closed form, independent of the code). The
    grazing pair a diver's back gave (ra 10.976 m, rb 11.401 m, slopes -0.081 and 37.9 m per
    interval, quadratic extremum 6.44 m) is raised to within 0.1 m of the nearer end."""
    from sim.sensors.sonar.echo_lines import _clamp_to_end_tangents

    r0 = 10.0
    A = np.array([0.3, 2.0, 8.0])
    t0 = np.array([0.2, 0.5, 0.9])
    ra, rb = r0 + A * t0**2, r0 + A * (1 - t0) ** 2
    sa, sb = -2 * A * t0, 2 * A * (1 - t0)
    fold = np.ones(3, dtype=bool)
    np.testing.assert_allclose(_clamp_to_end_tangents(np.full(3, r0), fold, ra, rb, sa, sb), r0)
    np.testing.assert_allclose(_clamp_to_end_tangents(np.full(3, r0 - 5.0), fold, ra, rb, sa, sb),
                               r0 + A * (t0**2 - t0))
    # a maximum (the same parabola upside down) is lowered to its tangents' crossing likewise
    np.testing.assert_allclose(_clamp_to_end_tangents(np.full(3, -r0 + 5.0), fold, -ra, -rb, -sa, -sb),
                               -(r0 + A * (t0**2 - t0)))
    # no fold: untouched
    assert _clamp_to_end_tangents(np.array([3.0]), np.array([False]), np.array([10.0]), np.array([11.0]),
                                  np.array([-1.0]), np.array([1.0]))[0] == 3.0
    r = _clamp_to_end_tangents(np.array([6.439]), np.array([True]), np.array([10.976]), np.array([11.401]),
                               np.array([-0.081]), np.array([37.897]))[0]
    assert 10.976 - 0.1 < r < 10.976


def test_compiled_echo_segments_match_the_numpy_reference_bit_for_bit():
    """Random intervals (connected and not, misses, folds of either sign, zero slopes) give
    the reference's rows in its order, every float equal."""
    from sim.sensors.sonar.echo_lines import echo_segments_reference
    from sim.sensors.sonar.ray_fan import RayTable, Segments

    g = np.random.default_rng(5)
    n, m = 4000, 6000
    dist = g.uniform(0.5, 40.0, n)
    dist[g.random(n) < 0.1] = np.inf
    rays = RayTable(col=g.integers(0, 50, n).astype(np.intp), az=np.zeros(n), phi=np.sort(g.uniform(-0.3, 0.3, n)),
                    weight=np.ones(n), dirs=np.zeros((n, 3)), dist=dist, normal=np.zeros((n, 3)),
                    refl=np.ones(n), obj=g.integers(-2, 4, n))
    a = g.integers(0, n - 1, m)
    b = np.minimum(a + g.integers(1, 4, m), n - 1)
    segs = Segments(a.astype(np.intp), b.astype(np.intp), g.random(m) < 0.7)
    strength = np.where(g.random(n) < 0.05, 0.0, g.uniform(0.0, 3.0, n))
    slope = g.normal(scale=30.0, size=n)
    slope[g.random(n) < 0.05] = 0.0
    with np.errstate(all="ignore"):  # the reference meets inf * 0 on misses
        want = echo_segments_reference(rays, segs, strength, slope, 1.0, 0.025)
    got = echo_segments(rays, segs, strength, slope, 1.0, 0.025)
    assert len(want.line) > 0.5 * m
    for f in ("line", "u0", "u1", "energy", "obj"):
        w, o = getattr(want, f), getattr(got, f)
        assert w.dtype == o.dtype and np.array_equal(w, o), f


def test_compiled_echo_segments_match_the_reference_on_a_scene():
    """A fan over a sphere on a plane (silhouette, shadow, cap folds): same rows, same bits."""
    from sim.sensors.sonar.echo_lines import echo_segments_reference

    fan = RayFan(np.deg2rad(np.linspace(-20, 20, 61)), np.deg2rad(np.linspace(0, 40, 24)))
    caster = AnalyticCaster(8.0, spheres=(AnalyticSphere(np.array([6.0, 0.3, 4.2]), 1.5, 1),))
    R = sonar_to_body_rotation(np.deg2rad([0.0, 20.0, 0.0]))
    base, _ = fan.cast(caster, np.zeros(3), R, 50.0)
    rays, segs = fan.refine_edges(caster, np.zeros(3), R, base, 50.0, 30.0, 5)
    strength = ray_strength(rays, 2.0, np.deg2rad(20.0), fan.elevation_step_rad)
    slope = fan.range_slope(rays, R)
    want = echo_segments_reference(rays, segs, strength, slope, 1.0, 0.02)
    got = echo_segments(rays, segs, strength, slope, 1.0, 0.02)
    assert len(want.line) > 1000
    for f in ("line", "u0", "u1", "energy", "obj"):
        assert np.array_equal(getattr(want, f), getattr(got, f)), f
