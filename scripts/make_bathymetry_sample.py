"""Write the shipped sample bathymetry ``scenarios/data/bathymetry_sample.tif``.

The grid is generated from a documented analytic model, so it needs no licence and is
reproducible bit for bit:

    depth(n, e) = 18 + 0.04 * (n - N0) + 0.02 * (e - E0)          (shelf sloping down to the N and E)
                  - 5.0 * exp(-((n - 40)^2 + (e - 30)^2) / (2 * 18^2))  (a 5 m mound, sigma 18 m)
                  + 0.4 * sin(2 pi (0.8 n + 0.6 e) / 25)           (sand waves, 25 m, crests NW-SE)

metres, positive down, with (n, e) the north/east offsets in metres from the grid's
south-west corner, N0 = E0 = 80. Grid: 161 x 161 nodes every 1 m, float32, in UTM zone 32N
(EPSG:32632), the south-west node at easting 500000 m, northing 4800000 m. The cells
with n + e > 290 m (the far north-east corner, an unsurveyed area) are nodata (-9999).

Run: python scripts/make_bathymetry_sample.py [OUT.tif]
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

SPACING_M = 1.0
N_NODES = 161
SW_EASTING_M, SW_NORTHING_M = 500000.0, 4800000.0
NODATA = -9999.0


def sample_depth_m(n_m: np.ndarray, e_m: np.ndarray) -> np.ndarray:
    """The analytic model above at offsets (n, e) from the south-west node, m."""
    shelf = 18.0 + 0.04 * (n_m - 80.0) + 0.02 * (e_m - 80.0)
    mound = -5.0 * np.exp(-((n_m - 40.0) ** 2 + (e_m - 30.0) ** 2) / (2.0 * 18.0**2))
    waves = 0.4 * np.sin(2.0 * np.pi * (0.8 * n_m + 0.6 * e_m) / 25.0)
    return shelf + mound + waves


def write_sample(path: Path) -> None:
    import rasterio
    from rasterio.transform import from_origin

    off = np.arange(N_NODES) * SPACING_M
    nn, ee = np.meshgrid(off[::-1], off, indexing="ij")  # raster rows run southwards
    depth = sample_depth_m(nn, ee).astype(np.float32)
    depth[nn + ee > 290.0] = NODATA
    # pixel centres on the nodes: the raster's top-left corner is half a cell beyond them
    transform = from_origin(SW_EASTING_M - 0.5 * SPACING_M, SW_NORTHING_M + off[-1] + 0.5 * SPACING_M,
                            SPACING_M, SPACING_M)
    with rasterio.open(path, "w", driver="GTiff", height=N_NODES, width=N_NODES, count=1, dtype="float32",
                       crs="EPSG:32632", transform=transform, nodata=NODATA, compress="deflate") as dst:
        dst.write(depth, 1)


if __name__ == "__main__":
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).resolve().parents[1] / "scenarios/data/bathymetry_sample.tif"
    write_sample(out)
    print(f"wrote {out}")
