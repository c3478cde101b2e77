"""``uavplan bench list | run`` and ``uavplan report``."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from uavplan.cli._common import err, out, print_table

bench_app = typer.Typer(help="Experiments: the papers' plans, run resumably.", no_args_is_help=True)


#: below this much run time a sweep's overhead figure is mostly process start and compilation
OVERHEAD_FROM_S = 60.0


def _fail(msg: str, code: int = 2) -> typer.Exit:
    err.print(msg, markup=False, highlight=False)
    return typer.Exit(code)


@bench_app.command("list")
def list_plans() -> None:
    """The experiment plans and their scales (a table on a terminal, a line per plan when piped)."""
    from uavplan.bench.catalog import available_plans, get_plan

    rows = []
    for name in available_plans():
        p = get_plan(name)
        smoke, paper = p.n_runs("smoke"), p.n_runs("paper")
        n_sc = len(p.scales["paper"].scenarios or p.scenarios)
        rows.append((name, f"{n_sc} x {len(p.algorithms)}", str(smoke), f"{paper:,}",
                     p.description))  # fmt: skip
    if not out.is_terminal:  # piped: whole descriptions, one line each
        for name, grid, smoke_n, paper_n, text in rows:
            out.print(f"{name}: {grid} scenarios x algorithms, {smoke_n} smoke runs, {paper_n} "
                      f"paper runs; {text}", markup=False, highlight=False)  # fmt: skip
        return
    table = Table(title="experiment plans")
    for col in ("plan", "scenarios x algorithms", "smoke runs", "paper runs", "description"):
        table.add_column(col)
    for row in rows:
        table.add_row(*row)
    print_table(table)


@bench_app.command("run")
def run(
    plan: Annotated[str, typer.Argument(help="Plan name (see `uavplan bench list`).")],
    scale: Annotated[str, typer.Option(help="smoke (CI) or paper (full).")] = "smoke",
    runs: Annotated[int | None, typer.Option(help="Runs per cell (overrides the scale).")] = None,
    iterations: Annotated[int | None, typer.Option(help="Iterations per run.")] = None,
    out_dir: Annotated[Path | None, typer.Option("--out", help="Results folder.")] = None,
    workers: Annotated[int | None, typer.Option(help="Worker processes [all cores].")] = None,
    scheduler: Annotated[
        str | None, typer.Option(help="Dask scheduler address, e.g. tcp://HOST:8786.")
    ] = None,
    executor: Annotated[str, typer.Option(help="process, serial or dask.")] = "process",
    seed: Annotated[int, typer.Option(help="Root seed.")] = 0,
    retry_failed: Annotated[bool, typer.Option(help="Run again runs that failed.")] = False,
    report: Annotated[bool, typer.Option(help="Write the report when done.")] = True,
    only: Annotated[
        str | None,
        typer.Option(help="Run only these configurations (comma-separated labels) of PLAN."),
    ] = None,
) -> None:
    """Run PLAN; finished runs in --out are skipped, so the same command resumes a sweep.

    Exit codes: 0 every run ok; 1 some runs failed (recorded; --retry-failed runs them again);
    2 bad input, or the sweep stopped (results cannot be written, e.g. a full disk; --out in use
    by another sweep; an unreadable shard): one line says why, everything stored before is
    intact and the same command resumes; 130 Ctrl-C."""
    from uavplan.bench.catalog import get_plan
    from uavplan.bench.plans import PlanError
    from uavplan.bench.runner import Progress as SweepProgress
    from uavplan.bench.runner import SweepInterrupted, SweepStopped, run_sweep

    try:
        p = get_plan(plan)
        p.runs(scale, runs, seed, iterations)  # validate before starting anything
    except PlanError as exc:
        raise _fail(str(exc)) from None
    labels = [a.label for a in p.algorithms]
    chosen = None if only is None else [o.strip() for o in only.split(",") if o.strip()]
    if chosen is not None and (not chosen or any(o not in labels for o in chosen)):
        bad = [o for o in chosen if o not in labels] or [str(only)]
        raise _fail(
            f"--only: plan {plan!r} has no configuration {', '.join(map(repr, bad))}; "
            f"choose from {', '.join(labels)}"
        )
    if scheduler:
        executor = "dask"
    folder = out_dir or Path("results") / f"{plan}-{scale}"
    from rich.progress import (  # here: 50 ms that `uavplan --help` need not pay
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TextColumn,
        TimeElapsedColumn,
    )

    with Progress(
        TextColumn(f"[bold]{plan}[/bold] {scale}"),
        BarColumn(),
        MofNCompleteColumn(),
        TextColumn("{task.fields[info]}"),
        TimeElapsedColumn(),
        console=err,
        transient=False,
    ) as bar:
        tid = bar.add_task("runs", total=None, info="starting")

        def on_progress(pr: SweepProgress) -> None:
            eta = f"{pr.eta:,.0f} s left" if pr.eta is not None else ""
            bar.update(
                tid,
                total=pr.total,
                completed=pr.skipped + pr.done,
                info=f"{pr.failed} failed  {eta}",
            )

        try:
            summary = run_sweep(
                p,
                folder,
                scale,
                runs,
                iterations,
                seed,
                executor,
                workers,
                scheduler,
                on_progress,
                retry_failed,
                only=chosen,
            )
        except SweepInterrupted as exc:
            raise _fail(str(exc), 130) from None
        except SweepStopped as exc:  # a full disk, a folder in use, an unreadable shard
            raise _fail(f"bench run {plan}: {exc}") from None
        except (OSError, RuntimeError, ValueError) as exc:
            raise _fail(f"bench run {plan}: {exc}", 1) from None
    out.print(
        f"{summary.executed} runs done, {summary.skipped} already finished, "
        f"{summary.failed} failed, in {summary.wall_time:.1f} s on {summary.workers} "
        f"{summary.executor} worker(s); results in {folder}"
    )
    if summary.overhead is not None and summary.executed:
        if summary.run_time >= OVERHEAD_FROM_S:
            out.print(f"runner overhead: {100 * summary.overhead:.1f} % of the runs' compute time")
        else:  # worker start, imports and kernel compilation are most of so short a sweep
            out.print(f"runner overhead: not measured (the runs took {summary.run_time:.1f} s in "
                      f"all, under {OVERHEAD_FROM_S:.0f} s)")  # fmt: skip
    for line in summary.failures[:20]:
        err.print(f"failed: {line}", markup=False, highlight=False)
    if len(summary.failures) > 20:
        err.print(f"... and {len(summary.failures) - 20} more failures")
    if report:
        out.print(f"report: {_write_report(folder)[0]}")
    if summary.failed:
        raise typer.Exit(1)


def report(
    folder: Annotated[Path, typer.Argument(help="A results folder written by `bench run`.")],
    claims: Annotated[
        bool,
        typer.Option(
            "--claims",
            help="FOLDER holds one results folder per plan: write the "
            "papers' claims ledger judged from them.",
        ),
    ] = False,
    out_file: Annotated[
        Path | None, typer.Option("--out", help="The ledger's file [FOLDER/claims.md].")
    ] = None,
) -> None:
    """Write FOLDER/report.html (self-contained) and FOLDER/report.md, figures as PNG; with
    --claims, the claims ledger: every headline claim of the four papers with our figures
    under the paper's protocol and ours, the test and a verdict."""
    if claims:
        _write_claims(folder, out_file or folder / "claims.md")
        return
    if out_file is not None:
        raise _fail("--out is for --claims (a plan's report is written into its folder)")
    if not (folder / "runs").is_dir():
        raise _fail(f"{folder}: not a results folder (no runs/ inside)")
    html_path, md_path = _write_report(folder)
    out.print(f"wrote {html_path} and {md_path}")


def _write_claims(folder: Path, target: Path) -> None:
    from uavplan.bench.claims.base import VERDICTS, build_ledger, render_markdown
    from uavplan.bench.store import StoreError
    from uavplan.io.atomic import write_bytes_atomic

    if not folder.is_dir():
        raise _fail(f"{folder}: no such folder (the results root, one folder per plan)")
    try:
        ledger = build_ledger(folder)
    except StoreError as exc:
        raise _fail(f"report --claims: {exc}") from None
    try:
        write_bytes_atomic(target, render_markdown(ledger, folder).encode())
    except OSError as exc:
        raise _fail(f"report --claims: cannot write {target}: {exc.strerror or exc}") from None
    counts = {v: sum(1 for _, f in ledger if f.verdict == v) for v in VERDICTS}
    out.print(f"{len(ledger)} claims: " + ", ".join(f"{v} {n}" for v, n in counts.items() if n))
    for c, f in ledger:
        out.print(f"  {c.id}: {f.verdict}", markup=False)
    out.print(f"wrote {target}", markup=False)


@bench_app.command("compact")
def compact(
    folder: Annotated[Path, typer.Argument(help="A sweep's results folder (its runs/ shards).")],
    rows: Annotated[int, typer.Option(min=1, help="Rows per shard at most.")] = 20_000,
) -> None:
    """Rewrite a finished sweep's many small shards as a few large ones (the same runs, about a
    third fewer bytes for tens of thousands of small runs); reading and resuming see no
    difference."""
    from uavplan.bench.store import ResultStore, StoreError

    if not (folder / "runs").is_dir():
        raise _fail(f"{folder}: no runs/ folder (give the --out folder of `uavplan bench run`)")
    store = ResultStore(folder)
    size = sum(f.stat().st_size for f in store.shards())
    try:
        before, after = store.compact(rows)
    except StoreError as exc:
        raise _fail(f"compact: {exc}; every run is still in {folder / 'runs'}") from None
    now = sum(f.stat().st_size for f in store.shards())
    out.print(f"{folder}: {before} shards ({size / 1e6:.1f} MB) -> {after} ({now / 1e6:.1f} MB)",
              markup=False, highlight=False)  # fmt: skip


def _write_report(folder: Path) -> tuple[Path, Path]:
    """The report of ``folder``, or a one-line error (a shard that cannot be read, no space)."""
    from uavplan.bench.report import write_report
    from uavplan.bench.store import StoreError

    try:
        return write_report(folder)
    except StoreError as exc:
        raise _fail(f"report: {exc}") from None
    except OSError as exc:
        why = exc.strerror or exc
        raise _fail(f"report: cannot write to {folder}: {why}; the runs are kept; "
                    f"`uavplan report {folder}` writes the report again") from None  # fmt: skip
