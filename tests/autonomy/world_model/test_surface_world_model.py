"""The world model on the surface: fed the detection reports the link delivered (late, in
packets, through the binary format and geodetic coordinates), it keeps the objects the
onboard PMHA keeps when fed the same detections; late reports are counted, not misordered."""

from __future__ import annotations

import numpy as np
import pytest

from autonomy.comms.messages import DetectionReport, decode
from autonomy.geodesy import GeodeticOrigin
from autonomy.localization import LocalizedDetection
from autonomy.world_model import PMHA
from autonomy.world_model.config import WorldModelConfig
from autonomy.world_model.surface import FixTrack, SonarFootprint, SurfaceWorldModel, near_reports, unseen

TRUTHS = np.array([[0, 10, 4], [0, 20, 4], [0, 25, 4], [-8, 10, 4], [-7, 15, 4], [-8, 22, 4]], float)
REGION = ([-20.0, 0.0, 0.0], [10.0, 35.0, 5.0])
ORIGIN = GeodeticOrigin()
EPOCH_S = 1_688_169_600.0
CLASSES = ("opi",)


def _scans(seed: int = 2, n_frames: int = 120, frame_dt_s: float = 1.0 / 3.0):
    """Frames of a synthetic survey: each OPI seen in a window of frames with probability 0.8
    (0.3 m noise, ATR score ~0.6), plus clutter; frame times on the message's millisecond grid."""
    rng = np.random.default_rng(seed)
    scans = []
    for k in range(n_frames):
        t = round(1.0 + k * frame_dt_s, 3)
        east_seen = 4.0 + 0.25 * k  # the sonar's footprint sweeps east
        dets = []
        for pos in TRUTHS:
            if abs(pos[1] - east_seen) < 6.0 and rng.random() < 0.8:
                dets.append(LocalizedDetection(t, pos + rng.normal(0.0, 0.3, 3), 0.09 * np.eye(3),
                                               float(np.clip(rng.normal(0.6, 0.1), 0.05, 0.95)), "opi"))
        if rng.random() < 0.2:
            dets.append(LocalizedDetection(t, np.array([rng.uniform(-15, 5), rng.uniform(5, 30), 4.0]),
                                           0.09 * np.eye(3), float(rng.uniform(0.05, 0.4)), "opi"))
        scans.append((t, dets))
    return scans


def _delivered(scans, seed: int = 5):
    """(arrival time, report) of every detection: sent in frame order one packet after another
    (50 ms each) from the frame time on, so they arrive late and split across ticks."""
    rng = np.random.default_rng(seed)
    out, modem_free, det_id = [], 0.0, 0
    for t, dets in scans:
        for d in dets:
            modem_free = max(modem_free, t + rng.uniform(0.0, 0.3)) + 0.05
            packet = DetectionReport.from_localized(d, det_id, ORIGIN, EPOCH_S, CLASSES).encode()
            out.append((modem_free, decode(packet)))
            det_id += 1
    return out


def test_surface_world_model_keeps_the_onboard_objects_from_the_same_detections():
    """The onboard PMHA takes each frame's detections as the link carries them (through the
    32-byte format: positions within 1 cm, scores within 1/510); the surface model takes the
    same reports late, one packet after another, split across ticks, and must end with the
    same world, to floating-point precision."""
    cfg = WorldModelConfig()
    scans = _scans()
    delivered = _delivered(scans)
    received = [r.to_localized(ORIGIN, EPOCH_S, CLASSES) for _, r in delivered]
    sent = [d for _, dets in scans for d in dets]
    assert max(np.abs(a.pos_ned - b.pos_ned).max() for a, b in zip(sent, received)) < 0.01
    assert max(abs(a.class_score - b.class_score) for a, b in zip(sent, received)) <= 1 / 510 + 1e-12
    onboard = PMHA(cfg, region_ned=REGION)
    k = 0
    for t, dets in scans:
        if dets:  # the surface sees only frames with detections, without the field of view
            scan = received[k:k + len(dets)]  # anchors near a report of the scan were in view
            onboard.update(t, scan, near_reports(scan, cfg.gate_mahalanobis2))
            k += len(dets)
    surface = SurfaceWorldModel(cfg, REGION, ORIGIN, EPOCH_S, CLASSES, hold_s=5.0)
    k, t_now = 0, 0.0
    while k < len(delivered):
        t_now += 0.1
        while k < len(delivered) and delivered[k][0] <= t_now:
            surface.receive(delivered[k][1])
            k += 1
        surface.flush(t_now)
    surface.flush(t_now, final=True)
    # reports did arrive late: after the next frame was taken, several ticks after their own
    assert max(t - (r.t_unix_s - EPOCH_S) for t, r in delivered) > 0.4
    assert surface.n_too_late == 0
    assert surface.n_scans == sum(1 for _, d in scans if d)
    a, b = onboard.world_model(), surface.world_model()
    assert len(a) == len(b) >= 6
    for oa, ob in zip(a, b):
        assert (oa.id, oa.n_detections) == (ob.id, ob.n_detections)
        np.testing.assert_allclose(ob.pos_ned, oa.pos_ned, atol=1e-9)
        np.testing.assert_allclose(ob.class_pmf, oa.class_pmf, atol=1e-12)
    # and they are the true OPIs
    est = np.array([o.pos_ned for o in b])
    assert all(np.min(np.linalg.norm(est - p, axis=1)) < 0.5 for p in TRUTHS)


def _one_object_split_reports(n_frames: int = 300):
    """One OPI at (-8, 22, 4) m seen every frame (3 Hz) by the AUV, its reports alternating
    0.2 m north and south of it (0.3 m sigma): what the twin objects (two anchors for one OPI)
    fed on before a scan's own reports placed the fan."""
    truth = np.array([-8.0, 22.0, 4.0])
    reports = []
    for k in range(n_frames):
        t = round(1.0 + k / 3.0, 3)
        pos = truth + np.array([0.2 if k % 2 else -0.2, 0.0, 0.0])
        det = LocalizedDetection(t, pos, 0.09 * np.eye(3), 0.6, "opi")
        reports.append(decode(DetectionReport.from_localized(det, k, ORIGIN, EPOCH_S, CLASSES).encode()))
    return truth, reports


def test_an_anchor_near_a_report_of_the_scan_pays_for_its_miss_so_one_object_has_no_twin():
    """Without a known field of view (no USBL track), anchors are at the visibility floor;
    one object's reports split between two anchors 0.4 m apart would then fit better than
    one anchor at almost no miss cost. A report of the scan shows the fan covered its
    neighbourhood, so the anchor it is not assigned to pays (1 - p_detect): one object."""
    truth, reports = _one_object_split_reports()
    surface = SurfaceWorldModel(WorldModelConfig(), REGION, ORIGIN, EPOCH_S, CLASSES)
    for r in reports:
        surface.receive(r)
        surface.flush(r.t_unix_s - EPOCH_S)
    surface.flush(0.0, final=True)
    objects = surface.world_model()
    assert len(objects) == 1
    assert np.linalg.norm(objects[0].pos_ned - truth) < 0.05
    # the same reports into a PMHA blind to the scan's own evidence split the object in two
    # anchors in its best world; the reported world model's duplicate test joins them again
    blind = PMHA(WorldModelConfig(), region_ned=REGION)
    for r in reports:
        det = r.to_localized(ORIGIN, EPOCH_S, CLASSES)
        blind.update(det.t_s, [det], unseen)
    assert len(blind.hypotheses[0].anchors) == 2
    assert len(blind.world_model()) == 1
    joined = blind.world_model()[0]
    assert joined.n_detections == sum(a.n_detections for a in blind.hypotheses[0].anchors)
    assert {joined.id, *joined.merged_ids} == {a.id for a in blind.hypotheses[0].anchors}
    assert joined.to_dict()["merged_ids"] == list(joined.merged_ids)
    assert np.linalg.norm(blind.world_model()[0].pos_ned - truth) < 0.05
    no_join = PMHA(WorldModelConfig(duplicate_mahalanobis2=None), region_ned=REGION)
    for r in reports:
        det = r.to_localized(ORIGIN, EPOCH_S, CLASSES)
        no_join.update(det.t_s, [det], unseen)
    assert len(no_join.world_model()) == 2


def test_near_reports_marks_points_within_the_gate_of_a_report():
    """(points within the squared Mahalanobis gate of some report) = 1, else 0."""
    r = [LocalizedDetection(0.0, np.array([0.0, 0.0, 0.0]), np.diag([1.0, 4.0, 1.0]), 0.5, "opi"),
         LocalizedDetection(0.0, np.array([10.0, 0.0, 0.0]), np.eye(3), 0.5, "opi")]
    v = near_reports(r, 9.0)
    pts = np.array([[2.9, 0, 0], [3.1, 0, 0], [0, 5.9, 0], [0, 6.1, 0], [10, 0, 2.9], [5, 0, 0]], float)
    np.testing.assert_array_equal(v(pts), [1, 0, 1, 0, 1, 0])
    assert near_reports([], 9.0)(pts).tolist() == [0.0] * 6


def test_a_report_after_a_later_scan_is_counted_too_late_and_scans_wait_for_their_frame():
    cfg = WorldModelConfig()
    surface = SurfaceWorldModel(cfg, REGION, ORIGIN, EPOCH_S, CLASSES, hold_s=5.0)

    def report(t, i):
        d = LocalizedDetection(t, TRUTHS[i], 0.09 * np.eye(3), 0.7, "opi")
        return decode(DetectionReport.from_localized(d, i, ORIGIN, EPOCH_S, CLASSES).encode())

    surface.receive(report(1.0, 0))
    assert surface.flush(1.5) == 0  # the frame may still have reports on the way
    assert surface.flush(6.0) == 1  # held hold_s at most
    surface.receive(report(2.0, 1))
    surface.receive(report(3.0, 2))
    assert surface.flush(3.1) == 1  # frame 2.0 is complete once a later frame arrives
    surface.receive(report(2.0, 3))  # its report arriving after that
    assert surface.n_too_late == 1
    assert surface.flush(3.2, final=True) == 1
    assert surface.n_scans == 3 and surface.pmha.t_s == 3.0


def test_fix_track_gives_position_and_course_of_a_straight_run():
    track = FixTrack(window_s=5.0, min_fixes=4)
    v = np.array([0.3, 0.4, 0.0])  # 0.5 m/s, course atan2(0.4, 0.3)
    for t in np.arange(0.0, 20.0, 1.0):
        track.add(t, np.array([1.0, 2.0, 2.0]) + v * t)
    pos, course = track.pose_at(12.3)
    np.testing.assert_allclose(pos, [1.0 + 0.3 * 12.3, 2.0 + 0.4 * 12.3, 2.0], atol=1e-9)
    assert course == pytest.approx(np.arctan2(0.4, 0.3))
    assert track.pose_at(40.0) is None  # no fixes near
    still = FixTrack()
    for t in range(10):
        still.add(t, [0.0, 0.0, 2.0])
    assert still.pose_at(5.0) is None  # no course without travel


def test_footprint_sees_ahead_not_behind_and_shrinks_by_its_margin():
    fp = SonarFootprint((0.5, 0.0, 0.2), (0.0, np.radians(15.0), 0.0), 1.0, 30.0, np.radians(130.0),
                        np.radians(20.0), margin_m=-2.0)
    visible = fp.visibility((np.array([0.0, 0.0, 2.0]), np.pi / 2))  # heading east at 2 m depth
    pts = np.array([[0.0, 10.0, 4.0], [0.0, -10.0, 4.0], [0.0, 29.5, 4.0]])  # ahead, behind, at the far edge
    assert list(visible(pts)) == [True, False, False]
    assert list(fp.visibility(None)(pts)) == [False, False, False]
