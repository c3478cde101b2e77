"""How long a geographic raster takes to place on a scenario's local grid (read through GDAL,
reprojected, the floor's and ceiling's grids computed), beside the one step it cannot avoid:
pyproj mapping every local node into the raster, measured in the same run.

    python benchmarks/raster_placement.py [--size 1000] [--repeats 3]

Prints, per raster size, the least time of ``--repeats`` for reading, placing and the pyproj
reference, and placing / reference (a ratio: machines differ, ratios travel)."""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np


def _raster(path: Path, n: int) -> None:
    import rasterio
    from rasterio.transform import Affine

    yy, xx = np.mgrid[0:n, 0:n].astype(np.float64)
    rng = np.random.default_rng(0)
    H = 300 + 0.5 * xx + 200 * np.sin(xx / 40) * np.cos(yy / 55) + 5 * rng.standard_normal((n, n))
    H[n // 3 : n // 3 + 20, n // 2 : n // 2 + 30] = -9999.0
    tr = Affine(1 / 3600, 0, 6.0, 0, -1 / 3600, 46.5)
    profile = {
        "driver": "GTiff",
        "width": n,
        "height": n,
        "count": 1,
        "dtype": "float32",
        "crs": "EPSG:4326",
        "transform": tr,
        "nodata": -9999.0,
        "compress": "lzw",
    }
    with rasterio.open(path, "w", **profile) as f:
        f.write(H.astype(np.float32), 1)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, nargs="+", default=[250, 1000])
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    from pyproj import CRS, Transformer

    from uavplan.world.raster import local_frame, place_raster, read_raster

    place_raster(read_raster(_tmp_raster(64)))  # compile or load the kernels first
    print(
        f"{'samples':>10} {'nodes':>10} {'read s':>8} {'place s':>8} {'pyproj s':>9} {'ratio':>6}"
    )
    for n in args.size:
        path = _tmp_raster(n)
        reads, places, refs = [], [], []
        for _ in range(args.repeats):
            t0 = time.perf_counter()
            src = read_raster(path)
            t1 = time.perf_counter()
            terrain, origin = place_raster(src)
            t2 = time.perf_counter()
            assert origin is not None
            frame, sx, sy = local_frame(origin)
            fwd = Transformer.from_crs(CRS.from_user_input(frame), src.crs, always_xy=True)
            ny, nx = terrain.shape
            X, Y = np.meshgrid(terrain.x0 + terrain.dx * np.arange(nx),
                               terrain.y0 + terrain.dy * np.arange(ny))  # fmt: skip
            t3 = time.perf_counter()
            fwd.transform(X - sx, Y - sy)
            t4 = time.perf_counter()
            reads.append(t1 - t0)
            places.append(t2 - t1)
            refs.append(t4 - t3)
        r, p, q = min(reads), min(places), min(refs)
        nodes = terrain.shape[0] * terrain.shape[1]
        print(f"{n * n:>10,} {nodes:>10,} {r:>8.3f} {p:>8.3f} {q:>9.3f} {p / q:>6.1f}")


def _tmp_raster(n: int) -> Path:
    path = Path(tempfile.mkdtemp()) / f"dem{n}.tif"
    _raster(path, n)
    return path


if __name__ == "__main__":
    main()
