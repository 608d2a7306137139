"""The ``mcm`` block of a scenario: paper 003's mine-countermeasures mapping in full mode.

``mode: full`` (``off`` by default): the MuJoCo hull flies the scenario's survey with the
side-scan sonar named ``sensor``; onboard, its pings form a tile pair every
``tile.tile_period_s`` (:mod:`autonomy.sidescan.tile_assembler`) and the highlight-shadow
detector (:mod:`autonomy.sidescan.detector`) reports per-tile detections; the SPA mapper
(``mapper``) and its baselines (``modes``) map them with the INS drift model (``ins``,
paper 003 eqs. 28-30) on the hull's true track as their navigation input. Runs write the
kinematic mode's GOSPA / cardinality / classification outputs (``auvsim run``: ``mcm.json`` and
PNGs; ``auvsim sweep``: per run). The scenario's objects with ``is_target: true`` are
mine-like (class 1), the others class 2.
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from autonomy.mapping.config import MapperMode, SpaMapperConfig
from autonomy.sidescan.config import SssTileConfig
from scenarios.config.base import StrictModel


class InsDriftConfig(StrictModel):
    """INS drift parameters (paper 003, Section V): eps_p m/h^2, eps_h deg/h, varsigma_p
    m/h^(3/2), varsigma_h deg/sqrt(h)."""

    eps_p_m_per_h2: float = Field(7.5, ge=0.0)
    eps_h_deg_per_h: float = Field(1.0, ge=0.0)
    varsigma_p: float = Field(7.5, ge=0.0)
    varsigma_h_deg_per_sqrt_h: float = Field(0.6, ge=0.0)
    rate_hz: float = Field(1.0, gt=0.0, le=100.0)


class McmConfig(StrictModel):
    """Full-mode MCM mapping of a mission (see the module docstring)."""

    mode: Literal["off", "full"] = "off"
    sensor: str = Field("sss", min_length=1, description="the side-scan sensor entry")
    tile: SssTileConfig = SssTileConfig()
    mapper: SpaMapperConfig = SpaMapperConfig()
    modes: tuple[MapperMode, ...] = ("spa", "clairvoyant", "ins_plain", "ins_filter")
    ins: InsDriftConfig = InsDriftConfig()
    gospa_cutoff_m: float = Field(50.0, gt=0.0)
    correct_within_m: float = Field(20.0, gt=0.0)
    label_match_m: float = Field(3.0, gt=0.0, description="a detection within this of a labelled object is "
                                 "correct when scoring the detector (pd, clutter), m")

    @model_validator(mode="after")
    def _check(self) -> "McmConfig":
        if not self.modes:
            raise ValueError("modes: give at least one mapper")
        return self
