"""Base of every onboard config block: frozen pydantic models, unknown keys rejected.

The scenario schema composes these blocks; the simulator's own configs (world, vehicle,
sensors) use the same base.
"""

from __future__ import annotations

from typing import Annotated

from pydantic import BaseModel, ConfigDict, Field

Vec2 = tuple[float, float]
Vec3 = tuple[float, float, float]
Probability = Annotated[float, Field(ge=0.0, le=1.0)]
PositiveFloat = Annotated[float, Field(gt=0.0)]
NonNegFloat = Annotated[float, Field(ge=0.0)]


class StrictModel(BaseModel):
    """Frozen config block; unknown keys, NaN and infinity are errors.

    A field that means "no limit" by infinity opts in with ``Field(allow_inf_nan=True)``
    and a bound (``gt``/``ge``) that NaN fails.
    """

    model_config = ConfigDict(extra="forbid", frozen=True, validate_default=True, allow_inf_nan=False)
