"""Seabed surfaces: analytic planes and terrain meshes (numpy; trimesh only where a caller asks
for a ``trimesh.Trimesh``).

Depths are NED z (positive down). Rough seabeds are Gaussian random fields with a
Gaussian correlation function; ripples are sinusoidal sand waves. Both are built as
triangle meshes, never MuJoCo height fields (whose ray casts are ~10x slower).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from scenarios.config.world import SeabedConfig
from scenarios.bathymetry import read_depth_grid

if TYPE_CHECKING:
    import trimesh


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
        """Seabed depth (NED z, m) under the given north/east positions (bilinear on a mesh
        seabed's grid, extended linearly beyond its edge; NaN at a NaN position)."""
        n = np.asarray(n_m, dtype=float)
        e = np.asarray(e_m, dtype=float)
        if not self.is_mesh:
            return self._plane_depth(n, e)
        n, e = np.broadcast_arrays(n, e)
        z = self.depth_grid_m
        if _bilinear_applies(self.grid_n_m, self.grid_e_m, z):
            return grid_bilinear(self.grid_n_m, self.grid_e_m, z, n.ravel(), e.ravel()).reshape(n.shape)
        from scipy.interpolate import RegularGridInterpolator  # other grids (read-only, float32, descending)

        interp = RegularGridInterpolator((self.grid_n_m, self.grid_e_m), z, bounds_error=False, fill_value=None)
        return interp(np.stack([n, e], axis=-1).reshape(-1, 2)).reshape(n.shape)

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
        """:meth:`terrain_arrays` as a ``trimesh.Trimesh`` (imports trimesh).

        Raises:
            ValueError: a plane seabed (no mesh).
        """
        import trimesh

        return trimesh.Trimesh(*self.terrain_arrays(), process=False)

    def terrain_arrays(self) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
        """Slab mesh (top = terrain, 1 m thick below the deepest node) for mesh seabeds:
        (vertices (n, 3) m NED, faces (m, 3) vertex indices, wound outward).

        Closed for a complete grid; a grid with missing (NaN) nodes gets the terrain
        triangles of its complete cells only (holes over nodata, no bottom or rim).

        Raises:
            ValueError: a plane seabed (no mesh), or a grid without a complete cell.
        """
        if not self.is_mesh:
            raise ValueError("plane seabeds have no terrain mesh")
        n, e, z = self.grid_n_m, self.grid_e_m, self.depth_grid_m
        if not np.all(np.isfinite(z)):
            return _holed_terrain_arrays(n, e, z)
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
        # trimesh in tests/sim/scene/test_seabed_mesh.py), so no normal repair pass is needed
        return verts, np.vstack(faces)


def _bilinear_applies(n_m: NDArray, e_m: NDArray, z: NDArray) -> bool:
    """Whether :func:`grid_bilinear` reproduces scipy's interpolator on this grid: the cases its
    compiled fast path covers (native float64 writeable values, two or more ascending nodes an axis)."""
    return (z.dtype == np.float64 and z.dtype.isnative and z.flags.writeable and len(n_m) >= 2 and len(e_m) >= 2
            and bool(np.all(np.diff(n_m) > 0)) and bool(np.all(np.diff(e_m) > 0)))


def grid_bilinear(n_m: NDArray, e_m: NDArray, z: NDArray, n_q: NDArray, e_q: NDArray) -> NDArray[np.float64]:
    """Bilinear interpolation of ``z`` (nx, ny) on the ascending grid ``n_m`` (nx,), ``e_m`` (ny,)
    at the points (``n_q``, ``e_q``) (k,), extended linearly from the edge cells outside the grid.

    The arithmetic is that of scipy's ``RegularGridInterpolator(method="linear",
    bounds_error=False, fill_value=None)`` (cell lookup, normalised distances, the four-term sum in
    its order), so the values agree bit for bit (tested) without importing scipy.interpolate.
    """
    out = np.empty(len(n_q))
    idx, frac = [], []
    for grid, q in ((n_m, n_q), (e_m, e_q)):
        i = np.clip(np.searchsorted(grid, q, side="right") - 1, 0, len(grid) - 2)
        idx.append(i)
        frac.append((q - grid[i]) / (grid[i + 1] - grid[i]))
    (i0, i1), (y0, y1) = idx, frac
    out[:] = (z[i0, i1] * (1 - y0) * (1 - y1) + z[i0, i1 + 1] * (1 - y0) * y1
              + z[i0 + 1, i1] * y0 * (1 - y1) + z[i0 + 1, i1 + 1] * y0 * y1)
    out[np.isnan(n_q) | np.isnan(e_q)] = np.nan
    return out


def _holed_terrain_arrays(n: NDArray, e: NDArray, z: NDArray) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Terrain triangles (normals up, -z) of the grid cells whose four nodes hold depths, with the
    vertices no triangle uses left out (the rest keep their order)."""
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
    faces = np.vstack([np.c_[a, d, b], np.c_[b, d, c_]])
    used = np.zeros(len(verts), dtype=bool)
    used[faces] = True
    renumber = np.cumsum(used) - 1
    return verts[used], renumber[faces]


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
