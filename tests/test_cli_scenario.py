"""``uavplan scenario list | show | export | schema | check``."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
import yaml
from typer.testing import CliRunner

from uavplan.cli import app
from uavplan.io.scenario_file import load_scenario
from uavplan.scenarios import load_builtin

BUILTINS = ["jacksboro", "simple2d", "spso", "topobathy"]

runner = CliRunner()


def run(*args: str) -> Any:
    result = runner.invoke(app, ["scenario", *args])
    assert "Traceback" not in result.output
    assert result.exception is None or isinstance(result.exception, SystemExit), result.exception
    return result


def base3d(**over: Any) -> dict[str, Any]:
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
    return {k: v for k, v in data.items() if v is not None}


def flat(**over: Any) -> dict[str, Any]:
    data: dict[str, Any] = {
        "name": "f",
        "bounds": {"lower": [0, 0, 0], "upper": [100, 100, 50]},
        "tasks": [{"start": [5, 5, 10], "goal": [95, 95, 10]}],
    }
    data.update(over)
    return {k: v for k, v in data.items() if v is not None}


def _bad_dem(d: Path) -> dict[str, Any]:
    (d / "broken.tif").write_text("not a tiff at all")
    return flat(terrain={"file": "broken.tif"}, bounds=None)


# (file name, content maker, [(field path incl. value, reason)]); "" = the whole file
BAD: list[tuple[str, Callable[[Path], Any], list[tuple[str, str]]]] = [
    (
        "outside.yaml",
        lambda d: base3d(tasks=[{"start": [5000, 10, 150], "goal": [800, 800, 150]}]),
        [("tasks[0].start = [5000, 10, 150]", "outside the bounds")],
    ),
    (
        "obstacle.yaml",
        lambda d: base3d(tasks=[{"start": [400, 500, 150], "goal": [800, 800, 150]}]),
        [("tasks[0].start", "inside cylinder 0")],
    ),
    (
        "under.json",
        lambda d: base3d(
            task_z="absolute",
            altitude=None,
            tasks=[{"start": [200, 100, 20], "goal": [800, 800, 400]}],
        ),
        [("tasks[0].start = [200, 100, 20]", "under the terrain")],
    ),
    (
        "band.yaml",
        lambda d: base3d(tasks=[{"start": [200, 100, 250], "goal": [800, 800, 150]}]),
        [("tasks[0].start", "outside the band")],
    ),
    (
        "polygon.yaml",
        lambda d: flat(polygons=[{"vertices": [[1, 1], [5, 5]]}]),
        [("polygons[0].vertices", "at least 3 vertices")],
    ),
    (
        "radius.yaml",
        lambda d: flat(circles=[{"center": [50, 50], "radius": -2}]),
        [("circles[0].radius = -2", "greater than 0")],
    ),
    (
        "nan.yaml",
        lambda d: (
            "name: n\nbounds: {lower: [0, 0], upper: [.nan, 10]}\n"
            "tasks: [{start: [1, 1], goal: [2, 2]}]\n"
        ),
        [("bounds.upper[0] = NaN", "finite number")],
    ),
    (
        "key.yaml",
        lambda d: flat(uav={"speed": 10, "colour": "red"}),
        [('uav.colour = "red"', "unknown key")],
    ),
    (
        "slow.yaml",
        lambda d: flat(uav={"speed": 10, "min_speed": 12}),
        [("uav.min_speed = 12", "min_speed 12 m/s is above speed 10 m/s")],
    ),
    (
        "climb.yaml",
        lambda d: flat(uav={"max_climb_angle": 120}),
        [("uav.max_climb_angle = 120", "less than or equal to 90")],
    ),
    (
        "dem.yaml",
        lambda d: flat(terrain={"file": "missing.tif"}, bounds=None),
        [('terrain.file = "missing.tif"', "DEM file not found")],
    ),
    ("baddem.yaml", _bad_dem, [("terrain.file", "not a raster GDAL can read")]),
    ("garbage.yaml", lambda d: bytes(range(256)) * 4, [("", "not a YAML or JSON file")]),
    ("scalar.yaml", lambda d: "42\n", [("", "top level must be a mapping")]),
    ("syntax.json", lambda d: '{"name": ', [("", "not valid JSON")]),
    (
        "dims.yaml",
        lambda d: flat(bounds={"lower": [0, 0], "upper": [100, 100]}),
        [("tasks[0].start = [5, 5, 10]", "has 3 coordinates but the scenario is 2-D")],
    ),
    (
        "ctor.yaml",
        lambda d: flat(polygons=[{"vertices": [[0, 0], [1, 1], [2, 2]]}]),
        [("polygons[0].vertices", "zero area")],
    ),
]


def _write(tmp_path: Path, name: str, content: Any) -> Path:
    path = tmp_path / name
    if isinstance(content, bytes):
        path.write_bytes(content)
    elif isinstance(content, str):
        path.write_text(content)
    elif path.suffix == ".json":
        path.write_text(json.dumps(content))
    else:
        path.write_text(yaml.safe_dump(content))
    return path


def test_list() -> None:
    r = run("list")
    assert r.exit_code == 0
    for name in BUILTINS:
        assert name in r.stdout
    assert "Phung" in r.stdout


@pytest.mark.parametrize("name", BUILTINS)
def test_show_builtin(name: str) -> None:
    r = run("show", name)
    assert r.exit_code == 0, r.output
    s = load_builtin(name)
    assert f"scenario: {name} ({s.dim}-D)" in r.stdout
    assert "bounds:" in r.stdout and "tasks (1" in r.stdout and "uav:" in r.stdout
    assert "obstacles:" in r.stdout and "altitude band:" in r.stdout


def test_show_details() -> None:
    out = run("show", "spso").stdout
    assert "terrain: spso, 879 x 1045 nodes" in out
    assert "cell 1 x 1 m" in out
    assert "6 cylinders (6 infinite)" in out
    assert "altitude band: [100, 200] m above ground" in out
    assert "planning: cost spso, 10 waypoints" in out
    out = run("show", "simple2d").stdout
    assert "terrain: none" in out and "4 circles" in out and "1 polygon," in out


@pytest.mark.parametrize("suffix", [".yaml", ".json"])
@pytest.mark.parametrize("name", BUILTINS)
def test_export_then_check_and_load(tmp_path: Path, name: str, suffix: str) -> None:
    target = tmp_path / f"{name}{suffix}"
    r = run("export", name, str(target))
    assert r.exit_code == 0, r.output
    text = target.read_text()
    data = json.loads(text) if suffix == ".json" else yaml.safe_load(text)
    assert data["name"] == name
    r = run("check", str(target))
    assert r.exit_code == 0 and r.stdout.strip() == "ok"
    a, b = load_builtin(name), load_scenario(target)
    assert a.tasks == b.tasks and a.bounds == b.bounds and a.cylinders == b.cylinders
    assert a.uav == b.uav  # the kinematic limits too
    assert a.circles == b.circles and a.polygons == b.polygons and a.altitude == b.altitude
    assert a.danger_areas == b.danger_areas and a.uncertain_areas == b.uncertain_areas
    r = run("show", str(target))
    assert r.exit_code == 0 and f"source: {target}" in r.stdout


def test_schema_is_json() -> None:
    r = run("schema")
    assert r.exit_code == 0
    sch = json.loads(r.stdout)
    assert sch["type"] == "object"
    for key in ("name", "bounds", "terrain", "cylinders", "tasks", "planning", "uav", "task_z"):
        assert key in sch["properties"]
    uav = sch["$defs"]["UAVSpec"]["properties"]
    assert uav["turn_radius"]["default"] == 0
    for key in ("min_speed", "max_speed", "max_climb_angle", "max_descent_angle"):
        assert "description" in uav[key], key
    assert "degrees" in uav["max_climb_angle"]["description"]


@pytest.mark.parametrize("case", BAD, ids=[c[0] for c in BAD])
@pytest.mark.parametrize("command", ["check", "show"])
def test_bad_files(tmp_path: Path, case: Any, command: str) -> None:
    name, make, expected = case
    path = _write(tmp_path, name, make(tmp_path))
    r = run(command, str(path))
    assert r.exit_code == 2, r.output
    assert "Traceback" not in r.output
    assert r.stdout == ""
    lines = r.stderr.splitlines()
    for where, reason in expected:
        prefix = f"{path}: {where}"
        assert any(line.startswith(prefix) and reason in line for line in lines), lines


def test_several_problems_several_lines(tmp_path: Path) -> None:
    data = base3d(
        circles=[{"center": [1, 1], "radius": -1}],
        polygons=[{"vertices": [[0, 0]]}],
        tasks=[
            {"start": [5000, 10, 150], "goal": [800, 800, 150]},
            {"start": [200, 100, 150], "goal": [400, 500, 150], "extra": 1},
            {"start": [200, 100, 150], "goal": [400, 500, 150]},
        ],
    )
    path = _write(tmp_path, "many.yaml", data)
    r = run("check", str(path))
    assert r.exit_code == 2
    lines = r.stderr.splitlines()
    assert len(lines) == 5, lines
    assert all(line.startswith(f"{path}: ") for line in lines)
    for part in (
        "circles[0].radius",
        "polygons[0].vertices",
        "tasks[1].extra",
        "tasks[0].start",
        "tasks[2].goal",
    ):
        assert any(part in line for line in lines), (part, lines)


def test_unknown_names(tmp_path: Path) -> None:
    for args in (("show", "nowhere"), ("check", "nowhere.yaml"), ("export", "nope", "x.yaml")):
        r = run(*args)
        assert r.exit_code == 2
        assert "not a built-in scenario" in r.stderr


def test_export_failures_keep_existing_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    r = run("export", "spso", str(tmp_path / "missing-dir" / "spso.yaml"))
    assert r.exit_code == 2
    assert "does not exist" in r.stderr and "spso.yaml" in r.stderr
    assert not (tmp_path / "missing-dir").exists()

    target = tmp_path / "spso.yaml"
    assert run("export", "simple2d", str(target)).exit_code == 0
    before = target.read_bytes()

    def fail_replace(src: str, dst: str) -> None:
        raise OSError(5, "Input/output error")

    monkeypatch.setattr(os, "replace", fail_replace)
    r = run("export", "spso", str(target))
    assert r.exit_code == 2
    assert r.stderr.strip() == f"{target}: cannot write: Input/output error"
    monkeypatch.undo()
    assert target.read_bytes() == before
    assert load_scenario(target).name == "simple2d"
    assert [p.name for p in tmp_path.iterdir()] == ["spso.yaml"]

    r = run("export", "spso", str(tmp_path / "spso.toml"))
    assert r.exit_code == 2 and "unknown suffix" in r.stderr


def test_module_entry_point(tmp_path: Path) -> None:
    bad = _write(tmp_path, "bad.yaml", base3d(tasks=[{"start": [5000, 10, 150], "goal": [1, 1]}]))
    r = subprocess.run(
        [sys.executable, "-m", "uavplan.cli", "scenario", "check", str(bad)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert r.returncode == 2
    assert "Traceback" not in r.stderr + r.stdout
    assert f"{bad}: tasks[0].start = [5000, 10, 150]: outside the bounds" in r.stderr
    assert f"{bad}: tasks[0].goal = [1, 1]: has 2 coordinates" in r.stderr


def test_show_says_where_the_scenario_is_on_earth() -> None:
    r = run("show", "jacksboro")
    assert "origin: 36.589167, -84.246250 (WGS84)" in r.output and "78 m off" in r.output
    assert "origin: none" in run("show", "simple2d").output


def test_the_cli_starts_without_numba_or_matplotlib() -> None:
    """`uavplan --help` answers in well under a second because the CLI imports the heavy
    libraries only in the commands that use them (a top-level import of Numba costs 0.2 s)."""
    import subprocess
    import sys

    heavy = "('numba', 'matplotlib', 'scipy')"
    code = f"import sys, uavplan.cli; print(sorted(m for m in {heavy} if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]", out.stdout


def test_bench_list_loads_no_world_model_nor_report_libraries() -> None:
    """`uavplan bench list` counts the plans' runs without deriving seeds and without loading
    Numba kernels, pandas, SciPy's statistics or matplotlib (they are imported on first use:
    uavplan._lazy), so it answers in about a second, not nine."""
    import subprocess
    import sys

    code = (
        "import sys\n"
        "from uavplan.cli import main\n"
        "sys.argv = ['uavplan', 'bench', 'list']\n"
        "try:\n    main()\nexcept SystemExit:\n    pass\n"
        "loaded = ('numba', 'matplotlib.figure', 'scipy.stats._stats_py', 'pandas.core.frame')\n"
        "print(sorted(m for m in loaded if m in sys.modules), file=sys.stderr)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert "rggpso-rq1" in out.stdout
    assert out.stderr.strip().splitlines()[-1] == "[]", out.stderr
