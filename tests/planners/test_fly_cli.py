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
        app, ["fly", "hrmaga-popup", "--iterations", "100", "--seed", "0", "-o", str(out)]
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
