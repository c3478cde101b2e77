"""Scenario files: schema, built-ins, round trips, problem lines, atomic writes."""

from __future__ import annotations

import json
import math
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from uavplan.io.scenario_file import (
    ScenarioFileError,
    ScenarioSpec,
    load_scenario,
    save_scenario,
    scenario_from_dict,
    scenario_to_dict,
    schema,
    spec_from_scenario,
)
from uavplan.scenarios import builtin_names, builtin_path, list_builtin, load_builtin, resolve
from uavplan.world import (
    UAV,
    AltitudeBand,
    Bounds,
    Circle,
    Cylinder,
    MovingObstacle,
    Polygon,
    Scenario,
    Task,
    Terrain,
)

BUILTINS = [
    "dense",
    "hrmaga-jacksboro",
    "hrmaga-popup",
    "hrmaga-spso",
    "hrmaga-topobathy",
    "hrmaga-virtual",
    "jacksboro",
    "luxembourg",
    "open",
    "ppswarm1",
    "ppswarm1-traffic",
    "ppswarm2",
    "ppswarm3",
    "ppswarm4",
    "quadrotors",
    "rscdwoa-mixed",
    "rscdwoa-static",
    "simple2d",
    "spso",
    "topobathy",
]


# ---------------------------------------------------------------------------- helpers
def assert_same(a: Scenario, b: Scenario) -> None:
    assert a.name == b.name
    assert a.description == b.description
    assert a.bounds == b.bounds
    assert a.tasks == b.tasks
    assert a.cylinders == b.cylinders
    assert a.circles == b.circles
    assert a.polygons == b.polygons
    assert a.danger_areas == b.danger_areas
    assert a.uncertain_areas == b.uncertain_areas
    assert a.altitude == b.altitude
    assert a.uav == b.uav
    assert (a.cost, a.n_waypoints) == (b.cost, b.n_waypoints)
    assert len(a.moving_obstacles) == len(b.moving_obstacles)
    for m, n in zip(a.moving_obstacles, b.moving_obstacles, strict=True):
        assert m.radius == n.radius
        np.testing.assert_array_equal(m.times, n.times)
        np.testing.assert_array_equal(m.positions, n.positions)
    if a.terrain is None:
        assert b.terrain is None
    else:
        assert b.terrain is not None
        assert (a.terrain.x0, a.terrain.y0, a.terrain.dx, a.terrain.dy) == (
            b.terrain.x0,
            b.terrain.y0,
            b.terrain.dx,
            b.terrain.dy,
        )
        np.testing.assert_array_equal(a.terrain.heights, b.terrain.heights)


def flat3d(**over: Any) -> dict[str, Any]:
    data: dict[str, Any] = {
        "name": "flat",
        "bounds": {"lower": [0, 0, 0], "upper": [100, 100, 50]},
        "tasks": [{"start": [5, 5, 10], "goal": [95, 95, 10]}],
    }
    data.update(over)
    return data


def on_spso(**over: Any) -> dict[str, Any]:
    data: dict[str, Any] = {
        "name": "s",
        "terrain": {"builtin": "spso"},
        "bounds": {"lower": [1, 1], "upper": [1045, 879]},
        "cylinders": [{"center": [400, 500], "radius": 80, "margin": 1}],
        "altitude": {"min": 100, "max": 200, "reference": "ground"},
        "task_z": "ground",
        "tasks": [{"start": [200, 100, 150], "goal": [800, 800, 150]}],
    }
    data.update(over)
    return data


def write(path: Path, data: Any) -> Path:
    if isinstance(data, bytes):
        path.write_bytes(data)
    elif isinstance(data, str):
        path.write_text(data)
    elif path.suffix == ".json":
        path.write_text(json.dumps(data))
    else:
        path.write_text(yaml.safe_dump(data))
    return path


def problems_of(path: Path) -> list[str]:
    with pytest.raises(ScenarioFileError) as info:
        load_scenario(path)
    problems = info.value.problems
    assert problems
    assert all("\n" not in line for line in problems)
    assert str(info.value) == "\n".join(problems)
    return problems


def has_line(problems: list[str], *parts: str) -> bool:
    return any(all(p in line for p in parts) for line in problems)


# ---------------------------------------------------------------------------- built-ins
def test_builtin_listing() -> None:
    assert builtin_names() == BUILTINS
    listing = dict(list_builtin())
    assert sorted(listing) == BUILTINS
    assert all(listing.values())
    assert "Applied Soft Computing" in listing["spso"]


@pytest.mark.parametrize("name", BUILTINS)
def test_builtin_loads(name: str) -> None:
    s = load_builtin(name)
    assert s.name == name
    assert s.metadata["builtin"] == name
    assert isinstance(s.metadata["spec"], dict)
    assert builtin_path(name).name == f"{name}.yaml"
    assert yaml.safe_load(builtin_path(name).read_text())["name"] == name
    for t in s.tasks:
        assert s.point_problems(np.asarray(t.start)) == []
        assert s.point_problems(np.asarray(t.goal)) == []
    assert resolve(name).name == name


def test_spso_is_the_readme_benchmark() -> None:
    s = load_builtin("spso")
    assert s.dim == 3 and s.terrain is not None and s.terrain.name == "spso"
    threats = [
        (400, 500, 80),
        (600, 200, 70),
        (500, 350, 80),
        (350, 200, 70),
        (700, 550, 70),
        (650, 750, 80),
    ]
    assert [(c.center[0], c.center[1], c.radius) for c in s.cylinders] == threats
    assert all(c.infinite and c.margin == 1 for c in s.cylinders)
    assert s.altitude == AltitudeBand(100, 200, "ground")
    t = s.tasks[0]
    assert t.start[:2] == (200, 100) and t.goal[:2] == (800, 800)
    assert t.start[2] == pytest.approx(150 + float(s.terrain.height(200, 100)))
    assert t.goal[2] == pytest.approx(150 + float(s.terrain.height(800, 800)))
    hmin, hmax = float(s.terrain.heights.min()), float(s.terrain.heights.max())
    assert s.bounds.lower == (1, 1, math.floor(hmin))
    assert s.bounds.upper == (1045, 879, math.ceil(hmax + 200))
    assert (s.cost, s.n_waypoints) == ("spso", 10)
    assert s.uav.speed == 20 and s.uav.size == 1
    assert "Phung" in s.description


def test_simple2d_straight_line_blocked() -> None:
    s = load_builtin("simple2d")
    assert s.dim == 2 and s.terrain is None
    assert s.bounds == Bounds((0, 0), (100, 100))
    assert (s.cost, s.n_waypoints) == ("length2d", 20)
    assert s.tasks[0].start == (5, 5) and s.tasks[0].goal == (95, 95)
    line = np.linspace(s.tasks[0].start, s.tasks[0].goal, 1001)
    assert any(s.point_problems(p) for p in line)
    # non-convex polygon
    v = s.polygons[0].array
    e = np.roll(v, -1, axis=0) - v  # edges
    f = np.roll(e, -1, axis=0)
    cross = e[:, 0] * f[:, 1] - e[:, 1] * f[:, 0]
    assert min(cross) < 0 < max(cross)


def test_jacksboro_cylinder_heights_above_ground() -> None:
    s = load_builtin("jacksboro")
    spec = s.metadata["spec"]
    assert s.terrain is not None
    assert 4 <= len(s.cylinders) <= 6
    for c, cs in zip(s.cylinders, spec["cylinders"], strict=True):
        ground = float(s.terrain.height(*c.center))
        assert c.z_max == pytest.approx(ground + cs["height"])
        assert not c.infinite
    assert s.altitude == AltitudeBand(50, 300, "ground")
    assert len(s.danger_areas) == 1 and len(s.uncertain_areas) == 1
    assert s.cost == "ppswarm" and s.n_waypoints == 10


def test_topobathy_sea_to_mountains() -> None:
    s = load_builtin("topobathy")
    assert s.terrain is not None and s.altitude is not None
    t = s.tasks[0]
    assert float(s.terrain.height(t.start[0], t.start[1])) == 0.0
    assert float(s.terrain.height(t.goal[0], t.goal[1])) > 1000
    assert len(s.cylinders) >= 2


# ---------------------------------------------------------------------------- round trips
@pytest.mark.parametrize("name", BUILTINS)
@pytest.mark.parametrize("suffix", [".yaml", ".yml", ".json"])
def test_builtin_round_trip(tmp_path: Path, name: str, suffix: str) -> None:
    s = load_builtin(name)
    out = save_scenario(s, tmp_path / f"x{suffix}")
    if suffix == ".json":
        json.loads(out.read_text())
    else:
        yaml.safe_load(out.read_text())
    assert_same(s, load_scenario(out))
    # the exported file is the file-level spec, not the expanded scenario (a terrain file is
    # named relative to each file's folder: the same file)
    again, first = scenario_to_dict(load_scenario(out)), scenario_to_dict(s)
    for spec, folder in ((again, out.parent), (first, builtin_path(name).parent)):
        terrain = spec.get("terrain") or {}
        if "file" in terrain:
            terrain["file"] = str((folder / terrain["file"]).resolve())
    assert again == first


def test_full_spec_round_trip_and_terrain_file_rebased(tmp_path: Path) -> None:
    src = tmp_path / "src"
    (src / "dem").mkdir(parents=True)
    heights = np.add.outer(np.arange(30.0), np.arange(40.0))  # (ny, nx), rows south to north
    np.save(src / "dem" / "hill.npy", heights)
    data = {
        "name": "full",
        "description": "every kind",
        "terrain": {"file": "dem/hill.npy", "cell_size": 10, "origin": [100, 200]},
        "cylinders": [
            {"center": [200, 300], "radius": 20},
            {"center": [300, 300], "radius": 20, "z_min": 0, "z_max": 80, "margin": 2},
            {"center": [400, 350], "radius": 15, "height": 50},
        ],
        "circles": [{"center": [250, 420], "radius": 5, "margin": 1}],
        "polygons": [{"vertices": [[350, 400], [380, 400], [380, 430], [365, 415], [350, 430]]}],
        "danger_areas": [{"center": [220, 250], "radius": 10}],
        "uncertain_areas": [{"x": 450, "y": 250, "width": 10, "height": 20, "revealed": False}],
        "moving_obstacles": [
            {"radius": 3, "times": [0, 10], "positions": [[150, 250, 60], [200, 300, 60]]}
        ],
        "altitude": {"min": 10, "max": 100},
        "uav": {"speed": 15, "size": 0.5},
        "task_z": "ground",
        "tasks": [
            {"start": [110, 210, 30], "goal": [480, 480, 30]},
            {"id": "second", "start": [110, 480, 40], "goal": [480, 210, 40], "start_time": 5},
        ],
        "planning": {"n_waypoints": 7},
    }
    path = write(src / "full.yaml", data)
    s = load_scenario(path)
    assert s.terrain is not None and s.terrain.shape == (30, 40)
    assert s.terrain.extent == (100, 490, 200, 490)
    assert [t.id for t in s.tasks] == ["uav0", "second"]
    assert s.tasks[0].start[2] == pytest.approx(30 + float(s.terrain.height(110, 210)))
    assert s.cylinders[2].z_max == pytest.approx(50 + float(s.terrain.height(400, 350)))
    assert s.cylinders[0].infinite and s.cylinders[1].z_max == 80
    assert s.cost == "ppswarm" and s.n_waypoints == 7
    assert s.uav.speed == 15 and s.uav.size == 0.5
    assert s.uav.turn_radius == 0 and s.uav.min_speed == 0  # no kinematic limits by default
    # default bounds: terrain extent; z [min h, max h + band max]
    assert s.bounds.lower == (100, 200, 0) and s.bounds.upper == (490, 490, 68 + 100)
    for suffix in (".yaml", ".json"):
        out_dir = tmp_path / "elsewhere" / "deeper"
        out_dir.mkdir(parents=True, exist_ok=True)
        out = save_scenario(s, out_dir / f"copy{suffix}")
        again = load_scenario(out)
        assert_same(s, again)
        assert again.metadata["spec"]["terrain"]["file"] == "../../src/dem/hill.npy"


def test_programmatic_scenario_round_trip(tmp_path: Path) -> None:
    s = Scenario(
        name="code",
        bounds=Bounds((0, 0, 0), (50, 60, 40)),
        tasks=(Task("a", (1, 1, 5), (49, 59, 5)),),
        cylinders=(Cylinder((25, 30), 4.5, 0, 20),),
        circles=(Circle((10, 40), 3),),
        polygons=(Polygon(((30, 5), (40, 5), (35, 12))),),
        moving_obstacles=(MovingObstacle(1.0, np.array([0.0, 3.0]), np.zeros((2, 3))),),
        altitude=AltitudeBand(1, 30, "absolute"),
        cost="ppswarm",
        n_waypoints=12,
    )
    spec = spec_from_scenario(s)
    assert isinstance(spec, ScenarioSpec)
    out = save_scenario(s, tmp_path / "code.json")
    assert_same(s, load_scenario(out))
    # terrain that is not built-in cannot be embedded
    custom = Scenario(
        name="t",
        bounds=Bounds((0, 0, 0), (2, 2, 5)),
        tasks=(Task("a", (0.5, 0.5, 1), (1.5, 1.5, 1)),),
        terrain=Terrain(np.zeros((3, 3)), name="custom"),
    )
    with pytest.raises(ScenarioFileError, match="not a built-in terrain"):
        spec_from_scenario(custom)
    # a built-in terrain is written by name
    on_map = Scenario(
        name="m",
        bounds=Bounds((1, 1, 0), (1045, 879, 600)),
        tasks=(Task("a", (200, 100, 400), (800, 800, 400)),),
        terrain=Terrain.builtin("spso"),
    )
    assert scenario_to_dict(on_map)["terrain"] == {"builtin": "spso"}
    assert_same(on_map, load_scenario(save_scenario(on_map, tmp_path / "m.yaml")))


UAV_LIMITS = {
    "speed": 20,
    "turn_radius": 20,
    "s1": 15,
    "s2": 10,
    "min_speed": 10,
    "max_speed": 25.5,
    "max_climb_angle": 30,
    "max_descent_angle": 22.5,
}


@pytest.mark.parametrize("suffix", [".yaml", ".json"])
def test_uav_limits_round_trip(tmp_path: Path, suffix: str) -> None:
    s = load_scenario(write(tmp_path / f"u{suffix}", flat3d(uav=UAV_LIMITS)))
    assert s.uav == UAV(
        speed=20, turn_radius=20, min_speed=10, max_speed=25.5, max_climb_angle=30,
        max_descent_angle=22.5,
    )  # fmt: skip
    assert s.uav.v_max == 25.5
    again = load_scenario(save_scenario(s, tmp_path / f"again{suffix}"))
    assert again.uav == s.uav
    assert scenario_to_dict(again)["uav"] == UAV_LIMITS
    # a Scenario built in code: load -> save -> load gives an equal UAV, with or without limits
    for uav in (
        s.uav, UAV(), UAV(speed=12, min_speed=3), UAV(max_climb_angle=90),
        UAV(s2_axes=(50, 50, 20)),
    ):  # fmt: skip
        code = Scenario(
            "code", Bounds((0, 0, 0), (100, 100, 50)), (Task("a", (5, 5, 10), (95, 95, 10)),),
            uav=uav,
        )  # fmt: skip
        spec = spec_from_scenario(code)
        assert scenario_from_dict(spec.model_dump()).uav == uav
        assert load_scenario(save_scenario(code, tmp_path / f"code{suffix}")).uav == uav
    # limits not given are left out of the written file (null means the default)
    written = scenario_to_dict(spec_from_scenario(code))["uav"]
    assert "max_speed" not in written and "max_descent_angle" not in written
    assert scenario_to_dict(load_builtin("rscdwoa-static"))["uav"]["s2_axes"] == [50, 50, 20]
    assert load_builtin("rscdwoa-static").uav.separation_radius == pytest.approx(73.4847, 1e-5)
    with pytest.raises(ValueError, match="s2_axes must be three finite distances"):
        UAV(s2_axes=(50.0, float("nan"), 20.0))


def test_ppswarm_uav_limits() -> None:
    for k in (1, 2, 3, 4):
        u = load_builtin(f"ppswarm{k}").uav
        assert u == UAV(
            speed=20, turn_radius=20, s1=15, s2=10, min_speed=10, max_climb_angle=30,
            max_descent_angle=30, airframe="small-fixed-wing",
        )  # fmt: skip
        assert u.v_max == 20


UAV_CASES: list[tuple[dict[str, Any], str, str]] = [
    ({"speed": 20, "min_speed": 30}, "uav.min_speed = 30",
     "min_speed 30 m/s is above speed 20 m/s (need min_speed <= speed)"),
    ({"min_speed": 25}, "uav.min_speed = 25", "above speed 20 m/s"),  # the default speed
    ({"speed": 20, "max_speed": 15}, "uav.max_speed = 15",
     "max_speed 15 m/s is below speed 20 m/s (need speed <= max_speed)"),
    ({"min_speed": -1}, "uav.min_speed = -1", "greater than or equal to 0"),
    ({"max_speed": 0}, "uav.max_speed = 0", "greater than or equal to 0.01"),
    ({"max_climb_angle": 0}, "uav.max_climb_angle = 0", "greater than 0"),
    ({"max_descent_angle": 95}, "uav.max_descent_angle = 95", "less than or equal to 90"),
    ({"max_climb_angle": True}, "uav.max_climb_angle = true", "not true/false"),
    ({"turn_radius": -5}, "uav.turn_radius = -5", "greater than or equal to 0"),
    ({"min_speed": ".nan"}, "uav.min_speed", "finite number"),
    ({"max_climb": 30}, "uav.max_climb", "did you mean 'max_climb_angle'"),
]  # fmt: skip


@pytest.mark.parametrize(("uav", "where", "reason"), UAV_CASES, ids=[c[1] for c in UAV_CASES])
def test_uav_problem_lines(tmp_path: Path, uav: dict[str, Any], where: str, reason: str) -> None:
    data = flat3d(uav={k: (math.nan if v == ".nan" else v) for k, v in uav.items()})
    path = write(tmp_path / "uav.yaml", data)
    problems = problems_of(path)
    assert has_line(problems, f"{path}: {where}", reason), problems
    assert len(problems) == 1, problems


def test_uav_problems_with_others_still_checked(tmp_path: Path) -> None:
    data = flat3d(
        uav={"speed": 10, "min_speed": 12, "max_speed": 8},
        tasks=[{"start": [500, 5, 10], "goal": [95, 95, 10]}],
    )
    problems = problems_of(write(tmp_path / "both.yaml", data))
    assert has_line(problems, "uav.min_speed = 12", "above speed 10 m/s")
    assert has_line(problems, "uav.max_speed = 8", "below speed 10 m/s")
    assert has_line(problems, "tasks[0].start", "outside the bounds")
    assert len(problems) == 3


def test_dict_and_spec_inputs(tmp_path: Path) -> None:
    d = flat3d()
    s = scenario_from_dict(d, source="mem")
    assert s.dim == 3 and s.terrain is None and s.cost == "ppswarm"
    assert scenario_to_dict(d) == d
    assert scenario_to_dict(ScenarioSpec.model_validate(d)) == d
    out = save_scenario(d, tmp_path / "d.yml")
    assert_same(s, load_scenario(out))
    two = scenario_from_dict(
        {
            "name": "2d",
            "bounds": {"lower": [0, 0], "upper": [1, 1]},
            "tasks": [{"start": [0.1, 0.1], "goal": [0.9, 0.9]}],
        }
    )
    assert two.dim == 2 and two.cost == "length2d" and two.n_waypoints == 10


def test_default_bounds_rules() -> None:
    no_band = scenario_from_dict(
        {
            "name": "x",
            "terrain": {"builtin": "spso"},
            "tasks": [{"start": [200, 100, 400], "goal": [800, 800, 400]}],
        }
    )
    t = no_band.terrain
    assert t is not None
    assert no_band.bounds.lower == (1, 1, math.floor(float(t.heights.min())))
    assert no_band.bounds.upper == (1045, 879, math.ceil(float(t.heights.max()) + 500))
    absolute = scenario_from_dict(
        {
            "name": "x",
            "terrain": {"builtin": "spso"},
            "altitude": {"min": 0, "max": 450, "reference": "absolute"},
            "tasks": [{"start": [200, 100, 400], "goal": [800, 800, 400]}],
        }
    )
    assert absolute.bounds.upper[2] == 450
    full = scenario_from_dict(on_spso(bounds={"lower": [1, 1, 0], "upper": [1045, 879, 600]}))
    assert full.bounds == Bounds((1, 1, 0), (1045, 879, 600))


def test_yaml_for_unknown_suffix(tmp_path: Path) -> None:
    path = write(tmp_path / "scene.txt", yaml.safe_dump(flat3d()))
    assert load_scenario(path).name == "flat"
    # JSON content is YAML too
    assert load_scenario(write(tmp_path / "scene.cfg", json.dumps(flat3d()))).name == "flat"


def test_geotiff_terrain(tmp_path: Path) -> None:
    tifffile = pytest.importorskip("tifffile")
    tifffile.imwrite(tmp_path / "dem.tif", np.full((20, 30), 7.0, dtype=np.float32))
    s = scenario_from_dict(
        {
            "name": "tif",
            "terrain": {"file": "dem.tif", "cell_size": 2},
            "tasks": [{"start": [1, 1, 20], "goal": [50, 30, 20]}],
        },
        base_dir=tmp_path,
    )
    assert s.terrain is not None and s.terrain.shape == (20, 30) and s.terrain.dx == 2
    assert s.bounds.lower == (0, 0, 7) and s.bounds.upper == (58, 38, 507)


def test_schema() -> None:
    sch = schema()
    json.dumps(sch)
    for key in (
        "name",
        "bounds",
        "terrain",
        "cylinders",
        "circles",
        "polygons",
        "danger_areas",
        "uncertain_areas",
        "moving_obstacles",
        "altitude",
        "uav",
        "task_z",
        "tasks",
        "planning",
        "description",
    ):
        assert key in sch["properties"]
    assert sch["required"] == ["name"]  # and one of tasks or fleet:
    assert sch["oneOf"] == [{"required": ["tasks"]}, {"required": ["fleet"]}]
    assert sch["additionalProperties"] is False


# ---------------------------------------------------------------------------- problems
Case = tuple[str, Callable[[Path], Any], list[tuple[str, str]]]

CASES: list[Case] = [
    (
        "outside_bounds.yaml",
        lambda d: on_spso(tasks=[{"start": [5000, 10, 150], "goal": [800, 800, 150]}]),
        [("tasks[0].start = [5000, 10, 150]", "outside the bounds")],
    ),
    (
        "in_obstacle.yaml",
        lambda d: on_spso(tasks=[{"start": [200, 100, 150], "goal": [400, 500, 150]}]),
        [("tasks[0].goal", "inside cylinder 0")],
    ),
    (
        "under_terrain.yaml",
        lambda d: on_spso(
            task_z="absolute",
            altitude=None,
            tasks=[{"start": [200, 100, 10], "goal": [800, 800, 400]}],
        ),
        [("tasks[0].start", "under the terrain")],
    ),
    (
        "band.yaml",
        lambda d: on_spso(tasks=[{"start": [200, 100, 150], "goal": [800, 800, 50]}]),
        [("tasks[0].goal", "outside the band [100, 200]")],
    ),
    (
        "polygon2.yaml",
        lambda d: flat3d(polygons=[{"vertices": [[1, 1], [2, 2]]}]),
        [("polygons[0].vertices", "at least 3 vertices")],
    ),
    (
        "flat_polygon.yaml",
        lambda d: flat3d(polygons=[{"vertices": [[1, 1], [2, 2], [3, 3]]}]),
        [("polygons[0].vertices", "zero area")],
    ),
    (
        "neg_radius.yaml",
        lambda d: flat3d(circles=[{"center": [50, 50], "radius": -4}]),
        [("circles[0].radius = -4", "greater than 0")],
    ),
    (
        "nan.yaml",
        lambda d: (
            "name: n\nbounds: {lower: [0, 0], upper: [10, .nan]}\n"
            "tasks: [{start: [1, 1], goal: [2, 2]}]\n"
        ),
        [("bounds.upper[1] = NaN", "finite number")],
    ),
    (
        "inf.json",
        lambda d: (
            '{"name": "i", "bounds": {"lower": [0, 0], "upper": [10, Infinity]},'
            ' "tasks": [{"start": [1, 1], "goal": [2, 2]}]}'
        ),
        [("bounds.upper[1] = Infinity", "finite number")],
    ),
    (
        "unknown_key.yaml",
        lambda d: flat3d(circles=[{"center": [50, 50], "radius": 4, "colour": "red"}]),
        [("circles[0].colour", "unknown key")],
    ),
    (
        "typo.yaml",
        lambda d: {**flat3d(), "cylinder": []},
        [("cylinder", "did you mean 'cylinders'")],
    ),
    (
        "missing_dem.yaml",
        lambda d: flat3d(terrain={"file": "nope/dem.tif"}, bounds=None),
        [("terrain.file", "DEM file not found")],
    ),
    (
        "bad_dem.yaml",
        lambda d: (
            (d / "broken.tif").write_text("not a tiff")
            and flat3d(terrain={"file": "broken.tif"}, bounds=None)
        ),
        [("terrain.file", "not a raster GDAL can read")],
    ),
    ("garbage.yaml", lambda d: bytes(range(256)) * 3, [("", "not a YAML or JSON file")]),
    ("scalar.yaml", lambda d: "just some words\n", [("", "top level must be a mapping")]),
    ("list.json", lambda d: "[1, 2]", [("", "top level must be a mapping")]),
    ("syntax.yaml", lambda d: "name: [oops\ntasks: 1\n", [("", "not valid YAML")]),
    ("syntax.json", lambda d: '{"name": "x",', [("", "not valid JSON")]),
    ("empty.yaml", lambda d: "", [("", "empty")]),
    ("dup.yaml", lambda d: "name: a\nname: b\n", [("", "duplicate key 'name'")]),
    (
        "dim.yaml",
        lambda d: flat3d(bounds={"lower": [0, 0], "upper": [100, 100]}),
        [("tasks[0].start = [5, 5, 10]", "scenario is 2-D"), ("tasks[0].goal", "scenario is 2-D")],
    ),
    (
        "band_order.yaml",
        lambda d: flat3d(altitude={"min": 30, "max": 20}),
        [("altitude", "min < max")],
    ),
    (
        "missing_name.yaml",
        lambda d: {k: v for k, v in flat3d().items() if k != "name"},
        [("name", "required field missing")],
    ),
    ("no_tasks.yaml", lambda d: flat3d(tasks=[]), [("tasks", "at least one task")]),
    (
        "cyl_2d.yaml",
        lambda d: {
            "name": "c",
            "bounds": {"lower": [0, 0], "upper": [9, 9]},
            "cylinders": [{"center": [5, 5], "radius": 1}],
            "tasks": [{"start": [1, 1], "goal": [8, 8]}],
        },
        [("cylinders", "2-D scenario has no cylinders")],
    ),
    (
        "terrain_both.yaml",
        lambda d: flat3d(terrain={"builtin": "spso", "file": "x.tif"}),
        [("terrain", "exactly one of")],
    ),
    (
        "bool.yaml",
        lambda d: flat3d(planning={"n_waypoints": True}),
        [("planning.n_waypoints = true", "not true/false")],
    ),
]


def _write_case(tmp_path: Path, case: Case) -> Path:
    name, make, _ = case
    data = make(tmp_path)
    if isinstance(data, dict) and data.get("bounds", 0) is None:
        data = {k: v for k, v in data.items() if k != "bounds"}
    return write(tmp_path / name, data)


@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_problem_lines(tmp_path: Path, case: Case) -> None:
    path = _write_case(tmp_path, case)
    problems = problems_of(path)
    for where, reason in case[2]:
        assert has_line(problems, f"{path}: {where}", reason), problems


def test_missing_dem_names_resolved_path(tmp_path: Path) -> None:
    path = write(tmp_path / "m.yaml", {**flat3d(terrain={"file": "nope/dem.tif"})})
    problems = problems_of(path)
    assert has_line(problems, str(tmp_path / "nope" / "dem.tif"))


def test_several_problems_reported_together(tmp_path: Path) -> None:
    data = on_spso(
        circles=[{"center": [1, 1], "radius": -1}, {"center": [5, 5], "radius": 2, "size": 3}],
        polygons=[{"vertices": [[0, 0], [1, 1]]}],
        tasks=[
            {"start": [5000, 10, 150], "goal": [800, 800, 150]},
            {"start": [200, 100, 150], "goal": [400, 500, 150]},
            {"start": [200, 100, float("nan")], "goal": [800, 800, 150]},
        ],
        wrong=1,
    )
    path = write(tmp_path / "many.yaml", data)
    problems = problems_of(path)
    expected = [
        ("circles[0].radius", "greater than 0"),
        ("circles[1].size", "unknown key"),
        ("polygons[0].vertices", "at least 3 vertices"),
        ("tasks[2].start[2]", "finite"),
        ("wrong", "unknown key"),
        # the rest is still checked, and still named by its index in the file
        ("tasks[0].start", "outside the bounds"),
        ("tasks[1].goal", "inside cylinder 0"),
    ]
    for where, reason in expected:
        assert has_line(problems, f"{path}: {where}", reason), problems
    assert len(problems) == len(expected)


def test_not_a_file(tmp_path: Path) -> None:
    assert has_line(problems_of(tmp_path / "absent.yaml"), "absent.yaml", "no such file")
    assert has_line(problems_of(tmp_path), "is a directory")
    with pytest.raises(ScenarioFileError, match="not a built-in scenario"):
        resolve("no-such-scenario")
    with pytest.raises(ScenarioFileError, match="no such built-in"):
        builtin_path("nope")
    assert isinstance(ScenarioFileError(["x"]), ValueError)


# ---------------------------------------------------------------------------- writing
def test_write_failures_leave_the_old_file(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    target = tmp_path / "keep.yaml"
    target.write_text("precious\n")
    with pytest.raises(ScenarioFileError, match="does not exist"):
        save_scenario(load_builtin("spso"), tmp_path / "no" / "dir" / "x.yaml")
    with pytest.raises(ScenarioFileError, match="unknown suffix"):
        save_scenario(load_builtin("spso"), tmp_path / "x.toml")

    def boom(fd: int) -> None:
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "fsync", boom)
    with pytest.raises(ScenarioFileError) as info:
        save_scenario(load_builtin("spso"), target)
    assert info.value.problems == [f"{target}: cannot write: No space left on device"]
    assert target.read_text() == "precious\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["keep.yaml"]
    monkeypatch.undo()

    def bad_replace(src: str, dst: str) -> None:
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(os, "replace", bad_replace)
    with pytest.raises(ScenarioFileError, match="Permission denied"):
        save_scenario(load_builtin("simple2d"), target)
    assert target.read_text() == "precious\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["keep.yaml"]
    monkeypatch.undo()

    os.chmod(target, 0o600)
    save_scenario(load_builtin("simple2d"), target)
    assert load_scenario(target).name == "simple2d"
    assert (target.stat().st_mode & 0o777) == 0o600
    assert sorted(p.name for p in tmp_path.iterdir()) == ["keep.yaml"]


def test_invalid_dict_is_not_written(tmp_path: Path) -> None:
    with pytest.raises(ScenarioFileError, match="required field missing"):
        save_scenario({"name": "x"}, tmp_path / "x.yaml")
    assert not (tmp_path / "x.yaml").exists()


@pytest.mark.slow  # four generations with their reference paths: 30 s
def test_resolve_generates_rgg_family_scenes() -> None:
    from uavplan.scenarios import resolve
    from uavplan.scenarios.generators import rgg_scenario

    s = resolve("rgg-n07-i042")
    t = rgg_scenario(7, 42)
    assert s.name == t.name == "rgg-n07-i042"
    assert s.metadata["reference_length"] == t.metadata["reference_length"]
    assert (
        resolve("rgg-n07-i042-s3").metadata["reference_length"]
        == rgg_scenario(7, 42, 3).metadata["reference_length"]
    )


# ---------------------------------------------------------------------------- fleet
def fleet_on_spso(**over: Any) -> dict[str, Any]:
    data = {k: v for k, v in on_spso().items() if k not in ("tasks", "task_z")}
    data["fleet"] = {"count": 12, "pattern": "crossing", "seed": 0}
    data.update(over)
    return data


def test_fleet_generates_tasks() -> None:
    from uavplan.world.fleet_tasks import fleet_tasks

    s = scenario_from_dict(fleet_on_spso(fleet={"count": 12, "pattern": "random", "seed": 3}))
    assert [t.id for t in s.tasks] == [f"uav{i}" for i in range(12)]
    assert s.tasks == fleet_tasks(s, 12, seed=3, pattern="random")
    assert s.metadata["fleet"] == {"count": 12, "pattern": "random", "seed": 3, "min_spacing": None}
    assert s.metadata["spec"]["fleet"] == {"count": 12, "pattern": "random", "seed": 3}
    assert "tasks" not in s.metadata["spec"]
    # defaults: crossing, seed 0, 3 * S2
    d = scenario_from_dict(fleet_on_spso(fleet={"count": 5}))
    assert d.tasks == fleet_tasks(d, 5, seed=0, pattern="crossing", min_spacing=30.0)
    # min_spacing
    w = scenario_from_dict(fleet_on_spso(fleet={"count": 5, "min_spacing": 80}))
    assert w.tasks == fleet_tasks(w, 5, min_spacing=80.0)


FLEET_CASES: list[Case] = [
    (
        "both.yaml",
        lambda d: fleet_on_spso(tasks=[{"start": [200, 100, 300], "goal": [800, 800, 300]}]),
        [("fleet", "give either 'tasks' or 'fleet', not both")],
    ),
    (
        "neither.yaml",
        lambda d: {k: v for k, v in fleet_on_spso().items() if k != "fleet"},
        [("tasks", "required field missing (or give 'fleet'")],
    ),
    (
        "null_fleet.yaml",
        lambda d: fleet_on_spso(fleet=None),
        [("tasks", "required field missing (or give 'fleet'")],
    ),
    (
        "count0.yaml",
        lambda d: fleet_on_spso(fleet={"count": 0}),
        [("fleet.count = 0", "greater than or equal to 1")],
    ),
    (
        "count_bool.yaml",
        lambda d: fleet_on_spso(fleet={"count": True}),
        [("fleet.count = true", "not true/false")],
    ),
    (
        "count_float.yaml",
        lambda d: fleet_on_spso(fleet={"count": 2.5}),
        [("fleet.count = 2.5", "valid integer")],
    ),
    (
        "no_count.yaml",
        lambda d: fleet_on_spso(fleet={"pattern": "random"}),
        [("fleet.count", "required field missing")],
    ),
    (
        "pattern.yaml",
        lambda d: fleet_on_spso(fleet={"count": 4, "pattern": "zigzag"}),
        [('fleet.pattern = "zigzag"', "'crossing' or 'random'")],
    ),
    (
        "seed.yaml",
        lambda d: fleet_on_spso(fleet={"count": 4, "seed": -1}),
        [("fleet.seed = -1", "greater than or equal to 0")],
    ),
    (
        "spacing.yaml",
        lambda d: fleet_on_spso(fleet={"count": 4, "min_spacing": -5}),
        [("fleet.min_spacing = -5", "greater than 0")],
    ),
    (
        "fleet_key.yaml",
        lambda d: fleet_on_spso(fleet={"count": 4, "size": 3}),
        [("fleet.size = 3", "unknown key (allowed: count, pattern, seed, min_spacing)")],
    ),
    (
        "fleet_scalar.yaml",
        lambda d: fleet_on_spso(fleet=7),
        [("fleet = 7", "valid dictionary")],
    ),
    (
        "too_many.yaml",
        lambda d: fleet_on_spso(fleet={"count": 5000}),
        [('fleet = {"count": 5000}', "cannot place 5000 UAV starts at least 30 m apart")],
    ),
    (
        "too_wide.yaml",
        lambda d: fleet_on_spso(fleet={"count": 40, "min_spacing": 400}),
        [('fleet = {"count": 40, "min_spacing": 400}', "placed ")],
    ),
]


@pytest.mark.parametrize("case", FLEET_CASES, ids=[c[0] for c in FLEET_CASES])
def test_fleet_problem_lines(tmp_path: Path, case: Case) -> None:
    path = _write_case(tmp_path, case)
    problems = problems_of(path)
    for where, reason in case[2]:
        assert has_line(problems, f"{path}: {where}", reason), problems
    assert len(problems) == len(case[2]), problems


def test_fleet_with_other_problems_still_checked(tmp_path: Path) -> None:
    data = fleet_on_spso(
        circles=[{"center": [1, 1], "radius": -1}],
        polygons=[{"vertices": [[100, 100], [200, 200], [300, 300]]}],
    )
    problems = problems_of(write(tmp_path / "f.yaml", data))
    assert has_line(problems, "circles[0].radius", "greater than 0"), problems
    assert has_line(problems, "polygons[0].vertices", "zero area"), problems
    assert len(problems) == 2, problems


@pytest.mark.parametrize("suffix", [".yaml", ".json"])
def test_fleet_round_trip(tmp_path: Path, suffix: str) -> None:
    s = scenario_from_dict(fleet_on_spso(fleet={"count": 20, "pattern": "random", "seed": 5}))
    out = save_scenario(s, tmp_path / f"fleet{suffix}")
    text = out.read_text()
    data = json.loads(text) if suffix == ".json" else yaml.safe_load(text)
    assert data["fleet"] == {"count": 20, "pattern": "random", "seed": 5}
    assert "tasks" not in data  # the fleet block is written, not the expanded tasks
    again = load_scenario(out)
    assert_same(s, again)
    assert scenario_to_dict(again) == scenario_to_dict(s)
    # spec_from_scenario (a scenario without its file-level spec) writes the expanded tasks
    spec = spec_from_scenario(s)
    assert spec.fleet is None and spec.tasks is not None and len(spec.tasks) == 20
    s.metadata.pop("spec")
    assert_same(s, load_scenario(save_scenario(s, tmp_path / f"expanded{suffix}")))


def test_fleet_builtins_load() -> None:
    for k, count in zip(range(1, 5), [6, 10, 15, 20], strict=True):
        s = load_builtin(f"ppswarm{k}")
        assert len(s.tasks) == 40 and len(s.cylinders) == count
        assert s.metadata["spec"]["fleet"] == {"count": 40, "pattern": "crossing", "seed": 0}
        assert (s.cost, s.n_waypoints) == ("ppswarm", 10)


def test_fleet_schema() -> None:
    sch = schema()
    assert "fleet" in sch["properties"]
    fleet = sch["$defs"]["FleetSpec"]
    assert fleet["required"] == ["count"]
    assert set(fleet["properties"]) == {"count", "pattern", "seed", "min_spacing"}
    assert ScenarioSpec.model_validate({"name": "x", "fleet": {"count": 3}}).tasks is None


@pytest.mark.parametrize(
    ("upper", "message"),
    [
        ([1e308, 1e308], "bounds.upper[0]"),  # passed `scenario check`, then planned inf
        ([-1e308, 10.0], "bounds.upper[0]"),
        ([2.0e6, 100.0], "extent beyond the 1,000 km this tool plans over (x: 2,000,000 m)"),
    ],
)
def test_absurd_bounds_are_refused(tmp_path: Path, upper: list[float], message: str) -> None:
    doc = {"name": "big", "bounds": {"lower": [0, 0], "upper": upper},
           "tasks": [{"id": "a", "start": [1, 1], "goal": [9, 9]}]}  # fmt: skip
    path = tmp_path / "big.json"
    path.write_text(json.dumps(doc))
    assert any(message in p for p in problems_of(path)), problems_of(path)


def test_resource_limits_are_checked_when_read(tmp_path: Path) -> None:
    doc = {"name": "many", "bounds": {"lower": [0, 0], "upper": [100, 100]},
           "circles": [{"center": [5, 5], "radius": 1}] * 100_001,
           "tasks": [{"id": "a", "start": [1, 1], "goal": [9, 9]}],
           "planning": {"n_waypoints": 5000}}  # fmt: skip
    path = tmp_path / "many.json"
    path.write_text(json.dumps(doc))
    found = problems_of(path)
    assert any(p.startswith(f"{path}: circles") and "at most 100000" in p for p in found)
    assert any("planning.n_waypoints = 5000" in p for p in found)
    big = tmp_path / "big.yaml"
    with big.open("w") as f:  # larger than a scenario file may be: refused before it is read
        f.write("name: x\n")
        f.truncate(65 * 2**20)
    assert any("a scenario file is at most" in p for p in problems_of(big))


# ------------------------------------------------------------------ heights of WGS84 tasks
def _luxembourg_with(tmp_path: Path, task: dict[str, Any], **top: Any) -> Path:
    """The built-in luxembourg scenario (a real DEM, placed on Earth) with one task of ours."""
    import yaml

    from uavplan.scenarios import builtin_path

    doc = yaml.safe_load(builtin_path("luxembourg").read_text(encoding="utf-8"))
    doc["terrain"]["file"] = str(builtin_path("luxembourg").parent / doc["terrain"]["file"])
    doc["tasks"] = [task]
    doc.pop("task_z", None)
    doc.update(top)
    path = tmp_path / "lux.yaml"
    path.write_text(yaml.safe_dump(doc), encoding="utf-8")
    return path


def test_wgs84_task_heights_above_ground_takeoff_or_sea_level(tmp_path: Path) -> None:
    """Near Luxembourg City (ground 277 m) to near Clervaux (ground 432 m): 100 m above the
    ground under each point, above the ground at take-off, or the AMSL altitudes themselves
    land where they should; a WGS84 task given above ground plans and flies over the DEM."""
    from uavplan.io.scenario_file import load_scenario

    start, goal = [49.6143714, 6.1375], [50.0503741, 6.0327821]
    lux = load_scenario(builtin_path("luxembourg"))
    g0 = float(lux.terrain.height(*lux.origin.to_local([[*start, 0.0]])[0][:2]))
    g1 = float(lux.terrain.height(*lux.origin.to_local([[*goal, 0.0]])[0][:2]))
    assert g1 - g0 > 100.0  # the highlands: a height above take-off is not one above ground

    def task(height: str | None, z0: float, z1: float) -> dict[str, Any]:
        t = {"frame": "wgs84", "start": [*start, z0], "goal": [*goal, z1]}
        return t if height is None else {**t, "height": height}

    sc = load_scenario(_luxembourg_with(tmp_path, task("ground", 100, 100)))
    assert sc.tasks[0].start[2] == pytest.approx(g0 + 100, abs=0.05)
    assert sc.tasks[0].goal[2] == pytest.approx(g1 + 100, abs=0.05)
    up = load_scenario(_luxembourg_with(tmp_path, task("takeoff", 100, 260)))
    assert up.tasks[0].goal[2] == pytest.approx(g0 + 260, abs=0.05)
    sea = load_scenario(_luxembourg_with(tmp_path, task(None, g0 + 100, g1 + 100)))
    assert sea.tasks[0].goal[2] == pytest.approx(g1 + 100, abs=0.05)  # AMSL is the default
    again = load_scenario(_luxembourg_with(tmp_path, task(None, 100, 100), task_z="ground"))
    assert again.tasks[0].goal == pytest.approx(sc.tasks[0].goal)  # task_z: ground as before
    # 150 m AMSL is under the ground: the error says where that is in the local frame
    local = r"under the terrain .* \(in the local frame: \[0\.0, -22500\.0, 150\.0\] m\)"
    with pytest.raises(ScenarioFileError, match=r"tasks\[0\]\.start = .*" + local):
        load_scenario(_luxembourg_with(tmp_path, task("amsl", 150, 600)))
    with pytest.raises(ScenarioFileError, match="height: 'ground' is for frame: wgs84 tasks"):
        load_scenario(_luxembourg_with(tmp_path, {"start": [0, -22500, 100],
                                                  "goal": [-7500, 26000, 100],
                                                  "height": "ground"}))  # fmt: skip
    from typer.testing import CliRunner

    from uavplan.cli import app

    r = CliRunner().invoke(app, ["plan", str(_luxembourg_with(tmp_path, task("ground", 100, 100))),
                                 "--out", str(tmp_path / "p")])  # fmt: skip
    assert r.exit_code == 0, r.output
    assert "independent verifier: every flown trajectory passes" in r.output
