"""Dataset frames are pinned: labels exactly, fan images within the cross-machine tolerance.

Against the FLS reference (``tests/data/fls_reference``; :mod:`sim.bench.fls_reference`,
``python scripts/fls_reference.py --write`` regenerates it): a change to image formation
that shifts any dataset fan beyond the tolerance, or changes a label, fails here. On a machine
whose numerics are the pinning machine's, every byte of every render must match as well (the
fan bytes of these frames are those of the code before the closed-loop speed-ups).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from sim.dataset.generate import RenderSettings, fls_config, scene_spec
from sim.dataset.randomization import TRAIN_RANDOMIZATION, WIDE_RANDOMIZATION
from sim.dataset.scene_render import render_frames
from sim.rng import component_rng
from sim.bench import fls_reference as fr
REFERENCE_DIR = Path(__file__).resolve().parents[2] / "data" / "fls_reference"
# K-distributed clutter, rippled seabed, basin walls in wide/3; its second frame was re-pinned when a
# fold's range extremum was bounded by the end tangents (309 pixels of a grazing surface changed)
BOXES = {"train/0": [[294.0, 339.0, 13.0, 13.0], [42.0, 211.0, 15.0, 14.0], [721.0, 280.0, 8.0, 10.0]],
         "wide/3": [[196.0, 123.0, 14.0, 12.0], [753.0, 144.0, 18.0, 18.0]]}


@pytest.mark.parametrize("key", sorted(BOXES))
def test_dataset_frames_match_the_pinned_reference(key):
    reference = fr.load_reference(REFERENCE_DIR)
    name, index = key.split("/")
    rz = {"train": TRAIN_RANDOMIZATION, "wide": WIDE_RANDOMIZATION}[name]
    spec = scene_spec(0, int(index), rz)
    with fr.capture(fr.CaseRenders()) as got:
        records = render_frames(spec, fls_config(spec, RenderSettings()), component_rng(0, f"dataset/fls/{index}"), 2)
    ref = reference.cases[key]
    assert fr.compare_case(ref, got) == []
    for r, ref_images in zip(records, ref.images):  # the fan a record carries (its PNG) is the pinned one
        assert fr.compare_images(ref_images, fr.u8_summary("fan", r.fan)) == []
    assert [o.bbox_coco for o in records[0].objects] == BOXES[key]
    if reference.fingerprint == fr.numerics_fingerprint():  # the pinning machine's numerics: every byte
        assert got.digest == reference.digests[key]
