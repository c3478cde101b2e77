"""Figures of scenarios and plans (matplotlib, Agg backend; the CLI and reports call these)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.patches import Circle as CirclePatch
from matplotlib.patches import Polygon as PolygonPatch
from matplotlib.patches import Rectangle

from uavplan.planners.results import PlanResult
from uavplan.world.scenario import Scenario

_MAX_SURFACE = 120  # grid nodes per side drawn in the 3-D view


def _terrain_xy(scenario: Scenario) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    t = scenario.terrain
    if t is None:
        return None
    ny, nx = t.shape
    xs = t.x0 + np.arange(nx) * t.dx
    ys = t.y0 + np.arange(ny) * t.dy
    return xs, ys, t.heights


def _colors(n: int) -> Any:
    """A colour per path: tab10 for a few, a continuous map for a fleet."""
    if n <= 10:
        cmap = plt.get_cmap("tab10")
        return lambda k: cmap(k % 10)
    cmap = plt.get_cmap("turbo")
    return lambda k: cmap(k / max(n - 1, 1))


def draw_top(ax: Axes, scenario: Scenario, results: Sequence[Any] = ()) -> None:
    """Top view: terrain shading and contours, obstacles and areas, paths, starts and goals.

    ``results``: objects with ``waypoints`` (n, dim), ``uav_id`` and ``feasible`` (PlanResult).
    """
    txy = _terrain_xy(scenario)
    if txy is not None:
        xs, ys, H = txy
        ax.imshow(
            H,
            origin="lower",
            extent=(xs[0], xs[-1], ys[0], ys[-1]),
            cmap="terrain",
            alpha=0.8,
            aspect="equal",
        )
        ax.contour(xs, ys, H, levels=12, colors="k", linewidths=0.4, alpha=0.5)
    for c in scenario.cylinders:
        ax.add_patch(CirclePatch(c.center, c.radius, color="tab:red", alpha=0.45, lw=0))
        if c.margin:
            ax.add_patch(
                CirclePatch(c.center, c.effective_radius, fill=False, ec="tab:red", lw=0.6)
            )
    for circ in scenario.circles:
        ax.add_patch(CirclePatch(circ.center, circ.radius, color="tab:purple", alpha=0.6, lw=0))
    for poly in scenario.polygons:
        ax.add_patch(PolygonPatch(poly.array, closed=True, color="tab:purple", alpha=0.6, lw=0))
    for d in scenario.danger_areas:
        ax.add_patch(CirclePatch(d.center, d.radius, color="gold", alpha=0.45, lw=0))
    for u in scenario.uncertain_areas:
        ax.add_patch(
            Rectangle(
                (u.x, u.y),
                u.width,
                u.height,
                color="tab:purple",
                alpha=0.35 if u.revealed else 0.15,
                hatch="//",
                lw=0.5,
            )
        )
    for m in scenario.moving_obstacles:
        ax.plot(m.positions[:, 0], m.positions[:, 1], ":", color="tab:gray", lw=1)
        ax.add_patch(
            CirclePatch((m.positions[0, 0], m.positions[0, 1]), m.radius, fill=False, ec="tab:gray")
        )
    color = _colors(len(results))
    many = len(results) > 10
    for k, r in enumerate(results):
        w = np.asarray(r.waypoints)
        sm = getattr(r, "smoothed", None)
        ax.plot(
            w[:, 0],
            w[:, 1],
            "-",
            color=color(k),
            lw=0.7 if many else 1.6,
            alpha=0.5 if sm is not None else 1.0,
            label=f"{r.uav_id} ({'feasible' if r.feasible else 'infeasible'})",
        )
        if sm is not None:  # PPSwarm Fig. 11: solid planned path, dashed Dubins-smoothed one
            sm = np.asarray(sm)
            ax.plot(sm[:, 0], sm[:, 1], "--", color=color(k), lw=0.7 if many else 1.2)
        if not many:
            ax.plot(w[1:-1, 0], w[1:-1, 1], ".", color=color(k), ms=4)
    ms = 3 if len(scenario.tasks) > 40 else 7
    for t in scenario.tasks:
        ax.plot(*t.start[:2], "o", color="green", ms=ms, mec="k", mew=0.5)
        ax.plot(*t.goal[:2], "*", color="red", ms=ms * 1.5, mec="k", mew=0.5)
    lo, hi = scenario.bounds.lo, scenario.bounds.hi
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    if results and len(results) <= 10:
        ax.legend(loc="upper left", fontsize=7)


def draw_3d(ax: Any, scenario: Scenario, results: Sequence[PlanResult] = ()) -> None:
    """3-D view: terrain surface, cylinders as wireframes, paths."""
    txy = _terrain_xy(scenario)
    zmax = 0.0
    if txy is not None:
        xs, ys, H = txy
        sy = max(1, len(ys) // _MAX_SURFACE)
        sx = max(1, len(xs) // _MAX_SURFACE)
        X, Y = np.meshgrid(xs[::sx], ys[::sy])
        ax.plot_surface(
            X,
            Y,
            H[::sy, ::sx],
            cmap="terrain",
            alpha=0.6,
            linewidth=0,
            antialiased=False,
        )
        zmax = float(H.max())
    paths_top = [float(np.max(r.waypoints[:, 2])) for r in results if r.waypoints.shape[1] == 3]
    top = max([zmax, *paths_top]) + 50.0
    theta = np.linspace(0, 2 * np.pi, 40)
    for c in scenario.cylinders:
        z0 = (
            float(scenario.ground(np.array(c.center[0]), np.array(c.center[1])))
            if np.isinf(c.z_min)
            else c.z_min
        )
        z1 = top if np.isinf(c.z_max) else c.z_max
        cx = c.center[0] + c.radius * np.cos(theta)
        cy = c.center[1] + c.radius * np.sin(theta)
        for z in (float(z0), float(z1)):
            ax.plot(cx, cy, z, color="tab:red", lw=0.8)
        for k in range(0, len(theta), 5):
            ax.plot([cx[k], cx[k]], [cy[k], cy[k]], [float(z0), float(z1)], color="tab:red", lw=0.4)
    color = _colors(len(results))
    for k, r in enumerate(results):
        sm = getattr(r, "smoothed", None)
        w = np.asarray(sm if sm is not None else r.waypoints)
        zs = w[:, 2] if w.shape[1] == 3 else np.zeros(len(w))
        ax.plot(w[:, 0], w[:, 1], zs, "-", color=color(k), lw=2 if len(results) <= 10 else 0.8)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_zlabel("z (m)")


def plan_figure(scenario: Scenario, results: Sequence[PlanResult], title: str = "") -> Figure:
    """A figure with the top view and, for 3-D scenarios, a 3-D view."""
    if scenario.dim == 3:
        fig = plt.figure(figsize=(13, 6))
        ax1 = fig.add_subplot(1, 2, 1)
        ax2 = fig.add_subplot(1, 2, 2, projection="3d")
        draw_top(ax1, scenario, results)
        draw_3d(ax2, scenario, results)
    else:
        fig = plt.figure(figsize=(7, 7))
        draw_top(fig.add_subplot(1, 1, 1), scenario, results)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return fig


def save_plan_figure(
    scenario: Scenario, results: Sequence[PlanResult], path: str | Path, title: str = ""
) -> Path:
    fig = plan_figure(scenario, results, title)
    out = Path(path)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out
