"""The one typed scenario object. Every component receives only its own sub-config."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from scenarios.config.atr import AtrConfig
from scenarios.config.base import StrictModel
from scenarios.config.fls import FlsConfig
from scenarios.config.guidance import ControlConfig, GuidanceConfig
from scenarios.config.nav_sensors import AltimeterConfig, DepthConfig, DvlConfig, GpsConfig, ImuConfig
from scenarios.config.navigation import NavigationConfig
from scenarios.config.vehicle import VehicleConfig
from scenarios.config.world import WorldConfig
from scenarios.config.world_model import LocalizationConfig, WorldModelConfig


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
