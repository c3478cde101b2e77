"""The world a plan is made in (:func:`planning_world`): the scenario under its execution model
(a plan file's, else the scenario's own, else uavplan's default for its UAV; the nominal one
when asked), every static clearance widened by the model's tracking error
(:func:`uavplan.world.execution.widened`); under uavplan's default also turns no tighter than
the UAV's named airframe flies (:func:`uavplan.world.execution.flyable_turns`)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from uavplan.world.airframes import Airframe
    from uavplan.world.execution import ExecutionModel
    from uavplan.world.scenario import Scenario


class WorldProblem(ValueError):
    """The planning world cannot be made: ``problems`` says why, one line each."""

    def __init__(self, problems: list[str]) -> None:
        super().__init__("; ".join(problems))
        self.problems = problems


@dataclass(frozen=True)
class PlanningWorld:
    """``world``: the scenario as planned in; ``model`` its execution model, ``source`` where
    the model came from (``--nominal``, the plan's, the scenario's or uavplan's default);
    ``turn_radius`` the radius its turns were raised to (0: the scenario's), ``given_turn``
    the scenario's; ``min_speed`` the slowest speed planned when raised (0: the scenario's),
    ``given_min`` the scenario's; ``airframe`` the named airframe that raised either."""

    world: Scenario
    model: ExecutionModel
    source: str
    turn_radius: float = 0.0
    given_turn: float = 0.0
    airframe: Airframe | None = None
    min_speed: float = 0.0
    given_min: float = 0.0
    #: the scenario as given (what the verifier checks against); its generated fleet placed
    #: again when the first placement left tasks outside the widened world (``replaced``)
    given: Scenario | None = None
    replaced: int = 0

    def tasks_line(self) -> str | None:
        """Why a generated fleet's tasks were placed again (for the console), or None."""
        if not self.replaced:
            return None
        return (f"fleet placed again: {self.replaced} of the generated fleet's starts and goals "
                "lay where the tracking error would take a UAV out of the band or too near an "
                "obstacle, so every task was placed in the world widened by it (--nominal "
                "keeps the first placement)")  # fmt: skip

    def speeds_line(self) -> str | None:
        """Why the slowest planned speed was raised (for the console), or None."""
        af = self.airframe
        if af is None or self.min_speed <= 0:
            return None
        why = (
            f"a {af.name} at its slowest airspeed with {af.turn_wind:g} m/s of wind behind "
            "it flies that fast over the ground"
        )
        return (f"speeds planned from {self.min_speed:g} m/s, not {self.given_min:g} m/s: "
                f"{why} (--nominal plans the scenario's speeds)")  # fmt: skip

    def turns_line(self) -> str | None:
        """Why the turns were raised (for the console), or None."""
        af = self.airframe
        if af is None or self.turn_radius <= 0:
            return None
        if af.kind == "fixed-wing":
            from uavplan.world.airframes import turn_radius_in_wind

            v = float(self.world.uav.speed)
            banked = turn_radius_in_wind(af, v)
            why = (f"the tightest a {af.name} flies at its {af.max_bank_deg:g} degree bank "
                   f"limit with {af.turn_wind:g} m/s of wind behind it"
                   if banked >= self.turn_radius - 1e-9 else
                   f"its L1 guidance's look-ahead at {v + af.turn_wind:g} m/s over the ground "
                   f"(a tighter turn is cut going in and overshot coming out; its "
                   f"{af.max_bank_deg:g} degree bank limit with {af.turn_wind:g} m/s of wind "
                   f"behind it allows {banked:.1f} m)")  # fmt: skip
        else:
            why = (f"a {af.name} turning at its cruise speed with {af.turn_accel:g} m/s^2 "
                   "(its mission would slow down for a sharper corner, late on the "
                   "plan's schedule)")  # fmt: skip
        return (f"turns planned at {self.turn_radius:.1f} m radius, not {self.given_turn:g} m: "
                f"{why} (--nominal plans the scenario's turns)")  # fmt: skip


def planning_world(
    scenario: Scenario, ref: str, nominal: bool = False, model: Any = None
) -> PlanningWorld:
    """The world ``scenario`` (named ``ref`` in messages) is planned in: under ``model`` when
    given (e.g. a plan file's), else the scenario's own, else uavplan's default for its UAV
    (:func:`~uavplan.world.execution.default_for`), the nominal model with ``nominal``.
    Raises :class:`WorldProblem` when the model is refused or a task's start or goal does not
    fit in the widened world."""
    from uavplan.world.airframes import AIRFRAMES
    from uavplan.world.execution import (
        NOMINAL,
        default_for,
        flyable_speeds,
        flyable_turns,
        widened,
    )

    original = scenario
    by_default = not nominal and model is None and scenario.execution is None
    model = (
        NOMINAL
        if nominal
        else (model or scenario.execution or default_for(scenario.uav, len(scenario.tasks)))
    )
    given_r, r, af = float(scenario.uav.turn_radius), 0.0, None
    given_v, v = float(scenario.uav.min_speed), 0.0
    if by_default:  # uavplan's default also turns and slows no more than the airframe flies
        scenario, r = flyable_turns(scenario)
        scenario, v = flyable_speeds(scenario)
        af = AIRFRAMES[str(scenario.uav.airframe)] if r > 0 or v > 0 else None
    source = "--nominal" if nominal else model.source
    try:
        world = widened(scenario, model)
    except ValueError as exc:
        raise WorldProblem([f"{ref}: the execution model ({model.describe()}): {exc}"]) from None
    given, replaced = original, 0
    if model.track_h or model.track_v:
        bad = _task_problems(world, ref, model)
        fleet = scenario.metadata.get("generated_fleet")
        if bad and fleet:  # a generated fleet is placed again, in the widened world
            from uavplan.world.fleet_tasks import with_fleet

            try:
                placed = with_fleet(world, **fleet)
            except ValueError as exc:
                again = f"{ref}: placed again in the widened world: {exc}"
                raise WorldProblem([*bad, again]) from None
            replaced = len(bad)
            world = dataclasses.replace(world, tasks=placed.tasks)
            given = dataclasses.replace(original, tasks=placed.tasks)
            bad = _task_problems(world, ref, model)
        if bad:  # the first few, and how many more (a generated fleet can have hundreds)
            more = [f"{ref}: ... and {len(bad) - 5} more starts and goals like these"]
            raise WorldProblem(bad[:5] + (more if len(bad) > 5 else []))
    return PlanningWorld(world, model, source, r, given_r, af, v, given_v, given, replaced)


def fleet_as_planned(scenario: Scenario, ref: str, record: dict[str, Any] | None) -> Scenario:
    """``scenario`` with its tasks where a plan made under the execution model ``record`` (a
    plan file's ``execution``) had them: a generated fleet that :func:`planning_world` placed
    again in the widened world is placed again the same way (the placement is deterministic);
    otherwise ``scenario`` itself. What commands reading a plan check it against."""
    from uavplan.world.execution import ExecutionModel, default_for

    if not record or not scenario.metadata.get("generated_fleet"):
        return scenario
    try:
        model = ExecutionModel.from_record(record)
        if scenario.execution is None and model == default_for(scenario.uav, len(scenario.tasks)):
            pw = planning_world(scenario, ref)  # uavplan's default, its flyable turns and speeds
        else:
            pw = planning_world(scenario, ref, model=model)
    except (ValueError, KeyError, TypeError):
        return scenario
    return pw.given if pw.replaced and pw.given is not None else scenario


def _task_problems(world: Scenario, ref: str, model: Any) -> list[str]:
    """Every task start or goal that the widened ``world`` refuses, one line each."""
    bad = []
    for t in world.tasks:
        for what, p in (("start", t.start), ("goal", t.goal)):
            why = world.point_problems(np.asarray(p, dtype=np.float64))
            if why:
                bad.append(f"{ref}: task {t.id}: its {what} {list(p)} is {why[0]} once every "
                           f"clearance is widened by the tracking error ({model.track_h:g} m "
                           f"horizontal, {model.track_v:g} m vertical); move it, or plan "
                           "with --nominal")  # fmt: skip
    return bad
