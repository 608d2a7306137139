"""Mechanically scanned imaging sonar (Ping360 class): one beam, one ping per head step.

Assembled from the sonar package (:mod:`sim.sensors.sonar`) as the forward-looking sonar is:
each ping casts a :class:`~sim.sensors.sonar.ray_fan.RayFan` of ``azimuth_rays`` columns
across the horizontal beam pattern x ``elevation_rays`` across the vertical beam, rotated to
the head angle, with surface edges bisected; the columns become echo lines
(:mod:`~sim.sensors.sonar.echo_lines`), pass the :class:`~sim.sensors.sonar.echo_chain.EchoChain`
(spreading, absorption, speckle, noise, TVG, gain) and are summed with the two-way azimuth
beam pattern (:func:`~sim.sensors.sonar.beam_pattern.two_way_beam_power`) into the ping's one
line of ``number_of_samples`` uint8 samples. Sample ``k`` covers ``[k, k + 1)`` sample
spacings of slant range. Each ping is rendered at the true pose of its own capture time, so a
moving vehicle distorts the scan as at sea; the head steps by :class:`sim.sensors.msis_head.HeadSweep`
and the scheduler fires the sensor at the device's ping rate
(:func:`autonomy.msis.ping360.ping_duration_s`).

Ground truth per ping: for each sample the surface whose echo energy there is the strongest:
a scene object's id (>= 0), :data:`WALL_ID` (a background surface whose normal is within 60 deg
of horizontal: basin walls), :data:`SEABED_ID` (other background) or :data:`NO_ECHO_ID`.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from autonomy.frames import rot_z
from autonomy.messages import MsisPing
from autonomy.msis.ping360 import grad_to_rad
from scenarios.config.msis import MsisConfig
from sim.sensors.base import Mount, SceneView, Sensor, as_mount
from sim.sensors.msis_head import HeadSweep
from sim.sensors.raycast import BACKGROUND_ID, NO_HIT_ID, RayCaster
from sim.sensors.registry import register_sensor
from sim.sensors.sonar.beam_pattern import SINC_3DB, two_way_beam_power
from sim.sensors.sonar.echo_chain import EchoChain
from sim.sensors.sonar.echo_lines import echo_segments, ray_strength, spread_segments
from sim.sensors.sonar.ray_fan import RayFan
from sim.dynamics.truth import VehicleTruth

FloatArray = NDArray[np.float64]
SEABED_ID = BACKGROUND_ID  #: -1: seabed (background surface facing up)
NO_ECHO_ID = NO_HIT_ID  #: -2: no surface echoes in the sample
WALL_ID = -3  #: background surface within 60 deg of vertical (basin walls)
WALL_MAX_ABS_NORMAL_Z = 0.5


@dataclass(frozen=True, slots=True)
class MsisPingTruth:
    """Exact truth of one ping.

    Attributes:
        t_s: capture time, s.
        angle_grad: head angle, gradians.
        pos_ned: (3,) head position, NED m.
        R_ns: (3, 3) beam frame (x along the beam at this head angle) -> NED rotation.
        labels: (n_samples,) int16 surface per sample (module docstring).
        mean_intensity: (n_samples,) float32 noise-free received power before TVG.
    """

    t_s: float
    angle_grad: float
    pos_ned: FloatArray
    R_ns: FloatArray
    labels: NDArray[np.int16]
    mean_intensity: NDArray[np.float32]


@dataclass(frozen=True, slots=True)
class MsisRender:
    """A ping as the vehicle gets it and its ground truth."""

    ping: MsisPing
    truth: MsisPingTruth

    @property
    def t_s(self) -> float:
        """Capture time of the ping, s."""
        return self.ping.t_s


@dataclass(frozen=True, slots=True)
class MsisEcho:
    """The noise-free part of a ping (:meth:`MsisSensor.ideal`): everything up to the first
    draw from the noise stream.

    Attributes:
        truth: the ping's exact truth (angle, pose, labels, expected power).
        mean_intensity: (1, n_samples) float32 expected power before TVG (``truth.mean_intensity``
            as one line).
        clutter: (1, n_samples) the bins the K texture applies to (seabed).
    """

    truth: MsisPingTruth
    mean_intensity: NDArray[np.float32]
    clutter: NDArray[np.bool_]


@register_sensor(MsisConfig)
class MsisSensor(Sensor[MsisRender]):
    """Ping360-class scanning sonar on the hull.

    Args:
        cfg: the sonar config.
        mount: a :class:`Mount` (position, roll and yaw used; the tilt is ``cfg.tilt_deg``) or a
            (3,) FRD offset of the head from the body origin, m.
        rng: speckle and noise stream (``sim.rng.component_rng(seed, name)``).
        name: the entry name (default ``msis``).

    The head steps once per noisy ping: :meth:`ideal` looks at the angle the head takes next
    (without stepping it, so that ``measure(..., noise=False)`` stays a query), :meth:`corrupt`
    steps the head there as it draws the ping's noise.

    Attributes:
        rate_hz: ping rate, Hz: ``1 / cfg.ping_duration_s``.
        mount: the head's mount; its ``rpy_rad`` is ``(roll, -tilt_down_rad, yaw)`` (pitch up > 0,
            as every :class:`Mount`) and ``R_bs`` (also :attr:`R_bs`) the head frame at angle 0 ->
            body rotation.
        tilt_down_rad: depression of the head's rotation plane, rad (``cfg.tilt_deg``).
        n_samples, sample_spacing_m: the range axis.
        head: the head's sweep state.
    """

    def __init__(self, cfg: MsisConfig, mount: Mount | ArrayLike = (0.0, 0.0, 0.0),
                 rng: np.random.Generator | None = None, *, name: str | None = None) -> None:
        m = as_mount(mount)
        self.tilt_down_rad = float(np.deg2rad(cfg.tilt_deg))
        self.head = HeadSweep(cfg.step_grad, cfg.sector_width_grad, cfg.sector_centre_grad)
        super().__init__(cfg, Mount(m.pos_body_m, np.array([m.rpy_rad[0], -self.tilt_down_rad, m.rpy_rad[2]]),
                                    m.site), rng, name=name)
        self.cfg: MsisConfig = cfg
        self.R_bs = self.mount.R_bs
        self.sample_period_ticks = cfg.sample_period_ticks
        self.sample_spacing_m = cfg.sample_spacing_m
        self.n_samples = int(cfg.number_of_samples)
        self.range_m = self.n_samples * self.sample_spacing_m
        self.transmit_us = cfg.effective_transmit_us
        hbw = np.deg2rad(cfg.horizontal_beamwidth_deg)
        vbw = np.deg2rad(cfg.vertical_beamwidth_deg)
        self._vbw = float(vbw)
        half = (cfg.azimuth_rays - 1) // 2
        # columns across the main lobe of the two-way pattern (first null at hbw / SINC_3DB)
        offsets = np.zeros(1) if half == 0 else np.linspace(-hbw / SINC_3DB, hbw / SINC_3DB, 2 * half + 1)
        w = two_way_beam_power(offsets, hbw)
        self._col_weight = (w / w.sum()).astype(np.float32)
        self.rays = RayFan(offsets, np.linspace(-0.5 * vbw, 0.5 * vbw, cfg.elevation_rays))
        bins = (np.arange(self.n_samples) + 0.5) * self.sample_spacing_m
        self.echo = EchoChain(bins, cfg.absorption_db_per_m, cfg.tvg_spreading_db_per_decade,
                              cfg.absorption_db_per_m if cfg.tvg_absorption else 0.0, cfg.noise_floor_db, cfg.speckle,
                              cfg.k_shape, cfg.gain_db, cfg.dynamic_range_db)
        self._R_head: dict[float, FloatArray] = {}

    @classmethod
    def rate_of(cls, cfg: MsisConfig) -> float:
        """The ping rate, Hz: ``1 / cfg.ping_duration_s`` (the device timing)."""
        return 1.0 / cfg.ping_duration_s

    def reset(self, rng: np.random.Generator) -> None:
        """New speckle and noise stream; the head back to its sector start."""
        super().reset(rng)
        self.head.reset()

    # -- sensor contract ------------------------------------------------------------------
    def ideal(self, truth: VehicleTruth, scene: SceneView) -> MsisEcho:
        """The noise-free ping from the true pose at ``truth.t_s`` at the angle the head takes
        next (the head does not step).

        Raises:
            ValueError: the scene has no ray caster.
        """
        return self.echo_at(truth.t_s, self.head.peek_angle(), truth.point_ned(self.mount_pos_body_m), truth.R_nb,
                            scene.require_caster("MsisSensor"))

    def exact(self, ideal: MsisEcho) -> MsisRender:
        """The exact ping: the dB display of mean + noise floor; the head stays where it is and
        nothing is drawn (to sweep without noise, call :meth:`render` with ``head.next_angle()``)."""
        return self._ping(ideal, noise=False)

    def corrupt(self, ideal: MsisEcho, truth: VehicleTruth) -> MsisRender:
        """The ping with speckle and receiver noise; the head steps to the ping's angle."""
        angle = self.head.next_angle()
        if angle != ideal.truth.angle_grad:
            raise ValueError(f"MsisSensor.corrupt: the head is at {angle} grad, the ideal ping at "
                             f"{ideal.truth.angle_grad} (corrupt each ideal() once, in order)")
        return self._ping(ideal, noise=True)

    # -- public -----------------------------------------------------------------------------
    @property
    def mount_roll_tilt_yaw_rad(self) -> FloatArray:
        """(3,) the mount as ``(roll, tilt down > 0, yaw)``, rad: the convention of
        :mod:`autonomy.sonar_frame` (what the pings carry as ``MsisPing.mount_rpy_rad``)."""
        return np.array([self.mount.rpy_rad[0], self.tilt_down_rad, self.mount.rpy_rad[2]])

    def beam_to_body(self, angle_grad: float) -> FloatArray:
        """(3, 3) rotation of the beam frame at head angle ``angle_grad`` to the body frame:
        the head turns about its own z axis, ``R_bs Rz(angle)``."""
        R = self._R_head.get(angle_grad)
        if R is None:
            R = self.R_bs @ rot_z(grad_to_rad(angle_grad))
            self._R_head[angle_grad] = R
        return R

    def render(self, t_s: float, angle_grad: float, pos_ned: ArrayLike, R_nb: ArrayLike, caster: RayCaster, *,
               noise: bool = True) -> MsisRender:
        """One ping at head angle ``angle_grad`` from the head at ``pos_ned`` (3,) with the
        vehicle's body->NED rotation ``R_nb`` (3, 3) (:meth:`echo_at`, then the noise and the
        display); the head does not move."""
        return self._ping(self.echo_at(t_s, angle_grad, pos_ned, R_nb, caster), noise=noise)

    def echo_at(self, t_s: float, angle_grad: float, pos_ned: ArrayLike, R_nb: ArrayLike,
                caster: RayCaster) -> MsisEcho:
        """The noise-free part of :meth:`render` (same arguments): the exact truth of the ping.
        Draws nothing."""
        cfg = self.cfg
        origin = np.asarray(pos_ned, dtype=float).reshape(3)
        R_ns = np.asarray(R_nb, dtype=float) @ self.beam_to_body(angle_grad)
        far = self.range_m
        base, _ = self.rays.cast(caster, origin, R_ns, far)
        rays, segments = self.rays.refine_edges(caster, origin, R_ns, base, far, far, cfg.edge_refine_iters)
        strength = ray_strength(rays, cfg.scattering_exponent, self._vbw, self.rays.elevation_step_rad)
        wall = (rays.obj == BACKGROUND_ID) & (np.abs(rays.normal[:, 2]) < WALL_MAX_ABS_NORMAL_Z)
        coded = replace(rays, obj=np.where(wall, WALL_ID, rays.obj))
        echoes = echo_segments(coded, segments, strength, self.rays.range_slope(rays, R_ns), 0.0,
                               self.sample_spacing_m)
        n_cols, n = self.rays.n_cols, self.n_samples
        cols = self.echo.mean_intensity(echoes.lines(n_cols, n, dtype=np.float32))
        mean = (self._col_weight @ cols)[None, :]
        labels = self._labels(echoes.line, echoes.u0, echoes.u1, echoes.energy, echoes.obj)
        truth = MsisPingTruth(t_s=float(t_s), angle_grad=float(angle_grad), pos_ned=origin, R_ns=R_ns, labels=labels,
                              mean_intensity=mean[0])
        return MsisEcho(truth, mean, (labels == SEABED_ID)[None, :])

    def _ping(self, echo: MsisEcho, *, noise: bool) -> MsisRender:
        """The ping of ``echo``: speckle and receiver noise (``noise``: drawn from the sensor's
        stream; else the expected intensity) and the dB display."""
        cfg, tr = self.cfg, echo.truth
        intensity = self.echo.realise(echo.mean_intensity, self._rng, noise=noise, clutter=echo.clutter)
        samples = self.echo.display(intensity)[0]
        ping = MsisPing(t_s=tr.t_s, angle_grad=tr.angle_grad, step_grad=int(cfg.step_grad),
                        sample_period_ticks=int(self.sample_period_ticks),
                        sample_spacing_m=float(self.sample_spacing_m), transmit_duration_us=float(self.transmit_us),
                        speed_of_sound_mps=float(cfg.speed_of_sound_mps), intensity=samples,
                        mount_pos_body_m=self.mount_pos_body_m.copy(), mount_rpy_rad=self.mount_roll_tilt_yaw_rad)
        return MsisRender(ping, tr)

    def _labels(self, line: NDArray[np.intp], u0: FloatArray, u1: FloatArray, energy: FloatArray,
                code: NDArray[np.int64]) -> NDArray[np.int16]:
        """Per-sample surface of the strongest beam-weighted echo energy (module docstring)."""
        n = self.n_samples
        labels = np.full(n, NO_ECHO_ID, dtype=np.int16)
        if len(code) == 0:
            return labels
        classes, row = np.unique(code, return_inverse=True)
        e = spread_segments(len(classes), n, row, u0, u1, energy * self._col_weight[line])
        best = e.argmax(axis=0)
        top = e[best, np.arange(n)]
        has = top > 1e-9 * max(float(top.max()), 1e-300)
        labels[has] = classes[best[has]]
        return labels
