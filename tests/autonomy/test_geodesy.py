"""NED <-> WGS-84 (autonomy.geodesy) against a closed-form ECEF derivation and against PROJ."""

from __future__ import annotations

import numpy as np
import pytest
from pydantic import ValidationError

from autonomy.geodesy import (
    GeodeticOrigin,
    geodetic_to_ned,
    lat_lon_depth_to_ned,
    ned_to_geodetic,
    ned_to_lat_lon_depth,
)

A_M = 6378137.0  # WGS-84 semi-major axis
F = 1.0 / 298.257223563  # WGS-84 flattening
E2 = F * (2.0 - F)
ORIGIN = GeodeticOrigin()


def _ecef(lat_deg, lon_deg, h_m):
    """Closed-form geodetic -> ECEF on the WGS-84 ellipsoid (prime-vertical radius N)."""
    lat, lon = np.radians(lat_deg), np.radians(lon_deg)
    n = A_M / np.sqrt(1.0 - E2 * np.sin(lat) ** 2)
    return np.stack([(n + h_m) * np.cos(lat) * np.cos(lon), (n + h_m) * np.cos(lat) * np.sin(lon),
                     (n * (1.0 - E2) + h_m) * np.sin(lat)], axis=-1)


def _ned_closed_form(lat_lon_h, origin):
    """NED of geodetic points: ECEF difference rotated into the origin's north, east, down."""
    lat0, lon0 = np.radians(origin.lat_deg), np.radians(origin.lon_deg)
    r_ne = np.array([
        [-np.sin(lat0) * np.cos(lon0), -np.sin(lat0) * np.sin(lon0), np.cos(lat0)],
        [-np.sin(lon0), np.cos(lon0), 0.0],
        [-np.cos(lat0) * np.cos(lon0), -np.cos(lat0) * np.sin(lon0), -np.sin(lat0)],
    ])
    g = np.asarray(lat_lon_h)
    d = _ecef(g[..., 0], g[..., 1], g[..., 2]) - _ecef(origin.lat_deg, origin.lon_deg, origin.height_m)
    return d @ r_ne.T


def _points_within_10km(n=400, seed=3):
    rng = np.random.default_rng(seed)
    r, a = 10_000.0 * np.sqrt(rng.random(n)), 2 * np.pi * rng.random(n)
    return np.column_stack([r * np.cos(a), r * np.sin(a), rng.uniform(-5.0, 200.0, n)])


@pytest.mark.parametrize("origin", [ORIGIN, GeodeticOrigin(lat_deg=-70.0, lon_deg=-179.99, height_m=30.0)])
def test_round_trip_ned_wgs84_ned_within_1mm_over_10km(origin):
    ned = _points_within_10km()
    back = geodetic_to_ned(ned_to_geodetic(ned, origin), origin)
    assert np.max(np.abs(back - ned)) < 1e-3
    back_depth = lat_lon_depth_to_ned(ned_to_lat_lon_depth(ned, origin), origin)
    assert np.max(np.abs(back_depth - ned)) < 1e-3


def test_inverse_agrees_with_closed_form_forward():
    """pymap3d's NED -> geodetic, pushed back through an independent closed-form geodetic -> ECEF
    -> NED, lands on the input: checks the inverse without trusting pymap3d's own forward."""
    ned = _points_within_10km(seed=8)
    g = ned_to_geodetic(ned, ORIGIN)
    assert np.max(np.abs(_ned_closed_form(g, ORIGIN) - ned)) < 1e-6
    assert np.max(np.abs(geodetic_to_ned(g, ORIGIN) - _ned_closed_form(g, ORIGIN))) < 1e-6


def test_known_point_against_proj_topocentric():
    pyproj = pytest.importorskip("pyproj")
    o = ORIGIN
    topo = pyproj.Transformer.from_pipeline(
        f"+proj=pipeline +step +proj=cart +ellps=WGS84 "
        f"+step +proj=topocentric +ellps=WGS84 +lat_0={o.lat_deg} +lon_0={o.lon_deg} +h_0={o.height_m}")
    ned = np.array([[1000.0, 2000.0, 10.0], [-7000.0, 6500.0, 150.0], [0.0, 0.0, 4.0]])
    g = ned_to_geodetic(ned, o)
    east, north, up = topo.transform(g[:, 1], g[:, 0], g[:, 2])
    np.testing.assert_allclose(np.column_stack([north, east, -np.asarray(up)]), ned, atol=1e-3)
    # one point written out: 1 km north, 2 km east, 10 m down of the CSSN origin
    assert g[0, 0] == pytest.approx(o.lat_deg + 1000.0 / 111_110.0, abs=2e-4)  # ~111.1 km per degree at 44 N
    assert g[0, 2] == pytest.approx(-10.0 + (1000.0**2 + 2000.0**2) / (2 * 6.37e6), abs=2e-3)  # curvature drop


def test_depth_is_height_below_origin_and_shapes_are_kept():
    o = GeodeticOrigin(lat_deg=44.0, lon_deg=9.0, height_m=48.0)
    lld = ned_to_lat_lon_depth([0.0, 0.0, 12.5], o)
    assert lld.shape == (3,)
    np.testing.assert_allclose(lld, [44.0, 9.0, 12.5], atol=1e-9)
    assert ned_to_geodetic(np.zeros((2, 5, 3)), o).shape == (2, 5, 3)
    with pytest.raises(ValueError, match=r"pos_ned must have shape \(\.\.\., 3\)"):
        ned_to_geodetic([1.0, 2.0], o)


def test_origin_limits_and_scenario_default():
    with pytest.raises(ValidationError):
        GeodeticOrigin(lat_deg=90.0)
    with pytest.raises(ValidationError):
        GeodeticOrigin(lon_deg=181.0)
    from scenarios.config.world import WorldConfig

    assert WorldConfig().origin == ORIGIN
    assert WorldConfig.model_validate({"origin": {"lat_deg": 43.5}}).origin.lon_deg == ORIGIN.lon_deg
