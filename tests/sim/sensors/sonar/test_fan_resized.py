"""The direct polar -> small fan resampling against the area-resized full fan (its oracle)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from autonomy.messages import FlsFrame
from scenarios.config.fls import FlsConfig
from scenarios.load import load_scenario
from sim.sensors.fls import FlsSensor
from sim.sensors.sonar.speckle import standard_exponential_f32

CNN_HW = (336, 640)  # the shipped ATR model's input


@pytest.fixture(scope="module", params=["shipped", "default"])
def remap(request):
    """The closed-loop sonar of the shipped CSSN scenario, and the default sonar config."""
    cfg = load_scenario("cssn_lawnmower").sensors.fls if request.param == "shipped" else FlsConfig()
    return FlsSensor(cfg, rng=np.random.default_rng(0))._remap


def _area(remap, polar):
    return cv2.resize(remap.image(polar), CNN_HW[::-1], interpolation=cv2.INTER_AREA)


def _inside(remap):
    """Output pixels whose whole area lies inside the fan in the oracle (no edge blending)."""
    full = cv2.resize(remap.inside.astype(np.uint8) * 255, CNN_HW[::-1], interpolation=cv2.INTER_AREA)
    return full == 255


def test_smooth_polar_image_lands_on_the_same_pixels(remap):
    b, k = np.mgrid[0:remap.n_beams, 0:remap.n_bins].astype(float)
    polar = (127 + 60 * np.sin(b / 150.0) + 60 * np.cos(k / 55.0)).astype(np.uint8)
    got, want = remap.resized(polar, *CNN_HW), _area(remap, polar)
    inside = _inside(remap)
    assert got.shape == want.shape == CNN_HW
    # a one-pixel shift of the grid would cost ~3 grey levels on these gradients
    assert np.abs(got.astype(int) - want)[inside].mean() < 0.6
    assert np.abs(got.astype(int) - want)[inside].max() <= 4
    outside = cv2.resize(remap.inside.astype(np.uint8) * 255, CNN_HW[::-1], interpolation=cv2.INTER_AREA) == 0
    assert outside.any() and not got[outside].any()


def test_speckle_grain_matches_the_area_resized_fan(remap):
    rng = np.random.default_rng(3)
    expo = standard_exponential_f32(rng, (remap.n_beams, remap.n_bins))
    polar = np.clip(np.round(200 + 255.0 / 60.0 * 10 * np.log10(expo)), 0, 255).astype(np.uint8)
    got, want = remap.resized(polar, *CNN_HW), _area(remap, polar)
    inside = _inside(remap)

    def grain(img):
        f = img.astype(float)
        return (f - cv2.GaussianBlur(f, (0, 0), 3))[inside].std()

    assert abs(got[inside].mean() - want[inside].mean()) < 1.0
    assert got[inside].std() == pytest.approx(want[inside].std(), rel=0.1)
    assert grain(got) == pytest.approx(grain(want), rel=0.15)


def test_frame_uses_the_direct_path_until_its_fan_is_formed(remap):
    polar = np.random.default_rng(1).integers(0, 256, (remap.n_beams, remap.n_bins), dtype=np.uint8)
    frame = FlsFrame(0.0, polar, geometry=remap.fan, resampler=remap)
    assert not frame.fan_formed and frame.fan_hw == (remap.fan.height_px, remap.fan.width_px)
    assert np.array_equal(frame.fan_resized(*CNN_HW), remap.resized(polar, *CNN_HW))
    assert np.array_equal(frame.fan, remap.image(polar)) and frame.fan_formed
    assert np.array_equal(frame.fan_resized(*CNN_HW), _area(remap, polar))


def test_frame_pickles_with_its_fan_formed(remap):
    import pickle

    polar = np.random.default_rng(2).integers(0, 256, (remap.n_beams, remap.n_bins), dtype=np.uint8)
    frame = FlsFrame(1.5, polar, geometry=remap.fan, resampler=remap, mount_pos_body_m=np.zeros(3),
                     mount_rpy_rad=np.zeros(3))
    back = pickle.loads(pickle.dumps(frame))
    assert back.fan_formed and back.t_s == 1.5 and np.array_equal(back.fan, remap.image(polar))
    assert np.array_equal(back.polar, polar) and back.geometry == remap.fan
