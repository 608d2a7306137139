"""Spreading, absorption and time-varied gain against the sonar equation."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from scenarios.config.fls import FlsConfig
from sim.sensors.analytic_caster import AnalyticCaster, AnalyticSphere
from sim.sensors.fls import FlsSensor
from sim.sensors.sonar.propagation import transmission_gain, tvg_gain


@pytest.mark.parametrize(("range_m", "alpha_db_per_m", "two_way_tl_db"), [
    (10.0, 0.0, 40.0),      # 2 x 20 log10(10)
    (100.0, 0.25, 130.0),   # 2 x (40 + 25)
    (30.0, 0.9, 2 * (20 * np.log10(30.0) + 27.0)),
])
def test_point_target_two_way_loss(range_m, alpha_db_per_m, two_way_tl_db):
    """A point target is hit by rays in proportion to 1/r^2; with the per-ray factor that gives
    the sonar equation's two-way transmission loss 2 (20 log r + alpha r)."""
    rays_on_target = range_m ** -2
    got_db = 10 * np.log10(transmission_gain(range_m, alpha_db_per_m) * rays_on_target)
    assert got_db == pytest.approx(-two_way_tl_db, abs=1e-9)
    # TVG of 40 log r + 2 alpha r restores it
    assert 10 * np.log10(tvg_gain(range_m, 40.0, alpha_db_per_m)) == pytest.approx(two_way_tl_db, abs=1e-9)


@pytest.mark.parametrize("alpha_db_per_m", [0.0, 0.25])
def test_sphere_echo_falls_with_range_as_the_sonar_equation(alpha_db_per_m):
    """A sphere's echo level (target strength fixed) falls 40 log10(r2 / r1) + 2 alpha (r2 - r1)
    dB from r1 to r2: total noise-free echo power of the rendered sphere at 6 m and 12 m."""
    cfg = FlsConfig(tilt_deg=0.0, range_window_m=(1.0, 20.0), elevation_rays=400, absorption_db_per_m=alpha_db_per_m)
    s = FlsSensor(cfg, rng=np.random.default_rng(0))
    level = []
    for r in (6.0, 12.0):
        c = np.array([r, 0.0, 0.0])
        caster = AnalyticCaster(None, spheres=(AnalyticSphere(c, 0.3, 0),))
        out = s.render(0.0, np.zeros(3), np.eye(3), caster, [SimpleNamespace(id=0, name="s", class_name="opi", is_target=True, centroid_ned=c)], noise=False)
        level.append(10 * np.log10(out.mean_intensity.astype(float).sum()))
    want = 40 * np.log10(2.0) + 2 * alpha_db_per_m * 6.0
    assert level[0] - level[1] == pytest.approx(want, abs=0.3)
