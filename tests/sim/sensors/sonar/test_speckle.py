"""Speckle and receiver noise against their distributions."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from sim.sensors.sonar.speckle import add_speckle_and_noise, standard_exponential_f32


def test_standard_exponential_f32_is_exp1():
    g = np.random.default_rng(3)
    x = standard_exponential_f32(g, (300, 400))
    assert x.dtype == np.float32 and x.shape == (300, 400)
    assert np.isfinite(x).all() and (x >= 0.0).all()
    sample = x.ravel()[::7].astype(float)
    assert stats.kstest(sample, "expon").pvalue > 1e-3
    assert stats.kstest(sample, stats.gamma(a=1.2).cdf).pvalue < 1e-6  # the test has teeth
    assert abs(x.mean() - 1.0) < 0.01 and abs(x.var() - 1.0) < 0.03
    assert np.array_equal(standard_exponential_f32(np.random.default_rng(3), (300, 400)), x)


def test_rayleigh_speckle_scales_echo_plus_noise():
    mean = np.full((200, 300), 4.0, np.float32)
    out = add_speckle_and_noise(mean, np.random.default_rng(1), "rayleigh", 1.0)
    ratio = out.ravel()[::5].astype(float) / 5.0  # (echo + noise) power
    assert stats.kstest(ratio, "expon").pvalue > 1e-3
    assert stats.kstest(ratio, "expon", args=(0, 0.8)).pvalue < 1e-6


def test_k_texture_only_where_clutter():
    nu = 1.5
    mean = np.ones((400, 500), np.float32)
    clutter = np.zeros(mean.shape, bool)
    clutter[:200] = True
    out = add_speckle_and_noise(mean, np.random.default_rng(2), "k", 0.0, k_shape=nu, clutter=clutter)
    k_part, plain = out[:200].ravel().astype(float), out[200:].ravel().astype(float)
    assert stats.kstest(plain, "expon").pvalue > 1e-3
    # K intensity with unit mean: second moment 2 (1 + 1/nu)
    assert np.mean(k_part) == pytest.approx(1.0, rel=0.02)
    assert np.mean(k_part ** 2) == pytest.approx(2 * (1 + 1 / nu), rel=0.05)
    assert stats.kstest(k_part, "expon").pvalue < 1e-6


def test_no_speckle_adds_exponential_noise_only():
    mean = np.full((300, 300), 2.0, np.float32)
    out = add_speckle_and_noise(mean, np.random.default_rng(4), "none", 0.5)
    assert (out >= 2.0).all()
    assert stats.kstest((out.ravel() - 2.0) / 0.5, "expon").pvalue > 1e-3
    np.testing.assert_array_equal(add_speckle_and_noise(mean, np.random.default_rng(4), "none", 0.0), mean)
