"""Basin walls as background in the domain randomisation (model v2 training data)."""

from __future__ import annotations

import json

import numpy as np

from sim.dataset.generate import RenderSettings, _manifest, fls_config, scene_spec
from sim.dataset.randomization import (HELDOUT_RANDOMIZATION, TRAIN_RANDOMIZATION, WIDE_RANDOMIZATION,
                                      BasinRandomization, Randomization)


def _exit_range_m(centre, size, heading) -> float:
    """Distance from the origin along ``heading`` to the boundary of the axis-aligned rectangle."""
    half = 0.5 * np.asarray(size)
    c = np.asarray(centre)
    t = [((c[k] + np.sign(heading[k]) * half[k]) / heading[k]) for k in range(2) if abs(heading[k]) > 1e-12]
    return float(min(t))


def test_wall_faced_by_the_sonar_lies_in_the_drawn_range():
    rz = WIDE_RANDOMIZATION.model_copy(update={"basin": BasinRandomization(probability=1.0)})
    for k in range(20):
        spec = scene_spec(7, k, rz)
        assert spec.basin.shape == "rectangular"
        c, size = np.array(spec.basin.center_ne_m), np.array(spec.basin.size_ne_m)
        assert np.all(np.abs(c) < 0.5 * size), "the sonar starts inside the basin"
        yaw = spec.poses[0].rpy_rad[2]
        heading = np.array([np.cos(yaw), np.sin(yaw)])  # yaw jitter is at most 0.05 rad
        r = _exit_range_m(c, size, heading)
        lo, hi = rz.basin.wall_range_m
        assert 0.8 * lo < r < 1.2 * hi, (k, r)


def test_presets_without_basin_keep_their_draws_and_manifests():
    # Turning the basin option off must not change the scene streams of existing datasets.
    no_basin = WIDE_RANDOMIZATION.model_copy(update={"basin": None})
    a, b = scene_spec(5, 3, no_basin), scene_spec(5, 3, WIDE_RANDOMIZATION)
    assert a.targets == b.targets and a.poses == b.poses and a.seabed == b.seabed
    assert scene_spec(5, 3, TRAIN_RANDOMIZATION).basin.shape == "none"
    for rz in (TRAIN_RANDOMIZATION, HELDOUT_RANDOMIZATION):
        assert "basin" not in _manifest(10, 1, rz, RenderSettings())["randomization"]
    assert json.loads(json.dumps(_manifest(10, 1, WIDE_RANDOMIZATION, RenderSettings())))["randomization"]["basin"]


def test_basin_wall_is_rendered_as_unlabelled_background():
    from sim.dataset.scene_render import render_frames
    from sim.rng import component_rng

    rz = Randomization(seabed_kinds=("plane",), n_targets=(0, 0), n_distractors=(0, 0), frames_per_scene=1,
                       range_max_m=(20.0, 20.0), altitude_m=(3.0, 3.0), tilt_deg=(8.0, 8.0), noise_scale=(0.5, 0.5),
                       basin=BasinRandomization(probability=1.0, wall_range_m=(12.0, 12.0)))
    spec = scene_spec(1, 0, rz)
    settings = RenderSettings(azimuth_columns=181, elevation_rays=12)
    rec = render_frames(spec, fls_config(spec, settings), component_rng(1, "fls"), 1)[0]
    assert rec.objects == ()
    g = rec.geometry
    yaw = spec.poses[0].rpy_rad[2]
    heading = np.array([np.cos(yaw), np.sin(yaw)])
    wall_r = _exit_range_m(spec.basin.center_ne_m, spec.basin.size_ne_m, heading)
    # mean brightness along the centre beam: peak within a metre of the wall, dark well beyond it
    ranges = np.arange(g.range_min_m + 0.5, g.range_max_m - 0.5, 0.1)
    x, y = g.polar_to_pixel(ranges, np.zeros_like(ranges))
    cols = np.clip(np.round(x).astype(int), 2, g.width_px - 3)
    rows = np.clip(np.round(y).astype(int), 0, g.height_px - 1)
    profile = np.array([rec.fan[r, c - 2:c + 3].mean() for r, c in zip(rows, cols)])
    r_peak = ranges[np.argmax(profile)]
    assert abs(r_peak - wall_r) < 1.5, (r_peak, wall_r)
    assert profile[ranges > wall_r + 2.0].mean() < 0.3 * profile.max()
