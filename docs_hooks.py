"""A mkdocs hook: before the site is built, every example under ``examples/`` runs and its figure
is written to ``docs/gallery/`` (what the gallery page shows), so the gallery is the examples as
they run today. An example that fails fails the build."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent


def on_pre_build(config: Any) -> None:
    out = ROOT / "docs" / "gallery"
    out.mkdir(exist_ok=True)
    for script in sorted((ROOT / "examples").glob("*.py")):
        png = out / f"{script.stem}.png"
        subprocess.run([sys.executable, str(script), str(png)], check=True, cwd=ROOT,
                       capture_output=True)  # fmt: skip
