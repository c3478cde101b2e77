"""Compiled kernels are cached where the install can write (issue 17 item 2)."""

from __future__ import annotations

from pathlib import Path

from uavplan import numba_cache_dir


def test_writable_package_keeps_numbas_default(tmp_path: Path) -> None:
    assert numba_cache_dir(tmp_path, {}) is None
    assert numba_cache_dir(tmp_path, {"NUMBA_CACHE_DIR": "/x"}, writable=False) is None


def test_read_only_package_caches_in_the_user_folder(tmp_path: Path) -> None:
    got = numba_cache_dir(tmp_path, {"XDG_CACHE_HOME": "/c"}, writable=False)
    assert got == "/c/uavplan/numba"
    assert numba_cache_dir(tmp_path, {}, writable=False) == str(
        Path.home() / ".cache" / "uavplan" / "numba"
    )
