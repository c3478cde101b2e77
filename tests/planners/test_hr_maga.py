"""HR-MAGA (Alg. 2): a continuous start-to-goal path of num ** v segments that clears the
terrain and every revealed uncertain area on the finest map; uncertain areas unknown on the
first level; segment ends moved out of them."""

from __future__ import annotations

import dataclasses
import itertools
import math

import numpy as np
import pytest

from uavplan.planners import PlannerError, get_planner
from uavplan.planners.population.hr_maga import HRMAGA
from uavplan.problems.path_problem import PathProblem
from uavplan.world.obstacles import DangerArea, UncertainArea
from uavplan.world.pyramid import terrain_pyramid
from uavplan.world.scenario import UAV, AltitudeBand, Bounds, Scenario, Task
from uavplan.world.terrain import Terrain


def hills() -> Scenario:
    """A 2 km x 2 km map of hills (20 m cells), an uncertain area and a danger area on the
    straight line, a band 30-250 m above ground."""
    x = np.arange(0, 2001, 20.0)
    X, Y = np.meshgrid(x, x)
    H = (
        150 * np.exp(-((X - 700) ** 2 + (Y - 600) ** 2) / 2e5)
        + 120 * np.exp(-((X - 1300) ** 2 + (Y - 1400) ** 2) / 1.5e5)
        + 20 * np.sin(X / 130) * np.cos(Y / 170)
    )
    t = Terrain(H, 0.0, 0.0, 20.0, 20.0, "hills")
    s = (100.0, 100.0, float(t.height(100.0, 100.0)) + 100.0)
    g = (1900.0, 1900.0, float(t.height(1900.0, 1900.0)) + 100.0)
    return Scenario(
        "hills",
        Bounds((0.0, 0.0, -50.0), (2000.0, 2000.0, 600.0)),
        (Task("uav0", s, g),),
        terrain=t,
        danger_areas=(DangerArea((1400.0, 1300.0), 150.0),),
        uncertain_areas=(UncertainArea(850.0, 850.0, 300.0, 300.0, revealed=True),),
        altitude=AltitudeBand(30.0, 250.0, "ground"),
        uav=UAV(speed=20.0),
        cost="hrmaga",
        n_waypoints=5,
    )


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_hr_maga_path_is_continuous_and_clear_on_the_finest_map(seed: int) -> None:
    sc = hills()
    r = get_planner("hr-maga").plan(sc, budget=150, seed=seed)
    w = r.waypoints
    assert w.shape == (28, 3)  # 3 ** 3 segments
    assert np.allclose(w[0], sc.tasks[0].start) and np.allclose(w[-1], sc.tasks[0].goal)
    assert r.feasible and r.flown_feasible, r.violations
    ev = PathProblem(sc, strict_altitude=True).evaluate(w[None])
    assert bool(ev.feasible[0])  # the terrain and the revealed area, along whole segments
    a = sc.uncertain_areas[0]
    dense = np.concatenate([np.linspace(p, q, 200) for p, q in itertools.pairwise(w)])
    inside = (
        (dense[:, 0] > a.x) & (dense[:, 0] < a.x + a.width)
        & (dense[:, 1] > a.y) & (dense[:, 1] < a.y + a.height)
    )  # fmt: skip
    assert not inside.any()
    assert np.all(dense[:, 2] >= sc.terrain.height(dense[:, 0], dense[:, 1]) + 30 - 1e-6)
    # the three best paths, best first, the returned one among them
    costs = r.info["costs"]
    assert len(r.info["paths"]) == 3 and costs == sorted(costs)
    assert np.allclose(r.info["paths"][0], w) and costs[0] == pytest.approx(r.cost)
    assert r.info["factors"] == [2, 2, 1]  # 100 cells per side: 2.5 -> 2 on the first level


def test_uncertain_areas_unknown_on_the_first_level() -> None:
    sc = hills()
    hr = HRMAGA()
    levels = terrain_pyramid(sc.terrain, 3)
    first = hr._level_scenario(sc, levels[0], 1)
    second = hr._level_scenario(sc, levels[1], 2)
    assert not first.uncertain_areas[0].revealed and not first.no_fly_polygons
    assert second.uncertain_areas[0].revealed and len(second.no_fly_polygons) == 1
    assert first.terrain is levels[0].feasibility
    # an area the scenario keeps unrevealed (revealed in flight) is unknown on every level
    hidden = dataclasses.replace(
        sc, uncertain_areas=(dataclasses.replace(sc.uncertain_areas[0], revealed=False),)
    )
    assert not hr._level_scenario(hidden, levels[2], 3).no_fly_polygons


def test_segment_end_moves_to_the_nearest_point_outside_the_area() -> None:
    sc = hills()
    lv = hr_level(sc)
    a = sc.uncertain_areas[0]  # x 850-1150, y 850-1150
    q = HRMAGA._admit(np.array([900.0, 1000.0, 500.0]), [a], lv)
    assert q[0] == pytest.approx(849.0) and q[1] == 1000.0  # the west edge is nearest
    ground = float(lv.terrain.height(q[0], q[1]))
    assert ground + 30 <= q[2] <= ground + 250  # back in the band over this level's map
    q = HRMAGA._admit(np.array([1000.0, 1140.0, ground + 100]), [a], lv)
    assert q[1] == pytest.approx(1151.0) and q[0] == 1000.0
    outside = np.array([500.0, 500.0, float(lv.terrain.height(500.0, 500.0)) + 100])
    assert np.array_equal(HRMAGA._admit(outside, [a], lv), outside)


def admit_reference(p, areas, sc, level=None):  # type: ignore[no-untyped-def]
    """Sect. III-C's move and the band, one point at a time in plain Python (the first form of
    ``HRMAGA._admit``): the reference of :meth:`HRMAGA._admit_all`."""
    from uavplan.planners.population.hr_maga import _lookup

    q = p.copy()
    lo, hi = sc.bounds.lo, sc.bounds.hi
    for _ in range(len(areas) + 1):
        inside = [
            a for a in areas if a.x <= q[0] <= a.x + a.width and a.y <= q[1] <= a.y + a.height
        ]
        if not inside:
            break
        a = inside[0]
        cands = [
            (q[0] - a.x, (a.x - 1.0, q[1])),
            (a.x + a.width - q[0], (a.x + a.width + 1.0, q[1])),
            (q[1] - a.y, (q[0], a.y - 1.0)),
            (a.y + a.height - q[1], (q[0], a.y + a.height + 1.0)),
        ]
        cands = [c for c in cands if lo[0] <= c[1][0] <= hi[0] and lo[1] <= c[1][1] <= hi[1]]
        if not cands:
            break
        q[:2] = min(cands)[1]
    band = sc.altitude
    if band is not None:
        base = 0.0
        if band.reference == "ground" and sc.terrain is not None:
            base = float(sc.terrain.lookup(q[0], q[1], _lookup(sc)))
        if level is not None and math.isfinite(band.max):
            q[2] = base + band.min + level * (band.max - band.min)
        q[2] = min(max(q[2], base + band.min), base + band.max)
    elif sc.terrain is not None:
        q[2] = max(q[2], float(sc.terrain.height(q[0], q[1])))
    q[2] = min(max(q[2], lo[2]), hi[2])
    return q


@pytest.mark.parametrize("level", [None, 0.0, 0.5, 0.75])
def test_admitting_points_together_gives_the_numbers_of_one_at_a_time(level) -> None:
    """The batch (:meth:`HRMAGA._admit_all`) against the point-by-point reference: inside and
    outside areas (overlapping ones, one at the map's edge, ties between two edges), above, in
    and below the band, off the bounds in z; with the band over the ground, absolute, none."""
    sc = hills()
    rng = np.random.default_rng(7)
    Q = np.column_stack(
        [rng.uniform(0, 2000, 400), rng.uniform(0, 2000, 400), rng.uniform(-100, 800, 400)]
    )
    Q[:40, :2] = rng.uniform(860, 1140, (40, 2))  # inside the first area
    Q[40:60, :2] = rng.uniform(0, 120, (20, 2))  # inside the corner area
    Q[60] = (1000.0, 1000.0, 100.0)  # the centre: four edges at the same distance
    Q[61] = (1100.0, 1100.0, 100.0)  # inside both overlapping areas
    areas = [
        *sc.uncertain_areas,  # x 850-1150, y 850-1150
        UncertainArea(1000.0, 1000.0, 400.0, 200.0, revealed=True),  # overlaps it
        UncertainArea(0.0, 0.0, 150.0, 150.0, revealed=True),  # at the map's corner
    ]
    for world in (
        hr_level(sc),
        dataclasses.replace(sc, altitude=AltitudeBand(40.0, 500.0, "absolute")),
        dataclasses.replace(sc, altitude=None),
    ):
        one = np.array([admit_reference(q, areas, world, level) for q in Q])
        np.testing.assert_array_equal(HRMAGA._admit_all(Q, areas, world, level), one)
        np.testing.assert_array_equal(HRMAGA._admit(Q[61], areas, world, level), one[61])


def hr_level(sc: Scenario) -> Scenario:
    return HRMAGA()._level_scenario(sc, terrain_pyramid(sc.terrain, 3)[2], 3)


def test_hr_maga_needs_a_terrain_and_3d() -> None:
    sc = hills()
    flat = dataclasses.replace(sc, terrain=None, altitude=None)
    with pytest.raises(PlannerError, match="terrain"):
        get_planner("hr-maga").plan(flat, budget=10, seed=0)


def test_evaluation_budget_is_kept_and_shared_by_the_levels() -> None:
    sc = hills()
    from uavplan.optimizers.base import Budget

    r = get_planner("hr-maga").plan(sc, budget=Budget(max_evaluations=20_000), seed=0)
    assert r.info["levels"] == 3
    # every level stops at its share; the last batch and the integration may overshoot a little
    assert 20_000 <= r.evaluations <= 24_000


def test_a_first_level_share_gives_the_global_level_its_evaluations() -> None:
    """``level1_share``: the global first level runs for many more steps than with the budget
    in proportion to sub-problems (1/91 of it), the later levels share the rest, and the whole
    budget is still kept."""
    sc = hills()
    from uavplan.optimizers.base import Budget

    runs = {
        share: get_planner("hr-maga", level1_share=share).plan(
            sc, budget=Budget(max_evaluations=20_000), seed=0
        )
        for share in (0.0, 1 / 3)
    }
    steps = {k: [len(h) for h in r.info["level_history"]] for k, r in runs.items()}
    assert steps[1 / 3][0] > 3 * steps[0.0][0]
    assert steps[1 / 3][1] >= 0.5 * steps[0.0][1] and steps[1 / 3][2] >= 0.5 * steps[0.0][2]
    assert 20_000 <= runs[1 / 3].evaluations <= 24_000


def test_hull_chains_go_both_ways_around_and_need_the_ends_on_the_hull() -> None:
    from uavplan.planners.population.hr_maga import _hull_chains

    # ends west and east of a square: one chain over its north side, one over its south
    pts = np.array([[0.0, 0.5], [3.0, 0.5], [1, 0], [2, 0], [2, 1], [1, 1]])
    a, b = _hull_chains(pts)
    assert a[0] == b[0] == 0 and a[-1] == b[-1] == 1
    assert sorted([sorted(a[1:-1]), sorted(b[1:-1])]) == [[2, 3], [4, 5]]
    # an end inside the square's hull: no way around from it
    assert _hull_chains(np.array([[1.5, 0.5], [3.0, 0.5], [1, 0], [2, 0], [2, 1], [1, 1]])) == (
        [],
        [],
    )


def test_batched_lockstep_gives_the_reference_plan_and_repair() -> None:
    """The level's P-MAGAs as one Numba batch (the default) and as one MAGA object each (the
    reference) give the same plan bit for bit: paths, per-level traces, evaluations; and the
    same P-MAGA repair (runs of different lengths: batches of different gene counts)."""
    from uavplan.planners.replanning import position_at

    sc = hills()
    plans = {
        lock: get_planner("hr-maga", lockstep=lock).plan(sc, budget=60, seed=4)
        for lock in ("batched", "reference")
    }
    a, b = plans["batched"], plans["reference"]
    np.testing.assert_array_equal(a.waypoints, b.waypoints)
    assert a.info["level_history"] == b.info["level_history"]
    assert (a.cost, a.evaluations) == (b.cost, b.evaluations)
    np.testing.assert_array_equal(a.history, b.history)
    # two unknown areas on the plan, revealed at once: two runs of failing segments
    areas = []
    for share in (0.3, 0.7):
        c = position_at(a.waypoints, a.times, share * a.times[-1])
        areas.append(UncertainArea(c[0] - 60, c[1] - 60, 120.0 + 80 * share, 120.0, True))
    world = dataclasses.replace(sc, uncertain_areas=(*sc.uncertain_areas, *areas))
    fixed = {}
    for lock in ("batched", "reference"):
        hr = get_planner("hr-maga", lockstep=lock, repair_detour=False)
        fixed[lock] = hr.repair(world, sc.tasks[0], a.waypoints, a.times, 1, 8, 11)
    (pa, ia), (pb, ib) = fixed["batched"], fixed["reference"]
    assert ia["how"] == "local repair" and ia["runs"] >= 2 and ia["segments"] > ia["runs"], ia
    np.testing.assert_array_equal(pa, pb)
    assert ia == ib


def test_detour_from_the_notch_of_two_overlapping_areas() -> None:
    """An end in the notch of two overlapping areas lies inside the hull of their corners, so
    the grown set has no way around; the first round's way around the one area the run
    crosses, which meets no other, is kept as a candidate and found (before: P-MAGA)."""
    sc = hills()
    areas = (
        UncertainArea(800.0, 1000.0, 400.0, 400.0, revealed=True),  # north of A
        UncertainArea(1100.0, 700.0, 400.0, 400.0, revealed=True),  # east of A, across A-B
    )
    world = dataclasses.replace(sc, uncertain_areas=areas, danger_areas=())
    t = world.terrain

    def at(x: float, y: float) -> np.ndarray:
        return np.array([x, y, float(t.height(x, y)) + 100.0])

    P = np.stack([np.asarray(sc.tasks[0].start), at(1000.0, 900.0), at(1700.0, 900.0)])
    hr = HRMAGA()
    problem = hr._problem(world, sc.tasks[0], None, True)
    inner, used = hr._detour(problem, world, P, 1, 1)
    assert inner is not None and used > 0
    way = np.vstack([P[1], inner, P[2]])
    assert bool(problem.evaluate(way[None]).feasible[0])
    assert way[:, 1].min() < 700.0  # south of the crossed area, away from the other one
