"""Config base shared with the onboard configs (defined in :mod:`autonomy.config_base`)."""

from __future__ import annotations

from autonomy.config_base import NonNegFloat, PositiveFloat, Probability, StrictModel, Vec2, Vec3

__all__ = ["NonNegFloat", "PositiveFloat", "Probability", "StrictModel", "Vec2", "Vec3"]
