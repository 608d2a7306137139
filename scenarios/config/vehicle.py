"""Vehicle config: which hull/parameter preset, overrides, and initial state."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from scenarios.config.base import StrictModel, Vec3


class ThrusterOverrides(StrictModel):
    """Optional overrides applied to every thruster of the preset (``None`` keeps it)."""

    time_constant_s: float | None = Field(
        None, ge=0.0, le=5.0, description="first-order rotor lag; 0 = instantaneous")
    dead_zone: float | None = Field(
        None, ge=0.0, lt=0.5, description="command magnitude producing no thrust")
    thrust_scale: float = Field(
        1.0, gt=0.0, le=5.0, description="multiplies forward and reverse thrust limits")


class VehicleConfig(StrictModel):
    """Vehicle selection.

    ``model`` picks ``sim/assets/<model>/params.yaml``. ``mass_kg`` overrides the dry mass
    (inertia scales with it, the buoyancy fraction is kept); ``buoyancy_fraction`` overrides
    buoyancy / weight (> 1 floats).
    """

    model: Literal["feelhippo", "remus100", "bluerov2_heavy"] = "feelhippo"
    mass_kg: float | None = Field(None, gt=0.0, le=10000.0, description="override dry mass")
    buoyancy_fraction: float | None = Field(
        None, ge=0.8, le=1.2, description="override buoyancy / weight (1.0 = neutral)")
    thrusters: ThrusterOverrides = ThrusterOverrides()
    initial_pos_ned: Vec3 = (0.0, 0.0, 0.5)
    initial_rpy_deg: Vec3 = (0.0, 0.0, 0.0)
