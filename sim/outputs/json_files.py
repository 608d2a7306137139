"""Run outputs as standard JSON: numpy values converted, NaN/inf written as null, floats
rounded where asked; world models with geodetic positions beside NED ([P000] section VII)."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from autonomy.geodesy import GeodeticOrigin, ned_to_lat_lon_depth


def _json_default(obj: Any) -> Any:
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, (np.floating, np.integer, np.bool_)):
        return obj.item()
    raise TypeError(f"not JSON serialisable: {type(obj).__name__}")


def _clean(obj: Any, decimals: int | None) -> Any:
    """NaN/inf -> None (standard JSON); floats rounded to ``decimals`` when given."""
    if isinstance(obj, float):
        if not math.isfinite(obj):
            return None
        return round(obj, decimals) if decimals is not None else obj
    if isinstance(obj, dict):
        return {k: _clean(v, decimals) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_clean(v, decimals) for v in obj]
    return obj


def standard_json(data: Any, decimals: int | None = None) -> Any:
    """``data`` as plain JSON values (numpy converted, NaN/inf -> None, which ``json`` would
    write as the non-standard ``NaN``), floats rounded to ``decimals`` when given."""
    return _clean(json.loads(json.dumps(data, default=_json_default)), decimals)


def write_json(path: Path, data: Any, decimals: int | None = None) -> None:
    """Write ``data`` as indented standard JSON (NaN -> null), floats rounded to ``decimals``."""
    path.write_text(json.dumps(standard_json(data, decimals), indent=2) + "\n")


def with_geodetic(world_model: dict[str, Any], origin: GeodeticOrigin) -> dict[str, Any]:
    """A world model's JSON (:meth:`autonomy.world_model.PMHA.to_json`) with each object's
    ``lat_deg``, ``lon_deg`` and ``depth_m`` (below the origin's height) beside its
    ``pos_ned`` (paper 000 section VII reports objects in latitude / longitude / depth)."""
    out = dict(world_model)
    out["origin"] = origin.model_dump()
    objects = []
    for obj in world_model.get("objects", []):
        lat, lon, depth = (float(v) for v in ned_to_lat_lon_depth(obj["pos_ned"], origin))
        objects.append({**obj, "lat_deg": lat, "lon_deg": lon, "depth_m": depth})
    out["objects"] = objects
    return out
