"""Sensor and autonomy messages exchanged between the simulator and the onboard stack.

Frames: positions in NED (m), body quantities in FRD, angles in radians, times in
seconds of mission time. Every message is an immutable dataclass.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from autonomy.sonar_geometry import FanGeometry

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class ImuMsg:
    """AHRS/IMU output: attitude, body rates and specific force."""

    t_s: float
    rpy_rad: FloatArray  # (3,) roll, pitch, yaw (yaw from FOG when fitted)
    rate_body_radps: FloatArray  # (3,) p, q, r
    accel_body_mps2: FloatArray  # (3,) specific force in FRD (reads -g at rest: [0, 0, -9.81])


@dataclass(frozen=True, slots=True)
class DvlMsg:
    """Doppler velocity log: bottom-track velocity in the body frame."""

    t_s: float
    vel_body_mps: FloatArray  # (3,) FRD; NaN when not valid
    valid: bool  # bottom lock
    altitude_m: float  # m, transducer to the beam-footprint plane straight below; NaN when not valid
    beam_ranges_m: FloatArray = field(default_factory=lambda: np.full(4, np.nan))  # (4,)


@dataclass(frozen=True, slots=True)
class WrenchCmdMsg:
    """The autopilot's commanded body wrench (what it asks of the thrusters, not what they give)."""

    t_s: float
    wrench_body: FloatArray  # (6,) X, Y, Z force (N), K, M, N moment (N m), FRD


@dataclass(frozen=True, slots=True)
class DepthMsg:
    t_s: float
    depth_m: float


@dataclass(frozen=True, slots=True)
class AltimeterMsg:
    t_s: float
    altitude_m: float  # NaN when out of range
    valid: bool


@dataclass(frozen=True, slots=True)
class GpsMsg:
    """GPS fix, only produced with the antenna at the surface."""

    t_s: float
    pos_ne_m: FloatArray  # (2,) north, east in the mission NED frame
    valid: bool


@dataclass(frozen=True, slots=True)
class UsblMsg:
    """USBL fix of a transponder, in the USBL head's frame (range, bearing, elevation).

    ``t_s`` is the time the fix was measured (the interrogation), not its arrival: the fix
    reaches the vehicle later by the acoustic two-way travel time and the processing delay,
    so a consumer must apply it at ``t_s``. ``valid`` is False (NaN values) when the
    transponder did not answer. ``transponder`` names the transponder ("beacon": a fixed
    beacon at a known position, for navigation).
    """

    t_s: float
    range_m: float
    bearing_rad: float  # starboard > 0
    elevation_rad: float  # down > 0
    transponder: str = "beacon"
    valid: bool = True


@dataclass(frozen=True, slots=True)
class FlsFrame:
    """One forward-looking-sonar frame as the vehicle sees it (no ground truth).

    ``polar`` is (n_beams, n_bins) uint8, beam 0 at the most port azimuth; ``fan`` is the
    Cartesian fan image (height_px, width_px) uint8 made from it. ``geometry`` maps fan
    pixels to (range, azimuth) and back. ``mount_*`` give the sonar's fixed extrinsics on
    the hull.
    """

    t_s: float
    polar: NDArray[np.uint8]
    fan: NDArray[np.uint8]
    geometry: FanGeometry
    mount_pos_body_m: FloatArray  # (3,) FRD offset of the sonar head from the body origin
    mount_rpy_rad: FloatArray  # (3,) sonar frame w.r.t. body (tilt is the pitch, down > 0)


@dataclass(frozen=True, slots=True)
class Detection:
    """An ATR detection on one FLS frame."""

    t_s: float
    class_name: str
    score: float  # in [0, 1]
    box_xyxy_px: FloatArray  # (4,) x0, y0, x1, y1 in the fan image
    range_m: float  # range of the box's reference point
    azimuth_rad: float  # azimuth of the box's reference point (starboard > 0)


@dataclass(frozen=True, slots=True)
class NavEstimate:
    """Navigation filter output."""

    t_s: float
    pos_ned: FloatArray  # (3,)
    rpy_rad: FloatArray  # (3,)
    vel_body_mps: FloatArray  # (3,)
    rate_body_radps: FloatArray  # (3,)
    cov_pos_ned: FloatArray  # (3, 3) position covariance, m^2
    cov_yaw_rad2: float = 0.0
    altitude_m: float = float("nan")


@dataclass(frozen=True, slots=True)
class MsisPing:
    """One ping of a mechanically scanned imaging sonar (Ping360 ``device_data``-like).

    Sample ``k`` covers slant range ``[k, k + 1) * sample_spacing_m`` from the head along the
    beam at ``angle_grad`` (gradians, 400 per turn, 0 = the mount's boresight, clockwise seen
    from above). ``mount_*`` give the head's fixed extrinsics on the hull ([P002], [Ping360]).
    """

    t_s: float
    angle_grad: float
    step_grad: int
    sample_period_ticks: int  # 25 ns ticks
    sample_spacing_m: float  # c * 25 ns * sample_period / 2
    transmit_duration_us: float
    speed_of_sound_mps: float
    intensity: NDArray[np.uint8]  # (number_of_samples,)
    mount_pos_body_m: FloatArray  # (3,) FRD offset of the head from the body origin
    mount_rpy_rad: FloatArray  # (3,) head frame at angle 0 w.r.t. body (tilt is the pitch, down > 0)

    @property
    def angle_rad(self) -> float:
        """Head angle, rad (clockwise seen from above, starboard > 0)."""
        return float(self.angle_grad) * (np.pi / 200.0)


@dataclass(frozen=True, slots=True)
class PositionFixMsg:
    """A horizontal position fix of the body origin with its covariance (feature-based
    localisation, e.g. a pool's circle or a tank's walls).

    The optional feature fields say what the fix was made from, in the navigation frame of
    the estimate it corrects (before the fix): the echo points, the fitted circle or the
    fitted wall segments with their 95 % rho half-widths.
    """

    t_s: float
    pos_ne_m: FloatArray  # (2,) north, east of the body origin, mission NED frame
    cov_ne_m2: FloatArray  # (2, 2)
    source: str = ""
    points_ne_m: FloatArray | None = None  # (N, 2) echo points of the fix, north, east m
    circle_ne_m: FloatArray | None = None  # (3,) fitted circle: centre north, east, radius, m
    segments_ne_m: FloatArray | None = None  # (k, 2, 2) segment end points (north, east), m
    segments_rho95_m: FloatArray | None = None  # (k,) 95 % rho half-width of each segment, m
    # heading error of the estimate the features were placed with (estimate - true, rad, e.g.
    # from walls of known direction) and its variance; NaN: none
    heading_err_rad: float = float("nan")
    heading_var_rad2: float = float("nan")


@dataclass(frozen=True, slots=True)
class SssPing:
    """One side-scan sonar ping: a port and a starboard echo line.

    Attributes:
        t_s: ping time, s.
        lines_u8: (2, n_bins) uint8 display lines, row 0 port, row 1 starboard; bin k of a
            side is slant range ``[k, k + 1) * bin_size_m`` from its transducer.
        bin_size_m: slant-range bin size, m.
        altitude_m: range of the first bottom return (the vertical ray), m; ``nan`` without one.
        ground_lines_u8: (2, n_ground) the lines resampled to ground range (bin size
            ``bin_size_m``, from nadir outwards) when the sonar's ``ground_range`` is on, else None.
        mount_pos_body_m: (3,) FRD position of the transducers, m.
    """

    t_s: float
    lines_u8: NDArray[np.uint8]
    bin_size_m: float
    altitude_m: float
    ground_lines_u8: NDArray[np.uint8] | None = None
    mount_pos_body_m: FloatArray = field(default_factory=lambda: np.zeros(3))
