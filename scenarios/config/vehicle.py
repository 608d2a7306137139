"""Vehicle config: which hull/parameter preset, overrides, and initial state."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from scenarios.config.base import StrictModel, Vec3


class VehicleConfig(StrictModel):
    model: Literal["feelhippo", "remus100", "bluerov2_heavy"] = "feelhippo"
    mass_kg: float | None = Field(None, gt=0.0, le=10000.0, description="override dry mass")
    initial_pos_ned: Vec3 = (0.0, 0.0, 0.5)
    initial_rpy_deg: Vec3 = (0.0, 0.0, 0.0)
