"""The CNN detector's per-frame path (IO binding on reused buffers, one-gather decode) gives the
same detections, bit for bit, as the straightforward path on real rendered FLS frames.

The reference below is the detector's code before the closed-loop speed-ups, kept verbatim: a
plain ``session.run`` on a fresh input, decoding with per-channel fancy indexing, the fan-pixel
conversion by column and NMS on every box.
"""

from __future__ import annotations

import threading

import numpy as np
import pytest

from autonomy.atr import build_detector
from autonomy.atr.config import AtrConfig
from autonomy.atr.detector import to_detections
from autonomy.atr.nms import nms
from autonomy.messages import FlsFrame

# Dataset scenes (randomization, index): targets, rocks, clutter and basin walls; ("wide", 1)
# has no detection at the operating threshold.
SCENES = (("train", 2), ("wide", 0), ("wide", 1), ("wide", 2), ("wide", 3))


def reference_decode(heatmap, size_log, offset, stride, score_threshold, max_detections):
    c, h, w = heatmap.shape
    flat = heatmap.reshape(-1)
    idx = np.flatnonzero(flat >= score_threshold)
    if idx.size == 0:
        return np.zeros((0, 4)), np.zeros(0), np.zeros(0, dtype=np.int64)
    if idx.size > max_detections:
        idx = idx[np.argpartition(-flat[idx], max_detections - 1)[:max_detections]]
    idx = idx[np.argsort(-flat[idx], kind="stable")]
    cls, rem = np.divmod(idx, h * w)
    iy, ix = np.divmod(rem, w)
    cx = (ix + offset[0, iy, ix]) * stride
    cy = (iy + offset[1, iy, ix]) * stride
    bw = np.exp(np.clip(size_log[0, iy, ix], -4.0, 8.0))
    bh = np.exp(np.clip(size_log[1, iy, ix], -4.0, 8.0))
    boxes = np.stack([cx - 0.5 * bw, cy - 0.5 * bh, cx + 0.5 * bw, cy + 0.5 * bh], axis=1)
    return boxes.astype(np.float64), flat[idx].astype(np.float64), cls.astype(np.int64)


def reference_boxes(det, fan, threshold):
    out = det.raw_outputs(fan)  # plain session.run on a fresh input
    boxes, scores, cls = reference_decode(out["heatmap"], out["size"], out["offset"], det.stride, threshold,
                                          det.max_detections)
    if boxes.shape[0] == 0:
        return boxes, scores, cls
    sx = fan.shape[1] / det.input_hw[1]
    sy = fan.shape[0] / det.input_hw[0]
    boxes = boxes.copy()
    boxes[:, [0, 2]] = (boxes[:, [0, 2]] + 0.5) * sx - 0.5
    boxes[:, [1, 3]] = (boxes[:, [1, 3]] + 0.5) * sy - 0.5
    keep = nms(boxes, scores, det.nms_iou, cls)
    return boxes[keep], scores[keep], cls[keep]


def assert_same(got, want):
    for g, w in zip(got, want):
        assert g.dtype == w.dtype and g.shape == w.shape
        np.testing.assert_array_equal(g, w)


@pytest.fixture(scope="module")
def frames():
    from sim.dataset.generate import RenderSettings, fls_config, scene_spec
    from sim.dataset.randomization import TRAIN_RANDOMIZATION, WIDE_RANDOMIZATION
    from sim.dataset.scene_render import render_frames
    from sim.rng import component_rng

    out = []
    for name, i in SCENES:
        spec = scene_spec(0, i, {"train": TRAIN_RANDOMIZATION, "wide": WIDE_RANDOMIZATION}[name])
        for r in render_frames(spec, fls_config(spec, RenderSettings()), component_rng(0, f"dataset/fls/{i}"), 2):
            out.append(FlsFrame(t_s=r.t_s, polar=np.zeros((1, 1), np.uint8), fan=r.fan, geometry=r.geometry,
                                mount_pos_body_m=np.zeros(3), mount_rpy_rad=np.zeros(3)))
    return out


@pytest.fixture(scope="module")
def detector():
    return build_detector(AtrConfig())


@pytest.mark.parametrize("threshold", [None, 0.05])
def test_boxes_are_bit_identical_to_the_plain_path(frames, detector, threshold):
    """At the operating threshold and at 0.05 (tens of peaks: NMS and the max-detections cap)."""
    thr = detector.score_threshold if threshold is None else threshold
    counts = []
    for f in frames:
        got = detector.detect_boxes(f.fan, threshold)
        assert_same(got, reference_boxes(detector, f.fan, thr))
        counts.append(got[0].shape[0])
    if threshold is None:
        assert 0 in counts and max(counts) >= 3  # frames without and with several detections
    else:
        assert min(counts) >= 5 and max(counts) >= 20  # several to tens of peaks in every frame


def test_max_detections_cap_and_single_box(frames):
    """A cap below the number of peaks (argpartition) and a cap of one (no NMS)."""
    for cap in (1, 4):
        det = build_detector(AtrConfig(max_detections=cap))
        for f in frames[:4]:
            got = det.detect_boxes(f.fan, 0.05)
            assert got[0].shape[0] >= 1
            assert_same(got, reference_boxes(det, f.fan, 0.05))


def test_messages_match_the_plain_path(frames, detector):
    for f in frames:
        boxes, scores, cls = reference_boxes(detector, f.fan, detector.score_threshold)
        want = to_detections(f, boxes, scores, [detector.class_names[i] for i in cls])
        got = detector.detect(f)
        assert [(d.class_name, d.score, d.box_xyxy_px.tobytes(), d.range_m, d.azimuth_rad) for d in got] == \
               [(d.class_name, d.score, d.box_xyxy_px.tobytes(), d.range_m, d.azimuth_rad) for d in want]


def test_results_do_not_share_the_reused_buffers(frames, detector):
    """Outputs of one frame survive the next frames' runs, and reruns repeat them exactly."""
    first = [detector.detect_boxes(f.fan) for f in frames]
    kept = [tuple(a.copy() for a in r) for r in first]
    again = [detector.detect_boxes(f.fan) for f in reversed(frames)][::-1]
    for a, b, c in zip(first, kept, again):
        assert_same(a, b)
        assert_same(c, b)


def test_other_fan_sizes_and_dtypes_take_the_plain_preprocessing(frames, detector):
    """``detect_boxes`` takes any fan size (as before); a float fan goes through ``preprocess``."""
    fan = frames[1].fan[::2, ::2].copy()
    assert_same(detector.detect_boxes(fan, 0.05), reference_boxes(detector, fan, 0.05))
    fan_f = frames[1].fan.astype(np.float64)
    assert_same(detector.detect_boxes(fan_f, 0.05), reference_boxes(detector, fan_f, 0.05))


def test_concurrent_calls_take_turns(frames, detector):
    want = [detector.detect_boxes(f.fan) for f in frames]
    got: dict[int, list] = {}

    def work(k):
        got[k] = [detector.detect_boxes(f.fan) for f in (frames if k % 2 else frames[::-1])]

    threads = [threading.Thread(target=work, args=(k,)) for k in range(3)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for k, res in got.items():
        for a, b in zip(res if k % 2 else res[::-1], want):
            assert_same(a, b)


def test_models_without_fixed_float32_outputs_run_the_plain_path(frames):
    """Such a model gets no IO binding (``_binding`` None) and still decodes the same."""
    det = build_detector(AtrConfig())
    bound = [det.detect_boxes(f.fan, 0.05) for f in frames[:4]]
    det._binding = None
    for f, b in zip(frames[:4], bound):
        assert_same(det.detect_boxes(f.fan, 0.05), b)
