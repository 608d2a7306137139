"""Navigation filter config."""

from __future__ import annotations

from typing import Literal

from scenarios.config.base import StrictModel


class NavigationConfig(StrictModel):
    mode: Literal["ekf", "dead_reckoning"] = "ekf"
