"""Measurement models: function, Jacobian, noise covariance and inverse (the measurement-model role).

* :class:`PositionFix`: linear fix of some state components (GPS north/east, pressure depth,
  a geolocalised sonar detection in NED).
* :class:`RangeBearingElevation`: a USBL head's range, bearing and elevation of a point.
* :class:`RangeAzimuth`: a forward-looking sonar's range and azimuth (elevation unobserved).

The spherical models take the point in the frame of the vehicle carrying the sensor (FRD,
m) and the sensor head's position in that frame (``mount_pos_m``); bearing/azimuth is
positive to starboard, elevation positive downwards, ranges in m, angles in rad.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from autonomy.frames import wrap_angle

FloatArray = NDArray[np.float64]


class PositionFix:
    """Linear fix ``z = H x + w``, ``w ~ N(0, R)``, where H picks the ``mapping`` components.

    Args:
        ndim_state: size n of the state.
        mapping: state indices measured, in measurement order (m of them).
        noise_covar: (m, m) R; None when each measurement carries its own covariance
            (then pass it to the updater and initiator).

    Raises:
        ValueError: bad mapping or covariance shape.
    """

    def __init__(self, ndim_state: int, mapping: Sequence[int], noise_covar: ArrayLike | None = None) -> None:
        idx = np.asarray(mapping, dtype=np.intp).reshape(-1)
        if idx.size == 0 or idx.min() < 0 or idx.max() >= ndim_state or len(set(idx.tolist())) != idx.size:
            raise ValueError(f"PositionFix mapping {mapping!r} must be distinct indices into {ndim_state} states")
        self.ndim_state = int(ndim_state)
        self.mapping = idx
        self.ndim_meas = int(idx.size)
        full = idx.size == ndim_state and np.array_equal(idx, np.arange(ndim_state))
        # index with a slice when H = I: a view, and the same floating-point operations as I x
        self._index: slice | NDArray[np.intp] = slice(None) if full else idx
        self._noise = None if noise_covar is None else np.asarray(noise_covar, dtype=float)
        if self._noise is not None and self._noise.shape != (self.ndim_meas, self.ndim_meas):
            raise ValueError(f"PositionFix noise_covar must be ({self.ndim_meas}, {self.ndim_meas})")

    def matrix(self) -> FloatArray:
        """H (m, n)."""
        H = np.zeros((self.ndim_meas, self.ndim_state))
        H[np.arange(self.ndim_meas), self.mapping] = 1.0
        return H

    def function(self, state: ArrayLike) -> FloatArray:
        """h(x) = H x for ``state`` (..., n) -> (..., m)."""
        return np.asarray(state, dtype=float)[..., self._index]

    def jacobian(self, state: ArrayLike | None = None) -> FloatArray:
        """dh/dx = H (m, n)."""
        return self.matrix()

    def covar(self) -> FloatArray:
        """R (m, m).

        Raises:
            ValueError: the model was built without a noise covariance.
        """
        if self._noise is None:
            raise ValueError("PositionFix has no fixed noise_covar; pass each measurement's covariance")
        return self._noise.copy()

    def project_covar(self, covar: ArrayLike) -> FloatArray:
        """H P H^T for ``covar`` (..., n, n) -> (..., m, m)."""
        P = np.asarray(covar, dtype=float)
        if isinstance(self._index, slice):
            return P
        return P[..., self._index[:, None], self._index]

    def cross_covar(self, covar: ArrayLike) -> FloatArray:
        """H P for ``covar`` (..., n, n) -> (..., m, n)."""
        return np.asarray(covar, dtype=float)[..., self._index, :]

    def residual(self, z: ArrayLike, z_pred: ArrayLike) -> FloatArray:
        """z - z_pred (no angles to wrap)."""
        return np.asarray(z, dtype=float) - z_pred

    def inverse(self, z: ArrayLike) -> FloatArray:
        """The state (n,) with the measured components set to ``z`` (m,), others zero."""
        x = np.zeros(self.ndim_state)
        x[self._index] = np.asarray(z, dtype=float)
        return x

    def inverse_jacobian(self, z: ArrayLike | None = None) -> FloatArray:
        """d inverse / dz = H^T (n, m)."""
        return self.matrix().T


class RangeBearingElevation:
    """Range, bearing and elevation of a point seen from a sensor head (USBL).

    ``d = p - mount_pos_m``; ``range = |d|``, ``bearing = atan2(d_y, d_x)`` (starboard > 0),
    ``elevation = atan2(d_z, hypot(d_x, d_y))`` (down > 0). Noise: range sigma
    ``range_sigma_m + range_sigma_frac * range`` (grows with range), both angles
    ``angle_sigma_rad``.

    Raises:
        ValueError: a negative sigma or a mount that is not 3 finite numbers.
    """

    ndim_meas = 3
    angle_components = (1, 2)

    def __init__(
        self,
        mount_pos_m: ArrayLike = (0.0, 0.0, 0.0),
        range_sigma_m: float = 0.0,
        range_sigma_frac: float = 0.0,
        angle_sigma_rad: float = 0.0,
    ) -> None:
        mount = np.asarray(mount_pos_m, dtype=float).reshape(-1)
        if mount.shape != (3,) or not np.all(np.isfinite(mount)):
            raise ValueError(f"mount_pos_m must be 3 finite metres, got {mount_pos_m!r}")
        if min(range_sigma_m, range_sigma_frac, angle_sigma_rad) < 0.0:
            raise ValueError("range and angle sigmas must be >= 0")
        self.mount_pos_m = mount
        self.range_sigma_m = float(range_sigma_m)
        self.range_sigma_frac = float(range_sigma_frac)
        self.angle_sigma_rad = float(angle_sigma_rad)

    def function(self, point_m: ArrayLike) -> FloatArray:
        """[range_m, bearing_rad, elevation_rad] (3,) of ``point_m`` (3,)."""
        x, y, z = d = np.asarray(point_m, dtype=float) - self.mount_pos_m
        return np.array([np.linalg.norm(d), np.arctan2(y, x), np.arctan2(z, np.hypot(x, y))])

    def jacobian(self, point_m: ArrayLike) -> FloatArray:
        """d[range, bearing, elevation]/d point (3, 3); singular on the vertical through the head."""
        x, y, z = np.asarray(point_m, dtype=float) - self.mount_pos_m
        rho2 = x * x + y * y
        rho = np.sqrt(rho2)
        r2 = rho2 + z * z
        r = np.sqrt(r2)
        return np.array(
            [
                [x / r, y / r, z / r],
                [-y / rho2, x / rho2, 0.0],
                [-x * z / (rho * r2), -y * z / (rho * r2), rho / r2],
            ]
        )

    def covar(self, range_m: float) -> FloatArray:
        """R (3, 3) at a measured range: diag(sigma_r^2, sigma_a^2, sigma_a^2)."""
        sig_r = self.range_sigma_m + self.range_sigma_frac * range_m
        sig_a = self.angle_sigma_rad
        return np.diag([sig_r**2, sig_a**2, sig_a**2])

    def residual(self, z: ArrayLike, z_pred: ArrayLike) -> FloatArray:
        """z - z_pred with the angle differences wrapped to [-pi, pi)."""
        res = np.asarray(z, dtype=float) - z_pred
        res[1:] = wrap_angle(res[1:])
        return res

    def inverse(self, z: ArrayLike) -> FloatArray:
        """The point (3,) at [range, bearing, elevation] ``z`` (3,)."""
        r, b, e = np.asarray(z, dtype=float)
        return self.mount_pos_m + r * np.array([np.cos(e) * np.cos(b), np.cos(e) * np.sin(b), np.sin(e)])

    def inverse_jacobian(self, z: ArrayLike) -> FloatArray:
        """d inverse / d[range, bearing, elevation] (3, 3)."""
        r, b, e = np.asarray(z, dtype=float)
        cb, sb, ce, se = np.cos(b), np.sin(b), np.cos(e), np.sin(e)
        return np.array(
            [
                [ce * cb, -r * ce * sb, -r * se * cb],
                [ce * sb, r * ce * cb, -r * se * sb],
                [se, 0.0, r * ce],
            ]
        )


class RangeAzimuth:
    """Range and azimuth of a point seen by an imaging sonar (paper 000 eq. 3); the elevation
    is not observed (the fan's vertical aperture).

    The point is given in the sonar frame (x boresight, y starboard, z down) relative to the
    head at ``mount_pos_m``; azimuth is positive to starboard. The inverse needs an
    elevation: zero (paper 000 eq. 4) unless given (e.g. from a flat-seabed solution).

    Raises:
        ValueError: a negative sigma or a bad mount (as :class:`RangeBearingElevation`).
    """

    ndim_meas = 2
    angle_components = (1,)

    def __init__(self, mount_pos_m: ArrayLike = (0.0, 0.0, 0.0), range_sigma_m: float = 0.0,
                 azimuth_sigma_rad: float = 0.0) -> None:
        self._rbe = RangeBearingElevation(mount_pos_m, range_sigma_m, 0.0, azimuth_sigma_rad)
        self.mount_pos_m = self._rbe.mount_pos_m
        self.range_sigma_m = float(range_sigma_m)
        self.azimuth_sigma_rad = float(azimuth_sigma_rad)

    def function(self, point_m: ArrayLike) -> FloatArray:
        """[range_m, azimuth_rad] (2,) of ``point_m`` (3,)."""
        return self._rbe.function(point_m)[:2]

    def jacobian(self, point_m: ArrayLike) -> FloatArray:
        """d[range, azimuth]/d point (2, 3)."""
        return self._rbe.jacobian(point_m)[:2]

    def covar(self) -> FloatArray:
        """R (2, 2) = diag(sigma_r^2, sigma_a^2)."""
        return np.diag([self.range_sigma_m**2, self.azimuth_sigma_rad**2])

    def residual(self, z: ArrayLike, z_pred: ArrayLike) -> FloatArray:
        """z - z_pred with the azimuth difference wrapped to [-pi, pi)."""
        res = np.asarray(z, dtype=float) - z_pred
        res[1] = wrap_angle(res[1])
        return res

    def inverse(self, z: ArrayLike, elevation_rad: float = 0.0) -> FloatArray:
        """The point (3,) at [range, azimuth] ``z`` and the given elevation."""
        r, a = np.asarray(z, dtype=float)
        return self._rbe.inverse([r, a, elevation_rad])

    def inverse_jacobian(self, z: ArrayLike, elevation_rad: float = 0.0) -> FloatArray:
        """d inverse / d[range, azimuth] (3, 2) at the given elevation."""
        r, a = np.asarray(z, dtype=float)
        return self._rbe.inverse_jacobian([r, a, elevation_rad])[:, :2]
