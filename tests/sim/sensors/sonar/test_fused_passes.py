"""The compiled passes give bit for bit what the numpy / OpenCV chains they replace give."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from autonomy.sonar_geometry import FanGeometry
from sim.sensors.sonar.display import FanRemap, to_uint8_db
from sim.sensors.sonar.speckle import add_speckle_and_noise, complement_uniform_f32


@pytest.mark.parametrize("shape", [(7, 5), (3, 4, 5), (1,), (2, 3), (301, 257), (722, 1142)])
@pytest.mark.parametrize("spare_word", [False, True])
def test_complement_uniform_is_one_minus_generator_random(shape, spare_word):
    a, b = np.random.default_rng(11), np.random.default_rng(11)
    if spare_word:  # leave numpy's spare uint32 half buffered in both generators
        a.random(3, dtype=np.float32)
        b.random(3, dtype=np.float32)
    for _ in range(3):
        got = complement_uniform_f32(a, shape)
        want = np.float32(1.0) - b.random(shape, dtype=np.float32)
        assert got.dtype == np.float32 and got.shape == shape
        assert np.array_equal(got, want)
        assert a.bit_generator.state == b.bit_generator.state  # the next draws match too
    assert np.array_equal(a.random(5), b.random(5)) and np.array_equal(a.integers(0, 99, 5), b.integers(0, 99, 5))


def test_other_bit_generators_draw_through_generator_random():
    a, b = np.random.Generator(np.random.Philox(3)), np.random.Generator(np.random.Philox(3))
    assert np.array_equal(complement_uniform_f32(a, (4, 6)), np.float32(1.0) - b.random((4, 6), dtype=np.float32))


def _speckle_reference(mean, rng, kind, noise_power, k_shape, clutter):
    """The earlier numpy chain: (mean [* texture] + noise) * -log(1 - U)."""
    if kind == "k":
        tex = rng.standard_gamma(k_shape, mean.shape, dtype=np.float32)
        tex *= np.float32(1.0 / k_shape)
        np.copyto(tex, np.float32(1.0), where=~clutter)
        out = np.multiply(mean, tex, out=tex)
        out += np.float32(noise_power)
    else:
        out = np.add(mean, np.float32(noise_power), dtype=np.float32)
    u = rng.random(mean.shape, dtype=np.float32)
    e = cv2.log(np.float32(1.0) - u)
    return out * -e


@pytest.mark.parametrize("kind", ["rayleigh", "k"])
def test_speckle_matches_the_numpy_chain(kind):
    g = np.random.default_rng(2)
    mean = (g.random((64, 301), dtype=np.float32) ** 6 * 1e-3).astype(np.float32)
    clutter = g.random(mean.shape) < 0.5
    a, b = np.random.default_rng(9), np.random.default_rng(9)
    for _ in range(2):
        got = add_speckle_and_noise(mean, a, kind, 1e-6, k_shape=1.7, clutter=clutter)
        assert np.array_equal(got, _speckle_reference(mean, b, kind, 1e-6, 1.7, clutter))


def test_display_matches_multiply_floor_log_chain():
    g = np.random.default_rng(4)
    x = (g.random((40, 257)) ** 8 * 10.0).astype(np.float32)
    x[0, :5] = 0.0
    gain = (g.random(257) * 1e4).astype(np.float32)
    y = np.maximum(np.multiply(x, gain[None, :], dtype=np.float32), np.float32(1e-30))
    db = cv2.log(y)
    scale = 255.0 * 10.0 / np.log(10.0) / 60.0
    want = cv2.addWeighted(db, scale, db, 0.0, 255.0 * (-5.0 + 60.0) / 60.0, dtype=cv2.CV_8U)
    assert np.array_equal(to_uint8_db(x, gain, -5.0, 60.0), want)


@pytest.mark.parametrize("size, window, n_beams, n_bins", [((894, 477), (1.0, 30.0), 722, 1142),
                                                             ((401, 300), (3.0, 12.0), 96, 250)])
def test_fan_image_is_cv2_remap(size, window, n_beams, n_bins):
    fov = np.deg2rad(130.0)
    fan = FanGeometry.fit(size[0], size[1], window[0], window[1], fov)
    beams = (np.arange(n_beams) + 0.5) / n_beams * fov - 0.5 * fov
    rm = FanRemap(fan, beams, window[0], (window[1] - window[0]) / n_bins, n_bins)
    g = np.random.default_rng(0)
    for polar in (g.integers(0, 256, (n_beams, n_bins), dtype=np.uint8),
                  np.full((n_beams, n_bins), 255, np.uint8),
                  (g.random((n_beams, n_bins)) ** 6 * 255).astype(np.uint8)):
        want = cv2.remap(polar, rm._fixed[0], rm._fixed[1], cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT,
                         borderValue=0)
        assert np.array_equal(rm.image(polar), want)
    as_float = g.random((n_beams, n_bins), dtype=np.float32)  # other types: cv2.remap itself
    assert rm.image(as_float).dtype == np.float32


def _spread_reference(n_rows, n_bins, row, u_a, u_b, energy, dtype):
    """The earlier numpy chain: one ``bincount`` of kinks, ``cv2.integral`` row differences."""
    lo, hi = np.minimum(u_a, u_b), np.maximum(u_a, u_b)
    length = hi - lo
    point = length < 1e-9
    stride = n_bins + 2
    kp = np.floor(lo[point])
    okp = (kp >= 0) & (kp < n_bins)
    base_p = row[point][okp] * stride + kp[okp].astype(np.intp)
    e_p = energy[point][okp]
    seg = ~point & (hi > 0.0) & (lo < n_bins)
    r = row[seg]
    density = energy[seg] / length[seg]
    pos = np.concatenate([np.clip(lo[seg], 0.0, n_bins), np.clip(hi[seg], 0.0, n_bins)])
    w = np.concatenate([density, -density])
    fl = np.floor(pos)
    base = np.concatenate([r, r]) * stride + fl.astype(np.intp)
    off = w * (1.0 - (pos - fl))
    idx = np.concatenate([base + 1, base, base + 1, base_p, base_p + 1])
    weights = np.concatenate([w, off, -off, e_p, -e_p])
    acc = np.bincount(idx, weights=weights, minlength=n_rows * stride).reshape(n_rows, stride)
    integral = cv2.integral(acc, sdepth=cv2.CV_64F)
    out = np.subtract(integral[1:, 1:n_bins + 1], integral[:-1, 1:n_bins + 1], dtype=dtype)
    return np.maximum(out, 0, out=out)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_spread_segments_matches_the_bincount_integral_chain(dtype):
    from sim.sensors.sonar.echo_lines import spread_segments

    g = np.random.default_rng(8)
    n_rows, n_bins, m = 37, 211, 4000
    row = g.integers(0, n_rows, m)
    u_a = g.uniform(-20.0, n_bins + 20.0, m)
    u_b = u_a + g.normal(0.0, 15.0, m)
    u_b[::9] = u_a[::9]  # points
    u_a[::13] = np.floor(u_a[::13])  # ends on bin edges
    energy = g.random(m) ** 3
    got = spread_segments(n_rows, n_bins, row, u_a, u_b, energy, dtype=dtype)
    want = _spread_reference(n_rows, n_bins, row, u_a, u_b, energy, dtype)
    assert got.dtype == dtype and np.array_equal(got, want)


def test_fan_labels_are_cv2_nearest_remap():
    fov = np.deg2rad(120.0)
    fan = FanGeometry.fit(500, 300, 2.0, 40.0, fov)
    beams = (np.arange(256) + 0.5) / 256 * fov - 0.5 * fov
    rm = FanRemap(fan, beams, 2.0, 38.0 / 900, 900)
    labels = np.random.default_rng(1).integers(-1, 5, (256, 900)).astype(np.int16)
    for fill in (-1, 7):
        want = cv2.remap(labels, rm._nearest[0], None, cv2.INTER_NEAREST, borderMode=cv2.BORDER_CONSTANT,
                         borderValue=fill)
        got = rm.labels(labels, fill)
        assert got.dtype == np.int16 and np.array_equal(got, want)


def test_same_surface_matches_the_einsum_chain():
    """The compiled test sums its dot products as ``np.einsum`` does (bit for bit)."""
    from sim.sensors.sonar.fused_passes import kernels
    from sim.sensors.sonar.ray_fan import SURFACE_CHORD_SIN, same_surface

    g = np.random.default_rng(3)
    a, b = g.normal(size=(200000, 3)) * 7.0, g.normal(size=(200000, 3))
    dots = np.array([kernels().row_dot3(a, i, b, i) for i in range(2000)])
    assert np.array_equal(dots, np.einsum("ij,ij->i", a[:2000], b[:2000]))

    n = 50000
    unit = lambda x: x / np.linalg.norm(x, axis=1, keepdims=True)  # noqa: E731
    v_a, v_b = unit(g.normal(size=(n, 3))), unit(g.normal(size=(n, 3)))
    n_a = unit(g.normal(size=(n, 3)))
    n_b = np.where(g.random((n, 1)) < 0.5, n_a, unit(g.normal(size=(n, 3))))
    d_a, d_b = g.uniform(1.0, 30.0, n), g.uniform(1.0, 30.0, n)
    d_a[::17], d_b[::23] = np.inf, np.inf
    o_a = g.integers(-2, 2, n)
    o_b = np.where(g.random(n) < 0.8, o_a, g.integers(-2, 2, n))
    # the earlier numpy chain
    both = np.isfinite(d_a) & np.isfinite(d_b) & (o_a == o_b)
    chord = np.where(both, d_b, 0.0)[:, None] * v_b
    chord -= np.where(both, d_a, 0.0)[:, None] * v_a
    tol = SURFACE_CHORD_SIN * np.sqrt(np.einsum("ij,ij->i", chord, chord)) + 1e-9
    want = both & (np.abs(np.einsum("ij,ij->i", chord, n_a)) <= tol) & (np.abs(np.einsum("ij,ij->i", chord, n_b)) <= tol)
    got = same_surface(d_a, n_a, o_a, v_a, d_b, n_b, o_b, v_b)
    assert 0.05 < want.mean() < 0.95 and np.array_equal(got, want)
