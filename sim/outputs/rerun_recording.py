"""Rerun recording of a mission: 3-D scene, vehicle pose, true and estimated paths,
FLS fan frames with ground-truth boxes and detections, navigation errors, world model, and
the scanning sonar's scan building up ping by ping with the features of each position fix.

Target tracking (paper 004) on the fan image ``sonar/fan``: ``sonar/fan/roi/<mode>`` the
polar region of interest of each sonar-using filter (``fused``, ``sonar``) at the ping, as an
outline (its range and azimuth bounds, :meth:`autonomy.tracking.roi.PolarRoi.outline`);
``sonar/fan/clusters`` the detector's clusters (green: taken by the fused filter, yellow:
inside its ROI and of the target's size, grey: refused).

Scanning-sonar entities (``<name>`` the sensor entry's name):

* ``world/msis/<name>/ping``: each ping's samples at or above ``msis_point_threshold`` as
  NED points along the beam from the head's true pose at the ping (max-pooled to at most
  ``msis_max_points`` bins), coloured by intensity; ``world/msis/<name>/beam`` the beam axis;
* ``sonar/msis/<name>/scan``: the Cartesian scan image in the head frame
  (:class:`sim.sensors.msis_scan.ScanImage`, each ping overwriting its head angle's rows),
  re-logged every ``msis_image_every`` pings;
* ``world/msis/<name>/fix/{points,circle,segments,segments_95,position}``: at each position
  fix, the echo points it used, the fitted circle or the wall segments with their 95 % rho
  bands (navigation frame of the estimate before the fix) and the fixed position.

The true, estimated and other vehicles' paths are ``world/path/<name>/<k>``: line strips of
at most ``path_chunk_points`` points each, the last one re-logged every ``path_every_s`` as it
grows, so the recording and the recorder's memory grow linearly with mission time (re-logging
the whole path each time grew the file with the square of it).

The per-step series (``world/vehicle`` and ``world/vehicles/<name>`` poses, ``nav/*`` errors, at
the step rate) are kept in arrays and sent as column chunks of ``series_rows`` rows
(:mod:`sim.outputs.rerun_columns`), not one ``rr.log`` row per step in the stream's batcher;
the rest is logged row-wise and the batcher flushed every ``flush_every_s`` simulated seconds.

An observer of the mission loop; it streams to an ``.rrd`` file as the mission runs.
"""

from __future__ import annotations

import os
from datetime import timedelta
from pathlib import Path

import cv2
import numpy as np

from autonomy.frames import quat_from_rot, rot_from_euler
from typing import Any

from autonomy.messages import PositionFixMsg
from autonomy.sonar_geometry import FanGeometry
from autonomy.tracking.onboard import TrackingFrameResult
from autonomy.tracking.roi import PolarRoi
from sim.outputs.rerun_columns import PoseColumn, ScalarColumn
from sim.events.records import InspectionGoal, MissionInfo, MissionSummary, ObserverBase, PerceptionResult, StepRecord
from sim.sensors.fls import FlsRender
from sim.sensors.msis import MsisRender
from sim.sensors.msis_scan import ScanImage
from sim.scene.target_meshes import target_mesh


# The stream's batcher holds every logged row until it cuts a chunk per entity at a flush
# (rerun's default: every 0.2 s of wall clock). Many small chunks cost memory (the file sink keeps
# each chunk's entry for the footer manifest until the end), and rows held for long cost memory
# in proportion to the run's speed (10 s of wall clock is 120 simulated s at 12x real time, 300 s
# at 30x). The recorder flushes every ``flush_every_s`` of simulated time (without waiting for
# the write), so what the batcher holds is bounded in simulated time whatever the run's speed;
# the wall-clock tick and the byte limit are backstops.
RECORDING_FLUSH_TICK_S = 10.0
RECORDING_FLUSH_BYTES = 8 * 2**20


# rerun's bindings (and pyarrow under them) allocate with mimalloc, which by default hands freed
# pages back to the system only after a delay and only when the freeing thread allocates again;
# with the stream's threads freeing each flushed chunk, the recording process's resident memory
# grew about 25 MB per simulated hour (outside Python and outside glibc's heaps) and stayed flat
# with these two options. mimalloc reads them when the library loads, so they are set here,
# before the recorder first imports rerun (a value already in the environment is kept).
MIMALLOC_OPTIONS = {"MIMALLOC_PURGE_DELAY": "0", "MIMALLOC_PURGE_DECOMMITS": "1"}
for _key, _value in MIMALLOC_OPTIONS.items():
    os.environ.setdefault(_key, _value)


class _GrowingPath:
    """A path logged as consecutive line strips ``<entity>/0``, ``<entity>/1``, ... of at most
    ``chunk_points`` points (each strip starts at the previous one's last point); only the
    strip still growing (and one filled since the last :meth:`log`) is kept and logged."""

    def __init__(self, entity: str, color: list[int], chunk_points: int) -> None:
        self.entity, self.color, self.chunk_points = entity, color, max(int(chunk_points), 2)
        self._points: list[list[float]] = []
        self._filled: list[tuple[int, list[list[float]]]] = []  # (index, points) not yet logged in full
        self._k = 0

    def append(self, pos_ned) -> None:
        """Add one (3,) NED position, m."""
        if len(self._points) >= self.chunk_points:
            self._filled.append((self._k, self._points))
            self._k += 1
            self._points = [self._points[-1]]
        self._points.append([float(x) for x in pos_ned])

    def log(self, rec, rr) -> None:
        """Log the strips filled since the last call, then the growing one."""
        for k, points in self._filled:
            rec.log(f"{self.entity}/{k}", rr.LineStrips3D([np.asarray(points)], colors=[self.color]))
        self._filled.clear()
        if len(self._points) > 1 or self._k == 0 and self._points:
            rec.log(f"{self.entity}/{self._k}", rr.LineStrips3D([np.asarray(self._points)], colors=[self.color]))


class RerunRecorder(ObserverBase):
    """Streams a mission into ``path`` (a rerun ``.rrd`` file).

    Args:
        path: output file.
        fls_every: log every n-th FLS frame (1 = all).
        fls_scale: resize factor for logged fan images (JPEG-encoded).
        path_every_s: how often the path line strips are re-logged.
        path_chunk_points: points per logged path strip (10 Hz steps: 60 s a strip).
        msis_point_threshold: raw intensity (uint8) from which a scanning-sonar sample is
            logged as a point.
        msis_max_points: at most this many (max-pooled) bins per ping.
        msis_image_every: re-log the scan image every n-th ping.
        msis_image_px: side of the logged scan image, px.
        series_rows: rows of the per-step series (vehicle poses, navigation errors) sent as one
            column chunk (10 Hz steps: 60 s), :mod:`sim.outputs.rerun_columns`.
        flush_every_s: simulated seconds between flushes of the stream's batcher (the rows it
            holds until then are the recorder's working memory).
        scorer: a :class:`sim.evaluation.detection_scoring.DetectionScorer` placed before this
            recorder among the observers: detections are coloured true (green) or false (red)
            by it; without one they are drawn in one neutral colour.
    """

    sonar_truth = True  # draws the frames' ground-truth boxes

    def __init__(self, path: Path, *, fls_every: int = 1, fls_scale: float = 0.5, path_every_s: float = 2.0,
                 path_chunk_points: int = 600, msis_point_threshold: int = 80, msis_max_points: int = 200, msis_image_every: int = 10,
                 msis_image_px: int = 256, series_rows: int = 600, flush_every_s: float = 30.0, scorer=None) -> None:
        import rerun as rr

        self.scorer = scorer
        self._rr = rr
        self.path = Path(path)
        self.fls_every = max(int(fls_every), 1)
        self.fls_scale = float(fls_scale)
        self.path_every_s = float(path_every_s)
        self._rec = rr.RecordingStream("auvsim", batcher_config=rr.ChunkBatcherConfig(
            flush_tick=timedelta(seconds=RECORDING_FLUSH_TICK_S), flush_num_bytes=RECORDING_FLUSH_BYTES))
        self.path_chunk_points = int(path_chunk_points)
        self._true = _GrowingPath("world/path/true", [40, 120, 220], self.path_chunk_points)
        self._est = _GrowingPath("world/path/estimated", [240, 140, 30], self.path_chunk_points)
        self._others: dict[str, _GrowingPath] = {}
        self.series_rows = max(int(series_rows), 1)
        self._series: dict[str, ScalarColumn | PoseColumn] = {}
        self._last_path_t = -np.inf
        self._t_step: float | None = None
        self._last_flush_t = 0.0
        self.flush_every_s = float(flush_every_s)
        self._n_fls = 0
        self._frame_logged = False
        self.msis_point_threshold = int(msis_point_threshold)
        self.msis_max_points = max(int(msis_max_points), 1)
        self.msis_image_every = max(int(msis_image_every), 1)
        self.msis_image_px = int(msis_image_px)
        self._scans: dict[str, ScanImage] = {}
        self._n_msis: dict[str, int] = {}
        self._msis_depth: dict[str, float] = {}
        self._fan_geometry: FanGeometry | None = None
        self._perception_sonar: str | None = None
        self._n_other_fls: dict[str, int] = {}

    # -- observer protocol -----------------------------------------------------------
    def on_start(self, info: MissionInfo) -> None:
        rr, rec = self._rr, self._rec
        self._perception_sonar = info.perception_sonar
        rec.save(self.path)
        rec.log("world", rr.ViewCoordinates.FRD, static=True)  # NED: x north, y east, z down
        scenario = info.scenario
        seabed = info.seabed
        cfg = scenario.world.seabed
        if seabed.is_mesh:
            mesh = seabed.terrain_mesh()
            rec.log("world/seabed", rr.Mesh3D(vertex_positions=mesh.vertices, triangle_indices=mesh.faces,
                                              albedo_factor=[140, 125, 100]), static=True)
        else:
            h = 0.5 * cfg.extent_m
            cn, ce = cfg.center_ne_m
            corners = np.array([[cn - h, ce - h], [cn + h, ce - h], [cn + h, ce + h], [cn - h, ce + h]])
            depth = seabed.depth_at(corners[:, 0], corners[:, 1])
            rec.log("world/seabed", rr.Mesh3D(vertex_positions=np.c_[corners, depth], triangle_indices=[[0, 1, 2], [0, 2, 3]],
                                              albedo_factor=[140, 125, 100]), static=True)
        for tcfg, obj in zip(scenario.world.targets, info.objects):
            mesh = target_mesh(tcfg)
            R = rot_from_euler(*np.deg2rad(tcfg.rpy_deg))
            verts = mesh.vertices @ R.T + np.asarray(tcfg.pos_ned)
            color = [230, 150, 30] if obj.is_target else [128, 128, 128]
            rec.log(f"world/objects/{obj.name}", rr.Mesh3D(vertex_positions=verts, triangle_indices=mesh.faces,
                                                           albedo_factor=color), static=True)
        env = info.vehicle_envelope_m
        rec.log("world/vehicle/hull", rr.Boxes3D(half_sizes=[0.5 * np.asarray(env)], colors=[[240, 220, 40]]), static=True)
        for name, env in info.vehicle_envelopes_m.items():  # extra vehicles (the surface buoy)
            rec.log(f"world/vehicles/{name}/hull", rr.Boxes3D(half_sizes=[0.5 * np.asarray(env)],
                                                              colors=[[60, 200, 90]]), static=True)
        rec.log("world/waypoints", rr.LineStrips3D([np.c_[info.waypoints_ne, np.full(len(info.waypoints_ne), 0.0)]],
                                                   colors=[[150, 150, 150]]), static=True)

    def on_step(self, r: StepRecord) -> None:
        t = self._t_step = r.t_s
        tr = r.truth
        self._pose("world/vehicle", t, tr.pos_ned, tr.R_nb)
        self._true.append(tr.pos_ned)
        self._est.append(r.nav.pos_ned)
        self._scalar("nav/horizontal_error_m", t, float(np.linalg.norm(tr.pos_ned[:2] - r.nav.pos_ned[:2])))
        self._scalar("nav/sigma_horizontal_m", t, float(np.sqrt(np.trace(r.nav.cov_pos_ned[:2, :2]))))
        self._scalar("nav/depth_error_m", t, float(tr.pos_ned[2] - r.nav.pos_ned[2]))
        for name, other in r.others.items():
            self._pose(f"world/vehicles/{name}", t, other.pos_ned, other.R_nb)
            if name not in self._others:
                self._others[name] = _GrowingPath(f"world/path/{name}", [60, 200, 90], self.path_chunk_points)
            self._others[name].append(other.pos_ned)
        if t - self._last_flush_t >= self.flush_every_s:
            self._last_flush_t = t
            self._rec.flush(timeout_sec=0.0)  # start the flush, do not wait for the write
        if r.t_s - self._last_path_t >= self.path_every_s:
            self._last_path_t = t
            self._rec.set_time("sim_time", duration=t)
            self._log_paths()

    def _pose(self, entity: str, t_s: float, pos_ned, R_nb) -> None:
        col = self._series.get(entity)
        if col is None:
            col = self._series[entity] = PoseColumn(entity, self.series_rows)
        col.append(self._rec, self._rr, t_s, [*pos_ned, *_xyzw(quat_from_rot(R_nb))])

    def _scalar(self, entity: str, t_s: float, value: float) -> None:
        col = self._series.get(entity)
        if col is None:
            col = self._series[entity] = ScalarColumn(entity, self.series_rows)
        col.append(self._rec, self._rr, t_s, value)

    def _log_paths(self) -> None:
        rr, rec = self._rr, self._rec
        for path in (*self._others.values(), self._true, self._est):
            path.log(rec, rr)

    def on_message(self, name: str, msg: Any) -> None:
        if isinstance(msg, FlsRender) and self._perception_sonar not in (None, name):
            self._on_other_sonar_frame(name, msg)
        elif isinstance(msg, FlsRender):
            self._on_sonar_frame(msg)
        elif isinstance(msg, PerceptionResult):
            self._on_perception(msg)
        elif isinstance(msg, TrackingFrameResult):
            self._on_tracking(msg)
        elif isinstance(msg, MsisRender):
            self._on_msis_ping(name, msg)
        elif isinstance(msg, PositionFixMsg):
            self._on_position_fix(name, msg)
        elif isinstance(msg, InspectionGoal):
            self._on_inspection_goal(msg)

    def _on_inspection_goal(self, goal: InspectionGoal) -> None:
        """The inspection planner's goal: the leg being flown (a red arrow at the survey depth of
        the vehicle's estimate) and a text line naming the phase, the object and the tour."""
        rr, rec = self._rr, self._rec
        rec.set_time("sim_time", duration=goal.t_s)
        if goal.start_ne_m is not None and goal.end_ne_m is not None:
            z = float(self._est._points[-1][2]) if self._est._points else 0.0
            s = np.array([*goal.start_ne_m, z])
            rec.log("world/inspection/goal", rr.Arrows3D(origins=[s], vectors=[np.array([*goal.end_ne_m, z]) - s],
                                                         colors=[[230, 40, 40]], labels=[f"inspect {goal.object_id}"]))
        else:
            rec.log("world/inspection/goal", rr.Clear(recursive=False))
        tour = " -> ".join(str(i) for i in goal.tour) or "none"
        leg = f", leg to object {goal.object_id}" if goal.object_id is not None else ""
        rec.log("inspection/goal", rr.TextLog(f"{goal.phase}{leg}; tour after it: {tour}"))

    def _on_msis_ping(self, name: str, render: MsisRender) -> None:
        rr, rec = self._rr, self._rec
        ping, truth = render.ping, render.truth
        rec.set_time("sim_time", duration=ping.t_s)
        x = np.asarray(ping.intensity)
        n = len(x)
        f = -(-n // self.msis_max_points)  # bins pooled per logged point
        m = n // f
        pooled = x[:m * f].reshape(m, f).max(axis=1)
        r = (np.arange(m) * f + 0.5 * f) * ping.sample_spacing_m
        u = np.asarray(truth.R_ns, dtype=float)[:, 0]  # beam axis, NED
        head = np.asarray(truth.pos_ned, dtype=float)
        self._msis_depth[name] = float(head[2])
        keep = pooled >= self.msis_point_threshold
        base = f"world/msis/{name}"
        if keep.any():
            v = pooled[keep]
            colors = cv2.applyColorMap(v.reshape(-1, 1), cv2.COLORMAP_INFERNO)[:, 0, ::-1]
            rec.log(f"{base}/ping", rr.Points3D(head[None, :] + r[keep, None] * u[None, :], colors=colors, radii=0.03))
        else:
            rec.log(f"{base}/ping", rr.Clear(recursive=False))
        rec.log(f"{base}/beam", rr.LineStrips3D([np.array([head, head + n * ping.sample_spacing_m * u])],
                                                colors=[[80, 200, 255]]))
        scan = self._scans.get(name)
        if scan is None or scan.n_samples != n or scan.sample_spacing_m != ping.sample_spacing_m:
            scan = self._scans[name] = ScanImage(n, ping.sample_spacing_m, self.msis_image_px)
        scan.add(render)
        scan.poses.clear()  # the recording keeps no per-ping poses
        k = self._n_msis[name] = self._n_msis.get(name, 0) + 1
        if not (k - 1) % self.msis_image_every:
            ok, jpg = cv2.imencode(".jpg", scan.cartesian(), [cv2.IMWRITE_JPEG_QUALITY, 85])
            if ok:
                rec.log(f"sonar/msis/{name}/scan", rr.EncodedImage(contents=jpg.tobytes(), media_type="image/jpeg"))

    def _on_position_fix(self, name: str, fix: PositionFixMsg) -> None:
        rr, rec = self._rr, self._rec
        rec.set_time("sim_time", duration=fix.t_s)
        z = self._msis_depth.get(name, 0.0)
        base = f"world/msis/{name}/fix"
        rec.log(f"{base}/position", rr.Points3D([[*np.asarray(fix.pos_ne_m, float), z]], colors=[[40, 220, 40]],
                                                radii=0.08, labels=[fix.source]))
        rec.log(f"nav/{name}_fix_sigma_m", rr.Scalars(float(np.sqrt(np.trace(fix.cov_ne_m2)))))
        if fix.points_ne_m is not None and len(fix.points_ne_m):
            p = np.asarray(fix.points_ne_m, float)
            rec.log(f"{base}/points", rr.Points3D(np.c_[p, np.full(len(p), z)], colors=[[255, 230, 90]], radii=0.04))
        if fix.circle_ne_m is not None:
            cn, ce, rad = np.asarray(fix.circle_ne_m, float)
            a = np.linspace(0.0, 2.0 * np.pi, 121)
            rec.log(f"{base}/circle", rr.LineStrips3D([np.c_[cn + rad * np.cos(a), ce + rad * np.sin(a),
                                                             np.full(len(a), z)]], colors=[[230, 40, 40]]))
        if fix.segments_ne_m is not None and len(fix.segments_ne_m):
            seg = np.asarray(fix.segments_ne_m, float)  # (k, 2, 2)
            d = seg[:, 1] - seg[:, 0]
            nrm = np.c_[-d[:, 1], d[:, 0]] / np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-9)[:, None]
            lift = lambda q: np.concatenate([q, np.full((*q.shape[:-1], 1), z)], axis=-1)  # noqa: E731
            rec.log(f"{base}/segments", rr.LineStrips3D(lift(seg), colors=[[230, 40, 40]]))
            if fix.segments_rho95_m is not None:
                off = (np.asarray(fix.segments_rho95_m, float)[:, None] * nrm)[:, None, :]
                bands = np.concatenate([seg + off, seg - off])
                rec.log(f"{base}/segments_95", rr.LineStrips3D(lift(bands), colors=[[230, 120, 120]]))

    def _on_sonar_frame(self, render: FlsRender) -> None:
        rr, rec = self._rr, self._rec
        self._n_fls += 1
        self._frame_logged = not (self._n_fls - 1) % self.fls_every
        if not self._frame_logged:
            return
        rec.set_time("sim_time", duration=render.frame.t_s)
        self._fan_geometry = render.frame.geometry
        fan = render.frame.fan
        s = self.fls_scale
        img = cv2.resize(fan, None, fx=s, fy=s, interpolation=cv2.INTER_AREA) if s != 1.0 else fan
        ok, jpg = cv2.imencode(".jpg", img, [cv2.IMWRITE_JPEG_QUALITY, 80])
        if ok:
            rec.log("sonar/fan", rr.EncodedImage(contents=jpg.tobytes(), media_type="image/jpeg"))
        gt = [o for o in render.truth.objects if o.visible]
        if gt:
            rec.log("sonar/fan/ground_truth", rr.Boxes2D(
                array=np.array([o.bbox_xyxy for o in gt]) * s, array_format=rr.Box2DFormat.XYXY,
                labels=[o.name for o in gt], colors=[[40, 220, 40]]))
        else:
            rec.log("sonar/fan/ground_truth", rr.Clear(recursive=False))

    def _on_other_sonar_frame(self, name: str, render: FlsRender) -> None:
        """A forward-looking sonar perception does not read: its fan under ``sonar/<name>/fan``
        (every ``fls_every``-th frame of its own), not over the perception sonar's."""
        k = self._n_other_fls[name] = self._n_other_fls.get(name, 0) + 1
        if (k - 1) % self.fls_every:
            return
        rr, rec = self._rr, self._rec
        rec.set_time("sim_time", duration=render.frame.t_s)
        s = self.fls_scale
        fan = render.frame.fan
        img = cv2.resize(fan, None, fx=s, fy=s, interpolation=cv2.INTER_AREA) if s != 1.0 else fan
        ok, jpg = cv2.imencode(".jpg", img, [cv2.IMWRITE_JPEG_QUALITY, 80])
        if ok:
            rec.log(f"sonar/{name}/fan", rr.EncodedImage(contents=jpg.tobytes(), media_type="image/jpeg"))

    def _on_perception(self, res: PerceptionResult) -> None:
        rr, rec = self._rr, self._rec
        rec.set_time("sim_time", duration=res.t_s)
        if res.world_objects:
            pos = np.array([o.pos_ned for o in res.world_objects])
            half = np.array([2.0 * np.sqrt(np.clip(np.diag(o.cov_ned), 1e-6, None)) for o in res.world_objects])
            rec.log("world/world_model", rr.Ellipsoids3D(centers=pos, half_sizes=half, colors=[[220, 40, 40]],
                                                         labels=[str(o.id) for o in res.world_objects]))
        if not self._frame_logged:
            return
        s = self.fls_scale
        if res.detections:
            rec.log("sonar/fan/detections", rr.Boxes2D(
                array=np.array([d.box_xyxy_px for d in res.detections]) * s, array_format=rr.Box2DFormat.XYXY,
                labels=[f"{d.class_name} {d.score:.2f}" for d in res.detections],
                colors=self._detection_colours(len(res.detections))))
        else:
            rec.log("sonar/fan/detections", rr.Clear(recursive=False))

    def _detection_colours(self, n: int) -> list[list[int]]:
        """Green/red by the scorer's verdict on the latest frame; amber without a scorer."""
        verdict = self.scorer.last_true_detection if self.scorer is not None else ()
        if len(verdict) != n:
            return [[240, 170, 30]] * n
        return [[40, 220, 40] if ok_ else [230, 40, 40] for ok_ in verdict]

    def _on_tracking(self, res: TrackingFrameResult) -> None:
        """ROI outlines and the clusters of a processed frame, on its fan image."""
        geo = self._fan_geometry
        if geo is None:
            return
        rr, rec = self._rr, self._rec
        rec.set_time("sim_time", duration=res.t_s)
        s = self.fls_scale
        for mode, colour in ROI_COLOURS.items():
            roi = res.roi.get(mode)
            if roi is None:
                rec.log(f"sonar/fan/roi/{mode}", rr.Clear(recursive=False))
                continue
            rec.log(f"sonar/fan/roi/{mode}", rr.LineStrips2D([roi_outline_px(roi, geo, s)], colors=[colour],
                                                             labels=[f"ROI {mode}"]))
        if not res.candidates:
            rec.log("sonar/fan/clusters", rr.Clear(recursive=False))
            return
        chosen, acc = res.chosen.get("fused"), res.accepted.get("fused", np.zeros(len(res.candidates), dtype=bool))
        colours = [[40, 220, 40] if c is chosen else [240, 200, 40] if ok else [150, 150, 150]
                   for c, ok in zip(res.candidates, acc)]
        rec.log("sonar/fan/clusters", rr.Boxes2D(array=np.array([c.box_xyxy_px for c in res.candidates]) * s,
                                                 array_format=rr.Box2DFormat.XYXY, colors=colours))

    def on_end(self, summary: MissionSummary) -> None:
        rec = self._rec
        if self._t_step is not None:
            rec.set_time("sim_time", duration=self._t_step)
        self._log_paths()
        for col in self._series.values():
            col.send(rec, self._rr)
        rec.flush()
        rec.disconnect()


ROI_COLOURS = {"fused": [60, 200, 255], "sonar": [255, 120, 40]}  # sonar-using filters and their ROI colours


def roi_outline_px(roi: PolarRoi, geometry: FanGeometry, scale: float = 1.0) -> np.ndarray:
    """Outline (k, 2) of a polar ROI in fan-image pixels (x, y), times ``scale`` (the logged
    image's resize factor)."""
    rng_az = roi.outline()
    x, y = geometry.polar_to_pixel(rng_az[:, 0], rng_az[:, 1])
    return np.c_[x, y] * scale


def _xyzw(q_wxyz: np.ndarray) -> list[float]:
    w, x, y, z = q_wxyz
    return [x, y, z, w]
