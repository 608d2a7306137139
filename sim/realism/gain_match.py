"""The display gain of simulated tank frames matched to real ones: the one level a user sets
by eye on a real sonar's display (the mid-range floor's median grey)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from autonomy.sonar_geometry import FanGeometry
from sim.dataset.tank_scenes import TANK, SimFrame, TankGeometry, TankScene, render_tank_frames
from sim.realism.image_measures import fan_radius_px


def background_grey(frames: list[SimFrame] | list[tuple[NDArray, NDArray]], geom: FanGeometry) -> float:
    """Median grey of the unlabelled fan pixels in the middle third of the range window
    (the level the display gain is matched on)."""
    rad, az = fan_radius_px(geom)
    near_px, far_px = geom.range_min_m / geom.m_per_px, geom.range_max_m / geom.m_per_px
    mid = (rad > near_px + (far_px - near_px) / 3) & (rad < far_px - (far_px - near_px) / 3) & (
        np.abs(az) < 0.5 * geom.fov_rad - 0.02)
    vals = [img[mid & (mask == 0)] for img, mask in ((f.image, f.mask) if isinstance(f, SimFrame) else f
                                                       for f in frames)]
    return float(np.median(np.concatenate(vals)))


def calibrate_gain_db(target_grey: float, scenes: list[TankScene], geom: FanGeometry, *, seed: int,
                      fls_overrides: dict | None = None, iterations: int = 3, tank: TankGeometry = TANK) -> float:
    """The display gain (dB) at which the simulated mid-range background median grey equals
    ``target_grey``: the one level a user matches by eye on a real sonar's display. Solved by
    the display law's inverse (dB display: 255 / dynamic range grey per dB; power-law display:
    grey ~ 10^(gamma gain / 20)), a few rounds for saturation."""
    from scenarios.config.fls import FlsConfig

    over = dict(fls_overrides or {})
    cfg = FlsConfig(preset="aris3000", **over)
    gain = float(cfg.gain_db)
    gamma = cfg.formation.display_gamma
    for _ in range(iterations):
        over["gain_db"] = gain
        grey = background_grey(list(render_tank_frames(scenes, geom, seed=seed, fls_overrides=over, tank=tank)),
                               geom)
        grey = max(grey, 0.5)
        if gamma is None:
            gain += (target_grey - grey) * cfg.dynamic_range_db / 255.0
        else:
            gain += 20.0 / gamma * np.log10(target_grey / grey)
    return float(gain)
