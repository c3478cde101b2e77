"""SRTM .hgt tiles (issue 16): reading (row 0 north, big-endian, voids), mosaics, resampling
onto the local frame through the scenario's origin (conservative), and scenario files."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

from uavplan.cli import app
from uavplan.io.scenario_file import ScenarioFileError, load_scenario
from uavplan.world.geo import GeoOrigin
from uavplan.world.raster import points_over_voids
from uavplan.world.srtm import VOID, mosaic, read_hgt, terrain_from_srtm
from uavplan.world.terrain import TerrainError

N = 1201  # 3 arc-seconds


def height(lat: np.ndarray, lon: np.ndarray) -> np.ndarray:
    """A smooth landscape in metres AMSL: a ramp plus a hill."""
    return 300.0 + 800.0 * (lat - 36.0) + 200.0 * np.sin(6.0 * lon)


def write_tile(folder: Path, lat: int, lon: int, void: tuple[slice, slice] | None = None) -> Path:
    name = f"{'N' if lat >= 0 else 'S'}{abs(lat):02d}{'E' if lon >= 0 else 'W'}{abs(lon):03d}.hgt"
    la = lat + 1 - np.arange(N) / (N - 1)  # row 0 is the northern edge
    lo = lon + np.arange(N) / (N - 1)
    H = np.round(height(la[:, None], lo[None, :])).astype(">i2")
    if void is not None:
        H[void] = VOID
    path = folder / name
    H.tofile(path)
    return path


def test_read_hgt_flips_rows_and_marks_voids(tmp_path: Path) -> None:
    p = write_tile(tmp_path, 36, -85, (slice(0, 10), slice(0, 10)))
    t = read_hgt(p)
    assert (t.lat, t.lon, t.n) == (36, -85, N)
    assert t.heights[0, 0] == pytest.approx(height(np.array(36.0), np.array(-85.0)), abs=0.5)
    assert np.isnan(t.heights[-10:, :10]).all()  # the void was at the north-west corner
    assert np.isfinite(t.heights[:-10]).all()


def test_bad_tiles_are_refused_with_the_file_named(tmp_path: Path) -> None:
    bad = tmp_path / "N36W085.hgt"
    bad.write_bytes(b"\0" * 1000)
    with pytest.raises(TerrainError, match=r"N36W085\.hgt.*1000 bytes"):
        read_hgt(bad)
    other = tmp_path / "tile.hgt"
    other.write_bytes(b"\0" * (2 * N * N))
    with pytest.raises(TerrainError, match="not an SRTM tile name"):
        read_hgt(other)


def test_mosaic_shares_the_edge_and_fills_missing_tiles_with_voids(tmp_path: Path) -> None:
    a = read_hgt(write_tile(tmp_path, 36, -85))
    b = read_hgt(write_tile(tmp_path, 37, -84))
    lats, lons, H = mosaic([a, b])
    assert H.shape == (2 * (N - 1) + 1, 2 * (N - 1) + 1)
    assert lats[0] == 36 and lats[-1] == pytest.approx(38) and lons[0] == -85
    assert np.isnan(H[N + 5, 5]) and np.isnan(H[5, N + 5])  # N37W085 and N36W084 missing
    assert H[5, 5] == a.heights[5, 5]


def test_resampled_terrain_is_conservative_and_fills_voids_high(tmp_path: Path) -> None:
    west = write_tile(tmp_path, 36, -85, (slice(600, 620), slice(1100, 1120)))
    east = write_tile(tmp_path, 36, -84)
    origin = GeoOrigin(36.5, -84.0, 100.0)  # on the tiles' shared meridian
    terrain, filled = terrain_from_srtm([west, east], origin, (-20e3, 20e3, -15e3, 15e3))
    assert terrain.dx == 90.0 and filled > 0
    ys = terrain.y0 + terrain.dy * np.arange(terrain.shape[0])
    xs = terrain.x0 + terrain.dx * np.arange(terrain.shape[1])
    Y, X = np.meshgrid(ys, xs, indexing="ij")
    G = origin.to_geodetic(np.column_stack([X.ravel(), Y.ravel()]))
    truth = height(G[:, 0], G[:, 1]).reshape(terrain.shape) - origin.alt
    Z = np.asarray(terrain.heights)
    # the void: rows 600-620 from the north, columns 1100-1120 of N36W085 (and one sample round)
    la, lo = G[:, 0].reshape(Z.shape), G[:, 1].reshape(Z.shape)
    in_void = (la > 37 - 621 / 1200) & (la < 37 - 599 / 1200)
    in_void &= (lo > -85 + 1099 / 1200) & (lo < -85 + 1121 / 1200)
    assert in_void.sum() > 0 and np.isfinite(Z).all()
    # never below the landscape at a node outside the void (int16 rounding: 0.5 m), and not
    # far above it (one source cell's rise at most)
    assert (Z[~in_void] >= truth[~in_void] - 0.5 - 1e-9).all()
    assert (Z - truth)[~in_void].max() < 5.0
    # in the void: the highest valid height around, so never far below the landscape there
    assert (np.abs(Z[in_void] - truth[in_void]) < 20.0).all()
    assert terrain.georef["voids_filled"] == filled
    inner = (la > 37 - 619 / 1200) & (la < 37 - 600 / 1200)
    inner &= (lo > -85 + 1100 / 1200) & (lo < -85 + 1119 / 1200)
    over = np.column_stack([X[inner], Y[inner]])
    assert len(over) > 0 and points_over_voids(terrain, over) == len(over)
    assert points_over_voids(terrain, np.column_stack([X[~in_void], Y[~in_void]])[::7][:50]) < 50
    assert points_over_voids(terrain, np.array([[-19e3, -14e3]])) == 0


def test_a_map_beyond_the_tiles_names_the_missing_tile(tmp_path: Path) -> None:
    west = write_tile(tmp_path, 36, -85)
    with pytest.raises(TerrainError, match=r"add N36W084\.hgt"):
        terrain_from_srtm([west], GeoOrigin(36.5, -84.2), (-5e3, 30e3, -5e3, 5e3))


def _scenario(tmp_path: Path, **over: object) -> Path:
    write_tile(tmp_path, 36, -85)
    data = {
        "name": "srtm-test",
        "bounds": {"lower": [-5000, -5000, 0], "upper": [5000, 5000, 3000]},
        "terrain": {"srtm": ["N36W085.hgt"]},
        "origin": {"lat": 36.5, "lon": -84.5, "alt": 0},
        "tasks": [{"start": [-4000, -4000, 2000], "goal": [4000, 4000, 2000]}],
    }
    data.update(over)
    path = tmp_path / "s.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def test_a_scenario_file_on_srtm_tiles(tmp_path: Path) -> None:
    sc = load_scenario(_scenario(tmp_path))
    assert sc.terrain is not None and sc.origin is not None
    assert sc.terrain.height(0.0, 0.0) == pytest.approx(
        height(np.array(36.5), np.array(-84.5)), abs=2
    )


def test_srtm_needs_an_origin_said_clearly(tmp_path: Path) -> None:
    path = _scenario(tmp_path, origin=None)
    with pytest.raises(ScenarioFileError, match=r"terrain\.srtm.*origin"):
        load_scenario(path)
    r = CliRunner().invoke(app, ["scenario", "check", str(path)])
    assert r.exit_code == 2 and "origin" in r.output and "Traceback" not in r.output
    path = _scenario(tmp_path, terrain={"srtm": ["N99W085.hgt"]})
    with pytest.raises(ScenarioFileError, match="not found"):
        load_scenario(path)


def _feature(kind: str, coordinates: object) -> dict[str, object]:
    return {
        "type": "Feature",
        "properties": {},
        "geometry": {"type": kind, "coordinates": coordinates},
    }


def test_tasks_in_wgs84_and_geojson_no_fly_zones(tmp_path: Path) -> None:
    """Starts and goals as lat/lon/alt, and no-fly polygons from a GeoJSON file, through the
    origin; a saved copy elsewhere still finds its files."""
    o = GeoOrigin(36.5, -84.5, 0.0)
    ring = o.to_geodetic([[-1000, -1000], [1000, -1000], [1000, 1000], [-1000, 1000]])
    coords = [[float(g[1]), float(g[0])] for g in [*ring, ring[0]]]
    gj = {"type": "FeatureCollection", "features": [_feature("Polygon", [coords])]}
    (tmp_path / "zones.geojson").write_text(json.dumps(gj))
    start = o.to_geodetic([[-4000, -4000, 2000]])[0].tolist()
    path = _scenario(
        tmp_path, no_fly=["zones.geojson"],
        tasks=[{"frame": "wgs84", "start": start, "goal": [36.53, -84.47, 2100]}],
    )  # fmt: skip
    sc = load_scenario(path)
    assert sc.tasks[0].start == pytest.approx((-4000, -4000, 2000), abs=1e-6)
    square = np.array([[-1000, -1000], [1000, -1000], [1000, 1000], [-1000, 1000]])
    assert np.asarray(sc.polygons[0].vertices) == pytest.approx(square, abs=1e-6)
    from uavplan.io.scenario_file import save_scenario

    (tmp_path / "elsewhere").mkdir()
    copy = save_scenario(sc, tmp_path / "elsewhere" / "copy.yaml")
    again = load_scenario(copy)
    assert len(again.polygons) == 1 and again.terrain is not None
    bad = {"type": "FeatureCollection", "features": [_feature("Point", [0, 0])]}
    (tmp_path / "bad.geojson").write_text(json.dumps(bad))
    with pytest.raises(ScenarioFileError, match=r"features\[0\] is 'Point'"):
        load_scenario(_scenario(tmp_path, no_fly=["bad.geojson"]))
    with pytest.raises(ScenarioFileError, match="wgs84 needs the scenario's origin"):
        task = {"frame": "wgs84", "start": [36.5, -84.5, 1], "goal": [36.6, -84.5, 1]}
        load_scenario(_scenario(tmp_path, origin=None, terrain=None, tasks=[task]))


def _geotiff(path: Path, epsg: int, geographic: bool = False) -> None:
    import rasterio
    from rasterio.transform import Affine

    H = np.add.outer(np.arange(200.0), np.arange(300.0)).astype(np.float32)
    tr = (Affine(0.001, 0, -84.5, 0, -0.001, 36.6) if geographic
          else Affine(30.0, 0, 500000.0, 0, -30.0, 4000000.0))  # fmt: skip
    with rasterio.open(path, "w", driver="GTiff", width=300, height=200, count=1,
                       dtype="float32", crs=f"EPSG:{epsg}", transform=tr) as f:  # fmt: skip
        f.write(H, 1)


def test_a_projected_geotiff_places_itself_on_earth(tmp_path: Path) -> None:
    """UTM 17N (EPSG:32617): the origin comes from the file, and the local frame is the file's
    CRS (shifted), so that exported positions convert exactly: a round trip through WGS84
    lands on the same local point, and a corner node is where the raster puts it."""
    from pyproj import Transformer

    _geotiff(tmp_path / "dem.tif", 32617)
    data = {"name": "utm", "terrain": {"file": "dem.tif"},
            "tasks": [{"start": [100, 100, 500], "goal": [8000, 5000, 600]}]}  # fmt: skip
    (tmp_path / "s.yaml").write_text(yaml.safe_dump(data))
    sc = load_scenario(tmp_path / "s.yaml")
    o = sc.origin
    assert o is not None and "EPSG:32617" in o.note and o.accuracy == 0 and o.crs == "EPSG:32617"
    corner = Transformer.from_crs(32617, 4326, always_xy=True).transform(
        500000 + 0.5 * 30.0, 4000000 - 199.5 * 30.0)  # fmt: skip
    sw = o.to_geodetic(np.array([[0.0, 0.0]]))[0]  # node (0, 0): the south-west sample
    assert (sw[1], sw[0]) == pytest.approx(corner, abs=1e-9)
    back = o.to_local(o.to_geodetic(np.array([[123.4, 5678.9, 10.0]])))[0]
    assert back == pytest.approx([123.4, 5678.9, 10.0], abs=1e-6)
    centre = Transformer.from_crs(32617, 4326, always_xy=True).transform(
        500000 + 150 * 30.0, 4000000 - 100 * 30.0)  # fmt: skip
    assert (o.lon, o.lat) == pytest.approx(centre, abs=1e-9)


def test_a_geographic_geotiff_is_resampled_onto_metres(tmp_path: Path) -> None:
    """EPSG:4326 pixels of 0.001 degrees from 36.6 N, 84.5 W: resampled like SRTM tiles onto
    the largest local box inside the DEM, cells of its smaller pixel side (0.001 degrees of
    longitude at 36.5 N: 89.5 m, rounded to 90), never below the DEM at a node."""
    _geotiff(tmp_path / "geo.tif", 4326, geographic=True)
    data = {"name": "geo", "terrain": {"file": "geo.tif"},
            "tasks": [{"start": [0, 0, 900], "goal": [5000, 3000, 900]}]}  # fmt: skip
    (tmp_path / "g.yaml").write_text(yaml.safe_dump(data))
    sc = load_scenario(tmp_path / "g.yaml")
    t, o = sc.terrain, sc.origin
    assert t is not None and o is not None and "EPSG:4326" in o.note
    assert t.dx == 90.0 and o.lat == pytest.approx(36.6 - 0.1, abs=1e-3)
    xs = t.x0 + t.dx * np.arange(t.shape[1])
    ys = t.y0 + t.dy * np.arange(t.shape[0])
    X, Y = np.meshgrid(xs, ys)
    G = o.to_geodetic(np.column_stack([X.ravel(), Y.ravel()]))
    # the file's heights are row + column (row 0 north): h = (36.6 - lat) / d + (lon + 84.5) / d
    truth = ((36.6 - G[:, 0]) / 0.001 - 0.5) + ((G[:, 1] + 84.5) / 0.001 - 0.5)
    Z = np.asarray(t.heights).ravel()
    assert (truth - 1e-6 <= Z).all() and (Z - truth).max() <= 2.0 + 1e-6
