"""Elevation rasters through GDAL: NoData of every common kind, pixel-is-point, compression and
tiling, geographic and projected placement, and the floor's and ceiling's grids held against
the raster's own ground everywhere (not only at the nodes)."""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pytest
import yaml
from numpy.typing import NDArray

from uavplan.io.scenario_file import ScenarioFileError, load_scenario
from uavplan.world import _raster_kernels as rk
from uavplan.world.geo import GeoOrigin
from uavplan.world.raster import (
    bilinear_samples,
    fill_voids,
    place_raster,
    read_raster,
)
from uavplan.world.terrain import Terrain, TerrainError

from .rasters import (
    hill_samples,
    landscape,
    peak_block,
    source_ground,
    utm_hill,
    write,
)

FloatArray = NDArray[np.float64]


def _origin(terrain: Terrain, given: GeoOrigin | None) -> GeoOrigin:
    if given is not None:
        return given
    return GeoOrigin.from_record(terrain.georef["origin"])


def _random_points(t: Terrain, n: int, seed: int = 0) -> tuple[FloatArray, FloatArray]:
    rng = np.random.default_rng(seed)
    xmin, xmax, ymin, ymax = t.extent
    return rng.uniform(xmin, xmax, n), rng.uniform(ymin, ymax, n)


def _held(t: Terrain, path: Path, origin: GeoOrigin, n: int = 60_000) -> tuple[float, float]:
    """The least margins, over random points, of the floor's grid above and the ceiling's grid
    below the raster's own ground (points over voids left out)."""
    x, y = _random_points(t, n)
    truth = source_ground(path, origin, x, y)
    ok = np.isfinite(truth)
    assert ok.mean() > 0.5
    return (
        float(np.min(t.height(x, y)[ok] - truth[ok])),
        float(np.min(truth[ok] - t.height_low(x, y)[ok])),
    )


def _hill_scenario(tmp_path: Path, void_half: int) -> Path:
    """``s.yaml`` on ``hill.tif``: the hill scene as an LZW GeoTIFF with NoData -9999 over a
    square of ``2 void_half`` samples around the peak, band 60-300 m above ground."""
    H, tr = hill_samples()
    write(tmp_path / "hill.tif", H, tr, nodata=-9999.0, void=peak_block(H, void_half),
          compress="lzw")  # fmt: skip
    data = {"name": "hill", "terrain": {"file": "hill.tif"}, "task_z": "ground",
            "altitude": {"min": 60, "max": 300},
            "tasks": [{"start": [-3500, -3000, 150], "goal": [3000, 3500, 150]}]}  # fmt: skip
    path = tmp_path / "s.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


# ------------------------------------------------------------------------------ NoData
NODATA = [
    ("float32", -9999.0),
    ("int16", -32768.0),
    ("uint16", 65535.0),
    ("float32", float("nan")),
    ("float32", float(np.finfo(np.float32).min)),
]


@pytest.mark.parametrize(("dtype", "nodata"), NODATA, ids=[f"{d}:{v:g}" for d, v in NODATA])
def test_the_files_nodata_is_a_void_whatever_its_value(
    tmp_path: Path, dtype: str, nodata: float
) -> None:
    """A void over the hill's peak, as NoData of each kind GIS tools write: read as voids (not
    as a pit, a tower or an error) and filled with the highest height on its rim."""
    H, tr = hill_samples()
    block = peak_block(H)
    path = write(tmp_path / "dem.tif", H, tr, dtype=dtype, nodata=nodata, void=block)
    src = read_raster(path)
    n = (block[0].stop - block[0].start) * (block[1].stop - block[1].start)
    assert src.voids == n
    assert (
        np.isnan(src.values[block]).all()
        and np.isfinite(np.delete(src.values.ravel(), np.flatnonzero(np.isnan(src.values)))).all()
    )
    valid = src.values[~src.void]
    assert valid.min() > 250 and valid.max() < 1200  # no -9999, 65535 or -3.4e38 among them
    rim = np.array(H, dtype=np.float64)
    rim_max = float(
        np.max(
            src.values[
                block[0].start - 1 : block[0].stop + 1, block[1].start - 1 : block[1].stop + 1
            ][
                ~np.isnan(
                    src.values[
                        block[0].start - 1 : block[0].stop + 1,
                        block[1].start - 1 : block[1].stop + 1,
                    ]
                )
            ]
        )
    )
    assert np.all(src.filled_high[block] == rim_max) and rim.shape == H.shape
    terrain, origin = place_raster(src)
    assert origin is not None and terrain.georef["voids_filled"] > 0
    assert float(np.min(terrain.heights)) > 250.0


def test_sentinels_without_a_nodata_value_are_voids_and_said(tmp_path: Path) -> None:
    H, tr = hill_samples()
    path = write(tmp_path / "dem.tif", H, tr, void=peak_block(H), void_value=-9999.0)
    src = read_raster(path)
    assert src.voids == 24 * 24 and "-9999" in src.voids_from and "no NoData" in src.voids_from


def test_a_scenario_on_a_nodata_raster_says_which_file_and_how_many(tmp_path: Path) -> None:
    from typer.testing import CliRunner

    from uavplan.cli import app

    _hill_scenario(tmp_path, 12)
    r = CliRunner().invoke(app, ["scenario", "show", str(tmp_path / "s.yaml")])
    assert r.exit_code == 0, r.output
    assert "-9999" not in r.output.split("raster:")[0]  # the terrain line: no pit
    assert "hill.tif (GTiff, EPSG:4326, LZW" in r.output and "576 voids (NoData -9999)" in r.output
    assert "voids:" in r.output and "nodes stand on no-data samples of hill.tif" in r.output


# ------------------------------------------------------------------------------ layout
def test_pixel_is_point_places_the_same_samples_as_pixel_is_area(tmp_path: Path) -> None:
    """The same DEM written with AREA_OR_POINT=Point (GDAL keeps the pixel centres) gives the
    same terrain, node for node, and the same origin: no half-pixel shift."""
    H, tr = hill_samples()
    area = place_raster(read_raster(write(tmp_path / "a.tif", H, tr)))
    point_src = read_raster(write(tmp_path / "p.tif", H, tr, point=True))
    assert point_src.area_or_point == "Point"
    point = place_raster(point_src)
    assert np.array_equal(area[0].heights, point[0].heights)
    assert area[1] is not None and point[1] is not None
    assert (area[1].lat, area[1].lon) == (point[1].lat, point[1].lon)
    # the projected grid too: its origin, its nodes
    U, trU = utm_hill()
    a = place_raster(read_raster(write(tmp_path / "ua.tif", U, trU, "EPSG:32616")))
    p = place_raster(read_raster(write(tmp_path / "up.tif", U, trU, "EPSG:32616", point=True)))
    assert a[0].georef["raster"]["offset"] == p[0].georef["raster"]["offset"]
    assert np.array_equal(a[0].heights, p[0].heights)


@pytest.mark.parametrize(
    "profile",
    [
        {"compress": "lzw"},
        {"compress": "deflate", "predictor": 2},
        {"compress": "zstd"},
        {"tiled": True, "blockxsize": 32, "blockysize": 32},
        {"tiled": True, "blockxsize": 64, "blockysize": 16, "compress": "lzw"},
    ],
    ids=["lzw", "deflate", "zstd", "tiled", "tiled-lzw"],
)
def test_compressed_and_tiled_rasters_read_as_the_plain_one(tmp_path: Path, profile: dict) -> None:
    H, tr = hill_samples()
    plain = read_raster(write(tmp_path / "plain.tif", H, tr, nodata=-9999.0, void=peak_block(H)))
    packed = read_raster(
        write(tmp_path / "packed.tif", H, tr, nodata=-9999.0, void=peak_block(H), **profile)
    )
    assert packed.compression == str(profile.get("compress", "")).upper()
    assert np.array_equal(plain.values, packed.values, equal_nan=True)
    assert np.array_equal(place_raster(plain)[0].heights, place_raster(packed)[0].heights)


def test_other_gdal_formats_read(tmp_path: Path) -> None:
    """An Arc/Info ASCII grid (with its NODATA_value) and an SRTM .hgt tile, by GDAL."""
    import rasterio

    H, tr = hill_samples(40, 50)
    ascii_path = tmp_path / "dem.asc"
    with rasterio.open(
        ascii_path,
        "w",
        driver="AAIGrid",
        width=50,
        height=40,
        count=1,
        dtype="float32",
        crs="EPSG:4326",
        transform=tr,
        nodata=-9999,
    ) as f:
        data = H.astype(np.float32)
        data[:3, :3] = -9999
        f.write(data, 1)
    src = read_raster(ascii_path)
    assert src.voids == 9 and src.driver == "AAIGrid"
    n = 1201
    tile = tmp_path / "N36W085.hgt"
    (np.full((n, n), 400, dtype=">i2")).tofile(tile)
    hgt = read_raster(tile)
    assert hgt.driver == "SRTMHGT" and hgt.voids == 0 and float(np.max(hgt.values)) == 400.0
    assert hgt.crs is not None and hgt.crs.is_geographic


def test_heights_in_feet_are_metres(tmp_path: Path) -> None:
    import rasterio

    H, tr = hill_samples(30, 40)
    path = write(tmp_path / "ft.tif", H / 0.3048, tr, dtype="float64")
    with rasterio.open(path, "r+") as f:
        f.units = ["ft"]
    assert np.allclose(read_raster(path).values, H, atol=1e-9)
    with rasterio.open(path, "r+") as f:
        f.units = ["furlong"]
    with pytest.raises(TerrainError, match=r"ft\.tif.*'furlong'"):
        read_raster(path)


def test_bad_rasters_are_refused_naming_the_file_and_why(tmp_path: Path) -> None:
    H, tr = hill_samples(30, 40)
    path = write(tmp_path / "one.tif", H, tr)
    with pytest.raises(TerrainError, match=r"one\.tif.*no band 2 \(it has 1\)"):
        read_raster(path, band=2)
    (tmp_path / "x.tif").write_bytes(b"II*\0garbage")
    with pytest.raises(TerrainError, match=r"x\.tif.*not a raster GDAL can read"):
        read_raster(tmp_path / "x.tif")
    allvoid = write(tmp_path / "void.tif", np.full((5, 5), -9999.0), tr, nodata=-9999.0)
    with pytest.raises(TerrainError, match="every sample is a void"):
        read_raster(allvoid)
    with pytest.raises(TerrainError, match="not found"):
        read_raster(tmp_path / "nope.tif")


# ------------------------------------------------------------------------------ envelopes
def test_geographic_floor_and_ceiling_hold_the_rasters_ground_everywhere(tmp_path: Path) -> None:
    """Between the nodes too: the floor's bilinear grid is never below, the ceiling's never
    above the raster's own ground (checked by the tests' own route, pyproj and rasterio, at
    60,000 random points), with and without voids, at three cell sizes."""
    H, tr = hill_samples()
    plain = write(tmp_path / "plain.tif", H, tr)
    holed = write(tmp_path / "holed.tif", H, tr, nodata=-9999.0, void=peak_block(H))
    for path, cell in ((plain, None), (plain, 250.0), (plain, 20.0), (holed, None)):
        t, origin = place_raster(read_raster(path), cell_size=cell)
        floor, ceiling = _held(t, path, _origin(t, origin))
        assert floor >= -1e-6 and ceiling >= -1e-6, (path.name, cell, floor, ceiling)
        lift = t.georef["lift"]
        assert lift["floor_median"] < 5.0 and lift["ceiling_median"] < 5.0, lift


def test_a_given_origin_and_a_projected_raster_through_it(tmp_path: Path) -> None:
    U, trU = utm_hill()
    path = write(tmp_path / "utm.tif", U, trU, "EPSG:32616", compress="deflate")
    src = read_raster(path)
    kept, origin = place_raster(src)
    assert kept.georef["raster"]["frame"] == "crs-offset" and kept.lower is None
    assert origin is not None and origin.accuracy == 0 and origin.crs == "EPSG:32616"
    given = GeoOrigin(origin.lat, origin.lon, 100.0)
    moved, none = place_raster(src, origin=given, bounds=(-1500, 1500, -1200, 1200))
    assert none is None and moved.georef["raster"]["frame"] == "reprojected"
    floor, ceiling = _held(moved, path, given)
    assert floor >= -1e-6 and ceiling >= -1e-6


def test_the_rise_bound_covers_every_sampled_rise(tmp_path: Path) -> None:
    """The kernel's bound per cell is at least the rise of the source above the interpolant
    found by dense sampling with the exact map, and close to it (it is exact per piece)."""
    H, tr = hill_samples(60, 80)
    path = write(tmp_path / "h.tif", H, tr)
    src = read_raster(path)
    t, origin = place_raster(src, cell_size=150.0)
    o = _origin(t, origin)
    ny, nx = t.shape
    X, Y = np.meshgrid(t.x0 + t.dx * np.arange(nx), t.y0 + t.dy * np.arange(ny))
    from uavplan.world.raster import _local_to_samples

    to_s = _local_to_samples(src, o)
    U, V = to_s(X, Y)
    S = bilinear_samples(src.filled_high, U, V)
    rise = rk.cell_rise(np.ascontiguousarray(src.filled_high), U, V, S, 1e-6)
    k = 24
    g = np.arange(k + 1) / k
    XI, ETA = np.meshgrid(g, g)
    rng = np.random.default_rng(3)
    gaps = []
    for _ in range(150):
        j, i = int(rng.integers(0, ny - 1)), int(rng.integers(0, nx - 1))
        u, v = to_s(X[j, i] + XI * t.dx, Y[j, i] + ETA * t.dy)
        s = bilinear_samples(src.filled_high, u, v)
        c = S[j : j + 2, i : i + 2]
        interp = (
            c[0, 0] * (1 - XI) * (1 - ETA)
            + c[0, 1] * XI * (1 - ETA)
            + c[1, 0] * (1 - XI) * ETA
            + c[1, 1] * XI * ETA
        )
        sampled = float(np.max(s - interp))
        assert rise[j, i] >= sampled - 1e-9
        gaps.append(rise[j, i] - max(sampled, 0.0))
    assert float(np.median(gaps)) < 0.5  # tight: the sampling misses little


def test_fill_voids_takes_each_regions_rim() -> None:
    v = np.array([[1.0, 2, 3, 4], [5, np.nan, np.nan, 8], [9, 10, 11, 12], [np.nan, 14, 15, 16]])
    hi, lo = fill_voids(v, True), fill_voids(v, False)
    assert hi[1, 1] == hi[1, 2] == 12 and lo[1, 1] == lo[1, 2] == 1
    assert hi[3, 0] == 14 and lo[3, 0] == 9


# ------------------------------------------------------------------------------ scenarios
def test_a_compressed_geographic_nodata_raster_plans_and_verifies(tmp_path: Path) -> None:
    """The issue's case: an LZW GeoTIFF in degrees with NoData -9999 over the hill, named by a
    scenario: ``uavplan plan`` exits 0 only with every flown point inside the band relative to
    the raster's own ground (outside the void), and says which file's voids it flew over."""
    from typer.testing import CliRunner

    from uavplan.cli import app

    _hill_scenario(tmp_path, 6)
    out = tmp_path / "run"
    r = CliRunner().invoke(
        app, ["plan", str(tmp_path / "s.yaml"), "--out", str(out), "--seed", "1"]
    )
    assert r.exit_code == 0, r.output
    assert "every flown trajectory passes" in r.output
    sc = load_scenario(tmp_path / "s.yaml")
    import json

    plan = json.loads((out / "plan.json").read_text())
    flown = np.asarray(plan["uavs"][0]["flown"]["points"], dtype=np.float64)
    # densely along the flight, by the tests' own route
    s = np.linspace(0, 1, 200)[:, None]
    pts = np.concatenate([a + s * (b - a) for a, b in itertools.pairwise(flown)])
    assert sc.origin is not None
    ground = source_ground(tmp_path / "hill.tif", sc.origin, pts[:, 0], pts[:, 1])
    ok = np.isfinite(ground)
    h = pts[ok, 2] - ground[ok]
    assert h.min() >= 60 - 1e-6 and h.max() <= 300 + 1e-6
    v = CliRunner().invoke(app, ["verify", str(out / "plan.json"), str(tmp_path / "s.yaml")])
    assert v.exit_code == 0 and "checked against the raster hill.tif itself" in v.output


def test_a_raster_with_a_local_crs_is_refused_unless_read_as_a_grid(tmp_path: Path) -> None:
    import tifffile

    tifffile.imwrite(
        tmp_path / "local.tif",
        np.ones((20, 30), np.float32),
        extratags=[
            (33550, "d", 3, (0.001, 0.001, 0.0), False),
            (33922, "d", 6, (0, 0, 0, -84.5, 36.6, 0), False),
            (34735, "H", 8, (1, 1, 0, 1, 2048, 0, 1, 4326), False),
        ],
    )
    data = {
        "name": "l",
        "terrain": {"file": "local.tif"},
        "tasks": [{"start": [0.001, 0.001, 10], "goal": [0.01, 0.01, 10]}],
    }
    (tmp_path / "s.yaml").write_text(yaml.safe_dump(data))
    with pytest.raises(ScenarioFileError, match="its CRS is a local one"):
        load_scenario(tmp_path / "s.yaml")


def test_landscape_matches_the_samples() -> None:
    H, _ = hill_samples(10, 10)
    assert H[0, 0] == pytest.approx(
        float(landscape(np.array(36.7 - 0.5 / 1200), np.array(-84.4 + 0.5 / 1200)))
    )


def test_a_flight_over_voids_is_warned_naming_the_file(tmp_path: Path) -> None:
    """A stripe of voids across the map: every flight crosses it, and ``uavplan plan`` says on
    stderr how far it flies over ground the raster does not know (and the verifier too)."""
    from typer.testing import CliRunner

    from uavplan.cli import app

    H, tr = hill_samples()
    write(tmp_path / "stripe.tif", H, tr, nodata=-9999.0, void=(slice(None), slice(40, 43)))
    data = {"name": "stripe", "terrain": {"file": "stripe.tif"}, "task_z": "ground",
            "altitude": {"min": 60, "max": 300},
            "tasks": [{"start": [-4000, 0, 150], "goal": [4000, 0, 150]}]}  # fmt: skip
    (tmp_path / "t.yaml").write_text(yaml.safe_dump(data))
    out = tmp_path / "run"
    r = CliRunner().invoke(app, ["plan", str(tmp_path / "t.yaml"), "-a", "rrt-star", "--out",
                                 str(out)])  # fmt: skip
    assert r.exit_code == 0, r.output
    assert (
        "WARNING: uav0 flies about" in r.output and "over voids (no data) of stripe.tif" in r.output
    )
    v = CliRunner().invoke(app, ["verify", str(out), str(tmp_path / "t.yaml")])
    assert v.exit_code == 0 and "over voids (no data) of stripe.tif" in v.output
