"""The one typed scenario object. Every component receives only its own sub-config."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from autonomy.atr.config import AtrConfig
from autonomy.control.config import ControlConfig
from autonomy.guidance.config import GuidanceConfig
from autonomy.localization.config import LocalizationConfig
from autonomy.navigation.config import NavigationConfig
from autonomy.world_model.config import WorldModelConfig
from scenarios.config.base import StrictModel
from scenarios.config.fls import FlsConfig
from scenarios.config.nav_sensors import AltimeterConfig, DepthConfig, DvlConfig, GpsConfig, ImuConfig
from scenarios.config.vehicle import VehicleConfig
from scenarios.config.world import WorldConfig


class PhysicsConfig(StrictModel):
    rate_hz: float = Field(200.0, ge=20.0, le=5000.0)
    integrator: Literal["euler", "implicitfast", "rk4"] = "implicitfast"


class SensorsConfig(StrictModel):
    fls: FlsConfig = FlsConfig()
    imu: ImuConfig = ImuConfig()
    dvl: DvlConfig = DvlConfig()
    depth: DepthConfig = DepthConfig()
    altimeter: AltimeterConfig = AltimeterConfig()
    gps: GpsConfig = GpsConfig()


class AutonomyConfig(StrictModel):
    """The onboard stack's settings; each block is defined next to its code in ``autonomy/``."""

    rate_hz: float = Field(10.0, gt=0.0, le=200.0)
    navigation: NavigationConfig = NavigationConfig()
    guidance: GuidanceConfig = GuidanceConfig()
    control: ControlConfig = ControlConfig()
    atr: AtrConfig = AtrConfig()
    localization: LocalizationConfig = LocalizationConfig()
    world_model: WorldModelConfig = WorldModelConfig()


class Scenario(StrictModel):
    """A whole simulation scenario, loaded once from YAML."""

    name: str = Field(min_length=1)
    description: str = ""
    seed: int = Field(0, ge=0, le=2**63 - 1)
    duration_s: float = Field(600.0, gt=0.0, le=86400.0)
    physics: PhysicsConfig = PhysicsConfig()
    world: WorldConfig = WorldConfig()
    vehicle: VehicleConfig = VehicleConfig()
    sensors: SensorsConfig = SensorsConfig()
    autonomy: AutonomyConfig = AutonomyConfig()
