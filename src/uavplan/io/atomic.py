"""Atomic file writes: a temporary file in the same folder, then ``os.replace``."""

from __future__ import annotations

import json
import math
import os
import stat
import tempfile
from pathlib import Path
from typing import Any


def write_bytes_atomic(path: str | Path, data: bytes) -> Path:
    """Write ``data`` to ``path`` so that readers see the old file or the new one, never half.

    An existing file keeps its permission bits. Raises ``OSError`` (and removes the temporary
    file) if anything fails; the old file is then untouched.
    """
    p = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{p.name}.", suffix=".tmp", dir=p.parent)
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.chmod(tmp, stat.S_IMODE(p.stat().st_mode) if p.exists() else 0o644)
        os.replace(tmp, p)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    return p


def write_text_atomic(path: str | Path, text: str) -> Path:
    return write_bytes_atomic(path, text.encode("utf-8"))


def strict_json(obj: Any) -> Any:
    """``obj`` with every float that is not finite replaced by None: JSON (RFC 8259) has no
    infinity or NaN, and Python's ``json`` would write the non-standard ``Infinity``."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: strict_json(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [strict_json(v) for v in obj]
    return obj


def write_json_atomic(path: str | Path, obj: Any) -> Path:
    """Strict JSON (non-finite numbers as null, :func:`strict_json`), written atomically."""
    return write_text_atomic(path, json.dumps(strict_json(obj), indent=2, allow_nan=False) + "\n")


def write_texts_atomic(files: list[tuple[Path, str]], threads: int = 8) -> list[Path]:
    """Many files, each written atomically (:func:`write_text_atomic`), several at once: the
    waits on the disk (fsync) overlap. The paths in the order given; the first error raised."""
    from concurrent.futures import ThreadPoolExecutor

    if len(files) <= 1:
        return [write_text_atomic(p, t) for p, t in files]
    with ThreadPoolExecutor(max_workers=threads) as pool:
        return list(pool.map(lambda pt: write_text_atomic(*pt), files))
