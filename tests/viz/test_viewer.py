"""The viewer page (issue 16): self-contained, small, and working in a real browser (headless
Chromium: not blank, the slider moves the UAVs, no console errors)."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from matplotlib import image
from typer.testing import CliRunner

from uavplan.cli import app
from uavplan.io.plan_file import parse_plan
from uavplan.scenarios import resolve
from uavplan.viz.viewer import viewer_html

BROWSER = shutil.which("chromium") or shutil.which("chromium-browser")


def fleet_doc(n: int, points: int = 400, feasible: bool = True) -> dict:  # type: ignore[type-arg]
    sc = resolve("ppswarm1-traffic")
    assert sc.terrain is not None
    rng = np.random.default_rng(1)
    uavs = []
    for k in range(n):
        a, b = rng.uniform([50, 50], [1000, 800], (2, 2))
        xy = a + np.linspace(0, 1, points)[:, None] * (b - a)
        P = np.column_stack([xy, sc.terrain.height(xy[:, 0], xy[:, 1]) + 150.0])
        t = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(P, axis=0), axis=1) / 20)])
        uavs.append({"id": f"uav{k}", "waypoints": P.tolist(), "times": t.tolist(),
                     "feasible": k != 3 or feasible})  # fmt: skip
    return {"scenario": "ppswarm1-traffic", "feasible": feasible, "uavs": uavs}


def test_the_page_is_self_contained_and_small() -> None:
    html = viewer_html(parse_plan(fleet_doc(40)), resolve("ppswarm1-traffic"))
    assert len(html.encode()) <= 5 * 2**20  # issue 16: 40 UAVs in <= 5 MB
    assert "<script src" not in html and "http://" not in html and "https://" not in html
    data = json.loads(html.split("const DATA=", 1)[1].split(";</script>", 1)[0])
    assert len(data["uavs"]) == 40 and len(data["moving"]) == 10
    assert len(data["terrain"]["h"]) <= 64 and len(data["cylinders"]) > 0
    H = np.asarray(resolve("ppswarm1").terrain.heights)  # type: ignore[union-attr]
    assert np.max(data["terrain"]["h"]) == pytest.approx(H.max(), abs=0.05)  # summits kept


def test_view_command_and_a_scenario_name_in_the_page(tmp_path: Path) -> None:
    doc = fleet_doc(3)
    doc["scenario"] = "</script><b>x"
    path = tmp_path / "plan.json"
    path.write_text(json.dumps(doc))
    r = CliRunner().invoke(app, ["view", str(path), "ppswarm1-traffic"])
    assert r.exit_code == 0, r.output
    html = (tmp_path / "plan.html").read_text()
    assert html.count("</script>") == 2  # the name cannot close the data script
    r = CliRunner().invoke(app, ["view", str(tmp_path / "none.json")])
    assert r.exit_code == 2 and "Traceback" not in r.output


def _browser_or_skip() -> str:
    if BROWSER is None:
        if os.environ.get("UAVPLAN_REQUIRE_BROWSER"):
            pytest.fail("UAVPLAN_REQUIRE_BROWSER is set but no chromium is installed")
        pytest.skip("no chromium here (.ci/run installs it)")
    return BROWSER


def test_the_page_in_headless_chromium(tmp_path: Path) -> None:
    browser = _browser_or_skip()
    page = tmp_path / "plan.html"
    page.write_text(viewer_html(parse_plan(fleet_doc(40, feasible=False)),
                                resolve("ppswarm1-traffic")))  # fmt: skip
    flags = [browser, "--headless=new", "--no-sandbox", "--disable-gpu", "--no-first-run",
             f"--user-data-dir={tmp_path / 'profile'}"]  # fmt: skip
    dom = subprocess.run(
        [*flags, "--virtual-time-budget=5000", "--dump-dom", f"{page.as_uri()}#selftest"],
        capture_output=True, text=True, timeout=120, check=True,
    ).stdout  # fmt: skip
    result = json.loads(dom.split('id="selftest"', 1)[1].split(">", 1)[1].split("</pre>", 1)[0])
    assert result == {"uavs": 40, "moved": 40, "errors": []}
    shot = tmp_path / "shot.png"
    subprocess.run([*flags, "--window-size=900,650", f"--screenshot={shot}", page.as_uri()],
                   capture_output=True, timeout=120, check=True)  # fmt: skip
    img = image.imread(shot)[..., :3]
    not_white = (img < 0.95).any(axis=2).mean()
    assert not_white > 0.2  # the terrain fills a good part of the view
    red = ((img[..., 0] > 0.8) & (img[..., 1] < 0.2) & (img[..., 2] < 0.2)).sum()
    assert red > 50  # the failing UAV (uav3) is drawn in red
