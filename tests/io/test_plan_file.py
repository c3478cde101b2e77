"""Plan files: written in one place, read back typed, format 1 still read, a JSON Schema that
every written plan satisfies; the schema, planners and export commands."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from uavplan.cli import app
from uavplan.io.plan_file import (
    PLAN_FORMAT,
    PlanFormatError,
    PlanSpec,
    parse_plan,
    plan_document,
    plan_schema,
    read_plan_file,
    write_plan_file,
)
from uavplan.planners import available_planners, get_planner
from uavplan.planners.fleet.fleet_plan import plan_all
from uavplan.scenarios import resolve
from uavplan.world.fleet_tasks import with_fleet

runner = CliRunner()


@pytest.fixture(scope="module")
def fleet_plan():  # type: ignore[no-untyped-def]
    sc = with_fleet(resolve("ppswarm1"), 3)
    planner = get_planner("ppswarm", pop_size=12, n_iter=3, n_restart=1, rrt_iterations=1500)
    return plan_all(sc, planner, None, 0)


@pytest.fixture(scope="module")
def single_plan():  # type: ignore[no-untyped-def]
    return plan_all(resolve("simple2d"), get_planner("rgg-pso+", pop_size=20), 10, 1)


def test_round_trip_keeps_the_trajectories_and_the_verdicts(fleet_plan, single_plan) -> None:  # type: ignore[no-untyped-def]
    for plan in (fleet_plan, single_plan):
        doc = json.loads(json.dumps(plan_document(plan)))  # through JSON, as on disk
        assert doc["format"] == PLAN_FORMAT and doc["feasible"] == plan.feasible
        PlanSpec.model_validate(doc)  # the schema accepts what we write
        pf = parse_plan(doc)
        assert pf.dim == plan.scenario.dim and pf.scenario == plan.scenario.name
        assert pf.feasible == plan.feasible and pf.separation_checked == (plan.fleet is not None)
        for u, r in zip(pf.uavs, plan.results, strict=True):
            assert u.id == r.uav_id and u.feasible == r.feasible and u.cost_model == r.cost_model
            np.testing.assert_allclose(u.planned.points, r.waypoints, atol=1e-6)
            np.testing.assert_allclose(u.planned.times, r.times, atol=1e-6)
            assert (u.smoothed is None) == (r.smoothed is None)
            if r.smoothed is not None:
                assert u.smoothed is not None and u.smoothed_clear == r.smoothed_ok
                np.testing.assert_allclose(u.smoothed.points, r.smoothed, atol=1e-6)
            # the declared flight, with the planner's verdict on it
            pts, ts = r.flown_trajectory()
            assert u.flown is not None and u.flown_kind == r.flown_kind
            assert u.flown_feasible == r.flown_feasible
            np.testing.assert_allclose(u.flown.points, pts, atol=1e-6)
            np.testing.assert_allclose(u.flown.times, ts, atol=1e-6)
            assert u.record["info"] == json.loads(json.dumps(u.record["info"]))
    flown = parse_plan(plan_document(fleet_plan)).trajectories("flown")
    assert len(flown) == 3 and all(r.flown_kind == "smoothed" for r in fleet_plan.results)
    with pytest.raises(PlanFormatError, match="no smoothed path"):  # the default mode has none
        parse_plan(plan_document(fleet_plan)).trajectories("smoothed")


def test_format_1_still_loads() -> None:
    v1 = {
        "format": "uavplan.plan/1",
        "scenario": "flat",
        "separation_checked": False,
        "uavs": [
            {"id": "a", "waypoints": [[0, 0, 1], [1, 0, 1]], "times": [0, 1], "feasible": True,
             "cost": "inf", "violations": []},
            {"id": "b", "waypoints": [[0, 1, 1], [1, 1, 1]], "times": [0, 1], "feasible": False,
             "violations": ["terrain"]},
        ],
    }  # fmt: skip
    pf = parse_plan(v1)
    assert pf.format == "uavplan.plan/1" and pf.feasible is False  # not every UAV feasible
    assert pf.uavs[0].cost == np.inf and pf.uavs[1].violations == ("terrain",)
    assert pf.uavs[0].cost_model is None
    v1["uavs"][1]["feasible"] = True
    assert parse_plan(v1).feasible is True
    PlanSpec.model_validate(v1)


@pytest.mark.parametrize(
    ("doc", "message"),
    [
        ([], "expected a JSON object"),
        ({"format": "uavplan.plan/9", "uavs": []}, "format: 'uavplan.plan/9' is not one of"),
        ({"uavs": [{"id": "a", "waypoints": [[0, 0, 1, 1], [1, 0]], "times": [0, 1]}]},
         "expected a point of 2 or 3 coordinates"),
        ({"uavs": [{"id": "a", "waypoints": [[0, 0], [1, 0]], "times": [0, 1],
                    "feasible": "yes"}]}, "feasible: 'yes' is not true or false"),
        ({"uavs": [{"id": "a", "waypoints": [[0, 0], [1, 0]], "times": [0, 1],
                    "smoothed": {"points": [[0, 0]], "times": [0]}}]},
         "smoothed.points: 1 points, need at least 2"),
        ({"uavs": [{"id": "a", "waypoints": [[0, 0], [1, 0]], "times": [0, 1],
                    "violations": "terrain"}]}, "violations: expected a list of names"),
        # the fast path of plain numbers leaves these to the element-by-element messages
        ({"uavs": [{"id": "a", "waypoints": [[0, 0], [1, True]], "times": [0, 1]}]},
         r"waypoints\[1\]\[1\]: True is not a number"),
        ({"uavs": [{"id": "a", "waypoints": [[0, 0], [1, "2"]], "times": [0, 1]}]},
         r"waypoints\[1\]\[1\]: '2' is not a number"),
        ({"uavs": [{"id": "a", "waypoints": [[0, 0], [1, 0]], "times": [0, 1e999]}]},
         r"times\[1\]: inf is not a finite number"),
        ({"uavs": [{"id": "a", "waypoints": [[0, 0], [1, 0]], "times": [0, False]}]},
         r"times\[1\]: False is not a number"),
    ],
)  # fmt: skip
def test_bad_plan_files_say_what_and_where(doc: object, message: str) -> None:
    with pytest.raises(PlanFormatError, match=message) as e:
        parse_plan(doc, source="p.json")
    assert str(e.value).startswith("p.json") and len(e.value.problems) == 1


def _strict(text: str) -> object:
    """Parse as RFC 8259 JSON: Python's ``Infinity``/``NaN`` extensions refused."""

    def refuse(name: str) -> None:
        raise ValueError(f"not JSON: {name}")

    return json.loads(text, parse_constant=refuse)


def test_an_infeasible_plan_is_strict_json_with_null_for_infinity(tmp_path: Path) -> None:
    # PSO under the "inf" rule on a scene with a wall: infinite costs in the cost and history
    sc = resolve("simple2d")
    plan = plan_all(sc, get_planner("pso", pop_size=4, constraints="inf"), 1, 0, polish=False)
    r = plan.results[0]
    assert not np.isfinite(r.cost) or not np.all(np.isfinite(r.history)), "needs an infinity"
    path = write_plan_file(plan, tmp_path / "plan.json")
    text = path.read_text()
    doc = _strict(text)
    assert isinstance(doc, dict) and doc["format"] == "uavplan.plan/4"
    u = doc["uavs"][0]
    numbers = [u["cost"], *u["terms"].values(), *u["history"]]
    assert not any(isinstance(v, str) for v in numbers)  # format 2 wrote "inf" strings
    assert (u["cost"] is None) == (not np.isfinite(r.cost))
    assert [h is None for h in u["history"]] == [not np.isfinite(h) for h in r.history]
    PlanSpec.model_validate(doc)
    back = read_plan_file(path).uavs[0]
    assert back.cost == r.cost or (back.cost == np.inf and not np.isfinite(r.cost))


def test_format_2_infinity_strings_still_load() -> None:
    v2 = {"format": "uavplan.plan/2", "uavs": [
        {"id": "a", "waypoints": [[0, 0], [1, 0]], "times": [0, 1], "cost": "inf",
         "history": ["inf", 3.0]}]}  # fmt: skip
    assert parse_plan(v2).uavs[0].cost == np.inf
    PlanSpec.model_validate(v2)


def test_files_on_disk(tmp_path: Path, single_plan) -> None:  # type: ignore[no-untyped-def]
    path = write_plan_file(single_plan, tmp_path / "plan.json")
    assert read_plan_file(tmp_path).uavs[0].id == single_plan.results[0].uav_id  # the folder
    for bad, msg in ((tmp_path / "nope.json", "no such plan file"), (tmp_path, None)):
        if msg:
            with pytest.raises(PlanFormatError, match=msg):
                read_plan_file(bad)
    path.write_text("{oops")
    with pytest.raises(PlanFormatError, match="invalid JSON"):
        read_plan_file(path)
    path.write_bytes(b"\xff\xfe")
    with pytest.raises(PlanFormatError, match="cannot read"):
        read_plan_file(path)


def test_schema_command_and_schema() -> None:
    s = plan_schema()
    assert s["title"] == "uavplan plan file" and "uavs" in s["properties"]
    r = runner.invoke(app, ["schema", "plan"])
    assert r.exit_code == 0 and json.loads(r.output)["title"] == "uavplan plan file"
    r = runner.invoke(app, ["schema", "scenario"])
    assert r.exit_code == 0 and "properties" in json.loads(r.output)
    r = runner.invoke(app, ["schema", "mission"])
    assert r.exit_code == 2 and "not one of" in r.output


def test_planners_command_lists_and_describes() -> None:
    r = runner.invoke(app, ["planners"])
    assert r.exit_code == 0
    for name in available_planners():
        assert name in r.output
    r = runner.invoke(app, ["planners", "rrt-star"])
    assert r.exit_code == 0 and "step" in r.output and "goal_bias" in r.output
    r = runner.invoke(app, ["planners", "pso"])
    assert "pop_size" in r.output and "constraints" in r.output
    r = runner.invoke(app, ["planners", "nope"])
    assert r.exit_code == 2 and "unknown planner" in r.output


def test_export_csv_and_the_infeasible_warning(tmp_path: Path, single_plan, fleet_plan) -> None:  # type: ignore[no-untyped-def]
    write_plan_file(single_plan, tmp_path / "plan.json")
    r = runner.invoke(app, ["export", str(tmp_path), "--format", "csv"])
    rows = (tmp_path / "plan.csv").read_text().splitlines()
    assert rows[0] == "uav,point,time_s,x_m,y_m"
    assert len(rows) == 1 + len(single_plan.results[0].waypoints)
    assert r.exit_code == (0 if single_plan.feasible else 1)
    # an infeasible plan is written, but said loudly, and the exit code is 1
    doc = plan_document(fleet_plan)
    doc["feasible"] = False
    (tmp_path / "bad.json").write_text(json.dumps(doc))
    out = tmp_path / "fleet.csv"
    r = runner.invoke(app, ["export", str(tmp_path / "bad.json"), "-o", str(out)])
    assert r.exit_code == 1 and "WARNING" in r.output and "not feasible" in r.output
    n_flown = sum(len(x.flown_trajectory()[0]) for x in fleet_plan.results)
    assert out.read_text().count("\n") == 1 + n_flown  # the flown trajectories by default
    assert n_flown > sum(len(x.waypoints) for x in fleet_plan.results)  # curves, not corners
    # the polylines on request, said not to be what the plan guarantees
    r = runner.invoke(app, ["export", str(tmp_path / "bad.json"), "-o", str(out), "--polylines"])
    assert r.exit_code == 1 and "not the flown trajectories" in r.output
    assert out.read_text().count("\n") == 1 + sum(len(x.waypoints) for x in fleet_plan.results)
    r = runner.invoke(app, ["export", str(tmp_path / "bad.json"), "--polylines", "--smoothed"])
    assert r.exit_code == 2 and "at most one" in r.output
    r = runner.invoke(app, ["export", str(tmp_path / "bad.json"), "-o", str(out), "--smoothed"])
    assert r.exit_code == 2 and "no smoothed path" in r.output
    r = runner.invoke(app, ["export", str(tmp_path), "--format", "nope"])
    assert r.exit_code == 2 and "unknown export format 'nope'" in r.output
    assert "csv" in runner.invoke(app, ["export", "--list"]).output


@pytest.mark.parametrize("flag", ["--iterations", "--pop-size", "--waypoints"])
@pytest.mark.parametrize("value", ["0", "-3"])
def test_plan_refuses_budgets_below_one(tmp_path: Path, flag: str, value: str) -> None:
    r = runner.invoke(app, ["plan", "simple2d", flag, value, "--out", str(tmp_path / "o")])
    assert r.exit_code == 2 and f"{flag} {value}: must be at least 1" in r.output
    assert not (tmp_path / "o").exists()


def test_plan_help_lists_every_planner() -> None:
    r = runner.invoke(app, ["plan", "--help"])
    assert r.exit_code == 0
    for name in available_planners():
        assert name in r.output


def test_plan_summary_is_not_cut_when_piped(tmp_path: Path) -> None:
    r = runner.invoke(app, ["plan", "jacksboro", "-a", "pso", "--iterations", "3",
                            "--out", str(tmp_path / "o")])  # fmt: skip
    assert r.exit_code in (0, 1)
    assert "flight s" in r.output and "cpu s" in r.output and "…" not in r.output


def test_plan_takes_a_time_budget(tmp_path: Path) -> None:
    """--time alone: no iteration limit (RRT* keeps improving its tree until the time is up)."""
    args = ["plan", "simple2d", "-a", "rrt-star", "--param", "stop_at_goal=false", "--cost",
            "length", "--time", "0.5", "--out", str(tmp_path)]  # fmt: skip
    r = runner.invoke(app, args)
    assert r.exit_code == 0, r.output
    doc = json.loads((tmp_path / "plan.json").read_text())
    u = doc["uavs"][0]
    assert doc["feasible"] and u["cost_model"] == "length"
    assert u["cost"] == pytest.approx(u["length"])
    assert 0.4 < u["wall_time"] < 5.0
    r = runner.invoke(app, ["plan", "simple2d", "--time", "-1", "--out", str(tmp_path / "x")])
    assert r.exit_code == 2 and "--time -1.0: must be a positive number of seconds" in r.output


def test_plan_exits_1_when_the_verifier_rejects_its_plan(tmp_path: Path, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """Never unsafe called safe: `plan` runs the independent verifier on what it wrote."""
    from types import SimpleNamespace

    import uavplan.verify

    r = runner.invoke(app, ["plan", "simple2d", "--iterations", "20", "--out", str(tmp_path / "a")])
    assert r.exit_code == 0 and "independent verifier: every flown trajectory passes" in r.output

    bad = SimpleNamespace(
        kind="circles", message="uav0 enters circle 2 at t=1.000 s", uavs=("uav0",)
    )
    fake = SimpleNamespace(ok=False, violations=[bad], n_segments=3, model=None, uav_margins=[],
                           pair_margins=[])  # fmt: skip
    monkeypatch.setattr(uavplan.verify, "verify_trajectories", lambda *a, **k: fake)
    r = runner.invoke(app, ["plan", "simple2d", "--iterations", "20", "--out", str(tmp_path / "b")])
    assert r.exit_code == 1
    assert "UNSAFE" in r.output and "circles: uav0 enters circle 2" in r.output
    assert (tmp_path / "b" / "plan.json").exists()  # what was written stays, for inspection


def test_a_plan_that_does_not_fly_is_written_refused_loudly_and_exits_1(tmp_path: Path) -> None:
    """The goal walled in on every side: every planner and fallback fails; the plan is written
    for inspection, the console says NOT FLYABLE naming the UAV and how to learn why, exit 1."""
    sc = tmp_path / "boxed.yaml"
    sc.write_text(
        "name: boxed\nbounds: {lower: [0, 0], upper: [100, 100]}\npolygons:\n"
        "  - vertices: [[60, 30], [90, 30], [90, 35], [60, 35]]\n"
        "  - vertices: [[60, 65], [90, 65], [90, 70], [60, 70]]\n"
        "  - vertices: [[60, 30], [65, 30], [65, 70], [60, 70]]\n"
        "  - vertices: [[85, 30], [90, 30], [90, 70], [85, 70]]\n"
        "tasks:\n  - {id: uav0, start: [10, 50], goal: [75, 50]}\n"
    )
    out = tmp_path / "out"
    r = runner.invoke(app, ["plan", str(sc), "--iterations", "20", "--out", str(out)])
    assert r.exit_code == 1, r.output
    assert "NOT FLYABLE: 1 of 1 UAVs' flown trajectories fail a check (uav0)" in r.output
    assert f"uavplan explain {out}" in r.output
    assert json.loads((out / "plan.json").read_text())["feasible"] is False


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--waypoints", "5000"], "--waypoints 5000: at most 1000 free waypoints per path"),
        (["--pop-size", "10000000"], "exceeds the 20,000,000 path points a run may hold"),
    ],
)
def test_plan_refuses_sizes_beyond_limits(tmp_path: Path, args: list[str], message: str) -> None:
    r = runner.invoke(app, ["plan", "simple2d", *args, "--out", str(tmp_path)])
    assert r.exit_code == 2 and message in r.output
    assert not (tmp_path / "plan.json").exists()
