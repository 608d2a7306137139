"""Doppler velocity log: four ray-cast Janus beams, bottom lock, speed-dependent noise."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from autonomy.messages import DvlMsg
from autonomy.navigation.dvl_geometry import janus_beam_dirs_body
from scenarios.config.nav_sensors import DvlConfig
from sim.sensors.noise import dropped, white_noise
from sim.sensors.base import HullSensor
from sim.sensors.raycast import RayCaster
from sim.truth import VehicleTruth


def _cross(a, b):
    """3-vector cross product (np.cross is slow for single vectors)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def _fitted_plane_ned(points_ned: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Centroid (3,) and unit normal (3,) of the least-squares plane through >= 3 points (n, 3), NED m."""
    centroid = points_ned.mean(axis=0)
    normal = np.linalg.svd(points_ned - centroid)[2][-1]
    return centroid, normal


def fitted_slope_rad(points_ned: np.ndarray) -> float:
    """Slope (rad from horizontal) of the least-squares plane through >= 3 points (n, 3)."""
    normal = _fitted_plane_ned(points_ned)[1]
    return float(np.arccos(np.clip(abs(normal[2]), 0.0, 1.0)))


def plane_altitude_m(points_ned: np.ndarray, origin_ned: np.ndarray) -> float:
    """Vertical distance (m, down positive) from ``origin_ned`` (3,) to the least-squares plane
    through ``points_ned`` (n >= 3, 3), all NED m: the plane's depth directly below the origin
    minus the origin's depth.

    Raises:
        ValueError: if the plane is vertical (no point directly below the origin).
    """
    centroid, normal = _fitted_plane_ned(points_ned)
    if abs(normal[2]) < 1e-9:
        raise ValueError("plane_altitude_m: the fitted plane is vertical")
    rel = origin_ned - centroid
    return float(-(normal[0] * rel[0] + normal[1] * rel[1]) / normal[2] - rel[2])


class DvlSensor(HullSensor):
    """Bottom-track DVL at ``mount_pos_body_m`` (FRD).

    Each beam measures the radial velocity ``b_i . v_mount`` of the transducer over the
    seabed (``v_mount = v + omega x r`` in FRD); with noise it becomes
    ``(1 + k) b_i . v_mount + n_i``, ``k`` a per-run scale error and
    ``n_i ~ N(0, (beam_noise_mps + noise_frac_speed |v|)^2)``. The velocity is the
    least-squares solution over the valid beams, so the reported ``vel_body_mps`` is the
    transducer's velocity in FRD. ``altitude_m`` is the vertical distance (m) from the
    transducer down to the least-squares plane through the valid beams' footprints (NED),
    evaluated directly below the transducer, so it is exact over any plane at any attitude.

    Bottom lock needs at least ``min_valid_beams`` beams that hit within the slant range of
    ``max_altitude_m``, above ``min_altitude_m``, below the grazing cut-off, and a seabed
    plane through the beam footprints no steeper than ``max_slope_deg``.
    """

    name = "dvl"

    def __init__(self, cfg: DvlConfig, mount_pos_body_m: ArrayLike, rng: np.random.Generator):
        if cfg.min_altitude_m >= cfg.max_altitude_m:
            raise ValueError("sensors.dvl: min_altitude_m must be below max_altitude_m")
        super().__init__(cfg, mount_pos_body_m, rng)
        self.beam_dirs_body = janus_beam_dirs_body(
            math.radians(cfg.beam_angle_deg), math.radians(cfg.beam_azimuth_offset_deg)
        )
        self.max_slant_range_m = cfg.max_altitude_m / math.cos(math.radians(cfg.beam_angle_deg))
        self._cos_max_incidence = math.cos(math.radians(cfg.max_incidence_deg))
        self._scale_error = float(white_noise(rng, cfg.scale_error))

    def _no_lock(self, t_s: float, ranges_m: np.ndarray) -> DvlMsg:
        return DvlMsg(t_s=t_s, vel_body_mps=np.full(3, np.nan), valid=False, altitude_m=float("nan"),
                      beam_ranges_m=ranges_m)

    def measure(self, truth: VehicleTruth, *, caster: RayCaster | None = None, noise: bool = True) -> DvlMsg:
        if caster is None:
            raise ValueError("DvlSensor.measure needs a RayCaster (caster=...)")
        cfg = self.cfg
        origin = truth.point_ned(self.mount_pos_body_m)
        dirs_ned = self.beam_dirs_body @ truth.R_nb.T
        hits = caster.cast(origin, dirs_ned, self.max_slant_range_m)
        ranges = np.asarray(hits.dist_m, dtype=float).copy()
        if noise and cfg.range_noise_m > 0.0:
            ranges += white_noise(self._rng, cfg.range_noise_m, 4)
        cos_incidence = -np.einsum("ij,ij->i", dirs_ned, hits.normal_ned)
        beam_alt = ranges * dirs_ned[:, 2]
        valid = (
            np.isfinite(ranges)
            & (ranges <= self.max_slant_range_m)
            & (cos_incidence >= self._cos_max_incidence)
            & (beam_alt >= cfg.min_altitude_m)
        )
        ranges[~valid] = np.nan
        if valid.sum() < cfg.min_valid_beams:
            return self._no_lock(truth.t_s, ranges)
        footprints = origin + ranges[valid, None] * dirs_ned[valid]
        if fitted_slope_rad(footprints) > math.radians(cfg.max_slope_deg):
            return self._no_lock(truth.t_s, ranges)
        if noise and dropped(self._rng, cfg.dropout_prob):
            return self._no_lock(truth.t_s, ranges)

        v_mount = truth.nu[:3] + _cross(truth.nu[3:], self.mount_pos_body_m)
        B = self.beam_dirs_body[valid]
        radial = B @ v_mount
        if noise:
            sigma = cfg.beam_noise_mps + cfg.noise_frac_speed * float(np.linalg.norm(v_mount))
            radial = (1.0 + self._scale_error) * radial + white_noise(self._rng, sigma, len(radial))
        vel_body = np.linalg.lstsq(B, radial, rcond=None)[0]
        return DvlMsg(t_s=truth.t_s, vel_body_mps=vel_body, valid=True,
                      altitude_m=plane_altitude_m(footprints, origin), beam_ranges_m=ranges)
