"""The fused cost kernels (:data:`uavplan.problems.path_problem.FUSED`: SPSO's and PPSwarm's
four terms) against the terms they replace, computed apart (``PathProblem(..., fused=False)``):
the same values to 1e-12 relative and the same infinities (and NaN), over random worlds and
random paths, for the total alone (which stops early at a collision) and for every term."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from uavplan.problems import PathProblem
from uavplan.problems import costs as C
from uavplan.world import AltitudeBand, Cylinder, Scenario, Task, Terrain
from uavplan.world.dynamic import MovingObstacle
from uavplan.world.geometry import GRID_MIN_CYLINDERS
from uavplan.world.scenario import Bounds

from .test_costs import random_paths

SEEDS = st.integers(0, 2**32 - 1)


def random_world(
    rng: np.random.Generator,
    n_cylinders: int,
    terrain: bool,
    band: bool,
    cost: str = "spso",
    reference: str = "ground",
    moving: int = 0,
) -> Scenario:
    """A 3-D world on [0, 100]^2 x [0, 60]: a random DEM (random origin and cell sizes), random
    cylinders (margins, some of finite height), ``moving`` moving obstacles, the ``cost``."""
    t = None
    if terrain:
        ny, nx = rng.integers(2, 12, 2)
        t = Terrain(
            rng.uniform(0, 20, (ny, nx)),
            float(rng.uniform(-5, 5)),
            float(rng.uniform(-5, 5)),
            float(rng.uniform(3, 15)),
            float(rng.uniform(3, 15)),
        )
    cyl = []
    for _ in range(n_cylinders):
        lo, hi = -np.inf, np.inf
        if rng.random() < 0.4:
            lo = float(rng.uniform(-10, 30))
            hi = lo + float(rng.uniform(1, 40))
        cyl.append(
            Cylinder(
                tuple(rng.uniform(0, 100, 2)),
                float(rng.uniform(1, 10)),
                lo,
                hi,
                margin=float(rng.choice([0.0, 1.0, rng.uniform(0, 2)])),
            )
        )
    return Scenario(
        name="random",
        bounds=Bounds((0.0, 0.0, 0.0), (100.0, 100.0, 60.0)),
        tasks=(Task("uav", (1.0, 2.0, 20.0), (95.0, 90.0, 30.0)),),
        terrain=t,
        cylinders=tuple(cyl),
        altitude=AltitudeBand(5.0, 40.0, reference) if band else None,  # type: ignore[arg-type]
        moving_obstacles=tuple(
            MovingObstacle(
                float(rng.uniform(1, 6)),
                np.array([0.0, 10.0]),
                rng.uniform([0, 0, 0], [100, 100, 50], (2, 3)),
            )
            for _ in range(moving)
        ),
        cost=cost,
    )


def angle_paths(P: int, N: int, rng: np.random.Generator) -> np.ndarray:
    """Paths whose turns and climb changes sit at SPSO's 45-degree limits or near them (where
    the fused kernel decides without computing the angles only outside a margin)."""
    out = np.empty((P, N, 3))
    for q in range(P):
        pts = [np.array([10.0, 10.0, 20.0])]
        heading = 0.0
        climb = 0.0
        for _ in range(N - 1):
            heading += np.radians(rng.choice([0.0, 45.0, -45.0, 90.0, 44.9999999, 45.0000001]))
            climb = rng.choice([0.0, 45.0, -45.0, 22.5, climb + 45.0, climb - 45.0])
            climb = float(np.clip(climb, -80.0, 80.0))
            r = float(rng.choice([1.0, 3.0, 7.5]))
            step = [np.cos(heading), np.sin(heading), np.tan(np.radians(climb))]
            pts.append(pts[-1] + r * np.array(step))
        out[q] = pts
    return out


def assert_same(got: np.ndarray, want: np.ndarray, what: str) -> None:
    np.testing.assert_array_equal(np.isnan(got), np.isnan(want), err_msg=what)
    np.testing.assert_array_equal(np.isposinf(got), np.isposinf(want), err_msg=what)
    ok = np.isfinite(want)
    np.testing.assert_allclose(got[ok], want[ok], rtol=1e-12, atol=1e-12, err_msg=what)


def compare(sc: Scenario, paths: np.ndarray, lookup: str | None = None) -> None:
    fused, ref = PathProblem(sc, lookup=lookup), PathProblem(sc, lookup=lookup, fused=False)
    assert fused.fused is not None and ref.fused is None
    assert_same(fused.cost(paths), ref.cost(paths), "cost")
    a, b = fused.evaluate(paths), ref.evaluate(paths)
    assert list(a.terms) == list(b.terms)
    assert_same(a.cost, b.cost, "evaluate")
    for name in a.terms:
        assert_same(a.terms[name], b.terms[name], name)
    np.testing.assert_array_equal(a.feasible, b.feasible)
    for exact in (True, False):
        (f1, cv1), (f2, cv2) = fused.evaluate_cv(paths, exact), ref.evaluate_cv(paths, exact)
        assert_same(f1, f2, f"evaluate_cv({exact})")
        np.testing.assert_array_equal(cv1, cv2)


#: the random world's draws: seed, cylinders, points per path, with a terrain or not
WORLD = {"seed": SEEDS, "J": st.integers(0, 8), "N": st.integers(2, 9), "terrain": st.booleans()}


@settings(max_examples=40, deadline=None)
@given(**WORLD, band=st.booleans())
def test_spso_fused_equals_the_terms(seed: int, J: int, N: int, terrain: bool, band: bool) -> None:
    rng = np.random.default_rng(seed)
    sc = random_world(rng, J, terrain, band)
    compare(sc, world_paths(rng, N))


def world_paths(rng: np.random.Generator, N: int) -> np.ndarray:
    """Random paths over the random worlds, and paths at the 45-degree limits."""
    paths = random_paths(rng, 12, N, 3, box=50.0) + np.array([50.0, 50.0, 20.0])
    return np.concatenate([paths, angle_paths(6, N, rng)])


@settings(max_examples=40, deadline=None)
@given(
    **WORLD,
    band=st.sampled_from([None, "ground", "absolute"]),
    lookup=st.sampled_from(["bilinear", "nearest"]),
    moving=st.integers(0, 2),
    cruise=st.one_of(st.none(), st.floats(-10.0, 70.0)),
)
def test_ppswarm_fused_equals_the_terms(
    seed: int,
    J: int,
    N: int,
    terrain: bool,
    band: str | None,
    lookup: str,
    moving: int,
    cruise: float | None,
) -> None:
    rng = np.random.default_rng(seed)
    sc = random_world(rng, J, terrain, band is not None, "ppswarm", band or "ground", moving)
    if cruise is not None:  # a cruise layer instead of the band's middle
        sc = dataclasses.replace(sc, tasks=(dataclasses.replace(sc.tasks[0], cruise=cruise),))
    compare(sc, world_paths(rng, N), lookup)


@settings(max_examples=5, deadline=None)
@given(seed=SEEDS, cost=st.sampled_from(["spso", "ppswarm"]))
def test_fused_with_the_cylinder_grid(seed: int, cost: str) -> None:
    rng = np.random.default_rng(seed)
    sc = random_world(rng, GRID_MIN_CYLINDERS + 6, True, True, cost, moving=cost == "ppswarm")
    compare(sc, random_paths(rng, 10, 6, 3, box=50.0) + np.array([50.0, 50.0, 20.0]))


@pytest.mark.parametrize("cost", ["spso", "ppswarm"])
def test_fused_keeps_nan_and_infinities(cost: str) -> None:
    rng = np.random.default_rng(5)
    sc = random_world(rng, 4, True, True, cost)
    paths = random_paths(rng, 8, 6, 3, box=50.0) + np.array([50.0, 50.0, 20.0])
    paths[0, 2, 2] = np.nan
    paths[1, 3, 0] = np.inf
    paths[2, 1, 2] = -30.0  # under the ground
    paths[3, 4, 1] = -np.inf
    compare(sc, paths)


def test_spso_fused_on_the_spso_scenario_and_its_limits() -> None:
    """The SPSO benchmark itself, with exact 45-degree turns and climb changes."""
    from uavplan.scenarios import load_builtin

    sc = load_builtin("spso")
    rng = np.random.default_rng(0)
    paths = angle_paths(30, 12, rng) * np.array([20.0, 20.0, 1.0]) + np.array([200, 100, 300])
    compare(sc, paths)
    assert np.isfinite(PathProblem(sc).cost(paths)).any()


def test_the_presets_that_fuse() -> None:
    from uavplan.scenarios import load_builtin

    sc = load_builtin("spso")
    assert PathProblem(sc).fused is not None
    assert PathProblem(sc, weights={"threat": 2.0}).fused is not None
    assert PathProblem(sc, lookup="bilinear").fused is None  # the kernel reads the nearest node
    assert PathProblem(sc, cost="hrmaga").fused is None
    assert PathProblem(sc, cost="ppswarm").fused is not None
    assert PathProblem(sc, cost="ppswarm", lookup="nearest").fused is not None
    assert PathProblem(load_builtin("simple2d"), cost="ppswarm").fused is None  # 3-D only
    assert tuple(t.name for t in PathProblem(sc).terms) == C.SPSO_TERMS


@pytest.mark.parametrize("weights", [{"threat": 2.0, "smoothness": 0.5}, {"length": 0.0}])
def test_spso_fused_with_other_weights(weights: dict[str, float]) -> None:
    rng = np.random.default_rng(2)
    sc = random_world(rng, 5, True, True)
    paths = random_paths(rng, 20, 7, 3, box=50.0) + np.array([50.0, 50.0, 20.0])
    a = PathProblem(sc, weights=weights).cost(paths)
    b = PathProblem(sc, weights=weights, fused=False).cost(paths)
    assert_same(a, b, "cost")


def test_the_fused_kernel_compiles_once_whatever_terms_a_world_has() -> None:
    """Worlds with and without the indexed threat pass and with and without moving obstacles,
    paths read-only or not: one signature of the fused kernel (each new one is a compilation
    of about ten seconds on a machine's first plan)."""
    rng = np.random.default_rng(5)
    many = GRID_MIN_CYLINDERS + 2
    worlds = [random_world(rng, 2, True, True, "ppswarm"),
              random_world(rng, many, False, True, "ppswarm"),
              random_world(rng, 2, False, True, "ppswarm", moving=2),
              random_world(rng, many, True, True, "ppswarm", moving=1)]  # fmt: skip
    for sc in worlds:
        paths = world_paths(rng, 5)
        PathProblem(sc).cost(paths)
        paths.setflags(write=False)
        PathProblem(sc).cost(paths)
    assert len(C.path_cost_batch.serial.signatures) == 1, C.path_cost_batch.serial.signatures
