"""FLS renderer checked against scene geometry (analytic caster, closed-form expectations)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

from autonomy.frames import rot_from_euler
from scenarios.config.fls import FlsConfig
from sim.sensors.analytic_caster import AnalyticBox, AnalyticCaster, AnalyticSphere
from sim.sensors.fls import FlsSensor


@dataclass(frozen=True)
class Obj:
    id: int
    name: str
    class_name: str
    is_target: bool
    centroid_ned: np.ndarray


def sensor(tilt_deg: float = 0.0, window=(1.0, 12.0), **kw) -> FlsSensor:
    cfg = FlsConfig(preset="m900_130", tilt_deg=tilt_deg, range_window_m=window, **kw)
    return FlsSensor(cfg, rng=np.random.default_rng(7))


def beam_of(s: FlsSensor, az_rad: float) -> int:
    return int(np.argmin(np.abs(s.geometry.beam_azimuths_rad() - az_rad)))


def bin_of(s: FlsSensor, r_m: float) -> int:
    g = s.geometry
    return int(np.floor((r_m - g.window_near_m) / g.range_resolution_m))


@pytest.mark.parametrize("az_deg", [-40.0, 0.0, 17.3])
def test_sphere_peak_in_expected_beam_and_bin(az_deg):
    s = sensor()
    R, rad = 9.0, 0.3
    a = np.deg2rad(az_deg)
    c = R * np.array([np.cos(a), np.sin(a), 0.0])
    caster = AnalyticCaster(None, spheres=(AnalyticSphere(c, rad, 0),))
    out = s.render(0.0, np.zeros(3), np.eye(3), caster, [Obj(0, "s", "opi", True, c)], noise=False)
    beam, k = np.unravel_index(np.argmax(out.mean_intensity), out.mean_intensity.shape)
    assert abs(beam - beam_of(s, a)) <= 1
    assert abs(k - bin_of(s, R - rad)) <= 1  # front surface, normal incidence
    # fan image: brightest pixels sit at the same (range, azimuth), within a bin / a pixel
    fan = out.frame.fan
    ys, xs = np.nonzero(fan == fan.max())
    r_px, a_px = out.frame.geometry.pixel_to_polar(xs.mean(), ys.mean())
    tol_r = s.geometry.range_resolution_m + out.frame.geometry.m_per_px
    assert abs(r_px - (R - rad)) <= tol_r
    assert abs(a_px - a) <= s.geometry.beam_spacing_rad + out.frame.geometry.m_per_px / R
    # the same peak in the 8-bit polar image
    assert out.frame.polar[beam, k] == out.frame.polar.max()


def shadow_run(profile: np.ndarray, obj_bins: np.ndarray) -> tuple[int, int]:
    """(first dark bin, first lit bin) of the dark run right after an object's last return."""
    last = int(obj_bins.max())
    lit = profile > 1e-3 * np.median(profile[profile > 0])
    after = np.flatnonzero(lit[last + 1:])
    start = last + 1
    while start < len(profile) and lit[start]:
        start += 1
    end = start + int(np.flatnonzero(lit[start:])[0])
    assert after.size and end > start
    return start, end


@pytest.mark.parametrize("x_c, h_obj", [(10.0, 0.5), (13.0, 0.8)])
def test_box_shadow_length(x_c, h_obj):
    """A box on a flat seabed: the shadow ends where the ray over its back top edge meets the
    seabed, i.e. a ground length h * x / (H - h) behind the back edge (within two bins)."""
    H, depth = 3.0, 10.0
    s = sensor(tilt_deg=15.0, window=(1.0, 25.0))
    half = np.array([0.3, 1.5, h_obj / 2])
    box = AnalyticBox(np.array([x_c, 0.0, depth - h_obj / 2]), half, 0)
    caster = AnalyticCaster(depth, boxes=(box,))
    out = s.render(0.0, np.array([0.0, 0.0, depth - H]), np.eye(3), caster, [], noise=False)
    b = beam_of(s, 0.0)
    profile = out.mean_intensity[b].astype(float)
    obj_bins = np.flatnonzero(out.truth.mask_polar[b] == 0)
    k_start, k_end = shadow_run(profile, obj_bins)
    dr, near = s.geometry.range_resolution_m, s.geometry.window_near_m
    x_b = x_c + half[0]
    r_top_back = np.hypot(x_b, H - h_obj)
    x_s = x_b * H / (H - h_obj)
    r_seabed = np.hypot(x_s, H)
    assert abs(near + k_start * dr - r_top_back) <= 2 * dr
    assert abs(near + k_end * dr - r_seabed) <= 2 * dr
    # as a ground length behind the back edge: h r / (H - h)
    r_end = near + k_end * dr
    ground = np.sqrt(r_end ** 2 - H ** 2) - x_b
    assert abs(ground - h_obj * x_b / (H - h_obj)) <= 2 * dr * r_end / np.sqrt(r_end ** 2 - H ** 2)


def test_object_above_seabed_appears_at_slant_range():
    H, depth, x, z_above = 6.0, 10.0, 6.0, 1.0
    s = sensor(tilt_deg=35.0, window=(1.0, 20.0))
    c = np.array([x, 0.0, depth - z_above])
    rad = 0.25
    caster = AnalyticCaster(depth, spheres=(AnalyticSphere(c, rad, 0),))
    origin = np.array([0.0, 0.0, depth - H])
    out = s.render(0.0, origin, np.eye(3), caster, [Obj(0, "s", "opi", True, c)], noise=False)
    b = beam_of(s, 0.0)
    k_peak = int(np.argmax(np.where(out.truth.mask_polar[b] == 0, out.mean_intensity[b], 0.0)))
    slant = np.linalg.norm(c - origin) - rad
    assert abs(k_peak - bin_of(s, slant)) <= 1
    assert abs(k_peak - bin_of(s, x - rad)) > 40  # not at the horizontal distance
    truth = out.truth.object(0)
    assert truth.range_m == pytest.approx(np.linalg.norm(c - origin))
    assert truth.elevation_rad == pytest.approx(np.arctan2(H - z_above, x) - np.deg2rad(35.0), abs=1e-9)


def test_tilt_and_heading_rotate_the_rays():
    """The same sphere seen from a yawed, tilted vehicle lands in the same beam/bin as computed
    from its position in the sonar frame."""
    s = sensor(tilt_deg=12.0, window=(1.0, 15.0))
    R_nb = rot_from_euler(0.05, -0.03, 1.2)
    origin = np.array([3.0, -2.0, 5.0])
    R_ns = R_nb @ s.R_bs
    p_s = np.array([8.0, -1.5, 1.0])
    c = origin + R_ns @ p_s
    caster = AnalyticCaster(None, spheres=(AnalyticSphere(c, 0.3, 0),))
    out = s.render(0.0, origin, R_nb, caster, [Obj(0, "s", "opi", True, c)], noise=False)
    # the echo's azimuth centroid: the brightest cell is ill-defined across a sphere's flat top
    per_beam = out.mean_intensity.astype(float).sum(axis=1)
    beam = np.sum(np.arange(len(per_beam)) * per_beam) / per_beam.sum()
    k = np.argmax(out.mean_intensity[int(round(beam))])
    assert abs(beam - beam_of(s, np.arctan2(p_s[1], p_s[0]))) <= 1
    assert abs(k - bin_of(s, np.linalg.norm(p_s) - 0.3)) <= 1
    assert out.truth.object(0).azimuth_rad == pytest.approx(np.arctan2(p_s[1], p_s[0]))


def seabed_scene():
    depth = 6.0
    c0 = np.array([9.0, 1.5, depth - 0.4])
    box = AnalyticBox(np.array([12.0, -2.0, depth - 0.3]), np.array([0.4, 0.6, 0.3]), 1,
                      R_nb=rot_from_euler(0.0, 0.0, 0.4))
    caster = AnalyticCaster(depth, spheres=(AnalyticSphere(c0, 0.4, 0),), boxes=(box,))
    objs = [Obj(0, "sphere", "opi", True, c0), Obj(1, "box", "debris", False, box.center_ned)]
    return caster, objs, np.array([0.0, 0.0, depth - 2.0])


def test_noise_off_is_deterministic_and_seeded_noise_repeats():
    caster, objs, origin = seabed_scene()
    a, b = sensor(tilt_deg=10.0, window=(1.0, 20.0)), sensor(tilt_deg=10.0, window=(1.0, 20.0))
    r1 = a.render(0.0, origin, np.eye(3), caster, objs, noise=False)
    r2 = a.render(0.0, origin, np.eye(3), caster, objs, noise=False)
    assert np.array_equal(r1.frame.polar, r2.frame.polar) and np.array_equal(r1.frame.fan, r2.frame.fan)
    assert np.array_equal(r1.truth.mask_fan, r2.truth.mask_fan)
    n1 = a.render(0.0, origin, np.eye(3), caster, objs)
    n2 = b.render(0.0, origin, np.eye(3), caster, objs)  # same seed, fresh sensor
    assert np.array_equal(n1.frame.polar, n2.frame.polar)
    assert not np.array_equal(n1.frame.polar, r1.frame.polar)
    c = FlsSensor(a.cfg, rng=np.random.default_rng(8)).render(0.0, origin, np.eye(3), caster, objs)
    assert not np.array_equal(c.frame.polar, n1.frame.polar)


def test_ground_truth_boxes_contain_bright_pixels():
    caster, objs, origin = seabed_scene()
    s = sensor(tilt_deg=10.0, window=(1.0, 20.0))
    out = s.render(0.0, origin, np.eye(3), caster, objs, noise=False)
    fan = out.frame.fan.astype(int)
    geo = out.frame.geometry
    for o in out.truth.objects:
        assert o.visible and o.bbox_xyxy is not None
        x0, y0, x1, y1 = o.bbox_xyxy
        # bright pixels near the object: within 3 m of its centroid's (range, azimuth)
        cx, cy = geo.polar_to_pixel(o.range_m, o.azimuth_rad)
        rad_px = 3.0 / geo.m_per_px
        ys, xs = np.mgrid[0:geo.height_px, 0:geo.width_px]
        near = (xs - cx) ** 2 + (ys - cy) ** 2 <= rad_px ** 2
        peak = fan[near].max()
        assert peak >= 200
        bright = near & (fan >= peak - 60)  # within ~12 dB of the object's peak
        bx, by = xs[bright], ys[bright]
        assert np.all((bx >= x0 - 1) & (bx <= x1 + 1) & (by >= y0 - 1) & (by <= y1 + 1))
        assert (x1 - x0) * geo.m_per_px < 4.0 and (y1 - y0) * geo.m_per_px < 4.0  # not a loose box
        my, mx = np.nonzero(out.truth.mask_fan == o.id)
        assert mx.size and np.all((mx >= x0 - 1) & (mx <= x1 + 1) & (my >= y0 - 1) & (my <= y1 + 1))


def disc_overlap(r1: float, r2: float, d: float) -> float:
    """Area of intersection of two discs of radii r1, r2 with centres d apart."""
    if d >= r1 + r2:
        return 0.0
    if d <= abs(r1 - r2):
        return np.pi * min(r1, r2) ** 2
    a1 = r1 ** 2 * np.arccos((d ** 2 + r1 ** 2 - r2 ** 2) / (2 * d * r1))
    a2 = r2 ** 2 * np.arccos((d ** 2 + r2 ** 2 - r1 ** 2) / (2 * d * r2))
    return a1 + a2 - 0.5 * np.sqrt((-d + r1 + r2) * (d + r1 - r2) * (d - r1 + r2) * (d + r1 + r2))


@pytest.mark.parametrize("offset_deg", [0.0, 5.0, 9.0])
def test_hidden_target_visible_fraction(offset_deg):
    """Target behind an occluder: visible fraction = 1 - (angular disc overlap / target disc)."""
    s = sensor(window=(1.0, 20.0), elevation_rays=96)
    front_c, front_r = np.array([8.0, 0.0, 0.0]), 1.0
    a = np.deg2rad(offset_deg)
    back_c, back_r = 15.0 * np.array([np.cos(a), np.sin(a), 0.0]), 0.6
    caster = AnalyticCaster(None, spheres=(AnalyticSphere(front_c, front_r, 0), AnalyticSphere(back_c, back_r, 1)))
    objs = [Obj(0, "front", "rock", False, front_c), Obj(1, "back", "opi", True, back_c)]
    out = s.render(0.0, np.zeros(3), np.eye(3), caster, objs, noise=False)
    front, back = out.truth.object(0), out.truth.object(1)
    assert front.visible and front.visible_fraction == pytest.approx(1.0)
    ang_f, ang_b = np.arcsin(front_r / 8.0), np.arcsin(back_r / 15.0)
    expected = 1.0 - disc_overlap(ang_f, ang_b, a) / (np.pi * ang_b ** 2)
    assert back.visible_fraction == pytest.approx(expected, abs=0.08)
    assert back.in_fov
    if offset_deg == 0.0:
        assert back.visible_fraction < 0.02 and not back.visible and back.bbox_xyxy is None


def test_out_of_beam_object_is_marked_not_boxed():
    s = sensor(window=(1.0, 20.0))
    c = np.array([-8.0, 0.0, 0.0])  # behind the sonar
    caster = AnalyticCaster(None, spheres=(AnalyticSphere(c, 0.5, 0),))
    t = s.render(0.0, np.zeros(3), np.eye(3), caster, [Obj(0, "s", "opi", True, c)], noise=False).truth.object(0)
    assert not t.in_fov and not t.visible and t.bbox_xyxy is None and t.visible_fraction == 0.0
