"""Small objects between the FLS's elevation rays: echo, label and range against an
independent ray-sphere oracle (closed-form intersections on a fine grid of directions)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

from scenarios import load_scenario
from sim.sensors.analytic_caster import AnalyticCaster, AnalyticSphere
from sim.sensors.fls import FlsSensor

SEABED_DEPTH_M = 10.0


@dataclass(frozen=True)
class _Obj:
    id: int
    name: str
    class_name: str
    is_target: bool
    centroid_ned: np.ndarray


def _oracle(origin: np.ndarray, tilt_rad: float, centre: np.ndarray, radius: float, fov_rad: float,
            vbw_rad: float, near_m: float, far_m: float) -> tuple[bool, float, bool]:
    """(seen, nearest seen range, whole sphere inside the aperture) for a level sonar heading
    north, tilted down by ``tilt_rad``, above a flat seabed at SEABED_DEPTH_M.

    Directions: a 0.004 deg grid of (azimuth, elevation) in the sonar frame over the sphere's
    angular box, clipped to the aperture; each ray is intersected with the sphere and the
    seabed plane in closed form; a ray sees the sphere where its sphere hit is the nearer one
    and lies in the range window."""
    v = centre - origin
    dist = np.linalg.norm(v)
    beta = np.arcsin(radius / dist)
    ct, st = np.cos(tilt_rad), np.sin(tilt_rad)
    # sonar frame -> NED for the level, north-heading vehicle: pitch the boresight down by tilt
    R_ns = np.array([[ct, 0.0, -st], [0.0, 1.0, 0.0], [st, 0.0, ct]])
    u = R_ns.T @ v / dist
    az_c, el_c = np.arctan2(u[1], u[0]), np.arcsin(u[2])
    step = np.deg2rad(0.004)
    az = np.arange(az_c - beta / np.cos(el_c) - step, az_c + beta / np.cos(el_c) + step, step)
    el = np.arange(el_c - beta - step, el_c + beta + step, step)
    az = az[np.abs(az) <= fov_rad / 2]
    el = el[np.abs(el) <= vbw_rad / 2]
    inside = abs(el_c) + beta <= vbw_rad / 2 and abs(az_c) + beta / np.cos(el_c) <= fov_rad / 2
    if az.size == 0 or el.size == 0:
        return False, np.inf, inside
    A, E = np.meshgrid(az, el, indexing="ij")
    d_s = np.stack([np.cos(A) * np.cos(E), np.sin(A) * np.cos(E), np.sin(E)], axis=-1).reshape(-1, 3)
    d = d_s @ R_ns.T
    oc = origin - centre
    b = d @ oc
    disc = b * b - (oc @ oc - radius ** 2)
    t_sphere = np.where(disc >= 0.0, -b - np.sqrt(np.maximum(disc, 0.0)), np.inf)
    with np.errstate(divide="ignore"):
        t_bed = np.where(d[:, 2] > 0.0, (SEABED_DEPTH_M - origin[2]) / d[:, 2], np.inf)
    seen = (t_sphere > 0.0) & (t_sphere <= t_bed) & (t_sphere >= near_m) & (t_sphere <= far_m)
    if not seen.any():
        return False, np.inf, inside
    return True, float(t_sphere[seen].min()), inside


SIZES_M = [0.2, 0.3, 0.5, 1.0]
RANGES_M = [5.0, 8.0, 12.0, 17.0, 19.0, 22.0, 25.0, 28.0, 30.0]


@pytest.fixture(scope="module")
def shipped_fls():
    cfg = load_scenario("cssn_lawnmower").sensors.fls
    return FlsSensor(cfg, rng=np.random.default_rng(0))


@pytest.mark.parametrize("altitude_m", [2.0, 4.0])
@pytest.mark.parametrize("azimuth_deg", [0.0, 23.0])
def test_spheres_on_the_seabed_echo_where_geometry_says(shipped_fls, altitude_m, azimuth_deg):
    """Spheres of 0.2-1 m diameter resting on a flat seabed at 5-30 m: each whose surface the
    oracle sees inside the aperture and window echoes and is labelled visible, the others are
    not; a sphere wholly inside the aperture peaks within one range bin of its nearest range."""
    s = shipped_fls
    g = s.geometry
    tilt = s.tilt_down_rad
    origin = np.array([0.0, 0.0, SEABED_DEPTH_M - altitude_m])
    dr = g.range_resolution_m
    n_seen = n_peak = 0
    failures = []
    for size in SIZES_M:
        radius = size / 2
        for rng_m in RANGES_M:
            a = np.deg2rad(azimuth_deg)
            centre = np.array([rng_m * np.cos(a), rng_m * np.sin(a), SEABED_DEPTH_M - radius])
            seen, r_near, inside = _oracle(origin, tilt, centre, radius, g.fov_rad, g.vertical_beamwidth_rad,
                                           g.window_near_m, g.window_far_m)
            caster = AnalyticCaster(SEABED_DEPTH_M, 0.0, spheres=(AnalyticSphere(centre, radius, 7),))
            out = s.render(0.0, origin, np.eye(3), caster, [_Obj(7, "s", "opi", True, centre)], noise=False)
            truth = out.truth.object(7)
            labelled = bool((out.truth.mask_polar == 7).any())
            echo = float(out.mean_intensity.max()) > 0.0
            case = f"d={size} r={rng_m}"
            if (truth.visible, labelled, echo) != (seen, seen, seen):
                failures.append(f"{case}: oracle seen={seen}, visible={truth.visible}, labelled={labelled}, "
                                f"echo={echo}")
                continue
            n_seen += seen
            if seen and inside:
                n_peak += 1
                peak_bin = int(np.unravel_index(np.argmax(out.mean_intensity), out.mean_intensity.shape)[1])
                want_bin = int(np.floor((r_near - g.window_near_m) / dr))
                if abs(peak_bin - want_bin) > 1:
                    failures.append(f"{case}: peak bin {peak_bin}, nearest range bin {want_bin}")
    assert not failures, "\n".join(failures)
    assert n_seen >= 8 and n_peak >= 4  # the grid covers seen and peaked cases


def test_the_issue_cases(shipped_fls):
    """A 0.2 m sphere on a flat seabed 19 m ahead, sonar 2 m above the bed, 15 deg tilt."""
    s = shipped_fls
    origin = np.array([0.0, 0.0, SEABED_DEPTH_M - 2.0])
    for x in (17.0, 19.0):
        centre = np.array([x, 0.0, SEABED_DEPTH_M - 0.1])
        caster = AnalyticCaster(SEABED_DEPTH_M, 0.3, spheres=(AnalyticSphere(centre, 0.1, 3),))
        t = s.render(0.0, origin, np.eye(3), caster, [_Obj(3, "s", "opi", True, centre)], noise=False).truth
        assert t.object(3).visible and t.object(3).bbox_xyxy is not None
