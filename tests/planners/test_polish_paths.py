"""A single UAV's path polished after planning (line of sight, terrain following), ``--raw``
keeping the optimizer's path, and the planner's flight check along whole segments."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from uavplan.cli import app
from uavplan.planners.polish import polished
from uavplan.scenarios import resolve
from uavplan.world.geometry import track_crosses_itself


def test_first_sentence_keeps_abbreviations() -> None:
    from uavplan._text import first_sentence

    doc = "P-MAGA (HR-MAGA Alg. 1): agents,\n    crossover. More here.\n\nOther paragraph."
    assert first_sentence(doc) == "P-MAGA (HR-MAGA Alg. 1): agents, crossover."
    assert first_sentence("RRT* as a planner; see the module docstring") == "RRT* as a planner"
    assert first_sentence("One line, no stop") == "One line, no stop"


def test_polish_shortens_by_line_of_sight_and_never_costs_more() -> None:
    from uavplan.planners import get_planner

    sc = resolve("spso")
    planner = get_planner("spso", pop_size=60)
    raw = planner.plan(sc, budget=30, seed=3)
    pol = planner.plan(sc, budget=30, seed=3, polish=polished)
    assert np.array_equal(raw.waypoints[0], pol.waypoints[0])
    assert np.array_equal(raw.waypoints[-1], pol.waypoints[-1])
    note = pol.info.get("polished")
    assert note  # this seed's path has corners to cut (12 points -> 4)
    assert len(pol.waypoints) < len(raw.waypoints) and pol.feasible
    assert pol.cost <= raw.cost + 1e-9 and note["cost"][0] == pytest.approx(raw.cost)
    assert "polished" not in raw.info


def test_polish_follows_the_terrain_where_the_flight_leaves_the_band() -> None:
    """SPSO on jacksboro (band 50-300 m above a rugged DEM, checked along whole segments in
    flight; the optimizer's problem checks it at the waypoints, as the SPSO paper does): the
    raw path is feasible for its problem and does not fly; polished, it flies, on the same
    horizontal track's vertices."""
    from uavplan.planners import get_planner

    sc = resolve("jacksboro")
    planner = get_planner("spso", pop_size=50, constraints="feasibility-first")
    raw = planner.plan(sc, budget=30, seed=0)
    pol = planner.plan(sc, budget=30, seed=0, polish=polished)
    assert raw.feasible and not raw.flown_feasible and "altitude" in raw.flown_violations
    assert pol.feasible and pol.flown_feasible
    assert pol.info["polished"]["steps"][:2] == ["terrain following", "shortcut"]
    assert not track_crosses_itself(np.asarray(pol.waypoints))


def test_plan_raw_keeps_the_optimizers_path(tmp_path: Path) -> None:
    r = CliRunner().invoke(app, ["plan", "simple2d", "--raw", "--nominal", "--out", str(tmp_path)])
    assert r.exit_code == 0, r.output
    doc = json.loads((tmp_path / "plan.json").read_text())
    assert "polished" not in doc["uavs"][0]["info"]
    r = CliRunner().invoke(app, ["plan", "simple2d", "--nominal", "--out", str(tmp_path / "p")])
    doc2 = json.loads((tmp_path / "p" / "plan.json").read_text())
    assert (
        doc2["uavs"][0]["info"]["polished"]["points"][1]
        < doc2["uavs"][0]["info"]["polished"]["points"][0]
    )
    assert doc2["uavs"][0]["cost"] <= doc["uavs"][0]["cost"]


def test_flight_check_plans_against_the_band_along_segments() -> None:
    """flight_check=true: the optimizer's problem checks the altitude band along whole
    segments, as the declared flight is checked, so a polyline it calls feasible flies."""
    from uavplan.planners import get_planner

    sc = resolve("spso")
    plain = get_planner("spso", pop_size=60)
    strict = get_planner("spso", pop_size=60, flight_check=True)
    assert not plain.problem(sc, sc.tasks[0]).strict_altitude
    assert strict.problem(sc, sc.tasks[0]).strict_altitude
    for seed in (0, 1):
        r = strict.plan(sc, budget=30, seed=seed)
        assert (not r.feasible) or r.flown_feasible
    assert strict.describe()["flight_check"] is True
