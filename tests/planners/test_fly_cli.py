"""``uavplan fly``: plans, reveals the unknown area in flight, repairs, verifies the flown
trajectory; bad input exits 2 with one line."""

from __future__ import annotations

import json
from pathlib import Path

from typer.testing import CliRunner

from uavplan.cli import app


def test_fly_repairs_and_verifies(tmp_path: Path) -> None:
    out = tmp_path / "mission.json"
    res = CliRunner().invoke(
        app,
        ["fly", "hrmaga-popup", "--iterations", "100", "--seed", "0", "--nominal", "-o", str(out)],
    )
    assert res.exit_code == 0, res.output
    assert "1 area(s) unknown at take-off" in res.output
    assert "area 0 seen at t=" in res.output and "repair, detour" in res.output
    assert "verified" in res.output
    m = json.loads(out.read_text())
    assert m["feasible"] is True and m["events"][0]["action"] == "repair"
    assert len(m["waypoints"]) == len(m["times"]) and m["times"] == sorted(m["times"])


def test_fly_bad_input_exits_2() -> None:
    r = CliRunner().invoke(app, ["fly", "no-such-scenario"])
    assert r.exit_code == 2 and "Traceback" not in r.output
    r = CliRunner().invoke(app, ["fly", "hrmaga-popup", "--sensor-range", "1"])
    assert r.exit_code == 2 and "sensor range 1 m" in r.output


def test_fly_a_plan_file(tmp_path: Path) -> None:
    """``uavplan fly PLAN.json``: the plan's own scenario, UAV, planner and options repair it;
    ``-a`` another planner; a wrong UAV or a file that is not a plan exits 2 with one line."""
    runner = CliRunner()
    res = runner.invoke(
        app, ["plan", "hrmaga-popup", "-a", "hr-maga", "--iterations", "60", "--nominal",
              "--out", str(tmp_path)]
    )  # fmt: skip
    assert res.exit_code in (0, 1), res.output
    plan = tmp_path / "plan.json"
    out = tmp_path / "mission.json"
    res = runner.invoke(app, ["fly", str(plan), "-o", str(out)])
    assert res.exit_code in (0, 1), res.output
    assert "hrmaga-popup: hr-maga" in res.output and "area 0 seen at t=" in res.output
    assert "execution model: nominal" in res.output  # the plan's own model
    first = json.loads(plan.read_text())["uavs"][0]["waypoints"]
    m = json.loads(out.read_text())
    assert m["waypoints"][0] == first[0] and m["events"][0]["action"] == "repair"
    assert (res.exit_code == 0) == m["feasible"]
    res = runner.invoke(app, ["fly", str(tmp_path), "-a", "p-maga", "--iterations", "5"])
    assert "hrmaga-popup: p-maga" in res.output and "from scratch" in res.output
    for args, msg in (
        ([str(plan), "--uav", "nope"], "--uav 'nope' is not in the plan (it has uav0)"),
        (["hrmaga-popup", "ppswarm1"], "a second argument and --uav are for a plan file"),
    ):
        r = runner.invoke(app, ["fly", *args])
        assert r.exit_code == 2 and msg in r.output and "Traceback" not in r.output
    bad = tmp_path / "bad.json"
    bad.write_text('{"uavs": 3}')
    r = runner.invoke(app, ["fly", str(bad)])
    assert r.exit_code == 2 and "uavs: expected a non-empty list, got 3" in r.output


def test_fly_repairs_and_verifies_under_the_execution_model(tmp_path: Path) -> None:
    """Without --nominal the mission is planned and repaired in the world widened by the
    default model and verified against the world as given under that model."""
    res = CliRunner().invoke(app, ["fly", "hrmaga-popup", "--iterations", "30"])
    assert res.exit_code == 0, res.output
    assert "execution model: take-off ±2 s" in res.output
    assert "verified under the execution model" in res.output
