"""The fleet engine's swarm evaluation: only the particles that can improve on their personal
best are checked (``PathProblem.evaluate_cv(below=...)``), in one kernel where it applies
(``uavplan.planners.fleet.fleet_objective``), against the reference (every particle, NumPy
terms)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from uavplan.optimizers.constraints import infinite_if_violated
from uavplan.planners import get_planner
from uavplan.planners.core.base import separated_problem
from uavplan.planners.fleet.fleet_objective import FleetObjective
from uavplan.planners.fleet.prioritized import PrioritizedPlanner
from uavplan.problems.encoding import CartesianEncoding
from uavplan.problems.path_problem import PathProblem
from uavplan.scenarios import resolve
from uavplan.world import Scenario
from uavplan.world.execution import DEFAULT
from uavplan.world.fleet_tasks import with_fleet
from uavplan.world.reservations import ReservationTable


@pytest.fixture(scope="module")
def fleet6() -> Scenario:
    return with_fleet(resolve("ppswarm1"), 6, seed=0)


@pytest.fixture(scope="module")
def planned(fleet6: Scenario) -> dict[str, np.ndarray]:
    """Each UAV's planned polyline and times in a small paper-mode plan, by UAV id."""
    fr = get_planner("ppswarm", pop_size=30, n_iter=6, n_restart=1, rrt_iterations=1500,
                     flight="after", max_delays=0).plan_fleet(fleet6, None, 0)  # fmt: skip
    return {r.uav_id: (r.waypoints, r.times) for r in fr.results}


def _problem(
    sc: Scenario, planned: dict, reserved: int, cruise: float | None = None, timed: bool = False,
    shadow: bool = False,
) -> PathProblem:  # fmt: skip
    """The last task's problem among the planned flights of the first ``reserved`` tasks
    (its cruise layer at ``cruise`` m in the band's reference when given; with ``timed`` the
    table under the default execution model's windows; with ``shadow`` taking off 15 m from
    the fifth UAV at its time, so that paths near that UAV's conflict with it)."""
    task = dataclasses.replace(sc.tasks[-1], cruise=cruise)
    if shadow:
        task = dataclasses.replace(task, start=sc.tasks[4].start + np.array([15.0, 0.0, 0.0]),
                                   start_time=sc.tasks[4].start_time)  # fmt: skip
    if timed:  # taking off 3 s after its planned time: some paths clear, some not
        table = ReservationTable.for_scenario(dataclasses.replace(sc, execution=DEFAULT))
        assert table.timed
        task = dataclasses.replace(task, start_time=task.start_time + 3.0)
    else:
        table = ReservationTable.for_uav(sc.bounds.lo, sc.bounds.hi, sc.uav)
    for t in sc.tasks[:reserved]:
        table.add(t.id, *planned[t.id])
    return separated_problem(sc, task, table)


def _swarm(enc: CartesianEncoding, path: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Genes around a planned path (many feasible, some not), some out in the box."""
    g = enc.encode(path[None])[0]
    scale = rng.choice([0.5, 5.0, 50.0], size=(600, 1))
    return np.clip(g + rng.normal(size=(600, g.size)) * scale, enc.lower, enc.upper)


def _reference(problem: PathProblem, enc: CartesianEncoding, X: np.ndarray, below=None):
    f, cv = problem.evaluate_cv(enc.decode(X), exact=False, below=below)
    return infinite_if_violated(f, cv)


@pytest.mark.parametrize(
    ("reserved", "cruise", "timed", "shadow"),
    [(0, None, False, False), (5, None, False, False), (5, 120.0, False, False),
     (5, None, False, True), (5, None, True, False)],
)  # fmt: skip
def test_fused_kernel_gives_the_reference_costs(
    fleet6: Scenario, planned: dict, reserved: int, cruise: float | None, timed: bool,
    shadow: bool,
) -> None:  # fmt: skip
    """Nominal and under the default execution model's timed table; where the separation
    decides some particles (``timed``, ``shadow``) that is checked too."""
    problem = _problem(fleet6, planned, reserved, cruise, timed, shadow)
    enc = CartesianEncoding(problem, 10)
    fused = FleetObjective.of(problem, enc)
    assert fused is not None
    rng = np.random.default_rng(reserved)
    X = _swarm(enc, planned[fleet6.tasks[4 if shadow else -1].id][0], rng)
    full = _reference(problem, enc, X)
    assert 50 < np.isfinite(full).sum() < 550  # both kinds are tested
    if timed or shadow:  # and the separation decides some
        alone = _reference(_problem(fleet6, planned, 0, cruise, timed, shadow), enc, X)
        assert np.sum(np.isfinite(alone) & np.isinf(full)) >= 5
    thresholds = (
        np.full(len(X), np.inf),
        np.where(rng.random(len(X)) < 0.5, np.inf, full * rng.uniform(0.99, 1.01, len(X))),
        np.full(len(X), -np.inf),
    )
    for below in thresholds:
        got = fused.evaluate(X, below)
        want = _reference(problem, enc, X, below)
        np.testing.assert_array_equal(np.isinf(got), np.isinf(want))
        fin = np.isfinite(want)
        np.testing.assert_allclose(got[fin], want[fin], rtol=1e-12, atol=0)
        # what matters is what the full evaluation gives: every value below the threshold is
        # the full value, every other one is at or above it in full
        m = full < below
        np.testing.assert_array_equal(want[m], full[m])
        assert np.all(want[~m] == np.inf) and np.all(full[~m] >= below[~m])


def test_fused_kernel_needs_what_it_computes(fleet6: Scenario, planned: dict) -> None:
    problem = _problem(fleet6, planned, 2)
    assert FleetObjective.of(problem, CartesianEncoding(problem, 10)) is not None
    spso = separated_problem(fleet6, fleet6.tasks[-1], None, cost="spso")
    assert FleetObjective.of(spso, CartesianEncoding(spso, 10)) is None
    flat = dataclasses.replace(fleet6, terrain=None)
    assert FleetObjective.of(*_pair(separated_problem(flat, flat.tasks[-1], None))) is not None


def _pair(problem: PathProblem) -> tuple[PathProblem, CartesianEncoding]:
    return problem, CartesianEncoding(problem, 10)


@pytest.mark.parametrize("flight", ["after", "in-loop"])
def test_lazy_swarms_are_the_reference_swarms(
    fleet6: Scenario, flight: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The whole fleet, bit for bit (the costs per iteration to 1e-12), with every particle
    checked (the reference evaluator)
    and with only those that can improve on their personal best."""
    opts = {"pop_size": 30, "n_iter": 6, "n_restart": 2, "rrt_iterations": 1500,
            "flight": flight}  # fmt: skip
    fast = get_planner("ppswarm", **opts).plan_fleet(fleet6, None, 4)
    monkeypatch.setattr(PrioritizedPlanner, "_swarm_evaluator",
                        lambda self, problem, enc, objective, opt: objective.evaluate)  # fmt: skip
    ref = get_planner("ppswarm", **opts).plan_fleet(fleet6, None, 4)
    assert fast.cost == ref.cost or (np.isinf(fast.cost) and np.isinf(ref.cost))
    np.testing.assert_array_equal(fast.restart_costs, ref.restart_costs)
    for a, b in zip(fast.results, ref.results, strict=True):
        np.testing.assert_array_equal(a.waypoints, b.waypoints)
        np.testing.assert_array_equal(a.flown_trajectory()[0], b.flown_trajectory()[0])
        # the fused objective sums ulps apart from the reference (docs/decisions.md)
        np.testing.assert_allclose(a.history, b.history, rtol=1e-12)
        assert a.evaluations == b.evaluations
