"""EKF tracking one target from USBL fixes and sonar detections, late fixes re-processed.

Paper 004 section 3: an EKF over the target's kinematic states (eq. 6) updated by USBL range,
bearing and elevation and by sonar range and azimuth (eq. 8-10), relative to the vehicle,
whose pose comes from navigation (the paper's vehicle states, taken as known as in its
section 4.1). USBL fixes arrive late by the acoustic travel time; "to account for measurement
delays methods of backward recalculation can be applied" (section 3): every measurement is
kept with its measurement time and the vehicle pose then, and a measurement older than the
newest one applied re-runs the filter from the checkpoint before it (re-processing from a
stored history), so a late fix is applied at the time it was measured, never as new.

Initiation (two-stage, as Bar-Shalom, Li and Kirubarajan 2001 section 3.2 start a track by
differencing before the manoeuvring model): the first measurement gives the position and a
zero-mean Gaussian velocity prior, and a Cartesian nearly-constant-velocity EKF (state (6,):
NED position, NED velocity; horizontal white acceleration ``initiation_accel_noise_m2_per_s3``,
vertical the heave noise) runs until the velocity is known well enough to define a course
(its 1 sigma below ``initiation_course_sigma_deg`` and the speed at least 3 sigma); the state
is then carried to the paper's (course, surge) parameterisation through the Jacobian of
``(atan2(v_e, v_n), |v_ne|)``. Starting directly with a course of sigma pi is not Gaussian
and makes a few runs diverge; a hovering target never hands over and stays well tracked.

The sonar measurement is (range, azimuth): the imaging sonar does not resolve elevation, so
the target's depth comes from the USBL. With no other depth cue the sonar-only filter keeps
the beam centre as a pseudo-measurement of elevation (0, variance of a uniform over the
vertical beam, ``beam^2 / 12``), and a track a sonar detection starts takes an elevation of 0 with the variance of a uniform over
the vertical beam (``beam^2 / 12``) to place its first position. Each update passes a chi-square gate; rejected measurements stay in the
history (re-processing re-decides them). ``usbl_rejections_to_restart`` USBL fixes rejected
in a row mean the track is lost (a manoeuvre beyond the process noise): the filter restarts
from the last of them, as at initiation (the USBL always answers, so it is the reference).
"""

from __future__ import annotations

import bisect
import logging
import math
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from autonomy.estimation.gater import MahalanobisGater
from autonomy.estimation.measurement import RangeBearingElevation
from autonomy.estimation.reprocessing import ReprocessingHistory
from autonomy.estimation.state import GaussianState
from autonomy.estimation.updater import ExtendedKalmanUpdater
from autonomy.frames import rot_from_euler
from autonomy.messages import UsblMsg
from autonomy.tracking.config import TrackingConfig
from autonomy.tracking.kinematics import COURSE, COURSE_RATE, HEAVE, N_STATES, POS, SURGE, TargetKinematics
from autonomy.tracking.roi import PolarRoi, polar_roi

FloatArray = NDArray[np.float64]
log = logging.getLogger(__name__)
USBL, SONAR = "usbl", "sonar"
CV_STATES = 6  # initiation state: NED position (m), NED velocity (m/s)


class RelativeSpherical:
    """Range, bearing and elevation of the target seen from a head on the vehicle, as a
    function of the tracker state (the shape :class:`ExtendedKalmanUpdater` takes).

    Args:
        head_ned: (3,) NED position of the sensor head at measurement time, m.
        R_nh: (3, 3) head frame -> NED rotation at measurement time.
        ndim: 3 (range, bearing, elevation) or 2 (range, azimuth).
    """

    _rbe = RangeBearingElevation()

    def __init__(self, head_ned: FloatArray, R_nh: FloatArray, ndim: int = 3) -> None:
        self.head_ned = head_ned
        self.R_hn = R_nh.T
        self.ndim_meas = ndim

    def _rel(self, x: FloatArray) -> FloatArray:
        return self.R_hn @ (x[POS] - self.head_ned)

    def function(self, x: ArrayLike) -> FloatArray:
        return self._rbe.function(self._rel(np.asarray(x, dtype=float)))[: self.ndim_meas]

    def jacobian(self, x: ArrayLike) -> FloatArray:
        """(ndim_meas, n): the state's first three entries are its NED position, the rest
        (course model (7,) or constant velocity (6,)) do not enter."""
        x = np.asarray(x, dtype=float)
        H = np.zeros((self.ndim_meas, x.size))
        H[:, POS] = (self._rbe.jacobian(self._rel(x)) @ self.R_hn)[: self.ndim_meas]
        return H

    def residual(self, z: ArrayLike, z_pred: ArrayLike) -> FloatArray:
        res = np.asarray(z, dtype=float) - z_pred
        res[1:] = np.angle(np.exp(1j * res[1:]))
        return res


@dataclass
class _Event:
    t_s: float
    seq: int
    kind: str
    z: FloatArray
    R: FloatArray
    model: RelativeSpherical
    accepted: bool = field(default=False)

    @property
    def key(self) -> tuple[float, int]:
        return (self.t_s, self.seq)


@dataclass
class _Pose:
    t_s: float
    pos_ned: FloatArray
    rpy_rad: FloatArray


class TargetTracker:
    """Tracks one target; feed it vehicle poses, USBL fixes and sonar detections.

    Args:
        cfg: tracker settings (mode, noise model, gates, ROI).
        usbl_mount_body_m: (3,) FRD position of the USBL head; ``usbl_mount_rpy_rad`` its frame.
        sonar_mount_body_m: (3,) FRD position of the sonar head; ``sonar_mount_rpy_rad`` its
            frame (roll, pitch, yaw of the sonar frame w.r.t. the body).

    Attributes:
        rejected: (time, reason) of each input refused (bad input or outside the gate).
        n_usbl_used, n_sonar_used: accepted updates in the current history's run.
    """

    def __init__(self, cfg: TrackingConfig, usbl_mount_body_m: ArrayLike = (0.0, 0.0, 0.0),
                 sonar_mount_body_m: ArrayLike = (0.0, 0.0, 0.0), *, usbl_mount_rpy_rad: ArrayLike = (0.0, 0.0, 0.0),
                 sonar_mount_rpy_rad: ArrayLike = (0.0, 0.0, 0.0)) -> None:
        self.cfg = cfg
        self.kinematics = TargetKinematics(cfg.pos_noise_m2_per_s, cfg.course_rate_noise_rad2_per_s3,
                                           cfg.surge_noise_m2_per_s3, cfg.heave_noise_m2_per_s3)
        self._usbl_mount = np.asarray(usbl_mount_body_m, dtype=float).reshape(3)
        self._R_b_usbl = rot_from_euler(*np.asarray(usbl_mount_rpy_rad, dtype=float))
        self._sonar_mount = np.asarray(sonar_mount_body_m, dtype=float).reshape(3)
        self._R_b_sonar = rot_from_euler(*np.asarray(sonar_mount_rpy_rad, dtype=float))
        self._gate = {m: MahalanobisGater.chi_square(cfg.gate_probability, m) for m in (2, 3)}
        self._cv_q_axes = np.diag([cfg.initiation_accel_noise_m2_per_s3] * 2 + [cfg.heave_noise_m2_per_s3])
        self._cv_pos_q = np.diag([cfg.pos_noise_m2_per_s] * 3 + [0.0] * 3)
        self.reset()

    # ------------------------------------------------------------------ inputs
    def reset(self) -> None:
        """Forget everything (no estimate until the first accepted measurement)."""
        self._poses: list[_Pose] = []
        self._state: GaussianState | None = None  # after the newest event
        self._history: ReprocessingHistory[_Event, GaussianState | None] = \
            ReprocessingHistory(self._apply_event, lambda: self._state, self._set_state, self._clock)
        self._seq = 0
        self._last_sonar_t = -math.inf  # time of the previous sonar detection (its error's correlation)
        self.rejected: list[tuple[float, str]] = []

    @property
    def now_s(self) -> float:
        """Time of the newest vehicle pose (-inf before any)."""
        return self._poses[-1].t_s if self._poses else -math.inf

    def record_pose(self, t_s: float, pos_ned: ArrayLike, rpy_rad: ArrayLike) -> None:
        """Vehicle pose (body origin NED, m; roll/pitch/yaw, rad) at ``t_s`` from navigation;
        times must increase."""
        if self._poses and t_s <= self._poses[-1].t_s:
            return
        self._poses.append(_Pose(float(t_s), np.asarray(pos_ned, dtype=float).copy(),
                                 np.asarray(rpy_rad, dtype=float).copy()))
        horizon = t_s - self.cfg.history_s - 1.0
        while len(self._poses) > 2 and self._poses[1].t_s < horizon:
            self._poses.pop(0)
        self._history.prune(t_s - self.cfg.history_s)  # older events folded into the oldest state

    def pose_at(self, t_s: float) -> tuple[FloatArray, FloatArray] | None:
        """Vehicle (position (3,), R_nb (3, 3)) at ``t_s`` by linear interpolation (yaw along
        the short way), or None outside the pose history."""
        ps = self._poses
        if not ps or t_s > ps[-1].t_s + 1e-9 or t_s < ps[0].t_s - 1e-9:
            return None
        i = bisect.bisect_left([p.t_s for p in ps], t_s)
        if i < len(ps) and abs(ps[i].t_s - t_s) <= 1e-9 or i == 0:
            p = ps[min(i, len(ps) - 1)]
            return p.pos_ned, rot_from_euler(*p.rpy_rad)
        a, b = ps[i - 1], ps[i]
        f = (t_s - a.t_s) / (b.t_s - a.t_s)
        d_rpy = np.angle(np.exp(1j * (b.rpy_rad - a.rpy_rad)))
        return a.pos_ned + f * (b.pos_ned - a.pos_ned), rot_from_euler(*(a.rpy_rad + f * d_rpy))

    def on_usbl(self, msg: UsblMsg) -> bool:
        """Add a USBL fix at its measurement time ``msg.t_s``. Returns whether it was taken
        into the history (bad input, another transponder, sonar-only mode: refused and logged)."""
        if self.cfg.mode == "sonar":
            return False
        if not msg.valid:
            return False
        if msg.transponder != self.cfg.transponder:
            return self._refuse(msg.t_s, f"USBL fix of unknown transponder {msg.transponder!r}")
        z = np.array([msg.range_m, msg.bearing_rad, msg.elevation_rad], dtype=float)
        if not np.all(np.isfinite(z)) or z[0] <= 0.0:
            return self._refuse(msg.t_s, f"USBL fix not finite or range <= 0: {z}")
        pose = self._pose_for(msg.t_s, "USBL")
        if pose is None:
            return False
        pos, R_nb = pose
        cfg = self.cfg
        sig_r = cfg.usbl_range_sigma_m + cfg.usbl_range_sigma_frac * z[0]
        sig_a = math.radians(cfg.usbl_angle_sigma_deg + cfg.usbl_angle_sigma_deg_per_100m * z[0] / 100.0)
        model = RelativeSpherical(pos + R_nb @ self._usbl_mount, R_nb @ self._R_b_usbl)
        self._insert(_Event(float(msg.t_s), self._next_seq(), USBL, z, np.diag([sig_r**2, sig_a**2, sig_a**2]), model))
        return True

    def on_sonar(self, t_s: float, range_m: float, azimuth_rad: float, elevation_rad: float = 0.0, *,
                 centre_sigma_m: float = 0.0) -> bool:
        """Add a sonar detection (sonar frame range m, azimuth rad, starboard > 0) at ``t_s``.
        An imaging sonar does not measure elevation: the update uses range and azimuth only;
        ``elevation_rad`` (down > 0, default the beam centre) with the variance of a uniform
        over the vertical beam places a track that a sonar detection starts and, in sonar-only
        mode (no other depth cue), is kept as a pseudo-measurement. ``centre_sigma_m`` (1
        sigma, m) adds, in range and across the beam, the uncertainty of where the target's
        centre lies w.r.t. the detection (a target cut by the edge of the view shows only
        part of itself; correlated from frame to frame as the extent's part below).

        The target's echo comes from its side facing the sonar: the measured range is taken
        as ``target_thickness_m / 2`` short of its centre (added back). The measurement
        noise is the image's resolution (``sonar_range_sigma_m``, ``sonar_azimuth_sigma_deg``,
        white) plus the target's extent, a uniform over it (``target_thickness_m / sqrt(12)``
        along the beam, ``target_size_m / sqrt(12)`` across), whose error is correlated from
        frame to frame (an AR(1) sequence, correlation ``rho = exp(-dt / tau)`` with ``dt``
        the time since the previous detection and ``tau = sonar_error_correlation_s``): its
        variance is inflated by ``(1 + rho) / (1 - rho)``, the factor by which such a
        sequence's samples carry less information than independent ones (the variance of
        the mean of n AR(1) samples is ``sigma^2 (1 + rho) / (n (1 - rho))`` for large n,
        docs/references.md [Zwiers1995]), so
        a detection after a gap counts fully and a run of frames counts as the independent
        looks it holds."""
        if self.cfg.mode == "usbl":
            return False
        if not (math.isfinite(range_m) and math.isfinite(azimuth_rad) and range_m > 0.0):
            return self._refuse(t_s, f"sonar detection not finite or range <= 0: {range_m}, {azimuth_rad}")
        pose = self._pose_for(t_s, "sonar")
        if pose is None:
            return False
        pos, R_nb = pose
        cfg = self.cfg
        sig_e2 = math.radians(cfg.sonar_vertical_beam_deg) ** 2 / 12.0
        if not (math.isfinite(centre_sigma_m) and centre_sigma_m >= 0.0):
            return self._refuse(t_s, f"sonar centre sigma not finite or < 0: {centre_sigma_m}")
        z = np.array([range_m + 0.5 * cfg.target_thickness_m, azimuth_rad, elevation_rad])
        k = self._correlation_inflation(float(t_s))
        c2 = centre_sigma_m**2  # as correlated as the extent's part: the same cut from frame to frame
        along2, across2 = k * (cfg.target_thickness_m**2 / 12.0 + c2), k * (cfg.target_size_m**2 / 12.0 + c2)
        R = np.diag([cfg.sonar_range_sigma_m**2 + along2,
                     math.radians(cfg.sonar_azimuth_sigma_deg) ** 2 + across2 / z[0] ** 2, sig_e2])
        ndim = 3 if cfg.mode == "sonar" else 2  # sonar only: the beam centre is its only depth cue
        head, R_nh = pos + R_nb @ self._sonar_mount, R_nb @ self._R_b_sonar
        self._insert(_Event(float(t_s), self._next_seq(), SONAR, z, R, RelativeSpherical(head, R_nh, ndim=ndim)))
        return True

    def _correlation_inflation(self, t_s: float) -> float:
        """``(1 + rho) / (1 - rho)``, ``rho = exp(-dt / tau)``, for a sonar detection at ``t_s``
        (``dt`` since the previous one, at least 1 ms); 1 for the first or with ``tau = 0``."""
        tau = self.cfg.sonar_error_correlation_s
        dt = abs(t_s - self._last_sonar_t)
        self._last_sonar_t = t_s
        if tau <= 0.0 or not math.isfinite(dt):
            return 1.0
        rho = math.exp(-max(dt, 1e-3) / tau)
        return (1.0 + rho) / (1.0 - rho)

    # ------------------------------------------------------------------ outputs
    @property
    def initialised(self) -> bool:
        return self._last_state() is not None

    def estimate(self, t_s: float | None = None) -> tuple[FloatArray, FloatArray] | None:
        """Mean (7,) ``[n, e, d, course, course_rate, surge, heave]`` and covariance (7, 7) at
        ``t_s`` (default: now) predicted from the last measurement, or None before the first."""
        last = self._last_state()
        if last is None:
            return None
        t = self.now_s if t_s is None else float(t_s)
        x, P = self._predict(last.mean, last.covar, max(t - last.t_s, 0.0))
        return self._as_course_state(x, P) if x.size == CV_STATES else (x, P)

    @property
    def course_known(self) -> bool:
        """Whether the filter runs the paper's course model (False: still initiating)."""
        last = self._last_state()
        return last is not None and last.ndim == N_STATES

    def roi(self, t_s: float | None = None) -> PolarRoi | None:
        """Polar ROI in the sonar frame at ``t_s`` (default: now), or None before the first
        estimate or without a pose then. It is centred where the target's echo is expected:
        its near side, ``target_thickness_m / 2`` short of the estimated centre (the
        measurement model of :meth:`on_sonar`)."""
        t = self.now_s if t_s is None else float(t_s)
        est = self.estimate(t)
        pose = self.pose_at(t)
        if est is None or pose is None:
            return None
        pos, R_nb = pose
        x, P = est
        try:
            roi = polar_roi(x[POS], P[POS, POS], pos + R_nb @ self._sonar_mount, R_nb @ self._R_b_sonar,
                            self.cfg.roi_sigma, self.cfg.target_size_m)
        except ValueError:
            return None
        return replace(roi, range_m=max(roi.range_m - 0.5 * self.cfg.target_thickness_m, 0.0))

    def used_counts(self) -> dict[str, int]:
        """Accepted updates per kind in the kept history."""
        out = {USBL: 0, SONAR: 0}
        for e in self._history.events:
            out[e.kind] += int(e.accepted)
        return out

    # ------------------------------------------------------------------ internals
    def _next_seq(self) -> int:
        self._seq += 1
        return self._seq

    def _refuse(self, t_s: float, reason: str) -> bool:
        log.warning("tracker: refused at t=%.3f s: %s", t_s, reason)
        self.rejected.append((float(t_s), reason))
        return False

    def _pose_for(self, t_s: float, what: str) -> tuple[FloatArray, FloatArray] | None:
        if not math.isfinite(t_s):
            self._refuse(t_s, f"{what} time not finite")
            return None
        if t_s > self.now_s + 1e-9:
            self._refuse(t_s, f"{what} measurement from the future (now {self.now_s:.3f} s)")
            return None
        if t_s < self._history.oldest[0]:
            self._refuse(t_s, f"{what} measurement older than the kept history ({self.cfg.history_s} s)")
            return None
        pose = self.pose_at(t_s)
        if pose is None:
            self._refuse(t_s, f"no vehicle pose at the {what} measurement time")
        return pose

    def _last_state(self) -> GaussianState | None:
        return self._state

    def _insert(self, ev: _Event) -> None:
        """Apply ``ev`` at its time: re-processing the later events ([BarShalom2001-OOSM])."""
        self._history.insert(ev, ev.t_s)

    def _set_state(self, state: GaussianState | None) -> None:
        self._state = state

    def _clock(self) -> float:
        return -math.inf if self._state is None else self._state.t_s

    def _apply_event(self, ev: _Event) -> None:
        self._state = self._apply(self._state, ev)

    def _apply(self, state: GaussianState | None, ev: _Event) -> GaussianState:
        """Posterior after ``ev`` from ``state`` (None: not initialised; the event initialises)."""
        if state is None:
            ev.accepted = True
            return GaussianState(*self._initial(ev), ev.t_s)
        x, P = self._predict(state.mean, state.covar, ev.t_s - state.t_s)
        m = ev.model.ndim_meas
        z, R = ev.z[:m], ev.R[:m, :m]
        H = ev.model.jacobian(x)
        S = H @ P @ H.T + R
        r = ev.model.residual(z, ev.model.function(x))
        ev.accepted = self._gate[m].admits(r, S)
        if not ev.accepted:
            if ev.kind == USBL and self._usbl_rejections_before(ev) + 1 >= self.cfg.usbl_rejections_to_restart:
                ev.accepted = True  # the track is lost: restart from this fix
                return GaussianState(*self._initial(ev), ev.t_s)
            return GaussianState(x, P, ev.t_s)
        x, P = ExtendedKalmanUpdater(ev.model).update(x, P, z, R)
        if x.size == CV_STATES and self._course_defined(x, P):
            x, P = self._as_course_state(x, P)
        return GaussianState(x, P, ev.t_s)

    def _usbl_rejections_before(self, ev: _Event) -> int:
        """USBL fixes rejected in a row just before ``ev`` in the history (sonar events,
        clutter included, do not break the run)."""
        n = 0
        events = self._history.events
        for e in reversed(events[: events.index(ev)]):
            if e.kind != USBL:
                continue
            if e.accepted:
                break
            n += 1
        return n

    def _predict(self, x: FloatArray, P: FloatArray, dt_s: float) -> tuple[FloatArray, FloatArray]:
        if x.size == N_STATES:
            return self.kinematics.predict(x, P, dt_s)
        F = np.eye(CV_STATES)
        F[0:3, 3:6] = dt_s * np.eye(3)
        q = np.diag(self._cv_q_axes)  # white acceleration per axis (ConstantVelocity's Q, per-axis q)
        Q = np.zeros((CV_STATES, CV_STATES))
        i = np.arange(3)
        Q[i, i] = q * dt_s**3 / 3.0 + np.diag(self._cv_pos_q)[:3] * dt_s
        Q[i, i + 3] = Q[i + 3, i] = q * dt_s**2 / 2.0
        Q[i + 3, i + 3] = q * dt_s
        return F @ x, F @ P @ F.T + Q

    def _course_defined(self, x: FloatArray, P: FloatArray) -> bool:
        """Whether the constant-velocity state fixes the course: speed >= 3 sigma along it and
        course sigma (cross-track velocity sigma / speed) below the configured bound."""
        v = x[3:5]
        speed = float(np.hypot(*v))
        if speed <= 0.0:
            return False
        along, across = v / speed, np.array([-v[1], v[0]]) / speed
        Pv = P[3:5, 3:5]
        sig_along = math.sqrt(max(float(along @ Pv @ along), 0.0))
        sig_course = math.sqrt(max(float(across @ Pv @ across), 0.0)) / speed
        return speed >= 3.0 * sig_along and sig_course <= math.radians(self.cfg.initiation_course_sigma_deg)

    def _as_course_state(self, x: FloatArray, P: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Constant-velocity state (6,) -> the paper's state (7,) through the Jacobian of
        ``course = atan2(v_e, v_n)``, ``surge = |v_ne|``; the course rate starts at 0 with
        its configured sigma, uncorrelated. At zero speed the course is 0 with sigma pi."""
        vn, ve = x[3], x[4]
        s2 = vn * vn + ve * ve
        J = np.zeros((N_STATES, CV_STATES))
        J[POS, 0:3] = np.eye(3)
        J[HEAVE, 5] = 1.0
        x7 = np.zeros(N_STATES)
        x7[POS], x7[HEAVE] = x[0:3], x[5]
        if s2 > 1e-12:
            s = math.sqrt(s2)
            x7[COURSE], x7[SURGE] = math.atan2(ve, vn), s
            J[COURSE, 3:5] = [-ve / s2, vn / s2]
            J[SURGE, 3:5] = [vn / s, ve / s]
        P7 = J @ P @ J.T
        if s2 <= 1e-12:
            P7[COURSE, COURSE] = math.pi**2
            P7[SURGE, SURGE] = float(np.trace(P[3:5, 3:5]))
        P7[COURSE_RATE, COURSE_RATE] = math.radians(self.cfg.initial_course_rate_sigma_dps) ** 2
        return x7, 0.5 * (P7 + P7.T)

    def _initial(self, ev: _Event) -> tuple[FloatArray, FloatArray]:
        """Constant-velocity state (6,) from one measurement: its inverse for the position
        (covariance through the inverse Jacobian) and a zero-mean velocity whose per-axis
        variance is that of the configured speed prior with its course uniform on the circle
        (``(u0^2 + sigma_u^2) / 2`` per horizontal axis, the second moment of that ring)."""
        rbe = RangeBearingElevation()
        J = ev.model.R_hn.T @ rbe.inverse_jacobian(ev.z)
        x = np.zeros(CV_STATES)
        x[POS] = ev.model.head_ned + ev.model.R_hn.T @ rbe.inverse(ev.z)
        P = np.zeros((CV_STATES, CV_STATES))
        P[POS, POS] = J @ ev.R @ J.T + 0.01 * np.eye(3)
        var_h = 0.5 * (self.cfg.initial_surge_mps**2 + self.cfg.initial_surge_sigma_mps**2)
        P[3:6, 3:6] = np.diag([var_h, var_h, 0.05**2])
        return x, P
