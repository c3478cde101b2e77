"""The large-fleet built-ins `open` (no obstacles) and `dense` (a generated cylinder field)."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from typer.testing import CliRunner

from uavplan.cli import app
from uavplan.scenarios import list_builtin, load_builtin, resolve
from uavplan.scenarios.generators import (
    DENSE_BOUNDS,
    DENSE_COUNT,
    DENSE_RADII,
    DENSE_SEED,
    dense_cylinders,
    dense_field_box,
)
from uavplan.world import Scenario
from uavplan.world.fleet_tasks import placement_box


@pytest.fixture(scope="module")
def scenes() -> dict[str, Scenario]:
    return {name: load_builtin(name) for name in ("open", "dense", "ppswarm1")}


def edge_gaps(sc: Scenario) -> np.ndarray:
    """Distances between the edges of every pair of cylinders."""
    c = np.array([cy.center for cy in sc.cylinders])
    r = np.array([cy.radius for cy in sc.cylinders])
    d = np.hypot(c[:, None, 0] - c[None, :, 0], c[:, None, 1] - c[None, :, 1])
    return np.asarray((d - r[:, None] - r[None, :])[np.triu_indices(len(r), 1)])


def coverage(sc: Scenario) -> float:
    area = float(np.prod(sc.bounds.hi[:2] - sc.bounds.lo[:2]))
    return sum(math.pi * c.radius**2 for c in sc.cylinders) / area


def test_same_setup_as_ppswarm1(scenes: dict[str, Scenario]) -> None:
    ref = scenes["ppswarm1"]
    listing = dict(list_builtin())
    for name in ("open", "dense"):
        s = scenes[name]
        assert s.dim == 3 and s.name == name
        assert "Drones 8, 192" in listing[name]
        assert s.uav == ref.uav
        assert (s.cost, s.n_waypoints) == ("ppswarm", 10)
        assert np.array_equal(s.bounds.lo[:2], ref.bounds.lo[:2])
        assert np.array_equal(s.bounds.hi[:2], ref.bounds.hi[:2])
        assert len(s.tasks) == 40
        assert s.metadata["spec"]["fleet"] == {"count": 40, "pattern": "crossing", "seed": 0}
    dense = scenes["dense"]
    assert dense.terrain is not None and dense.terrain.name == "spso"
    assert dense.bounds == ref.bounds and dense.altitude == ref.altitude
    assert dense.metadata["spec"]["terrain"] == ref.metadata["spec"]["terrain"]


def test_open_is_flat_and_empty(scenes: dict[str, Scenario]) -> None:
    s = scenes["open"]
    assert s.terrain is None
    assert not (s.cylinders or s.circles or s.polygons or s.danger_areas)
    assert not (s.uncertain_areas or s.moving_obstacles)
    assert s.altitude is not None and s.altitude.reference == "absolute"
    assert (s.altitude.min, s.altitude.max) == (100, 200)
    assert s.bounds.lower[2] == 0 and s.bounds.upper[2] >= s.altitude.max
    assert {t.start[2] for t in s.tasks} | {t.goal[2] for t in s.tasks} == {150.0}


def test_dense_field(scenes: dict[str, Scenario]) -> None:
    s = scenes["dense"]
    s1 = s.uav.s1
    description = " ".join(s.description.split())
    assert len(s.cylinders) >= 40
    assert f"{len(s.cylinders)} infinitely tall cylinders" in description
    for c in s.cylinders:
        assert c.infinite and c.margin == 0 and 20 <= c.radius <= 50
    fraction = coverage(s)
    assert 0.12 <= fraction <= 0.20
    assert f"covering {100 * fraction:.1f} % of the map" in description
    gaps = edge_gaps(s)
    narrowest = float(gaps.min())
    assert 1.5 * s1 <= narrowest <= 2 * s1 + 3
    assert f"the narrowest {narrowest:.1f} m" in description
    # several narrow passages (1.5-3 S1), some only a centred path passes with S1 to both sides
    counts = [int(np.count_nonzero(gaps < g)) for g in (3 * s1, 2 * s1 + 3, 2 * s1)]
    assert counts[0] >= 5 and counts[1] >= 3
    m = re.search(r"(\d+) pairs of .* (\d+) of them under 33 m .* (\d+) under 30 m", description)
    assert m is not None and [int(g) for g in m.groups()] == counts


@pytest.mark.parametrize("name", ["open", "dense"])
def test_bands_free(scenes: dict[str, Scenario], name: str) -> None:
    s = scenes[name]
    lo, hi, band = placement_box(s)
    for c in s.cylinders:
        reach = c.effective_radius + s.uav.s1
        assert np.all(np.asarray(c.center) - reach >= lo + band), c
        assert np.all(np.asarray(c.center) + reach <= hi - band), c
    field_lo, field_hi = dense_field_box()
    assert np.allclose(field_lo, lo + band) and np.allclose(field_hi, hi - band)


def test_generator_reproduces_dense_yaml(scenes: dict[str, Scenario]) -> None:
    assert dense_cylinders() == scenes["dense"].cylinders
    assert dense_cylinders(DENSE_SEED, DENSE_COUNT) == scenes["dense"].cylinders
    bounds = scenes["dense"].bounds
    assert (tuple(bounds.lo[:2]), tuple(bounds.hi[:2])) == DENSE_BOUNDS


def test_generator_other_draws() -> None:
    other = dense_cylinders(seed=3, n=25, min_gap=40.0)
    assert len(other) == 25 and other != dense_cylinders(seed=4, n=25, min_gap=40.0)
    assert other == dense_cylinders(seed=3, n=25, min_gap=40.0)
    lo, hi = dense_field_box()
    c = np.array([cy.center for cy in other])
    r = np.array([cy.radius for cy in other])
    assert np.all((r >= DENSE_RADII[0]) & (r <= DENSE_RADII[1]))
    assert np.all(r[:-1] >= r[1:])  # largest first
    assert np.all(c - (r + 15)[:, None] >= lo) and np.all(c + (r + 15)[:, None] <= hi)
    d = np.hypot(c[:, None, 0] - c[None, :, 0], c[:, None, 1] - c[None, :, 1])
    assert np.min((d - r[:, None] - r[None, :])[np.triu_indices(25, 1)]) >= 40.0
    with pytest.raises(ValueError, match="n must be"):
        dense_cylinders(n=0)
    with pytest.raises(ValueError, match="radius_range"):
        dense_cylinders(radius_range=(30.0, 20.0))
    with pytest.raises(ValueError, match="cannot place 3 cylinders 1000 m apart"):
        dense_cylinders(n=3, min_gap=1000.0)


@pytest.mark.parametrize(("name", "n"), [("dense", 200), ("open", 500)])
def test_large_fleets_place(name: str, n: int) -> None:
    s = resolve(f"{name}@{n}")
    assert s.name == f"{name}@{n}" and len(s.tasks) == n
    starts = np.array([t.start[:2] for t in s.tasks])
    d = np.hypot(starts[:, None, 0] - starts[None, :, 0], starts[:, None, 1] - starts[None, :, 1])
    assert np.min(d[np.triu_indices(n, 1)]) >= 3 * s.uav.s2


def test_cli_show() -> None:
    runner = CliRunner()
    out = runner.invoke(app, ["scenario", "show", "dense"])
    assert out.exit_code == 0, out.output
    assert "40 cylinders (40 infinite)" in out.stdout and "terrain: spso" in out.stdout
    out = runner.invoke(app, ["scenario", "show", "open"])
    assert out.exit_code == 0, out.output
    assert "terrain: none" in out.stdout and "0 cylinders, 0 circles, 0 polygons" in out.stdout
