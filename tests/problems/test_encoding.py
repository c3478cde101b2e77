"""Encodings: Cartesian round trip, SPSO's spherical vectors."""

from __future__ import annotations

import numpy as np
import pytest

from uavplan.problems import CartesianEncoding, PathProblem
from uavplan.problems.encoding import SphericalEncoding
from uavplan.scenarios import load_builtin


@pytest.fixture(scope="module")
def spso_problem() -> PathProblem:
    return PathProblem(load_builtin("spso"))


def test_spherical_bounds_follow_spso(spso_problem: PathProblem) -> None:
    enc = SphericalEncoding(spso_problem)
    # SPSO main.m: r in [0, 2 |end - start| / n], psi in +-pi/4, phi within pi/4 of the heading
    r_max = 2 * np.hypot(600.0, 700.0) / 10
    phi0 = np.arctan2(700.0, 600.0)
    assert enc.lower[:3] == pytest.approx([0.0, -np.pi / 4, phi0 - np.pi / 4])
    assert enc.upper[:3] == pytest.approx([r_max, np.pi / 4, phi0 + np.pi / 4])
    assert enc.dim == 30 and enc.block == 3


def test_spherical_decode_steps_from_the_previous_node(spso_problem: PathProblem) -> None:
    enc = SphericalEncoding(spso_problem)
    rng = np.random.default_rng(0)
    X = enc.lower + rng.random((50, enc.dim)) * (enc.upper - enc.lower)
    genes = enc.to_cartesian_genes(X).reshape(50, 10, 3)
    start = np.array([200.0, 100.0, 150.0])  # SPSO's start, z above ground
    g = X.reshape(50, 10, 3)
    prev = np.broadcast_to(start, (50, 3))
    lo, hi = enc.cart.point_lower, enc.cart.point_upper
    for i in range(10):
        r, psi, phi = g[:, i, 0], g[:, i, 1], g[:, i, 2]
        step = np.stack(
            [r * np.cos(psi) * np.cos(phi), r * np.cos(psi) * np.sin(phi), r * np.sin(psi)], axis=1
        )
        prev = np.clip(prev + step, lo, hi)
        assert np.allclose(genes[:, i], prev)
    paths = enc.decode(X)
    assert paths.shape == (50, 12, 3)
    assert np.allclose(paths[:, 0], spso_problem.start)
    assert np.allclose(paths[:, -1], spso_problem.goal)
    # costs through the spherical encoding equal the problem's cost of the decoded paths
    assert np.array_equal(enc.evaluate(X), spso_problem.cost(paths))


def test_cartesian_round_trip(spso_problem: PathProblem) -> None:
    enc = CartesianEncoding(spso_problem)
    rng = np.random.default_rng(1)
    X = enc.lower + rng.random((20, enc.dim)) * (enc.upper - enc.lower)
    assert np.allclose(enc.encode(enc.decode(X)), X)


def test_polar_form_in_2d() -> None:
    sc = load_builtin("simple2d")
    enc = SphericalEncoding(PathProblem(sc))
    assert enc.block == 2 and enc.dim == 2 * sc.n_waypoints
    rng = np.random.default_rng(2)
    X = enc.lower + rng.random((10, enc.dim)) * (enc.upper - enc.lower)
    paths = enc.decode(X)
    assert paths.shape == (10, sc.n_waypoints + 2, 2)
    assert np.all(sc.bounds.contains(paths))


def test_clipped_cumsum_matches_its_numpy_reference() -> None:
    from uavplan.problems.encoding import clipped_cumsum, clipped_cumsum_reference

    rng = np.random.default_rng(3)
    for d in (2, 3):
        steps = rng.normal(0.0, 30.0, (50, 12, d))
        start = rng.uniform(0, 100, d)
        lo, hi = np.zeros(d), np.full(d, 100.0)
        got = clipped_cumsum(steps, start, lo, hi)
        want = clipped_cumsum_reference(steps, start, lo, hi)
        np.testing.assert_array_equal(got, want)
        assert (got == 0.0).any() and (got == 100.0).any()  # the clip was exercised
