"""Display mapping and the polar -> fan resampling against their geometry."""

from __future__ import annotations

import numpy as np

from autonomy.sonar_geometry import FanGeometry
from sim.sensors.sonar.display import FanRemap, to_uint8_db


def test_to_uint8_db_matches_the_formula(rng):
    img = (10.0 ** rng.uniform(-9, 2, (40, 60))).astype(np.float32)
    img[0, :5] = 0.0
    gain = (10.0 ** rng.uniform(-1, 3, 60)).astype(np.float32)
    got = to_uint8_db(img, gain, -10.0, 60.0)
    db = 10.0 * np.log10(np.maximum(img.astype(float) * gain, 1e-30)) - 10.0
    want = np.clip(np.round(255.0 * (db + 60.0) / 60.0), 0, 255)
    assert got.dtype == np.uint8
    assert np.abs(got.astype(int) - want).max() <= 1
    assert (got[0, :5] == 0).all() and (want == 255).any() and (want == 0).any()
    u8 = to_uint8_db(np.array([[1.0, 1e-5, 1e-2]], np.float32), np.ones(3, np.float32), 0.0, 50.0)
    assert u8.tolist() == [[255, 0, 153]]  # -20 dB of a 50 dB range


def _remap():
    fan = FanGeometry.fit(400, 300, 1.0, 20.0, np.deg2rad(90))
    az = np.deg2rad(-45) + (np.arange(100) + 0.5) * np.deg2rad(0.9)
    return fan, az, FanRemap(fan, az, 1.0, 0.1, 190)


def test_fan_remap_puts_a_cell_at_its_polar_position():
    fan, az, remap = _remap()
    polar = np.zeros((100, 190), np.uint8)
    polar[70, 120] = 255
    x, y = fan.polar_to_pixel(1.0 + 120.5 * 0.1, az[70])
    img = remap.image(polar)
    ys, xs = np.nonzero(img)
    assert np.hypot(np.average(xs, weights=img[ys, xs]) - x, np.average(ys, weights=img[ys, xs]) - y) < 1.0
    labels = remap.labels(polar.astype(np.int16) // 255 * 5 - 1, fill=-1)
    assert set(np.unique(labels).tolist()) <= {-1, 4}
    assert remap.image(np.full((100, 190), 9, np.uint8))[0, 0] == 0  # outside the fan


def test_box_covers_the_sector():
    fan, az, remap = _remap()
    b0, k0, b1, k1 = 40, 50, 60, 80
    x0, y0, x1, y1 = remap.box_px(b0, k0, b1, k1)
    # every point of the annular sector (beam edges, bin edges) projects inside the box
    a = np.linspace(az[b0] - np.deg2rad(0.45), az[b1] + np.deg2rad(0.45), 50)
    r = np.linspace(1.0 + k0 * 0.1, 1.0 + (k1 + 1) * 0.1, 20)
    xs, ys = fan.polar_to_pixel(r[:, None], a[None, :])
    assert xs.min() >= x0 - 1e-9 and xs.max() <= x1 + 1e-9 and ys.min() >= y0 - 1e-9 and ys.max() <= y1 + 1e-9
    # and the box is tight: its edges touch the sector
    assert min(abs(xs.min() - x0), abs(xs.max() - x1)) < 0.5 and abs(ys.min() - y0) < 0.5
