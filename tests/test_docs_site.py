"""The documentation site builds in mkdocs' strict mode (every page, link and anchor resolved,
the API reference from the docstrings), and its gallery is drawn by running every example under
``examples/`` (a failing example fails the build). Needs the extra ``uavplan[docs]``, which
``.ci/run`` installs."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def test_the_site_builds_strictly_with_the_gallery_drawn(tmp_path: Path) -> None:
    pytest.importorskip("mkdocs")
    pytest.importorskip("mkdocstrings")
    gallery = ROOT / "docs" / "gallery"
    for png in gallery.glob("*.png"):
        png.unlink()  # drawn afresh by the build
    site = tmp_path / "site"
    r = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-d", str(site)],
                       cwd=ROOT, capture_output=True, text=True)  # fmt: skip
    assert r.returncode == 0, r.stderr[-3000:]
    examples = sorted(p.stem for p in (ROOT / "examples").glob("*.py"))
    assert examples and all((site / "gallery" / f"{e}.png").stat().st_size > 10_000
                            for e in examples)  # fmt: skip
    page = (site / "gallery" / "index.html").read_text()
    assert all(f"gallery/{e}.png" in page or f"{e}.png" in page for e in examples)
    api = (site / "api" / "strategy" / "index.html").read_text()
    assert "strategy_for" in api and "execute" in api
