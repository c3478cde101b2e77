"""Reference shortest paths for flat (2-D) scenes: a visibility graph searched with Dijkstra.

:func:`shortest_path` returns the length and the waypoints of the shortest feasible path from a
task's start to its goal among a 2-D scene's circles and polygons (the RGG-PSO+ scenes, Liu et
al. 2024, Sect. 5.2.1). Experiments normalize path lengths by it.

Graph. The nodes are the start, the goal, the *convex* vertices of every polygon (a shortest path
among polygons bends only there: at a reflex vertex, or where two obstacles cross, the free space
is locally convex and a path cannot be shortened by bending there), and the vertices of a regular
``m``-gon *circumscribed* about each circle (``m = circle_sides``, default 64). Nodes outside the
bounds are dropped. An edge joins two nodes when the segment between them is clear of the TRUE
obstacles (circles as circles, polygons as polygons), judged by the exact batched kernels of
:mod:`uavplan.world.geometry` with exactly the rule of
:class:`~uavplan.problems.path_problem.PathProblem` (a circle is hit when the distance from its
centre is ``< radius + margin``; a polygon when the distance is ``<= 0``). Dijkstra
(:func:`scipy.sparse.csgraph.dijkstra`) with predecessors gives the path.

Touching. A shortest path touches obstacles: it runs along polygon edges and around their
corners, and is tangent to circles. ``PathProblem`` calls a path that touches a polygon
infeasible (distance ``<= 0``), and floating point decides a tangent. So every obstacle node is
pushed outward by a tiny ``delta = 1e-9 x`` the largest extent of the bounds (1e-7 m in a
100 m scene): a polygon vertex along the outward bisector of its corner, and the circumscribed
``m``-gon of a circle of radius ``r`` has circumradius ``(r + delta) / cos(pi / m)`` (its edges
are tangent to the circle of radius ``r + delta``). Paths "along" an edge or "tangent" to a
circle then keep a clearance of order ``delta``, far above rounding (~1e-13 m), so every graph
edge, and so the returned path, is judged feasible by ``PathProblem`` by construction. The cost
is at most ``2 delta`` of extra length per bend (and the ``(r + delta) / r`` factor on arcs).

Accuracy. With polygons only, the result is the exact shortest path up to the ``delta`` push.
With circles it is an upper bound (the path is feasible) and, for a single circle,

    L_exact <= L <= L_exact / cos(pi / m)     (times (r + delta) / r),

because the graph contains the taut path around the circumscribed m-gon, the m-gon lies inside
the disc of radius ``r' = r / cos(pi / m)``, and the length ``L(r)`` of the tangent-arc path
satisfies ``dL/dr = (arc angle)``, so ``d(L/r)/dr = -(tangent lengths) / r^2 <= 0``, i.e.
``L(r') <= (r'/r) L(r)``. The same envelope argument (``dL/ds = arc length / s <= L / s`` when
every radius is scaled by ``s``) gives the bound for a whole scene as long as growing each
circle to ``r / cos(pi / m)`` closes no passage the optimum uses (true for the generated RGG
scenes, whose obstacles keep >= 1 m apart, far more than ``12 m x (1/cos(pi/64) - 1) = 0.015 m``).
For m = 64 the factor is ``1/cos(pi/64) = 1.0012``.

Batching and pruning. Candidate edges are all node pairs that are locally tangent at both ends
(a path bends around an obstacle node only if both of the node's neighbours on its polygon or
m-gon lie on one side of each incident edge: the classic "bitangent" filter, lenient by an
angle of 1e-6 rad so the ``delta`` push never removes an edge); they go through the kernels all
at once (in chunks that bound memory), with no Python loop over edges.

Not supported (``ValueError``): 3-D scenarios, moving obstacles, polygons with a margin.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from uavplan.world.geometry import cylinder_distances, segment_polygon_distance
from uavplan.world.scenario import Scenario, Task

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

__all__ = [
    "ANGLE_TOL",
    "DEFAULT_CIRCLE_SIDES",
    "OFFSET_REL",
    "circle_nodes",
    "polygon_nodes",
    "shortest_path",
]

#: Sides of the regular polygon circumscribed about each circle.
DEFAULT_CIRCLE_SIDES = 64
#: Outward push of every obstacle node, relative to the largest extent of the bounds.
OFFSET_REL = 1e-9
#: Angle (radians) under which a neighbour counts as on the edge line in the bitangent filter.
ANGLE_TOL = 1e-6
#: Candidate edges sent through the kernels at once.
_CHUNK = 1 << 17


# ---------------------------------------------------------------------------- nodes
def polygon_nodes(vertices: FloatArray, delta: float) -> tuple[FloatArray, FloatArray]:
    """Convex corners of a simple polygon pushed ``delta`` outward along their bisectors.

    Returns ``(nodes (k, 2), frames (k, 3, 2))``: ``frames[i]`` holds the original corner, its
    previous and its next vertex (for the bitangent filter).
    """
    v = np.asarray(vertices, dtype=np.float64)
    x, y = v[:, 0], v[:, 1]
    area2 = float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))
    if area2 < 0:  # make it counter-clockwise
        v = v[::-1]
    prev = np.roll(v, 1, axis=0)
    nxt = np.roll(v, -1, axis=0)
    a = prev - v
    b = nxt - v
    turn = (v[:, 0] - prev[:, 0]) * (nxt[:, 1] - v[:, 1]) - (v[:, 1] - prev[:, 1]) * (
        nxt[:, 0] - v[:, 0]
    )
    convex = turn > 0  # counter-clockwise: a left turn is a convex corner
    ua = a / np.linalg.norm(a, axis=1, keepdims=True)
    ub = b / np.linalg.norm(b, axis=1, keepdims=True)
    out = -(ua + ub)  # the interior bisector is ua + ub at a convex corner
    norm = np.linalg.norm(out, axis=1, keepdims=True)
    out = out / np.where(norm > 0, norm, 1.0)
    nodes = v + delta * out
    frames = np.stack([v, prev, nxt], axis=1)
    return np.asarray(nodes[convex]), np.asarray(frames[convex])


def circle_nodes(
    center: tuple[float, float], radius: float, sides: int, delta: float
) -> tuple[FloatArray, FloatArray]:
    """Vertices of the regular ``sides``-gon circumscribed about the circle of radius
    ``radius + delta`` (so its edges are tangent to that circle), and their frames (vertex,
    previous, next) as in :func:`polygon_nodes`."""
    if sides < 3:
        raise ValueError(f"circle_sides must be >= 3, got {sides}")
    theta = 2.0 * np.pi * np.arange(sides) / sides
    rho = (radius + delta) / np.cos(np.pi / sides)
    v = np.asarray(center, dtype=np.float64) + rho * np.stack([np.cos(theta), np.sin(theta)], 1)
    frames = np.stack([v, np.roll(v, 1, axis=0), np.roll(v, -1, axis=0)], axis=1)
    return v, frames


def _tangent_ok(frames: FloatArray, d: FloatArray) -> BoolArray:
    """Whether edge directions ``d`` (E, 2) leave the corners ``frames`` (E, 3, 2) tangentially:
    both neighbours on one side of the edge line (within :data:`ANGLE_TOL`)."""
    apex = frames[:, 0]
    a = frames[:, 1] - apex
    b = frames[:, 2] - apex
    dn = np.hypot(d[:, 0], d[:, 1])
    ca = d[:, 0] * a[:, 1] - d[:, 1] * a[:, 0]
    cb = d[:, 0] * b[:, 1] - d[:, 1] * b[:, 0]
    za = np.abs(ca) <= ANGLE_TOL * dn * np.hypot(a[:, 0], a[:, 1])
    zb = np.abs(cb) <= ANGLE_TOL * dn * np.hypot(b[:, 0], b[:, 1])
    return np.asarray((np.sign(ca) == np.sign(cb)) | za | zb)


# ---------------------------------------------------------------------------- edges
def _clear(
    a: FloatArray,
    b: FloatArray,
    centers: FloatArray,
    radii: FloatArray,
    verts: FloatArray,
    starts: NDArray[np.int64],
) -> BoolArray:
    """Segments ``a -> b`` (E, 2) clear of every circle and polygon, by PathProblem's rule."""
    ok = np.ones(len(a), dtype=bool)
    for lo in range(0, len(a), _CHUNK):
        hi = min(lo + _CHUNK, len(a))
        seg = np.ascontiguousarray(np.stack([a[lo:hi], b[lo:hi]], axis=1))
        good = np.ones(hi - lo, dtype=bool)
        if len(radii):
            n = len(radii)
            d = cylinder_distances(seg, centers, np.full(n, -np.inf), np.full(n, np.inf))
            good &= np.all(d[:, 0, :] >= radii, axis=1)
        if len(starts) > 1 and good.any():
            idx = np.flatnonzero(good)
            dp = segment_polygon_distance(np.ascontiguousarray(seg[idx]), verts, starts)
            good[idx] = np.all(dp[:, 0, :] > 0.0, axis=1)
        ok[lo:hi] = good
    return ok


# ---------------------------------------------------------------------------- search
def shortest_path(
    scenario: Scenario,
    circle_sides: int = DEFAULT_CIRCLE_SIDES,
    *,
    task: Task | str | int | None = None,
) -> tuple[float, FloatArray]:
    """Shortest feasible path of a 2-D scene's task (the first by default).

    Returns:
        ``(length, path)``: the length in metres and the waypoints ``(k, 2)``, start and goal
        included; ``(inf, empty (0, 2))`` if no feasible path exists (start or goal out of the
        bounds or inside an obstacle, or walled off). See the module notes for the accuracy with
        circles (within a factor ``1 / cos(pi / circle_sides)``).

    Raises:
        ValueError: a 3-D scenario, moving obstacles, or polygons with a margin.
    """
    sc = scenario
    if sc.dim != 2:
        raise ValueError("shortest_path handles 2-D scenarios only")
    if sc.moving_obstacles:
        raise ValueError("shortest_path ignores time: the scenario has moving obstacles")
    polys = sc.no_fly_polygons
    if any(p.margin > 0 for p in polys):
        raise ValueError("shortest_path does not support polygon margins")
    t = task if isinstance(task, Task) else sc.task(task)
    start = np.asarray(t.start, dtype=np.float64)
    goal = np.asarray(t.goal, dtype=np.float64)
    empty = np.zeros((0, 2))
    if not bool(sc.bounds.contains(start, tol=0.0)) or not bool(sc.bounds.contains(goal, tol=0.0)):
        return float("inf"), empty

    lo, hi = sc.bounds.lo, sc.bounds.hi
    delta = OFFSET_REL * float(np.max(hi - lo))
    centers = np.array([c.center for c in sc.circles], dtype=np.float64).reshape(-1, 2)
    radii = np.array([c.effective_radius for c in sc.circles], dtype=np.float64)
    verts, starts = sc.packed_polygons()

    node_parts = [np.stack([start, goal])]
    frame_parts = [np.full((2, 3, 2), np.nan)]
    for c in sc.circles:
        nodes, frames = circle_nodes(c.center, c.effective_radius, circle_sides, delta)
        node_parts.append(nodes)
        frame_parts.append(frames)
    for p in polys:
        nodes, frames = polygon_nodes(p.array, delta)
        node_parts.append(nodes)
        frame_parts.append(frames)
    xy = np.concatenate(node_parts)
    fr = np.concatenate(frame_parts)

    # drop obstacle nodes outside the bounds or inside an obstacle (edges from them would fail)
    keep = np.all((xy >= lo) & (xy <= hi), axis=1)
    if len(radii):
        dc = np.hypot(xy[:, None, 0] - centers[:, 0], xy[:, None, 1] - centers[:, 1])
        keep &= np.all(dc >= radii, axis=1)
    for p in polys:
        keep &= ~p.contains(xy)
    keep[:2] = True
    xy = xy[keep]
    fr = fr[keep]
    n = len(xy)

    if np.array_equal(start, goal):
        return 0.0, np.stack([start, goal])

    i, j = np.triu_indices(n, 1)
    d = xy[j] - xy[i]
    free = np.isnan(fr[:, 0, 0])  # the start and the goal bend any way
    cand = (free[i] | _tangent_ok(fr[i], d)) & (free[j] | _tangent_ok(fr[j], -d))
    i, j = i[cand], j[cand]
    ok = _clear(xy[i], xy[j], centers, radii, verts, starts)
    i, j = i[ok], j[ok]
    w = np.hypot(xy[j, 0] - xy[i, 0], xy[j, 1] - xy[i, 1])
    from scipy.sparse import coo_matrix  # lazy: SciPy's import is 0.3 s of a CLI start
    from scipy.sparse.csgraph import dijkstra

    w = np.maximum(w, 1e-300)  # an explicit zero would read as "no edge"
    graph = coo_matrix((w, (i, j)), shape=(n, n)).tocsr()
    dist, pred = dijkstra(graph, directed=False, indices=0, return_predecessors=True)
    if not np.isfinite(dist[1]):
        return float("inf"), empty
    order = [1]
    while order[-1] != 0:
        order.append(int(pred[order[-1]]))
    path = xy[order[::-1]]
    seg = np.diff(path, axis=0)
    return float(np.sum(np.hypot(seg[:, 0], seg[:, 1]))), np.asarray(path)
