"""Watertight trimesh meshes of seabed objects, in the object's NED-aligned local frame.

Every mesh has its base centre at the origin and extends *upwards*, i.e. towards negative
z (the local frame is NED-aligned: x north, y east, z down). Outward normals.
"""

from __future__ import annotations

import numpy as np
import trimesh

from scenarios.config.world import TargetConfig


def _revolve(profile_rz: np.ndarray, sections: int) -> trimesh.Trimesh:
    """Solid of revolution about the local z axis from a closed (radius, z) profile."""
    mesh = trimesh.creation.revolve(profile_rz, sections=sections)
    if mesh.volume < 0.0:
        mesh.invert()
    return mesh


def half_sphere(radius_m: float, sections: int = 32, rings: int = 12) -> trimesh.Trimesh:
    t = np.linspace(0.0, 0.5 * np.pi, rings)
    profile = np.vstack([[0.0, 0.0], np.c_[radius_m * np.cos(t), -radius_m * np.sin(t)]])
    profile[-1, 0] = 0.0
    return _revolve(profile, sections)


def truncated_cone(base_radius_m: float, top_radius_m: float, height_m: float, sections: int = 32) -> trimesh.Trimesh:
    profile = np.array([[0.0, 0.0], [base_radius_m, 0.0], [top_radius_m, -height_m], [0.0, -height_m]])
    if top_radius_m <= 0.0:
        profile = profile[[0, 1, 3]]
    return _revolve(profile, sections)


def cylinder(radius_m: float, height_m: float, sections: int = 32) -> trimesh.Trimesh:
    mesh = trimesh.creation.cylinder(radius=radius_m, height=height_m, sections=sections)
    mesh.apply_translation([0.0, 0.0, -0.5 * height_m])
    return mesh


def box(size_m: tuple[float, float, float]) -> trimesh.Trimesh:
    mesh = trimesh.creation.box(extents=size_m)
    mesh.apply_translation([0.0, 0.0, -0.5 * size_m[2]])
    return mesh


def tyre(radius_m: float, tube_radius_m: float, sections: int = 32, tube_sections: int = 12) -> trimesh.Trimesh:
    """Torus lying flat on the seabed; ``radius_m`` is the outer radius."""
    mesh = trimesh.creation.torus(
        major_radius=radius_m - tube_radius_m,
        minor_radius=tube_radius_m,
        major_sections=sections,
        minor_sections=tube_sections,
    )
    mesh.apply_translation([0.0, 0.0, -tube_radius_m])
    return mesh


def target_mesh(cfg: TargetConfig) -> trimesh.Trimesh:
    """The mesh for a target config, before its pose is applied."""
    if cfg.shape == "half_sphere":
        return half_sphere(cfg.radius_m)
    if cfg.shape == "truncated_cone":
        return truncated_cone(cfg.radius_m, cfg.top_radius_m, cfg.height_m)
    if cfg.shape == "cylinder":
        return cylinder(cfg.radius_m, cfg.height_m)
    if cfg.shape == "box":
        return box(cfg.size_m)
    if cfg.shape == "tyre":
        return tyre(cfg.radius_m, cfg.tube_radius_m)
    raise ValueError(f"unknown target shape {cfg.shape!r}")
