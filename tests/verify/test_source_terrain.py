"""The verifier's terrain check against the elevation raster itself: it reads the file again
(its own GDAL route), so a misread raster cannot pass both the planner and the verifier; and,
on random rasters with random voids in every placement, a flight the planner's checks pass is
inside the band relative to the raster's own ground all along (the property the floor's and
ceiling's grids exist for), which the verifier confirms."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from uavplan.io.plan_file import Trajectory
from uavplan.io.scenario_file import ScenarioFileError, load_scenario
from uavplan.problems.validity import MotionValidator
from uavplan.verify import verify_trajectories
from uavplan.world import Terrain
from world.rasters import hill_samples, peak_block, source_ground, write


def _scenario(tmp_path: Path, raster: str, **more: object) -> Path:
    data = {
        "name": "src",
        "terrain": {"file": raster},
        "altitude": {"min": 60, "max": 300},
        "task_z": "ground",
        "tasks": [{"start": [-3000, -3000, 150], "goal": [3000, 3000, 150]}],
        **more,
    }
    path = tmp_path / "s.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def _straight(sc: object, z_of: object, n: int = 60) -> Trajectory:
    t = np.linspace(0.0, 1.0, n)
    x = -3000.0 + 6000.0 * t
    y = -3000.0 + 6000.0 * t
    z = z_of(x, y)  # type: ignore[operator]
    return Trajectory("uav0", np.column_stack([x, y, z]), t * 500.0)


def test_a_misread_raster_cannot_pass_the_verifier(tmp_path: Path) -> None:
    """The planner's terrain lowered by 120 m (as a misread NoData or unit would): a flight 150 m
    above that terrain is inside the band there, and the verifier, reading the raster itself,
    finds it under the band (and in places under the hill) and says the terrain disagrees."""
    H, tr = hill_samples()
    write(tmp_path / "hill.tif", H, tr, compress="lzw")
    sc = load_scenario(_scenario(tmp_path, "hill.tif"))
    t = sc.terrain
    assert t is not None and t.lower is not None
    wrong = Terrain(t.heights - 120.0, t.x0, t.y0, t.dx, t.dy, t.name, t.georef, t.lower - 120.0)
    misread = dataclasses.replace(sc, terrain=wrong)
    flight = _straight(misread, lambda x, y: wrong.height(x, y) + 100.0)
    report = verify_trajectories([flight], misread, kinematics=False)
    assert report.terrain_source == "hill.tif"
    kinds = {v.kind for v in report.violations}
    assert "altitude" in kinds and all("ground of hill.tif" in v.message for v in report.violations)
    assert any("disagrees with hill.tif" in w and "misread" in w for w in report.warnings)
    # 100 m above the terrain as read: inside the band, and the terrain agrees with its raster
    good = verify_trajectories([_straight(sc, lambda x, y: t.height(x, y) + 100.0)], sc,
                               kinematics=False)  # fmt: skip
    assert good.ok and not [w for w in good.warnings if "disagrees" in w]


def test_the_verifier_checks_between_its_points_exactly(tmp_path: Path) -> None:
    """One straight segment, its ends hundreds of metres above the ground, 20 m under the
    highest ground between them: the verifier finds that point, between its ends, exactly."""
    H, tr = hill_samples()
    write(tmp_path / "hill.tif", H, tr)
    sc = load_scenario(_scenario(tmp_path, "hill.tif"))
    assert sc.terrain is not None and sc.origin is not None
    a, b = np.array([-3000.0, -3000.0]), np.array([3000.0, 3000.0])
    s = np.linspace(0, 1, 20001)
    ground = source_ground(tmp_path / "hill.tif", sc.origin, a[0] + s * (b - a)[0],
                           a[1] + s * (b - a)[1])  # fmt: skip
    z = float(np.nanmax(ground)) - 20.0
    assert z - ground[0] > 100 and z - ground[-1] > 100
    flight = Trajectory("uav0", np.array([[*a, z], [*b, z]]), np.array([0, 500.0]))
    report = verify_trajectories([flight], sc, kinematics=False)
    under = [v for v in report.violations if v.kind == "terrain"]
    assert len(under) == 1 and -20.1 < under[0].value <= -20.0 + 1e-9
    assert "goes 20.0" in under[0].message and "under the ground of hill.tif" in under[0].message


def test_srtm_tiles_are_read_again_through_gdal(tmp_path: Path) -> None:
    n = 1201
    la = 37 - np.arange(n) / (n - 1)
    lo = -85 + np.arange(n) / (n - 1)
    Z = (300 + 800 * (la[:, None] - 36) + 200 * np.sin(6 * lo[None, :])).round().astype(">i2")
    Z[600:620, 600:620] = -32768
    Z.tofile(tmp_path / "N36W085.hgt")
    data = {
        "name": "srtm", "bounds": {"lower": [-5000, -5000, 0], "upper": [5000, 5000, 3000]},
        "terrain": {"srtm": ["N36W085.hgt"]}, "origin": {"lat": 36.5, "lon": -84.5, "alt": 0},
        "altitude": {"min": 50, "max": 400}, "task_z": "ground",
        "tasks": [{"start": [-4000, -4000, 150], "goal": [4000, 4000, 150]}],
    }  # fmt: skip
    (tmp_path / "s.yaml").write_text(yaml.safe_dump(data))
    sc = load_scenario(tmp_path / "s.yaml")
    t = sc.terrain
    assert t is not None
    flight = _straight(sc, lambda x, y: t.height(x, y) + 100.0)
    report = verify_trajectories([flight], sc, kinematics=False)
    assert report.terrain_source == "N36W085.hgt" and report.ok, report.violations
    assert any("voids (no data) of N36W085.hgt" in w for w in report.warnings)


def test_a_raster_gone_after_loading_is_a_clear_error(tmp_path: Path) -> None:
    from typer.testing import CliRunner

    from uavplan.cli import app

    H, tr = hill_samples()
    write(tmp_path / "hill.tif", H, tr)
    path = _scenario(tmp_path, "hill.tif")
    (tmp_path / "hill.tif").unlink()
    with pytest.raises(ScenarioFileError, match="not found"):
        load_scenario(path)
    r = CliRunner().invoke(app, ["verify", str(tmp_path / "none.json"), str(path)])
    assert r.exit_code == 2 and "Traceback" not in r.output


# ------------------------------------------------------------------------------ the property
KINDS = ("geographic", "utm", "utm-reprojected", "plain-grid")


def _random_raster(tmp_path: Path, rng: np.random.Generator, kind: str, voids: int) -> Path:
    from rasterio.transform import Affine

    rows, cols = (int(v) for v in rng.integers(14, 36, 2))
    yy, xx = np.mgrid[0:rows, 0:cols].astype(np.float64)
    H = 200.0 + rng.uniform(-2, 2) * xx + rng.uniform(-2, 2) * yy
    for _ in range(int(rng.integers(1, 5))):
        cx, cy = rng.uniform(0, cols), rng.uniform(0, rows)
        H += rng.uniform(-150, 400) * np.exp(-((xx - cx) ** 2 + (yy - cy) ** 2)
                                              / (2 * rng.uniform(1.5, 6) ** 2))  # fmt: skip
    H += rng.uniform(0, 25) * rng.standard_normal(H.shape)  # rough: every cell bends
    mask = np.zeros(H.shape, dtype=bool)
    for _ in range(voids):
        r0, c0 = int(rng.integers(1, rows - 4)), int(rng.integers(1, cols - 4))
        mask[r0 : r0 + int(rng.integers(1, 4)), c0 : c0 + int(rng.integers(1, 4))] = True
    H[mask] = -9999.0
    if kind == "geographic":
        step = float(rng.choice([1 / 1200, 1 / 3600, 0.002]))
        tr, crs = Affine(step, 0, -84.4, 0, -step, 36.7), "EPSG:4326"
    elif kind == "plain-grid":
        tr, crs = Affine(25.0, 0, 0, 0, -25.0, 0), None
    else:
        cell = float(rng.choice([10.0, 30.0, 90.0]))
        tr, crs = Affine(cell, 0, 730_000.0, 0, -cell, 4_066_000.0), "EPSG:32616"
    return write(tmp_path / "r.tif", H, tr, crs, nodata=-9999.0, compress="deflate")


@settings(
    max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    seed=st.integers(0, 2**32 - 1),
    kind=st.sampled_from(KINDS),
    ratio=st.sampled_from([0.45, 1.0, 2.3]),
    voids=st.integers(0, 3),
)
def test_flights_the_planner_passes_stay_in_the_band_over_the_rasters_own_ground(
    tmp_path_factory: pytest.TempPathFactory, seed: int, kind: str, ratio: float, voids: int
) -> None:
    from uavplan.world.geo import GeoOrigin
    from uavplan.world.raster import pixel_metres, place_raster, raster_centre, read_raster

    tmp = tmp_path_factory.mktemp("prop")
    rng = np.random.default_rng(seed)
    path = _random_raster(tmp, rng, kind, voids)
    src = read_raster(path)
    origin = GeoOrigin(36.68, -84.38, 50.0) if kind == "utm-reprojected" else None
    terrain: dict[str, object] = {"file": path.name}
    if kind == "plain-grid":
        terrain["cell_size"] = 25.0
    elif kind != "utm":
        at = origin if origin is not None else GeoOrigin(*raster_centre(src))
        terrain["cell_size"] = max(1.0, round(min(pixel_metres(src, at)) * ratio, 1))
    cell = terrain.get("cell_size")
    t0, _ = place_raster(src, origin=origin, cell_size=cell)  # type: ignore[arg-type]
    band = (40.0, 220.0)
    xmin, xmax, ymin, ymax = t0.extent
    cx, cy = 0.5 * (xmin + xmax), 0.5 * (ymin + ymax)
    lo, hi = float(t0.height(cx, cy)) + band[0], float(t0.height_low(cx, cy)) + band[1]
    assume(lo < hi)
    data: dict[str, object] = {
        "name": "prop", "terrain": terrain, "altitude": {"min": band[0], "max": band[1]},
        "tasks": [{"start": [cx, cy, (lo + hi) / 2], "goal": [cx + 1, cy + 1, (lo + hi) / 2]}],
    }  # fmt: skip
    if origin is not None:
        data["origin"] = {"lat": origin.lat, "lon": origin.lon, "alt": origin.alt}
    (tmp / "s.yaml").write_text(yaml.safe_dump(data))
    sc = load_scenario(tmp / "s.yaml")
    t = sc.terrain
    assert t is not None and np.array_equal(t.heights, t0.heights)
    xmin, xmax, ymin, ymax = t.extent
    # candidate flights hugging the band's floor and ceiling over the planner's grids
    n_paths, n_pts = 150, 5
    step = 3.0 * max(t.dx, t.dy)
    xy = np.empty((n_paths, n_pts, 2))
    xy[:, 0] = np.column_stack([rng.uniform(xmin, xmax, n_paths), rng.uniform(ymin, ymax, n_paths)])
    for k in range(1, n_pts):  # short random walks: each segment crosses a few cells
        xy[:, k] = xy[:, k - 1] + rng.uniform(-step, step, (n_paths, 2))
    xy[..., 0] = np.clip(xy[..., 0], xmin, xmax)
    xy[..., 1] = np.clip(xy[..., 1], ymin, ymax)
    floor = t.height(xy[..., 0], xy[..., 1]) + band[0]
    ceil = t.height_low(xy[..., 0], xy[..., 1]) + band[1]
    w = rng.choice([0.0, 0.02, 0.5, 0.98, 1.0], size=(n_paths, n_pts))
    z = floor + w * (ceil - floor)
    paths = np.concatenate([xy, z[..., None]], axis=-1)
    validator = MotionValidator(sc, strict_altitude=True)
    ok = validator.paths_valid(paths)
    origin = sc.origin
    # densely along every flight the planner's checks pass, by the tests' own route
    s = np.linspace(0, 1, 300)[None, :, None]
    good = paths[ok]
    pts = good[:, :-1, None, :] + s[:, None] * (good[:, 1:, None, :] - good[:, :-1, None, :])
    pts = pts.reshape(-1, 3)
    if origin is None:  # the plain grid: the raster's rows and columns are the grid's
        ground = _plain_ground(path, t, pts)
    else:
        ground = source_ground(path, origin, pts[:, 0], pts[:, 1])
    known = np.isfinite(ground)  # NaN: a void's cell (no ground known) or none
    h = pts[known, 2] - ground[known]
    if h.size:
        assert h.min() >= band[0] - 1e-6 and h.max() <= band[1] + 1e-6, (kind, h.min(), h.max())
    # the verifier, reading the raster itself, agrees: every one of them passes (no time
    # overlaps between them, so that separation does not come into it)
    trajs = [Trajectory(f"u{k}", p, k * 1e5 + np.arange(len(p)) * 1e3)
             for k, p in enumerate(paths[ok])]  # fmt: skip
    if trajs:
        report = verify_trajectories(trajs, sc, kinematics=False)
        assert not [v for v in report.violations if v.kind in ("terrain", "altitude")], (
            report.violations[:2])  # fmt: skip
        assert not [wn for wn in report.warnings if "disagrees" in wn], report.warnings
    assert h.size > 0 or not ok.any()


def _plain_ground(path: Path, t: Terrain, pts: np.ndarray) -> np.ndarray:
    import rasterio

    with rasterio.open(path) as ds:
        m = ds.read(1, masked=True)
    H = np.where(np.ma.getmaskarray(m), np.nan, np.asarray(m.data, dtype=np.float64))[::-1]
    u = (pts[:, 0] - t.x0) / t.dx
    v = (pts[:, 1] - t.y0) / t.dy
    ny, nx = H.shape
    i = np.clip(np.floor(u).astype(int), 0, nx - 2)
    j = np.clip(np.floor(v).astype(int), 0, ny - 2)
    s, r = u - i, v - j
    return (H[j, i] * (1 - s) * (1 - r) + H[j, i + 1] * s * (1 - r) + H[j + 1, i] * (1 - s) * r
            + H[j + 1, i + 1] * s * r)  # fmt: skip


def test_peak_block_helper() -> None:
    H, _ = hill_samples(40, 40)
    sl = peak_block(H, 3)
    assert H[sl].max() == H.max()


def test_the_ground_within_a_small_reach_is_bounded_tightly_on_a_coarse_raster() -> None:
    """Luxembourg (30 arc-second samples, 600 m x 930 m): the least and largest height of a
    flight above the ground within 3 m of it. Every point within 3 m (sampled densely) stands
    inside the bound, and the bound is within a metre of that."""
    from uavplan.scenarios import resolve
    from uavplan.verify.source_terrain import (
        _piece_reach_bound,
        read_source,
        source_clearance,
    )

    sc = resolve("luxembourg")
    src = read_source(sc.terrain)
    assert src is not None
    rng = np.random.default_rng(3)
    xy = np.array([[0.0, -22500.0], [-2700.0, -4600.0], [-4800.0, 8800.0], [-7500.0, 26000.0]])
    z = np.array([sc.terrain.height(*p) for p in xy]) + np.array([100.0, 60.0, 140.0, 100.0])
    tr = Trajectory("a", np.column_stack([xy, z]), np.arange(4.0) * 500, True)
    low, high = _piece_reach_bound(tr, src, 3.0, 150.0)
    # brute force: points along the flight, each against ground points within 3 m of it
    s = np.linspace(0, 1, 4001)
    P = np.concatenate([tr.points[k] + s[:, None] * (tr.points[k + 1] - tr.points[k])
                        for k in range(3)])  # fmt: skip
    ang = rng.uniform(0, 2 * np.pi, (len(P), 16))
    rad = 3.0 * np.sqrt(rng.uniform(0, 1, (len(P), 16)))
    qx = (P[:, 0:1] + rad * np.cos(ang)).ravel()
    qy = (P[:, 1:2] + rad * np.sin(ang)).ravel()
    u, v = src.to_samples(qx, qy)
    ground = Terrain(src.lo, 0.0, 0.0, 1.0, 1.0, "s").height(u, v)
    above = np.repeat(P[:, 2], 16) - ground
    assert above.max() <= high + 1e-6 and above.min() >= low - 1e-6
    assert high - above.max() < 1.0 and above.min() - low < 1.0
    assert source_clearance(tr, src, 3.0) == pytest.approx((low, high))  # the best bound
    exact = source_clearance(tr, src, 0.0)
    assert exact[0] - low < 1.0 and high - exact[1] < 1.0


def test_the_small_reach_bound_holds_along_random_flights_over_a_real_raster() -> None:
    """The bound of the ground within reach takes the steepest slope over each piece's own
    neighbourhood in a cell (not the whole cell's): over random short flights across
    Luxembourg, at reaches of 1-30 m, every ground point sampled within the reach of the
    flight stands inside it."""
    from uavplan.scenarios import resolve
    from uavplan.verify.source_terrain import _piece_reach_bound, read_source

    sc = resolve("luxembourg")
    src = read_source(sc.terrain)
    assert src is not None
    rng = np.random.default_rng(11)
    lo, hi = np.asarray(sc.bounds.lower[:2]), np.asarray(sc.bounds.upper[:2])
    for _ in range(12):
        start = rng.uniform(lo + 3000.0, hi - 3000.0)
        xy = start + np.cumsum(rng.normal(0.0, 700.0, (4, 2)), axis=0)
        xy = np.clip(xy, lo + 100.0, hi - 100.0)
        z = np.array([sc.terrain.height(*p) for p in xy]) + rng.uniform(20.0, 200.0, 4)
        tr = Trajectory("a", np.column_stack([xy, z]), np.arange(4.0) * 100, True)
        reach = float(rng.uniform(1.0, 30.0))
        low, high = _piece_reach_bound(tr, src, reach, 150.0)
        if not (np.isfinite(low) and np.isfinite(high)):
            continue
        s = np.linspace(0, 1, 1501)
        P = np.concatenate([tr.points[k] + s[:, None] * (tr.points[k + 1] - tr.points[k])
                            for k in range(3)])  # fmt: skip
        ang = rng.uniform(0, 2 * np.pi, (len(P), 12))
        rad = reach * np.sqrt(rng.uniform(0, 1, (len(P), 12)))
        rad[:, 0] = reach  # on the reach's edge too
        u, v = src.to_samples((P[:, 0:1] + rad * np.cos(ang)).ravel(),
                              (P[:, 1:2] + rad * np.sin(ang)).ravel())  # fmt: skip
        z_rep = np.repeat(P[:, 2], 12)
        floor = Terrain(src.hi, 0.0, 0.0, 1.0, 1.0, "s").height(u, v)
        ceiling = Terrain(src.lo, 0.0, 0.0, 1.0, 1.0, "s").height(u, v)
        assert (z_rep - floor).min() >= low - 1e-6
        assert (z_rep - ceiling).max() <= high + 1e-6


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_directional_bound_holds_along_flights_that_hug_cell_edges(seed: int) -> None:
    """Flights running along and across the raster's rows and columns of samples (where a
    line from the flight enters a neighbouring cell after a few metres, the case the
    directional bound and the cuts at the cells are for), at reaches of 1-12 m: every ground
    point sampled within the reach stands inside the bound, with and without targets, and
    targets the bound meets are met."""
    from uavplan.scenarios import resolve
    from uavplan.verify.source_terrain import _piece_reach_bound, read_source

    sc = resolve("luxembourg")
    src = read_source(sc.terrain)
    assert src is not None
    rng = np.random.default_rng(seed)
    lo, hi = np.asarray(sc.bounds.lower[:2]), np.asarray(sc.bounds.upper[:2])
    floor = Terrain(src.hi, 0.0, 0.0, 1.0, 1.0, "s")
    ceiling = Terrain(src.lo, 0.0, 0.0, 1.0, 1.0, "s")
    for _ in range(6):
        start = rng.uniform(lo + 5000.0, hi - 5000.0)
        u, _ = src.to_samples(start[:1], start[1:])
        per_m = float(src.to_samples(start[:1] + 1.0, start[1:])[0][0] - u[0])  # du / dx
        # to within a few metres of a column of samples, then along it or across it
        u_edge = np.round(u) + rng.uniform(-0.006, 0.006)
        x_edge = start[0] + (u_edge[0] - u[0]) / per_m
        along = rng.random() < 0.5
        d = np.array([0.0, 1.0]) if along else np.array([1.0, 0.0])
        xy = np.array([[x_edge, start[1]]]) + np.linspace(0.0, 1200.0, 4)[:, None] * d
        z = np.array([sc.terrain.height(*p) for p in xy]) + rng.uniform(40.0, 120.0, 4)
        tr = Trajectory("a", np.column_stack([xy, z]), np.arange(4.0) * 100, True)
        reach = float(rng.uniform(1.0, 12.0))
        low, high = _piece_reach_bound(tr, src, reach, 150.0)
        s = np.linspace(0, 1, 2001)
        P = np.concatenate([tr.points[k] + s[:, None] * (tr.points[k + 1] - tr.points[k])
                            for k in range(3)])  # fmt: skip
        ang = rng.uniform(0, 2 * np.pi, (len(P), 12))
        rad = reach * np.sqrt(rng.uniform(0, 1, (len(P), 12)))
        rad[:, :4] = reach  # on the reach's edge
        qu, qv = src.to_samples((P[:, 0:1] + rad * np.cos(ang)).ravel(),
                                (P[:, 1:2] + rad * np.sin(ang)).ravel())  # fmt: skip
        z_rep = np.repeat(P[:, 2], 12)
        true_low = float((z_rep - floor.height(qu, qv)).min())
        true_high = float((z_rep - ceiling.height(qu, qv)).max())
        assert np.isfinite(low) and np.isfinite(high)
        assert true_low >= low - 1e-6 and true_high <= high + 1e-6
        # toward targets just inside the sampled truth: still sound
        rl, rh = _piece_reach_bound(tr, src, reach, 150.0, (true_low - 0.01, true_high + 0.01))
        assert rl <= true_low + 1e-6 and rh >= true_high - 1e-6
        # toward targets the bound everywhere meets: met (the cheaper bound first, the
        # directional one and the cuts where it misses), and still sound
        rl, rh = _piece_reach_bound(tr, src, reach, 150.0, (low, high))
        assert low - 1e-9 <= rl <= true_low + 1e-6 and true_high - 1e-6 <= rh <= high + 1e-9
