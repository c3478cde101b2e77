"""What ``uavplan plan`` does without ``-a``: the table by scenario kind, what it gives on the
built-in single-UAV scenes (feasible, no loop; seeds 0-9 on every built-in scenario, fleets
included, with ``-m slow``), and :func:`~uavplan.strategy.execute` carrying out a strategy:
best of runs, other planners, fallbacks, the repair after planning for every kind of fleet."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from uavplan.cli import app
from uavplan.planners import available_planners
from uavplan.scenarios import builtin_names, resolve
from uavplan.strategy import (
    TABLE,
    ScenarioKind,
    Strategy,
    best_plan,
    chosen,
    execute,
    run_seeds,
    strategy_for,
)
from uavplan.world.geometry import track_crosses_itself


def test_the_table_names_a_registered_planner_for_every_kind() -> None:
    assert set(TABLE) == set(ScenarioKind)
    for s in TABLE.values():
        assert s.planner in available_planners() and s.runs >= 1
        assert all(a in available_planners() for a in s.also)
        assert s.replanner in available_planners() and s.repair
    expect = {
        "simple2d": ("spso", ScenarioKind.SCENE_2D),
        "spso": ("spso", ScenarioKind.SINGLE_3D),
        "ppswarm1": ("ppswarm", ScenarioKind.FLEET),
        "ppswarm1-traffic": ("ppswarm", ScenarioKind.FLEET),
        "rscdwoa-static": ("rscdwoa-apf", ScenarioKind.FLEET_CONSTANT_SPEED),
        "rscdwoa-mixed": ("rscdwoa-apf", ScenarioKind.FLEET_CONSTANT_SPEED),
        "hrmaga-jacksboro": ("hr-maga", ScenarioKind.SINGLE_3D_UNKNOWN),
    }
    for name, (planner, kind) in expect.items():
        s = strategy_for(resolve(name))
        assert (s.planner, s.kind) == (planner, kind), name
    # a table of one's own changes the default without touching uavplan's
    mine = {**TABLE, ScenarioKind.SCENE_2D: Strategy("rrt-star", "mine", runs=2)}
    s = strategy_for(resolve("simple2d"), mine)
    assert (s.planner, s.runs, s.kind) == ("rrt-star", 2, ScenarioKind.SCENE_2D)
    assert strategy_for(resolve("simple2d")).planner == "spso"
    with pytest.raises(ValueError, match="at least one run"):
        Strategy("spso", "none", runs=0)


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


def test_a_plan_that_does_not_fly_falls_back(capsys: pytest.CaptureFixture[str]) -> None:
    """When the kept plan fails a check as flown, the fallbacks are tried in order and the
    first that flies is kept; the console says so (here RRT* with two iterations ends on the
    blocked straight line, a fallback RRT* as well, then the RGG's shortest path flies)."""
    from uavplan.cli.plan import _attempt_lines

    sc = resolve("simple2d")
    s = Strategy("rrt-star", "test", fallbacks=(("rrt-star", {"step": 1.0}), ("rgg", {})))
    outcome = execute(s, sc, 2, 0)
    assert [(a.role, a.planner, a.flies) for a in outcome.attempts] == [
        ("run", "rrt-star", False), ("fallback", "rrt-star", False), ("fallback", "rgg", True),
    ]  # fmt: skip
    assert outcome.kept == 2 and outcome.best == 0 and outcome.plan.algorithm == "rgg"
    _attempt_lines(outcome)
    text = capsys.readouterr().out
    assert "rrt-star's plan does not fly (uav0: circles" in text
    assert "rrt-star's plan does not fly (uav0: circles +2); trying the fallback rgg" in text
    assert "rgg's plan flies: it is the one written" in text
    # none flies: the first choice is kept, and the console says so
    none = execute(dataclasses.replace(s, fallbacks=(("rrt-star", {"step": 1.0}),)), sc, 2, 0)
    assert none.kept == 0 and not none.plan.feasible
    _attempt_lines(none)
    assert "no fallback's plan flies either: rrt-star's is written" in capsys.readouterr().out


def test_options_for_the_default_leave_only_that_planner() -> None:
    """Options set for the default planner (``--param``, ``--pop-size``, the scenario's planning
    options) turn off the other planners and the fallbacks: the user asked for that planner."""
    s = strategy_for(resolve("hrmaga-jacksboro"))
    assert s.also == ("spso",) and [n for n, _ in s.fallbacks] == ["rrt-star", "rgg-pso+"]
    plain = s.with_options({"pop_size": 10}).plain()
    assert plain.also == () and plain.fallbacks == () and plain.options == {"pop_size": 10}
    assert plain.runs == s.runs and plain.planner == "hr-maga"
    assert chosen("pso", {"pop_size": 4}, repair=False) == Strategy(
        "pso", "chosen", options={"pop_size": 4}, repair=False
    )


def test_fallbacks_scale_rrt_star_to_the_map() -> None:
    assert strategy_for(resolve("ppswarm1")).fallbacks == ()
    (name, opts), _ = strategy_for(resolve("jacksboro")).fallbacks
    assert name == "rrt-star" and 800 < opts["step"] < 900  # 2 % of a 43.6 km diagonal
    assert strategy_for(resolve("spso")).fallbacks[0][1]["step"] == 50.0  # its default, 1 km map


@pytest.mark.slow
@pytest.mark.parametrize("scenario", builtin_names())
def test_every_builtin_default_plan_flies_without_loops_seeds_0_to_9(
    tmp_path: Path, scenario: str
) -> None:
    """``uavplan plan NAME --seed S``, seeds 0-9, on every built-in scenario, is feasible as
    flown and no UAV's track crosses itself (``-m slow``; the fleets take about a minute a
    seed; ``benchmarks/default_paths.py`` adds the lengths against rival planners)."""
    for seed in range(10):
        out = tmp_path / str(seed)
        r = CliRunner().invoke(app, ["plan", scenario, "--seed", str(seed), "--out", str(out)])
        assert r.exit_code == 0, (seed, r.output)
        doc = json.loads((out / "plan.json").read_text())
        assert doc["feasible"] is True, seed
        for u in doc["uavs"]:
            assert not track_crosses_itself(np.asarray(u["waypoints"])), (seed, u["id"])


def test_run_seeds_start_with_the_root_and_are_reproducible() -> None:
    assert run_seeds(7, 1) == [7]
    s = run_seeds(7, 3)
    assert s[0] == 7 and len(set(s)) == 3 and s == run_seeds(7, 3)
    assert run_seeds(8, 3)[1:] != s[1:]


def test_best_plan_prefers_a_flying_plan_then_the_lowest_cost() -> None:
    from types import SimpleNamespace as NS

    def plan(cost: float, ok: bool) -> NS:
        return NS(feasible=ok, results=(NS(cost=cost),))

    a, b, c = plan(5.0, False), plan(9.0, True), plan(7.0, True)
    assert best_plan([a, b, c]) is c  # type: ignore[list-item]
    assert best_plan([a, plan(float("inf"), False)]) is a  # type: ignore[list-item]


def test_the_best_of_several_runs_is_kept_and_each_plans_alone(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Several runs: each root seed planned, the kept plan the best, each the plan the
    planner makes alone from its seed (``-a NAME --seed S``); the console lists them."""
    from uavplan.cli.plan import _attempt_lines

    sc = resolve("simple2d")
    s = Strategy("pso", "test", runs=3, options={"pop_size": 10}, repair=False)
    outcome = execute(s, sc, 5, 0)
    seeds = run_seeds(0, 3)
    assert [(a.role, a.seed) for a in outcome.attempts] == [("run", x) for x in seeds]
    assert outcome.attempts[outcome.kept].plan is best_plan([a.plan for a in outcome.attempts])
    for a in outcome.attempts:
        alone = execute(chosen("pso", {"pop_size": 10}, repair=False), sc, 5, a.seed).plan
        assert alone.results[0].cost == pytest.approx(a.cost, rel=1e-12)
    _attempt_lines(outcome)
    line = next(x for x in capsys.readouterr().out.splitlines() if x.startswith("runs ("))
    kept = outcome.attempts[outcome.kept]
    assert all(f"pso seed {x}: " in line for x in seeds)
    assert f"kept pso seed {kept.seed}, which `-a pso --seed {kept.seed}` plans alone" in line


def test_other_planners_run_once_beside_the_default() -> None:
    sc = resolve("simple2d")
    outcome = execute(Strategy("pso", "test", also=("rgg",), repair=False), sc, 3, 0)
    assert [(a.role, a.planner, a.seed) for a in outcome.attempts] == [
        ("run", "pso", 0), ("also", "rgg", 0),
    ]  # fmt: skip
    assert outcome.attempts[outcome.kept].plan is best_plan([a.plan for a in outcome.attempts])
    assert "and of rgg once" in Strategy("pso", "t", also=("rgg",)).describe()


def test_a_constant_speed_fleet_is_repaired_like_any_other() -> None:
    """The constant-speed default (RSCDWOA-APF in the prioritized frame) goes through the same
    repair after planning as a fleet planner's: here two UAVs' loops are cut."""
    sc = resolve("ppswarm1@3")
    sc = dataclasses.replace(sc, uav=dataclasses.replace(sc.uav, min_speed=sc.uav.speed))
    s = strategy_for(sc)
    assert s.kind is ScenarioKind.FLEET_CONSTANT_SPEED and s.planner == "rscdwoa-apf"
    assert s.repair and s.fallbacks == ()
    plan = execute(s, sc, 10, 0).plan
    assert plan.fleet is not None and plan.fleet.info.get("repair")
    raw = execute(dataclasses.replace(s, repair=False), sc, 10, 0).plan
    assert raw.fleet is not None and "repair" not in raw.fleet.info


def test_a_generated_fleet_that_the_tracking_error_pushes_out_is_placed_again() -> None:
    """``ppswarm4@1000`` stacks four altitude layers in the 100-200 m band, the top one 5 m under
    the ceiling: under a small fixed wing's 8 m vertical tracking error some tasks leave the
    band, so the fleet is placed again in the widened world (the given world gets the same
    tasks, for the verifier); ``--nominal`` keeps the first placement."""
    import numpy as np

    from uavplan.scenarios import resolve
    from uavplan.strategy import planning_world

    sc = resolve("ppswarm4@1000")
    pw = planning_world(sc, "ppswarm4@1000")
    assert pw.replaced > 0 and pw.tasks_line() is not None
    assert len(pw.world.tasks) == 1000 and pw.given is not None
    assert [t.start for t in pw.given.tasks] == [t.start for t in pw.world.tasks]
    for t in pw.world.tasks:
        for p in (t.start, t.goal):
            assert not pw.world.point_problems(np.asarray(p, dtype=np.float64))
    nominal = planning_world(sc, "ppswarm4@1000", nominal=True)
    assert nominal.replaced == 0 and nominal.world.tasks == sc.tasks


def test_commands_reading_a_plan_place_its_generated_fleet_as_the_plan_did() -> None:
    """A plan of ``ppswarm4@1000`` made under the default model flies the fleet placed again:
    the commands that read it (``verify``, ``explain``) place it the same way from the plan's
    execution record when the plan's paths start there, and keep the scenario's own placement
    for a nominal plan or paths that start elsewhere."""
    from uavplan.cli._common import world_of_plan
    from uavplan.scenarios import resolve
    from uavplan.strategy import planning_world
    from uavplan.strategy.world import fleet_as_planned

    sc = resolve("ppswarm4@1000")
    pw = planning_world(sc, "ppswarm4@1000")
    record = pw.model.record()
    placed = fleet_as_planned(sc, "ppswarm4@1000", record)
    assert [t.start for t in placed.tasks] == [t.start for t in pw.world.tasks] != [
        t.start for t in sc.tasks]  # fmt: skip
    assert fleet_as_planned(sc, "ppswarm4@1000", None) is sc
    starts = {t.id: t.start for t in pw.world.tasks[:50]}
    assert world_of_plan(sc, "ppswarm4@1000", record, starts).tasks == placed.tasks
    first = {t.id: t.start for t in sc.tasks[:50]}
    assert world_of_plan(sc, "ppswarm4@1000", record, first) is sc


def test_a_world_refusing_many_tasks_names_the_first_few_and_counts_the_rest() -> None:
    """A fleet file's 1,000 tasks, spaced 45 m (three layers, the outer two too near the band's
    ends for an 8 m vertical tracking error): the error is a few lines, not 1,300."""
    import dataclasses

    import pytest

    from uavplan.scenarios import resolve
    from uavplan.strategy import WorldProblem, planning_world
    from uavplan.world.fleet_tasks import with_fleet

    sc = with_fleet(resolve("ppswarm2"), 1000, seed=0, min_spacing=45.0)
    with pytest.raises(WorldProblem) as exc:
        planning_world(dataclasses.replace(sc, name="fleet.yaml"), "fleet.yaml")
    lines = exc.value.problems
    assert len(lines) == 6 and "task uav0" in lines[0]
    assert lines[-1].startswith("fleet.yaml: ... and ") and "more starts and goals" in lines[-1]
