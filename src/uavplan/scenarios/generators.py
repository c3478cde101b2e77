"""The random 2-D scene family of RGG-PSO+ (Liu et al. 2024, Sect. 5.2.1), reproducibly.

The paper evaluates on 1000 random scenes: a 100 x 100 scene, "5-15 obstacles randomly distributed
in different sizes" (circles and polygons, Fig. 1), 100 scenes per obstacle setting, always with a
feasible (and an optimal) path, never with the straight start-goal segment as the optimum. It gives
no generator; the choices below are ours.

* **Settings.** Ten obstacle counts, ``SETTINGS = (5, 6, ..., 14)`` (``range(5, 15)``: the paper's
  "5-15" with 15 as the exclusive end, the only reading that gives 10 settings of consecutive
  counts starting at 5); 100 scenes each = 1000. Any other counts can be asked for.
* **Seeds.** Scene ``(n, index)`` draws everything from
  ``np.random.SeedSequence(entropy=root_seed, spawn_key=(n, index))``: a scene does not depend on
  which others are generated, or in what order.
* **Scene.** Bounds ``[0, 100]^2``; start uniform in ``[5, 10]^2``, goal uniform in ``[90, 95]^2``
  (opposite corners, as in Fig. 1); cost ``length2d`` (RGG-PSO+ Sect. 3), ``n_waypoints = 20``
  (the paper's N = 20, Sect. 5.2.2).
* **Obstacles.** Each is a circle (probability 0.4), a convex polygon (0.3) or a non-convex polygon
  (0.3), drawn independently. Each has a bounding circle of radius ``r ~ U(4, 12)`` m ("different
  sizes"): a circle is that disc; a convex polygon has 3-8 vertices on it (evenly spaced angles,
  jittered by up to 35 % of the spacing, random rotation); a non-convex polygon is star-shaped
  with 5-10 vertices at such angles and radii ``U(0.35, 1) r`` (the largest set to ``r``),
  redrawn until at least one corner is reflex.
* **No overlap.** Bounding circles keep at least ``GAP = 1`` m from each other and from the box
  walls, and ``CLEARANCE = 2`` m from the start and the goal (which are thus outside every
  obstacle). So each obstacle counts as one (the obstacle count is the complexity measure), every
  passage is at least 1 m wide, and the circle approximation of the reference path
  (:mod:`uavplan.world.visibility`) keeps its ``1 / cos(pi / 64)`` bound. Obstacles are placed one
  after another, each with up to 500 tries; a scene that cannot place all restarts.
* **Rounding.** Coordinates and radii are rounded to 1 mm (3 decimals) *before* any check, so a
  scenario file holds exactly the scene the reference was computed for.
* **Rejection.** A scene is redrawn (same random stream, continued) unless (a) the straight
  start-goal segment is infeasible (``PathProblem(...).evaluate``), (b) the visibility-graph
  shortest path is finite, (c) that path is feasible by ``PathProblem``, and (d) it is at least
  ``MIN_DETOUR = 0.1`` m longer than the straight segment. (d) is our strengthening of the paper's
  "the optimal path is not the segment": without it about 4 % of the scenes have an optimum
  within 1 cm of the segment (it merely grazes an obstacle), which no planner can tell apart
  from the segment at the 1 mm precision of the coordinates; about 13 % of first draws fail (d).
* **Metadata.** The generator parameters, the obstacle kinds, the number of attempts and why
  earlier attempts were rejected, the straight-line distance, ``reference_length`` (the shortest
  path length, metres) and ``reference_path`` (its waypoints, a list of ``[x, y]``).

Export. The scenario file format has no metadata field, so :func:`export_family` writes one YAML
file per scene (``<name>.yaml``) and a sidecar ``references.csv`` with columns ``name,
n_obstacles, index, root_seed, reference_length, reference_path`` (the path as JSON);
:func:`read_references` reads it back and :func:`load_family` loads the files with the references
put back into ``metadata``. The length also appears in each file's description, for people.

The dense cylinder field. :func:`dense_cylinders` draws the cylinders of the ``dense`` built-in
(``dense.yaml``, the SPSO map with a dense field of infinitely tall cylinders for large-fleet
experiments); the built-in is the YAML file, which ``dense_cylinders()`` (its defaults, seed
``DENSE_SEED``) reproduces exactly. Our choices:

* **Field.** The cylinders (with S1 beyond their edge) keep inside the x/y bounds shrunk by the
  fleet edge margin ``max(turn_radius, s1)`` and then by the ``"crossing"`` band depth
  (``BAND_FRACTION`` of the shorter side, :func:`uavplan.world.fleet_tasks.placement_box`), so
  the fleet start and goal bands along the edges stay free.
* **Draw.** ``n`` radii ``U(20, 50)`` m, rounded to whole metres and placed largest first (a
  denser packing than in drawing order); each centre is uniform in the field (rounded to 0.1 m
  *before* any check, so the file holds exactly the checked values), the first of ``DENSE_TRIES``
  candidates (drawn at once) whose edge gap to every placed cylinder is at least ``min_gap``
  (default ``1.5 * S1`` = 22.5 m); a draw that cannot place all starts over (same random stream,
  continued), up to ``DENSE_ATTEMPTS`` draws.
* At this density many neighbours end up 22.5-45 m (1.5-3 S1) apart: narrow passages.
"""

from __future__ import annotations

import csv
import io
import json
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from uavplan.problems.path_problem import PathProblem
from uavplan.scenarios.names import PER_SETTING, SETTINGS, family_names, rgg_name
from uavplan.world.fleet_tasks import BAND_FRACTION
from uavplan.world.obstacles import Circle, Cylinder, Polygon
from uavplan.world.scenario import Bounds, Scenario, Task
from uavplan.world.visibility import DEFAULT_CIRCLE_SIDES, shortest_path

FloatArray = NDArray[np.float64]

__all__ = [
    "CIRCLE_SIDES",
    "CLEARANCE",
    "DENSE_BOUNDS",
    "DENSE_COUNT",
    "DENSE_RADII",
    "DENSE_SEED",
    "GAP",
    "GOAL_BOX",
    "KIND_PROBS",
    "MIN_DETOUR",
    "PER_SETTING",
    "RADIUS_RANGE",
    "REFERENCES_CSV",
    "SETTINGS",
    "SIZE",
    "START_BOX",
    "dense_cylinders",
    "dense_field_box",
    "export_family",
    "family_names",
    "load_family",
    "read_references",
    "rgg_family",
    "rgg_name",
    "rgg_scenario",
]

#: Side of the square scene, metres.
SIZE = 100.0
#: Start and goal are uniform in these boxes ((x_lo, y_lo), (x_hi, y_hi)).
START_BOX = ((5.0, 5.0), (10.0, 10.0))
GOAL_BOX = ((90.0, 90.0), (95.0, 95.0))
#: Radius range of an obstacle's bounding circle, metres.
RADIUS_RANGE = (4.0, 12.0)
#: Minimum gap between bounding circles, and between a bounding circle and the walls, metres.
GAP = 1.0
#: Minimum distance from the start and the goal to any bounding circle, metres.
CLEARANCE = 2.0
#: Obstacle kinds and their probabilities.
KIND_PROBS = {"circle": 0.4, "convex": 0.3, "nonconvex": 0.3}
#: Vertex counts (inclusive) of convex and non-convex polygons.
CONVEX_VERTICES = (3, 8)
NONCONVEX_VERTICES = (5, 10)
#: Inner radius range of non-convex (star-shaped) polygons, as a fraction of r.
NONCONVEX_RADII = (0.35, 1.0)
#: Angle jitter of polygon vertices, as a fraction of the even spacing.
ANGLE_JITTER = 0.35
#: The shortest path must be at least this much longer than the straight segment, metres.
MIN_DETOUR = 0.1
#: Coordinates and radii are rounded to this many decimals (1 mm).
DECIMALS = 3
#: Free waypoints a planner uses (RGG-PSO+ N = 20).
N_WAYPOINTS = 20
#: Sides of the circumscribed polygons that stand for circles in the reference path.
CIRCLE_SIDES = DEFAULT_CIRCLE_SIDES
#: Placement tries per obstacle, and scene attempts, before giving up.
PLACE_TRIES = 500
MAX_ATTEMPTS = 10_000
#: File name of the sidecar table written by :func:`export_family`.
REFERENCES_CSV = "references.csv"

_KINDS = tuple(KIND_PROBS)
_PROBS = np.array([KIND_PROBS[k] for k in _KINDS])


def _rng(n_obstacles: int, index: int, root_seed: int) -> np.random.Generator:
    return np.random.default_rng(
        np.random.SeedSequence(entropy=root_seed, spawn_key=(n_obstacles, index))
    )


def _angles(rng: np.random.Generator, k: int) -> FloatArray:
    spacing = 2.0 * np.pi / k
    jitter = rng.uniform(-ANGLE_JITTER, ANGLE_JITTER, k) * spacing
    return np.asarray(rng.uniform(0.0, 2.0 * np.pi) + spacing * np.arange(k) + jitter)


def _is_convex(v: FloatArray) -> bool:
    prev = np.roll(v, 1, axis=0)
    nxt = np.roll(v, -1, axis=0)
    turn = (v[:, 0] - prev[:, 0]) * (nxt[:, 1] - v[:, 1]) - (v[:, 1] - prev[:, 1]) * (
        nxt[:, 0] - v[:, 0]
    )
    return bool(np.all(turn > 0))


def _polygon(rng: np.random.Generator, center: FloatArray, r: float, convex: bool) -> FloatArray:
    """Vertices (counter-clockwise, rounded) of a polygon inscribed in the bounding circle."""
    while True:
        if convex:
            k = int(rng.integers(CONVEX_VERTICES[0], CONVEX_VERTICES[1] + 1))
            rho = np.full(k, r)
        else:
            k = int(rng.integers(NONCONVEX_VERTICES[0], NONCONVEX_VERTICES[1] + 1))
            rho = rng.uniform(NONCONVEX_RADII[0], NONCONVEX_RADII[1], k) * r
            rho[int(np.argmax(rho))] = r
        th = _angles(rng, k)
        v = np.round(center + rho[:, None] * np.stack([np.cos(th), np.sin(th)], axis=1), DECIMALS)
        if _is_convex(v) == convex:
            return np.asarray(v)


def _place(
    rng: np.random.Generator, n: int, start: FloatArray, goal: FloatArray
) -> tuple[FloatArray, FloatArray] | None:
    """Centres (n, 2) and bounding radii (n,) of n non-overlapping obstacles, or None."""
    centers = np.zeros((0, 2))
    radii = np.zeros(0)
    for _ in range(n):
        for _ in range(PLACE_TRIES):
            r = round(float(rng.uniform(*RADIUS_RANGE)), DECIMALS)
            c = np.round(rng.uniform(r + GAP, SIZE - r - GAP, 2), DECIMALS)
            if np.hypot(*(c - start)) < r + CLEARANCE or np.hypot(*(c - goal)) < r + CLEARANCE:
                continue
            if len(radii) and np.any(
                np.hypot(centers[:, 0] - c[0], centers[:, 1] - c[1]) < radii + r + GAP
            ):
                continue
            centers = np.vstack([centers, c])
            radii = np.append(radii, r)
            break
        else:
            return None
    return centers, radii


def _attempt(
    rng: np.random.Generator, n: int
) -> tuple[FloatArray, FloatArray, list[str], list[Circle], list[Polygon]] | None:
    start = np.round(rng.uniform(START_BOX[0], START_BOX[1]), DECIMALS)
    goal = np.round(rng.uniform(GOAL_BOX[0], GOAL_BOX[1]), DECIMALS)
    placed = _place(rng, n, start, goal)
    if placed is None:
        return None
    centers, radii = placed
    kinds = [_KINDS[int(k)] for k in rng.choice(len(_KINDS), size=n, p=_PROBS)]
    circles: list[Circle] = []
    polygons: list[Polygon] = []
    for kind, c, r in zip(kinds, centers, radii, strict=True):
        if kind == "circle":
            circles.append(Circle((float(c[0]), float(c[1])), float(r)))
        else:
            v = _polygon(rng, c, float(r), convex=kind == "convex")
            polygons.append(Polygon(tuple((float(a), float(b)) for a, b in v)))
    return start, goal, kinds, circles, polygons


def rgg_scenario(n_obstacles: int, index: int, root_seed: int = 0) -> Scenario:
    """Scene ``index`` of the family with ``n_obstacles`` obstacles (see the module notes).

    Deterministic in ``(n_obstacles, index, root_seed)``. ``metadata`` holds the generator
    parameters, ``reference_length`` and ``reference_path``.
    """
    if n_obstacles < 1:
        raise ValueError(f"n_obstacles must be >= 1, got {n_obstacles}")
    if index < 0 or root_seed < 0:
        raise ValueError("index and root_seed must be >= 0")
    rng = _rng(n_obstacles, index, root_seed)
    name = rgg_name(n_obstacles, index)
    bounds = Bounds((0.0, 0.0), (SIZE, SIZE))
    rejected = {
        "placement": 0,
        "straight_feasible": 0,
        "no_path": 0,
        "reference_infeasible": 0,
        "small_detour": 0,
    }
    for attempt in range(1, MAX_ATTEMPTS + 1):
        drawn = _attempt(rng, n_obstacles)
        if drawn is None:
            rejected["placement"] += 1
            continue
        start, goal, kinds, circles, polygons = drawn
        scene = Scenario(
            name=name,
            bounds=bounds,
            tasks=(Task("uav0", tuple(start), tuple(goal)),),
            circles=tuple(circles),
            polygons=tuple(polygons),
            cost="length2d",
            n_waypoints=N_WAYPOINTS,
        )
        problem = PathProblem(scene)
        if bool(problem.evaluate(np.stack([start, goal])[None]).feasible[0]):
            rejected["straight_feasible"] += 1
            continue
        length, path = shortest_path(scene, CIRCLE_SIDES)
        if not np.isfinite(length):
            rejected["no_path"] += 1
            continue
        if not bool(problem.evaluate(path[None]).feasible[0]):
            rejected["reference_infeasible"] += 1
            continue
        straight = float(np.hypot(*(goal - start)))
        if length < straight + MIN_DETOUR:
            rejected["small_detour"] += 1
            continue
        n_circ = kinds.count("circle")
        n_conv = kinds.count("convex")
        metadata: dict[str, Any] = {
            "generator": "uavplan.scenarios.generators.rgg_scenario",
            "n_obstacles": n_obstacles,
            "index": index,
            "root_seed": root_seed,
            "attempts": attempt,
            "rejected": rejected,
            "kinds": kinds,
            "n_circles": n_circ,
            "n_convex": n_conv,
            "n_nonconvex": n_obstacles - n_circ - n_conv,
            "size": SIZE,
            "start_box": [list(START_BOX[0]), list(START_BOX[1])],
            "goal_box": [list(GOAL_BOX[0]), list(GOAL_BOX[1])],
            "radius_range": list(RADIUS_RANGE),
            "gap": GAP,
            "clearance": CLEARANCE,
            "kind_probs": dict(KIND_PROBS),
            "min_detour": MIN_DETOUR,
            "circle_sides": CIRCLE_SIDES,
            "straight_length": straight,
            "reference_length": length,
            "reference_path": path.tolist(),
        }
        description = (
            f"RGG-PSO+ style random scene (Liu et al. 2024, Sect. 5.2.1): {n_obstacles} "
            f"obstacles ({n_circ} circles, {n_conv} convex and {n_obstacles - n_circ - n_conv} "
            f"non-convex polygons), root_seed {root_seed}, index {index}; shortest path "
            f"{length!r} m (visibility graph, circles as circumscribed {CIRCLE_SIDES}-gons)."
        )
        return Scenario(
            name=name,
            bounds=bounds,
            tasks=scene.tasks,
            circles=scene.circles,
            polygons=scene.polygons,
            cost="length2d",
            n_waypoints=N_WAYPOINTS,
            description=description,
            metadata=metadata,
        )
    raise RuntimeError(f"{name}: no valid scene in {MAX_ATTEMPTS} attempts ({rejected})")


def rgg_family(
    per_setting: int = PER_SETTING, root_seed: int = 0, settings: Iterable[int] = SETTINGS
) -> Iterator[Scenario]:
    """The family, setting by setting: ``per_setting`` scenes for each obstacle count
    (10 x 100 = 1000 by default), generated lazily."""
    for n in settings:
        for i in range(per_setting):
            yield rgg_scenario(n, i, root_seed)


# ---------------------------------------------------------------------------- files
_CSV_FIELDS = ("name", "n_obstacles", "index", "root_seed", "reference_length", "reference_path")


def export_family(
    folder: str | Path,
    per_setting: int = PER_SETTING,
    root_seed: int = 0,
    settings: Iterable[int] = SETTINGS,
) -> list[Path]:
    """Write the family as scenario files ``<folder>/<name>.yaml`` plus ``references.csv``.

    The folder is created if needed. Returns the written scenario files, in family order.
    """
    from uavplan.io.atomic import write_text_atomic
    from uavplan.io.scenario_file import save_scenario

    out = Path(folder)
    out.mkdir(parents=True, exist_ok=True)
    files: list[Path] = []
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(_CSV_FIELDS)
    for sc in rgg_family(per_setting, root_seed, settings):
        files.append(save_scenario(sc, out / f"{sc.name}.yaml"))
        m = sc.metadata
        writer.writerow(
            [
                sc.name,
                m["n_obstacles"],
                m["index"],
                m["root_seed"],
                repr(float(m["reference_length"])),
                json.dumps(m["reference_path"]),
            ]
        )
    write_text_atomic(out / REFERENCES_CSV, buf.getvalue())
    return files


def read_references(folder: str | Path) -> dict[str, dict[str, Any]]:
    """``references.csv`` of an exported family: name -> ``n_obstacles``, ``index``,
    ``root_seed``, ``reference_length`` (float) and ``reference_path`` (list of [x, y])."""
    out: dict[str, dict[str, Any]] = {}
    with open(Path(folder) / REFERENCES_CSV, newline="", encoding="utf-8") as f:
        for row in csv.DictReader(f):
            out[row["name"]] = {
                "n_obstacles": int(row["n_obstacles"]),
                "index": int(row["index"]),
                "root_seed": int(row["root_seed"]),
                "reference_length": float(row["reference_length"]),
                "reference_path": json.loads(row["reference_path"]),
            }
    return out


def load_family(folder: str | Path) -> Iterator[Scenario]:
    """Load an exported family (in ``references.csv`` order), each scene's ``metadata`` holding
    its row of ``references.csv``."""
    from uavplan.io.scenario_file import load_scenario

    for name, ref in read_references(folder).items():
        sc = load_scenario(Path(folder) / f"{name}.yaml")
        sc.metadata.update(ref)
        yield sc


# ---------------------------------------------------------------------------- dense field
#: Seed, cylinder count, radius range (m) and x/y bounds (m, the SPSO map) of ``dense``.
DENSE_SEED = 0
DENSE_COUNT = 40
DENSE_RADII = (20.0, 50.0)
DENSE_BOUNDS = ((1.0, 1.0), (1045.0, 879.0))
#: Centre candidates per cylinder, and draws, before :func:`dense_cylinders` gives up.
DENSE_TRIES = 5000
DENSE_ATTEMPTS = 100


def dense_field_box(
    bounds: tuple[tuple[float, float], tuple[float, float]] = DENSE_BOUNDS,
    s1: float = 15.0,
    turn_radius: float = 20.0,
) -> tuple[FloatArray, FloatArray]:
    """``(lower [x, y], upper [x, y])`` that cylinder edges, grown by S1, must keep inside so that
    the fleet start and goal bands stay free (the placement box of
    :func:`uavplan.world.fleet_tasks.placement_box` shrunk by its band depth)."""
    edge = max(turn_radius, s1)
    lo = np.asarray(bounds[0], dtype=np.float64) + edge
    hi = np.asarray(bounds[1], dtype=np.float64) - edge
    band = BAND_FRACTION * float(np.min(hi - lo))
    return lo + band, hi - band


def dense_cylinders(
    seed: int = DENSE_SEED,
    n: int = DENSE_COUNT,
    *,
    bounds: tuple[tuple[float, float], tuple[float, float]] = DENSE_BOUNDS,
    s1: float = 15.0,
    turn_radius: float = 20.0,
    radius_range: tuple[float, float] = DENSE_RADII,
    min_gap: float | None = None,
) -> tuple[Cylinder, ...]:
    """``n`` infinitely tall cylinders of a dense field (see the module notes), largest first.

    Deterministic in its arguments; the defaults give the ``dense`` built-in's cylinders.
    ``min_gap`` is the least distance between two cylinder edges (default ``1.5 * s1``).

    Raises:
        ValueError: bad arguments, or no draw in ``DENSE_ATTEMPTS`` places all ``n``.
    """
    if n < 1:
        raise ValueError(f"n must be >= 1, got {n}")
    r_lo, r_hi = radius_range
    if not 0 < r_lo <= r_hi:
        raise ValueError(f"radius_range must have 0 < low <= high, got {radius_range}")
    gap = 1.5 * s1 if min_gap is None else float(min_gap)
    lo, hi = dense_field_box(bounds, s1, turn_radius)
    if np.any(hi - lo < 2 * (s1 + r_hi)):
        raise ValueError(f"the field {lo.tolist()}..{hi.tolist()} is too small for the radii")
    rng = np.random.default_rng(seed)
    for _ in range(DENSE_ATTEMPTS):
        radii = np.sort(np.round(rng.uniform(r_lo, r_hi, n)))[::-1]
        centers = np.zeros((0, 2))
        for r in radii:
            # all tries at once; the first that keeps the gap (and, rounded, the field) wins
            c = np.round(rng.uniform(lo + s1 + r, hi - s1 - r, (DENSE_TRIES, 2)), 1)
            ok = np.all((c - r - s1 >= lo) & (c + r + s1 <= hi), axis=1)
            d = np.hypot(c[:, None, 0] - centers[None, :, 0], c[:, None, 1] - centers[None, :, 1])
            ok &= np.all(d - radii[None, : centers.shape[0]] - r >= gap, axis=1)
            if not np.any(ok):
                break
            centers = np.vstack([centers, c[int(np.argmax(ok))]])
        if centers.shape[0] == n:
            return tuple(
                Cylinder((float(c[0]), float(c[1])), float(r))
                for c, r in zip(centers, radii, strict=True)
            )
    raise ValueError(f"cannot place {n} cylinders {gap:g} m apart in {DENSE_ATTEMPTS} draws")
