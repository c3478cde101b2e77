"""Fleet task generator and the four PPSwarm built-in scenarios."""

from __future__ import annotations

import dataclasses
import itertools
import math
from pathlib import Path

import numpy as np
import pytest

from uavplan.io.scenario_file import load_scenario, save_scenario
from uavplan.scenarios import list_builtin, resolve
from uavplan.world import AltitudeBand, Bounds, Cylinder, Scenario, Task
from uavplan.world.fleet_tasks import (
    MIN_LENGTH_FRACTION,
    fleet_layout,
    fleet_tasks,
    placement_box,
    with_fleet,
)

PPSWARM = ["ppswarm1", "ppswarm2", "ppswarm3", "ppswarm4"]


@pytest.fixture(scope="module")
def scenes() -> dict[str, Scenario]:
    return {name: resolve(name) for name in PPSWARM}


def ends(tasks: tuple[Task, ...]) -> tuple[np.ndarray, np.ndarray]:
    return np.array([t.start for t in tasks]), np.array([t.goal for t in tasks])


def min_pair_distance(p: np.ndarray) -> float:
    d = np.hypot(p[:, None, 0] - p[None, :, 0], p[:, None, 1] - p[None, :, 1])
    d[np.diag_indices(len(p))] = np.inf
    return float(d.min())


def crossings(tasks: tuple[Task, ...]) -> int:
    """Pairs of straight start-goal lines (x/y) that properly intersect."""
    s, g = ends(tasks)
    a, b = s[:, :2], g[:, :2]

    def orient(p: np.ndarray, q: np.ndarray, r: np.ndarray) -> np.ndarray:
        return np.sign(
            (q[..., 0] - p[..., 0]) * (r[..., 1] - p[..., 1])
            - (q[..., 1] - p[..., 1]) * (r[..., 0] - p[..., 0])
        )

    A, B = a[:, None], b[:, None]
    C, D = a[None, :], b[None, :]
    cross = (orient(A, B, C) * orient(A, B, D) < 0) & (orient(C, D, A) * orient(C, D, B) < 0)
    return int(np.count_nonzero(np.triu(cross, 1)))


def check_fleet(s: Scenario, tasks: tuple[Task, ...], n: int, spacing: float = 30.0) -> None:
    assert [t.id for t in tasks] == [f"uav{i}" for i in range(n)]
    starts, goals = ends(tasks)
    if n > 1:
        assert min_pair_distance(starts) >= spacing
        assert min_pair_distance(goals) >= spacing
    diag = math.hypot(*(s.bounds.hi[:2] - s.bounds.lo[:2]))
    length = np.hypot(*(goals[:, :2] - starts[:, :2]).T)
    assert length.min() >= MIN_LENGTH_FRACTION * diag
    assert s.altitude is not None
    for t in tasks:
        assert t.start_time == 0.0
        for p in (t.start, t.goal):
            assert s.point_problems(np.asarray(p)) == [], (t.id, p)
            # z: the band's middle above the ground
            assert p[2] == pytest.approx(
                float(s.ground(np.asarray(p[0]), np.asarray(p[1]))) + s.altitude.mid
            )
            for c in s.cylinders:  # S1 from every threat edge
                assert math.hypot(p[0] - c.center[0], p[1] - c.center[1]) >= (
                    c.effective_radius + s.uav.s1
                )


# ---------------------------------------------------------------------------- validity, spacing
@pytest.mark.parametrize("name", PPSWARM)
@pytest.mark.parametrize("n", [10, 40, 500])
def test_crossing_fleets_valid_and_spaced(scenes: dict[str, Scenario], name: str, n: int) -> None:
    s = scenes[name]
    check_fleet(s, fleet_tasks(s, n, seed=0, pattern="crossing"), n)


@pytest.mark.parametrize("name", PPSWARM)
@pytest.mark.parametrize("n", [10, 500])
def test_random_fleets_valid_and_spaced(scenes: dict[str, Scenario], name: str, n: int) -> None:
    s = scenes[name]
    check_fleet(s, fleet_tasks(s, n, seed=3, pattern="random"), n)


def test_custom_spacing_and_single_uav(scenes: dict[str, Scenario]) -> None:
    s = scenes["ppswarm3"]
    check_fleet(s, fleet_tasks(s, 40, seed=1, min_spacing=60.0), 40, spacing=60.0)
    check_fleet(s, fleet_tasks(s, 1, seed=1), 1)


def test_default_spacing_follows_s2(scenes: dict[str, Scenario]) -> None:
    s = scenes["ppswarm1"]
    wide = dataclasses.replace(s, uav=dataclasses.replace(s.uav, s2=20.0))
    starts, goals = ends(fleet_tasks(wide, 100, seed=0))
    assert min_pair_distance(starts) >= 60 and min_pair_distance(goals) >= 60


# ---------------------------------------------------------------------------- determinism
def test_deterministic_per_seed(scenes: dict[str, Scenario]) -> None:
    s = scenes["ppswarm2"]
    for pattern in ("crossing", "random"):
        a = fleet_tasks(s, 40, seed=7, pattern=pattern)
        assert a == fleet_tasks(s, 40, seed=7, pattern=pattern)
        assert a != fleet_tasks(s, 40, seed=8, pattern=pattern)
    assert fleet_tasks(s, 40, seed=0) == resolve("ppswarm2").tasks


# ---------------------------------------------------------------------------- the crossing pattern
@pytest.mark.parametrize("name", PPSWARM)
def test_crossing_pattern_crosses(scenes: dict[str, Scenario], name: str) -> None:
    s = scenes[name]
    tasks = fleet_tasks(s, 40, seed=0, pattern="crossing")
    n_pairs = 40 * 39 // 2
    assert crossings(tasks) >= 0.4 * n_pairs  # about 60 % of the pairs cross
    # starts in the west/south band, goals in the east/north band, on their own sides
    lo, hi, band = placement_box(s)
    starts, goals = ends(tasks)
    ds = starts[:, :2] - lo
    dg = hi - goals[:, :2]
    jitter = 30.0 / 2  # the lattice constant's half
    assert np.all(ds.min(axis=1) <= band + jitter)
    assert np.all(dg.min(axis=1) <= band + jitter)
    assert np.all((ds / (hi - lo)).sum(axis=1) <= 1 + jitter / 800)
    assert np.all((dg / (hi - lo)).sum(axis=1) <= 1 + jitter / 800)


def test_crossing_on_a_tiny_example() -> None:
    a = (Task("a", (0, 0), (10, 10)), Task("b", (0, 10), (10, 0)))
    b = (Task("a", (0, 0), (10, 0)), Task("b", (0, 10), (10, 10)))
    assert crossings(a) == 1 and crossings(b) == 0


# ---------------------------------------------------------------------------- failures
def test_impossible_fleets_say_how_many_fit(scenes: dict[str, Scenario]) -> None:
    s = scenes["ppswarm4"]
    with pytest.raises(
        ValueError,
        match=r"cannot place 3000 UAV starts .*placed \d+ in one altitude layer, and at most "
        r"\d+ in 4 layers \(the altitude band holds up to 4 layers 30 m apart\)",
    ):
        fleet_tasks(s, 3000)  # about 740 a layer, 4 layers in the 100 m band
    with pytest.raises(ValueError, match=r"at least 400 m apart.*placed \d+ .*has no room"):
        fleet_tasks(s, 40, min_spacing=400)
    with pytest.raises(ValueError, match=r"at most \d+ of them get a goal far enough"):
        fleet_tasks(s, 40, min_length_fraction=0.95)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"n_uavs": 0}, "n_uavs must be a positive integer"),
        ({"n_uavs": 2.5}, "n_uavs must be a positive integer"),
        ({"n_uavs": True}, "n_uavs must be a positive integer"),
        ({"n_uavs": 5, "pattern": "zigzag"}, "unknown fleet pattern 'zigzag'"),
        ({"n_uavs": 5, "seed": -1}, "seed must be a non-negative integer"),
        ({"n_uavs": 5, "min_spacing": 0.0}, "min_spacing must be a positive number"),
        ({"n_uavs": 5, "min_spacing": float("nan")}, "min_spacing must be a positive number"),
        ({"n_uavs": 5, "min_length_fraction": 1.0}, "min_length_fraction"),
    ],
)
def test_bad_arguments(scenes: dict[str, Scenario], kwargs: dict[str, object], match: str) -> None:
    with pytest.raises(ValueError, match=match):
        fleet_tasks(scenes["ppswarm1"], **kwargs)  # type: ignore[arg-type]


# ---------------------------------------------------------------------------- the built-ins
def test_ppswarm_builtins(scenes: dict[str, Scenario]) -> None:
    listing = dict(list_builtin())
    area = float(np.prod(scenes["ppswarm1"].bounds.hi[:2] - scenes["ppswarm1"].bounds.lo[:2]))
    fractions = []
    for name, count in zip(PPSWARM, [6, 10, 15, 20], strict=True):
        s = scenes[name]
        assert "Drones 8, 192" in listing[name]
        assert len(s.cylinders) == count
        assert len(s.tasks) == 40 and s.metadata["fleet"]["count"] == 40
        assert (s.cost, s.n_waypoints) == ("ppswarm", 10)
        assert s.altitude is not None and (s.altitude.min, s.altitude.max) == (100, 200)
        assert (s.uav.speed, s.uav.turn_radius, s.uav.s1, s.uav.s2) == (20, 20, 15, 10)
        # every cylinder (with S1) keeps out of the start and goal bands
        lo, hi, band = placement_box(s)
        for c in s.cylinders:
            reach = c.effective_radius + s.uav.s1
            assert c.infinite
            assert np.all(np.asarray(c.center) - reach >= lo + band), c
            assert np.all(np.asarray(c.center) + reach <= hi - band), c
        # no two cylinders overlap, so the covered area is the sum of the discs
        for i, a in enumerate(s.cylinders):
            for b in s.cylinders[:i]:
                assert math.dist(a.center, b.center) > a.radius + b.radius
        fraction = sum(math.pi * c.radius**2 for c in s.cylinders) / area
        assert f"{100 * fraction:.1f} %" in listing[name]
        fractions.append(fraction)
    assert fractions == sorted(fractions) and len(set(fractions)) == 4
    # each scenario holds the previous one's cylinders
    for lower, higher in itertools.pairwise(PPSWARM):
        inner = scenes[lower].cylinders
        assert scenes[higher].cylinders[: len(inner)] == inner


# ---------------------------------------------------------------------------- with_fleet
def test_with_fleet_and_round_trip(scenes: dict[str, Scenario], tmp_path: Path) -> None:
    s = scenes["ppswarm1"]
    big = with_fleet(s, 120, seed=4, pattern="random", min_spacing=35.0)
    assert len(big.tasks) == 120 and len(s.tasks) == 40  # the original is unchanged
    assert big.tasks == fleet_tasks(s, 120, seed=4, pattern="random", min_spacing=35.0)
    assert big.cylinders == s.cylinders and big.name == s.name
    fleet = {"count": 120, "pattern": "random", "seed": 4, "min_spacing": 35.0}
    assert big.metadata["fleet"] == fleet and big.metadata["spec"]["fleet"] == fleet
    assert s.metadata["spec"]["fleet"] == {"count": 40, "pattern": "crossing", "seed": 0}
    again = load_scenario(save_scenario(big, tmp_path / "big.yaml"))
    assert again.tasks == big.tasks

    # a scenario with listed tasks gets the fleet in place of them
    spso = with_fleet(resolve("spso"), 12, seed=2)
    assert "tasks" not in spso.metadata["spec"]
    assert load_scenario(save_scenario(spso, tmp_path / "spso.json")).tasks == spso.tasks

    # a scenario built in code has no file-level spec: saving writes the expanded tasks
    code = Scenario(
        name="code",
        bounds=s.bounds,
        tasks=s.tasks[:1],
        terrain=s.terrain,
        cylinders=s.cylinders,
        altitude=s.altitude,
    )
    built = with_fleet(code, 15, seed=1)
    assert "spec" not in built.metadata
    assert load_scenario(save_scenario(built, tmp_path / "code.yaml")).tasks == built.tasks


def test_with_fleet_metadata_matches_a_loaded_fleet(scenes: dict[str, Scenario]) -> None:
    s = scenes["ppswarm2"]
    again = with_fleet(s, 40, seed=0, pattern="crossing")
    assert again.tasks == s.tasks
    assert again.metadata["fleet"] == s.metadata["fleet"]
    assert again.metadata["spec"] == s.metadata["spec"]


# ---------------------------------------------------------------------------- altitude layers
def pair_distances(p: np.ndarray) -> np.ndarray:
    """3-D distances between every two points (the diagonal inf)."""
    d = np.sqrt(np.sum((p[:, None, :] - p[None, :, :]) ** 2, axis=2))
    d[np.diag_indices(len(p))] = np.inf
    return d


def height_offsets(s: Scenario, p: np.ndarray) -> np.ndarray:
    """z less the one-layer height (the band's middle above the ground), rounded to the mm."""
    assert s.altitude is not None
    return np.round(p[:, 2] - (np.asarray(s.ground(p[:, 0], p[:, 1])) + s.altitude.mid), 3)


@pytest.fixture(scope="module")
def thousand(scenes: dict[str, Scenario]) -> Scenario:
    return with_fleet(scenes["ppswarm1"], 1000)  # one layer holds 916


def test_thousand_uavs_in_altitude_layers(scenes: dict[str, Scenario], thousand: Scenario) -> None:
    s, tasks = scenes["ppswarm1"], thousand.tasks
    assert [t.id for t in tasks] == [f"uav{i}" for i in range(1000)]
    assert fleet_layout(s, 1000) == (tasks, 2)  # the same seed gives the same tasks
    assert fleet_tasks(s, 1000, seed=1) != tasks
    assert thousand.metadata["fleet"]["layers"] == 2
    starts, goals = ends(tasks)
    for p in (starts, goals):
        assert pair_distances(p).min() >= 30.0  # in 3-D
        # two layers 30 m apart, centred on the one-layer height (150 m above ground)
        assert set(height_offsets(s, p)) == {-15.0, 15.0}
    diag = math.hypot(*(s.bounds.hi[:2] - s.bounds.lo[:2]))
    assert np.hypot(*(goals[:, :2] - starts[:, :2]).T).min() >= MIN_LENGTH_FRACTION * diag
    for t in tasks:
        assert t.start_time == 0.0
        for p in (t.start, t.goal):
            assert s.point_problems(np.asarray(p)) == [], (t.id, p)


def test_random_pattern_in_altitude_layers(scenes: dict[str, Scenario]) -> None:
    s = scenes["ppswarm2"]
    tasks, layers = fleet_layout(s, 1000, seed=3, pattern="random")  # one layer holds 860
    assert layers == 2 and len(tasks) == 1000
    starts, goals = ends(tasks)
    for p in (starts, goals):
        assert pair_distances(p).min() >= 30.0
        assert set(height_offsets(s, p)) == {-15.0, 15.0}
        assert all(s.point_problems(q) == [] for q in p)
    diag = math.hypot(*(s.bounds.hi[:2] - s.bounds.lo[:2]))
    assert np.hypot(*(goals[:, :2] - starts[:, :2]).T).min() >= MIN_LENGTH_FRACTION * diag


def test_fleets_that_fit_in_one_layer_are_unchanged(scenes: dict[str, Scenario]) -> None:
    """Coordinates recorded with the generator before altitude layers existed."""
    s = scenes["ppswarm1"]
    small = fleet_tasks(s, 40, seed=0)
    assert small[0].start == (42.86381978058217, 143.85176412542938, 376.8607211659799)
    assert small[20] == Task(
        "uav20",
        (902.6864252180575, 87.51194021438177, 430.6252165120451),
        (770.2347134957964, 796.4288227426694, 322.6230596147225),
    )
    assert small[39].goal == (999.189433802865, 844.2746467866219, 364.9866443520017)
    fleet = with_fleet(s, 500, seed=0)
    assert "layers" not in fleet.metadata["fleet"]
    large = fleet.tasks
    assert large[0].start == (49.207605461769845, 134.41693566085695, 372.8794996499883)
    assert large[250] == Task(
        "uav250",
        (143.4589944756945, 572.3857428648928, 316.388747294259),
        (889.4488552760215, 545.1097063577341, 355.5433261352494),
    )
    assert large[499].goal == (589.0293622668883, 373.50513629179625, 361.5093011370084)


def test_layers_keep_clear_of_finite_cylinders() -> None:
    """A finite cylinder below the one-layer height blocks the lower layer (with S1) only."""
    tower = Cylinder((200.0, 200.0), 60.0, z_min=0.0, z_max=125.0)
    s = Scenario(
        name="tower",
        bounds=Bounds((0.0, 0.0, 0.0), (400.0, 400.0, 300.0)),
        tasks=(Task("t", (10.0, 10.0, 150.0), (390.0, 390.0, 150.0)),),
        cylinders=(tower,),
        altitude=AltitudeBand(100.0, 200.0, "absolute"),
    )
    one = fleet_layout(s, 60, seed=0, pattern="random")
    assert one.layers == 1
    reach = tower.effective_radius + s.uav.s1
    for n, heights in ((250, {135.0, 165.0}), (400, {120.0, 150.0, 180.0})):
        tasks, layers = fleet_layout(s, n, seed=0, pattern="random")
        assert layers == len(heights) and len(tasks) == n
        starts, goals = ends(tasks)
        for p in (starts, goals):
            assert set(np.round(p[:, 2], 6)) == heights
            assert pair_distances(p).min() >= 30.0
            near = np.hypot(p[:, 0] - 200.0, p[:, 1] - 200.0) < reach
            assert not np.any(near), "a node counts only if it is valid in every layer"
            assert all(s.point_problems(q) == [] for q in p)
    # in one layer (150 m, above the tower and its S1) the fleet may pass over it
    s1, g1 = ends(one.tasks)
    assert np.any(np.hypot(*(np.vstack([s1, g1])[:, :2] - 200.0).T) < reach)


def test_a_2d_fleet_that_does_not_fit_still_raises() -> None:
    s = resolve("simple2d")
    with pytest.raises(ValueError, match=r"cannot place 60 UAV starts .*placed \d+ \(valid"):
        fleet_tasks(s, 60, min_spacing=10.0)


def test_layered_fleet_saves_and_loads_the_same(thousand: Scenario, tmp_path: Path) -> None:
    assert thousand.metadata["spec"]["fleet"] == {"count": 1000, "pattern": "crossing", "seed": 0}
    again = load_scenario(save_scenario(thousand, tmp_path / "big.yaml"))
    assert again.tasks == thousand.tasks
    assert again.metadata["fleet"] == thousand.metadata["fleet"]  # layers: 2 as well
    assert resolve("ppswarm1@1000").tasks == thousand.tasks
