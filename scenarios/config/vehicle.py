"""Vehicle config: which hull/parameter preset, overrides, and initial state."""

from __future__ import annotations

from typing import Literal

from pydantic import Field, field_validator

from autonomy.surface.config import SurfaceAutonomyConfig
from scenarios.config.base import StrictModel, Vec2, Vec3
from scenarios.config.nav_sensors import GpsConfig, ImuConfig
from scenarios.config.usbl import UsblConfig


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


class SurfaceVehicleConfig(StrictModel):
    """A second vehicle in the scene: a surface vessel (``preset``, a ``surface_3dof``
    parameter file in ``sim/assets``) with its GNSS, compass and autonomy.

    ``behaviour``: ``station_keep`` holds ``station_ne_m`` (default: the start point);
    ``follow`` holds the AUV's position plus ``offset_m``: (along, across) the AUV's course
    with ``offset_frame: track`` ((-5, 0): 5 m behind it), (north, east) with ``ned``.

    ``usbl``: a USBL head under the hull (the preset's ``usbl`` mount) whose transponder is
    the AUV (``transponder: auv``); when given, a following vehicle follows its own USBL fixes
    of the AUV instead of the AUV's true position, and with ``comms.acoustic`` on the fixes
    are sent down to the AUV (``comms.surface``).
    """

    preset: Literal["surface_buoy"] = "surface_buoy"
    initial_pos_ne_m: Vec2 = (0.0, 0.0)
    initial_heading_deg: float = Field(0.0, ge=-360.0, le=360.0)
    behaviour: Literal["station_keep", "follow"] = "station_keep"
    station_ne_m: Vec2 | None = None
    offset_m: Vec2 = (-5.0, 0.0)
    offset_frame: Literal["track", "ned"] = "track"
    gnss: GpsConfig = GpsConfig(noise_m=0.7, dropout_prob=0.0)
    compass: ImuConfig = ImuConfig(rate_hz=10.0, heading_source="ahrs")
    usbl: UsblConfig | None = Field(None, description="USBL head fixing the AUV (transponder: auv)")

    @field_validator("usbl")
    @classmethod
    def _usbl_fixes_the_auv(cls, value: UsblConfig | None) -> UsblConfig | None:
        if value is not None and value.transponder != "auv":
            raise ValueError(f"usbl.transponder must be 'auv' (the buoy's USBL fixes the AUV), got {value.transponder!r}")
        return value
    autonomy: SurfaceAutonomyConfig = SurfaceAutonomyConfig()
