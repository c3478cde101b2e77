"""The benchmarks' own glue code against the library: a benchmark that compares us with a peer
must still run after the kernels change (``vs_ompl.py`` broke silently when ``static_world_ok``
took its arguments as one tuple)."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType

import numpy as np

from uavplan.problems.validity import MotionValidator

ROOT = Path(__file__).resolve().parent.parent


def _load(name: str) -> ModuleType:
    spec = importlib.util.spec_from_file_location(
        f"_bench_{name}", ROOT / "benchmarks" / f"{name}.py"
    )
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


def test_vs_ompl_segment_check_agrees_with_the_motion_validator() -> None:
    vs = _load("vs_ompl")
    sc = vs.field()
    ok = vs.segment_check(sc)
    mv = MotionValidator(sc, strict_altitude=True)
    rng = np.random.default_rng(0)
    lo = np.array([0.0, 0.0, 0.0])
    hi = np.array([1000.0, 1000.0, 200.0])
    ends = lo + rng.random((200, 2, 3)) * (hi - lo)
    expected = mv.paths_valid(ends)
    got = np.array([ok(*e[0], *e[1]) for e in ends])
    assert expected.any() and not expected.all()  # both verdicts occur
    assert np.array_equal(got, expected)
