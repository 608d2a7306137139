"""Doppler velocity log: four ray-cast Janus beams, bottom lock, speed-dependent noise."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from autonomy.messages import DvlMsg
from autonomy.navigation.dvl_geometry import janus_beam_dirs_body
from scenarios.config.nav_sensors import DvlConfig
from sim.sensors.base import Mount, SceneView, Sensor
from sim.sensors.noise import dropped, white_noise
from sim.sensors.registry import register_sensor
from sim.dynamics.truth import VehicleTruth

FloatArray = NDArray[np.float64]


def _fitted_plane_ned(points_ned: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Centroid (3,) and unit normal (3,) of the least-squares plane through >= 3 points (n, 3), NED m."""
    centroid = points_ned.mean(axis=0)
    normal = np.linalg.svd(points_ned - centroid)[2][-1]
    return centroid, normal


def _slope_of_normal_rad(normal: np.ndarray) -> float:
    return float(np.arccos(np.clip(abs(normal[2]), 0.0, 1.0)))


def plane_altitude_m(points_ned: np.ndarray, origin_ned: np.ndarray,
                     plane: tuple[np.ndarray, np.ndarray] | None = None) -> float:
    """Vertical distance (m, down positive) from ``origin_ned`` (3,) to the least-squares plane
    through ``points_ned`` (n >= 3, 3), all NED m: the plane's depth directly below the origin
    minus the origin's depth. ``plane``: that plane's (centroid, unit normal) when already
    fitted (saves the SVD).

    Raises:
        ValueError: if the plane is vertical (no point directly below the origin).
    """
    centroid, normal = _fitted_plane_ned(points_ned) if plane is None else plane
    if abs(normal[2]) < 1e-9:
        raise ValueError("plane_altitude_m: the fitted plane is vertical")
    rel = origin_ned - centroid
    return float(-(normal[0] * rel[0] + normal[1] * rel[1]) / normal[2] - rel[2])


@dataclass(frozen=True, slots=True)
class DvlEcho:
    """Exact beam geometry at capture (the DVL's ideal value).

    Attributes:
        t_s: capture time, s.
        origin_ned: (3,) transducer position, NED m.
        dirs_ned: (4, 3) beam unit directions, NED.
        ranges_m: (4,) true slant range of each beam to the first hit (inf: none in range).
        cos_incidence: (4,) cosine of each beam's incidence on the surface hit.
        vel_mount_body_mps: (3,) true velocity over ground of the transducer, FRD m/s.
    """

    t_s: float
    origin_ned: FloatArray
    dirs_ned: FloatArray
    ranges_m: FloatArray
    cos_incidence: FloatArray
    vel_mount_body_mps: FloatArray


@register_sensor(DvlConfig)
class DvlSensor(Sensor[DvlMsg]):
    """Bottom-track DVL at the mount point.

    Each beam measures the radial velocity ``b_i . v_mount`` of the transducer over the
    seabed (``v_mount = v + omega x r`` in FRD); corrupted it becomes
    ``(1 + k) b_i . v_mount + n_i``, ``k`` a per-run scale error (drawn in :meth:`reset`) and
    ``n_i ~ N(0, (beam_noise_mps + noise_frac_speed |v|)^2)``; beam ranges get white noise
    and the lock drops out at random. The velocity is the least-squares solution over the
    valid beams, so the reported ``vel_body_mps`` is the transducer's velocity in FRD.
    ``altitude_m`` is the vertical distance (m) from the transducer down to the least-squares
    plane through the valid beams' footprints (NED), evaluated directly below the transducer,
    so it is exact over any plane at any attitude.

    Bottom lock needs at least ``min_valid_beams`` beams that hit within the slant range of
    ``max_altitude_m``, above ``min_altitude_m``, below the grazing cut-off, and a seabed
    plane through the beam footprints no steeper than ``max_slope_deg``. A rotated mount
    turns the beams with it (the velocity is still reported in the body frame).

    Raises:
        ValueError: ``min_altitude_m >= max_altitude_m``; ``measure`` without a caster.
    """

    def __init__(self, cfg: DvlConfig, mount: Mount | ArrayLike, rng: np.random.Generator | None = None, *,
                 name: str | None = None) -> None:
        if cfg.min_altitude_m >= cfg.max_altitude_m:
            raise ValueError("sensors.dvl: min_altitude_m must be below max_altitude_m")
        super().__init__(cfg, mount, rng, name=name)
        dirs = janus_beam_dirs_body(math.radians(cfg.beam_angle_deg), math.radians(cfg.beam_azimuth_offset_deg))
        self.beam_dirs_body = dirs if self.mount.is_aligned else dirs @ self.mount.R_bs.T
        self.max_slant_range_m = cfg.max_altitude_m / math.cos(math.radians(cfg.beam_angle_deg))
        self._cos_max_incidence = math.cos(math.radians(cfg.max_incidence_deg))

    def reset(self, rng: np.random.Generator) -> None:
        super().reset(rng)
        self._scale_error = float(white_noise(rng, self.cfg.scale_error))

    def ideal(self, truth: VehicleTruth, scene: SceneView) -> DvlEcho:
        caster = scene.require_caster("DvlSensor")
        origin = truth.point_ned(self.mount.pos_body_m)
        dirs_ned = self.beam_dirs_body @ truth.R_nb.T
        hits = caster.cast(origin, dirs_ned, self.max_slant_range_m)
        return DvlEcho(t_s=truth.t_s, origin_ned=origin, dirs_ned=dirs_ned,
                       ranges_m=np.asarray(hits.dist_m, dtype=float),
                       cos_incidence=-np.einsum("ij,ij->i", dirs_ned, hits.normal_ned),
                       vel_mount_body_mps=truth.point_vel_body(self.mount.pos_body_m))

    def exact(self, ideal: DvlEcho) -> DvlMsg:
        return self._message(ideal, noisy=False)

    def corrupt(self, ideal: DvlEcho, truth: VehicleTruth) -> DvlMsg:
        return self._message(ideal, noisy=True)

    def _message(self, echo: DvlEcho, noisy: bool) -> DvlMsg:
        cfg = self.cfg
        ranges = echo.ranges_m.copy()
        if noisy and cfg.range_noise_m > 0.0:
            ranges += white_noise(self._rng, cfg.range_noise_m, 4)
        beam_alt = ranges * echo.dirs_ned[:, 2]
        valid = (
            np.isfinite(ranges)
            & (ranges <= self.max_slant_range_m)
            & (echo.cos_incidence >= self._cos_max_incidence)
            & (beam_alt >= cfg.min_altitude_m)
        )
        ranges[~valid] = np.nan
        if valid.sum() < cfg.min_valid_beams:
            return self._no_lock(echo.t_s, ranges)
        footprints = echo.origin_ned + ranges[valid, None] * echo.dirs_ned[valid]
        plane = _fitted_plane_ned(footprints)  # fitted once: the slope test and the altitude
        if _slope_of_normal_rad(plane[1]) > math.radians(cfg.max_slope_deg):
            return self._no_lock(echo.t_s, ranges)
        if noisy and dropped(self._rng, cfg.dropout_prob):
            return self._no_lock(echo.t_s, ranges)

        B = self.beam_dirs_body[valid]
        radial = B @ echo.vel_mount_body_mps
        if noisy:
            sigma = cfg.beam_noise_mps + cfg.noise_frac_speed * float(np.linalg.norm(echo.vel_mount_body_mps))
            radial = (1.0 + self._scale_error) * radial + white_noise(self._rng, sigma, len(radial))
        vel_body = np.linalg.lstsq(B, radial, rcond=None)[0]
        return DvlMsg(t_s=echo.t_s, vel_body_mps=vel_body, valid=True,
                      altitude_m=plane_altitude_m(footprints, echo.origin_ned, plane),
                      beam_ranges_m=ranges)

    @staticmethod
    def _no_lock(t_s: float, ranges_m: np.ndarray) -> DvlMsg:
        return DvlMsg(t_s=t_s, vel_body_mps=np.full(3, np.nan), valid=False, altitude_m=float("nan"),
                      beam_ranges_m=ranges_m)
