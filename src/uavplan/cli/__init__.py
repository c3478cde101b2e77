"""Command line: ``uavplan plan | demo | verify | explain | fly | export | simulate | view |
planners | schema | scenario ... | bench ... | report``.

One module per command group: :mod:`uavplan.cli.plan` (``plan``, ``demo``),
:mod:`uavplan.cli.scenario`, :mod:`uavplan.cli.bench` (``bench``, ``report``),
:mod:`uavplan.cli.verify`, :mod:`uavplan.cli.explain`, :mod:`uavplan.cli.export`,
:mod:`uavplan.cli.simulate`,
:mod:`uavplan.cli.view`,
:mod:`uavplan.cli.planners`,
:mod:`uavplan.cli.schema`.
"""

from __future__ import annotations

import typer

from uavplan.cli.bench import bench_app
from uavplan.cli.bench import report as report_command
from uavplan.cli.explain import explain as explain_command
from uavplan.cli.export import export as export_command
from uavplan.cli.fly import fly as fly_command
from uavplan.cli.plan import demo as demo_command
from uavplan.cli.plan import plan as plan_command
from uavplan.cli.planners import PlannerListInHelp
from uavplan.cli.planners import planners as planners_command
from uavplan.cli.scenario import scenario_app
from uavplan.cli.schema import schema as schema_command
from uavplan.cli.simulate import simulate as simulate_command
from uavplan.cli.verify import verify as verify_command
from uavplan.cli.view import view as view_command

app = typer.Typer(
    name="uavplan",
    help="Plan safe, flyable UAV paths and compare planners.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
app.command("plan", cls=PlannerListInHelp)(plan_command)
app.command("demo")(demo_command)
app.add_typer(scenario_app, name="scenario")
app.add_typer(bench_app, name="bench")
app.command("report")(report_command)
app.command("verify")(verify_command)
app.command("explain")(explain_command)
app.command("fly")(fly_command)
app.command("export")(export_command)
app.command("simulate")(simulate_command)
app.command("view")(view_command)
app.command("planners")(planners_command)
app.command("algorithms", help="The same as `planners`: every planner, or NAME's options.")(
    planners_command
)
app.command("schema")(schema_command)


def _as_sentences(t: typer.Typer) -> None:
    """Every command's help from its docstring as sentences (the lines of a paragraph joined:
    rich's help box wraps them itself, where the docstring's own line breaks would break them
    mid-sentence) and its line in the command list the first sentence."""
    import inspect

    from uavplan._text import first_sentence

    for info in t.registered_commands:
        doc = info.help or (info.callback.__doc__ if info.callback else None)
        if doc:
            paras = inspect.cleandoc(doc).split("\n\n")
            info.help = "\n\n".join(" ".join(p.split()) for p in paras)
            info.short_help = info.short_help or first_sentence(doc)
    for g in t.registered_groups:
        if g.typer_instance is not None:
            _as_sentences(g.typer_instance)


_as_sentences(app)


def main() -> None:
    try:
        app()
    except MemoryError:
        # one line, not a traceback: what ran out, and what to do (exit 1: the input may be
        # valid, the machine too small for it; files already written are left as they are)
        import sys

        from uavplan.cli._common import err

        err.print("[bold red]out of memory[/]: this machine's memory did not hold the job; "
                  "a smaller fleet or world, or a machine with more memory, may do "
                  "(files written before this point are kept as they were)")  # fmt: skip
        sys.exit(1)


if __name__ == "__main__":  # pragma: no cover
    main()
