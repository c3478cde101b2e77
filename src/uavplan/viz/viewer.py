"""A plan in one self-contained HTML page (``uavplan view``, and ``plan.html`` beside
``plan.png``): the terrain as a lit, coloured mesh, obstacles as solids, danger and uncertain
areas, moving obstacles in time, every UAV as a marker with a trail along its flown trajectory,
play/pause and a time slider, a click on a UAV for its id, verdict and margins, a scale bar and a
north arrow. It opens offline: the page holds its data as JSON, a minified build of three.js
(``vendor/three.min.js``, MIT, built as ``vendor/BUILD.md`` says) and our renderer
(``viewer.js``), no network.

Why three.js: users of 3-D fleet views expect depth, lighting and solids, and three.js is the
most used WebGL library; the classes the viewer uses come to about 0.6 MB minified. What a page
may hold is bounded so that a 1,000-UAV plan stays a few megabytes: the terrain at most
:data:`TERRAIN_SIDE` nodes a side (each the highest of the block it stands for, so no summit is
flattened under a path), and the flown paths at most :data:`PATH_POINTS` points each and
:data:`PATH_BUDGET` in all (evenly resampled in index, the ends kept). The flown trajectories
shown are the ones the plan declares (what the verifier checks); the planned polylines are drawn
thin and dashed.
"""

from __future__ import annotations

import json
from collections.abc import Collection, Mapping
from importlib import resources
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from uavplan.io.plan_file import PlanFile
    from uavplan.world.scenario import Scenario

#: at most this many terrain nodes per side in the page
TERRAIN_SIDE = 160
#: at most this many points per drawn path
PATH_POINTS = 400
#: at most this many flown-path points in a page in all (a 1,000-UAV plan: 200 each)
PATH_BUDGET = 200_000


def _flat(a: Any, nd: int) -> list[float]:
    out: list[float] = np.round(np.asarray(a, dtype=np.float64), nd).ravel().tolist()
    return out


def _r(a: Any, nd: int = 2) -> Any:
    return np.round(np.asarray(a, dtype=np.float64), nd).tolist()


def _thin(P: np.ndarray, cap: int, T: np.ndarray | None = None) -> tuple[np.ndarray, Any]:
    if len(P) <= cap:
        return P, T
    k = np.unique(np.linspace(0, len(P) - 1, cap).round().astype(int))
    return P[k], (None if T is None else T[k])


def _xyz(points: Any, dim: int) -> np.ndarray:
    P = np.zeros((len(points), 3))
    P[:, :dim] = points
    return P


def _margins(plan: PlanFile) -> dict[str, Any]:
    rows = (plan.margins or {}).get("uavs") or []
    return {str(m.get("uav")): m for m in rows if isinstance(m, Mapping)}


def viewer_data(
    plan: PlanFile, scenario: Scenario | None, rejected: Collection[str] | None = None
) -> dict[str, Any]:
    """The page's JSON: bounds, terrain, obstacles, moving obstacles, UAVs (flat ``x, y, z``
    lists). ``rejected``: the UAVs the independent verifier rejected (drawn red, and the page
    says the plan is not to be flown)."""
    dim = plan.dim
    bad = set(rejected or ())
    cap = max(40, min(PATH_POINTS, PATH_BUDGET // max(1, len(plan.uavs))))
    margins = _margins(plan)
    uavs, lows, highs = [], [], []
    for u in plan.uavs:
        fl = u.trajectory("flown")
        F3 = _xyz(fl.points, dim)
        lows.append(F3.min(axis=0))
        highs.append(F3.max(axis=0))
        F, T = _thin(F3, cap, np.asarray(fl.times, dtype=np.float64))
        Q = _thin(_xyz(u.planned.points, dim), cap)[0]
        ok = u.flown_feasible if u.flown is not None else u.feasible
        why = list(u.flown_violations if u.flown is not None else u.violations)
        if u.id in bad:
            ok, why = False, [*why, "rejected by the independent verifier"]
        length = float(np.linalg.norm(np.diff(F3, axis=0), axis=1).sum())
        uavs.append({"id": u.id, "ok": ok, "why": why, "f": _flat(F, 1), "t": _flat(T, 2),
                     "p": _flat(Q, 1), "len": round(length, 1),
                     "m": margins.get(u.id)})  # fmt: skip
    lo, hi = np.min(lows, axis=0), np.max(highs, axis=0)
    data: dict[str, Any] = {"name": plan.scenario or "plan", "dim": dim, "uavs": uavs,
                            "feasible": plan.feasible and not bad,
                            "rejected": bool(bad), "execution": plan.execution}  # fmt: skip
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
                               "nx": Hb.shape[1], "ny": Hb.shape[0], "h": _flat(Hb, 1)}  # fmt: skip
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
            {"r": m.radius, "t": _r(m.times, 3), "p": _r(_xyz(np.asarray(m.positions)[:, :dim],
                                                            dim))}
            for m in scenario.moving_obstacles
        ]  # fmt: skip
    data["bounds"] = {"lo": _r(lo), "hi": _r(hi)}
    return data


def _asset(*parts: str) -> str:
    return resources.files("uavplan.viz").joinpath(*parts).read_text(encoding="utf-8")


def viewer_html(
    plan: PlanFile, scenario: Scenario | None = None, rejected: Collection[str] | None = None
) -> str:
    """The whole page as one string (``rejected``: as :func:`viewer_data`)."""
    payload = json.dumps(viewer_data(plan, scenario, rejected), allow_nan=False,
                         separators=(",", ":"))  # fmt: skip
    payload = payload.replace("</", "<\\/")  # no "</script>" inside the script
    title = (plan.scenario or "plan").replace("&", "&amp;").replace("<", "&lt;")
    return (
        "<!doctype html>\n<html><head><meta charset='utf-8'>"
        "<meta name='viewport' content='width=device-width,initial-scale=1'>"
        f"<title>uavplan: {title}</title><style>{_asset('viewer.css')}</style></head><body>"
        "<div id='bar'><button id='play'>play</button>"
        "<input id='time' type='range' min='0' max='1000' value='0'><span id='clock'></span>"
        "<label><input id='planned' type='checkbox'> planned</label>"
        "<label><input id='labels' type='checkbox'> ids</label></div>"
        "<div id='view'></div><div id='legend'></div><div id='info'></div>"
        "<div id='scale'><div id='scalebar'></div><span id='scaletext'></span></div>"
        "<div id='north' title='north'><svg viewBox='-12 -18 24 36' width='24' height='36'>"
        "<text x='0' y='-9' font-size='10' font-weight='bold' text-anchor='middle'>N</text>"
        "<path d='M0 -6 L6 16 L0 12 L-6 16 Z' fill='#222'/></svg></div><div id='labelbox'></div>"
        "<pre id='selftest' style='display:none'></pre>"
        f"<script>const DATA={payload};</script>"
        f"<script>{_asset('vendor', 'three.min.js')}</script>"
        f"<script>{_asset('viewer.js')}</script></body></html>\n"
    )
