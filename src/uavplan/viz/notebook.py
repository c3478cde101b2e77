"""Plans, results and scenarios shown in Jupyter: the HTML that IPython displays for them (a
summary table and the plan figure, inline). :func:`uavplan.notebook_display` registers
:func:`html` with IPython's HTML formatter by class name, so nothing here is imported until a
notebook shows one."""

from __future__ import annotations

import base64
import html as _html
import io
import math
from typing import Any

import numpy as np


def _figure_png(scenario: Any, results: Any, title: str) -> str:
    """The plan figure as an inline ``<img>``."""
    import matplotlib.pyplot as plt

    from uavplan.viz.figures import plan_figure

    fig = plan_figure(scenario, results, title)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=80, bbox_inches="tight")
    plt.close(fig)
    data = base64.b64encode(buf.getvalue()).decode("ascii")
    return f'<img alt="{_html.escape(title)}" src="data:image/png;base64,{data}"/>'


def _num(v: Any, fmt: str = ".6g") -> str:
    try:
        f = float(v)
    except (TypeError, ValueError):
        return ""
    return format(f, fmt) if math.isfinite(f) else "inf"


def _table(rows: list[list[str]], head: list[str]) -> str:
    th = "".join(f"<th>{_html.escape(h)}</th>" for h in head)
    body = "".join(
        "<tr>" + "".join(f"<td>{_html.escape(c)}</td>" for c in r) + "</tr>" for r in rows
    )
    return f"<table><thead><tr>{th}</tr></thead><tbody>{body}</tbody></table>"


def _result_rows(results: Any, limit: int = 25) -> list[list[str]]:
    rows = []
    for r in list(results)[:limit]:
        _, ft = r.flown_trajectory()
        rows.append([str(r.uav_id), "yes" if r.feasible else "NO",
                     "yes" if r.flown_feasible else "NO", _num(r.cost), _num(r.length, ".1f"),
                     _num(float(ft[-1] - ft[0]), ".1f")])  # fmt: skip
    return rows


_HEAD = ["UAV", "planned", "flown", "cost", "m", "flight s"]


def plan_html(plan: Any) -> str:
    """A :class:`~uavplan.planners.fleet.fleet_plan.FleetPlan`: its verdict, the UAVs' table (the
    first 25) and the figure."""
    n = len(plan.results)
    ok = sum(bool(r.flown_feasible) for r in plan.results)
    verdict = "flies" if plan.feasible else "does NOT fly"
    model = plan.scenario.execution
    under = f"; execution model: {model.describe()}" if model is not None else ""
    title = f"{plan.scenario.name}: {plan.algorithm}, seed {plan.seed}"
    more = f"<p>... and {n - 25} more UAVs</p>" if n > 25 else ""
    return (f"<div><p><b>{_html.escape(title)}</b>: {n} UAV(s), {ok} flown feasible; the plan "
            f"{verdict}{_html.escape(under)}</p>{_table(_result_rows(plan.results), _HEAD)}"
            f"{more}{_figure_png(plan.scenario, plan.results, title)}</div>")  # fmt: skip


def result_html(result: Any) -> str:
    """One UAV's :class:`~uavplan.planners.core.results.PlanResult`: its row."""
    return f"<div>{_table(_result_rows([result]), _HEAD)}</div>"


def scenario_html(scenario: Any) -> str:
    """A :class:`~uavplan.world.scenario.Scenario`: what is in it, and the map with its
    tasks' straight lines."""
    lo, hi = np.asarray(scenario.bounds.lo), np.asarray(scenario.bounds.hi)
    size = " x ".join(f"{float(h - low):,.0f}" for low, h in zip(lo, hi, strict=False))
    u = scenario.uav
    rows = [
        ["dimensions", f"{scenario.dim}-D, {size} m"],
        ["tasks", str(len(scenario.tasks))],
        ["terrain", getattr(scenario.terrain, "name", None) or "none"],
        ["UAV", f"{u.speed:g} m/s, turn radius {u.turn_radius:g} m, S2 {u.s2:g} m"],
    ]
    desc = _html.escape(scenario.description or "")
    figure = _figure_png(scenario, [], scenario.name)
    return (f"<div><p><b>{_html.escape(scenario.name)}</b> {desc}</p>"
            f"{_table(rows, ['', ''])}{figure}</div>")  # fmt: skip


def html(obj: Any) -> str:
    """The HTML IPython shows for a plan, a UAV's result or a scenario."""
    kind = type(obj).__name__
    if kind == "FleetPlan":
        return plan_html(obj)
    if kind == "PlanResult":
        return result_html(obj)
    return scenario_html(obj)
