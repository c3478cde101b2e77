"""``uavplan explain``: a plan's story per UAV from its diagnostics, and its failures as the
independent verifier finds them (which UAVs, when, by how much); the diagnostics section as
plan.json writes it."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from uavplan.cli import app
from uavplan.planners.core.events import KINDS, Event


@pytest.fixture(scope="module")
def fleet_plan(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("explain") / "p"
    r = CliRunner().invoke(app, ["plan", "ppswarm1@6", "--iterations", "5", "--seed", "1",
                                 "--out", str(out)])  # fmt: skip
    assert r.exit_code == 0, r.output
    return out


def test_the_diagnostics_section_tells_each_uavs_rescue(fleet_plan: Path) -> None:
    doc = json.loads((fleet_plan / "plan.json").read_text())
    diag = doc["diagnostics"]
    assert diag["schema"] == "uavplan.diagnostics/1"
    events = [Event.from_record(e) for e in diag["events"]]
    late = doc["fleet"]["info"]["delayed"]  # the engine's own record
    told = {e.uav: e.value for e in events if e.kind in ("waited", "delayed")}
    assert late and told == {u: pytest.approx(s) for u, s in late.items()}
    restarts = [e for e in events if e.kind == "restart"]
    assert len(restarts) == len(doc["fleet"]["restart_costs"]) and any(
        "(kept)" in e.detail for e in restarts
    )
    # each restart's UAVs left failing are kept (a restart with any has an infinite cost), and
    # its event names them
    failed = doc["fleet"]["info"]["restart_failed"]
    assert len(failed) == len(restarts)
    for e, left, c in zip(restarts, failed, doc["fleet"]["restart_costs"], strict=True):
        assert not left or c is None, (e, left, c)
        assert all(u in e.detail for u in left[:8]) and ("left failing" in e.detail) == bool(left)
    from uavplan.io.plan_file import PlanSpec

    PlanSpec.model_validate(doc)  # the schema holds the section
    r = CliRunner().invoke(app, ["explain", str(fleet_plan)])
    assert r.exit_code == 0, r.output
    assert "the planner says it flies; the verifier agrees" in r.output
    for uav, s in late.items():
        assert f"{uav}:\n  waited: " in r.output and f"taking off {s:g} s later" in r.output


def test_explain_names_the_pair_and_the_time_of_a_separation_failure(
    fleet_plan: Path, tmp_path: Path
) -> None:
    """uav0's flight replaced by uav1's, 3 m to the east and on uav1's times: the verifier
    finds them closer than S2, and explain says which two and when."""
    doc = json.loads((fleet_plan / "plan.json").read_text())
    a, b = doc["uavs"][0], doc["uavs"][1]
    pts = np.asarray(b["flown"]["points"], dtype=float) + np.array([3.0, 0.0, 0.0])
    a["flown"] = {**b["flown"], "points": pts.tolist()}
    a["waypoints"], a["times"] = pts[[0, -1]].tolist(), [b["flown"]["times"][0],
                                                        b["flown"]["times"][-1]]  # fmt: skip
    bad = tmp_path / "plan.json"
    bad.write_text(json.dumps(doc))
    r = CliRunner().invoke(app, ["explain", str(bad)])
    assert r.exit_code == 1, r.output
    assert "the verifier finds" in r.output
    line = next(x for x in r.output.splitlines() if "FAILS separation" in x)
    assert f"{a['id']} and {b['id']}" in line and " m apart at t=" in line
    t = float(line.split(" at t=")[1].split(" s")[0])
    assert b["flown"]["times"][0] <= t <= b["flown"]["times"][-1]
    # both UAVs are told, each with the failure
    assert r.output.count("FAILS separation") >= 2


def test_events_are_typed() -> None:
    with pytest.raises(ValueError, match="unknown event kind"):
        Event("teleported", "uav0", "no")
    e = Event("waited", "uav3", "takes off 10 s later", 10.0)
    assert Event.from_record(e.record()) == e
    inf = Event("restart", None, "2: a UAV left infeasible", float("inf"))
    assert inf.record()["value"] is None
    from typing import get_args

    from uavplan.io.plan_file import EventSpec

    assert set(get_args(EventSpec.model_fields["kind"].annotation)) == set(KINDS)


def test_explain_bad_input(tmp_path: Path) -> None:
    r = CliRunner().invoke(app, ["explain", str(tmp_path / "missing.json")])
    assert r.exit_code == 2 and "Traceback" not in r.output


def test_a_large_fleets_story_puts_the_failures_first_and_tells_mass_rescues_by_kind() -> None:
    """30 UAVs that waited, one repaired, one failing: the failing UAV leads with the
    verifier's finding, the repaired one follows, and the 30 waits are one line with their
    span; with ``everyone`` each UAV has its line."""
    from types import SimpleNamespace

    from uavplan.cli.explain import LIST_MAX, story_lines

    ids = [f"uav{i}" for i in range(40)]
    events = [Event("waited", f"uav{i}", f"takes off {5 * i:g} s later", 5.0 * i)
              for i in range(1, 31)]  # fmt: skip
    events += [Event("repaired", "uav31", "re-flown after planning: RRT* (try 1)"),
               Event("unresolved", "uav32", "its flight fails: separation")]  # fmt: skip
    doc = {"uavs": [{"id": u} for u in ids],
           "diagnostics": {"events": [e.record() for e in events]}}  # fmt: skip
    finding = SimpleNamespace(kind="separation", uavs=("uav32", "uav33"), message="too close")
    lines = story_lines(doc, SimpleNamespace(violations=[finding]))
    assert LIST_MAX < 30
    assert lines[:2] == ["fails (2 UAV(s)):", "uav32:"]
    assert lines[2:4] == ["  unresolved: its flight fails: separation",
                          "  FAILS separation: too close"]  # fmt: skip
    assert lines.index("repaired after planning (1 UAV(s)):") > lines.index("uav33:")
    waited = [x for x in lines if x.startswith("  waited:")]
    assert len(waited) == 1 and "30 UAV(s)" in waited[0] and "5-150 s later" in waited[0]
    assert lines[-1] == "7 other UAV(s) fly their first planned flight (--all lists every UAV)"
    every = story_lines(doc, SimpleNamespace(violations=[finding]), everyone=True)
    assert sum(x.startswith("  waited:") for x in every) == 30
    assert sum(x.endswith("flies its first planned flight") for x in every) == 7


def test_a_discarded_restarts_failures_are_named() -> None:
    """The restart events read the engine's record of each restart's UAVs left failing."""
    import dataclasses

    from uavplan.planners import get_planner
    from uavplan.planners.core.events import plan_events
    from uavplan.planners.fleet.fleet_plan import plan_all
    from uavplan.scenarios import resolve

    plan = plan_all(resolve("ppswarm1@3"), get_planner("ppswarm", n_iter=2, n_restart=2), None, 0)
    assert plan.fleet is not None and len(plan.fleet.info["restart_failed"]) == 2
    left = [f"uav{i}" for i in range(10)]
    fleet = dataclasses.replace(
        plan.fleet,
        restart_costs=(1.0, float("inf")),
        info={**plan.fleet.info, "best_restart": 1, "restart_failed": [[], left]},
    )
    restarts = [e for e in plan_events(dataclasses.replace(plan, fleet=fleet))
                if e.kind == "restart"]  # fmt: skip
    assert [e.detail for e in restarts] == [
        "1: cost 1 (kept)",
        "2: 10 UAV(s) left failing: uav0, uav1, uav2, uav3, uav4, uav5, uav6, uav7 and 2 more",
    ]
