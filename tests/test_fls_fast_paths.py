"""FLS renderer fast paths against the plain numpy they replace."""

from __future__ import annotations

import numpy as np
from scipy import stats

from sim.sensors.fls_image import row_cumsum, spread_segments, standard_exponential_f32, to_uint8_db


def test_row_cumsum_matches_numpy(rng):
    a = rng.standard_normal((57, 130)) * rng.uniform(0.1, 1e3, (57, 1))
    got = row_cumsum(a, 120)
    want = np.cumsum(a, axis=1)[:, :120]
    assert got.shape == (57, 120) and got.dtype == np.float64
    assert np.allclose(got, want, rtol=0.0, atol=1e-12 * np.abs(a).sum(axis=0).max())
    assert row_cumsum(a, 120, np.float32).dtype == np.float32


def test_spread_segments_float32_matches_float64(rng):
    row = rng.integers(0, 4, 300)
    ua = rng.uniform(-5, 60, 300)
    ub = ua + rng.exponential(5.0, 300)
    e = rng.uniform(0.1, 2.0, 300)
    f64 = spread_segments(4, 50, row, ua, ub, e)
    f32 = spread_segments(4, 50, row, ua, ub, e, dtype=np.float32)
    assert f32.dtype == np.float32 and np.allclose(f32, f64, rtol=1e-6, atol=1e-6)
    assert (f64 >= 0.0).all()


def test_standard_exponential_f32_is_exp1():
    g = np.random.default_rng(3)
    x = standard_exponential_f32(g, (300, 400))
    assert x.dtype == np.float32 and x.shape == (300, 400)
    assert np.isfinite(x).all() and (x >= 0.0).all()
    sample = x.ravel()[::7].astype(float)
    assert stats.kstest(sample, "expon").pvalue > 1e-3
    assert stats.kstest(sample, stats.gamma(a=1.2).cdf).pvalue < 1e-6  # the test has teeth
    assert abs(x.mean() - 1.0) < 0.01 and abs(x.var() - 1.0) < 0.03
    # same seed, same draws
    assert np.array_equal(standard_exponential_f32(np.random.default_rng(3), (300, 400)), x)


def test_to_uint8_db_matches_the_formula(rng):
    img = (10.0 ** rng.uniform(-9, 2, (40, 60))).astype(np.float32)
    img[0, :5] = 0.0
    gain = (10.0 ** rng.uniform(-1, 3, 60)).astype(np.float32)
    gain_db, dr_db = -10.0, 60.0
    got = to_uint8_db(img, gain, gain_db, dr_db)
    db = 10.0 * np.log10(np.maximum(img.astype(float) * gain, 1e-30)) + gain_db
    want = np.clip(np.round(255.0 * (db + dr_db) / dr_db), 0, 255)
    assert got.dtype == np.uint8
    assert np.abs(got.astype(int) - want).max() <= 1
    assert (got[0, :5] == 0).all() and (want == 255).any() and (want == 0).any()
