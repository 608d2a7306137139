"""Every byte an FLS render returns is pinned, on the bench pose sequence and on dataset scenes.

Stronger than the dataset's pinned fan images: the digests
(:func:`sim.sensors.fls_digest.update_with_render`) cover the polar and fan images, both label
masks, the mean and realised intensities, every object's truth record and the noise
generator's state after each frame. They are those of the renderer before the issue-18 speed-ups
(``scripts/fls_frame_digest.py --bench-frames 2 --scenes 2 --dataset-frames 2`` on that code);
a change that alters any of those bytes fails here.
"""

from __future__ import annotations

import hashlib

import pytest

from sim.sensors.fls import FlsSensor
from sim.sensors.fls_digest import update_with_render

PINNED = {
    "bench": "4ae6ce2da9de6709f4e8ad3dfc0202adc83e49dbcb9357a9e5b72f98376a68bc",  # warm-up + 2 frames
    "train/1": "22b99aa6c274d7d5189b027e156dd8a5db280334ee1de2bf6774bd1bc62f6b05",  # K clutter, rough mesh seabed
    "wide/1": "f5608036e57837cecaeb399ce2ba0c0def0892d957aa039f83059a8223113135",  # rough seabed, basin walls
}


@pytest.fixture
def digest(monkeypatch):
    """A hash fed every render of this test."""
    h = hashlib.sha256()
    inner = FlsSensor.render

    def hashed(self, *args, **kwargs):
        out = inner(self, *args, **kwargs)
        update_with_render(h, out, self.rng)
        return out

    monkeypatch.setattr(FlsSensor, "render", hashed)
    return h


def test_bench_frames_are_byte_identical_to_the_pinned_ones(digest):
    from scenarios.load import load_scenario
    from sim.bench import fls as bench_fls

    bench_fls.run(load_scenario("cssn_lawnmower"), 2, without_truth=False)
    assert digest.hexdigest() == PINNED["bench"]


@pytest.mark.parametrize("key", ["train/1", "wide/1"])
def test_dataset_frames_are_byte_identical_to_the_pinned_ones(digest, key):
    from sim.dataset.generate import RANDOMIZATION_PRESETS, RenderSettings, fls_config, scene_spec
    from sim.dataset.scene_render import render_frames
    from sim.rng import component_rng

    name, index = key.split("/")
    spec = scene_spec(0, int(index), RANDOMIZATION_PRESETS[name])
    render_frames(spec, fls_config(spec, RenderSettings()), component_rng(0, f"dataset/fls/{index}"), 2)
    assert digest.hexdigest() == PINNED[key]
