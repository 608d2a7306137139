"""Forward-looking sonar hardware presets and their resolution against a scenario config.

Figures from paper 000 Table II for the BlueView M900-130 and paper 004 for the ARIS 3000
(``docs/references.md`` [BlueViewM900], [ARIS3000]). Values marked "estimate" are ours: horizontal beam widths, ARIS range
resolution and absorption at the operating frequency.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from scenarios.config.fls import PRESET_GEOMETRY_KEYS, FlsConfig


@dataclass(frozen=True, slots=True)
class FlsPreset:
    """Sonar hardware. Angles in degrees, ranges in metres."""

    fov_deg: float
    n_beams: int
    vertical_beamwidth_deg: float
    range_min_m: float
    range_max_m: float
    range_resolution_m: float
    beamwidth_az_deg: float
    absorption_db_per_m: float
    fan_size_px: tuple[int, int]  # (width, height)
    range_window_m: tuple[float, float] | None = None  # default displayed window
    pings_per_frame: int | None = None  # transmit cycles per image (None: not modelled, no rate limit)
    frequency_hz: float = 0.0  # centre (operating) frequency; 0: unknown


SOUND_SPEED_MPS = 1500.0  # nominal, for the two-way listening time of a ping


def max_frame_rate_hz(pings_per_frame: int, window_far_m: float, sound_speed_mps: float = SOUND_SPEED_MPS) -> float:
    """Highest frame rate of a sonar that fires ``pings_per_frame`` transmit cycles per image,
    each listening for the two-way travel time to the far end of the window:
    ``c / (2 far pings_per_frame)`` (Sound Metrics ARIS Integration SDK, max frame rate =
    1 / (cycle period x pings per frame); ``docs/references.md`` [ARISSDK]). Hz."""
    return float(sound_speed_mps / (2.0 * window_far_m * pings_per_frame))


PRESETS: dict[str, FlsPreset] = {
    # BlueView M900-130: 130 x 20 deg, 100 m, 0.18 deg spacing (722 beams), 1 inch bins, 894x477 fan.
    # Beam width 1 deg and 0.25 dB/m absorption at 900 kHz are estimates.
    "m900_130": FlsPreset(130.0, 722, 20.0, 1.0, 100.0, 0.0254, 1.0, 0.25, (894, 477), frequency_hz=900e3),
    # ARIS 3000, 3 MHz mode: 30 x 14 deg, 128 beams, 5 m. Resolution / beam width / absorption estimates.
    # 128 beams are formed in 8 transmit cycles per frame (the SDK's ping mode 9).
    "aris3000": FlsPreset(30.0, 128, 14.0, 0.7, 5.0, 0.003, 0.25, 0.9, (512, 512), pings_per_frame=8,
                          frequency_hz=3.0e6),
    # ARIS 3000, 1.8 MHz mode: 15 m (at most 6.25 frames/s over the full window).
    "aris3000_lf": FlsPreset(30.0, 128, 14.0, 0.7, 15.0, 0.01, 0.4, 0.45, (512, 512), pings_per_frame=8,
                             frequency_hz=1.8e6),
}


@dataclass(frozen=True, slots=True)
class FlsGeometry:
    """Resolved sonar geometry and sampling (all radians / metres).

    The polar image has ``n_beams`` rows (beam 0 most port) and ``n_bins`` columns;
    beam b is centred on azimuth ``-fov/2 + (b + 0.5) fov / n_beams`` and bin k spans
    ``[window_near + k dr, window_near + (k + 1) dr)``.
    """

    fov_rad: float
    n_beams: int
    vertical_beamwidth_rad: float
    range_max_m: float  # hardware limit: rays are cast this far
    window_near_m: float
    window_far_m: float
    range_resolution_m: float
    beamwidth_az_rad: float
    absorption_db_per_m: float
    fan_size_px: tuple[int, int]
    elevation_rays: int
    azimuth_columns: int
    frequency_hz: float = 0.0  # the preset's centre frequency (0: unknown)
    sound_speed_mps: float = SOUND_SPEED_MPS  # the nominal speed that turns travel times into ranges
    elevation_span_beamwidths: float = 1.0  # rays span this many vertical beam widths

    @property
    def n_bins(self) -> int:
        return int(np.ceil((self.window_far_m - self.window_near_m) / self.range_resolution_m - 1e-9))

    @property
    def beam_spacing_rad(self) -> float:
        return self.fov_rad / self.n_beams

    def beam_azimuths_rad(self) -> np.ndarray:
        """(n_beams,) beam centre azimuths, port (negative) to starboard."""
        return -0.5 * self.fov_rad + (np.arange(self.n_beams) + 0.5) * self.beam_spacing_rad

    def column_azimuths_rad(self) -> np.ndarray:
        """(azimuth_columns,) azimuths of the ray columns, cell-centred like the beams."""
        step = self.fov_rad / self.azimuth_columns
        return -0.5 * self.fov_rad + (np.arange(self.azimuth_columns) + 0.5) * step

    def elevations_rad(self) -> np.ndarray:
        """(elevation_rays,) ray elevations, up (negative) to down, edges included: the vertical
        beam width times ``elevation_span_beamwidths``."""
        half = 0.5 * self.vertical_beamwidth_rad * self.elevation_span_beamwidths
        return np.linspace(-half, half, self.elevation_rays)

    def bin_centres_m(self) -> np.ndarray:
        return self.window_near_m + (np.arange(self.n_bins) + 0.5) * self.range_resolution_m


def resolve_geometry(cfg: FlsConfig) -> FlsGeometry:
    """Preset values overridden by every non-``None`` field of ``cfg``; checked for sense."""
    p = PRESETS[cfg.preset]
    over = {k: getattr(cfg, k) for k in PRESET_GEOMETRY_KEYS if getattr(cfg, k) is not None}
    p = replace(p, **over)
    near, far = p.range_window_m if p.range_window_m is not None else (p.range_min_m, p.range_max_m)
    if not (p.range_min_m <= near < far <= p.range_max_m):
        raise ValueError(
            f"sensors.fls.range_window_m: ({near}, {far}) must lie inside the {cfg.preset} range "
            f"limits [{p.range_min_m}, {p.range_max_m}] m with near < far")
    if (far - near) / p.range_resolution_m > 20000:
        raise ValueError(f"sensors.fls: window {far - near:g} m at {p.range_resolution_m:g} m bins "
                         "gives more than 20000 bins; coarsen range_resolution_m or narrow the window")
    if p.pings_per_frame is not None and cfg.rate_hz > (fmax := max_frame_rate_hz(p.pings_per_frame, far)) + 1e-9:
        raise ValueError(f"sensors.fls.rate_hz: {cfg.rate_hz:g} Hz is above the {cfg.preset}'s {fmax:.2f} frames/s "
                         f"for a {far:g} m window ({p.pings_per_frame} pings per frame, each listening "
                         f"2 x {far:g} m / {SOUND_SPEED_MPS:g} m/s); lower rate_hz or shorten range_window_m")
    columns = cfg.azimuth_columns if cfg.azimuth_columns is not None else p.n_beams
    if columns > p.n_beams:
        raise ValueError(f"sensors.fls.azimuth_columns ({columns}) must not exceed n_beams ({p.n_beams})")
    return FlsGeometry(
        fov_rad=float(np.deg2rad(p.fov_deg)), n_beams=int(p.n_beams),
        vertical_beamwidth_rad=float(np.deg2rad(p.vertical_beamwidth_deg)), range_max_m=float(p.range_max_m),
        window_near_m=float(near), window_far_m=float(far), range_resolution_m=float(p.range_resolution_m),
        beamwidth_az_rad=float(np.deg2rad(p.beamwidth_az_deg)), absorption_db_per_m=float(p.absorption_db_per_m),
        fan_size_px=(int(p.fan_size_px[0]), int(p.fan_size_px[1])), elevation_rays=int(cfg.elevation_rays),
        azimuth_columns=int(columns), frequency_hz=float(p.frequency_hz),
        elevation_span_beamwidths=float(cfg.formation.elevation_span_beamwidths),
    )
