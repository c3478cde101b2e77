"""A plan's story as typed events: what happened to each UAV while its fleet was planned (the
path it flies, a later candidate, a slower speed, a later take-off, a repair after planning, a
flight left failing), what each restart of the fleet gave, and which attempts a strategy made
(:mod:`uavplan.strategy` adds those). ``plan.json`` keeps them in its ``diagnostics`` section
(:func:`diagnostics`), ``uavplan explain`` tells them.

The fleet engine keeps its records in the results' ``info`` (``rescue`` per UAV, ``delayed``,
``repair``, ``unrepaired`` (what the repair tried) and ``best_restart`` per fleet);
:func:`plan_events` reads them into events, one vocabulary for every planner (:data:`KINDS`)."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from uavplan.planners.fleet.fleet_plan import FleetPlan

#: The event kinds and what each says.
KINDS: Mapping[str, str] = {
    "candidate": "its first candidate path did not fly against the UAVs before it; a later "
    "candidate did",
    "slower": "it flies its path slower than the cruise speed to keep clear of the others",
    "waited": "it takes off later on the same path to keep clear of the others",
    "delayed": "its path was planned again from a later take-off",
    "repaired": "re-flown after planning against every other UAV's flight",
    "unresolved": "its flight fails a check as planned; the plan does not fly",
    "restart": "one restart of the whole fleet: its cost, or the UAVs it left failing",
    "attempt": "one planner run of the strategy (uavplan plan without -a)",
}

#: The engine's ``rescue`` records as event kinds (``first``: the first candidate flew).
_RESCUES = {"candidate": "candidate", "slower": "slower", "wait": "waited", "delay": "delayed"}

#: The ``diagnostics`` section's schema name.
SCHEMA = "uavplan.diagnostics/1"


@dataclass(frozen=True)
class Event:
    """One event: its ``kind`` (:data:`KINDS`), the ``uav`` it concerns (None: the fleet or
    the plan), a one-line ``detail``, and a ``value`` where the kind has one (seconds of a
    later take-off, a restart's or an attempt's cost)."""

    kind: str
    uav: str | None
    detail: str
    value: float | None = None

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"unknown event kind {self.kind!r}; choose from {sorted(KINDS)}")

    def record(self) -> dict[str, Any]:
        v = self.value
        return {"kind": self.kind, "uav": self.uav, "detail": self.detail,
                "value": None if v is None or not math.isfinite(v) else float(v)}  # fmt: skip

    @classmethod
    def from_record(cls, rec: Mapping[str, Any]) -> Event:
        v = rec.get("value")
        return cls(str(rec["kind"]), rec.get("uav"), str(rec.get("detail", "")),
                   None if v is None else float(v))  # fmt: skip


def plan_events(plan: FleetPlan) -> tuple[Event, ...]:
    """The events of a plan's UAVs and restarts, from the engine's records (in the UAVs'
    order, then the restarts)."""
    fleet = plan.fleet
    finfo = dict(fleet.info) if fleet is not None else {}
    delayed = dict(finfo.get("delayed") or {})
    unrepaired = dict(finfo.get("unrepaired") or {})
    out: list[Event] = []
    for r in plan.results:
        rescue = (r.info or {}).get("rescue")
        late = delayed.get(r.uav_id)
        if rescue in _RESCUES:
            kind = _RESCUES[rescue]
            when = f", taking off {late:g} s later" if late else ""
            out.append(Event(kind, r.uav_id, KINDS[kind] + when, late))
        elif late:
            out.append(Event("waited", r.uav_id, f"takes off {late:g} s later", late))
        how = (r.info or {}).get("repaired")
        if how:
            out.append(Event("repaired", r.uav_id, f"re-flown after planning: {how}"))
        if not r.flown_feasible:
            checks = list(dict.fromkeys(str(v).split(":")[0]
                                        for v in (r.flown_violations or r.violations)))  # fmt: skip
            tried = unrepaired.get(r.uav_id)
            why = f"; the repair after planning tried {tried}" if tried else ""
            fails = ", ".join(checks) or "a check"
            out.append(Event("unresolved", r.uav_id, f"its flight fails: {fails}{why}"))
    if fleet is not None and len(fleet.restart_costs) > 1:
        best = finfo.get("best_restart")
        failed = list(finfo.get("restart_failed") or [])
        for k, c in enumerate(fleet.restart_costs, start=1):
            kept = " (kept)" if best == k else ""
            what = f"cost {float(c):.6g}"
            left = failed[k - 1] if k <= len(failed) else []
            if not math.isfinite(c) and k > len(failed):  # a plan from before the record
                what = "a UAV left infeasible"
            elif not math.isfinite(c) and not left:  # every flight passes, a path's cost is inf
                what = "cost inf (every UAV's flight passes)"
            if left:  # which, so that a discarded restart's failures are not lost
                more = f" and {len(left) - 8} more" if len(left) > 8 else ""
                what = f"{len(left)} UAV(s) left failing: {', '.join(left[:8])}{more}"
            out.append(Event("restart", None, f"{k}: {what}{kept}", float(c)))
    return tuple(out)


def diagnostics(events: Sequence[Event]) -> dict[str, Any]:
    """``plan.json``'s ``diagnostics`` section."""
    return {"schema": SCHEMA, "events": [e.record() for e in events]}
