"""Seabed surfaces: analytic planes and trimesh terrain meshes (pure numpy + trimesh).

Depths are NED z (positive down). Rough seabeds are Gaussian random fields with a
Gaussian correlation function; ripples are sinusoidal sand waves. Both are built as
triangle meshes, never MuJoCo height fields (whose ray casts are ~10x slower).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import trimesh
from numpy.typing import ArrayLike, NDArray

from scenarios.config.world import SeabedConfig


@dataclass(frozen=True)
class Seabed:
    """A seabed surface with a depth lookup.

    Attributes:
        cfg: the config it was made from.
        grid_n_m, grid_e_m: (nx,), (ny,) grid axes of the terrain mesh (None for planes).
        depth_grid_m: (nx, ny) terrain depth on the grid (None for planes).
    """

    cfg: SeabedConfig
    grid_n_m: NDArray[np.float64] | None = None
    grid_e_m: NDArray[np.float64] | None = None
    depth_grid_m: NDArray[np.float64] | None = None

    @property
    def is_mesh(self) -> bool:
        return self.depth_grid_m is not None

    def _plane_depth(self, n_m: NDArray, e_m: NDArray) -> NDArray:
        """Depth of the mean surface: ``depth_m`` at ``center_ne_m``, falling by ``tan(slope)`` per
        metre along ``slope_azimuth_deg`` (downhill) for a slope."""
        c = self.cfg
        if c.kind != "slope":
            return np.full(np.broadcast(n_m, e_m).shape, c.depth_m)
        az = np.deg2rad(c.slope_azimuth_deg)
        k = np.tan(np.deg2rad(c.slope_deg))
        return c.depth_m + k * ((n_m - c.center_ne_m[0]) * np.cos(az) + (e_m - c.center_ne_m[1]) * np.sin(az))

    def depth_at(self, n_m: ArrayLike, e_m: ArrayLike) -> NDArray[np.float64]:
        """Seabed depth (NED z, m) under the given north/east positions."""
        n = np.asarray(n_m, dtype=float)
        e = np.asarray(e_m, dtype=float)
        if not self.is_mesh:
            return self._plane_depth(n, e)
        from scipy.interpolate import RegularGridInterpolator

        interp = RegularGridInterpolator(
            (self.grid_n_m, self.grid_e_m), self.depth_grid_m, bounds_error=False, fill_value=None
        )
        pts = np.stack(np.broadcast_arrays(n, e), axis=-1)
        return interp(pts.reshape(-1, 2)).reshape(pts.shape[:-1])

    def plane_normal_ned(self) -> NDArray[np.float64]:
        """Unit upward (towards the surface, -z) normal of a plane/slope seabed."""
        c = self.cfg
        if c.kind != "slope":
            return np.array([0.0, 0.0, -1.0])
        az = np.deg2rad(c.slope_azimuth_deg)
        k = np.tan(np.deg2rad(c.slope_deg))
        n = np.array([k * np.cos(az), k * np.sin(az), -1.0])
        return n / np.linalg.norm(n)

    def terrain_mesh(self) -> trimesh.Trimesh:
        """Slab mesh (top = terrain, 1 m thick below the deepest node) for mesh seabeds.

        Closed for a complete grid; a grid with missing (NaN) nodes gets the terrain
        triangles of its complete cells only (holes over nodata, no bottom or rim).

        Raises:
            ValueError: a plane seabed (no mesh).
        """
        if not self.is_mesh:
            raise ValueError("plane seabeds have no terrain mesh")
        n, e, z = self.grid_n_m, self.grid_e_m, self.depth_grid_m
        if not np.all(np.isfinite(z)):
            return self._holed_terrain_mesh()
        nx, ny = z.shape
        nn, ee = np.meshgrid(n, e, indexing="ij")
        top = np.c_[nn.ravel(), ee.ravel(), z.ravel()]
        bottom = top.copy()
        bottom[:, 2] = z.max() + 1.0
        verts = np.vstack([top, bottom])
        idx = np.arange(nx * ny).reshape(nx, ny)
        a, b, c_, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
        # Top faces wound so their normals point up (-z) in NED.
        faces = [np.c_[a, d, b], np.c_[b, d, c_]]
        off = nx * ny
        faces += [np.c_[a + off, b + off, d + off], np.c_[b + off, c_ + off, d + off]]
        rim = np.concatenate([idx[0, :], idx[1:, -1], idx[-1, -2::-1], idx[-2:0:-1, 0]])
        r0, r1 = rim, np.roll(rim, -1)
        faces += [np.c_[r0, r0 + off, r1], np.c_[r1, r0 + off, r1 + off]]
        # wound outward by construction (closed, consistent, positive volume; checked against
        # trimesh in tests/sim/test_seabed_mesh.py), so no normal repair pass is needed
        return trimesh.Trimesh(verts, np.vstack(faces), process=False)

    def _holed_terrain_mesh(self) -> trimesh.Trimesh:
        """Terrain triangles (normals up, -z) of the grid cells whose four nodes hold depths."""
        return _holed_terrain_mesh_impl(self.grid_n_m, self.grid_e_m, self.depth_grid_m)


def _holed_terrain_mesh_impl(n: NDArray, e: NDArray, z: NDArray) -> trimesh.Trimesh:
    nx, ny = z.shape
    nn, ee = np.meshgrid(n, e, indexing="ij")
    verts = np.c_[nn.ravel(), ee.ravel(), np.nan_to_num(z, nan=0.0).ravel()]
    idx = np.arange(nx * ny).reshape(nx, ny)
    ok = np.isfinite(z)
    cell = (ok[:-1, :-1] & ok[1:, :-1] & ok[1:, 1:] & ok[:-1, 1:]).ravel()
    a, b, c_, d = (idx[:-1, :-1].ravel()[cell], idx[1:, :-1].ravel()[cell], idx[1:, 1:].ravel()[cell],
                   idx[:-1, 1:].ravel()[cell])
    if not len(a):
        raise ValueError("the depth grid has no complete cell to mesh")
    mesh = trimesh.Trimesh(verts, np.vstack([np.c_[a, d, b], np.c_[b, d, c_]]), process=False)
    mesh.remove_unreferenced_vertices()
    return mesh


def _gaussian_random_field(shape: tuple[int, int], spacing_m: float, rms_m: float, corr_m: float, rng: np.random.Generator) -> NDArray:
    white = rng.standard_normal(shape)
    kx = np.fft.fftfreq(shape[0], d=spacing_m)
    ky = np.fft.rfftfreq(shape[1], d=spacing_m)
    k2 = kx[:, None] ** 2 + ky[None, :] ** 2
    filt = np.exp(-(np.pi**2) * corr_m**2 * k2 / 2.0)
    field = np.fft.irfft2(np.fft.rfft2(white) * filt, s=shape)
    std = field.std()
    return field * (rms_m / std) if std > 0.0 else field


def make_seabed(cfg: SeabedConfig, rng: np.random.Generator) -> Seabed:
    """Build the seabed described by ``cfg`` (``rng`` draws rough-seabed heights).

    ``kind: file`` reads the grid (:func:`scenarios.bathymetry.read_depth_grid`); the
    returned seabed's ``cfg`` then gives the grid's square hull as ``extent_m`` /
    ``center_ne_m`` and its median depth as ``depth_m``.

    Raises:
        scenarios.bathymetry.BathymetryError: an unusable bathymetry file.
    """
    if cfg.kind in ("plane", "slope"):
        return Seabed(cfg)
    if cfg.kind == "file":
        from scenarios.bathymetry import read_depth_grid

        g = read_depth_grid(cfg.file)
        span = max(g.n_m[-1] - g.n_m[0], g.e_m[-1] - g.e_m[0])
        centre = (0.5 * float(g.n_m[0] + g.n_m[-1]), 0.5 * float(g.e_m[0] + g.e_m[-1]))
        resolved = cfg.model_copy(update={"extent_m": float(span), "center_ne_m": centre,
                                          "depth_m": float(np.nanmedian(g.depth_m))})
        return Seabed(resolved, g.n_m, g.e_m, g.depth_m)
    half = 0.5 * cfg.extent_m
    nx = max(int(round(cfg.extent_m / cfg.mesh_resolution_m)) + 1, 3)
    n = cfg.center_ne_m[0] + np.linspace(-half, half, nx)
    e = cfg.center_ne_m[1] + np.linspace(-half, half, nx)
    nn, ee = np.meshgrid(n, e, indexing="ij")
    base = Seabed(cfg.model_copy(update={"kind": "slope"}))._plane_depth(nn, ee)
    if cfg.kind == "rough":
        relief = _gaussian_random_field(nn.shape, float(n[1] - n[0]), cfg.roughness_m, cfg.roughness_corr_m, rng)
    else:  # ripple
        az = np.deg2rad(cfg.ripple_azimuth_deg)
        along = nn * np.cos(az) + ee * np.sin(az)
        relief = cfg.ripple_amplitude_m * np.sin(2.0 * np.pi * along / cfg.ripple_wavelength_m)
        relief += _gaussian_random_field(nn.shape, float(n[1] - n[0]), cfg.roughness_m, cfg.roughness_corr_m, rng)
    return Seabed(cfg, n, e, base + relief)
