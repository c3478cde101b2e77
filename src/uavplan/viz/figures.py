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

from uavplan.planners.core.results import PlanResult
from uavplan.world.scenario import Scenario

_MAX_SURFACE = 120  # grid nodes per side drawn in the 3-D view
_MAX_CONTOUR = 300  # grid nodes per side the top view's contours are traced on


def _terrain_xy(scenario: Scenario) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    t = scenario.terrain
    if t is None:
        return None
    ny, nx = t.shape
    xs = t.x0 + np.arange(nx) * t.dx
    ys = t.y0 + np.arange(ny) * t.dy
    return xs, ys, t.heights


#: past this extent (m) the axes are labelled in km
KM_FROM = 5000.0


def _in_km(scenario: Scenario) -> bool:
    lo, hi = scenario.bounds.lo, scenario.bounds.hi
    return bool(max(hi[0] - lo[0], hi[1] - lo[1]) > KM_FROM)


def _label_axes(ax: Any, scenario: Scenario, zlabel: bool = False) -> None:
    """x, y (and z) labels in m, or in km with km ticks past :data:`KM_FROM`."""
    from matplotlib.ticker import FuncFormatter

    km = _in_km(scenario)
    unit = "km" if km else "m"
    if km:
        fmt = FuncFormatter(lambda v, _: f"{v / 1000:g}")
        ax.xaxis.set_major_formatter(fmt)
        ax.yaxis.set_major_formatter(fmt)
    ax.set_xlabel(f"x ({unit})")
    ax.set_ylabel(f"y ({unit})")
    if zlabel:
        ax.set_zlabel("z (m)")


def _flown(r: Any) -> tuple[np.ndarray, bool]:
    """A result's trajectory as flown (declared; the planned polyline otherwise) and whether
    it passes every check."""
    fn = getattr(r, "flown_trajectory", None)
    pts = np.asarray(fn()[0]) if callable(fn) else np.asarray(r.waypoints)
    return pts, bool(getattr(r, "flown_feasible", r.feasible))


def _legend(ax: Axes, scenario: Scenario, results: Sequence[Any]) -> None:
    """Every kind of thing drawn: the UAVs (a line each up to 10), planned vs flown, starts and
    goals, and the obstacle and area kinds present; below the axes."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    handles: list[Any] = []
    if len(results) <= 10:
        color = _colors(len(results))
        for k, r in enumerate(results):
            ok = _flown(r)[1]
            label = f"{r.uav_id}" + ("" if ok else " (FAILS a check)")
            handles.append(Line2D([], [], color=color(k), lw=1.6 if ok else 3, label=label))
    elif results:
        bad = sum(not _flown(r)[1] for r in results)
        label = f"{len(results)} UAVs (colour key)" + (f", {bad} failing (red)" if bad else "")
        handles.append(Line2D([], [], color=_colors(len(results))(0), lw=1, label=label))
    if results:
        handles.append(Line2D([], [], color="k", lw=1.6, label="flown trajectory"))
        handles.append(Line2D([], [], color="k", lw=0.8, ls="--", label="planned polyline"))
    handles.append(Line2D([], [], ls="", marker="o", color="green", mec="k", label="start"))
    handles.append(Line2D([], [], ls="", marker="*", color="red", mec="k", ms=10, label="goal"))
    kinds = [(scenario.cylinders, Patch(color="tab:red", alpha=0.45, label="cylinder")),
             (scenario.circles, Patch(color="tab:purple", alpha=0.6, label="circle")),
             (scenario.polygons, Patch(color="tab:purple", alpha=0.6, label="polygon")),
             (scenario.danger_areas, Patch(color="gold", alpha=0.45, label="danger area")),
             (scenario.uncertain_areas,
              Patch(fc="tab:purple", alpha=0.35, hatch="//", label="uncertain area")),
             (scenario.moving_obstacles,
              Line2D([], [], color="tab:gray", ls=":", marker="o", mfc="none",
                     label="moving obstacle (track)"))]  # fmt: skip
    handles += [h for objs, h in kinds if objs]
    void = scenario.terrain.georef.get("void_mask") if scenario.terrain is not None else None
    if void is not None and np.any(void):
        handles.append(Patch(fc="none", ec="0.3", hatch="////", label="no data in the DEM"))
    ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, -0.1), ncol=4,
              fontsize=7, frameon=False)  # fmt: skip


def _colors(n: int) -> Any:
    """A colour per path: tab10 for a few, a continuous map for a fleet."""
    if n <= 10:
        cmap = plt.get_cmap("tab10")
        return lambda k: cmap(k % 10)
    cmap = plt.get_cmap("turbo")
    return lambda k: cmap(k / max(n - 1, 1))


def draw_top(
    ax: Axes, scenario: Scenario, results: Sequence[Any] = (), colorbar: bool = True
) -> None:
    """Top view: terrain shading and contours (with a colour bar), obstacles and areas, each
    UAV's flown trajectory (solid; a UAV that fails a check thick, with a red edge) over its
    planned polyline (dashed), starts and goals, and a legend of all of them.

    ``results``: objects with ``waypoints`` (n, dim), ``uav_id`` and ``feasible`` (PlanResult,
    whose flown trajectory is drawn when it declares one).
    """
    txy = _terrain_xy(scenario)
    if txy is not None:
        xs, ys, H = txy
        im = ax.imshow(
            H,
            origin="lower",
            extent=(xs[0], xs[-1], ys[0], ys[-1]),
            cmap="terrain",
            alpha=0.8,
            aspect="equal",
        )
        # contours of a finer grid look the same; each axis keeps its own step (a long, thin
        # grid keeps its short side whole, which contour needs at least 2 nodes of)
        sy, sx = (max(1, n // _MAX_CONTOUR) for n in H.shape)
        ax.contour(xs[::sx], ys[::sy], H[::sy, ::sx], levels=12, colors="k",
                   linewidths=0.4, alpha=0.5)  # fmt: skip
        if colorbar:
            ax.figure.colorbar(im, ax=ax, fraction=0.04, pad=0.02, label="terrain height (m)")
        void = scenario.terrain.georef.get("void_mask") if scenario.terrain is not None else None
        if void is not None and np.any(void):  # no data in the raster: hatched, not a plateau
            ax.contourf(xs, ys, np.asarray(void, dtype=float), levels=[0.5, 1.5], colors="none",
                        hatches=["////"])  # fmt: skip
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
    from matplotlib import patheffects

    color = _colors(len(results))
    many = len(results) > 10
    # a fleet's lines go in one collection per style (a Line2D each costs seconds at 1,000)
    planned: list[tuple[np.ndarray, Any]] = []
    lines: list[tuple[np.ndarray, Any]] = []
    for k, r in enumerate(results):
        w = np.asarray(r.waypoints)
        flown, ok = _flown(r)
        col = color(k)
        halo = [] if ok else [patheffects.withStroke(linewidth=4.5, foreground="red")]
        if flown.shape != w.shape or not np.allclose(flown, w):
            if many:
                planned.append((w[:, :2], col))
            else:
                ax.plot(w[:, 0], w[:, 1], "--", color=col, lw=0.9, alpha=0.8)
        if many and ok:
            lines.append((flown[:, :2], col))
        else:
            ax.plot(flown[:, 0], flown[:, 1], "-", color=col, lw=0.8 if many else 1.6,
                    path_effects=halo)  # fmt: skip
        if not many:
            if len(w) <= 60:  # a planner's waypoints, not a trajectory stepped in time
                ax.plot(w[1:-1, 0], w[1:-1, 1], ".", color=col, ms=4)
            at = (float(w[0, 0]), float(w[0, 1]))
            ax.annotate(str(r.uav_id), at, xytext=(4, 4), textcoords="offset points", fontsize=7)
    from matplotlib.collections import LineCollection

    for group, style, lw, alpha in ((planned, "--", 0.6, 0.8), (lines, "-", 0.8, 1.0)):
        if group:
            ax.add_collection(LineCollection([g for g, _ in group],
                                             colors=[c for _, c in group], linestyles=style,
                                             linewidths=lw, alpha=alpha))  # fmt: skip
    ms = 3 if len(scenario.tasks) > 40 else 7
    if scenario.tasks:
        S = np.array([t.start[:2] for t in scenario.tasks])
        G = np.array([t.goal[:2] for t in scenario.tasks])
        ax.plot(S[:, 0], S[:, 1], "o", color="green", ms=ms, mec="k", mew=0.5, ls="none")
        ax.plot(G[:, 0], G[:, 1], "*", color="red", ms=ms * 1.5, mec="k", mew=0.5, ls="none")
    lo, hi = scenario.bounds.lo, scenario.bounds.hi
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_aspect("equal")
    _label_axes(ax, scenario)
    _legend(ax, scenario, results)


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
            alpha=0.35,  # the paths stay visible through it
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
    outlines = [np.asarray(p.array) for p in scenario.polygons]
    outlines += [np.column_stack([c.center[0] + c.radius * np.cos(theta),
                                  c.center[1] + c.radius * np.sin(theta)])
                 for c in scenario.circles]  # fmt: skip
    for V in outlines:
        V = np.vstack([V, V[:1]])
        g0 = float(np.min(scenario.ground(V[:, 0], V[:, 1])))
        for z in (g0, top):
            ax.plot(V[:, 0], V[:, 1], np.full(len(V), z), color="tab:purple", lw=0.8)
        for v in V[:: max(1, len(V) // 8)]:
            ax.plot([v[0], v[0]], [v[1], v[1]], [g0, top], color="tab:purple", lw=0.4)
    color = _colors(len(results))
    many = len(results) > 10
    lines: list[tuple[np.ndarray, Any]] = []
    for k, r in enumerate(results):
        w, ok = _flown(r)
        zs = w[:, 2] if w.shape[1] == 3 else np.zeros(len(w))
        if many and ok:
            lines.append((np.column_stack([w[:, 0], w[:, 1], zs]), color(k)))
            continue
        lw = (2 if not many else 0.8) * (1 if ok else 1.8)
        ax.plot(w[:, 0], w[:, 1], zs, "-", color=color(k) if ok else "red", lw=lw)
    if lines:
        from mpl_toolkits.mplot3d.art3d import Line3DCollection

        # one collection has one depth: drawn in a fixed order instead (the surface, the
        # paths and obstacles, the starts and goals on top), not sorted by depth
        ax.computed_zorder = False
        ax.add_collection3d(Line3DCollection([g for g, _ in lines], colors=[c for _, c in lines],
                                             linewidths=0.8, zorder=2))  # fmt: skip
    shown = [t for t in scenario.tasks[:200] if len(t.start) == 3]
    for t in [] if lines else shown:  # sorted by depth with the paths, one artist each
        ax.scatter(*t.start, color="green", s=12, edgecolors="k", linewidths=0.4)
        ax.scatter(*t.goal, color="red", marker="*", s=30, edgecolors="k", linewidths=0.4)
    if shown and lines:
        S = np.array([t.start for t in shown])
        G = np.array([t.goal for t in shown])
        ax.scatter(S[:, 0], S[:, 1], S[:, 2], color="green", s=12, edgecolors="k",
                   linewidths=0.4, zorder=3, depthshade=False)  # fmt: skip
        ax.scatter(G[:, 0], G[:, 1], G[:, 2], color="red", marker="*", s=30, edgecolors="k",
                   linewidths=0.4, zorder=3, depthshade=False)  # fmt: skip
    _label_axes(ax, scenario, zlabel=True)


def _uav_key(fig: Figure, ax: Any, results: Sequence[Any]) -> None:
    """The colour key of a fleet's paths (more than 10 UAVs, no line each in the legend): UAV
    number in plan.json's order, its ids at the ends."""
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import Normalize

    n = len(results)
    sm = ScalarMappable(norm=Normalize(0, n - 1), cmap=plt.get_cmap("turbo"))
    bar = fig.colorbar(sm, ax=ax, orientation="horizontal", fraction=0.035, pad=0.1, aspect=40)
    bar.set_ticks([0, n - 1])
    bar.set_ticklabels([str(results[0].uav_id), str(results[-1].uav_id)])
    bar.set_label(f"UAV, in plan.json's order ({n}); failing ones in red", fontsize=8)
    bar.ax.tick_params(labelsize=7)


def plan_figure(scenario: Scenario, results: Sequence[PlanResult], title: str = "") -> Figure:
    """A figure with the top view and, for 3-D scenarios, a 3-D view; a fleet of more than 10
    UAVs gets a colour key for its paths."""
    if scenario.dim == 3:
        fig = plt.figure(figsize=(13, 6.6 if len(results) > 10 else 6))
        ax1 = fig.add_subplot(1, 2, 1)
        ax2 = fig.add_subplot(1, 2, 2, projection="3d")
        draw_top(ax1, scenario, results)
        draw_3d(ax2, scenario, results)
    else:
        fig = plt.figure(figsize=(7, 7.6 if len(results) > 10 else 7))
        ax2 = ax1 = fig.add_subplot(1, 1, 1)
        draw_top(ax1, scenario, results)
    if len(results) > 10:
        _uav_key(fig, ax2, results)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return fig


def save_plan_figure(
    scenario: Scenario, results: Sequence[PlanResult], path: str | Path, title: str = ""
) -> Path:
    fig = plan_figure(scenario, results, title)
    out = Path(path)
    fig.savefig(out, dpi=110, bbox_inches="tight")  # nothing clipped: labels, legend, colour bar
    plt.close(fig)
    return out
