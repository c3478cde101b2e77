"""What ``uavplan plan`` does without ``-a``: one :class:`Strategy` per kind of scenario, in one
table (:data:`TABLE`), chosen by :func:`strategy_for`.

A strategy names the planner our own results show best for the kind (``docs/results.md``,
"What a user gets without -a", holds the figures), how many independent runs of it are made
and which other planners also run once (the best plan of them all is kept:
:func:`~uavplan.strategy.execute.best_plan`), whether the plan is repaired after planning (a
single UAV's path polished, a fleet's looping or failing UAVs re-flown one by one: the same
for every fleet, whatever planned it), the planners tried in order when the kept plan does not
fly, and the planner that repairs a path in flight (``uavplan fly``).

The reasoning per kind (the measured figures are in ``docs/results.md``):

* **2-D scene**, **3-D world, one UAV**: SPSO, the shortest paths on the RGG-PSO+ paper's
  scenes and the SPSO paper's cost on its own benchmark.
* **One UAV among danger or uncertain areas** (HR-MAGA's world): HR-MAGA, whose loss sees the
  danger areas and whose levels see the uncertain ones; its result varies from seed to seed,
  so three runs are made and the best kept, and SPSO runs once beside it (on a world with
  one danger and one uncertain area its runs came within a few per cent of the best any
  planner reached).
* **One UAV, when the plan does not fly**: RRT* with a step scaled to the map (it finds a
  way through traps and walls where a swarm's path does not), then RGG-PSO+ (a graph path,
  then optimized).
* **A fleet**: PPSwarm, every UAV's flight checked while planning and reserved for the others.
* **A fleet that flies at one constant speed** (``min_speed`` equal to the top speed: fixed
  wings that can neither wait nor slow down, the RSCDWOA layouts): RSCDWOA-APF, which steps
  each UAV in time at its speed around the others; PPSwarm's rescues (waiting, slower speeds)
  are not open to such UAVs.

A fleet has no fallback planners (minutes per try): its failing UAVs are repaired one by one
instead (:mod:`uavplan.planners.fleet.fleet_polish`).
"""

from __future__ import annotations

import dataclasses
import enum
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from uavplan.world.scenario import Scenario


class ScenarioKind(enum.Enum):
    """The kinds of scenario the defaults are chosen by."""

    SCENE_2D = "2-D scene"
    SINGLE_3D = "3-D single UAV"
    SINGLE_3D_UNKNOWN = "3-D single UAV with danger or uncertain areas"
    FLEET = "fleet"
    FLEET_CONSTANT_SPEED = "fleet of constant-speed UAVs"


@dataclass(frozen=True)
class Strategy:
    """What a plan command does: the attempts, how the kept plan is selected, what follows
    planning, the fallbacks.

    Attributes:
        planner: the planner's registry name.
        why: one line: why this planner (for the console).
        kind: the scenario kind it was chosen for; None when the user named the planner.
        options: the planner's options (every attempt of ``planner`` gets them; the fallbacks
            get them on top of their own).
        runs: independent runs of ``planner`` (root seeds from
            :func:`~uavplan.strategy.execute.run_seeds`); the best plan is kept.
        also: other planners run once with the root seed, competing for the kept plan.
        repair: polish a single UAV's path and repair a fleet's looping or failing UAVs after
            planning (``--raw`` turns it off).
        fallbacks: ``(planner, options)`` tried in order, each once with the root seed, when
            the kept plan does not fly; the first that flies is kept.
        replanner: the planner that repairs the rest of a path in flight (``uavplan fly``).
    """

    planner: str
    why: str
    kind: ScenarioKind | None = None
    options: Mapping[str, Any] = field(default_factory=dict)
    runs: int = 1
    also: tuple[str, ...] = ()
    repair: bool = True
    fallbacks: tuple[tuple[str, Mapping[str, Any]], ...] = ()
    replanner: str = "hr-maga"

    def __post_init__(self) -> None:
        if self.runs < 1:
            raise ValueError(f"a strategy makes at least one run, not {self.runs}")

    def plain(self) -> Strategy:
        """The strategy without the other planners and the fallbacks: when the user sets
        options for the default planner, that planner is what was asked for."""
        return dataclasses.replace(self, also=(), fallbacks=())

    def with_options(self, options: Mapping[str, Any], repair: bool = True) -> Strategy:
        """The strategy with ``options`` for its planner (and ``repair`` as given)."""
        return dataclasses.replace(self, options=dict(options), repair=repair)

    def describe(self) -> str:
        """The console's words for what runs: ``; the best of 3 runs and of spso once``."""
        best = f"; the best of {self.runs} runs" if self.runs > 1 else ""
        if self.also:
            best += f" and of {', '.join(self.also)} once"
        return best


#: scenario kind -> what ``uavplan plan`` does for it (its fallbacks are made for the
#: scenario by :func:`strategy_for`).
TABLE: Mapping[ScenarioKind, Strategy] = {
    ScenarioKind.SCENE_2D: Strategy(
        "spso", "the shortest paths on the RGG-PSO+ paper's 1,000 scenes"
    ),
    ScenarioKind.SINGLE_3D: Strategy("spso", "the SPSO paper's cost on its benchmark"),
    ScenarioKind.SINGLE_3D_UNKNOWN: Strategy(
        "hr-maga",
        "its loss sees danger areas, its levels uncertain ones, and it repairs locally",
        runs=3,
        also=("spso",),
    ),
    ScenarioKind.FLEET: Strategy(
        "ppswarm", "every UAV's flight checked while planning: 40/40 verified as flown"
    ),
    ScenarioKind.FLEET_CONSTANT_SPEED: Strategy(
        "rscdwoa-apf",
        "it flies each UAV at its one speed in time around the others: 400/400 verified",
    ),
}

#: The single UAV's fallbacks, in order (RRT*'s options scaled to the map).
SINGLE_FALLBACKS = ("rrt-star", "rgg-pso+")


def scenario_kind(scenario: Scenario) -> ScenarioKind:
    """The kind of ``scenario``: a fleet (more than one task; of constant-speed UAVs when
    ``min_speed`` equals the top speed, 3-D), else a 2-D scene, else one UAV in 3-D (among
    danger or uncertain areas, or not)."""
    if len(scenario.tasks) > 1:
        uav = scenario.uav
        if scenario.dim == 3 and uav.min_speed > 0 and uav.min_speed >= uav.v_max:
            return ScenarioKind.FLEET_CONSTANT_SPEED
        return ScenarioKind.FLEET
    if scenario.dim == 2:
        return ScenarioKind.SCENE_2D
    if scenario.danger_areas or scenario.uncertain_areas:
        return ScenarioKind.SINGLE_3D_UNKNOWN
    return ScenarioKind.SINGLE_3D


def fallbacks_for(scenario: Scenario) -> tuple[tuple[str, Mapping[str, Any]], ...]:
    """The planners tried in order when a single UAV's plan does not fly: RRT* with its step
    scaled to the map (:func:`~uavplan.planners.sampling.rrt_star.map_scaled_options`), then
    RGG-PSO+; none for a fleet."""
    if len(scenario.tasks) > 1:
        return ()
    from uavplan.planners.sampling.rrt_star import map_scaled_options

    opts: dict[str, Mapping[str, Any]] = {"rrt-star": map_scaled_options(scenario)}
    return tuple((name, opts.get(name, {})) for name in SINGLE_FALLBACKS)


def strategy_for(
    scenario: Scenario, table: Mapping[ScenarioKind, Strategy] | None = None
) -> Strategy:
    """The strategy for ``scenario``: its kind's row of ``table`` (:data:`TABLE`), its
    fallbacks made for the scenario."""
    kind = scenario_kind(scenario)
    row = (TABLE if table is None else table)[kind]
    return dataclasses.replace(row, kind=kind, fallbacks=row.fallbacks or fallbacks_for(scenario))


def chosen(planner: str, options: Mapping[str, Any] | None = None, repair: bool = True) -> Strategy:
    """The strategy of a planner the user named: one run of it, nothing else."""
    return Strategy(planner, "chosen", options=dict(options or {}), repair=repair)
