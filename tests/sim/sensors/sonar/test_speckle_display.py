"""The counter-based speckle and display pass against the exact laws and the sequential path."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from sim.sensors.sonar.display import to_uint8_db
from sim.sensors.sonar.echo_chain import EchoChain
from sim.sensors.sonar.speckle_display import CounterSpeckleDisplay, db_display_table, exponential_quantiles

BINS_M = np.linspace(1.0, 30.0, 600)


def _chain(**kw) -> EchoChain:
    args = dict(bin_centres_m=BINS_M, absorption_db_per_m=0.03, tvg_db_per_decade=20.0, tvg_absorption_db_per_m=0.03,
                noise_floor_db=-60.0, speckle="rayleigh", k_shape=2.0, gain_db=-3.0, dynamic_range_db=50.0)
    args.update(kw)
    return EchoChain(**args)


def test_quantile_table_is_exponential_with_unit_mean():
    e = exponential_quantiles().astype(np.float64)
    assert e.mean() == pytest.approx(1.0, abs=1e-6)
    assert e.var() == pytest.approx(1.0, abs=2e-3)  # Exp(1): variance 1 (the tail above 11.8 is cut)
    # the table is the law: Kolmogorov-Smirnov distance of its levels to Exp(1) at the 2^-16 grid
    assert stats.kstest(e, "expon").statistic < 2e-4


def test_display_table_matches_the_exact_db_law_within_one_level():
    rng = np.random.default_rng(3)
    x = (10.0 ** rng.uniform(-12.0, 2.0, 200_000)).astype(np.float32)
    exact = to_uint8_db(x[None, :], np.ones(x.size, np.float32), -3.0, 50.0)[0].astype(int)
    lut = db_display_table(-3.0, 50.0)
    got = lut[x.view(np.uint32) >> np.uint32(23 - 9)].astype(int)
    diff = np.abs(got - exact)
    assert diff.max() <= 1
    assert np.mean(diff) < 0.01  # only values within 0.004 dB of a rounding boundary
    assert lut[0] == 0 and lut[np.float32(np.inf).view(np.uint32) >> np.uint32(14)] == 255


def test_realised_intensity_is_rayleigh_speckle_on_mean_plus_noise():
    chain = _chain(counter_speckle=True)
    assert chain.counter is not None
    mean = np.full((400, BINS_M.size), 2e-4, dtype=np.float32)
    mean[:, 300:] = 5e-3
    inten, u8 = chain.realise_display(mean, np.random.default_rng(0))
    ratio = inten / (mean + np.float32(chain.noise_power))
    for part in (ratio[:, :300], ratio[:, 300:]):
        x = part.ravel().astype(np.float64)
        assert x.mean() == pytest.approx(1.0, abs=0.01)
        assert x.var() == pytest.approx(1.0, abs=0.02)
        assert stats.kstest(x[::7], "expon").pvalue > 1e-3
    # neighbours along range and across lines uncorrelated (pairs share one hash: both halves)
    assert abs(np.corrcoef(ratio[:, :-1].ravel(), ratio[:, 1:].ravel())[0, 1]) < 0.01
    assert abs(np.corrcoef(ratio[:-1].ravel(), ratio[1:].ravel())[0, 1]) < 0.01
    # the display is the exact law of the realised intensity, within one grey level
    exact = chain.display(inten)
    assert np.abs(u8.astype(int) - exact.astype(int)).max() <= 1


def test_one_draw_per_frame_same_key_same_frame_new_key_new_speckle():
    chain = _chain(counter_speckle=True)
    mean = np.full((50, BINS_M.size), 1e-3, dtype=np.float32)
    rng_a, rng_b = np.random.default_rng(7), np.random.default_rng(7)
    a1, _ = chain.realise_display(mean, rng_a)
    b1, _ = chain.realise_display(mean, rng_b)
    np.testing.assert_array_equal(a1, b1)
    ref = np.random.default_rng(7)
    ref.integers(0, 1 << 64, dtype=np.uint64)
    assert rng_a.bit_generator.state == ref.bit_generator.state  # exactly one 64-bit draw
    a2, _ = chain.realise_display(mean, rng_a)
    assert abs(np.corrcoef(a1.ravel(), a2.ravel())[0, 1]) < 0.02


def test_stream_generator_and_other_chains_keep_the_sequential_path():
    mean = np.full((20, BINS_M.size), 1e-3, dtype=np.float32)
    stream = _chain(counter_speckle=False)
    assert stream.counter is None
    i1, u1 = stream.realise_display(mean, np.random.default_rng(1))
    i2 = stream.realise(mean, np.random.default_rng(1))
    np.testing.assert_array_equal(i1, i2)
    np.testing.assert_array_equal(u1, stream.display(i2))
    assert _chain(counter_speckle=True, speckle="none").counter is None
    # noise off: the expected image, no draw
    counter = _chain(counter_speckle=True)
    rng = np.random.default_rng(2)
    state = rng.bit_generator.state
    inten, _ = counter.realise_display(mean, rng, noise=False)
    np.testing.assert_array_equal(inten, mean + np.float32(counter.noise_power))
    assert rng.bit_generator.state == state


@pytest.mark.parametrize("k_shape", [1.3, 4.0])
def test_k_clutter_is_k_distributed_where_the_mask_says_and_rayleigh_elsewhere(k_shape):
    """K = Gamma(k)/k texture times Exp(1): mean 1, variance 1 + 2 / k on the clutter;
    Exp(1) off it (objects)."""
    chain = _chain(counter_speckle=True, speckle="k", k_shape=k_shape, noise_floor_db=-120.0)
    assert chain.counter is not None and chain.counter.texture_table is not None
    mean = np.full((600, BINS_M.size), 1e-3, dtype=np.float32)
    clutter = np.ones(mean.shape, dtype=bool)
    clutter[:, 400:] = False
    inten, u8 = chain.realise_display(mean, np.random.default_rng(3), clutter=clutter)
    ratio = (inten / (mean + np.float32(chain.noise_power))).astype(np.float64)
    on, off = ratio[:, :400].ravel(), ratio[:, 400:].ravel()
    assert on.mean() == pytest.approx(1.0, abs=0.01)
    assert on.var() == pytest.approx(1.0 + 2.0 / k_shape, rel=0.03)
    # its law: the product of the two exact laws (K-S against a large sample of it)
    ref = np.random.default_rng(4)
    k_sample = ref.gamma(k_shape, 1.0 / k_shape, 200_000) * ref.exponential(1.0, 200_000)
    assert stats.ks_2samp(on[::5], k_sample).statistic < 0.01
    assert off.mean() == pytest.approx(1.0, abs=0.01) and off.var() == pytest.approx(1.0, abs=0.03)
    assert np.abs(u8.astype(int) - chain.display(inten).astype(int)).max() <= 1
