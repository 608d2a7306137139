"""Sizes of the shipped vehicle presets, read from their ``sim/assets/<preset>/params.yaml``
(for load-time checks; zeros when a file is unreadable, which only weakens the checks)."""

from __future__ import annotations

import math
from importlib import resources

import yaml


def vehicle_envelope_m(model: str) -> tuple[float, float, float]:
    """Envelope (length, width, height) of a vehicle preset, m (from its ``params.yaml``;
    zeros when unreadable, which only weakens the checks)."""
    try:
        text = (resources.files("sim") / "assets" / model / "params.yaml").read_text()
        env = yaml.safe_load(text)["envelope_m"]
        return float(env[0]), float(env[1]), float(env[2])
    except (OSError, KeyError, TypeError, ValueError, IndexError, yaml.YAMLError):
        return 0.0, 0.0, 0.0


def surface_hull_span_m(preset: str) -> tuple[float, float, float]:
    """(horizontal half-diagonal, top depth, bottom depth) of a ``surface_3dof`` preset's hull
    afloat, m (NED z of its top and keel; from its ``params.yaml``, zeros when unreadable)."""
    try:
        data = yaml.safe_load((resources.files("sim") / "assets" / preset / "params.yaml").read_text())
        size = [float(x) for x in data["hull"]["size_m"]]
        centre_z = float(data.get("waterline_depth_m", 0.0)) + float(data["hull"].get("center_body_m", [0, 0, 0])[2])
        return 0.5 * math.hypot(size[0], size[1]), centre_z - 0.5 * size[2], centre_z + 0.5 * size[2]
    except (OSError, KeyError, TypeError, ValueError, IndexError, AttributeError, yaml.YAMLError):
        return 0.0, 0.0, 0.0


def vehicle_half_height_m(model: str) -> float:
    """Half the vertical envelope of a vehicle preset, m."""
    return 0.5 * vehicle_envelope_m(model)[2]
