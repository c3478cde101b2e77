"""Tasks for a fleet of UAVs: reproducible starts and goals for 10 to 1000 (and more) UAVs.

PPSwarm (Meng et al. 2024, Drones 8:192, Sect. 5.1-5.2) plans 10-40 UAVs in each of four
scenarios and up to 500 in scenario 1, but gives neither the start and goal positions nor how they
were chosen (its Fig. 4 only shows the obstacles). The choices below are ours.

* **Where.** Inside the x/y bounds shrunk by an edge margin ``max(uav.turn_radius, uav.s1)``
  (20 m with the PPSwarm defaults: room for a minimum-radius turn, and the threat cost's distance
  kept from the box walls). Every start and goal is a valid place (``scenario.point_problems``
  empty) and keeps at least ``uav.s1`` (S1) from the edge of every cylinder, circle and no-fly
  polygon, as PPSwarm's threat cost (Eq. 5) asks of the path. Moving obstacles and danger areas
  are not looked at.
* **Height.** z is absolute: the middle of the altitude band (above the ground for a ``ground``
  band: ``ground(x, y) + (min + max) / 2``, 150 m above ground in the PPSwarm scenarios); without a
  band, halfway between the ground (or the bounds' lower z) and the bounds' upper z; no z in 2-D.
  That is the height of a fleet in one layer; stacked layers lie above and below it (**Layers**).
* **Spacing.** Starts are pairwise at least ``min_spacing`` apart in 3-D (default
  ``3 * uav.s2``, 30 m), and so are goals (a start may be near another UAV's goal: every UAV
  leaves its start at t = 0, before any other can reach its goal). Candidates are the nodes of a
  hexagonal lattice of constant ``min_spacing`` (random rotation and offset) in x/y, the densest
  packing, which is what lets 500 UAVs fit on the 1045 m x 879 m map even around 20 cylinders
  (740-916 in one layer on the PPSwarm maps); in one layer the chosen nodes are then jittered (up
  to half the lattice constant, each move kept only if the x/y spacing and validity still hold),
  so small fleets do not sit on a visible grid.
* **Layers.** In 3-D, when the starts (or the goals) do not fit in one layer, they are stacked
  in the fewest altitude layers L >= 2 that hold them: the layers share the nodes of one lattice
  placement and lie at the one-layer height (above) moved by ``(i - (L - 1) / 2) * step``,
  i = 0 ... L-1, ``step = min_spacing * (1 + 1e-9) + 1e-9`` (a hair over the spacing, so
  rounding never brings two points under it). Two positions at one node are then at least
  ``step`` apart vertically, at two nodes at least the lattice constant apart in x/y. A node
  counts only if it is valid at the height of every layer (bounds, terrain, altitude band, finite
  cylinders with S1 checked at that height), and it gives all its layers: the positions in
  selection order are the nodes in selection order, each with its layers lowest first (node
  major), so a fleet of n takes the first ceil(n / L) nodes, the last one perhaps not full. L goes
  up to as many layers ``step`` apart as the band's height (and the bounds' z range) holds (4 in
  the 100-200 m band of the PPSwarm scenarios: 135/165 m, 120/150/180 m, 105/135/165/195 m above
  ground); each count is tried on ``LATTICE_TRIES`` placements (drawn once), the first that holds
  the fleet is taken. Layered positions are not jittered. Starts and goals get their layers
  independently (in practice the same number); a side that fits in one layer stays as it was.
  ``ppswarm1`` holds 1000 UAVs in 2 layers, 2000 in 3 and 3000 in 4; 2-D scenarios have one layer.
* **Patterns.**

  - ``"crossing"``: starts along the west and south edges, goals along the east and north edges.
    The start region is the band of depth ``BAND_FRACTION`` (12 %) of the shorter side (about
    100 m on the PPSwarm map) along the west and south edges, on the south-west side of the
    north-west/south-east diagonal; the goal region is its mirror image. Starts are drawn at
    random from the start region; when it cannot hold the fleet the region grows inward, nearest
    nodes first, then past the diagonal. Goals come from the goal region the same way, and are
    paired with the starts at random, so the straight start-goal lines cross each other many
    times (about 60 % of the pairs of lines for 40 UAVs).
  - ``"random"``: starts and goals drawn uniformly from the whole free area, paired at random.

  In both, every straight start-goal line is at least ``min_length_fraction`` (40 %) of the x/y
  diagonal of the bounds long (546 m on the PPSwarm map). Pairing is a uniformly random-cost
  assignment (:func:`scipy.optimize.linear_sum_assignment`) between the starts and the first
  goal candidates in selection order that never takes a pair shorter than that; when none
  exists, the goal candidates grow (by half, in selection order) until one does. The jitter keeps
  the length rule too.
* **Determinism.** Everything is drawn from ``np.random.default_rng(seed)``; the same scenario,
  ``n_uavs``, seed, pattern and spacing always give the same tasks (the number of layers too, so a
  saved ``fleet`` block regenerates a layered fleet). Fleets of different sizes are independent
  draws (not nested). A fleet that fits in one layer is drawn exactly as before layers existed.
* **Failure.** If fewer than ``n_uavs`` valid spaced positions exist (after 8 lattice placements;
  in 3-D in one layer, and then in any number of layers the band holds, each on 8 more), or no
  pairing meets the length rule, a ``ValueError`` says how many could be placed (in 3-D: in one
  layer, and the most in how many layers, of how many the band holds) or paired.

Task ids are ``uav0`` ... ``uav{n-1}``; every task leaves at t = 0.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from uavplan.world.scenario import Scenario, Task

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

__all__ = [
    "BAND_FRACTION",
    "MIN_LENGTH_FRACTION",
    "PATTERNS",
    "SPACING_FACTOR",
    "FleetLayout",
    "fleet_layout",
    "fleet_tasks",
    "layer_record",
    "placement_box",
    "with_fleet",
]

#: The task patterns :func:`fleet_tasks` knows.
PATTERNS: tuple[str, ...] = ("crossing", "random")
#: Default ``min_spacing`` = this times ``uav.s2`` (S2, the safe distance between UAVs).
SPACING_FACTOR = 3.0
#: Straight start-goal lines are at least this fraction of the bounds' x/y diagonal long.
MIN_LENGTH_FRACTION = 0.4
#: Depth of the start (goal) band along the west and south (east and north) edges, as a fraction
#: of the shorter side of the placement box.
BAND_FRACTION = 0.12
#: Lattice placements (rotation and offset) tried before giving up.
LATTICE_TRIES = 8
#: Jitter moves tried per chosen node.
JITTER_TRIES = 8
#: Upper limit on lattice nodes (a coarser lattice is used on maps huge compared to the spacing).
MAX_LATTICE_NODES = 200_000


def placement_box(scenario: Scenario) -> tuple[FloatArray, FloatArray, float]:
    """Where fleet starts and goals may go: ``(lower [x, y], upper [x, y], band depth)``, metres.

    ``lower``/``upper`` are the x/y bounds shrunk by ``max(uav.turn_radius, uav.s1)``; the
    ``"crossing"`` start band is the strip ``band`` deep inside it along the west and south
    edges, the goal band the one along the east and north edges. A scenario whose obstacles keep
    (with S1) inside ``[lower + band, upper - band]`` leaves both bands free.
    """
    edge = max(scenario.uav.turn_radius, scenario.uav.s1)
    lo = scenario.bounds.lo[:2] + edge
    hi = scenario.bounds.hi[:2] - edge
    if np.any(hi <= lo):
        raise ValueError(
            f"scenario {scenario.name!r}: the x/y bounds are too small for an edge margin of "
            f"{edge:g} m"
        )
    band = BAND_FRACTION * float(np.min(hi - lo))
    return lo, hi, band


# ---------------------------------------------------------------------------- validity
def _heights(
    scenario: Scenario, xy: FloatArray, dz: float | FloatArray = 0.0
) -> tuple[FloatArray, FloatArray]:
    """(z, ground) of fleet positions at ``xy`` (n, 2), each (n,); zeros in 2-D. ``dz`` (a number
    or (n,)) moves z up from the one-layer height (an altitude layer's offset)."""
    n = xy.shape[0]
    if scenario.dim == 2:
        return np.zeros(n), np.zeros(n)
    ground = np.asarray(scenario.ground(xy[:, 0], xy[:, 1]), dtype=np.float64).reshape(n)
    band = scenario.altitude
    if band is not None and band.reference == "ground":
        z = 0.5 * (ground + _ceiling_ground(scenario, xy, ground)) + band.mid
    elif band is not None:
        z = np.full(n, band.mid)
    else:
        floor = ground if scenario.terrain is not None else np.full(n, scenario.bounds.lower[2])
        floor = np.maximum(floor, scenario.bounds.lower[2])
        z = 0.5 * (floor + scenario.bounds.upper[2])
    if np.any(dz != 0):  # (only then: a fleet in one layer keeps its heights bit for bit)
        z = z + dz
    return z, ground


def _segment_distance(xy: FloatArray, vertices: FloatArray) -> FloatArray:
    """Distance from each point (n, 2) to the boundary of a closed polygon (k, 2)."""
    a = vertices
    b = np.roll(vertices, -1, axis=0)
    ab = b - a  # (k, 2)
    ap = xy[:, None, :] - a[None, :, :]  # (n, k, 2)
    denom = np.maximum(np.sum(ab * ab, axis=1), 1e-300)
    t = np.clip(np.sum(ap * ab[None], axis=2) / denom[None], 0.0, 1.0)
    d = ap - t[..., None] * ab[None]
    return np.asarray(np.min(np.hypot(d[..., 0], d[..., 1]), axis=1))


def _valid(
    scenario: Scenario, xy: FloatArray, lo: FloatArray, hi: FloatArray, dz: float = 0.0
) -> BoolArray:
    """Which positions (n, 2) are valid fleet starts/goals (vectorized, conservative), at the
    one-layer height moved up by ``dz``."""
    s1 = scenario.uav.s1
    ok = np.all((xy >= lo) & (xy <= hi), axis=1)
    z, ground = _heights(scenario, xy, dz)
    for c in scenario.cylinders:
        d = np.hypot(xy[:, 0] - c.center[0], xy[:, 1] - c.center[1])
        reach = c.effective_radius + s1
        if scenario.dim == 3 and not c.infinite:
            near_z = (z >= c.z_min - c.margin - s1) & (z <= c.z_max + c.margin + s1)
            ok &= ~((d < reach) & near_z)
        else:
            ok &= d >= reach
    for ci in scenario.circles:
        d = np.hypot(xy[:, 0] - ci.center[0], xy[:, 1] - ci.center[1])
        ok &= d >= ci.effective_radius + s1
    for poly in scenario.no_fly_polygons:
        if not np.any(ok):
            break
        idx = np.flatnonzero(ok)
        inside = poly.contains(xy[idx])
        near = _segment_distance(xy[idx], poly.array) < poly.margin + s1
        ok[idx[inside | near]] = False
    if scenario.dim == 3:
        ok &= (z >= scenario.bounds.lower[2]) & (z <= scenario.bounds.upper[2])
        if scenario.terrain is not None:
            ok &= z >= ground
        band = scenario.altitude
        if band is not None:
            h = z - ground if band.reference == "ground" else z
            hc = z - _ceiling_ground(scenario, xy, ground) if band.reference == "ground" else z
            ok &= (h >= band.min) & (hc <= band.max)
    return np.asarray(ok)


def _ceiling_ground(scenario: Scenario, xy: FloatArray, ground: FloatArray) -> FloatArray:
    """The ground the band's ceiling is held against at ``xy`` (the terrain's ceiling grid)."""
    t = scenario.terrain
    if t is None or t.lower is None:
        return ground
    return np.asarray(t.height_low(xy[:, 0], xy[:, 1]), dtype=np.float64).reshape(len(ground))


def _point(scenario: Scenario, xy: FloatArray, z: float) -> tuple[float, ...]:
    if scenario.dim == 2:
        return (float(xy[0]), float(xy[1]))
    return (float(xy[0]), float(xy[1]), float(z))


# ---------------------------------------------------------------------------- placement
def _lattice(lo: FloatArray, hi: FloatArray, a: float, rng: np.random.Generator) -> FloatArray:
    """Nodes of a hexagonal lattice of constant ``a`` (random rotation and offset) in the box."""
    theta = rng.uniform(0.0, math.pi / 3)
    e1 = a * np.array([math.cos(theta), math.sin(theta)])
    e2 = a * np.array([math.cos(theta + math.pi / 3), math.sin(theta + math.pi / 3)])
    center = 0.5 * (lo + hi) + rng.uniform(0.0, 1.0) * e1 + rng.uniform(0.0, 1.0) * e2
    radius = 0.5 * float(np.hypot(*(hi - lo)))
    k = math.ceil(2 * radius / (a * math.sqrt(3) / 2)) + 2
    idx = np.arange(-k, k + 1, dtype=np.float64)
    i, j = np.meshgrid(idx, idx, indexing="ij")
    pts = center + i.reshape(-1, 1) * e1 + j.reshape(-1, 1) * e2
    inside = np.all((pts >= lo) & (pts <= hi), axis=1)
    return np.asarray(pts[inside])


def _keys(
    pattern: str,
    xy: FloatArray,
    lo: FloatArray,
    hi: FloatArray,
    band: float,
    goal: bool,
    rng: np.random.Generator,
) -> FloatArray:
    """Selection order of candidate nodes (smallest first)."""
    if pattern == "random":
        return np.asarray(rng.random(xy.shape[0]), dtype=np.float64)
    p = (hi - xy) if goal else (xy - lo)  # distances from the west/south (east/north) edges
    uv = p / (hi - lo)
    own_side = uv[:, 0] + uv[:, 1] <= 1.0
    depth = np.min(p, axis=1)
    diag = float(np.hypot(*(hi - lo)))
    return np.where(
        own_side,
        np.where(depth <= band, band * rng.random(xy.shape[0]), depth),
        1e3 * diag + (uv[:, 0] + uv[:, 1]) * diag,
    )


def _lattice_constant(scenario: Scenario, spacing: float) -> float:
    lo, hi, _ = placement_box(scenario)
    area = float(np.prod(hi - lo))
    # A hair over the spacing, so that rounding never brings two nodes under it.
    return max(spacing * (1 + 1e-9) + 1e-9, math.sqrt(area * 2 / math.sqrt(3) / MAX_LATTICE_NODES))


def _candidates(
    scenario: Scenario,
    n: int,
    a: float,
    pattern: str,
    goal: bool,
    rng: np.random.Generator,
) -> tuple[FloatArray | None, int]:
    """Valid lattice nodes (m, 2), m >= ``n``, in selection order; or ``(None, most found)``."""
    lo, hi, band = placement_box(scenario)
    best = 0
    for _ in range(LATTICE_TRIES):
        nodes = _lattice(lo, hi, a, rng)
        nodes = nodes[_valid(scenario, nodes, lo, hi)]
        best = max(best, nodes.shape[0])
        if nodes.shape[0] >= n:
            keys = _keys(pattern, nodes, lo, hi, band, goal, rng)
            return np.asarray(nodes[np.argsort(keys, kind="stable")]), nodes.shape[0]
    return None, best


def _layer_step(spacing: float) -> float:
    """Height between two altitude layers: a hair over the spacing (as the lattice constant), so
    that rounding never brings two points under it."""
    return spacing * (1 + 1e-9) + 1e-9


def _layer_offsets(layers: int, step: float) -> FloatArray:
    """Height offsets of ``layers`` altitude layers ``step`` apart, centred on 0 (lowest first)."""
    return (np.arange(layers, dtype=np.float64) - (layers - 1) / 2) * step


def _max_layers(scenario: Scenario, step: float) -> int:
    """Most altitude layers ``step`` apart that the band (and the bounds' z range) can hold."""
    extent = scenario.bounds.upper[2] - scenario.bounds.lower[2]
    if scenario.altitude is not None:
        extent = min(extent, scenario.altitude.max - scenario.altitude.min)
    return math.floor(extent / step) + 1


@dataclasses.dataclass(frozen=True)
class _Layered:
    """Positions in stacked altitude layers, or (``xy`` None) the most that could be placed."""

    xy: FloatArray | None  # (m, 2), node-major: every layer of a node, lowest first
    dz: FloatArray | None  # (m,) height offset of each position
    layers: int  # layers used; when xy is None, those of the most positions found
    most: int  # positions placed (best lattice); m when xy is given
    max_layers: int  # as many as the band holds


def _layered_candidates(
    scenario: Scenario,
    n: int,
    a: float,
    step: float,
    pattern: str,
    goal: bool,
    rng: np.random.Generator,
) -> _Layered:
    """Valid positions in the fewest altitude layers (>= 2) that hold ``n`` (3-D only).

    The layers share the nodes of one lattice placement; a node counts if it is valid at the
    height of every layer. Layer counts are tried from 2 up, each on the ``LATTICE_TRIES``
    placements (drawn once) in turn; the nodes of the first that holds ``n`` come in selection
    order, each with all its layers (lowest first).
    """
    lo, hi, band = placement_box(scenario)
    l_max = _max_layers(scenario, step)
    tries = [_lattice(lo, hi, a, rng) for _ in range(LATTICE_TRIES)] if l_max >= 2 else []
    cache: dict[tuple[int, int], BoolArray] = {}

    def valid_at(t: int, k: int) -> BoolArray:
        """Nodes of placement ``t`` valid at the height offset ``k * step / 2``."""
        if (t, k) not in cache:
            cache[t, k] = _valid(scenario, tries[t], lo, hi, 0.5 * k * step)
        return cache[t, k]

    # every_layer[t][p]: nodes of placement t valid in every layer of the last count of parity p
    # (L layers are at k = 1 - L, 3 - L, ..., L - 1; L + 2 layers add k = +-(L + 1))
    every_layer = [[np.ones(nodes.shape[0], dtype=np.bool_), valid_at(t, 0)]
                   for t, nodes in enumerate(tries)]  # fmt: skip
    most, most_layers = 0, 2
    for layers in range(2, l_max + 1):
        p = layers % 2
        for t in range(len(tries)):
            ok = every_layer[t][p] & valid_at(t, layers - 1) & valid_at(t, 1 - layers)
            every_layer[t][p] = ok
            count = layers * int(np.count_nonzero(ok))
            if count > most:
                most, most_layers = count, layers
            if count >= n:
                nodes = tries[t][ok]
                keys = _keys(pattern, nodes, lo, hi, band, goal, rng)
                nodes = nodes[np.argsort(keys, kind="stable")]
                offsets = _layer_offsets(layers, step)
                return _Layered(
                    np.repeat(nodes, layers, axis=0),
                    np.tile(offsets, nodes.shape[0]),
                    layers,
                    count,
                    l_max,
                )
        if not any(np.any(m) for masks in every_layer for m in masks):
            break  # no node is valid in this many layers: more layers cannot help
    return _Layered(None, None, most_layers, most, l_max)


def _pair(
    starts: FloatArray, pool: FloatArray, n: int, min_len: float, rng: np.random.Generator
) -> tuple[NDArray[np.intp] | None, int]:
    """Goals for ``starts`` from the first nodes of ``pool`` (in order; their indices in
    ``pool``), paired at random so that every start-goal distance (x/y) is >= ``min_len``; or
    ``(None, most pairs that are long enough)``.

    The pool grows (by half) until the pairing works: a uniformly random-cost assignment between
    the starts and the pool, with long-enough pairs always preferred.
    """
    m = n
    while True:
        cand = pool[:m]
        length = np.hypot(
            starts[:, None, 0] - cand[None, :, 0], starts[:, None, 1] - cand[None, :, 1]
        )
        short = length < min_len
        cost = rng.random((n, m)) + short * (n + 1.0)
        from scipy.optimize import linear_sum_assignment  # lazy: 0.6 s of every CLI start

        rows, cols = linear_sum_assignment(cost)
        bad = int(np.count_nonzero(short[rows, cols]))
        if not bad:
            return np.asarray(cols[np.argsort(rows)]), n
        if m == pool.shape[0]:
            return None, n - bad
        m = min(pool.shape[0], m + max(1, m // 2))


def _jitter(
    scenario: Scenario,
    pts: FloatArray,
    partners: FloatArray,
    spacing: float,
    min_len: float,
    a: float,
    rng: np.random.Generator,
) -> None:
    """Move each point (in place) up to ``a / 2`` at random where validity, the spacing to the
    other points and the length to its partner (the other end of its task) allow."""
    lo, hi, _ = placement_box(scenario)
    n = pts.shape[0]
    for i in rng.permutation(n):
        r = 0.5 * a * np.sqrt(rng.random(JITTER_TRIES))
        phi = rng.uniform(0.0, 2 * math.pi, JITTER_TRIES)
        cand = pts[i] + np.stack([r * np.cos(phi), r * np.sin(phi)], axis=1)
        ok = np.hypot(*(cand - partners[i]).T) >= min_len
        others = np.delete(pts, i, axis=0)
        if others.shape[0]:
            d = np.hypot(
                cand[:, None, 0] - others[None, :, 0], cand[:, None, 1] - others[None, :, 1]
            )
            ok &= np.min(d, axis=1) >= spacing * (1 + 1e-9)
        if not np.any(ok):
            continue
        ok[ok] = _valid(scenario, cand[ok], lo, hi)
        if np.any(ok):
            pts[i] = cand[int(np.argmax(ok))]


class FleetLayout(NamedTuple):
    """What :func:`fleet_layout` makes: the tasks and the altitude layers they use."""

    tasks: tuple[Task, ...]
    #: Altitude layers of the starts or of the goals, whichever has more (1: the fleet fits in
    #: one layer; always 1 in 2-D).
    layers: int


def fleet_tasks(
    scenario: Scenario,
    n_uavs: int,
    seed: int = 0,
    pattern: str = "crossing",
    min_spacing: float | None = None,
    *,
    min_length_fraction: float = MIN_LENGTH_FRACTION,
) -> tuple[Task, ...]:
    """Start and goal for each of ``n_uavs`` UAVs (``uav0`` ... ``uav{n-1}``), reproducibly.

    Args:
        scenario: the world (its tasks are ignored).
        n_uavs: number of UAVs (>= 1).
        seed: seed of ``np.random.default_rng``.
        pattern: ``"crossing"`` (starts along the west/south edges, goals along the east/north
            edges, paired at random so the lines cross) or ``"random"`` (anywhere).
        min_spacing: least distance between two starts, and between two goals, metres; default
            ``3 * uav.separation_radius`` (``3 * uav.s2`` for a sphere).
        min_length_fraction: least straight start-goal length (x/y), as a fraction of the
            bounds' x/y diagonal.

    Returns:
        The tasks, absolute z (see the module docstring: in 3-D a fleet too large for one layer
        of positions is stacked in altitude layers), all leaving at t = 0.

    Raises:
        ValueError: bad arguments, or the fleet does not fit (the message says how many fit, and
            in 3-D with how many layers).
    """
    return fleet_layout(
        scenario,
        n_uavs,
        seed,
        pattern,
        min_spacing,
        min_length_fraction=min_length_fraction,
    ).tasks


def fleet_layout(
    scenario: Scenario,
    n_uavs: int,
    seed: int = 0,
    pattern: str = "crossing",
    min_spacing: float | None = None,
    *,
    min_length_fraction: float = MIN_LENGTH_FRACTION,
) -> FleetLayout:
    """:func:`fleet_tasks` (the same arguments) with the number of altitude layers it used."""
    if isinstance(n_uavs, bool) or not isinstance(n_uavs, int | np.integer) or n_uavs < 1:
        raise ValueError(f"n_uavs must be a positive integer, got {n_uavs!r}")
    n = int(n_uavs)
    if pattern not in PATTERNS:
        raise ValueError(f"unknown fleet pattern {pattern!r} (choose from {', '.join(PATTERNS)})")
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise ValueError(f"seed must be a non-negative integer, got {seed!r}")
    spacing = (
        SPACING_FACTOR * scenario.uav.separation_radius
        if min_spacing is None
        else float(min_spacing)
    )
    if not (math.isfinite(spacing) and spacing > 0):
        what = "3 * the UAV separation radius" if min_spacing is None else "min_spacing"
        raise ValueError(f"min_spacing must be a positive number, got {spacing!r} ({what})")
    if not (0 <= min_length_fraction < 1):
        raise ValueError(f"min_length_fraction must be in [0, 1), got {min_length_fraction!r}")

    rng = np.random.default_rng(int(seed))
    where = f"scenario {scenario.name!r}"
    a = _lattice_constant(scenario, spacing)
    step = _layer_step(spacing)
    # per side (starts, goals): positions in selection order, their layer offsets, layer count
    sides: list[tuple[FloatArray, FloatArray | None, int]] = []
    for goal in (False, True):
        pool, count = _candidates(scenario, n, a, pattern, goal, rng)
        if pool is not None:  # one layer: as it always was
            sides.append((pool, None, 1))
            continue
        placed = f"{count}"
        if scenario.dim == 3:
            stacked = _layered_candidates(scenario, n, a, step, pattern, goal, rng)
            if stacked.xy is not None and stacked.dz is not None:
                sides.append((stacked.xy, stacked.dz, stacked.layers))
                continue
            if stacked.max_layers < 2:
                placed += (
                    " in one altitude layer, and the altitude band (and the bounds' z range) "
                    f"has no room for layers {spacing:g} m apart"
                )
            else:
                placed += (
                    f" in one altitude layer, and at most {stacked.most} in {stacked.layers} "
                    f"layers (the altitude band holds up to {stacked.max_layers} layers "
                    f"{spacing:g} m apart)"
                )
        what = "goals" if goal else "starts"
        raise ValueError(
            f"cannot place {n} UAV {what} at least {spacing:g} m apart in {where}: placed "
            f"{placed} (valid positions are at least S1 = {scenario.uav.s1:g} m from every "
            "obstacle and inside the bounds less the edge margin); use fewer UAVs or a "
            "smaller min_spacing"
        )
    (start_pool, start_dz, start_layers), (goal_pool, goal_dz, goal_layers) = sides
    starts = start_pool[:n].copy()

    # Goals paired at random with the starts, among the pairs that are long enough.
    diag = float(np.hypot(*(scenario.bounds.hi[:2] - scenario.bounds.lo[:2])))
    min_len = min_length_fraction * diag
    chosen, paired = _pair(starts, goal_pool, n, min_len, rng)
    if chosen is None:
        raise ValueError(
            f"cannot pair {n} UAV starts and goals in {where} so that every straight start-goal "
            f"line is at least {min_len:.0f} m long ({min_length_fraction:g} of the x/y "
            f"diagonal): all {n} starts placed, but at most {paired} of them get a goal far "
            "enough; use fewer UAVs or a smaller min_spacing"
        )
    goals = goal_pool[chosen].copy()
    # Jitter in one layer only (its spacing check is in x/y); stacked layers stay on the lattice.
    if start_layers == 1:
        _jitter(scenario, starts, goals, spacing, min_len, a, rng)
    if goal_layers == 1:
        _jitter(scenario, goals, starts, spacing, min_len, a, rng)

    z_s, _ = _heights(scenario, starts, 0.0 if start_dz is None else start_dz[:n])
    z_g, _ = _heights(scenario, goals, 0.0 if goal_dz is None else goal_dz[chosen])
    tasks = tuple(
        Task(f"uav{i}", _point(scenario, starts[i], z_s[i]), _point(scenario, goals[i], z_g[i]))
        for i in range(n)
    )
    for t in tasks:  # the vectorized checks are stricter; this is the scenario's own word
        for which, p in (("start", t.start), ("goal", t.goal)):
            problems = scenario.point_problems(np.asarray(p))
            if problems:  # pragma: no cover - _valid is stricter than point_problems
                raise AssertionError(f"{t.id} {which} {p}: {'; '.join(problems)}")
    return FleetLayout(tasks, max(start_layers, goal_layers))


def with_fleet(
    scenario: Scenario,
    n_uavs: int,
    seed: int = 0,
    pattern: str = "crossing",
    min_spacing: float | None = None,
) -> Scenario:
    """The same scenario with a generated fleet of ``n_uavs`` tasks (see :func:`fleet_tasks`).

    ``metadata["fleet"]`` records the fleet parameters (as a loaded fleet file does: ``count``,
    ``pattern``, ``seed``, ``min_spacing``, None for the default; and ``layers``, the altitude
    layers used, only when more than one: :func:`layer_record`); a file-level spec kept in
    ``metadata["spec"]`` (a scenario loaded from a file) gets the ``fleet`` block in place of its
    ``tasks`` (never ``layers``: the parameters alone regenerate the same tasks), so saving the
    new scenario writes a file that loads to the same tasks.
    """
    tasks, layers = fleet_layout(
        scenario, n_uavs, seed=seed, pattern=pattern, min_spacing=min_spacing
    )
    fleet: dict[str, Any] = {"count": int(n_uavs), "pattern": pattern, "seed": int(seed)}
    if min_spacing is not None:
        fleet["min_spacing"] = float(min_spacing)
    metadata = dict(scenario.metadata)
    metadata["fleet"] = {**fleet, "min_spacing": fleet.get("min_spacing"), **layer_record(layers)}
    spec = metadata.get("spec")
    if isinstance(spec, Mapping):
        new_spec = {k: v for k, v in spec.items() if k not in ("tasks", "fleet")}
        new_spec["fleet"] = dict(fleet)
        metadata["spec"] = new_spec
    return dataclasses.replace(scenario, tasks=tasks, metadata=metadata)


def layer_record(layers: int) -> dict[str, int]:
    """The ``metadata["fleet"]`` entry for a fleet in ``layers`` altitude layers: ``{"layers":
    layers}`` when more than one, else nothing (so a one-layer fleet's record is unchanged)."""
    return {"layers": int(layers)} if layers > 1 else {}
