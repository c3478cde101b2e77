"""The viewer page: self-contained, bounded in size, every three.js class it uses in the vendored
bundle, and working in a real browser (headless Chromium on its software WebGL: a WebGL context,
the canvas not blank, the slider moves the UAVs, failing UAVs red, no console errors)."""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from matplotlib import image
from typer.testing import CliRunner

from uavplan.cli import app
from uavplan.io.plan_file import parse_plan
from uavplan.scenarios import resolve
from uavplan.viz.viewer import PATH_BUDGET, TERRAIN_SIDE, viewer_data, viewer_html

BROWSER = shutil.which("chromium") or shutil.which("chromium-browser")


def fleet_doc(n: int, points: int = 400, feasible: bool = True, scenario: str = "ppswarm1-traffic",
              failing: Any = (3,)) -> dict[str, Any]:  # fmt: skip
    """``n`` straight timed flights across ``scenario`` (the UAVs ``failing`` fail unless
    ``feasible``)."""
    sc = resolve(scenario)
    lo, hi = np.asarray(sc.bounds.lower), np.asarray(sc.bounds.upper)
    rng = np.random.default_rng(1)
    uavs = []
    for k in range(n):
        a, b = rng.uniform(lo[:2] + 0.05 * (hi[:2] - lo[:2]), hi[:2] - 0.05 * (hi[:2] - lo[:2]),
                           (2, 2))  # fmt: skip
        xy = a + np.linspace(0, 1, points)[:, None] * (b - a)
        if sc.dim == 3:
            ground = (sc.terrain.height(xy[:, 0], xy[:, 1]) if sc.terrain is not None
                      else np.full(points, lo[2]))  # fmt: skip
            P = np.column_stack([xy, ground + 0.3 * (hi[2] - lo[2])])
        else:
            P = xy
        t = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(P, axis=0), axis=1) / 20)])
        uavs.append({"id": f"uav{k}", "waypoints": P.tolist(), "times": t.tolist(),
                     "feasible": k not in failing or feasible})  # fmt: skip
    return {"scenario": scenario, "feasible": feasible, "uavs": uavs}


def page_data(html: str) -> dict[str, Any]:
    out: dict[str, Any] = json.loads(html.split("const DATA=", 1)[1].split(";</script>", 1)[0])
    return out


def test_the_page_is_self_contained_and_small() -> None:
    html = viewer_html(parse_plan(fleet_doc(40)), resolve("ppswarm1-traffic"))
    assert len(html.encode()) <= 5 * 2**20
    assert not re.search(r"<script[^>]+src|<link|<img|@import|fetch\(", html)
    assert "three.js r187 (MIT" in html  # the vendored build, with its licence named
    data = page_data(html)
    assert len(data["uavs"]) == 40 and len(data["moving"]) == 10
    T = data["terrain"]
    assert max(T["nx"], T["ny"]) <= TERRAIN_SIDE and len(T["h"]) == T["nx"] * T["ny"]
    assert len(data["cylinders"]) > 0
    H = np.asarray(resolve("ppswarm1").terrain.heights)  # type: ignore[union-attr]
    assert max(T["h"]) == pytest.approx(H.max(), abs=0.05)  # summits kept


def test_a_thousand_uav_page_stays_under_10_mb_and_keeps_every_flight_s_ends() -> None:
    doc = fleet_doc(1000, points=400)
    html = viewer_html(parse_plan(doc), resolve("ppswarm1-traffic"))
    assert len(html.encode()) <= 10 * 2**20
    data = page_data(html)
    shown = [len(u["t"]) for u in data["uavs"]]
    assert sum(shown) <= PATH_BUDGET and min(shown) >= 40
    for u, src in zip(data["uavs"][:50], doc["uavs"][:50], strict=True):
        f = np.reshape(u["f"], (-1, 3))
        assert np.allclose(f[0], src["waypoints"][0], atol=0.06)
        assert np.allclose(f[-1], src["waypoints"][-1], atol=0.06)
        assert u["t"][-1] == pytest.approx(src["times"][-1], abs=0.006)


def test_what_the_verifier_rejects_is_drawn_failing() -> None:
    data = viewer_data(parse_plan(fleet_doc(5)), None, rejected={"uav1"})
    assert data["feasible"] is False and data["rejected"] is True
    bad = [u for u in data["uavs"] if u["ok"] is False]
    assert [u["id"] for u in bad] == ["uav1"]
    assert "rejected by the independent verifier" in bad[0]["why"]


def test_the_bundle_has_every_three_class_the_viewer_uses() -> None:
    viz = resources.files("uavplan.viz")
    used = set(re.findall(r"THREE\.([A-Za-z0-9]+)", viz.joinpath("viewer.js").read_text()))
    entry = viz.joinpath("vendor", "three-entry.js").read_text()
    exported = set(re.findall(r"\b([A-Z][A-Za-z0-9]+)\b", entry.split("export {", 1)[1]))
    assert used <= exported, sorted(used - exported)
    bundle = viz.joinpath("vendor", "three.min.js").read_text()
    assert bundle.startswith("/* three.js r187") and "</script" not in bundle
    assert "MIT License" in viz.joinpath("vendor", "LICENSE.three.txt").read_text()


def test_view_command_and_a_scenario_name_in_the_page(tmp_path: Path) -> None:
    doc = fleet_doc(3)
    doc["scenario"] = "</script><b>x"
    path = tmp_path / "plan.json"
    path.write_text(json.dumps(doc))
    r = CliRunner().invoke(app, ["view", str(path), "ppswarm1-traffic"])
    assert r.exit_code == 0, r.output
    html = (tmp_path / "plan.html").read_text()
    assert html.count("</script>") == 3  # the name cannot close the data script
    r = CliRunner().invoke(app, ["view", str(tmp_path / "none.json")])
    assert r.exit_code == 2 and "Traceback" not in r.output


def _browser_or_skip() -> str:
    if BROWSER is None:
        if os.environ.get("UAVPLAN_REQUIRE_BROWSER"):
            pytest.fail("UAVPLAN_REQUIRE_BROWSER is set but no chromium is installed")
        pytest.skip("no chromium here (.ci/run installs it)")
    return BROWSER


def chromium(tmp_path: Path) -> list[str]:
    """Headless Chromium drawing WebGL on its software renderer (SwiftShader)."""
    return [_browser_or_skip(), "--headless=new", "--no-sandbox", "--use-angle=swiftshader",
            "--enable-unsafe-swiftshader", "--no-first-run",
            f"--user-data-dir={tmp_path / 'profile'}"]  # fmt: skip


#: The harness page: each viewer page in turn in an iframe of the browser's size, its own test's
#: result (``#selftest``) read from the iframe's DOM (the pages are files: the browser runs with
#: ``--allow-file-access-from-files``), all of them written into this page's ``#selftest``; a
#: page that never writes its result leaves ``null`` when the virtual time runs out.
HARNESS = """<!doctype html><html><body style="margin:0">
<pre id="selftest" style="display:none"></pre><script>
const pages = PAGES, out = pages.map(() => null);
let i = 0;
const show = () => { document.getElementById("selftest").textContent = JSON.stringify(out); };
function next() {
  show();
  if (i === pages.length) return;
  const f = document.createElement("iframe");
  f.width = 900; f.height = 650; f.style.border = "0";
  const poll = () => {
    const pre = f.contentDocument && f.contentDocument.getElementById("selftest");
    if (pre && pre.textContent) { out[i] = JSON.parse(pre.textContent); f.remove(); i++; next(); }
    else setTimeout(poll, 50);
  };
  f.onload = poll; f.src = pages[i]; document.body.appendChild(f);
}
next();
</script></body></html>"""


def selftests(flags: list[str], pages: list[Path], hash_: str = "selftest") -> list[dict[str, Any]]:
    """Each page's own test (viewer.js, ``#selftest``), the pages one after another in one
    browser (a browser's start is most of the time of one page's test)."""
    harness = pages[0].with_name("harness.html")
    harness.write_text(
        HARNESS.replace("PAGES", json.dumps([f"{p.as_uri()}#{hash_}" for p in pages]))
    )
    dom = subprocess.run(
        [*flags, "--allow-file-access-from-files", "--window-size=900,650",
         f"--virtual-time-budget={5000 * len(pages)}", "--dump-dom", harness.as_uri()],
        capture_output=True, text=True, timeout=120, check=True,
    ).stdout  # fmt: skip
    out: list[dict[str, Any]] = json.loads(
        dom.split('id="selftest"', 1)[1].split(">", 1)[1].split("</pre>", 1)[0]
    )
    assert len(out) == len(pages) and None not in out, out
    return out


def test_the_page_in_headless_chromium(tmp_path: Path) -> None:
    flags = chromium(tmp_path)
    failing, ok = tmp_path / "failing.html", tmp_path / "plan.html"
    doc = fleet_doc(40, feasible=False, failing=range(0, 40, 2))  # half of them fail
    failing.write_text(viewer_html(parse_plan(doc), resolve("ppswarm1-traffic")))
    ok.write_text(viewer_html(parse_plan(fleet_doc(40)), resolve("ppswarm1-traffic")))
    result, all_ok = selftests(flags, [failing, ok])
    assert result["webgl"] is True and result["errors"] == []
    assert result["uavs"] == 40 and result["moved"] == 40
    assert result["picked"] == "uav39"  # a click on its marker opens its card
    assert result["played"] is True  # play moves the clock and the slider
    assert result["painted"] > 0.2  # the terrain fills a good part of the view
    assert result["red"] > 100  # the failing UAVs' markers and paths are drawn in red
    assert all_ok["errors"] == [] and all_ok["red"] < result["red"] / 3
    shot = tmp_path / "shot.png"  # what the browser shows (composited) is the canvas drawn
    subprocess.run([*flags, "--window-size=900,650", f"--screenshot={shot}", ok.as_uri()],
                   capture_output=True, timeout=120, check=True)  # fmt: skip
    img = image.imread(shot)[..., :3]
    assert (img < 0.9).any(axis=2).mean() > 0.2


WORLDS = ["simple2d", "hrmaga-popup", "rscdwoa-mixed", "none"]


def test_every_kind_of_world_draws_without_errors(tmp_path: Path) -> None:
    """A 2-D world (polygons, circles), terrain with danger and uncertain areas, a world
    without terrain with moving obstacles, and a plan without its scenario (paths only)."""
    pages = []
    for scenario in WORLDS:
        page = tmp_path / f"{scenario}.html"
        doc = fleet_doc(4, points=50, scenario="ppswarm1" if scenario == "none" else scenario)
        world = None if scenario == "none" else resolve(scenario)
        page.write_text(viewer_html(parse_plan(doc), world))
        pages.append(page)
    for scenario, result in zip(WORLDS, selftests(chromium(tmp_path), pages), strict=True):
        assert result["webgl"] is True and result["errors"] == [], (scenario, result)
        assert result["moved"] == 4 and result["painted"] > 0.1, (scenario, result)


def test_the_page_beside_a_plan_shows_the_margins_the_verifier_measured(tmp_path: Path) -> None:
    out = tmp_path / "p"
    r = CliRunner().invoke(app, ["plan", "ppswarm1@4", "--iterations", "5", "--seed", "1",
                                 "--out", str(out)])  # fmt: skip
    assert r.exit_code == 0, r.output
    doc = json.loads((out / "plan.json").read_text())
    data = page_data((out / "plan.html").read_text())
    want = {m["uav"]: m for m in doc["margins"]["uavs"]}
    assert {u["id"]: u["m"] for u in data["uavs"]} == want and len(want) == 4
    assert data["feasible"] is True and data["execution"] == doc["execution"]
