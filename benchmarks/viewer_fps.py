"""The viewer's frame rate in headless Chromium on its software WebGL (SwiftShader): the page of
a plan with N UAVs, as frames per second while the fleet plays (the camera still: the standing
scene is drawn once and copied) and while the camera turns (everything drawn every frame); each
frame is finished (a pixel read back) before the next; and the seconds from opening the page to
its first frame. The reference, measured in the same run
and window: the same page with nothing in its scenes (what a frame costs the browser at all).
Also the page's size.

Plans: synthetic fleets on ``ppswarm1-traffic`` (each UAV a straight timed flight of ``--points``
points 150 m above the terrain), or ``--plan PATH`` (a plan.json, with its scenario).
Run: ``python benchmarks/viewer_fps.py [--uavs 40 1000] [--plan PATH] [--window 1280,800]``.
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from uavplan.io.plan_file import parse_plan, read_plan_file
from uavplan.scenarios import resolve
from uavplan.viz.viewer import viewer_html


def fleet_doc(n: int, points: int) -> dict[str, Any]:
    sc = resolve("ppswarm1-traffic")
    assert sc.terrain is not None
    rng = np.random.default_rng(1)
    uavs = []
    for k in range(n):
        a, b = rng.uniform([50, 50], [1000, 800], (2, 2))
        xy = a + np.linspace(0, 1, points)[:, None] * (b - a)
        P = np.column_stack([xy, sc.terrain.height(xy[:, 0], xy[:, 1]) + 150.0])
        t = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(P, axis=0), axis=1) / 20)])
        uavs.append({"id": f"uav{k}", "waypoints": P.tolist(), "times": t.tolist()})
    return {"scenario": "ppswarm1-traffic", "feasible": True, "uavs": uavs}


def measure(browser: str, page: Path, window: str, hash_: str, profile: Path) -> dict[str, Any]:
    dom = subprocess.run(
        [browser, "--headless=new", "--no-sandbox", "--use-angle=swiftshader",
         "--enable-unsafe-swiftshader", "--no-first-run", f"--user-data-dir={profile}",
         f"--window-size={window}", "--dump-dom", f"{page.as_uri()}#{hash_}"],
        capture_output=True, text=True, timeout=300, check=True,
    ).stdout  # fmt: skip
    out: dict[str, Any] = json.loads(
        dom.split('id="selftest"', 1)[1].split(">", 1)[1].split("</pre>", 1)[0]
    )
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--uavs", type=int, nargs="*", default=[40, 1000], help="synthetic fleets")
    ap.add_argument("--points", type=int, default=400)
    ap.add_argument("--plan", type=Path, action="append", default=[])
    ap.add_argument("--window", nargs="+", default=["1280,800", "900,650"])
    ap.add_argument("--repeat", type=int, default=3, help="runs per page (the median is shown)")
    a = ap.parse_args()
    browser = shutil.which("chromium") or shutil.which("chromium-browser")
    if browser is None:
        sys.exit("no chromium here (apt-get install chromium)")
    with tempfile.TemporaryDirectory() as tmp:
        pages = []
        for n in a.uavs:
            path = Path(tmp) / f"synthetic{n}.html"
            path.write_text(viewer_html(parse_plan(fleet_doc(n, a.points)),
                                        resolve("ppswarm1-traffic")))  # fmt: skip
            pages.append((f"synthetic, {n} UAVs x {a.points} points", path))
        for plan_path in a.plan:
            pf = read_plan_file(plan_path)
            path = Path(tmp) / f"plan{len(pages)}.html"
            path.write_text(viewer_html(pf, resolve(pf.scenario) if pf.scenario else None))
            pages.append((f"{plan_path} ({len(pf.uavs)} UAVs)", path))
        print(f"{'page':46s} {'window':>9s} {'MB':>5s} {'open s':>6s} {'fps play':>8s} "
              f"{'turning':>8s} {'empty':>7s} {'play/empty':>10s}")  # fmt: skip
        for label, path in pages:
            mb = path.stat().st_size / 2**20
            for window in a.window:
                runs = [measure(browser, path, window, "fps", Path(tmp) / "profile")
                        for _ in range(a.repeat)]  # fmt: skip
                empty = [measure(browser, path, window, "fps-empty", Path(tmp) / "profile")
                         for _ in range(a.repeat)]  # fmt: skip
                if any(r["errors"] for r in runs):
                    sys.exit(f"{label}: the page reported errors: {runs[0]['errors']}")
                play = float(np.median([r["fps"] for r in runs]))
                turn = float(np.median([r["fps_turning"] for r in runs]))
                ref = float(np.median([r["fps"] for r in empty]))
                ready = float(np.median([r["ready_ms"] for r in runs])) / 1000
                print(f"{label:46s} {window:>9s} {mb:5.2f} {ready:6.1f} {play:8.1f} {turn:8.1f} "
                      f"{ref:7.1f} {play / ref:10.2f}")  # fmt: skip
        print(f"renderer: {runs[0]['renderer']}; canvas {runs[0]['size']} (last window)")


if __name__ == "__main__":
    main()
