"""Automatic target recognition config."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from scenarios.config.base import StrictModel


class AtrConfig(StrictModel):
    detector: Literal["cnn", "classical", "none"] = "cnn"
    score_threshold: float = Field(0.5, ge=0.0, le=1.0)
