"""Our RRT* against OMPL's RRT* and Informed RRT* on a dense 3-D cylinder field (issue 18 items
5 and 6): path length at matched wall times, success rates, ratios, all from this one run.

Run: ``python benchmarks/vs_ompl.py [--seeds 5] [--times 0.5 1 2 5] [--reference 10]
[--profile 2] [--profile-only]`` (needs ``pip install ompl``, the ``peers`` extra; without it
only our rows are printed).

First a profile: the share of an RRT* run's wall time spent outside the kernels (the Numba
loop, the tightening kernels, the validator's and the cost's calls, the Python loop's tree and
grid kernels; timed by wrappers), before (``loop="python"``, the reference loop, as the planner
ran until this change) and after, with the RRT* iterations per second.

**The field** (:func:`field`, generated here, seed ``FIELD_SEED``): a 1000 m x 1000 m x 200 m box,
no terrain, no altitude band; 48 vertical cylinders of radius 20-50 m from
:func:`uavplan.scenarios.generators.dense_cylinders` (the ``dense`` built-in's rejection
sampler: edges at least 22.5 m apart, so many passages of 22.5-45 m), standing on the ground;
about half (drawn) taller than the box, the others with tops drawn in 60-150 m, so a path may
thread the passages or climb over the low ones: a 3-D problem. 18.5 % of the map's area is
covered, 35 % of the field's. The task crosses the field: (20, 500, 30) to (980, 500, 30); the
way round through the free bands along the edges is about twice as long as the way through.

**A fair comparison.**

* The same start, goal and bounds (OMPL's ``RealVectorStateSpace`` has the box as its bounds;
  ours samples the same box: no band), no obstacle inflation on either side (the cylinders'
  radii as they are, no margin), and the same metric: the Euclidean length of the returned
  polyline.
* The same validity checker, exact on both sides: OMPL's ``MotionValidator`` is a Python
  subclass whose ``checkMotion`` calls the compiled segment check of our
  :class:`uavplan.problems.validity.MotionValidator` (:attr:`segment_kernel`, specialised for
  this field: about 1 us per call from Python), and its ``StateValidityChecker`` the same check
  of the zero-length segment. So OMPL does no discrete motion checking (its resolution does not
  matter), and neither side can cut a corner that the other would refuse.
* Every returned path, OMPL's and ours, is judged by the independent verifier
  (:func:`uavplan.verify.verifier.verify_trajectories`, planned polyline, no kinematics); one
  that fails counts as a failure, as does no path (OMPL: no exact solution).
* Ours may shorten its path after the search (``tighten``); OMPL's rows
  ``InformedRRTstar+simplify`` give OMPL's own path simplifier (``simplifySolution``) the last
  10 % of the same wall time, so that both sides are seen with post-processing too.
* Each planner at its own defaults otherwise: OMPL's RRT* and Informed RRT* with
  ``PathLengthOptimizationObjective`` (range 0.2 x the space's extent = 286 m, goal bias 0.05,
  k-nearest rewiring, rewire factor 1.1, delayed collision checking); ours as each row says.
  OMPL's ``solve(t)`` gets the wall time, ours ``Budget(max_time=t)`` through
  ``Planner.plan`` (planning time: problem set-up, search, the final path's evaluation; Numba
  compilation left out, as every reported time). Both are single-threaded (one Numba thread).

Printed: per planner and wall time, the median length over the seeds (and min-max), the success
rate, the median ratio to OMPL's best median at ``--reference`` seconds (over OMPL's rows
without and with simplification; the target: ours at 0.5 s <= that, at 100 % success), and the
straight-line distance as a lower bound.
"""

from __future__ import annotations

import argparse
import functools
import math
import statistics
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numba
import numpy as np
from numba import njit

from uavplan.io.plan_file import Trajectory
from uavplan.optimizers.base import Budget
from uavplan.planners import get_planner
from uavplan.problems._validity_kernels import static_world_ok
from uavplan.problems.validity import MotionValidator
from uavplan.scenarios.generators import dense_cylinders
from uavplan.verify.verifier import verify_trajectories
from uavplan.world.obstacles import Cylinder
from uavplan.world.scenario import Bounds, Scenario, Task

FIELD_SEED = 1
N_CYLINDERS = 48
START = (20.0, 500.0, 30.0)
GOAL = (980.0, 500.0, 30.0)
#: OMPL's generator is seeded once per process; its runs follow one another in the stream
OMPL_SEED = 1
#: ``+simplify`` rows: the share of the wall time given to OMPL's path simplifier (shortcuts,
#: B-spline smoothing, vertex reduction: ``SimpleSetup.simplifySolution``) after the search
SIMPLIFY_SHARE = 0.1

#: our rows: label -> rrt-star options
OURS: dict[str, dict[str, Any]] = {
    "ours rrt-star (defaults: anytime)": {},
    "ours rrt-star informed": {"informed": True},
    "ours rrt-star informed tighten": {"informed": True, "tighten": True},
}


def field(seed: int = FIELD_SEED) -> Scenario:
    """The benchmark's field (see the module docstring)."""
    base = dense_cylinders(seed, N_CYLINDERS, bounds=((0.0, 0.0), (1000.0, 1000.0)))
    rng = np.random.default_rng(seed)
    tall = rng.random(len(base)) < 0.5
    tops = np.round(rng.uniform(60.0, 150.0, len(base)))
    cyl = tuple(
        Cylinder(c.center, c.radius, 0.0, math.inf if t else float(h))
        for c, t, h in zip(base, tall, tops, strict=True)
    )
    return Scenario(
        name="vs-ompl-field",
        bounds=Bounds((0.0, 0.0, 0.0), (1000.0, 1000.0, 200.0)),
        tasks=(Task("uav", START, GOAL),),
        cylinders=cyl,
        cost="length",
        description=f"vs_ompl.py field: {N_CYLINDERS} cylinders, seed {seed}",
    )


def segment_check(sc: Scenario) -> Callable[[float, float, float, float, float, float], bool]:
    """Our exact segment check of ``sc`` as a compiled function of the two ends (the field's
    arrays frozen in, so a call from Python costs about a microsecond)."""
    sk = MotionValidator(sc, strict_altitude=True).segment_kernel
    assert sk is not None, "the field must have a compiled segment check"
    kernel, kargs = sk
    assert kernel is static_world_ok.serial

    @njit
    def ok(x0: float, y0: float, z0: float, x1: float, y1: float, z1: float) -> bool:
        e = np.empty((1, 2, 3))
        e[0, 0, 0], e[0, 0, 1], e[0, 0, 2] = x0, y0, z0
        e[0, 1, 0], e[0, 1, 1], e[0, 1, 2] = x1, y1, z1
        return bool(kernel(e, kargs)[0])

    ok(0.0, 0.0, 0.0, 1.0, 1.0, 1.0)  # compile now
    return ok  # type: ignore[no-any-return]


def length(path: np.ndarray) -> float:
    return float(np.sum(np.linalg.norm(np.diff(path, axis=0), axis=1)))


def verified(sc: Scenario, path: np.ndarray | None) -> bool:
    """The independent verifier's verdict on the planned polyline (timed at cruise speed)."""
    if path is None:
        return False
    p = np.asarray(path, dtype=np.float64)
    t = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
    t = t / sc.uav.speed
    rep = verify_trajectories([Trajectory("uav", p, t)], sc, kinematics=False)
    return rep.ok and bool(np.allclose(p[0], START)) and bool(np.allclose(p[-1], GOAL))


@dataclass
class Run:
    length: float  # inf on failure
    ok: bool
    wall: float
    iterations: int


# ------------------------------------------------------------------------------ OMPL
def ompl_runner(sc: Scenario) -> Callable[[str, float, int], Run] | None:
    try:
        from ompl import base as ob
        from ompl import geometric as og
        from ompl import util as ou
    except ImportError:
        return None
    ou.setLogLevel(ou.LOG_ERROR)
    check = segment_check(sc)
    lo, hi = sc.bounds.lo, sc.bounds.hi

    class Motion(ob.MotionValidator):  # type: ignore[misc, name-defined]
        def checkMotion(self, s1: Any, s2: Any, *rest: Any) -> bool:
            return check(s1[0], s1[1], s1[2], s2[0], s2[1], s2[2])  # type: ignore[no-any-return]

    def state_ok(s: Any) -> bool:
        return check(s[0], s[1], s[2], s[0], s[1], s[2])  # type: ignore[no-any-return]

    keep: list[Any] = []  # nanobind: keep the Python objects OMPL holds alive

    ou.RNG.setSeed(OMPL_SEED)  # once: OMPL seeds its generators once per process

    def run(name: str, t: float, seed: int) -> Run:
        space = ob.RealVectorStateSpace(3)
        b = ob.RealVectorBounds(3)
        for i in range(3):
            b.setLow(i, float(lo[i]))
            b.setHigh(i, float(hi[i]))
        space.setBounds(b)
        ss = og.SimpleSetup(space)
        si = ss.getSpaceInformation()
        ss.setStateValidityChecker(state_ok)
        mv = Motion(si)
        si.setMotionValidator(mv)
        s, g = space.allocState(), space.allocState()
        for i in range(3):
            s[i], g[i] = START[i], GOAL[i]
        ss.setStartAndGoalStates(s, g)
        ss.getProblemDefinition().setOptimizationObjective(ob.PathLengthOptimizationObjective(si))
        base, _, simplify = name.partition("+")
        planner = (og.RRTstar if base == "RRTstar" else og.InformedRRTstar)(si)
        ss.setPlanner(planner)
        keep.extend([space, b, ss, si, mv, s, g, planner])
        t0 = time.perf_counter()
        if simplify:  # the last SIMPLIFY_SHARE of the time simplifies the path
            ss.solve(float(t) * (1.0 - SIMPLIFY_SHARE))
            if ss.haveExactSolutionPath():
                ss.simplifySolution(float(t) * SIMPLIFY_SHARE)
        else:
            ss.solve(float(t))
        wall = time.perf_counter() - t0
        path = None
        if ss.haveExactSolutionPath():
            p = ss.getSolutionPath()
            path = np.array(
                [[p.getState(k)[i] for i in range(3)] for k in range(p.getStateCount())]
            )
        ok = verified(sc, path)
        return Run(length(path) if ok and path is not None else math.inf, ok, wall,
                   int(planner.numIterations()))  # fmt: skip

    return run


# ------------------------------------------------------------------------------ ours
def ours_runner(sc: Scenario) -> Callable[[dict[str, Any], float, int], Run]:
    def run(options: dict[str, Any], t: float, seed: int) -> Run:
        planner = get_planner("rrt-star", **options)
        r = planner.plan(sc, budget=Budget(max_time=float(t)), seed=seed)
        path = np.asarray(r.waypoints) if r.feasible else None
        ok = verified(sc, path)
        return Run(length(path) if ok and path is not None else math.inf, ok, r.wall_time,
                   int(r.info.get("rrt_iterations", r.iterations)))  # fmt: skip

    return run


# ------------------------------------------------------------------------------ profile
class KernelClock:
    """Wall time spent inside the named functions (module attributes or methods, replaced by
    timing wrappers while active; nested calls counted once)."""

    def __init__(self, targets: list[tuple[Any, str]]) -> None:
        self.targets = targets
        self.seconds = 0.0
        self._depth = 0
        self._saved: list[tuple[Any, str, Any]] = []

    def _wrap(self, f: Callable[..., Any]) -> Callable[..., Any]:
        def timed(*a: Any, **k: Any) -> Any:
            self._depth += 1
            t0 = time.perf_counter()
            try:
                return f(*a, **k)
            finally:
                self._depth -= 1
                if self._depth == 0:
                    self.seconds += time.perf_counter() - t0

        return timed

    def __enter__(self) -> KernelClock:
        for owner, name in self.targets:
            f = owner.__dict__[name] if isinstance(owner, type) else getattr(owner, name)
            self._saved.append((owner, name, f))
            setattr(owner, name, self._wrap(f))
        return self

    def __exit__(self, *exc: object) -> None:
        for owner, name, f in reversed(self._saved):
            setattr(owner, name, f)
        self._saved.clear()


def kernel_targets() -> list[tuple[Any, str]]:
    """The compiled kernels and the validator's and cost's entry points an RRT* run calls:
    the Numba loop, the tightening kernels, the Python loop's batched segment checks and tree
    kernels, and the path evaluations."""
    from uavplan.planners.sampling import _rrt_star_kernels as K
    from uavplan.planners.sampling import _tighten_kernels as T
    from uavplan.planners.sampling import grid_index as G
    from uavplan.planners.sampling import rrt_star as R
    from uavplan.problems.path_problem import PathProblem

    return [(K, "grow"), (T, "band"), (T, "shortcut"), (MotionValidator, "paths_valid"),
            (PathProblem, "evaluate"), (R, "_insert_rewire"), (G, "_grid_nearest"),
            (G, "_grid_near")]  # fmt: skip


def profile_share(sc: Scenario, seconds: float, seeds: int) -> None:
    """Share of a planner run's wall time spent outside the kernels, before (the Python loop)
    and after (the Numba loop, informed and tightened)."""
    print(f"\nprofile: {seconds:g} s runs, {seeds} seeds, time outside the kernels "
          "(validity, cost, tree and tightening kernels) / the run's wall time")  # fmt: skip
    variants = (("before: loop=python, defaults", {"loop": "python"}),
                ("before: loop=python, informed", {"informed": True, "loop": "python"}),
                ("after: defaults", {}),
                ("after: informed tighten", {"informed": True, "tighten": True}))  # fmt: skip
    for label, opts in variants:
        planner = get_planner("rrt-star", **opts)
        planner.plan(sc, budget=Budget(max_time=0.2), seed=0)
        shares, its = [], []
        for s in range(seeds):
            with KernelClock(kernel_targets()) as clock:
                t0 = time.perf_counter()
                r = planner.plan(sc, budget=Budget(max_time=seconds), seed=s)
                wall = time.perf_counter() - t0
            shares.append(1.0 - clock.seconds / wall)
            its.append(r.info["rrt_iterations"] / wall)
        print(f"  {label:<32} outside kernels {statistics.median(shares):6.1%} "
              f"(seeds {min(shares):.1%}-{max(shares):.1%}), "
              f"{statistics.median(its):,.0f} RRT* iterations/s")  # fmt: skip


# ------------------------------------------------------------------------------ the table
def summary(runs: list[Run]) -> tuple[float, float, float, float]:
    """Median length of the successful runs (inf if none), min, max, success rate."""
    good = [r.length for r in runs if r.ok]
    if not good:
        return math.inf, math.inf, math.inf, 0.0
    return statistics.median(good), min(good), max(good), len(good) / len(runs)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--times", type=float, nargs="+", default=[0.5, 1.0, 2.0, 5.0])
    ap.add_argument("--reference", type=float, default=10.0, help="OMPL's reference time, s")
    ap.add_argument("--only-ours", action="store_true")
    ap.add_argument("--profile", type=float, default=2.0, metavar="SECONDS",
                    help="the profile's run length (0: no profile)")  # fmt: skip
    ap.add_argument("--profile-only", action="store_true", help="the profile alone")
    args = ap.parse_args()
    numba.set_num_threads(1)
    sc = field()
    straight = float(np.linalg.norm(np.subtract(GOAL, START)))
    area = sum(math.pi * c.radius**2 for c in sc.cylinders) / 1e6
    print(f"field: {len(sc.cylinders)} cylinders ({area:.1%} of the map), straight line "
          f"{straight:.0f} m; seeds {args.seeds}; wall times {args.times} s")  # fmt: skip
    if args.profile > 0:
        profile_share(sc, args.profile, min(args.seeds, 3))
    if args.profile_only:
        return
    ours = ours_runner(sc)
    # warm-up: compile our kernels (cached) before timing
    ours({"informed": True}, 0.3, 0)
    ompl = None if args.only_ours else ompl_runner(sc)
    if ompl is None and not args.only_ours:
        print("OMPL is not installed (pip install ompl): our rows only")
    # (label, times, run(t, seed)); every seed runs every planner at every time in turn, so
    # that the shared machine's load drifts over all of them alike
    planners: list[tuple[str, list[float], Callable[[float, int], Run]]] = []
    if ompl is not None:
        for name in ("RRTstar", "InformedRRTstar", "InformedRRTstar+simplify"):
            planners.append((f"OMPL {name}", [*args.times, args.reference],
                             functools.partial(ompl, name)))  # fmt: skip
    for label, opts in OURS.items():
        planners.append((label, list(args.times), functools.partial(ours, opts)))
    runs: dict[tuple[str, float], list[Run]] = {}
    for seed in range(args.seeds):
        for t in sorted({t for _, ts, _ in planners for t in ts}):
            for label, ts, fn in planners:
                if t in ts:
                    runs.setdefault((label, t), []).append(fn(t, seed))
        print(f"  seed {seed} done", flush=True)
    rows = [(label, t, runs[label, t]) for label, ts, _ in planners for t in ts]
    ref_runs = {lab: r for lab, t, r in rows if lab.startswith("OMPL") and t == args.reference}
    raw = min((summary(r)[0] for k, r in ref_runs.items() if "+" not in k), default=math.nan)
    ref = min((summary(r)[0] for r in ref_runs.values()), default=math.nan)
    print()
    print(f"reference: OMPL's best median length at {args.reference:g} s = {ref:.1f} m "
          f"({raw:.1f} m without its simplifier)")  # fmt: skip
    print(f"{'planner':<36} {'time s':>6} {'median m':>9} {'min':>7} {'max':>7} "
          f"{'success':>7} {'/ref':>6} {'/straight':>9} {'iterations':>10}")  # fmt: skip
    for label, t, runs in rows:
        med, mn, mx, rate = summary(runs)
        its = statistics.median(r.iterations for r in runs)
        print(f"{label:<36} {t:>6g} {med:>9.1f} {mn:>7.1f} {mx:>7.1f} {rate:>7.0%} "
              f"{med / ref:>6.3f} {med / straight:>9.3f} {its:>10.0f}")  # fmt: skip
    for label in OURS:
        at = next(r for lab, t, r in rows if lab == label and t == min(args.times))
        med, _, _, rate = summary(at)
        for what, r in (("OMPL's planners", raw), ("with its simplifier", ref)):
            met = med <= r and rate == 1.0
            print(f"target ({label} at {min(args.times):g} s <= {what} at {args.reference:g} s, "
                  f"100 % success): {'met' if met else 'NOT met'} ({med:.1f} m vs {r:.1f} m, "
                  f"{rate:.0%}; seeds at or below: "
                  f"{sum(x.ok and x.length <= r for x in at)}/{len(at)})")  # fmt: skip


if __name__ == "__main__":
    main()
