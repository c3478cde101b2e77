"""A mkdocs hook: while the site is built, every example under ``examples/`` runs and its figure
is written to ``docs/gallery/`` (what the gallery page shows), so the gallery is the examples as
they run today. An example that fails fails the build.

The examples start before the pages are read (``on_pre_build``) and run beside mkdocs' own
work: the figures are declared to mkdocs when it gathers the files (``on_files``, so the
gallery page's image links resolve in strict mode) and waited for when every page has been
read, just before mkdocs copies the files to the site (``on_env``)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent
OUT = ROOT / "docs" / "gallery"

_running: list[tuple[Path, subprocess.Popen[bytes]]] = []


def _examples() -> list[Path]:
    return sorted((ROOT / "examples").glob("*.py"))


def on_pre_build(config: Any) -> None:
    OUT.mkdir(exist_ok=True)
    _running.clear()
    # the examples run side by side (each is one process planning on one core at a time)
    for script in _examples():
        png = OUT / f"{script.stem}.png"
        png.unlink(missing_ok=True)  # never a stale figure in the site
        proc = subprocess.Popen([sys.executable, str(script), str(png)], cwd=ROOT,
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE)  # fmt: skip
        _running.append((script, proc))


def on_files(files: Any, config: Any) -> Any:
    from mkdocs.structure.files import File

    for script, _ in _running:
        uri = f"gallery/{script.stem}.png"
        if files.get_file_from_path(uri) is None:
            files.append(File.generated(config, uri, abs_src_path=str(OUT / f"{script.stem}.png")))
    return files


def on_env(env: Any, config: Any, files: Any) -> Any:
    failed = []
    for script, proc in _running:
        _, err = proc.communicate()
        if proc.returncode:
            failed.append(f"{script.name} exited {proc.returncode}: {err.decode()[-2000:]}")
    _running.clear()
    if failed:
        raise RuntimeError("gallery examples failed:\n" + "\n".join(failed))
    return env
