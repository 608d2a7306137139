"""Image-formation settings a sonar shares (forward-looking and side-scan): correlated speckle,
seabed texture, volume reverberation and the display law.

Every field's default leaves the image formation as it was: speckle drawn independently per
range bin and line, no texture, no reverberation, a dB display. The models and their sources
are in :mod:`sim.sensors.sonar.image_formation`; the values a real sonar calls for are
estimated in ``docs/studies/realism.md``.
"""

from __future__ import annotations

from pydantic import Field

from scenarios.config.base import StrictModel


class SonarFormationConfig(StrictModel):
    """Image formation beyond independent speckle.

    Attributes:
        pulse_length_m: range extent of the transmitted pulse (c tau / 2), m; None: one range
            bin (speckle independent between bins). Longer pulses correlate neighbouring bins.
        beam_correlated_speckle: correlate the speckle of neighbouring lines by the beams'
            two-way amplitude pattern (their overlap); False: independent lines.
        texture_sigma: standard deviation of the log of the seabed's log-normal texture (0: none).
        texture_corr_m: correlation length (Gaussian sigma) of the texture's log, m.
        reverberation_db: volume reverberation level at 1 m before TVG, dB on the noise floor's
            scale (None: none). Falls as ``r^-2`` with absorption, flat under 20 log r TVG.
        display_gamma: show amplitude to this power (``255 (A / A_0)^gamma``, saturating; 0 dB
            after the gain is 255); None: the dB display over ``dynamic_range_db``.
        display_soft_limit: with ``display_gamma``, pass the power law through ``tanh`` (a
            receiver that limits softly: the brightest echoes approach white without piling up).
        object_rice_k: Rice factor of object echoes: coherent (specular) over diffuse power
            (0: fully developed speckle on objects too).
        object_tail_m: e-folding length along range of the echo tail that follows each object's
            echo (multipath between object and floor, a shell's ringing), m; None: no tail.
        object_tail_ratio: energy of that tail over the object's direct echo.
        object_specular_share: share of an object's backscatter in a specular lobe,
            ``cos^object_specular_exponent(incidence)``, beside the diffuse ``cos^m`` of the
            sonar's ``scattering_exponent`` (0: diffuse only). Smooth plastic and metal return
            mostly where the surface faces the sonar: a cylinder shows a bright line, not a fill.
        object_specular_exponent: the lobe's exponent (larger: narrower).
        object_back_wall_ratio: energy of the echo from an object's far wall over its near
            wall's (sound passes through a thin shell, a bottle or a can, and returns from the
            far side as well); 0: the near surface only. The far wall is where each ray leaves
            the object. Objects of bounding radius above 1 m (walls, structures) are solid.
        object_back_wall_repeats: echoes of sound ringing between the walls: the k-th comes one
            more wall-to-wall crossing later, with ``object_back_wall_ratio ** k`` of the energy.
        side_lobe_floor_db: two-way level (dB re the main lobe) the azimuth pattern keeps outside
            its main lobe, out to the sonar's ``side_lobe_extent_beamwidths`` (None: the ideal
            aperture's falling side lobes). Bright echoes then streak along the arc.
        elevation_span_beamwidths: rays span this many vertical -3 dB beam widths (1: the
            nominal beam; 2.26 reaches the main lobe's first null, where the floor enters the
            beam gradually instead of at a hard edge). Forward-looking sonar only.
    """

    pulse_length_m: float | None = Field(None, gt=0.0, le=10.0)
    beam_correlated_speckle: bool = False
    texture_sigma: float = Field(0.0, ge=0.0, le=3.0)
    texture_corr_m: float = Field(0.05, gt=0.0, le=100.0)
    reverberation_db: float | None = Field(None, ge=-200.0, le=0.0)
    display_gamma: float | None = Field(None, gt=0.0, le=4.0)
    display_soft_limit: bool = False
    side_lobe_floor_db: float | None = Field(None, ge=-120.0, le=-3.0)
    object_rice_k: float = Field(0.0, ge=0.0, le=100.0)
    object_tail_m: float | None = Field(None, gt=0.0, le=10.0)
    object_tail_ratio: float = Field(0.0, ge=0.0, le=10.0)
    elevation_span_beamwidths: float = Field(1.0, ge=1.0, le=4.0)
    object_specular_share: float = Field(0.0, ge=0.0, le=1.0)
    object_specular_exponent: float = Field(20.0, ge=1.0, le=1000.0)
    object_back_wall_ratio: float = Field(0.0, ge=0.0, le=1.0)
    object_back_wall_repeats: int = Field(1, ge=1, le=6, strict=True)

    @property
    def is_default(self) -> bool:
        """Whether every field keeps today's image formation."""
        return self == SonarFormationConfig()
