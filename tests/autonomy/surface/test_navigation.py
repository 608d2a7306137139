"""The buoy's GNSS filter on synthetic tracks drawn apart from its own model."""

from __future__ import annotations

import math

import numpy as np

from autonomy.messages import GpsMsg
from autonomy.surface.config import SurfaceNavigationConfig
from autonomy.surface.navigation import GnssDisturbanceFilter

MASS, DL, DQ = (40.0, 59.7), (8.0, 20.0), (27.7, 86.7)


def _run(truth_pos, heading_rad, noise_m, seed, duration_s=300.0, thrust_body=(0.0, 0.0)):
    cfg = SurfaceNavigationConfig(gnss_noise_m=noise_m)
    f = GnssDisturbanceFilter(cfg, MASS, DL, DQ, initial_speed_sigma_mps=0.6)
    rng = np.random.default_rng(seed)
    out = []
    for k in range(int(duration_s * 10) + 1):
        t = 0.1 * k
        f.set_input(thrust_body, heading_rad)
        fixes = []
        if k % 10 == 0:
            fixes = [GpsMsg(t_s=t, pos_ne_m=truth_pos(t) + rng.normal(0.0, noise_m, 2), valid=True)]
        f.update(fixes)
        f.predict(t)
        out.append((t, *f.pos_ne_m, *f.vel_ne_mps, *f.disturbance_ne_mps2))
    return np.array(out)


def test_drifting_buoy_velocity_and_disturbance_are_estimated():
    """No thrust, drifting with a 0.2 m/s current (north-east): over ground the buoy moves at
    the current, and the disturbance that keeps it moving against the (ground-relative)
    drag model is K v = (d_l + d_q |v_body|) v / m per body axis."""
    v = np.array([0.2, 0.1])
    heading = 0.4
    est = _run(lambda t: np.array([1.0, 2.0]) + v * t, heading, 0.7, seed=3)
    late = est[est[:, 0] > 150.0]
    c, s = math.cos(heading), math.sin(heading)
    R = np.array([[c, -s], [s, c]])
    vb = R.T @ v
    b_expected = R @ ((np.array(DL) + np.array(DQ) * np.abs(vb)) * vb / np.array(MASS))
    np.testing.assert_allclose(late[:, 3:5].mean(axis=0), v, atol=0.02)
    np.testing.assert_allclose(late[:, 5:7].mean(axis=0), b_expected, atol=0.01)
    pos_err = np.hypot(*(late[:, 1:3] - (np.array([1.0, 2.0]) + v * late[:, :1])).T)
    assert np.sqrt(np.mean(pos_err ** 2)) < 0.5 * 0.7 * math.sqrt(2)  # well under the raw fixes' 0.99 m rms


def test_invalid_fixes_are_skipped_and_the_estimate_times_out():
    cfg = SurfaceNavigationConfig(max_fix_gap_s=5.0)
    f = GnssDisturbanceFilter(cfg, MASS, DL, DQ)
    assert f.update([GpsMsg(0.0, np.full(2, np.nan), False)]) == 0 and not f.initialised
    assert f.update([GpsMsg(1.0, np.array([3.0, 4.0]), True)]) == 1
    np.testing.assert_allclose(f.pos_ne_m, [3.0, 4.0])
    assert f.valid(5.9) and not f.valid(6.1)
