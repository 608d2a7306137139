"""Guidance (lawnmower survey, LOS) and control (autopilots) configs."""

from __future__ import annotations

from pydantic import Field

from scenarios.config.base import StrictModel, Vec2


class SurveyConfig(StrictModel):
    origin_ne_m: Vec2 = (0.0, 0.0)
    speed_mps: float = Field(0.5, gt=0.0, le=3.0)
    altitude_m: float = Field(2.0, gt=0.0, le=100.0)


class GuidanceConfig(StrictModel):
    survey: SurveyConfig = SurveyConfig()


class ControlConfig(StrictModel):
    pass
