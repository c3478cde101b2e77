"""A plan in one self-contained HTML page (``uavplan view``, and ``plan.html`` beside
``plan.png``): the terrain, the obstacles, every UAV's planned and flown paths, and a time slider
that plays the fleet and the moving obstacles. It opens offline: the page holds its data as JSON
and a small canvas-2D renderer of ours (``viewer.js``: an orthographic 3-D view turned with the
mouse), no library and no network.

Why not plotly or three.js: plotly's gl3d bundle alone is about 2 MB per page and both draw with
WebGL, which headless browsers and remote desktops often lack; a 2-D canvas draws a terrain of
at most 64 x 64 quads and hundreds of UAVs smoothly everywhere, and the page for 40 UAVs stays
far under 5 MB (the test measures it). The flown trajectories shown are the ones the plan
declares (what the verifier checks); the planned polylines are drawn thin and dashed.
"""

from __future__ import annotations

import json
from importlib import resources
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from uavplan.io.plan_file import PlanFile
    from uavplan.world.scenario import Scenario

#: at most this many terrain quads per side in the page
TERRAIN_SIDE = 64
#: at most this many points per drawn path (evenly resampled in index; the flown trajectory's
#: own points are kept when fewer)
PATH_POINTS = 400


def _r(a: Any, nd: int = 2) -> Any:
    return np.round(np.asarray(a, dtype=np.float64), nd).tolist()


def _thin(P: np.ndarray, T: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray | None]:
    if len(P) <= PATH_POINTS:
        return P, T
    k = np.unique(np.linspace(0, len(P) - 1, PATH_POINTS).round().astype(int))
    return P[k], (None if T is None else T[k])


def viewer_data(plan: PlanFile, scenario: Scenario | None) -> dict[str, Any]:
    """The page's JSON: bounds, terrain, obstacles, moving obstacles, UAVs."""
    dim = plan.dim
    uavs = []
    for u in plan.uavs:
        fl = u.trajectory("flown")
        P3 = np.zeros((len(fl.points), 3))
        P3[:, :dim] = fl.points
        F, T = _thin(P3, np.asarray(fl.times))
        Q = np.zeros((len(u.planned.points), 3))
        Q[:, :dim] = u.planned.points
        ok = u.flown_feasible if u.flown is not None else u.feasible
        uavs.append({"id": u.id, "flown": _r(F), "times": _r(T, 3), "planned": _r(_thin(Q)[0]),
                     "ok": ok})  # fmt: skip
    allp = np.vstack([np.asarray(u["flown"]) for u in uavs])
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    data: dict[str, Any] = {"name": plan.scenario or "plan", "dim": dim, "uavs": uavs,
                            "feasible": plan.feasible}  # fmt: skip
    if scenario is not None:
        b = scenario.bounds
        lo = np.minimum(lo, np.r_[b.lower, [0.0] * (3 - dim)])
        hi = np.maximum(hi, np.r_[b.upper, [0.0] * (3 - dim)])
        t = scenario.terrain
        if t is not None:
            ny, nx = t.shape
            sy, sx = max(1, -(-ny // TERRAIN_SIDE)), max(1, -(-nx // TERRAIN_SIDE))
            H = np.asarray(t.heights)
            # each shown node is the highest of the block it stands for: the page never shows a
            # path under a summit that the coarse picture flattened
            rows = np.maximum.reduceat(H, np.arange(0, ny, sy), axis=0)
            Hb = np.maximum.reduceat(rows, np.arange(0, nx, sx), axis=1)
            data["terrain"] = {"x0": t.x0, "y0": t.y0, "dx": t.dx * sx, "dy": t.dy * sy,
                               "h": _r(Hb, 1)}  # fmt: skip
        zlo, zhi = float(lo[2]), float(hi[2])
        cyl = [{"c": _r(c.center), "r": c.radius, "z": [max(c.z_min, zlo), min(c.z_max, zhi)]}
               for c in scenario.cylinders]  # fmt: skip
        disc = [{"c": _r(c.center), "r": c.radius, "z": [zlo, zhi]} for c in scenario.circles]
        data["cylinders"] = cyl + disc
        data["polygons"] = [{"v": _r(p.vertices), "z": [zlo, zhi]} for p in scenario.polygons]
        data["danger"] = [{"c": _r(d.center), "r": d.radius} for d in scenario.danger_areas]
        data["uncertain"] = [
            {"v": _r([[u.x, u.y], [u.x + u.width, u.y], [u.x + u.width, u.y + u.height],
                      [u.x, u.y + u.height]]), "known": u.revealed}
            for u in scenario.uncertain_areas
        ]  # fmt: skip
        data["moving"] = [
            {"r": m.radius, "t": _r(m.times, 3), "p": _r(np.asarray(m.positions)[:, :3])}
            for m in scenario.moving_obstacles
        ]
    data["bounds"] = {"lo": _r(lo), "hi": _r(hi)}
    return data


def viewer_html(plan: PlanFile, scenario: Scenario | None = None) -> str:
    """The whole page as one string."""
    js = resources.files("uavplan.viz").joinpath("viewer.js").read_text(encoding="utf-8")
    payload = json.dumps(viewer_data(plan, scenario), allow_nan=False, separators=(",", ":"))
    payload = payload.replace("</", "<\\/")  # no "</script>" inside the script
    title = (plan.scenario or "plan").replace("<", "&lt;")
    return (
        "<!doctype html>\n<html><head><meta charset='utf-8'>"
        f"<title>uavplan: {title}</title>"
        "<style>body{margin:0;font:13px sans-serif;background:#fff}"
        "#bar{display:flex;gap:8px;align-items:center;padding:6px 10px;"
        "border-bottom:1px solid #ccc}"
        "#time{flex:1}#legend{position:absolute;right:10px;top:44px;background:#fffd;"
        "padding:6px 8px;border:1px solid #ccc;line-height:1.5}canvas{display:block}</style>"
        "</head><body><div id='bar'><button id='play'>play</button>"
        "<input id='time' type='range' min='0' max='1000' value='0'><span id='clock'></span>"
        "</div><div id='legend'></div><canvas id='view'></canvas>"
        "<pre id='selftest' style='display:none'></pre>"
        f"<script>const DATA={payload};</script><script>{js}</script></body></html>\n"
    )
