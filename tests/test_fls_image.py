"""FLS image formation pieces against numerical oracles, speckle statistics, presets and config."""

from __future__ import annotations

import numpy as np
import pytest
from pydantic import ValidationError
from scipy import integrate, stats

from autonomy.sonar_geometry import FanGeometry
from scenarios.config.fls import FlsConfig
from sim.sensors.analytic_caster import AnalyticCaster
from sim.sensors.fls import FlsSensor
from sim.sensors.fls_image import (
    FanRemap,
    azimuth_kernel,
    spread_segments,
    to_uint8_db,
    tvg_gain,
    two_way_beam_power,
)
from sim.sensors.fls_presets import resolve_geometry


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


def test_beam_pattern_half_power_and_side_lobe():
    bw = np.deg2rad(1.0)
    assert 10 * np.log10(two_way_beam_power(bw / 2, bw)) == pytest.approx(-6.02, abs=0.02)
    x = np.linspace(0.6 * bw, 3 * bw, 5001)
    p = two_way_beam_power(x, bw)
    # first side lobe of a uniform aperture: -13.26 dB one way, doubled two way
    interior = (p[1:-1] > p[:-2]) & (p[1:-1] > p[2:])
    assert 10 * np.log10(p[1:-1][interior][0]) == pytest.approx(-26.5, abs=0.1)
    k = azimuth_kernel(np.deg2rad(0.18), bw, 3.0)
    assert k.sum() == pytest.approx(1.0) and np.argmax(k) == len(k) // 2 and np.allclose(k, k[::-1])


def test_fan_remap_puts_a_cell_at_its_polar_position():
    fan = FanGeometry.fit(400, 300, 1.0, 20.0, np.deg2rad(90))
    az = np.deg2rad(-45) + (np.arange(100) + 0.5) * np.deg2rad(0.9)
    remap = FanRemap(fan, az, 1.0, 0.1, 190)
    polar = np.zeros((100, 190), np.uint8)
    polar[70, 120] = 255
    x, y = fan.polar_to_pixel(1.0 + 120.5 * 0.1, az[70])
    img = remap.image(polar)
    ys, xs = np.nonzero(img)
    assert np.hypot(np.average(xs, weights=img[ys, xs]) - x, np.average(ys, weights=img[ys, xs]) - y) < 1.0
    labels = remap.labels(polar.astype(np.int16) // 255 * 5 - 1, fill=-1)
    assert set(np.unique(labels).tolist()) <= {-1, 4}
    assert remap.image(np.full((100, 190), 9, np.uint8))[0, 0] == 0  # outside the fan


def test_tvg_and_display_mapping():
    r = np.array([1.0, 10.0, 100.0])
    assert 10 * np.log10(tvg_gain(r, 20.0, 0.0)) == pytest.approx([0.0, 20.0, 40.0])
    assert 10 * np.log10(tvg_gain(r, 0.0, 0.5)) == pytest.approx(r)  # 2 alpha r
    img = np.array([[1.0, 1e-5, 1e-2]], np.float32)
    u8 = to_uint8_db(img, np.ones(3, np.float32), gain_db=0.0, dynamic_range_db=50.0)
    assert u8.tolist() == [[255, 0, 153]]  # -20 dB of a 50 dB range


def flat_seabed_render(speckle: str, seed: int, **kw):
    cfg = FlsConfig(tilt_deg=10.0, range_window_m=(1.0, 20.0), speckle=speckle, noise_floor_db=-200.0, **kw)
    s = FlsSensor(cfg, rng=np.random.default_rng(seed))
    out = s.render(0.0, np.array([0.0, 0.0, 4.0]), np.eye(3), AnalyticCaster(6.0, 0.3), [])
    patch = np.s_[250:470, 400:600]  # uniform seabed, ~10-16 m
    mean = out.mean_intensity[patch]
    assert np.all(mean > 0)  # seabed everywhere in the patch
    return (out.intensity[patch] / mean).ravel()


def test_rayleigh_speckle_is_exponential():
    ratio = flat_seabed_render("rayleigh", 3)
    assert stats.kstest(ratio, "expon").pvalue > 1e-3
    assert stats.kstest(ratio, stats.gamma(a=2.0, scale=0.5).cdf).pvalue < 1e-6  # the test has teeth


def test_k_distributed_clutter():
    nu = 1.5
    ratio = flat_seabed_render("k", 4, k_shape=nu)
    ref_rng = np.random.default_rng(99)
    ref = stats.gamma(a=nu, scale=1.0 / nu).rvs(200_000, random_state=ref_rng) * ref_rng.exponential(size=200_000)
    assert stats.ks_2samp(ratio, ref).pvalue > 1e-3
    assert stats.kstest(ratio, "expon").pvalue < 1e-6
    # K intensity pdf mean 1, second moment 2 (1 + 1/nu)
    assert np.mean(ratio ** 2) == pytest.approx(2 * (1 + 1 / nu), rel=0.05)
    cdf_at_1 = integrate.quad(lambda t: stats.gamma.pdf(t, nu, scale=1 / nu) * (1 - np.exp(-1 / t)), 0, np.inf)[0]
    assert np.mean(ratio <= 1.0) == pytest.approx(cdf_at_1, abs=0.01)


def test_presets():
    g = resolve_geometry(FlsConfig(preset="m900_130", range_window_m=(1.0, 30.0)))
    assert g.n_beams == 722 and np.rad2deg(g.fov_rad) == pytest.approx(130.0)
    assert np.rad2deg(g.beam_spacing_rad) == pytest.approx(0.18, abs=0.001)
    assert g.range_resolution_m == pytest.approx(0.0254) and g.n_bins == 1142
    assert g.fan_size_px == (894, 477) and g.range_max_m == 100.0
    a = resolve_geometry(FlsConfig(preset="aris3000"))
    assert (a.n_beams, np.rad2deg(a.fov_rad), np.rad2deg(a.vertical_beamwidth_rad), a.window_far_m) == (
        128, pytest.approx(30.0), pytest.approx(14.0), 5.0)
    assert resolve_geometry(FlsConfig(preset="aris3000_lf")).window_far_m == 15.0
    s = FlsSensor(FlsConfig(preset="aris3000", elevation_rays=8))
    assert s.n_rays == 128 * 8 and s.fan_geometry.width_px == 512


def test_bad_config_names_the_key():
    with pytest.raises(ValueError, match="range_window_m"):
        resolve_geometry(FlsConfig(preset="aris3000", range_window_m=(1.0, 30.0)))
    with pytest.raises(ValidationError, match="range_window_m"):
        FlsConfig(range_window_m=(5.0, 2.0))
    with pytest.raises(ValidationError, match="preset"):
        FlsConfig(preset="m900")
    with pytest.raises(ValidationError, match="elevation_rays"):
        FlsConfig(elevation_rays=1)
    with pytest.raises(ValueError, match="azimuth_columns"):
        resolve_geometry(FlsConfig(azimuth_columns=1000))


def test_fewer_ray_columns_interpolate_to_beams():
    cfg = FlsConfig(tilt_deg=10.0, range_window_m=(1.0, 20.0), azimuth_columns=361)
    s = FlsSensor(cfg)
    out = s.render(0.0, np.array([0.0, 0.0, 4.0]), np.eye(3), AnalyticCaster(6.0, 0.3), [], noise=False)
    assert out.frame.polar.shape == (722, s.n_bins) and s.n_rays == 361 * cfg.elevation_rays
    full = FlsSensor(FlsConfig(tilt_deg=10.0, range_window_m=(1.0, 20.0)))
    ref = full.render(0.0, np.array([0.0, 0.0, 4.0]), np.eye(3), AnalyticCaster(6.0, 0.3), [], noise=False)
    centre = np.s_[100:600, 300:600]
    assert np.allclose(out.mean_intensity[centre], ref.mean_intensity[centre], rtol=0.05)
