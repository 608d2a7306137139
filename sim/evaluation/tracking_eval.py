"""Scoring the target trackers of a run against the movers' true trajectories (paper 004).

:class:`TrackingEvaluation` is a mission observer built with the run's tracking stack, the
true trajectory of the tracked mover (and its bubble plume) and the sonar's geometry. At each
autonomy tick it records the 3-D position error of the three filters (sonar only, USBL
only, fused), whether the sonar-only filter had a detection that tick ("sonar when
available", the paper's fourth error set) and whether the fused filter took a sonar
detection (the fraction of filter steps with sonar, paper: ~30 %), and whether the target
truly lies in the sonar's field of view and how far it is from the vehicle.

Each sonar frame's clusters are labelled against truth in the sonar's (range, azimuth) plane
(points at ``(r cos a, r sin a)``): a cluster within ``match_m`` of the target's body (the
segment of its long axis: a diver's echo may be its legs or its head alone, and a diver cut
by the edge of the view shows only the part inside) is the target, else one within
``match_m`` of a live bubble is a bubble, else clutter; the
gating figures are the fraction of bubble clusters the fused filter's gate refuses (outside
its ROI or failing the size gate; the window alone: ``bubble_outside_roi_fraction``) and of
target clusters it accepts (kept), and, with the
in-ROI scoring, the fraction of bubble clusters not chosen as the target and of frames
showing the target whose target cluster was chosen; each bubble cluster the gate accepted is
recorded (``roi.accepted_bubbles``: time, where, its shape cues and score, whether chosen,
its place in the ROI) to audit. The sonar pose at ping time is the
truth at the nearest tick (the vehicle moves < 0.1 m between ticks).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from sim.events.records import ObserverBase
import numpy as np
from numpy.typing import NDArray
from scipy.stats import chi2

from autonomy.tracking.onboard import MODES, TrackingStack
from sim.scene.movers import DIVER_HALF_LENGTH_M, DIVER_RADIUS_M, VEHICLE_HALF_SIZE_M
from sim.evaluation.nees import horizontal_nees  # noqa: F401 (also imported from here)

FloatArray = NDArray[np.float64]
ERROR_SETS = ("sonar", "sonar_when_available", "usbl", "fused")
NEES2_95 = float(chi2.ppf(0.95, 2))  # chi-square(2) 95 % point
_COLS = 14


class TrackingEvaluation(ObserverBase):
    """Mission observer scoring the tracking stack.

    Args:
        stack: the run's tracking stack (read only).
        target_pos_at: t_s -> (3,) true NED position of the tracked mover, m.
        bubbles_at: t_s -> (k, 3) NED positions of its live bubbles (or None: no plume).
        target_axis_at: t_s -> (2, 3) NED ends of the mover's long body axis, m (None: the
            position alone).
        sonar_mount_body_m, R_bs: (3,) FRD sonar position, m, and (3, 3) sonar->body rotation.
        fov_rad, window_m, vertical_beam_rad: the sonar's field of view (azimuth, range window
            (near, far) m, vertical beam).
        warmup_s: ticks before this time are not scored (the filters start), s.
        match_m: cluster-to-truth labelling distance, m.
        breaths_at: t_s -> (ages (K,) s, bubble positions (K, m, 3) NED m, in water (K, m))
            of the plume's breaths (None: no plume view figures).
        plume_apart_m: how far (in the sonar's plane) a bubble must lie from the target's
            body axis for the detector to see it as a cluster of its own (the target's half
            width, the detector's clustering distance and the bubble's size), m.
    """

    sonar_truth = False  # reads no sonar ground truth (the sonar need not compute it)

    def __init__(self, stack: TrackingStack, target_pos_at, bubbles_at, sonar_mount_body_m: FloatArray,
                 R_bs: FloatArray, fov_rad: float, window_m: tuple[float, float], vertical_beam_rad: float,
                 warmup_s: float = 10.0, match_m: float = 0.6, target_axis_at=None, breaths_at=None,
                 plume_apart_m: float = 0.76) -> None:
        self.stack = stack
        self.target_pos_at = target_pos_at
        self.target_axis_at = target_axis_at or (lambda t: np.repeat(np.atleast_2d(target_pos_at(t)), 2, axis=0))
        self.bubbles_at = bubbles_at
        self.mount = np.asarray(sonar_mount_body_m, dtype=float)
        self.R_bs = np.asarray(R_bs, dtype=float)
        self.fov_rad, self.window_m, self.vbeam_rad = float(fov_rad), tuple(window_m), float(vertical_beam_rad)
        self.warmup_s, self.match_m = float(warmup_s), float(match_m)
        self.rows: list[tuple[float, ...]] = []  # t, err x3 modes, sonar_avail, fused_sonar, in_fov, distance,
        # horizontal err x3, horizontal NEES x3
        self.primary_est_ned: list[tuple[float, float, float, float]] = []  # t, NED of the primary filter's estimate
        self._poses: dict[int, tuple[FloatArray, FloatArray]] = {}
        self._n_results = 0
        self.n_bubble = self.n_bubble_rejected = self.n_target = self.n_target_kept = 0
        self.n_bubble_not_chosen = self.n_frames_with_target = self.n_target_chosen = 0
        self.n_bubble_outside = 0
        self.accepted_bubbles: list[dict[str, float]] = []  # each bubble cluster the fused gate accepted
        self.breaths_at, self.plume_apart_m = breaths_at, float(plume_apart_m)
        self.n_frames = self.n_breath_in_view = self.n_breath_apart = 0
        self._breath_view_age: dict[float, float] = {}  # release time -> oldest age seen in view
        self._breath_apart_m: list[float] = []  # each in-view breath's nearest bubble to the body, per frame

    # observer interface
    def on_start(self, info: Any) -> None:
        pass

    def on_message(self, name: str, msg: Any) -> None:
        pass

    def on_end(self, summary: Any) -> None:
        pass

    def _sonar_polar(self, p_ned: FloatArray, pos: FloatArray, R_nb: FloatArray) -> FloatArray:
        """(k, 3) range, azimuth, elevation of NED points (k, 3) in the sonar frame."""
        rel = (np.atleast_2d(p_ned) - (pos + R_nb @ self.mount)) @ (R_nb @ self.R_bs)
        rng = np.linalg.norm(rel, axis=1)
        return np.stack([rng, np.arctan2(rel[:, 1], rel[:, 0]), np.arctan2(rel[:, 2], np.hypot(rel[:, 0], rel[:, 1]))],
                        axis=1)

    def on_step(self, rec: Any) -> None:
        t = float(rec.t_s)
        truth = rec.truth
        self._poses[int(round(t * 1000))] = (truth.pos_ned.copy(), truth.R_nb.copy())
        results = self.stack.results[self._n_results:]
        self._n_results = len(self.stack.results)
        for res in results:
            self._plume_view(res)
            self._label(res)
        tgt = np.asarray(self.target_pos_at(t), dtype=float)
        errs, errs_h, nees_h = [], [], []
        for m in MODES:
            est = self.stack.trackers[m].estimate(t)
            errs.append(float(np.linalg.norm(est[0][:3] - tgt)) if est is not None else math.nan)
            errs_h.append(float(np.linalg.norm(est[0][:2] - tgt[:2])) if est is not None else math.nan)
            nees_h.append(horizontal_nees(est[0][:2] - tgt[:2], est[1][:2, :2]) if est is not None else math.nan)
            if m == self.stack.cfg.mode and est is not None:
                self.primary_est_ned.append((t, *(float(v) for v in est[0][:3])))
        sonar_avail = any(r.chosen["sonar"] is not None for r in results)
        fused_sonar = any(r.chosen["fused"] is not None for r in results)
        r, a, e = self._sonar_polar(tgt, truth.pos_ned, truth.R_nb)[0]
        in_fov = (abs(a) <= 0.5 * self.fov_rad and self.window_m[0] <= r <= self.window_m[1]
                  and abs(e) <= 0.5 * self.vbeam_rad)
        self.rows.append((t, *errs, float(sonar_avail), float(fused_sonar), float(in_fov),
                          float(np.linalg.norm(tgt - truth.pos_ned)), *errs_h, *nees_h))

    def _pose_at(self, t_s: float) -> tuple[FloatArray, FloatArray]:
        pose = self._poses.get(int(round(t_s * 1000)))
        if pose is None:  # nearest recorded tick
            keys = np.array(list(self._poses))
            pose = self._poses[int(keys[np.argmin(np.abs(keys - t_s * 1000))])]
        return pose

    def _plane_xy(self, points: FloatArray, pos: FloatArray, R_nb: FloatArray) -> FloatArray:
        """(k, 2) NED points (k, 3) in the sonar's (range, azimuth) plane, m."""
        sp = self._sonar_polar(points, pos, R_nb)
        return np.c_[sp[:, 0] * np.cos(sp[:, 1]), sp[:, 0] * np.sin(sp[:, 1])]

    def _axis_distance(self, xy: FloatArray, t_s: float, pos: FloatArray, R_nb: FloatArray) -> FloatArray:
        """(k,) distance (m) of sonar-plane points (k, 2) to the target's body axis in that plane."""
        a, b = self._plane_xy(np.asarray(self.target_axis_at(t_s), dtype=float), pos, R_nb)
        ab = b - a
        u = np.clip((xy - a) @ ab / max(float(ab @ ab), 1e-12), 0.0, 1.0)
        return np.linalg.norm(xy - (a + u[:, None] * ab), axis=1)

    def _plume_view(self, res: Any) -> None:
        """Which breaths the sonar sees on this frame (a bubble inside its azimuth, range window
        and vertical beam) and whether all of those bubbles lie ``plume_apart_m`` or more from
        the target's body in the sonar's plane (so the detector could see the breath apart;
        an upper bound: breaths can still chain to the body through one another)."""
        if self.breaths_at is None:
            return
        self.n_frames += 1
        ages, pts, wet = self.breaths_at(res.t_s)
        if not len(ages):
            return
        pos, R_nb = self._pose_at(res.t_s)
        k, m = wet.shape
        flat = pts.reshape(-1, 3)
        r, a, e = self._sonar_polar(flat, pos, R_nb).T
        seen = (wet.ravel() & (np.abs(a) <= 0.5 * self.fov_rad) & (r >= self.window_m[0]) & (r <= self.window_m[1])
                & (np.abs(e) <= 0.5 * self.vbeam_rad)).reshape(k, m)
        if not seen.any():
            return
        d = np.where(seen.ravel(), self._axis_distance(self._plane_xy(flat, pos, R_nb), res.t_s, pos, R_nb),
                     np.inf).reshape(k, m).min(axis=1)
        in_view = seen.any(axis=1)
        for i in np.nonzero(in_view)[0]:
            key = round(res.t_s - float(ages[i]), 6)
            self._breath_view_age[key] = max(self._breath_view_age.get(key, 0.0), float(ages[i]))
            self._breath_apart_m.append(float(d[i]))
        self.n_breath_in_view += int(in_view.sum())
        self.n_breath_apart += int((in_view & (d >= self.plume_apart_m)).sum())

    def _label(self, res: Any) -> None:
        if not res.candidates or res.roi["fused"] is None:
            return
        pos, R_nb = self._pose_at(res.t_s)
        cr = np.array([c.range_m for c in res.candidates])
        ca = np.array([c.azimuth_rad for c in res.candidates])
        c_xy = np.c_[cr * np.cos(ca), cr * np.sin(ca)]

        d_tgt = self._axis_distance(c_xy, res.t_s, pos, R_nb)
        bub = self.bubbles_at(res.t_s) if self.bubbles_at is not None else None
        d_bub = (np.linalg.norm(c_xy[:, None, :] - self._plane_xy(bub, pos, R_nb)[None, :, :], axis=2).min(axis=1)
                 if bub is not None and len(bub) else np.full(len(cr), np.inf))
        is_tgt = d_tgt <= self.match_m
        is_bub = ~is_tgt & (d_bub <= self.match_m)
        inside = res.accepted["fused"]
        self.n_bubble_outside += int((is_bub & ~res.inside["fused"]).sum())
        chosen = np.array([c is res.chosen["fused"] for c in res.candidates])
        self.n_target += int(is_tgt.sum())
        self.n_target_kept += int((is_tgt & inside).sum())
        self.n_bubble += int(is_bub.sum())
        self.n_bubble_rejected += int((is_bub & ~inside).sum())
        self.n_bubble_not_chosen += int((is_bub & ~chosen).sum())
        self.n_frames_with_target += int(is_tgt.any())
        self.n_target_chosen += int((is_tgt & chosen).any())
        roi = res.roi["fused"]
        for i in np.nonzero(is_bub & inside)[0]:  # what each accepted bubble cluster was, for the audit
            self.accepted_bubbles.append({
                "t_s": round(float(res.t_s), 6), "range_m": float(cr[i]), "azimuth_deg": math.degrees(ca[i]),
                "score": float(res.candidates[i].score), "chosen": bool(chosen[i]),
                "body_distance_m": float(d_tgt[i]), "bubble_distance_m": float(d_bub[i]),
                # normalised: 0 at the ROI's centre, 1 on its corners' axes (autonomy.tracking.roi)
                "roi_centre_distance_normalised": float(roi.centre_distance(cr[i], ca[i])),
                "roi_half_range_m": roi.half_range_m, "roi_half_azimuth_deg": math.degrees(roi.half_azimuth_rad),
                "target_clusters_on_frame": int(is_tgt.sum()),
                **{k: (int(v[i]) if k == "n_contours" else float(v[i])) for k, v in res.features.items()}})

    # results
    def error_sets(self, horizontal: bool = False) -> dict[str, FloatArray]:
        """The four error sets (m) after the warm-up: each filter's error at every tick, and
        the sonar-only filter's at the ticks it had a detection; 3-D, or ``horizontal`` (north
        and east only: paper 004's GPS ground truth of a target in the vehicle's plane)."""
        a = np.array(self.rows, dtype=float).reshape(-1, _COLS)
        a = a[a[:, 0] >= self.warmup_s]
        c = 8 if horizontal else 1
        out = {"sonar": a[:, c], "usbl": a[:, c + 1], "fused": a[:, c + 2], "sonar_when_available": a[a[:, 4] > 0, c]}
        return {k: v[np.isfinite(v)] for k, v in out.items()}

    def metrics(self) -> dict[str, Any]:
        """Statistics of the error sets (m; 3-D under ``errors``, north-east under
        ``errors_horizontal``), sonar-step fraction, ROI gating, field of view."""
        a = np.array(self.rows, dtype=float).reshape(-1, _COLS)
        scored = a[a[:, 0] >= self.warmup_s]
        stats: dict[str, dict] = {}
        stats_h: dict[str, dict] = {}
        for out, horizontal in ((stats, False), (stats_h, True)):
            for k, v in self.error_sets(horizontal).items():
                out[k] = ({"n": int(v.size), "mean_m": float(v.mean()), "std_m": float(v.std()),
                           "median_m": float(np.median(v)), "p95_m": float(np.percentile(v, 95))} if v.size else
                          {"n": 0})
        return {
            "mode": self.stack.cfg.mode,
            "scored_from_s": self.warmup_s,
            "errors": stats,
            "errors_horizontal": stats_h,
            "fused_sonar_step_fraction": float(scored[:, 5].mean()) if len(scored) else math.nan,
            "roi": {"bubble_clusters": self.n_bubble, "bubble_rejected": self.n_bubble_rejected,
                    "target_kept": self.n_target_kept, "bubble_rejected_fraction":
                    self.n_bubble_rejected / self.n_bubble if self.n_bubble else math.nan,
                    "target_clusters": self.n_target, "target_kept_fraction":
                    self.n_target_kept / self.n_target if self.n_target else math.nan,
                    "bubble_outside_roi_fraction":
                    self.n_bubble_outside / self.n_bubble if self.n_bubble else math.nan,
                    "bubble_not_chosen_fraction": self.n_bubble_not_chosen / self.n_bubble if self.n_bubble else math.nan,
                    "target_chosen_fraction": self.n_target_chosen / self.n_frames_with_target
                    if self.n_frames_with_target else math.nan, "accepted_bubbles": list(self.accepted_bubbles)},
            "plume": self.plume_metrics(),
            "nees_horizontal": self.nees_metrics(),
            "target_in_fov_fraction": float(a[:, 6].mean()) if len(a) else math.nan,
            "min_distance_m": float(a[:, 7].min()) if len(a) else math.nan,
        }

    def nees_metrics(self) -> dict[str, dict[str, float]]:
        """Consistency of each filter after the warm-up: mean horizontal (north, east) NEES
        (2 for a consistent filter) and the fraction of ticks above the chi-square(2) 95 %
        point (0.05 for a consistent filter; both carried in each entry as ``consistent_mean``
        and ``consistent_above_95_fraction`` so metrics.json reads on its own) over ``n`` ticks;
        ticks are correlated, so these are figures to read, not a test."""
        a = np.array(self.rows, dtype=float).reshape(-1, _COLS)
        a = a[a[:, 0] >= self.warmup_s]
        out = {}
        for i, m in enumerate(MODES):
            v = a[:, 11 + i]
            v = v[np.isfinite(v)]
            out[m] = {"n": int(v.size), "mean": float(v.mean()) if v.size else math.nan,
                      "above_95_fraction": float(np.mean(v > NEES2_95)) if v.size else math.nan,
                      "consistent_mean": 2.0, "consistent_above_95_fraction": 0.05}
        return out

    def plume_metrics(self) -> dict[str, Any]:
        """What the sonar could see of the plume: sonar frames, (frame, breath) pairs with a
        bubble in view and those whose in-view bubbles all lie ``plume_apart_m`` or more from
        the target's body in the sonar's plane, breaths seen, how old a breath was when last
        in view (s: mean, max) and the median distance of each in-view breath's nearest
        bubble to the body (m)."""
        ages = np.array(list(self._breath_view_age.values()), dtype=float)
        apart = np.array(self._breath_apart_m, dtype=float)
        return {"frames": self.n_frames, "breath_frames_in_view": self.n_breath_in_view,
                "breath_frames_apart": self.n_breath_apart, "apart_m": self.plume_apart_m,
                "breaths_seen": int(ages.size),
                "last_in_view_age_mean_s": float(ages.mean()) if ages.size else math.nan,
                "last_in_view_age_max_s": float(ages.max()) if ages.size else math.nan,
                "nearest_to_body_median_m": float(np.median(apart)) if apart.size else math.nan}

    def plot(self, error_png: Path, box_png: Path, title: str = "") -> None:
        """Error over time (PNG) and the box plot of the four error sets (PNG)."""
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        a = np.array(self.rows, dtype=float).reshape(-1, _COLS)
        fig = Figure(figsize=(9, 4))
        FigureCanvasAgg(fig)
        ax = fig.add_subplot()
        for col, m, colour in ((1, "sonar only", "tab:orange"), (2, "USBL only", "tab:blue"),
                               (3, "fused", "tab:green")):
            ax.plot(a[:, 0], a[:, col], lw=1.0, label=m, color=colour)
        avail = a[:, 4] > 0
        ax.plot(a[avail, 0], a[avail, 1], ".", ms=2, color="tab:red", label="sonar when available")
        ax.axvline(self.warmup_s, color="0.6", ls=":", lw=0.8, label=f"scored from {self.warmup_s:g} s")
        ax.set_xlabel("time (s)")
        ax.set_ylabel("3-D position error (m)")
        ax.set_title(title or "target position error")
        ax.legend(loc="upper right", fontsize=8)
        ax.grid(alpha=0.3)
        fig.tight_layout()
        fig.savefig(error_png, dpi=110)
        error_boxplot_png(self.error_sets(), box_png, title or "error sets", ylabel="3-D position error (m)")


def error_boxplot_png(sets: dict[str, FloatArray], path: Path, title: str, ylabel: str = "position error (m)") -> None:
    """Box plot (PNG) of the four error sets (m), as paper 004 fig. 8 (whiskers 1.5 IQR, no fliers);
    ``ylabel`` says which error (3-D or horizontal)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6, 4))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ax.boxplot([sets[k] if sets[k].size else [np.nan] for k in ERROR_SETS], showfliers=False)
    ax.set_xticks(range(1, 5), ["sonar", "sonar when\navailable", "USBL", "fused"])
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(alpha=0.3, axis="y")
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def evaluation_for(stack: TrackingStack | None, movers: Any, sonar: Any, warmup_s: float = 10.0) -> TrackingEvaluation:
    """The evaluation of a mission's tracking stack: the mover named by the tracker's
    transponder is the truth, its plume the bubbles.

    Args:
        stack: the mission's tracking stack (:attr:`sim.features.tracking.TrackingFeature.stack`).
        movers: the world's movers (:attr:`sim.scene.physics.Physics.movers`).
        sonar: the sonar the tracker reads (its mount and geometry).

    Raises:
        ValueError: no tracking stack, or no mover carries the transponder.
    """
    if stack is None:
        raise ValueError("evaluation_for: the mission has no tracking (autonomy.tracking.enabled)")
    name = stack.cfg.transponder
    if name not in movers.trajectories:
        raise ValueError(f"evaluation_for: no mover named {name!r} carries the transponder")
    traj = movers.trajectories[name]
    plume = movers.plumes.get(name)
    kind = next(m.kind for m in movers.movers if m.name == name)
    half_length_m = DIVER_HALF_LENGTH_M if kind == "diver" else VEHICLE_HALF_SIZE_M[0]
    half_width_m = DIVER_RADIUS_M if kind == "diver" else VEHICLE_HALF_SIZE_M[1]

    def axis_at(t_s: float) -> FloatArray:
        pos, course = traj.pose_at(t_s)
        half = half_length_m * np.array([np.cos(course), np.sin(course), 0.0])
        return np.stack([pos - half, pos + half])

    def bubbles_at(t_s: float) -> FloatArray:
        pos, alive = plume.positions_at(t_s)
        return pos[alive]

    def breaths_at(t_s: float):
        _, ages, pts, wet = plume.breaths_at(t_s)
        return ages, pts, wet

    g = sonar.geometry
    return TrackingEvaluation(stack, lambda t: traj.pose_at(t)[0], bubbles_at if plume is not None else None,
                              sonar.mount.pos_body_m, sonar.mount.R_bs, g.fov_rad, (g.window_near_m, g.window_far_m),
                              g.vertical_beamwidth_rad, warmup_s=warmup_s, target_axis_at=axis_at,
                              breaths_at=breaths_at if plume is not None else None,
                              plume_apart_m=half_width_m + stack.detector.cfg.cluster_distance_m
                              + (plume.cfg.radius_m if plume is not None else 0.0))
