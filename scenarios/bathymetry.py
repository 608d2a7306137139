"""Read a measured depth grid (GeoTIFF, ASCII XYZ, NumPy ``.npy``) into the mission NED
frame, for ``world.seabed.kind: file``.

Depths are positive down (NED z), metres. Missing cells (nodata) are NaN: the seabed mesh
has holes there, and a scenario whose vehicle start, survey or targets lie over them, or
outside the grid, is refused at load (:func:`bathymetry_problems`).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from scenarios.config.world import BathymetryFileConfig
from autonomy.guidance.survey import plan_from_config

KEY = "world.seabed.file"


class BathymetryError(ValueError):
    """A bathymetry file that cannot be used; the message names the key and the file."""


@dataclass(frozen=True)
class DepthGrid:
    """A regular depth grid in the mission NED frame.

    Attributes:
        n_m: (nx,) increasing north coordinates of the grid rows, m.
        e_m: (ny,) increasing east coordinates of the grid columns, m.
        depth_m: (nx, ny) seabed depth (NED z, positive down), m; NaN where missing.
    """

    n_m: NDArray[np.float64]
    e_m: NDArray[np.float64]
    depth_m: NDArray[np.float64]

    def valid_at(self, n_m: float, e_m: float) -> bool:
        """True when (north, east) lies inside the grid on a cell whose four nodes hold depths."""
        n, e = self.n_m, self.e_m
        if not (n[0] <= n_m <= n[-1] and e[0] <= e_m <= e[-1]):
            return False
        i = min(max(int(np.searchsorted(n, n_m, side="right")) - 1, 0), len(n) - 2)
        j = min(max(int(np.searchsorted(e, e_m, side="right")) - 1, 0), len(e) - 2)
        return bool(np.all(np.isfinite(self.depth_m[i:i + 2, j:j + 2])))


def _format(cfg: BathymetryFileConfig, path: Path) -> str:
    if cfg.format != "auto":
        return cfg.format
    suffix = path.suffix.lower()
    fmt = {".tif": "geotiff", ".tiff": "geotiff", ".xyz": "xyz", ".txt": "xyz", ".npy": "npy"}.get(suffix)
    if fmt is None:
        raise BathymetryError(f"{KEY}.path: {path}: cannot tell the format from {suffix!r}; "
                              "use .tif/.tiff, .xyz/.txt or .npy, or set world.seabed.file.format")
    return fmt


def _need_origin(cfg: BathymetryFileConfig, path: Path) -> tuple[float, float]:
    if cfg.origin_en_m is None:
        raise BathymetryError(f"{KEY}.origin_en_m: required for {path.name} (the projected easting, northing "
                              "of the mission NED origin, m)")
    return float(cfg.origin_en_m[0]), float(cfg.origin_en_m[1])


def _read_geotiff(cfg: BathymetryFileConfig, path: Path) -> DepthGrid:
    try:
        import rasterio
    except ImportError:  # pragma: no cover - rasterio is a dependency of the bathymetry extra
        raise BathymetryError(f"{KEY}.path: {path}: reading a GeoTIFF needs rasterio (pip install rasterio)") from None
    try:
        with rasterio.open(path) as src:
            crs, tr, nodata = src.crs, src.transform, src.nodata
            band = src.read(1).astype(float)
    except rasterio.errors.RasterioError as exc:
        raise BathymetryError(f"{KEY}.path: {path}: not a readable GeoTIFF ({exc})") from None
    if crs is None or not crs.is_projected or str(crs.linear_units).lower() not in ("metre", "meter", "metres"):
        raise BathymetryError(f"{KEY}.path: {path}: CRS {crs.to_string() if crs else 'none'} is not a projected "
                              "CRS in metres; reproject it first (e.g. gdalwarp -t_srs EPSG:326xx for UTM)")
    if tr.b != 0.0 or tr.d != 0.0 or tr.a <= 0.0 or tr.e >= 0.0:
        raise BathymetryError(f"{KEY}.path: {path}: the raster must be north-up without rotation")
    nodata = cfg.nodata if cfg.nodata is not None else nodata
    if nodata is not None:
        band[band == nodata] = np.nan
    e0, n0 = _need_origin(cfg, path)
    rows, cols = band.shape
    east = tr.c + (np.arange(cols) + 0.5) * tr.a - e0
    north = tr.f + (np.arange(rows) + 0.5) * tr.e - n0
    return DepthGrid(north[::-1].copy(), east, band[::-1].copy())


def _read_xyz(cfg: BathymetryFileConfig, path: Path) -> DepthGrid:
    try:
        pts = np.loadtxt(path, dtype=float, ndmin=2)
    except (ValueError, OSError) as exc:
        raise BathymetryError(f"{KEY}.path: {path}: not an XYZ text grid ({exc})") from None
    if pts.shape[1] != 3 or len(pts) < 4:
        raise BathymetryError(f"{KEY}.path: {path}: needs at least 4 lines of 'easting northing value'")
    e0, n0 = _need_origin(cfg, path)
    east, j = np.unique(pts[:, 0], return_inverse=True)
    north, i = np.unique(pts[:, 1], return_inverse=True)
    for name, axis in (("easting", east), ("northing", north)):
        step = np.diff(axis)
        if len(axis) < 2 or not np.allclose(step, step[0], rtol=1e-6, atol=1e-6):
            raise BathymetryError(f"{KEY}.path: {path}: the {name}s do not form a regular grid")
    z = np.full((len(north), len(east)), np.nan)
    z[i, j] = pts[:, 2]
    if cfg.nodata is not None:
        z[z == cfg.nodata] = np.nan
    return DepthGrid(north - n0, east - e0, z)


def _read_npy(cfg: BathymetryFileConfig, path: Path) -> DepthGrid:
    try:
        z = np.load(path, allow_pickle=False)
    except (ValueError, OSError) as exc:
        raise BathymetryError(f"{KEY}.path: {path}: not a NumPy .npy array ({exc})") from None
    if z.ndim != 2 or not np.issubdtype(z.dtype, np.number):
        raise BathymetryError(f"{KEY}.path: {path}: must hold a 2-D numeric array, got shape {z.shape} {z.dtype}")
    if cfg.spacing_m is None:
        raise BathymetryError(f"{KEY}.spacing_m: required for a .npy grid (m between nodes)")
    z = z.astype(float)
    if cfg.nodata is not None:
        z[z == cfg.nodata] = np.nan
    n0, e0 = cfg.origin_ne_m
    return DepthGrid(n0 + cfg.spacing_m * np.arange(z.shape[0]), e0 + cfg.spacing_m * np.arange(z.shape[1]), z)


def read_depth_grid(cfg: BathymetryFileConfig) -> DepthGrid:
    """The depth grid ``cfg`` names, cropped and decimated, in mission NED.

    Raises:
        BathymetryError: the file is missing or unreadable, in the wrong CRS or layout, or
            holds no valid depth (all nodata) in the kept area; the message names the key.
    """
    path = Path(cfg.path).expanduser()
    if not path.is_file():
        raise BathymetryError(f"{KEY}.path: {path}: no such file")
    reader = {"geotiff": _read_geotiff, "xyz": _read_xyz, "npy": _read_npy}[_format(cfg, path)]
    g = reader(cfg, path)
    depth = g.depth_m if cfg.values == "depth" else -g.depth_m
    n, e = g.n_m, g.e_m
    if cfg.crop_ne_m is not None:
        (n_lo, n_hi), (e_lo, e_hi) = cfg.crop_ne_m
        keep_n, keep_e = (n >= n_lo) & (n <= n_hi), (e >= e_lo) & (e <= e_hi)
        n, e, depth = n[keep_n], e[keep_e], depth[np.ix_(keep_n, keep_e)]
    k = cfg.decimate
    n, e, depth = n[::k], e[::k], depth[::k, ::k]
    if len(n) < 2 or len(e) < 2:
        raise BathymetryError(f"{KEY}: {path}: fewer than 2 x 2 grid nodes left after crop_ne_m/decimate")
    if not np.any(np.isfinite(depth)):
        raise BathymetryError(f"{KEY}.path: {path}: holds no valid depth (all cells nodata"
                              f"{' in crop_ne_m' if cfg.crop_ne_m else ''})")
    if np.nanmin(depth) <= 0.0:
        raise BathymetryError(f"{KEY}.values: {path}: depths must be positive down (min {np.nanmin(depth):g} m); "
                              "for heights (negative below sea level) set values: elevation")
    return DepthGrid(np.asarray(n, float), np.asarray(e, float), np.asarray(depth, float))


def bathymetry_problems(scenario) -> list[str]:
    """Placement problems of a ``kind: file`` seabed: the file itself, and the vehicle start,
    survey waypoints and targets lying outside the grid or over nodata, or below the bed."""
    try:
        grid = read_depth_grid(scenario.world.seabed.file)
    except BathymetryError as exc:
        return [str(exc)]
    problems = []
    n, e, d = scenario.vehicle.initial_pos_ned
    extent = f"grid north {grid.n_m[0]:.1f}..{grid.n_m[-1]:.1f} m, east {grid.e_m[0]:.1f}..{grid.e_m[-1]:.1f} m"
    if not grid.valid_at(n, e):
        problems.append(f"vehicle.initial_pos_ned: ({n:g}, {e:g}) m is outside the bathymetry or over nodata "
                        f"({KEY}: {extent})")
    else:
        from scipy.interpolate import RegularGridInterpolator

        from scenarios.vehicle_presets import vehicle_half_height_m

        bed = float(RegularGridInterpolator((grid.n_m, grid.e_m), grid.depth_m)([[n, e]])[0])
        half_h = vehicle_half_height_m(scenario.vehicle.model)
        if d + half_h > bed:
            problems.append(f"vehicle.initial_pos_ned: depth {d:g} m puts the hull (half height {half_h:.2f} m) "
                            f"into the seabed ({KEY}: the bed is at {bed:.2f} m there)")
    try:
        wps = np.asarray(plan_from_config(scenario.autonomy.guidance.survey).waypoints_ne_m, dtype=float)
    except Exception:  # noqa: BLE001 - survey problems are reported by their own checks
        wps = np.zeros((0, 2))
    bad = [tuple(w) for w in wps if not grid.valid_at(*w)]
    if bad:
        problems.append(f"autonomy.guidance.survey: {len(bad)} of {len(wps)} waypoints lie outside the bathymetry "
                        f"or over nodata, first ({bad[0][0]:.1f}, {bad[0][1]:.1f}) m ({KEY}: {extent})")
    for k, t in enumerate(scenario.world.targets):
        if not grid.valid_at(t.pos_ned[0], t.pos_ned[1]):
            problems.append(f"world.targets.{k}.pos_ned: ({t.pos_ned[0]:g}, {t.pos_ned[1]:g}) m is outside the "
                            f"bathymetry or over nodata ({KEY}: {extent})")
    return problems
