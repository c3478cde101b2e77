"""The verifier as a gate (issue 19 item 6): how a run's claims become ``verifier_ok``
(``uavplan.bench.kinds.gate``); ``tests/bench/test_plans.py`` asserts it on every smoke run of
every plan, ``tests/io/test_plan_file.py`` that ``uavplan plan`` runs the verifier before it
exits 0."""

from __future__ import annotations

import numpy as np

from uavplan.bench.kinds import gate
from uavplan.verify import Trajectory, verify_trajectories
from uavplan.world import AltitudeBand, Bounds, Cylinder, Scenario, Task, Terrain


def _world() -> Scenario:
    """Flat ground with an 8 m ridge across x = 50, a band 5-50 m above ground, a cylinder."""
    x = np.arange(0.0, 101.0, 10.0)
    h = np.where(np.isclose(x, 50.0), 8.0, 0.0)
    terrain = Terrain(np.tile(h, (11, 1)), 0.0, 0.0, 10.0, 10.0, "ridge")
    return Scenario(
        "ridge",
        Bounds((0.0, 0.0, 0.0), (100.0, 100.0, 100.0)),
        (Task("uav0", (5.0, 20.0, 10.0), (95.0, 20.0, 10.0)),),
        terrain=terrain,
        cylinders=(Cylinder((50.0, 80.0), 5.0),),
        altitude=AltitudeBand(5.0, 50.0, "ground"),
    )


def _claim(points: list[tuple[float, float, float]], paper_band: bool) -> tuple[str, object, bool]:
    p = np.array(points)
    t = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1) / 10.0)])
    rep = verify_trajectories([Trajectory("uav0", p, t, True)], _world(), kinematics=False)
    return ("planned", rep, paper_band)


def test_nothing_claimed_no_verdict() -> None:
    assert gate([]) == {"verifier_ok": None, "verifier_rejects": "", "band_paper_criterion": 0}


def test_the_band_is_counted_not_rejected_for_a_polyline_under_the_papers_criterion() -> None:
    over_ridge = [(5.0, 20.0, 10.0), (95.0, 20.0, 10.0)]  # 2 m above the ridge's top
    g = gate([_claim(over_ridge, paper_band=True)])
    assert g["verifier_ok"] is True and g["band_paper_criterion"] == 1
    strict = gate([_claim(over_ridge, paper_band=False)])  # e.g. a trajectory that is flown
    assert strict["verifier_ok"] is False and "below the band" in strict["verifier_rejects"]
    assert strict["band_paper_criterion"] == 0


def test_every_other_violation_is_rejected_under_any_criterion() -> None:
    through_cylinder = [(5.0, 80.0, 20.0), (95.0, 80.0, 20.0)]
    g = gate([_claim(through_cylinder, paper_band=True)])
    assert g["verifier_ok"] is False and "cylinder" in g["verifier_rejects"]
    under_ground = [(5.0, 20.0, 10.0), (50.0, 20.0, 5.0), (95.0, 20.0, 10.0)]  # ridge at 8 m
    g = gate([_claim(under_ground, paper_band=True)])
    assert g["verifier_ok"] is False and "terrain" in g["verifier_rejects"]


def test_one_rejected_claim_rejects_the_run() -> None:
    ok = _claim([(5.0, 20.0, 20.0), (95.0, 20.0, 20.0)], paper_band=False)
    bad = _claim([(5.0, 80.0, 20.0), (95.0, 80.0, 20.0)], paper_band=False)
    assert gate([ok])["verifier_ok"] is True
    assert gate([ok, bad])["verifier_ok"] is False
