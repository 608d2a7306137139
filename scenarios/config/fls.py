"""Forward-looking sonar config."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from scenarios.config.base import StrictModel


class FlsConfig(StrictModel):
    enabled: bool = True
    preset: Literal["m900_130", "aris3000"] = "m900_130"
    rate_hz: float = Field(3.0, gt=0.0, le=100.0)
