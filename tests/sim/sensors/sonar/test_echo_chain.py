"""The echo chain on one line (single beam), two lines (side-scan) and a fan."""

from __future__ import annotations

import numpy as np
import pytest

from sim.sensors.sonar.beam_pattern import azimuth_kernel
from sim.sensors.sonar.echo_chain import EchoChain

DR = 0.05
BINS_M = 1.0 + (np.arange(600) + 0.5) * DR


def chain(alpha: float = 0.3, **kw) -> EchoChain:
    args = dict(absorption_db_per_m=alpha, tvg_db_per_decade=20.0, tvg_absorption_db_per_m=alpha,
                noise_floor_db=-90.0, speckle="rayleigh", k_shape=2.0, gain_db=-20.0, dynamic_range_db=50.0)
    args.update(kw)
    return EchoChain(BINS_M, **args)


@pytest.mark.parametrize("n_lines", [1, 2])
def test_tvg_flattens_an_area_echo(n_lines):
    """Unit energy per bin, weighted r^2 as echo segments carry it, is received at
    r^-2 10^(-2 alpha r / 10); TVG of 20 log r + 2 alpha r makes it range-independent:
    0 dB, shown at gain -20 dB on a 50 dB scale as 255 * 30 / 50 = 153 everywhere."""
    c = chain()
    energy = np.tile((BINS_M ** 2).astype(np.float32), (n_lines, 1))
    mean = c.mean_intensity(energy)
    assert mean.shape == (n_lines, 600)
    np.testing.assert_allclose(mean[0], BINS_M ** -2 * 10 ** (-0.2 * 0.3 * BINS_M), rtol=1e-5)
    shown = c.display(c.realise(mean, np.random.default_rng(0), noise=False))
    assert (shown == 153).all()


def test_without_tvg_absorption_the_far_end_darkens():
    c = chain(tvg_absorption_db_per_m=0.0)
    mean = c.mean_intensity(np.tile((BINS_M ** 2).astype(np.float32), (1, 1)))
    shown = c.display(c.realise(mean, np.random.default_rng(0), noise=False)).astype(int)[0]
    # 2 alpha r uncompensated: 0.6 dB/m, 255/50 counts per dB
    assert shown[0] - shown[-1] == pytest.approx(0.6 * (BINS_M[-1] - BINS_M[0]) * 255 / 50, abs=1.0)


def test_noise_is_seeded_and_off_means_mean_plus_floor():
    c = chain(azimuth_kernel=azimuth_kernel(np.deg2rad(0.5), np.deg2rad(1.0), 3.0))
    mean = c.mean_intensity(np.ones((40, 600), np.float32))
    a = c.realise(mean, np.random.default_rng(5))
    b = c.realise(mean, np.random.default_rng(5))
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c.realise(mean, np.random.default_rng(6)))
    np.testing.assert_allclose(c.realise(mean, None, noise=False), mean + 1e-9, rtol=1e-6)


def test_bad_axis_rejected():
    with pytest.raises(ValueError, match="range bin"):
        EchoChain([], 0.1, 20.0, 0.1, -90.0, "none", 2.0, 0.0, 50.0)
    with pytest.raises(ValueError, match="dynamic_range_db"):
        EchoChain(BINS_M, 0.1, 20.0, 0.1, -90.0, "none", 2.0, 0.0, 0.0)
