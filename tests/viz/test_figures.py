"""Every kind of plan figure renders, is not blank, and says what it shows (issue 17 item 3:
colour bar, legend of every kind drawn, km past 5 km, failing UAVs marked)."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from matplotlib import image

from uavplan.scenarios import resolve
from uavplan.viz.figures import plan_figure, save_plan_figure


def _straight(sc, k: int, ok: bool = True) -> SimpleNamespace:  # type: ignore[no-untyped-def]
    t = sc.tasks[k]
    w = np.linspace(np.asarray(t.start), np.asarray(t.goal), 6)
    return SimpleNamespace(waypoints=w, uav_id=t.id, feasible=ok)


@pytest.mark.parametrize("name", ["simple2d", "ppswarm1@4", "rscdwoa-mixed", "hrmaga-jacksboro"])
def test_plan_figures_render_with_legend_and_units(tmp_path: Path, name: str) -> None:
    sc = resolve(name)
    results = [_straight(sc, k, ok=k != 1) for k in range(min(4, len(sc.tasks)))]
    fig = plan_figure(sc, results, name)
    top = fig.axes[0]
    legend = [t.get_text() for t in top.get_legend().get_texts()]
    assert "start" in legend and "goal" in legend
    if len(results) > 1:
        assert any("FAILS a check" in t for t in legend)
    if sc.cylinders:
        assert "cylinder" in legend
    if sc.moving_obstacles:
        assert "moving obstacle (track)" in legend
    span = max(np.subtract(sc.bounds.hi, sc.bounds.lo)[:2])
    assert top.get_xlabel() == ("x (km)" if span > 5000 else "x (m)")
    if sc.terrain is not None:
        assert any(a.get_ylabel() == "terrain height (m)" for a in fig.axes)  # the colour bar
    path = save_plan_figure(sc, results, tmp_path / "p.png", name)
    img = image.imread(path)[..., :3]
    assert (img < 0.95).any(axis=2).mean() > 0.1  # not blank


def test_a_large_fleet_gets_a_colour_key(tmp_path: Path) -> None:
    """More than 10 UAVs: no line each in the legend, a colour key from the first UAV's id to
    the last's instead, and the failing count in the legend."""
    sc = resolve("ppswarm1@15")
    results = [_straight(sc, k, ok=k != 3) for k in range(15)]
    fig = plan_figure(sc, results, "fleet")
    legend = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert "15 UAVs (colour key), 1 failing (red)" in legend
    keys = [a for a in fig.axes if "in plan.json's order" in a.get_xlabel()]
    assert len(keys) == 1
    assert [t.get_text() for t in keys[0].get_xticklabels()] == [sc.tasks[0].id, sc.tasks[14].id]
    path = save_plan_figure(sc, results, tmp_path / "f.png", "fleet")
    img = image.imread(path)[..., :3]
    assert (img < 0.95).any(axis=2).mean() > 0.1
