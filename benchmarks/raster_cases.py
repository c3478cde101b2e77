"""The raster cases through the public API (NoData of five kinds, pixel-is-point, compression,
and the altitude band held against the raster's own ground along ten planned flights), on
whichever uavplan is imported: run it again with ``PYTHONPATH=OTHER_TREE/src`` to compare a
revision (``git worktree add OTHER_TREE REV``).

    python benchmarks/raster_cases.py [--seeds 10]
"""

from __future__ import annotations

import argparse
import itertools
import json
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import yaml

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "world"))
from rasters import hill_samples, peak_block, source_ground, write

NODATA = [("float32", -9999.0), ("int16", -32768.0), ("uint16", 65535.0),
          ("float32", float("nan")), ("float32", float(np.finfo(np.float32).min))]  # fmt: skip
PROFILES: list[dict[str, Any]] = [
    {"compress": "lzw"}, {"compress": "deflate"},
    {"tiled": True, "blockxsize": 32, "blockysize": 32},
]  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=10)
    args = ap.parse_args()
    import uavplan
    from uavplan.io.scenario_file import load_scenario

    print("uavplan from", uavplan.__file__)
    tmp = Path(tempfile.mkdtemp())
    H, tr = hill_samples()

    def scenario(name: str, raster: str) -> Path:
        data = {"name": name, "terrain": {"file": raster}, "task_z": "ground",
                "altitude": {"min": 60, "max": 300},
                "tasks": [{"start": [-3500, -3000, 150], "goal": [3000, 3500, 150]}]}  # fmt: skip
        path = tmp / f"{name}.yaml"
        path.write_text(yaml.safe_dump(data))
        return path

    def case(title: str, fn: Callable[[], str]) -> None:
        try:
            print(f"{title}: {fn()}")
        except Exception as exc:
            print(f"{title}: ERROR {type(exc).__name__}: {str(exc).splitlines()[0][:150]}")

    for dtype, nodata in NODATA:

        def heights(dtype: str = dtype, nodata: float = nodata) -> str:
            write(tmp / "v.tif", H, tr, dtype=dtype, nodata=nodata, void=peak_block(H))
            t = load_scenario(scenario("v", "v.tif")).terrain
            assert t is not None
            lo, hi = float(np.min(t.heights)), float(np.max(t.heights))
            return f"terrain heights {lo:.6g}..{hi:.6g} (valid samples 300..{H.max():.0f})"

        case(f"NoData {dtype} {nodata:g}", heights)

    def point() -> str:
        write(tmp / "a.tif", H, tr)
        write(tmp / "p.tif", H, tr, point=True)
        a, p = load_scenario(scenario("a", "a.tif")), load_scenario(scenario("p", "p.tif"))
        assert a.terrain is not None and p.terrain is not None
        assert a.origin is not None and p.origin is not None
        d = np.asarray(a.terrain.heights) - np.asarray(p.terrain.heights)
        return (f"area vs point terrains differ by {d.min():.1f}..{d.max():.1f} m; origins "
                f"{a.origin.lat:.6f}, {a.origin.lon:.6f} vs {p.origin.lat:.6f}, "
                f"{p.origin.lon:.6f}")  # fmt: skip

    case("pixel-is-point", point)
    for profile in PROFILES:

        def packed(profile: dict[str, Any] = profile) -> str:
            write(tmp / "c.tif", H, tr, **profile)
            t = load_scenario(scenario("c", "c.tif")).terrain
            assert t is not None
            return f"loads, {t.shape}"

        case(f"compressed {profile}", packed)

    def band() -> str:
        from typer.testing import CliRunner

        from uavplan.cli import app

        write(tmp / "h.tif", H, tr)
        path = scenario("h", "h.tif")
        origin = load_scenario(path).origin
        rows = []
        for seed in range(args.seeds):
            out = tmp / f"run{seed}"
            r = CliRunner().invoke(app, ["plan", str(path), "--out", str(out), "--seed", str(seed)])
            plan = json.loads((out / "plan.json").read_text())
            P = np.asarray(plan["uavs"][0]["flown"]["points"], dtype=np.float64)
            s = np.linspace(0, 1, 400)[:, None]
            pts = np.concatenate([a + s * (b - a) for a, b in itertools.pairwise(P)])
            h = pts[:, 2] - source_ground(tmp / "h.tif", origin, pts[:, 0], pts[:, 1])
            rows.append((r.exit_code, round(float(np.nanmin(h)), 1), round(float(np.nanmax(h)), 1)))
        return f"(exit, least, most) height above the raster's ground, band [60, 300]: {rows}"

    case("band against the raster", band)


if __name__ == "__main__":
    main()
