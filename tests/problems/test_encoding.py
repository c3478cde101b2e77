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


@pytest.mark.parametrize(
    ("scene", "encoding", "lookup"),
    [
        ("spso", SphericalEncoding, None),
        ("spso", CartesianEncoding, None),
        ("spso", SphericalEncoding, "bilinear"),
        ("ppswarm1", SphericalEncoding, None),
        ("ppswarm1", CartesianEncoding, None),
        ("simple2d", SphericalEncoding, None),
        ("simple2d", CartesianEncoding, None),
    ],
)
def test_decode_kernel_gives_the_bits_of_the_numpy_form(scene, encoding, lookup) -> None:
    """One Numba pass (steps, clipping, terrain, endpoints) against the NumPy chain it replaced,
    bit for bit, also outside the gene box (the optimizers' velocities never leave it, but a
    user's genes may)."""
    problem = PathProblem(load_builtin(scene), lookup=lookup)
    enc = encoding(problem)
    rng = np.random.default_rng(3)
    span = enc.upper - enc.lower
    X = enc.lower - 0.2 * span + rng.random((64, enc.dim)) * 1.4 * span
    got, want = enc.decode(X), enc.decode_reference(X)
    assert got.shape == want.shape
    np.testing.assert_array_equal(got, want)


def test_decode_refuses_a_wrong_gene_shape(spso_problem: PathProblem) -> None:
    enc = SphericalEncoding(spso_problem)
    with pytest.raises(ValueError, match=r"genes must be \(pop, 30\)"):
        enc.decode(np.zeros((4, 29)))


@pytest.mark.parametrize("encoding", [SphericalEncoding, CartesianEncoding])
def test_feasibility_tracking_checks_only_what_can_lower_the_record(encoding) -> None:
    """The best feasible cost after each call equals the running minimum over every path's
    full evaluation, though only the paths that could lower it are checked."""
    problem = PathProblem(load_builtin("spso"))
    enc = encoding(problem, track_feasibility=True)
    rng = np.random.default_rng(7)
    want, best, checked = [], np.inf, []
    original = problem.feasible
    problem.feasible = lambda p: (checked.append(len(p)), original(p))[1]  # type: ignore[method-assign]
    sph = SphericalEncoding(problem)  # swarms drawn as spherical genes, then encoded
    centre = sph.lower + 0.5 * (sph.upper - sph.lower)
    for k in range(12):
        scale = 0.5 if k < 6 else 0.05  # wide swarms, then tight ones (most paths feasible)
        X = np.clip(centre + scale * rng.standard_normal((60, sph.dim)) * (sph.upper - sph.lower),
                    sph.lower, sph.upper)  # fmt: skip
        if encoding is CartesianEncoding:
            X = enc.encode(sph.decode(X))
        f = enc.evaluate(X)
        ev = problem.evaluate(enc.decode(X))
        np.testing.assert_array_equal(f, ev.cost)
        best = min(best, float(np.min(ev.cost[ev.feasible], initial=np.inf)))
        want.append(best)
    assert enc.feasible_history == want
    assert np.isfinite(want[-1])
    assert sum(checked) < 12 * 60 / 2  # far fewer paths checked than evaluated
