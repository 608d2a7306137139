"""Side-scan sonar geometry on the analytic caster, against closed-form expectations."""

from __future__ import annotations


import numpy as np
import pytest
from pydantic import ValidationError

from autonomy.frames import rot_from_euler
from scenarios.config.sss import SssConfig
from sim.sensors.analytic_caster import AnalyticBox, AnalyticCaster, AnalyticSphere
from sim.sensors.raycast import BACKGROUND_ID
from sim.sensors.registry import sensor_class
from sim.sensors.sss import SssSensor, Waterfall, ground_range_resample
from tests.support import SceneObj

SEABED_M = 30.0
SONAR_DEPTH_M = 10.0
ALT_M = SEABED_M - SONAR_DEPTH_M


def sonar(**kw) -> SssSensor:
    return SssSensor(SssConfig(speckle="none", **kw), (0.0, 0.0, 0.0), np.random.default_rng(1))


def render(s, caster, objects=(), yaw_rad=0.0, noise=False):
    return s.render(0.0, np.array([0.0, 0.0, SONAR_DEPTH_M]), rot_from_euler(0.0, 0.0, yaw_rad), caster, objects,
                    noise=noise)


def test_registered_and_ping_rate_from_range():
    assert sensor_class("sss") is SssSensor
    assert SssConfig(range_max_m=75.0).rate_hz == pytest.approx(1500.0 / 150.0)
    assert SssConfig(range_max_m=150.0, sound_speed_mps=1480.0).rate_hz == pytest.approx(1480.0 / 300.0)
    with pytest.raises(ValidationError, match="two-way travel-time"):
        SssConfig(range_max_m=75.0, rate_hz=12.0)


@pytest.mark.parametrize("yaw_deg", [0.0, 37.0])
def test_first_bottom_return_at_altitude_and_nadir_gap(yaw_deg):
    s = sonar()
    r = render(s, AnalyticCaster(SEABED_M), yaw_rad=np.deg2rad(yaw_deg))
    first = int(np.floor(ALT_M / s.bin_size_m))
    for side in (0, 1):
        nz = np.flatnonzero(r.mean_intensity[side] > 0.0)
        assert nz[0] == first  # nadir gap: the water column returns nothing
        # the flat seabed returns out to the range (no gaps)
        assert nz[-1] == s.n_bins - 1 and len(nz) == s.n_bins - first
    assert r.ping.altitude_m == pytest.approx(ALT_M)
    assert np.all(r.labels == BACKGROUND_ID)


def test_sphere_slant_range_exact_to_a_bin_on_its_side():
    s = sonar()
    centre = np.array([0.0, 40.0, SEABED_M - 1.0])  # 40 m to starboard, resting on the seabed
    caster = AnalyticCaster(SEABED_M, spheres=(AnalyticSphere(centre, 1.0, 5),))
    r = render(s, caster, [SceneObj(5, "s", "sphere", True, centre)])
    near_m = np.linalg.norm(centre - np.array([0.0, 0.0, SONAR_DEPTH_M])) - 1.0
    hits = np.flatnonzero(r.labels[1] == 5)
    assert hits[0] == int(np.floor(near_m / s.bin_size_m))
    assert not np.any(r.labels[0] == 5)  # not on the port line


@pytest.mark.parametrize("side, sign", [(0, -1.0), (1, 1.0)])
def test_box_shadow_length_from_similar_triangles(side, sign):
    s = sonar(ground_range=True)
    h, x0, x1 = 2.0, 30.0, 32.0  # box height, near and far ground range of its faces
    box = AnalyticBox(np.array([0.0, sign * 0.5 * (x0 + x1), SEABED_M - 0.5 * h]),
                      np.array([5.0, 0.5 * (x1 - x0), 0.5 * h]), 9)
    r = render(s, AnalyticCaster(SEABED_M, boxes=(box,)))
    shadow_end_ground_m = x1 * ALT_M / (ALT_M - h)  # ray over the far top edge meets the seabed
    r_top = np.hypot(x1, ALT_M - h)
    r_end = np.hypot(shadow_end_ground_m, ALT_M)
    line = r.mean_intensity[side]
    # slant range: empty exactly between the far top edge and where the seabed reappears
    k_top, k_end = int(np.floor(r_top / s.bin_size_m)), int(np.floor(r_end / s.bin_size_m))
    assert np.all(line[k_top + 1:k_end] == 0.0)
    assert line[k_top] > 0.0 and line[k_end + 1] > 0.0  # the seabed is back within a bin
    assert np.any(r.labels[side, :k_top + 1] == 9) and not np.any(r.labels[side, k_top + 1:] == 9)
    # ground range: the seabed reappears x1 h / (H - h) beyond the box's far face (the flat-seabed
    # correction maps seabed returns exactly; the raised box top lands nearer nadir than x1)
    g = ground_range_resample(line[None, :], ALT_M, s.bin_size_m)[0]
    obj_end = np.flatnonzero(ground_range_resample(r.labels[side][None], ALT_M, s.bin_size_m, nearest=True)[0] == 9)[-1]
    assert (obj_end + 0.5) * s.bin_size_m == pytest.approx(np.sqrt(r_top ** 2 - ALT_M ** 2), abs=s.bin_size_m)
    start = obj_end + np.flatnonzero(g[obj_end:] == 0.0)[0]
    back_m = (start + np.flatnonzero(g[start:] > 0.0)[0]) * s.bin_size_m
    assert back_m - x1 == pytest.approx(x1 * h / (ALT_M - h), abs=2.0 * s.bin_size_m)
    assert r.ground_labels is not None and r.ping.ground_lines_u8 is not None


def test_grazing_angle_backscatter_falls_with_range():
    # Lambert seabed: noise-free mean power per bin falls with slant range beyond the beam's peak
    s = sonar(vertical_beamwidth_deg=120.0, depression_deg=45.0)
    line = render(s, AnalyticCaster(SEABED_M)).mean_intensity[1].astype(float)
    far = line[int(40 / s.bin_size_m):int(70 / s.bin_size_m)]
    assert np.all(np.diff(far) <= 1e-12 * far.max())


def test_waterfall_and_noise_stream():
    s = SssSensor(SssConfig(), (0.0, 0.0, 0.0), np.random.default_rng(3))
    caster = AnalyticCaster(SEABED_M)
    wf = Waterfall(s.n_bins)
    a = render(s, caster, noise=True)
    wf.add(a)
    wf.add(render(s, caster, noise=True))
    img = wf.image()
    assert img.shape == (2, 2 * s.n_bins) and img.dtype == np.uint8
    assert np.array_equal(img[0, :s.n_bins], a.ping.lines_u8[0, ::-1])
    assert not np.array_equal(img[0], img[1])  # speckle differs ping to ping
