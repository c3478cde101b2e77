"""Building the :class:`~uavplan.world.Scenario` from a validated spec: terrain, default bounds,
obstacles, tasks (generated for a ``fleet``), with every problem found.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np

from uavplan.io.scenario_file.errors import NO_VALUE, Problems, ScenarioFileError
from uavplan.io.scenario_file.schema import (
    MAX_CELL,
    MAX_COORD,
    MAX_EXTENT,
    MAX_FILE_BYTES,
    MAX_PATH_POINTS,
    MIN_CELL,
    AltitudeSpec,
    FleetSpec,
    PlanningSpec,
    ScenarioSpec,
    dump_spec,
)
from uavplan.world import (
    UAV,
    AltitudeBand,
    Bounds,
    Circle,
    Cylinder,
    DangerArea,
    MovingObstacle,
    Polygon,
    Scenario,
    Task,
    Terrain,
    UncertainArea,
)
from uavplan.world.execution import ExecutionModel
from uavplan.world.fleet_tasks import fleet_layout, layer_record
from uavplan.world.geo import GeoOrigin
from uavplan.world.raster import place_raster, read_raster
from uavplan.world.srtm import terrain_from_srtm
from uavplan.world.terrain import TerrainError, not_a_regular_file

#: Headroom above the highest terrain for the default z bound when there is no altitude band, m.
DEFAULT_Z_HEADROOM = 500.0


@cache
def builtin_terrain(name: str) -> Terrain:
    """Built-in terrains are immutable (read-only heights), so they are read once per process."""
    return Terrain.builtin(name)


def _resolve(name: str, base_dir: Path) -> Path:
    """A file a scenario names: ``~`` expanded, relative to the scenario file's folder."""
    path = Path(name).expanduser()
    return Path(os.path.abspath(path if path.is_absolute() else base_dir / path))


def _load_srtm(spec: ScenarioSpec, problems: Problems, base_dir: Path) -> Terrain | None:
    ts = spec.terrain
    assert ts is not None and ts.srtm is not None
    if spec.origin is None:
        problems.add(("terrain", "srtm"), "SRTM tiles need the scenario's origin (lat, lon, alt)")
        return None
    if spec.bounds is None:
        problems.add(("terrain", "srtm"), "SRTM tiles need bounds: the map's extent in metres")
        return None
    paths = []
    for k, name in enumerate(ts.srtm):
        path = _resolve(name, base_dir)
        why = not_a_regular_file(path)
        if why is not None:
            problems.add(("terrain", "srtm", k), f"SRTM tile {why}: {path}")
            return None
        paths.append(path)
    lo, hi = spec.bounds.lower, spec.bounds.upper
    try:
        terrain, _ = terrain_from_srtm(
            paths, GeoOrigin(**spec.origin.model_dump()), (lo[0], hi[0], lo[1], hi[1]),
            ts.cell_size,
        )  # fmt: skip
    except TerrainError as exc:
        problems.add(("terrain", "srtm"), str(exc))
        return None
    except (OSError, ValueError) as exc:
        problems.add(("terrain", "srtm"), f"cannot read the SRTM tiles: {exc}")
        return None
    return terrain


def _no_fly_polygons(spec: ScenarioSpec, problems: Problems, base_dir: Path) -> list[Polygon]:
    """The ``no_fly`` GeoJSON files' polygons in the local frame (through the origin)."""
    if not spec.no_fly:
        return []
    if spec.origin is None:
        problems.add(("no_fly",), "GeoJSON no-fly zones need the scenario's origin (lat, lon)")
        return []
    geo = GeoOrigin(**spec.origin.model_dump())
    out: list[Polygon] = []
    for k, name in enumerate(spec.no_fly):
        path = _resolve(name, base_dir)
        why = not_a_regular_file(path)
        if why is not None:
            problems.add(("no_fly", k), f"GeoJSON file {why}: {path}")
            continue
        if path.stat().st_size > MAX_FILE_BYTES:
            problems.add(("no_fly", k), f"GeoJSON file {path}: {path.stat().st_size:,} bytes; "
                         f"at most {MAX_FILE_BYTES:,}")  # fmt: skip
            continue
        try:
            doc = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError, json.JSONDecodeError, RecursionError) as exc:
            what = "nested too deeply" if isinstance(exc, RecursionError) else str(exc)
            problems.add(("no_fly", k), f"cannot read GeoJSON {path}: {what}")
            continue
        features = None
        if isinstance(doc, dict):
            features = [doc] if doc.get("type") == "Feature" else doc.get("features")
        if not isinstance(features, list):
            problems.add(("no_fly", k), f"{path}: not a GeoJSON FeatureCollection or Feature")
            continue
        for j, f in enumerate(features):
            g = f.get("geometry") if isinstance(f, dict) else None
            kind = g.get("type") if isinstance(g, dict) else None
            if kind not in ("Polygon", "MultiPolygon"):
                problems.add(("no_fly", k), f"{path}: features[{j}] is {kind!r}, not a Polygon "
                             "or MultiPolygon")  # fmt: skip
                continue
            assert isinstance(g, dict)
            polys = [g["coordinates"]] if kind == "Polygon" else g["coordinates"]
            for rings in polys:
                try:
                    ring = np.asarray(rings[0], dtype=np.float64)[:, :2]  # [lon, lat]
                    if len(ring) > 1 and (ring[0] == ring[-1]).all():
                        ring = ring[:-1]
                    local = geo.to_local(
                        np.column_stack([ring[:, 1], ring[:, 0], np.zeros(len(ring))])
                    )
                    out.append(Polygon(tuple((float(x), float(y)) for x, y, _ in local)))
                except (ValueError, TypeError, IndexError, KeyError) as exc:
                    problems.add(("no_fly", k), f"{path}: features[{j}]: {exc}")
    return out


def _load_terrain(
    spec: ScenarioSpec, problems: Problems, base_dir: Path
) -> tuple[Terrain | None, GeoOrigin | None]:
    """The scenario's terrain and, for a georeferenced raster placed by itself, the origin it
    gives the scenario. A raster (any file but ``.npy``/``.npz``) is read through GDAL and
    placed by :func:`uavplan.world.raster.place_raster`: through the scenario's origin and over
    its bounds where it gives them."""
    ts = spec.terrain
    assert ts is not None
    if ts.builtin is not None:
        try:
            return builtin_terrain(ts.builtin), None
        except Exception as exc:
            problems.add(("terrain", "builtin"), f"cannot load the built-in terrain: {exc}")
            return None, None
    assert ts.file is not None
    resolved = _resolve(ts.file, base_dir)
    why = not_a_regular_file(resolved)
    if why is not None:
        problems.add(("terrain", "file"), f"DEM file {why}: {resolved}")
        return None, None
    grid_origin = (float(ts.origin[0]), float(ts.origin[1]))
    try:
        if resolved.suffix.lower() in (".npy", ".npz"):
            terrain = Terrain.from_file(
                resolved, cell_size=ts.cell_size, origin=grid_origin, key=ts.key
            )
            return terrain, None
        src = read_raster(resolved, ts.band)
        origin = GeoOrigin(**spec.origin.model_dump()) if spec.origin is not None else None
        box = None
        if spec.bounds is not None:
            lo, hi = spec.bounds.lower, spec.bounds.upper
            box = (lo[0], hi[0], lo[1], hi[1])
        terrain, dem_origin = place_raster(
            src, origin=origin, bounds=box, cell_size=ts.cell_size, grid_origin=grid_origin
        )
    except TerrainError as exc:
        problems.add(("terrain", "file"), str(exc))
        return None, None
    except Exception as exc:  # an EPSG code pyproj does not know, say
        problems.add(("terrain", "file"), f"cannot read or place the DEM {resolved}: {exc}")
        return None, None
    frame = terrain.georef.get("raster", {}).get("frame")
    if frame == "reprojected" and "origin" in ts.model_fields_set and any(ts.origin):
        problems.add(
            ("terrain", "origin"),
            f"places a grid that has no georeference; {src.name} has one and is placed through "
            "the scenario's origin (lat, lon): drop terrain.origin",
        )
        return None, None
    return terrain, dem_origin


def _terrain_range(terrain: Terrain) -> str | None:
    """Why a loaded terrain's grid is beyond the format's ranges (an .npz's own ``dx`` or
    ``x0``, a GeoTIFF's pixel scale): its cells, its corner, its extent."""
    xmin, xmax, ymin, ymax = terrain.extent
    name = terrain.name
    if not (MIN_CELL <= terrain.dx <= MAX_CELL and MIN_CELL <= terrain.dy <= MAX_CELL):
        return (f"{name}: cells of {terrain.dx:g} x {terrain.dy:g} m; a DEM cell is from "
                f"{MIN_CELL:g} m to {MAX_CELL:g} m")  # fmt: skip
    if max(abs(xmin), abs(xmax), abs(ymin), abs(ymax)) > MAX_COORD:
        return f"{name}: its grid reaches beyond {MAX_COORD:g} m from the origin (x0, y0)"
    if max(xmax - xmin, ymax - ymin) > MAX_EXTENT:
        return (f"{name}: {xmax - xmin:,.0f} x {ymax - ymin:,.0f} m, beyond the "
                f"{MAX_EXTENT / 1000:,.0f} km this tool plans over")  # fmt: skip
    return None


def _default_z(terrain: Terrain, altitude: AltitudeSpec | None) -> tuple[float, float]:
    hmin = float(np.min(terrain.ceiling_heights))
    hmax = float(np.max(terrain.heights))
    if altitude is None:
        top = hmax + DEFAULT_Z_HEADROOM
    elif altitude.reference == "ground":
        top = hmax + altitude.max
    else:
        top = altitude.max
    return float(math.floor(hmin)), float(math.ceil(top))


def _dim_reason(spec: ScenarioSpec, dim: int) -> str:
    if spec.terrain is not None:
        return "3-D (it has a terrain)"
    return f"{dim}-D (bounds have {dim} values)"


def _execution(spec: ScenarioSpec) -> ExecutionModel | None:
    if spec.execution is None:
        return None
    values = spec.execution.model_dump(exclude={"source"})
    said = spec.execution.source or "the scenario's execution block"
    return ExecutionModel(**values, source=said)


def build_scenario(spec: ScenarioSpec, problems: Problems, base_dir: Path) -> Scenario:
    terrain: Terrain | None = None
    terrain_failed = False
    dem_origin: GeoOrigin | None = None
    if spec.terrain is not None:
        if spec.terrain.srtm is not None:
            terrain = _load_srtm(spec, problems, base_dir)
        else:
            terrain, dem_origin = _load_terrain(spec, problems, base_dir)
        terrain_failed = terrain is None
        if terrain is not None and (why := _terrain_range(terrain)) is not None:
            problems.add(("terrain",), why, NO_VALUE)
            terrain, terrain_failed = None, True

    # ---- dimension
    dim: int | None
    if spec.terrain is not None:
        dim = 3
    elif spec.bounds is not None:
        dim = len(spec.bounds.lower)
    else:
        problems.add(
            ("bounds",), "required when there is no terrain (lower and upper corners)", NO_VALUE
        )
        dim = None

    def ground(x: float, y: float) -> float:
        return float(terrain.height(x, y)) if terrain is not None else 0.0

    # ---- altitude band
    altitude: AltitudeBand | None = None
    if spec.altitude is not None:
        if dim == 2:
            problems.add(
                ("altitude",),
                "an altitude band needs a 3-D scenario (a terrain or [x, y, z] bounds)",
            )
        a = spec.altitude
        try:
            altitude = AltitudeBand(a.min, a.max, a.reference)
        except ValueError as exc:
            problems.add(("altitude",), str(exc))

    # ---- bounds
    bounds: Bounds | None = None
    if spec.bounds is not None:
        lo, hi = list(spec.bounds.lower), list(spec.bounds.upper)
        if len(lo) != len(hi):
            problems.add(
                ("bounds",),
                f"lower has {len(lo)} values and upper {len(hi)}; give both as [x, y] or both "
                "as [x, y, z]",
            )
        else:
            bad = [f"{'xyz'[k]}: {lo[k]:g} >= {hi[k]:g}" for k in range(len(lo)) if lo[k] >= hi[k]]
            wide = [f"{'xyz'[k]}: {hi[k] - lo[k]:,.0f} m" for k in range(len(lo))
                    if hi[k] - lo[k] > MAX_EXTENT]  # fmt: skip
            if bad:
                problems.add(
                    ("bounds",), f"lower must be below upper on every axis ({'; '.join(bad)})"
                )
            elif wide:
                problems.add(
                    ("bounds",),
                    f"extent beyond the {MAX_EXTENT / 1000:,.0f} km this tool plans over "
                    f"({'; '.join(wide)}): split the area or check the units (metres)",
                )
            elif len(lo) == 2 and spec.terrain is not None:
                if terrain is not None:
                    zlo, zhi = _default_z(terrain, spec.altitude)
                    try:
                        bounds = Bounds((*lo, zlo), (*hi, zhi))
                    except ValueError as exc:
                        problems.add(("bounds",), f"default z range [{zlo:g}, {zhi:g}]: {exc}")
            else:
                try:
                    bounds = Bounds(tuple(lo), tuple(hi))
                except ValueError as exc:
                    problems.add(("bounds",), str(exc))
    elif terrain is not None:
        xmin, xmax, ymin, ymax = (float(v) for v in terrain.extent)
        zlo, zhi = _default_z(terrain, spec.altitude)
        try:
            bounds = Bounds((xmin, ymin, zlo), (xmax, ymax, zhi))
        except ValueError as exc:
            problems.add(
                ("altitude",) if spec.altitude is not None else ("terrain",),
                f"the default bounds z range [{zlo:g}, {zhi:g}] is empty ({exc}); give bounds",
            )

    # ---- UAV
    uav: UAV | None = None
    try:
        uav = UAV(**spec.uav.model_dump())
    except ValueError as exc:
        problems.add(("uav",), str(exc))

    # ---- static obstacles
    cylinders: list[Cylinder] = []
    if spec.cylinders and dim == 2:
        problems.add(
            ("cylinders",),
            "a 2-D scenario has no cylinders (use circles, or make it 3-D with a terrain or "
            "[x, y, z] bounds)",
            NO_VALUE,
        )
    else:
        for i, c in enumerate(spec.cylinders):
            z_max = c.z_max
            if c.height is not None:
                if terrain_failed:
                    continue
                z_max = ground(c.center[0], c.center[1]) + c.height
            try:
                cylinders.append(
                    Cylinder(
                        (c.center[0], c.center[1]),
                        c.radius,
                        -np.inf if c.z_min is None else c.z_min,
                        np.inf if z_max is None else z_max,
                        c.margin,
                    )
                )
            except ValueError as exc:
                problems.add(("cylinders", i), str(exc), NO_VALUE)

    circles: list[Circle] = []
    for i, ci in enumerate(spec.circles):
        try:
            circles.append(Circle((ci.center[0], ci.center[1]), ci.radius, ci.margin))
        except ValueError as exc:
            problems.add(("circles", i), str(exc), NO_VALUE)

    polygons: list[Polygon] = []
    for i, pg in enumerate(spec.polygons):
        try:
            polygons.append(Polygon(tuple((v[0], v[1]) for v in pg.vertices), pg.margin))
        except ValueError as exc:
            problems.add(("polygons", i, "vertices"), str(exc))
    polygons += _no_fly_polygons(spec, problems, base_dir)

    dangers: list[DangerArea] = []
    for i, d in enumerate(spec.danger_areas):
        try:
            dangers.append(DangerArea((d.center[0], d.center[1]), d.radius))
        except ValueError as exc:
            problems.add(("danger_areas", i), str(exc), NO_VALUE)

    uncertain: list[UncertainArea] = []
    for i, u in enumerate(spec.uncertain_areas):
        try:
            uncertain.append(UncertainArea(u.x, u.y, u.width, u.height, u.revealed))
        except ValueError as exc:
            problems.add(("uncertain_areas", i), str(exc), NO_VALUE)

    moving: list[MovingObstacle] = []
    for i, m in enumerate(spec.moving_obstacles):
        ok = True
        for k, pos in enumerate(m.positions):
            if dim is not None and len(pos) != dim:
                problems.add(
                    ("moving_obstacles", i, "positions", k),
                    f"has {len(pos)} coordinates but the scenario is {_dim_reason(spec, dim)}",
                )
                ok = False
        if len(m.positions) != len(m.times):
            problems.add(
                ("moving_obstacles", i),
                f"{len(m.times)} times but {len(m.positions)} positions (one position per time)",
                NO_VALUE,
            )
            ok = False
        if not ok:
            continue
        try:
            moving.append(MovingObstacle(m.radius, np.asarray(m.times), np.asarray(m.positions)))
        except ValueError as exc:
            problems.add(("moving_obstacles", i), str(exc), NO_VALUE)

    # ---- tasks
    # the file's origin, else the one a georeferenced DEM places the frame at
    geo = dem_origin if spec.origin is None else GeoOrigin(**spec.origin.model_dump())
    tasks: list[Task] = []
    checks: list[tuple[int, str, tuple[float, ...]]] = []  # (spec index, which, point)
    seen: dict[str, int] = {}
    for i, t in enumerate(spec.tasks or []):
        tid = t.id if t.id is not None else f"uav{problems.orig('tasks', i)}"
        if tid in seen:
            problems.add(
                ("tasks", i, "id"),
                f"duplicate task id (also tasks[{problems.orig('tasks', seen[tid])}])",
                tid,
            )
        seen.setdefault(tid, i)
        points: dict[str, tuple[float, ...]] = {}
        takeoff_xy: tuple[float, float] | None = None
        for which in ("start", "goal"):
            v = [float(c) for c in getattr(t, which)]
            above = spec.task_z == "ground"  # the z given is a height above the ground here
            if t.frame == "wgs84":
                if geo is None:
                    problems.add(
                        ("tasks", i, which),
                        "frame: wgs84 needs the scenario's origin (or a "
                        "georeferenced terrain that places it)",
                    )
                    continue
                if not (-90 < v[0] < 90 and -180 <= v[1] <= 180):
                    problems.add(("tasks", i, which), "is not [lat, lon(, alt)] in degrees", v)
                    continue
                x, y, _ = geo.to_local([[v[0], v[1], geo.alt]])[0]
                ref = t.height or ("ground" if above else "amsl")
                if which == "start":
                    takeoff_xy = (float(x), float(y))
                z = [] if len(v) < 3 else [v[2] - geo.alt if ref == "amsl" else v[2]]
                v = [float(x), float(y), *z]
                above = ref != "amsl"
                under = takeoff_xy if ref == "takeoff" else None
            if dim is not None and len(v) != dim:
                problems.add(
                    ("tasks", i, which),
                    f"has {len(v)} coordinates but the scenario is {_dim_reason(spec, dim)}",
                )
                continue
            if above and len(v) == 3:
                if terrain_failed or (t.frame == "wgs84" and ref == "takeoff" and under is None):
                    continue
                at = under if t.frame == "wgs84" and under is not None else (v[0], v[1])
                v[2] += ground(*at)
            points[which] = tuple(v)
            checks.append((i, which, tuple(v)))
        if len(points) != 2:
            continue
        try:
            tasks.append(Task(tid, points["start"], points["goal"], t.start_time))
        except ValueError as exc:
            problems.add(("tasks", i), str(exc), NO_VALUE)

    # ---- the scenario (with whatever was valid), then where the tasks start and end
    if not tasks and checks:  # no valid task, but single points to check: scene for checks only
        p0 = checks[0][2]
        tasks.append(Task("check", p0, p0))
    if spec.fleet is not None and bounds is not None:  # stands in until the fleet is generated
        tasks.append(Task("fleet", bounds.lower, bounds.lower))
    if bounds is None or uav is None or not tasks or dim is None or terrain_failed:
        problems.raise_if_any()
        raise ScenarioFileError([f"{problems.source}: invalid scenario"])  # pragma: no cover
    try:
        scenario = Scenario(
            name=spec.name,
            bounds=bounds,
            tasks=tuple(tasks),
            terrain=terrain,
            circles=tuple(circles),
            polygons=tuple(polygons),
            cylinders=tuple(cylinders),
            danger_areas=tuple(dangers),
            uncertain_areas=tuple(uncertain),
            moving_obstacles=tuple(moving),
            altitude=altitude,
            uav=uav,
            cost=spec.planning.cost or ("length2d" if dim == 2 else "ppswarm"),
            n_waypoints=spec.planning.n_waypoints,
            description=spec.description,
            origin=GeoOrigin(**spec.origin.model_dump()) if spec.origin is not None else dem_origin,
            execution=_execution(spec),
            metadata={
                "source": problems.source,
                "base_dir": str(base_dir),
                "spec": dump_spec(spec),
            },
        )
    except ValueError as exc:
        problems.add((), str(exc))
        problems.raise_if_any()
        raise  # pragma: no cover
    for i, which, point in checks:
        wgs84 = spec.tasks is not None and spec.tasks[i].frame == "wgs84"
        local = f" (in the local frame: {[round(c, 2) for c in point]} m)" if wgs84 else ""
        for reason in scenario.point_problems(np.asarray(point)):
            problems.add(("tasks", i, which), reason + local)
    problems.raise_if_any()
    if spec.fleet is not None:
        scenario = _with_generated_fleet(scenario, spec.fleet, problems)
    _check_planning(spec.planning, scenario, problems)
    problems.raise_if_any()
    return scenario


def _check_planning(ps: PlanningSpec, scenario: Scenario, problems: Problems) -> None:
    """The ``planning`` block against the scenario and the planner registry: the cost preset
    for the scenario's dimension, the population's size, and the planner with its options as
    ``uavplan plan`` would build it (the planners are imported only when the block names one
    or gives options)."""
    from uavplan.problems import preset_problem

    for where, cost in ((("planning", "cost"), ps.cost),
                        (("planning", "options", "cost"), ps.options.get("cost"))):  # fmt: skip
        if isinstance(cost, str):
            reason = preset_problem(cost, scenario.dim)
            if reason is not None:
                problems.add(where, reason)
    if ps.pop_size is not None and ps.pop_size * (ps.n_waypoints + 2) > MAX_PATH_POINTS:
        problems.add(("planning", "pop_size"),
                     f"a population of {ps.pop_size:,} paths of {ps.n_waypoints + 2} points "
                     f"exceeds the {MAX_PATH_POINTS:,} path points a run may hold")  # fmt: skip
    if ps.planner is None and not ps.options:
        return
    from uavplan.optimizers.base import OptimizerError
    from uavplan.planners import PlannerError, get_planner
    from uavplan.strategy import strategy_for

    name = ps.planner if ps.planner is not None else strategy_for(scenario).planner
    options = dict(ps.options)
    if ps.pop_size is not None:
        options.setdefault("pop_size", ps.pop_size)

    def why(**given: Any) -> str | None:
        try:
            get_planner(name, **given)
        except (PlannerError, OptimizerError, TypeError, ValueError) as exc:
            return " ".join(str(exc).split())
        return None

    text = why(**options)
    if text is None:
        return
    if ps.planner is not None and text.startswith("unknown planner"):
        problems.add(("planning", "planner"), text)
        return
    alone = {k: why(**{k: v}) for k, v in options.items()}  # each option's own problem
    for k, reason in alone.items():
        if reason is not None:
            where = ("planning", "pop_size") if k not in ps.options else ("planning", "options", k)
            problems.add(where, reason)
    if all(r is None for r in alone.values()):
        problems.add(("planning", "options"), text)


def _with_generated_fleet(scenario: Scenario, fleet: FleetSpec, problems: Problems) -> Scenario:
    """The scenario with the tasks its ``fleet`` block generates (every other check passed)."""
    try:
        tasks, layers = fleet_layout(
            scenario,
            fleet.count,
            seed=fleet.seed,
            pattern=fleet.pattern,
            min_spacing=fleet.min_spacing,
        )
    except ValueError as exc:
        problems.add(("fleet",), str(exc))
        problems.raise_if_any()
        raise  # pragma: no cover
    scenario.metadata["fleet"] = {**fleet.model_dump(), **layer_record(layers)}
    return dataclasses.replace(scenario, tasks=tasks)
