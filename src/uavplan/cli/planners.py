"""``uavplan planners [NAME]``: the registered planners, or one planner's options (generated
from its config: defaults, ranges, what each does)."""

from __future__ import annotations

from typing import Annotated, Any

import typer
from rich.table import Table

from uavplan.cli._common import fail, print_table


class PlannerListInHelp(typer.core.TyperCommand):
    """A command whose ``--help`` ends with every registered planner, a line each (the registry
    is imported only when that help is asked for, so ``uavplan --help`` stays quick)."""

    def format_help(self, ctx: Any, formatter: Any) -> None:
        from uavplan.planners import available_planners, planner_entry

        super().format_help(ctx, formatter)
        table = Table(title="planners (-a NAME; `uavplan planners NAME` shows its options)",
                      title_justify="left", box=None, pad_edge=False)  # fmt: skip
        table.add_column("name", no_wrap=True)
        table.add_column("kind", no_wrap=True)
        table.add_column("what it is")
        for n in available_planners():
            e = planner_entry(n)
            table.add_row(n, "fleet" if e.fleet else "single UAV", e.summary)
        print_table(table)


def planners(
    name: Annotated[str | None, typer.Argument(help="A planner: show its options.")] = None,
) -> None:
    """List the planners, or show NAME's options (usable as --param NAME=VALUE)."""

    from uavplan.planners import (
        PlannerError,
        available_planners,
        describe_options,
        get_planner,
        planner_entry,
    )

    if name is None:
        table = Table(title="planners (uavplan plan SCENARIO -a NAME)")
        for col in ("name", "kind", "what it is"):
            table.add_column(col)
        for n in available_planners():
            e = planner_entry(n)
            table.add_row(n, "fleet" if e.fleet else "single UAV", e.summary)
        print_table(table)
        return
    try:
        p = get_planner(name)
    except PlannerError as exc:
        raise fail(str(exc)) from None
    entry = planner_entry(name)
    table = Table(title=f"{name}: {entry.summary}")
    for col in ("option", "value", "valid", "what it does"):
        table.add_column(col)
    for o in describe_options(type(p.config)):
        if o["name"] == "optimizer_options":
            continue
        table.add_row(o["name"], repr(getattr(p.config, o["name"])), o["range"], o["doc"])
    opt = p.optimizer_name()
    if opt is not None and p.optimizer_config is not None:
        cfg = p.optimizer_config
        for o in describe_options(type(cfg)):
            value = repr(getattr(cfg, o["name"]))
            table.add_row(o["name"], value, o["range"], f"{opt}: {o['doc']}")
    print_table(table)
