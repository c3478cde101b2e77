"""Hardening of the inputs users give uavplan (issue 19 items 1-3): the fuzzer of
``tests/io/fuzzing.py`` driven by hypothesis over scenario files, plan files and DEMs (a few
hundred cases; ``benchmarks/fuzz_inputs.py`` runs 10,000), then one test per limit and per
class of failure the fuzzer found: every bad input ends with exit code 2 and a line naming the
file, the field and the value, never a traceback, a hang or an allocation beyond the limits.
"""

from __future__ import annotations

import json
import os
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from uavplan.cli import app

sys.path.insert(0, str(Path(__file__).resolve().parent))

import fuzzing

runner = CliRunner()
_CACHE = Path(tempfile.mkdtemp(prefix="uavplan-fuzz-plans-"))


def _fuzz_settings(n: int) -> settings:
    return settings(
        max_examples=n,
        deadline=None,
        derandomize=True,  # the same cases on every CI run; the benchmark explores further
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
        database=None,
    )


def _fuzz_test(kind: str, n: int, plan_scale: float, doc: str) -> Any:
    """A hypothesis test of ``n`` cases of one kind (the case's choices are hypothesis's)."""

    @_fuzz_settings(n)
    @given(st.data())
    def test(data: Any) -> None:
        with tempfile.TemporaryDirectory() as tmp:
            draw = fuzzing.HypothesisDraw(data)
            case = fuzzing.make_case(draw, Path(tmp), _CACHE, kind, plan_scale, heavy=False)
            result = fuzzing.run_case(case, timeout=60.0)
            assert result.outcome not in fuzzing.FAILURES, (
                f"{result.outcome} [{case.kind}: {case.note}]: uavplan "
                f"{' '.join(result.command)}\n{result.detail}"
            )

    test.__doc__ = doc
    return test


test_fuzz_scenario_files = _fuzz_test(
    "scenario", 120, 0.15, "Mutated scenario files (structure, bytes): check, sometimes plan."
)
test_fuzz_special_files = _fuzz_test(
    "special", 40, 0.0, "Alias bombs, deep nesting, huge, empty and odd files, FIFOs, devices."
)
test_fuzz_dems = _fuzz_test(
    "dem", 60, 0.1, "GeoTIFFs with odd tags, .npy/.npz, SRTM tiles, links, devices, FIFOs."
)
test_fuzz_plan_files = _fuzz_test("plan-file", 50, 0.0, "Mutated plan.json: verify, export.")


# ------------------------------------------------------------------ helpers
def _scene(tmp: Path, data: dict[str, Any], name: str = "scene.yaml") -> Path:
    path = tmp / name
    path.write_text(yaml.safe_dump(data) if name.endswith(".yaml") else json.dumps(data))
    return path


def _simple(**changes: Any) -> dict[str, Any]:
    data = fuzzing.base_scenario("simple2d")
    data.update(changes)
    return data


def _check(path: Path | str) -> Any:
    return runner.invoke(app, ["scenario", "check", str(path)])


def _clean_error(result: Any, *words: str) -> str:
    """The exit-2 message, asserting no traceback and that it says each of ``words``."""
    assert result.exception is None or isinstance(result.exception, SystemExit), result.exception
    assert result.exit_code == 2, (result.exit_code, result.stdout, result.stderr)
    err = result.stderr
    assert "Traceback" not in err
    for w in words:
        assert w in err, (w, err)
    return str(err)


# ------------------------------------------------------------------ reading files
def test_yaml_python_tags_are_refused_and_run_nothing(tmp_path: Path) -> None:
    marker = tmp_path / "pwned"
    path = tmp_path / "scene.yaml"
    path.write_text(
        f"name: !!python/object/apply:os.system ['touch {marker}']\n"
        "bounds: {lower: [0, 0], upper: [10, 10]}\n"
        "tasks: [{start: [1, 1], goal: [9, 9]}]\n"
    )
    _clean_error(_check(path), "scene.yaml", "python/object")
    path.write_text("name: !!python/name:os.system\ntasks: []\n")
    _clean_error(_check(path), "scene.yaml")
    assert not marker.exists()


def test_alias_bomb_ends_quickly(tmp_path: Path) -> None:
    path = tmp_path / "scene.yaml"
    path.write_bytes(fuzzing.bomb_yaml(12))  # 9**11 items when expanded
    t0 = time.monotonic()
    err = _clean_error(_check(path), "scene.yaml", "tasks")
    assert time.monotonic() - t0 < 10.0
    assert max(map(len, err.splitlines())) < 600  # each value shown is cut, not expanded


@pytest.mark.parametrize("suffix", [".yaml", ".json"])
def test_deep_nesting_is_a_clean_error(tmp_path: Path, suffix: str) -> None:
    path = tmp_path / f"scene{suffix}"
    path.write_text('{"name": "x", "tasks": ' + "[" * 100_000 + "]" * 100_000 + "}")
    _clean_error(_check(path), path.name, "not valid")


@pytest.mark.parametrize("text", ["[" * 100_000 + "]" * 100_000, "\n" + "- " * 100_000 + "x"])
def test_deep_nesting_with_the_pure_python_parser(
    tmp_path: Path, text: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The parser used where libyaml is older than 0.2.6 (no nesting limit: its composer
    overflowed the C stack and killed the process under PyYAML 6.0.3, CI of 4 Dec)."""
    from uavplan.io.scenario_file import read

    monkeypatch.setattr(read, "LOADER", read.PY_LOADER)
    path = tmp_path / "scene.yaml"
    path.write_text("name: x\ntasks: " + text + "\n")
    _clean_error(_check(path), path.name, "nested too deeply")


def test_libyaml_is_used_only_with_its_nesting_limit() -> None:
    from uavplan.io.scenario_file import read

    if not getattr(yaml, "__with_libyaml__", False):
        assert read.LOADER is read.PY_LOADER
        return
    from yaml import _yaml

    assert (read.LOADER is not read.PY_LOADER) == (tuple(_yaml.get_version()) >= (0, 2, 6))


@pytest.mark.parametrize(
    ("line", "words"),
    [
        ("task_z: 2026-13-45", ["task_z", "2026-13-45"]),  # a date PyYAML cannot build
        ("task_z: 2026-02-30 25:61:00", ["task_z", "2026-02-30 25:61:00"]),
        ("task_z: !!timestamp 2020-99-99", ["task_z", "2020-99-99"]),
        ("bounds: !!int abc", ["not valid YAML", "abc"]),
        ("bounds: !!float x", ["not valid YAML"]),
    ],
)
def test_dates_and_mistagged_scalars_are_clean_errors(
    tmp_path: Path, line: str, words: list[str]
) -> None:
    """Found by ``benchmarks/fuzz_inputs.py --seed 1`` (a ValueError out of PyYAML's
    timestamp constructor): no field is a date, so a date-like scalar stays text."""
    path = tmp_path / "scene.yaml"
    path.write_text("name: x\n" + line + "\ntasks: [[0, 0], [10, 10]]\n")
    _clean_error(_check(path), path.name, *words)


def test_large_yaml_is_refused_before_parsing_and_json_is_not(tmp_path: Path) -> None:
    from uavplan.io.scenario_file.schema import MAX_YAML_BYTES

    data = _simple(description="x" * (MAX_YAML_BYTES + 10))
    _clean_error(_check(_scene(tmp_path, data)), "scene.yaml", "as JSON")
    assert _check(_scene(tmp_path, data, "scene.json")).exit_code == 0


@pytest.mark.parametrize("what", ["fifo", "dir", "/dev/zero", "/dev/null", "loop"])
def test_scenario_path_that_is_not_a_regular_file(tmp_path: Path, what: str) -> None:
    path = tmp_path / "scene.yaml"
    if what == "fifo":
        os.mkfifo(path)
    elif what == "dir":
        path.mkdir()
    elif what == "loop":
        path.symlink_to(path)
    else:
        path.symlink_to(what)
    _clean_error(_check(path), "scene.yaml")  # and no wait on the FIFO


# ------------------------------------------------------------------ DEMs
def _dem_scene(tmp: Path, block: dict[str, Any]) -> Path:
    return _scene(tmp, fuzzing.dem_scene(block))


@pytest.mark.parametrize("what", ["fifo", "dir", "dev", "link-dev", "dangling", "missing", "loop"])
def test_dem_path_that_is_not_a_regular_file(tmp_path: Path, what: str) -> None:
    dem = tmp_path / "dem.tif"
    name = "dem.tif"
    if what == "fifo":
        os.mkfifo(dem)
    elif what == "dir":
        dem.mkdir()
    elif what == "dev":
        name = "/dev/zero"
    elif what == "link-dev":
        dem.symlink_to("/dev/zero")
    elif what == "dangling":
        dem.symlink_to(tmp_path / "nowhere.tif")
    elif what == "loop":
        dem.symlink_to(dem)
    _clean_error(_check(_dem_scene(tmp_path, {"file": name})), "terrain.file")
    srtm = tmp_path / "N36W085.hgt"
    if what == "fifo":
        os.mkfifo(srtm)
        _clean_error(_check(_dem_scene(tmp_path, {"srtm": [srtm.name]})), "terrain.srtm")


def test_dem_grids_beyond_the_limit_are_refused_before_reading(tmp_path: Path) -> None:
    from uavplan.world.terrain import MAX_DEM_CELLS

    header = "{'descr': '<f8', 'fortran_order': False, 'shape': (100000, 100000), }"
    header += " " * (63 - len(header) % 64) + "\n"
    (tmp_path / "dem.npy").write_bytes(
        b"\x93NUMPY\x01\x00" + len(header).to_bytes(2, "little") + header.encode()
    )
    _clean_error(_check(_dem_scene(tmp_path, {"file": "dem.npy"})), f"{MAX_DEM_CELLS:,}")
    (tmp_path / "dem.tif").write_bytes(fuzzing._huge_tiff())
    _clean_error(_check(_dem_scene(tmp_path, {"file": "dem.tif"})), "200000 x 200000")
    with (tmp_path / "big.npz").open("wb") as f:  # 30 M zeros compress to little
        np.savez_compressed(f, heights=np.zeros((6000, 5000), np.uint8))
    _clean_error(_check(_dem_scene(tmp_path, {"file": "big.npz"})), "6000 x 5000")


def test_dem_samples_that_are_not_real_numbers(tmp_path: Path) -> None:
    np.save(tmp_path / "dem.npy", np.ones((4, 4), np.complex64))
    _clean_error(_check(_dem_scene(tmp_path, {"file": "dem.npy"})), "not real numbers")
    np.save(tmp_path / "dem.npy", np.array([{"a": 1}, None], dtype=object), allow_pickle=True)
    _clean_error(_check(_dem_scene(tmp_path, {"file": "dem.npy"})), "terrain.file")


def test_resampled_srtm_grid_beyond_the_limit(tmp_path: Path) -> None:
    tile = tmp_path / "N36W085.hgt"
    tile.write_bytes(np.full((1201, 1201), 300, ">i2").tobytes())
    scene = fuzzing.dem_scene({"srtm": [tile.name], "cell_size": 1.0})
    scene["bounds"] = {"lower": [-40_000, -40_000], "upper": [40_000, 40_000]}
    _clean_error(_check(_scene(tmp_path, scene)), "terrain.srtm", "at most 25,000,000")


def test_srtm_tiles_beyond_the_limit(tmp_path: Path) -> None:
    from uavplan.world.srtm import MAX_SRTM_SAMPLES

    names = []
    for k in range(5):  # five sparse 1-arc-second tiles: more samples than the limit
        p = tmp_path / f"N3{k}W085.hgt"
        with p.open("wb") as f:
            f.truncate(2 * 3601 * 3601)
        names.append(p.name)
    scene = fuzzing.dem_scene({"srtm": names})
    _clean_error(_check(_scene(tmp_path, scene)), "terrain.srtm", f"{MAX_SRTM_SAMPLES:,}")


# ------------------------------------------------------------------ semantic checks at load
@pytest.mark.parametrize(
    ("where", "value", "words"),
    [
        (("uav", "speed"), 1e9, ["uav.speed", "m/s"]),
        (("uav", "speed"), 1e-9, ["uav.speed", "greater than or equal to 0.01"]),
        (("uav", "max_speed"), 5e3, ["uav.max_speed"]),
        (("uav", "turn_radius"), 1e300, ["uav.turn_radius", "1,000 km"]),
        (("uav", "s2"), 1e7, ["uav.s2"]),
        (("circles", 0, "radius"), 1e300, ["circles[0].radius", "less than or equal to 1000000"]),
        (("circles", 0, "margin"), 2e6, ["circles[0].margin"]),
        (("tasks", 0, "start_time"), 1e300, ["tasks[0].start_time", "115 days"]),
        (("tasks", 0, "id"), "../../etc/x", ["tasks[0].id", "names files"]),
        (("planning", "n_waypoints"), 1001, ["planning.n_waypoints", "Limits"]),
        (("planning", "cost"), "spso", ["planning.cost", "3-D"]),
        (("planning", "cost"), "nope", ["planning.cost", "unknown cost preset"]),
        (("planning", "planner"), "nope", ["planning.planner", "unknown planner"]),
        (("planning", "options"), {"w": float("nan")}, ["planning.options.w", "finite"]),
        (("planning", "options"), {"zz": 1}, ["planning.options.zz", "unknown option"]),
        (("planning", "options"), {"cost": "spso"}, ["planning.options.cost", "3-D"]),
        (("planning", "iterations"), 0, ["planning.iterations"]),
        (("planning", "pop_size"), 10**7, ["planning.pop_size", "path points"]),
        (("planning", "time"), -1, ["planning.time"]),
    ],
)
def test_absurd_values_are_refused_at_load(
    tmp_path: Path, where: tuple[Any, ...], value: Any, words: list[str]
) -> None:
    data = _simple()
    node = data
    for key in where[:-1]:
        node = node.setdefault(key, {}) if isinstance(key, str) else node[key]
    node[where[-1]] = value
    _clean_error(_check(_scene(tmp_path, data)), "scene.yaml", *words)


def test_every_planning_problem_is_one_line(tmp_path: Path) -> None:
    data = _simple(planning={"planner": "spso", "options": {"w": ".nan", "zz": 1, "pop_size": 0}})
    err = _clean_error(_check(_scene(tmp_path, data)), "planning.options.w")
    assert "planning.options.zz" in err and "planning.options.pop_size" in err
    assert len(err.strip().splitlines()) == 3


def test_planning_block_gives_plan_its_defaults(tmp_path: Path) -> None:
    data = _simple(
        planning={
            "planner": "pso",
            "options": {"w": 0.5},
            "iterations": 2,
            "pop_size": 6,
            "n_waypoints": 3,
        }
    )
    out = tmp_path / "out"
    r = runner.invoke(app, ["plan", str(_scene(tmp_path, data)), "-o", str(out)])
    assert r.exit_code in (0, 1), r.stderr
    doc = json.loads((out / "plan.json").read_text())
    assert doc["algorithm"] == "pso"
    assert doc["uavs"][0]["iterations"] == 2
    assert doc["config"]["optimizer_options"] == {"w": 0.5, "pop_size": 6}


@pytest.mark.parametrize(
    ("param", "words"),
    [
        ("w=nan", ["--param w=nan", "finite"]),
        ("zz=1", ["--param zz=1", "unknown option"]),
        ("pop_size=0", ["--param pop_size=0"]),
        ("noequals", ["--param", "NAME=VALUE"]),
    ],
)
def test_param_values_are_named(tmp_path: Path, param: str, words: list[str]) -> None:
    r = runner.invoke(
        app,
        [
            "plan",
            "simple2d",
            "-a",
            "pso",
            "--iterations",
            "1",
            "--param",
            param,
            "-o",
            str(tmp_path / "out"),
        ],
    )
    _clean_error(r, *words)


def test_cost_flag_for_the_wrong_dimension(tmp_path: Path) -> None:
    r = runner.invoke(
        app, ["plan", "simple2d", "-a", "pso", "--cost", "spso", "-o", str(tmp_path / "out")]
    )
    _clean_error(r, "--cost spso", "3-D")


# ------------------------------------------------------------------ resource bounds
def test_run_refused_with_its_estimate_when_memory_is_short(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from uavplan.planners import memory

    monkeypatch.setattr(memory, "available_memory", lambda: (64 * 2**20, "available memory"))
    r = runner.invoke(
        app,
        [
            "plan",
            "simple2d",
            "-a",
            "spso",
            "--pop-size",
            "100000",
            "--iterations",
            "1",
            "-o",
            str(tmp_path / "out"),
        ],
    )
    _clean_error(r, "simple2d", "needs about", "population", "available memory is 64 MiB")
    assert not (tmp_path / "out").exists()  # refused before the run: nothing written


def test_memory_estimate_grows_with_the_run() -> None:
    from uavplan.planners import get_planner
    from uavplan.planners.memory import available_memory, estimate_run
    from uavplan.scenarios import resolve

    one = estimate_run(resolve("simple2d"), get_planner("spso"), 100, 10)
    more = estimate_run(resolve("simple2d"), get_planner("spso"), 1000, 10)
    assert more.population == pytest.approx(10 * one.population)
    fleet = estimate_run(resolve("ppswarm1"), get_planner("ppswarm"), None, None)
    assert fleet.fleet > 0 and fleet.terrain > 0 and fleet.population > 0
    hr = estimate_run(resolve("hrmaga-spso"), get_planner("hr-maga"), None, None)
    assert (
        hr.population
        > estimate_run(resolve("hrmaga-spso"), get_planner("spso"), 49, None).population
    )
    avail, where = available_memory()
    assert avail is None or (avail > 0 and where)


def test_limits_are_documented() -> None:
    from uavplan.io.plan_file import MAX_PLAN_BYTES
    from uavplan.io.scenario_file.schema import (
        MAX_FILE_BYTES,
        MAX_PATH_POINTS,
        MAX_UAVS,
        MAX_YAML_BYTES,
    )
    from uavplan.world.srtm import MAX_SRTM_SAMPLES
    from uavplan.world.terrain import MAX_DEM_CELLS

    doc = (Path(__file__).resolve().parents[2] / "docs" / "scenario-format.md").read_text()
    for n in (MAX_DEM_CELLS, MAX_SRTM_SAMPLES, MAX_PATH_POINTS, MAX_UAVS):
        assert f"{n:,}" in doc, n
    for size in (MAX_FILE_BYTES, MAX_YAML_BYTES, MAX_PLAN_BYTES):
        assert f"{size // 2**20} MiB" in doc, size


# ------------------------------------------------------------------ no other file touched
def test_a_scenario_reads_only_the_files_it_names(tmp_path: Path) -> None:
    """Every file ``scenario check`` opens is the scenario, its DEM or GeoJSON, or part of
    the installed software (Python's and the packages' own files)."""
    np.save(tmp_path / "dem.npy", np.linspace(0, 50, 400).reshape(20, 20))
    geo = {
        "type": "FeatureCollection",
        "features": [
            {
                "type": "Feature",
                "geometry": {
                    "type": "Polygon",
                    "coordinates": [
                        [[8.001, 47.001], [8.0011, 47.001], [8.0011, 47.0011], [8.001, 47.001]]
                    ],
                },
            }
        ],
    }
    (tmp_path / "zones.geojson").write_text(json.dumps(geo))
    scene = fuzzing.dem_scene({"file": "dem.npy", "cell_size": 10.0})
    scene["origin"] = {"lat": 47.0, "lon": 8.0}
    scene["no_fly"] = ["zones.geojson"]
    path = _scene(tmp_path, scene)
    opened: list[str] = []
    active = [True]

    def hook(event: str, args: tuple[Any, ...]) -> None:
        if active[0] and event == "open" and isinstance(args[0], str | Path):
            opened.append(os.path.abspath(args[0]))

    sys.addaudithook(hook)  # an audit hook cannot be removed: it stops recording below
    try:
        r = _check(path)
    finally:
        active[0] = False
    assert r.exit_code == 0, r.stderr
    installed = tuple(
        os.path.abspath(p)
        for p in (sys.prefix, sys.base_prefix, Path(fuzzing.__file__).parents[2] / "src")
    )
    named = {str(path), str(tmp_path / "dem.npy"), str(tmp_path / "zones.geojson")}
    others = [
        p
        for p in opened
        if p not in named
        and not p.startswith(installed)
        and not p.startswith(("/proc/", "/dev/urandom", "/etc/localtime", "/usr/"))
    ]
    assert not others, others
    assert named & set(opened) == named


def _export(plan: Path, fmt: str, out: Path) -> Any:
    return runner.invoke(
        app, ["export", str(plan), "simple2d", "-f", fmt, "--origin", "47,8", "-o", str(out)]
    )


def test_export_never_writes_outside_its_folder(tmp_path: Path) -> None:
    text, _ = fuzzing.real_plan("2d", _CACHE)
    doc = json.loads(text)
    doc["uavs"][0]["id"] = "../../escaped"
    plan = tmp_path / "a" / "b" / "plan.json"
    plan.parent.mkdir(parents=True)
    plan.write_text(json.dumps(doc))
    for fmt in ("qgc", "wpl"):
        r = _export(plan, fmt, plan.parent / fmt)
        _clean_error(r, "escaped", "cannot name a file")
    assert not list(tmp_path.rglob("escaped*"))


def test_plan_file_numbers_beyond_the_format_limits(tmp_path: Path) -> None:
    text, _ = fuzzing.real_plan("2d", _CACHE)
    for key, value, words in (
        ("times", 2**63, "times are within"),
        ("waypoints", 1e300, "coordinates are within"),
    ):
        doc = json.loads(text)
        rec = doc["uavs"][0]
        if key == "times":
            rec["flown"]["times"][1] = value
        else:
            rec["flown"]["points"][1][0] = value
        plan = tmp_path / "plan.json"
        plan.write_text(json.dumps(doc))
        r = _export(plan, "kml", tmp_path / "m.kml")
        _clean_error(r, "plan.json", words)


def test_export_origin_altitude_beyond_range(tmp_path: Path) -> None:
    text, _ = fuzzing.real_plan("2d", _CACHE)
    plan = tmp_path / "plan.json"
    plan.write_text(text.decode())
    r = runner.invoke(app, ["export", str(plan), "simple2d", "-f", "geojson", "--origin",
                            "0,0,1e308", "-o", str(tmp_path / "m.geojson")])  # fmt: skip
    _clean_error(r, "--origin", "altitude")


def test_tiny_positive_lengths_are_refused(tmp_path: Path) -> None:
    area = {"x": 50, "y": 50, "width": 3e-299, "height": 5}
    data = _simple(uncertain_areas=[area])
    _clean_error(_check(_scene(tmp_path, data)), "uncertain_areas[0].width", "1 mm")


def test_figure_of_a_long_thin_dem(tmp_path: Path) -> None:
    """A DEM of 2 x 3,000 nodes: the top view's contours keep both rows (matplotlib's
    contour needs 2 x 2 at least; the step was taken over the long side for both)."""
    from uavplan.viz.figures import save_plan_figure

    np.save(tmp_path / "dem.npy", np.zeros((2, 3000)))
    scene = fuzzing.dem_scene({"file": "dem.npy", "cell_size": 1.0})
    scene["tasks"] = [{"start": [5, 0.5, 50], "goal": [2500, 0.5, 50]}]
    from uavplan.io.scenario_file import load_scenario

    scenario = load_scenario(_scene(tmp_path, scene))
    assert save_plan_figure(scenario, [], tmp_path / "f.png").is_file()


@pytest.mark.parametrize(
    ("arrays", "words"),
    [
        ({"heights": np.full((10, 10), 1e307)}, "heights reach 1e+307 m"),
        ({"heights": np.zeros((10, 10)), "dx": np.array(1e-300)}, "a DEM cell is from"),
        ({"heights": np.zeros((10, 10)), "x0": np.array(1e300)}, "beyond 1e+07 m"),
        ({"heights": np.zeros((100, 100)), "dx": np.array(1e5)}, "beyond the 1,000 km"),
    ],
)
def test_dem_values_beyond_range(tmp_path: Path, arrays: dict[str, Any], words: str) -> None:
    """Finite but absurd numbers inside a DEM file (found by the fuzzer: heights of 1e307
    made the viewer's JSON fail)."""
    with (tmp_path / "dem.npz").open("wb") as f:
        np.savez(f, **arrays)
    _clean_error(_check(_dem_scene(tmp_path, {"file": "dem.npz"})), "terrain", words)
