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
    # the examples run side by side (each is one process planning on one core at a time)
    running = [
        (script, subprocess.Popen([sys.executable, str(script), str(out / f"{script.stem}.png")],
                                  cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE))
        for script in sorted((ROOT / "examples").glob("*.py"))
    ]  # fmt: skip
    failed = []
    for script, proc in running:
        _, err = proc.communicate()
        if proc.returncode:
            failed.append(f"{script.name} exited {proc.returncode}: {err.decode()[-2000:]}")
    if failed:
        raise RuntimeError("gallery examples failed:\n" + "\n".join(failed))
