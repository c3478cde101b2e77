"""The planner a user gets without -a (issue 17 item 1): by scenario kind, and what it gives on
the built-in single-UAV scenes: feasible, no loop, no self-crossing (seeds 0-2 on two scenes in
the default run; seeds 0-9 on every built-in scenario, fleets included, with ``-m slow``)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from uavplan.cli import app
from uavplan.planners import available_planners
from uavplan.planners.defaults import DEFAULTS, default_planner
from uavplan.scenarios import builtin_names, resolve
from uavplan.world.geometry import track_crosses_itself


def test_defaults_are_registered_planners_by_kind() -> None:
    for d in DEFAULTS.values():
        assert d.planner in available_planners() and d.runs >= 1
    assert default_planner(resolve("simple2d"))[:2] == ("spso", "2-D scene")
    assert default_planner(resolve("spso"))[:2] == ("spso", "3-D single UAV")
    assert default_planner(resolve("ppswarm1"))[:2] == ("ppswarm", "fleet")
    assert default_planner(resolve("ppswarm1-traffic"))[:2] == ("ppswarm", "fleet")
    for name in ("rscdwoa-static", "rscdwoa-mixed"):  # fixed-wing, one speed
        assert default_planner(resolve(name))[:2] == ("rscdwoa-apf", "fleet of constant-speed UAVs")
    assert default_planner(resolve("hrmaga-jacksboro"))[:2] == (
        "hr-maga",
        "3-D single UAV with danger or uncertain areas",
    )


@pytest.mark.parametrize("scenario", ["simple2d", "spso"])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_default_plan_is_feasible_without_loops(
    tmp_path: Path, scenario: str, seed: int
) -> None:
    r = CliRunner().invoke(app, ["plan", scenario, "--seed", str(seed), "--out", str(tmp_path)])
    assert r.exit_code == 0, r.output
    assert "planner: spso (the default" in r.output
    doc = json.loads((tmp_path / "plan.json").read_text())
    assert doc["feasible"] is True
    P = np.asarray(doc["uavs"][0]["waypoints"])[:, :2]
    assert not track_crosses_itself(P)
    straight = float(np.linalg.norm(P[-1] - P[0]))
    assert doc["uavs"][0]["length"] < 1.6 * straight  # no detour of a loop's size


def test_first_sentence_keeps_abbreviations() -> None:
    from uavplan.planners.registry import first_sentence

    doc = "P-MAGA (HR-MAGA Alg. 1): agents,\n    crossover. More here.\n\nOther paragraph."
    assert first_sentence(doc) == "P-MAGA (HR-MAGA Alg. 1): agents, crossover."
    assert first_sentence("RRT* as a planner; see the module docstring") == "RRT* as a planner"
    assert first_sentence("One line, no stop") == "One line, no stop"


def test_polish_shortens_by_line_of_sight_and_never_costs_more() -> None:
    from uavplan.planners import get_planner

    sc = resolve("spso")
    planner = get_planner("spso", pop_size=60)
    raw = planner.plan(sc, budget=30, seed=3)
    pol = planner.plan(sc, budget=30, seed=3, polish=True)
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
    pol = planner.plan(sc, budget=30, seed=0, polish=True)
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


def test_a_default_plan_that_does_not_fly_falls_back(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Without -a, when the default's plan fails a check as flown, the fallbacks are tried in
    order and the first that flies is written, and the console says so (here the default is
    made RRT* with two iterations, which ends on the blocked straight line, and the fallbacks
    a planner that fails as well, then the RGG's shortest path)."""
    import uavplan.planners.defaults as D

    monkeypatch.setitem(D.DEFAULTS, "2-D scene", D.Default("rrt-star", "test"))
    monkeypatch.setattr(
        D, "fallback_planners", lambda sc: [("rrt-star", {"step": 1.0}), ("rgg", {})]
    )
    args = ["plan", "simple2d", "--iterations", "2", "--out", str(tmp_path)]
    r = CliRunner().invoke(app, args)
    assert r.exit_code == 0, r.output
    assert "rrt-star's plan does not fly (uav0: circles" in r.output
    assert "trying the fallback rrt-star" in r.output
    assert "rrt-star's plan does not fly (uav0: circles +2); trying the fallback rgg" in r.output
    assert "rgg's plan flies: it is the one written" in r.output
    doc = json.loads((tmp_path / "plan.json").read_text())
    assert doc["algorithm"] == "rgg" and doc["feasible"] is True
    # options for the default turn the fallbacks off: the user asked for that planner
    r = CliRunner().invoke(app, [*args, "--param", "goal_bias=0.1"])
    assert r.exit_code == 1 and "fallback" not in r.output


def test_fallbacks_scale_rrt_star_to_the_map() -> None:
    from uavplan.planners.defaults import fallback_planners

    assert fallback_planners(resolve("ppswarm1")) == []
    (name, opts), _ = fallback_planners(resolve("jacksboro"))
    assert name == "rrt-star" and 800 < opts["step"] < 900  # 2 % of a 43.6 km diagonal
    assert fallback_planners(resolve("spso"))[0][1]["step"] == 50.0  # its default, 1 km map


@pytest.mark.slow
@pytest.mark.parametrize("scenario", builtin_names())
def test_every_builtin_default_plan_flies_without_loops_seeds_0_to_9(
    tmp_path: Path, scenario: str
) -> None:
    """Issue 17's figure as a test (``-m slow``; the fleets take about a minute a seed):
    ``uavplan plan NAME --seed S``, seeds 0-9, on every built-in scenario, is feasible as flown
    and no UAV's track crosses itself (``benchmarks/default_paths.py`` adds the lengths against
    rival planners)."""
    for seed in range(10):
        out = tmp_path / str(seed)
        r = CliRunner().invoke(app, ["plan", scenario, "--seed", str(seed), "--out", str(out)])
        assert r.exit_code == 0, (seed, r.output)
        doc = json.loads((out / "plan.json").read_text())
        assert doc["feasible"] is True, seed
        for u in doc["uavs"]:
            assert not track_crosses_itself(np.asarray(u["waypoints"])), (seed, u["id"])


def test_run_seeds_start_with_the_root_and_are_reproducible() -> None:
    from uavplan.planners.defaults import run_seeds

    assert run_seeds(7, 1) == [7]
    s = run_seeds(7, 3)
    assert s[0] == 7 and len(set(s)) == 3 and s == run_seeds(7, 3)
    assert run_seeds(8, 3)[1:] != s[1:]


def test_best_plan_prefers_a_flying_plan_then_the_lowest_cost() -> None:
    from types import SimpleNamespace as NS

    from uavplan.planners.defaults import best_plan

    def plan(cost: float, ok: bool) -> NS:
        return NS(feasible=ok, results=(NS(cost=cost),))

    a, b, c = plan(5.0, False), plan(9.0, True), plan(7.0, True)
    assert best_plan([a, b, c]) is c  # type: ignore[list-item]
    assert best_plan([a, plan(float("inf"), False)]) is a  # type: ignore[list-item]


def test_the_default_keeps_the_best_of_its_runs(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A kind whose default makes several runs: each root seed planned, the console lists them,
    the kept plan is the lowest cost and plan.json carries its own seed, which plans it alone."""
    import uavplan.planners.defaults as D

    monkeypatch.setitem(D.DEFAULTS, "2-D scene", D.Default("pso", "test", runs=3))
    args = ["plan", "simple2d", "--iterations", "5", "--pop-size", "10", "--raw"]
    r = CliRunner().invoke(app, [*args, "--out", str(tmp_path / "a")])
    assert r.exit_code in (0, 1), r.output
    assert "the best of 3 runs" in r.output
    line = next(x for x in r.output.splitlines() if x.startswith("runs ("))
    seeds = D.run_seeds(0, 3)
    keys = []
    for s in seeds:
        assert f"pso seed {s}: " in line
        one = CliRunner().invoke(app, ["plan", "simple2d", "-a", "pso", "--seed", str(s),
                                       *args[2:], "--out", str(tmp_path / str(s))])  # fmt: skip
        assert one.exit_code in (0, 1)
        d = json.loads((tmp_path / str(s) / "plan.json").read_text())
        keys.append((not d["feasible"], d["uavs"][0]["cost"]))
    doc = json.loads((tmp_path / "a" / "plan.json").read_text())
    k = min(range(3), key=lambda i: keys[i])
    assert doc["seed"] == seeds[k]
    assert doc["uavs"][0]["cost"] == pytest.approx(keys[k][1], rel=1e-12)


def test_the_default_also_runs_other_planners_and_keeps_the_best(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``also``: another planner runs once with the root seed; the best plan of all is written
    under its own planner's name."""
    import uavplan.planners.defaults as D

    monkeypatch.setitem(D.DEFAULTS, "2-D scene", D.Default("pso", "test", also=("rgg",)))
    args = ["plan", "simple2d", "--iterations", "3", "--out", str(tmp_path), "--raw"]
    r = CliRunner().invoke(app, args)
    assert r.exit_code in (0, 1), r.output
    assert "and of rgg once" in r.output
    line = next(x for x in r.output.splitlines() if x.startswith("runs ("))
    assert "pso seed 0: " in line and "rgg seed 0: " in line
    doc = json.loads((tmp_path / "plan.json").read_text())
    assert doc["algorithm"] in ("pso", "rgg") and f"kept {doc['algorithm']} seed 0" in line
