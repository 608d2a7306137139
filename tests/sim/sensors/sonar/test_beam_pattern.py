"""Beam patterns against the uniform line aperture's closed forms."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import optimize

from sim.sensors.sonar.beam_pattern import apply_azimuth_pattern, azimuth_kernel, two_way_beam_power


@pytest.mark.parametrize("bw_deg", [0.25, 1.0, 14.0, 20.0])
def test_one_way_minus_3db_full_width_is_the_beamwidth(bw_deg):
    bw = np.deg2rad(bw_deg)
    one_way = lambda t: np.sqrt(two_way_beam_power(t, bw))  # noqa: E731
    half = optimize.brentq(lambda t: one_way(t) - 0.5, 1e-9, bw)
    assert 2.0 * half == pytest.approx(bw, rel=1e-4)
    assert 10 * np.log10(two_way_beam_power(bw / 2, bw)) == pytest.approx(-6.02, abs=0.01)


def test_matches_a_uniform_aperture_of_the_same_width():
    """A line aperture of length L at wavelength lambda: one-way power sinc^2(L sin t / lambda),
    -3 dB full width 0.8859 lambda / L (small angles). Sized for a 1 deg beam, the two patterns
    agree over the main lobe and first side lobes."""
    bw = np.deg2rad(1.0)
    l_over_lambda = 0.8859 / bw
    t = np.linspace(-3 * bw, 3 * bw, 601)
    aperture = np.sinc(l_over_lambda * np.sin(t)) ** 4
    np.testing.assert_allclose(two_way_beam_power(t, bw), aperture, atol=3e-5)


def test_first_side_lobe_two_way():
    bw = np.deg2rad(1.0)
    x = np.linspace(0.6 * bw, 3 * bw, 5001)
    p = two_way_beam_power(x, bw)
    interior = (p[1:-1] > p[:-2]) & (p[1:-1] > p[2:])
    # uniform aperture: first side lobe -13.26 dB one way, doubled two way
    assert 10 * np.log10(p[1:-1][interior][0]) == pytest.approx(-26.5, abs=0.1)


def test_azimuth_kernel_and_its_convolution():
    bw, spacing = np.deg2rad(1.0), np.deg2rad(0.18)
    k = azimuth_kernel(spacing, bw, 3.0)
    assert len(k) == 2 * int(np.ceil(3.0 / 0.18)) + 1
    assert k.sum() == pytest.approx(1.0) and np.argmax(k) == len(k) // 2 and np.allclose(k, k[::-1])
    lines = np.zeros((61, 5), np.float32)
    lines[30, 2] = 1.0
    out = apply_azimuth_pattern(lines, k)
    np.testing.assert_allclose(out[30 - len(k) // 2:30 + len(k) // 2 + 1, 2], k, rtol=1e-6)
    assert out.sum() == pytest.approx(1.0, rel=1e-6)  # energy kept
    single = np.ones((1, 7), np.float32)  # a single-beam sonar's one line
    np.testing.assert_allclose(apply_azimuth_pattern(single, k), single, rtol=1e-6)
    assert apply_azimuth_pattern(lines, np.ones(1, np.float32)) is lines
