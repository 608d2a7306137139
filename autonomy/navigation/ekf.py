"""AHRS + DVL dead reckoning with an error-state-consistent EKF (depth, GPS, USBL updates).

State ``x`` (10,):
    [0:3]  body-origin position, NED (m)
    [3:6]  AHRS attitude bias b (rad): true rpy = measured rpy - b (heading bias: FOG drift)
    [6]    DVL scale-factor error s: v_dvl = (1 + s) v_true + n
    [7:10] error n of the DVL velocity currently held (FRD, m/s)

Propagation is dead reckoning: the last DVL velocity (lever arm removed) is held in the body
frame and rotated into NED with the AHRS attitude, ``p_dot = R(rpy_m - b) ((v_m - n)/(1+s) -
omega x r_dvl)``. Each valid DVL ping resets ``n`` to a fresh, independent error with the
beam-geometry covariance, so the held error integrates into position exactly as it does in
the sensor. Depth, GPS (at the surface) and USBL fixes are EKF updates (Joseph form).
In ``dead_reckoning`` mode GPS and USBL are ignored.

Without a DVL (``velocity_source='speed_model'``) the held velocity is the surge/sway of the
vehicle's speed model (:class:`autonomy.navigation.speed_model.SpeedModel`) driven by the
commanded force (:class:`autonomy.messages.WrenchCmdMsg`), heave 0; ``n`` is then the model's
velocity error, a random walk (``speed_model.noise_mps_per_sqrt_s``, heave
``heave_noise_mps_per_sqrt_s``) never reset, and ``s`` its
speed scale error (prior ``speed_model.scale_sigma``): position fixes estimate both. The model
velocity is turned into NED by the heading alone (``p_dot = Rz(psi) v``: the model's surge and
sway are horizontal, its heave error vertical), so the depth sensor, which follows the heave,
does not feed back into the horizontal velocity through the roll and pitch.

The altitude of the body origin above the seabed is a separate scalar Kalman filter. It is
propagated with the dead-reckoned NED velocity over the local seabed plane,
``a_dot = g . v_ne - v_down`` (``g`` the seabed depth gradient d depth / d(north, east) from
the last DVL beam footprints), and updated by each DVL and altimeter altitude, moved to the
body origin by the sensor's mount offset, with that sensor's own variance.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from autonomy.estimation.gater import mahalanobis2
from autonomy.estimation.updater import kalman_update
from autonomy.estimation.measurement import PositionFix, RangeBearingElevation
from autonomy.frames import cross3, euler_rate_matrix, rot_from_euler, rot_x, rot_y, rot_z, wrap_angle
from autonomy.messages import (AltimeterMsg, DepthMsg, DvlMsg, GpsMsg, ImuMsg, NavEstimate, PositionFixMsg, UsblMsg,
                               WrenchCmdMsg)
from autonomy.navigation.config import NavigationConfig
from autonomy.navigation.noise_model import NavNoiseModel
from autonomy.navigation.speed_model import SpeedModel

FloatArray = NDArray[np.float64]

N_STATES = 10
POS, ATT, SCALE, DVEL = slice(0, 3), slice(3, 6), 6, slice(7, 10)
_E = np.eye(3)
# Seabed relief the altitude filter allows for beyond the local plane: a random walk of the
# seabed depth along the distance travelled, m per sqrt(m).
SEABED_RELIEF_M_PER_SQRT_M = 0.03
# Smallest altitude measurement variance, m^2 (keeps a noise-free sensor from freezing the filter).
_MIN_ALTITUDE_VAR_M2 = 1e-6


def _rotation_and_jacobian(roll: float, pitch: float, yaw: float, v0: float, v1: float, v2: float
                           ) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """Row-major entries of ``R = Rz(yaw) Ry(pitch) Rx(roll)`` ([Fossen2021] section 2.2.1) and of
    ``d(R v)/d(roll, pitch, yaw)`` (3, 3), in Python floats (numpy's per-call cost dominates
    for 3-vectors). The Jacobian's columns are ``R (e_x x v)``, ``Rz Ry (e_y x Rx v)`` and
    ``e_z x (R v)``."""
    cf, sf = math.cos(roll), math.sin(roll)
    ct, st = math.cos(pitch), math.sin(pitch)
    cp, sp = math.cos(yaw), math.sin(yaw)
    r00, r01, r02 = cp * ct, -sp * cf + cp * st * sf, sp * sf + cp * cf * st
    r10, r11, r12 = sp * ct, cp * cf + sf * st * sp, -cp * sf + st * sp * cf
    r20, r21, r22 = -st, ct * sf, ct * cf
    # pitch column: Rz Ry (e_y x w), w = Rx v, e_y x w = (w2, 0, -w0)
    w2 = sf * v1 + cf * v2
    y0, y2 = ct * w2 - st * v0, -st * w2 - ct * v0
    rv0 = r00 * v0 + r01 * v1 + r02 * v2
    rv1 = r10 * v0 + r11 * v1 + r12 * v2
    return ((r00, r01, r02, r10, r11, r12, r20, r21, r22),
            (-r01 * v2 + r02 * v1, cp * y0, -rv1,
             -r11 * v2 + r12 * v1, sp * y0, rv0,
             -r21 * v2 + r22 * v1, y2, 0.0))


def rotated_vector_jacobian(rpy_rad: FloatArray, v: FloatArray) -> FloatArray:
    """d(R(rpy) v)/d(roll, pitch, yaw) for ZYX Euler angles, shape (3, 3)."""
    roll, pitch, yaw = (float(a) for a in rpy_rad)
    v0, v1, v2 = (float(a) for a in v)
    return np.array(_rotation_and_jacobian(roll, pitch, yaw, v0, v1, v2)[1]).reshape(3, 3)


class NavigationFilter:
    """Navigation EKF (or dead reckoning) fed with sensor messages.

    Args:
        cfg: filter settings.
        initial_pos_ned: (3,) prior position of the body origin, NED (m).
        initial_yaw_rad: heading used until the first AHRS message.
        noise: the filter's model of its sensors' noise.
        mounts: FRD sensor offsets (3,) from the body origin, m, keyed ``dvl``, ``depth``,
            ``gps``, ``usbl``, ``altimeter`` (missing keys: at the origin; other keys ignored).
        usbl_beacon_pos_ned: (3,) known transponder position for :meth:`on_usbl`.
        t0_s: mission time of the prior.

    Messages must be fed in time order; one stamped earlier than the filter time (latency)
    is applied at the filter time.
    """

    def __init__(
        self,
        cfg: NavigationConfig,
        initial_pos_ned: ArrayLike,
        initial_yaw_rad: float,
        noise: NavNoiseModel,
        *,
        mounts: Mapping[str, ArrayLike] | None = None,
        usbl_beacon_pos_ned: ArrayLike | None = None,
        t0_s: float = 0.0,
    ):
        self.cfg = cfg
        self.noise = noise
        mounts = mounts or {}
        self._r_dvl, self._r_depth, self._r_gps, self._r_usbl, self._r_alt = (
            np.asarray(mounts.get(k, np.zeros(3)), dtype=float).reshape(3)
            for k in ("dvl", "depth", "gps", "usbl", "altimeter")
        )
        self._beacon_ned = None if usbl_beacon_pos_ned is None else np.asarray(usbl_beacon_pos_ned, float).reshape(3)
        # measurement models of the fixes; GPS and depth observe the sensor's NED position
        self._gps_model = PositionFix(3, (0, 1), self.noise.gps_noise_m**2 * np.eye(2))
        self._depth_model = PositionFix(3, (2,), np.array([[self.noise.depth_noise_m**2]]))
        self._usbl_model = RangeBearingElevation(
            self._r_usbl, cfg.usbl_range_noise_m, cfg.usbl_range_noise_frac, np.radians(cfg.usbl_angle_noise_deg)
        )
        # (3,) attitude noise variances, rad^2, as Python floats (scalar arithmetic in predict)
        self._att_noise_var = tuple((np.asarray(self.noise.attitude_noise_rad, dtype=float) ** 2).tolist())
        self._F = np.eye(N_STATES)  # transition and process noise of the DVL prediction, written in place
        self._Q = np.zeros((N_STATES, N_STATES))
        self._t_s = float(t0_s)
        self._x = np.zeros(N_STATES)
        self._x[POS] = np.asarray(initial_pos_ned, dtype=float).reshape(3)
        p0 = np.zeros(N_STATES)
        p0[POS] = [cfg.initial_pos_sigma_m**2] * 2 + [cfg.initial_depth_sigma_m**2]
        p0[ATT] = self.noise.attitude_bias_sigma_rad**2
        self._speed_model = SpeedModel(cfg.speed_model) if cfg.velocity_source == "speed_model" else None
        p0[SCALE] = (self.noise.dvl_scale_sigma if self._speed_model is None else cfg.speed_model.scale_sigma) ** 2
        p0[DVEL] = cfg.initial_vel_sigma_mps**2
        self._P = np.diag(p0)
        self._rpy_meas = np.array([0.0, 0.0, float(initial_yaw_rad)])
        self._t_imu_s = float(t0_s)
        self._rate_meas = np.zeros(3)
        self._vel_dvl_meas = np.zeros(3)
        self._omega_at_dvl = np.zeros(3)
        self._lever_vel_dvl = [0.0, 0.0, 0.0]  # omega x r_dvl of the held DVL velocity, m/s
        self._t_dvl_valid_s = -np.inf
        self._altitude_m = float("nan")  # body origin above the seabed, m (NaN until measured)
        self._altitude_var_m2 = float("inf")
        self._seabed_grad_ne = np.zeros(2)  # d(seabed depth)/d(north, east), from the DVL footprints

    # ------------------------------------------------------------------ state access
    @property
    def t_s(self) -> float:
        return self._t_s

    @property
    def state(self) -> FloatArray:
        """Copy of the state vector (10,); layout in the module docstring."""
        return self._x.copy()

    @property
    def covariance(self) -> FloatArray:
        """Copy of the state covariance (10, 10)."""
        return self._P.copy()

    def _attitude(self, t_s: float | None = None) -> FloatArray:
        """Bias-corrected AHRS attitude, extrapolated with the measured body rates to ``t_s``
        (default: the filter time)."""
        tau = (self._t_s if t_s is None else t_s) - self._t_imu_s
        rpy = self._rpy_meas
        if tau > 0.0:
            rpy = rpy + euler_rate_matrix(rpy[0], rpy[1]) @ self._rate_meas * tau
        return rpy - self._x[ATT]

    def _scaled_axes(self) -> FloatArray:
        """(3,) 1 for the velocity axes the scale error divides: the DVL's three, the speed
        model's surge and sway."""
        return np.ones(3) if self._speed_model is None else np.array([1.0, 1.0, 0.0])

    def _vel_body(self) -> FloatArray:
        scaled = self._scaled_axes()
        v_m = self._vel_dvl_meas - self._x[DVEL]
        return v_m * (scaled / (1.0 + self._x[SCALE]) + 1.0 - scaled) - cross3(self._omega_at_dvl, self._r_dvl)

    # ------------------------------------------------------------------ propagation
    def predict(self, t_s: float) -> None:
        """Dead-reckon the state and covariance forward to ``t_s`` (no-op if not later).

        ``x_pos += R v_body dt``, ``P = F P F^T + Q`` with ``F = I + dt d(p_dot)/dx`` and ``Q``
        as in the module docstring. With a DVL the 3 x 3 blocks are formed in Python floats (this
        runs at the IMU rate, where numpy's per-call cost exceeds the arithmetic); the speed
        model's prediction is :meth:`_predict_speed_model`."""
        dt = float(t_s) - self._t_s
        if dt <= 0.0:
            return
        if self._speed_model is not None:
            self._predict_speed_model(dt)
            self._t_s = float(t_s)
            return
        x, cfg = self._x, self.cfg
        # midpoint attitude of the step (as _attitude, in scalars)
        roll, pitch, yaw = self._rpy_meas.tolist()
        tau = self._t_s + 0.5 * dt - self._t_imu_s
        if tau > 0.0:
            p, q, r = self._rate_meas.tolist()
            cphi, sphi = math.cos(roll), math.sin(roll)
            cth, tth = math.cos(pitch), math.tan(pitch)
            roll, pitch, yaw = (roll + (p + sphi * tth * q + cphi * tth * r) * tau,
                                pitch + (cphi * q - sphi * r) * tau,
                                yaw + (sphi / cth * q + cphi / cth * r) * tau)
        b0, b1, b2, one_s, n0, n1, n2 = x[3:10].tolist()
        one_s += 1.0
        vm0, vm1, vm2 = (a - b for a, b in zip(self._vel_dvl_meas.tolist(), (n0, n1, n2)))
        l0, l1, l2 = self._lever_vel_dvl
        vb0, vb1, vb2 = vm0 / one_s - l0, vm1 / one_s - l1, vm2 / one_s - l2
        (r00, r01, r02, r10, r11, r12, r20, r21, r22), J = _rotation_and_jacobian(
            roll - b0, pitch - b1, yaw - b2, vb0, vb1, vb2)
        j00, j01, j02, j10, j11, j12, j20, j21, j22 = J

        # F and Q are reused: every entry that varies is written here, the rest stays I or 0
        F, Q = self._F, self._Q
        ks, kn = -dt / one_s**2, -dt / one_s
        # F[0:3, 3:10], row by row (a flat tuple converts faster than nested lists)
        F[0:3, 3:10].flat = (
            -j00 * dt, -j01 * dt, -j02 * dt, ks * (r00 * vm0 + r01 * vm1 + r02 * vm2), kn * r00, kn * r01, kn * r02,
            -j10 * dt, -j11 * dt, -j12 * dt, ks * (r10 * vm0 + r11 * vm1 + r12 * vm2), kn * r10, kn * r11, kn * r12,
            -j20 * dt, -j21 * dt, -j22 * dt, ks * (r20 * vm0 + r21 * vm1 + r22 * vm2), kn * r20, kn * r21, kn * r22)
        s0, s1, s2 = (v * dt * dt for v in self._att_noise_var)  # J diag(sigma^2) J^T dt^2
        q00 = s0 * j00 * j00 + s1 * j01 * j01 + s2 * j02 * j02
        q01 = s0 * j00 * j10 + s1 * j01 * j11 + s2 * j02 * j12
        q02 = s0 * j00 * j20 + s1 * j01 * j21 + s2 * j02 * j22
        q11 = s0 * j10 * j10 + s1 * j11 * j11 + s2 * j12 * j12
        q12 = s0 * j10 * j20 + s1 * j11 * j21 + s2 * j12 * j22
        q22 = s0 * j20 * j20 + s1 * j21 * j21 + s2 * j22 * j22
        Q[0:3, 0:3].flat = (q00, q01, q02, q01, q11, q12, q02, q12, q22)
        Q[5, 5] = self.noise.heading_rw_rad_per_sqrt_s**2 * dt
        # the held velocity goes stale: an unknown acceleration a ~ N(0, sigma_a^2) over the
        # age tau of the ping gives var(a tau) = sigma_a^2 tau^2; after lock loss, a random walk
        age = min(self._t_s - self._t_dvl_valid_s, cfg.dvl_timeout_s)
        q_vel = cfg.hold_accel_sigma_mps2**2 * (2.0 * age * dt + dt * dt)
        if self._t_s - self._t_dvl_valid_s > cfg.dvl_timeout_s:
            q_vel += cfg.dvl_lost_noise_mps_per_sqrt_s**2 * dt
        Q[7, 7] = Q[8, 8] = Q[9, 9] = q_vel

        vn = r00 * vb0 + r01 * vb1 + r02 * vb2
        ve = r10 * vb0 + r11 * vb1 + r12 * vb2
        vd = r20 * vb0 + r21 * vb1 + r22 * vb2
        if math.isfinite(self._altitude_m):
            # altitude over the local seabed plane: a_dot = g . v_ne - v_down, h = (g_n, g_e, -1)
            gn, ge = self._seabed_grad_ne.tolist()
            h_R = np.array([gn * r00 + ge * r10 - r20, gn * r01 + ge * r11 - r21, gn * r02 + ge * r12 - r22])
            var_rate = float(h_R @ self._P[DVEL, DVEL] @ h_R) / one_s**2
            self._altitude_m += (gn * vn + ge * ve - vd) * dt
            self._altitude_var_m2 += (var_rate * dt * dt
                                      + SEABED_RELIEF_M_PER_SQRT_M**2 * math.hypot(vn, ve) * dt)
        x[0] += vn * dt
        x[1] += ve * dt
        x[2] += vd * dt
        self._P = F @ self._P @ F.T + Q
        self._t_s = float(t_s)

    def _predict_speed_model(self, dt: float) -> None:
        """:meth:`predict` by ``dt`` (s, > 0) with the speed model's velocity (the clock is
        advanced by the caller)."""
        x, noise = self._x, self.noise
        if self._speed_model is not None:
            self._vel_dvl_meas = np.array([*self._speed_model.step(dt), 0.0])
        att = self._attitude(self._t_s + 0.5 * dt)  # midpoint attitude of the step
        one_s = 1.0 + x[SCALE]
        scaled = self._scaled_axes()
        inv_scale = scaled / one_s + (1.0 - scaled)
        v_m = self._vel_dvl_meas - x[DVEL]
        v_body = v_m * inv_scale - cross3(self._omega_at_dvl, self._r_dvl)
        if self._speed_model is None:
            R = rot_from_euler(*att)
            J_att = rotated_vector_jacobian(att, v_body)
        else:  # the model's surge/sway along the heading only: depth says nothing of them
            R = rot_z(att[2])
            J_att = np.column_stack([np.zeros(3), np.zeros(3), cross3(_E[2], R @ v_body)])

        F = np.eye(N_STATES)
        F[POS, ATT] = -J_att * dt
        F[POS, SCALE] = -(R @ (v_m * scaled)) / one_s**2 * dt
        F[POS, DVEL] = -R * inv_scale[None, :] * dt
        Q = np.zeros((N_STATES, N_STATES))
        Q[POS, POS] = J_att @ np.diag(noise.attitude_noise_rad**2) @ J_att.T * dt**2
        Q[5, 5] = noise.heading_rw_rad_per_sqrt_s**2 * dt
        # the held velocity goes stale: an unknown acceleration a ~ N(0, sigma_a^2) over the
        # age tau of the ping gives var(a tau) = sigma_a^2 tau^2; after lock loss, a random walk
        age = min(self._t_s - self._t_dvl_valid_s, self.cfg.dvl_timeout_s)
        q_vel = self.cfg.hold_accel_sigma_mps2**2 * (2.0 * age * dt + dt * dt)
        if self._speed_model is not None:  # the model's error: a random walk (heave: its own)
            sm = self.cfg.speed_model
            q_vel = np.array([sm.noise_mps_per_sqrt_s, sm.noise_mps_per_sqrt_s, sm.heave_noise_mps_per_sqrt_s]) ** 2 * dt
        elif self._t_s - self._t_dvl_valid_s > self.cfg.dvl_timeout_s:
            q_vel += self.cfg.dvl_lost_noise_mps_per_sqrt_s**2 * dt
        Q[DVEL, DVEL] = np.diag(np.broadcast_to(q_vel, (3,)))

        v_ned = R @ v_body
        if np.isfinite(self._altitude_m):
            # altitude over the local seabed plane: a_dot = g . v_ne - v_down
            h = np.array([self._seabed_grad_ne[0], self._seabed_grad_ne[1], -1.0])
            Rs = R * inv_scale[None, :]
            var_rate = float(h @ Rs @ self._P[DVEL, DVEL] @ Rs.T @ h)
            self._altitude_m += float(h @ v_ned) * dt
            self._altitude_var_m2 += (var_rate * dt * dt
                                      + SEABED_RELIEF_M_PER_SQRT_M**2 * float(np.hypot(v_ned[0], v_ned[1])) * dt)
        x[POS] += v_ned * dt
        self._P = F @ self._P @ F.T + Q

    # ------------------------------------------------------------------ measurements
    def _update(self, residual: FloatArray, H: FloatArray, R_meas: FloatArray, gate_chi2: float | None) -> bool:
        P = self._P
        S = H @ P @ H.T + R_meas
        if gate_chi2 is not None and mahalanobis2(residual, S) > gate_chi2:
            return False
        self._x, self._P = kalman_update(self._x, P, residual, H, R_meas)
        return True

    def on_imu(self, msg: ImuMsg) -> None:
        """AHRS attitude and rates: held until the next IMU message."""
        self.predict(msg.t_s)
        self._rpy_meas = np.asarray(msg.rpy_rad, dtype=float).copy()
        self._t_imu_s = max(self._t_s, float(msg.t_s))
        self._rate_meas = np.asarray(msg.rate_body_radps, dtype=float).copy()

    def on_wrench_cmd(self, msg: WrenchCmdMsg) -> None:
        """The commanded body force drives the speed model (ignored with a DVL)."""
        self.predict(msg.t_s)
        if self._speed_model is not None:
            self._speed_model.set_force(np.asarray(msg.wrench_body, dtype=float)[:2])

    def on_dvl(self, msg: DvlMsg) -> None:
        """Valid bottom-track velocity replaces the held velocity and its error state (ignored
        with the speed model: the vehicle has no DVL velocity then)."""
        self.predict(msg.t_s)
        if not msg.valid or self._speed_model is not None:
            return
        vel = np.asarray(msg.vel_body_mps, dtype=float)
        ranges = np.asarray(msg.beam_ranges_m, dtype=float)
        used = np.isfinite(ranges) if ranges.shape == (len(self.noise.dvl_beam_dirs_body),) else None
        if used is not None and used.sum() < 3:
            used = None
        self._vel_dvl_meas = vel.copy()
        self._omega_at_dvl = self._rate_meas.copy()
        self._lever_vel_dvl = cross3(self._omega_at_dvl, self._r_dvl).tolist()  # omega x r_dvl, held
        self._x[DVEL] = 0.0
        self._P[DVEL, :] = 0.0
        self._P[:, DVEL] = 0.0
        self._P[DVEL, DVEL] = self.noise.dvl_velocity_cov(vel, used)
        self._t_dvl_valid_s = max(self._t_s, float(msg.t_s))
        if np.isfinite(msg.altitude_m):
            var = self._dvl_seabed_plane(ranges)
            self._update_altitude(self._body_altitude_m(float(msg.altitude_m), self._r_dvl), var)

    def _dvl_seabed_plane(self, ranges_m: FloatArray) -> float:
        """Refresh the seabed gradient from the DVL beam footprints; return the variance (m^2)
        of the DVL altitude. ``ranges_m``: (4,) slant ranges, NaN for beams not used."""
        noise = self.noise
        dirs_body = noise.dvl_beam_dirs_body
        if ranges_m.shape == (len(dirs_body),) and np.isfinite(ranges_m).sum() >= 3:
            used = np.isfinite(ranges_m)
            offsets = ranges_m[used, None] * (dirs_body[used] @ rot_from_euler(*self._attitude()).T)
            A = np.column_stack([np.ones(len(offsets)), offsets[:, 0], offsets[:, 1]])
            try:
                var = noise.dvl_altitude_var_m2(offsets)
            except ValueError:
                pass
            else:
                self._seabed_grad_ne = np.linalg.lstsq(A, offsets[:, 2], rcond=None)[0][1:3]
                return max(var, _MIN_ALTITUDE_VAR_M2)
        # no footprints: all four beams on a level seabed at their nominal geometry
        var = noise.dvl_range_noise_m**2 * float(np.mean(dirs_body[:, 2] ** 2)) / len(dirs_body)
        return max(var, _MIN_ALTITUDE_VAR_M2)

    def _update_altitude(self, altitude_m: float, var_m2: float) -> None:
        """Kalman update of the body-origin altitude with a measurement (m) of variance ``var_m2``."""
        if not np.isfinite(self._altitude_m):
            self._altitude_m, self._altitude_var_m2 = altitude_m, var_m2
            return
        gain = self._altitude_var_m2 / (self._altitude_var_m2 + var_m2)
        self._altitude_m += gain * (altitude_m - self._altitude_m)
        self._altitude_var_m2 *= 1.0 - gain

    def _body_altitude_m(self, sensor_altitude_m: float, mount_body_m: np.ndarray) -> float:
        """Altitude (m) of the body origin from a sensor's altitude (m, straight below the sensor)
        and its FRD mount offset (3,), over the seabed plane of the current gradient."""
        lever_ned = rot_from_euler(*self._attitude()) @ mount_body_m
        return sensor_altitude_m + float(lever_ned[2]) - float(self._seabed_grad_ne @ lever_ned[:2])

    def on_depth(self, msg: DepthMsg) -> None:
        """Pressure depth of the depth sensor."""
        self.predict(msg.t_s)
        att = self._attitude()
        model = self._depth_model
        predicted = model.function(self._x[POS] + rot_from_euler(*att) @ self._r_depth)
        H = np.zeros((1, N_STATES))
        H[:, POS] = model.jacobian()
        H[:, ATT] = -rotated_vector_jacobian(att, self._r_depth)[model.mapping]
        self._update(model.residual([msg.depth_m], predicted), H, model.covar(), None)

    def on_altimeter(self, msg: AltimeterMsg) -> None:
        """Altimeter slant range along body down, turned into the vertical distance under the
        altimeter over the seabed plane (AHRS attitude, gradient from the DVL footprints; level
        seabed before the first DVL footprints), moved to the body origin and fused."""
        self.predict(msg.t_s)
        if not (msg.valid and np.isfinite(msg.altitude_m)):
            return
        beam_ned = rot_from_euler(*self._attitude())[:, 2]
        # the echo comes from r * beam_ned; the plane lies g . (r beam_ne) deeper there than below
        vertical_per_range = float(beam_ned[2] - self._seabed_grad_ne @ beam_ned[:2])
        range_m = float(msg.altitude_m)
        var = max(self.noise.altimeter_altitude_var_m2(range_m, vertical_per_range), _MIN_ALTITUDE_VAR_M2)
        self._update_altitude(self._body_altitude_m(range_m * vertical_per_range, self._r_alt), var)

    def on_gps(self, msg: GpsMsg) -> bool:
        """GPS north/east fix of the antenna. Returns whether it was applied (valid, EKF mode,
        inside the innovation gate)."""
        if not msg.valid or self.cfg.mode != "ekf":
            return False
        self.predict(msg.t_s)
        att = self._attitude()
        model = self._gps_model
        predicted = model.function(self._x[POS] + rot_from_euler(*att) @ self._r_gps)
        H = np.zeros((2, N_STATES))
        H[:, POS] = model.jacobian()
        H[:, ATT] = -rotated_vector_jacobian(att, self._r_gps)[model.mapping]
        return self._update(model.residual(msg.pos_ne_m, predicted), H, model.covar(), self.cfg.gps_gate_chi2)

    def on_usbl(self, msg: UsblMsg) -> bool:
        """Range/bearing/elevation of the known beacon seen from the vehicle's USBL head.
        Returns whether it was applied (EKF mode, inside the innovation gate); fixes of other
        transponders (a tracked target's) and missing fixes are ignored."""
        if not msg.valid or msg.transponder != "beacon":
            return False
        if self._beacon_ned is None:
            raise ValueError("NavigationFilter.on_usbl needs usbl_beacon_pos_ned at construction")
        if self.cfg.mode != "ekf":
            return False
        self.predict(msg.t_s)
        att = self._attitude()
        R = rot_from_euler(*att)
        model = self._usbl_model
        beacon_body = R.T @ (self._beacon_ned - self._x[POS])  # beacon from the body origin, FRD
        predicted = model.function(beacon_body)
        J_obs = model.jacobian(beacon_body)
        # d(beacon_body)/d(att): R^T w = R(att)^T w; use d(R^T w)_i/d(att) = (dR/d att)^T w
        w = self._beacon_ned - self._x[POS]
        J_rel_att = np.empty((3, 3))
        for k in range(3):
            J_rel_att[:, k] = _rotation_derivative(att, k).T @ w
        H = np.zeros((3, N_STATES))
        H[:, POS] = J_obs @ (-R.T)
        H[:, ATT] = -(J_obs @ J_rel_att)  # state holds the bias: att = rpy_m - b
        z = np.array([msg.range_m, msg.bearing_rad, msg.elevation_rad])
        residual = model.residual(z, predicted)
        return self._update(residual, H, model.covar(msg.range_m), self.cfg.usbl_gate_chi2)

    def on_position_fix(self, msg: PositionFixMsg) -> bool:
        """North/east fix of the body origin with its own covariance (feature-based localisation,
        e.g. a scanning sonar in a known pool), and when the message has one, the heading error
        of the estimate the features were placed with, fused into the heading bias state.
        Returns whether the position was applied (EKF mode; no innovation gate: the fixes come
        out of their own outlier rejection)."""
        if self.cfg.mode != "ekf":
            return False
        self.predict(msg.t_s)
        model = PositionFix(3, (0, 1), np.asarray(msg.cov_ne_m2, dtype=float).reshape(2, 2))
        H = np.zeros((2, N_STATES))
        H[:, POS] = model.jacobian()
        applied = self._update(model.residual(np.asarray(msg.pos_ne_m, dtype=float), model.function(self._x[POS])),
                               H, model.covar(), None)
        if np.isfinite(msg.heading_err_rad) and np.isfinite(msg.heading_var_rad2) and msg.heading_var_rad2 > 0.0:
            # the features were placed with heading psi_m - b, rotated by b_true - b from the truth:
            # the error measures the heading bias state, residual = the error itself
            H = np.zeros((1, N_STATES))
            H[0, 5] = 1.0
            self._update(np.array([float(msg.heading_err_rad)]), H, np.array([[float(msg.heading_var_rad2)]]), None)
        return applied

    def message_handlers(self) -> dict[type, Callable[[Any], Any]]:
        """Message type -> the method that fuses it (what a message bus dispatches on)."""
        return {ImuMsg: self.on_imu, DvlMsg: self.on_dvl, DepthMsg: self.on_depth,
                AltimeterMsg: self.on_altimeter, GpsMsg: self.on_gps, UsblMsg: self.on_usbl,
                PositionFixMsg: self.on_position_fix, WrenchCmdMsg: self.on_wrench_cmd}

    # ------------------------------------------------------------------ output
    def estimate(self) -> NavEstimate:
        """Current estimate at the filter time."""
        att = self._attitude()
        att[2] = float(wrap_angle(att[2]))
        return NavEstimate(
            t_s=self._t_s,
            pos_ned=self._x[POS].copy(),
            rpy_rad=att,
            vel_body_mps=self._vel_body(),
            rate_body_radps=self._rate_meas.copy(),
            cov_pos_ned=self._P[POS, POS].copy(),
            cov_yaw_rad2=float(self._P[5, 5]),
            altitude_m=self._altitude_m,
        )


def _rotation_derivative(rpy_rad: FloatArray, axis: int) -> FloatArray:
    """dR/d(angle ``axis``) of ``R = Rz Ry Rx`` (axis 0 roll, 1 pitch, 2 yaw), (3, 3)."""
    roll, pitch, yaw = rpy_rad
    Rx, Ry, Rz = rot_x(roll), rot_y(pitch), rot_z(yaw)
    S = [np.array([[0, 0, 0], [0, 0, -1], [0, 1, 0]]), np.array([[0, 0, 1], [0, 0, 0], [-1, 0, 0]]),
         np.array([[0, -1, 0], [1, 0, 0], [0, 0, 0]])][axis]
    if axis == 0:
        return Rz @ Ry @ Rx @ S
    if axis == 1:
        return Rz @ Ry @ S @ Rx
    return Rz @ S @ Ry @ Rx
