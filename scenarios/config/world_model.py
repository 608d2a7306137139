"""Target geolocalisation and PMHA world-model configs."""

from __future__ import annotations

from typing import Literal

from scenarios.config.base import StrictModel


class LocalizationConfig(StrictModel):
    method: Literal["flat_seabed", "planar"] = "flat_seabed"


class WorldModelConfig(StrictModel):
    max_hypotheses: int = 100
