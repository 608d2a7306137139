"""FLS assembly: speckle statistics on a rendered seabed, presets, config and ray columns."""

from __future__ import annotations

import numpy as np
import pytest
from pydantic import ValidationError
from scipy import integrate, stats

from scenarios.config.fls import FlsConfig
from sim.sensors.analytic_caster import AnalyticCaster
from sim.sensors.fls import FlsSensor
from scenarios.fls_presets import resolve_geometry


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


def test_aris_frame_rate_is_bounded_by_its_pings_per_frame():
    """The ARIS forms its 128 beams in 8 pings, each listening the two-way time to the far
    end of the window: 1500 / (2 x 15 x 8) = 6.25 frames/s over 15 m, 18.75 over 5 m."""
    from scenarios.fls_presets import max_frame_rate_hz

    assert max_frame_rate_hz(8, 15.0) == pytest.approx(6.25)
    assert max_frame_rate_hz(8, 5.0) == pytest.approx(18.75)
    resolve_geometry(FlsConfig(preset="aris3000_lf", rate_hz=6.0))
    resolve_geometry(FlsConfig(preset="aris3000_lf", rate_hz=10.0, range_window_m=(1.0, 9.0)))  # 10.4 frames/s
    with pytest.raises(ValueError, match="rate_hz"):
        resolve_geometry(FlsConfig(preset="aris3000_lf", rate_hz=10.0))
    resolve_geometry(FlsConfig(preset="m900_130", rate_hz=10.0, range_window_m=(1.0, 100.0)))  # not modelled
