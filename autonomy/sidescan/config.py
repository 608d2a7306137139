"""Onboard side-scan MCM config (``mcm`` block of a full-mode scenario): tile period and the
highlight-shadow detector's thresholds."""

from __future__ import annotations

from pydantic import Field

from autonomy.config_base import StrictModel


class SssDetectorConfig(StrictModel):
    """Highlight-shadow detector on a ground-range tile (:mod:`autonomy.sidescan.detector`).

    Intensities are normalised per range column by the column's median over the tile's pings
    (the seabed level at that range). ``smooth_along_m`` x ``smooth_range_m``: box filter against speckle, m;
    ``highlight_ratio``: a highlight pixel is at least this times the seabed level;
    ``shadow_ratio``: a shadow pixel at most this; ``min_highlight_m2``: smallest highlight
    blob, m^2; ``shadow_window_m``: ground range just beyond the highlight searched for the
    shadow, m; ``min_shadow_fraction``: fraction of that window that must be shadow;
    ``near_m``: ground ranges closer than this are ignored (nadir and first returns), m.
    Class likelihood: ``pi`` of class 1 (mine-like) is ``sigmoid((length - class_length_m) /
    class_length_scale_m)`` of the highlight's along-track length.
    """

    smooth_along_m: float = Field(0.5, gt=0.0, le=10.0)
    smooth_range_m: float = Field(0.1, gt=0.0, le=10.0)
    highlight_ratio: float = Field(1.8, gt=1.0)
    shadow_ratio: float = Field(0.35, gt=0.0, lt=1.0)
    min_highlight_m2: float = Field(0.05, gt=0.0)
    shadow_window_m: float = Field(1.5, gt=0.0)
    min_shadow_fraction: float = Field(0.5, gt=0.0, le=1.0)
    near_m: float = Field(6.0, ge=0.0)
    merge_m: float = Field(1.5, ge=0.0, description="highlight blobs closer than this are one object, m")
    class_length_m: float = Field(1.3, gt=0.0, description="along-track highlight length between the classes, m")
    class_length_scale_m: float = Field(0.25, gt=0.0)


class SssTileConfig(StrictModel):
    """Tile assembly: one tile pair every ``tile_period_s`` s of pings."""

    tile_period_s: float = Field(33.0, gt=0.0, le=3600.0)
    detector: SssDetectorConfig = SssDetectorConfig()
