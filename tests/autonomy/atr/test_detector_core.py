"""ATR building blocks: IoU/NMS, reference point, union-find, CenterNet decoding, classical detector."""

from __future__ import annotations

import numpy as np
import pytest
from pycocotools import mask as mask_utils
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import connected_components

from autonomy.atr.centernet_decode import decode_centernet
from autonomy.atr.classical import ClassicalDetector
from autonomy.atr.nms import box_iou, nms
from autonomy.atr.reference_point import box_reference_polar, box_reference_px
from autonomy.atr.union_find import UnionFind
from autonomy.messages import FlsFrame
from autonomy.sonar_geometry import FanGeometry

GEOM = FanGeometry.fit(894, 477, 1.0, 30.0, np.deg2rad(130.0))


def _frame(fan: np.ndarray, geom: FanGeometry = GEOM) -> FlsFrame:
    return FlsFrame(t_s=1.5, polar=np.zeros((2, 2), np.uint8), fan=fan, geometry=geom,
                    mount_pos_body_m=np.zeros(3), mount_rpy_rad=np.zeros(3))


def _random_boxes(rng, n):
    xy = rng.uniform(0, 100, (n, 2))
    wh = rng.uniform(1, 30, (n, 2))
    return np.concatenate([xy, xy + wh], axis=1)


def test_box_iou_matches_pycocotools():
    rng = np.random.default_rng(0)
    a, b = _random_boxes(rng, 20), _random_boxes(rng, 15)
    to_xywh = lambda x: np.concatenate([x[:, :2], x[:, 2:] - x[:, :2]], axis=1)  # noqa: E731
    oracle = mask_utils.iou(to_xywh(a).tolist(), to_xywh(b).tolist(), [0] * len(b))
    np.testing.assert_allclose(box_iou(a, b), oracle, atol=1e-9)


def test_nms_keeps_no_overlapping_pair_and_every_dropped_box_has_a_keeper():
    rng = np.random.default_rng(1)
    boxes = _random_boxes(rng, 200)
    scores = rng.random(200)
    keep = nms(boxes, scores, 0.4)
    iou = box_iou(boxes[keep], boxes[keep])
    np.fill_diagonal(iou, 0.0)
    assert iou.max() <= 0.4
    assert np.all(np.diff(scores[keep]) <= 0)
    dropped = np.setdiff1d(np.arange(200), keep)
    # each suppressed box overlaps a kept box of higher score
    iou_dk = box_iou(boxes[dropped], boxes[keep])
    higher = scores[keep][None, :] > scores[dropped][:, None]
    assert np.all(np.any((iou_dk > 0.4) & higher, axis=1))


def test_nms_classes_do_not_suppress_each_other():
    boxes = np.array([[0, 0, 10, 10], [0, 0, 10, 10.5]], float)
    assert len(nms(boxes, [0.9, 0.8], 0.5)) == 1
    assert len(nms(boxes, [0.9, 0.8], 0.5, class_ids=[0, 1])) == 2


def test_union_find_matches_scipy_components():
    rng = np.random.default_rng(2)
    n = 60
    edges = rng.integers(0, n, (40, 2))
    uf = UnionFind(n)
    for i, j in edges:
        uf.union(int(i), int(j))
    graph = csr_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(n, n))
    n_comp, lab = connected_components(graph, directed=False)
    ours = uf.labels()
    assert ours.max() + 1 == n_comp
    # same partition: label pairs map one-to-one
    assert len(set(zip(ours.tolist(), lab.tolist()))) == n_comp


def test_reference_point_is_leading_edge_along_centre_bearing():
    # A box straight ahead: reference point is the bottom-centre (nearest the apex).
    r0, half_px = 12.0, 10.0
    cx, cy = GEOM.polar_to_pixel(r0, 0.0)
    box = np.array([[cx - half_px, cy - half_px, cx + half_px, cy + half_px]])
    p = box_reference_px(box, GEOM)[0]
    np.testing.assert_allclose(p, [cx, cy + half_px], atol=1e-9)
    rng_m, az = box_reference_polar(box, GEOM)
    assert rng_m[0] == pytest.approx(r0 - half_px * GEOM.m_per_px, abs=1e-9)
    assert az[0] == pytest.approx(0.0, abs=1e-12)
    # A box at 40 deg starboard: the point lies on the bearing of the box centre, on the box
    # boundary, and is nearer than the centre.
    cx, cy = GEOM.polar_to_pixel(15.0, np.deg2rad(40.0))
    box = np.array([[cx - 8, cy - 5, cx + 8, cy + 5]])
    rng_m, az = box_reference_polar(box, GEOM)
    assert az[0] == pytest.approx(np.deg2rad(40.0), abs=1e-9)
    px = box_reference_px(box, GEOM)[0]
    on_edge = np.isclose(px[0], box[0, 0]) or np.isclose(px[1], box[0, 3])
    assert on_edge and rng_m[0] < 15.0


def test_decode_centernet_recovers_planted_peaks():
    h, w, stride = 30, 56, 4
    heat = np.zeros((2, h, w), np.float32)
    size = np.zeros((2, h, w), np.float32)
    off = np.zeros((2, h, w), np.float32)
    heat[1, 10, 20] = 0.9
    off[:, 10, 20] = (0.25, 0.5)
    size[:, 10, 20] = np.log([12.0, 8.0])
    heat[0, 3, 4] = 0.3  # below threshold
    boxes, scores, cls = decode_centernet(heat, size, off, stride, 0.5, 10)
    assert cls.tolist() == [1] and scores[0] == pytest.approx(0.9)
    cx, cy = (20.25) * stride, (10.5) * stride
    np.testing.assert_allclose(boxes[0], [cx - 6, cy - 4, cx + 6, cy + 4], atol=1e-5)
    b2, s2, _ = decode_centernet(heat, size, off, stride, 0.1, 1)
    assert len(s2) == 1 and s2[0] == pytest.approx(0.9)
    # nothing above the threshold: empty arrays of the documented shapes and dtypes
    b0, s0, c0 = decode_centernet(heat, size, off, stride, 0.95, 10)
    assert b0.shape == (0, 4) and s0.shape == (0,) and c0.shape == (0,)
    assert (b0.dtype, s0.dtype, c0.dtype) == (np.float64, np.float64, np.int64)


def _blob_fan(rng, centres_px, radius_px=9, level=200):
    fan = rng.exponential(30.0, (477, 894)).clip(0, 255).astype(np.uint8)
    yy, xx = np.mgrid[:477, :894]
    for cx, cy in centres_px:
        fan[(xx - cx) ** 2 + (yy - cy) ** 2 <= radius_px ** 2] = level
    return fan


def test_classical_detector_finds_bright_blobs_and_reports_their_polar_position():
    rng = np.random.default_rng(3)
    truth = [(12.0, -0.4), (20.0, 0.3)]
    centres = [tuple(float(v) for v in GEOM.polar_to_pixel(r, a)) for r, a in truth]
    fan = _blob_fan(rng, centres)
    dets = ClassicalDetector(score_threshold=0.3).detect(_frame(fan))
    assert len(dets) == 2
    for (r, a), (cx, cy) in zip(truth, centres):
        d = min(dets, key=lambda d: np.hypot(*(0.5 * (d.box_xyxy_px[:2] + d.box_xyxy_px[2:]) - (cx, cy))))
        bc = 0.5 * (d.box_xyxy_px[:2] + d.box_xyxy_px[2:])
        assert np.hypot(bc[0] - cx, bc[1] - cy) < 3.0
        assert d.azimuth_rad == pytest.approx(a, abs=0.02)
        # leading edge: one blob radius (9 px) nearer than the centre, within 2 px
        assert d.range_m == pytest.approx(r - 9 * GEOM.m_per_px, abs=2 * GEOM.m_per_px)
        assert d.class_name == "opi" and 0.3 <= d.score <= 1.0 and d.t_s == 1.5


def test_classical_detector_clusters_fragments_and_roi_weights_scores():
    rng = np.random.default_rng(4)
    cx, cy = GEOM.polar_to_pixel(15.0, 0.0)
    gap_px = 0.3 / GEOM.m_per_px  # fragments 0.3 m apart: closer than cluster_distance_m = 0.5
    fan = _blob_fan(rng, [(cx - gap_px, cy), (cx + gap_px, cy)], radius_px=4)
    det = ClassicalDetector(score_threshold=0.2)
    boxes, scores = det.detect_boxes(fan, GEOM.m_per_px)
    assert len(boxes) == 1
    assert boxes[0, 0] < cx - gap_px and boxes[0, 2] > cx + gap_px
    from autonomy.atr.config import ClassicalAtrConfig

    roi_det = ClassicalDetector(ClassicalAtrConfig(roi_radius_m=1.0), score_threshold=0.0)
    _, s_near = roi_det.detect_boxes(fan, GEOM.m_per_px, roi_centre_px=(cx, cy))
    _, s_far = roi_det.detect_boxes(fan, GEOM.m_per_px, roi_centre_px=(cx + 3.0 / GEOM.m_per_px, cy))
    assert s_near[0] > 0.5 * scores[0] and s_far[0] < 0.05 * s_near[0]


def test_classical_detector_quiet_on_pure_speckle():
    rng = np.random.default_rng(5)
    fan = rng.exponential(30.0, (477, 894)).clip(0, 255).astype(np.uint8)
    assert ClassicalDetector(score_threshold=0.5).detect(_frame(fan)) == []


@pytest.mark.parametrize("bad", [np.zeros((477, 894), np.float32), np.zeros((477, 894, 3), np.uint8), None])
def test_classical_detector_rejects_bad_images(bad):
    with pytest.raises(ValueError, match="2-D uint8"):
        ClassicalDetector().detect(_frame(bad))
