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


def test_first_run_is_told_that_kernels_compile(tmp_path, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    import uavplan
    from uavplan.cli import _common

    pkg = tmp_path / "uavplan"
    pkg.mkdir()
    monkeypatch.setattr(uavplan, "__file__", str(pkg / "__init__.py"))
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    printed: list[str] = []
    monkeypatch.setattr(_common.err, "print", lambda text, **kw: printed.append(text))
    _common.compile_notice()
    assert printed and "compiling kernels once" in printed[0]
    for rel in _common._KERNEL_MODULES:
        folder = (pkg / rel).parent / "__pycache__"
        folder.mkdir(parents=True, exist_ok=True)
        (folder / f"{Path(rel).stem}.kernel-1.py311.nbi").write_bytes(b"")
    printed.clear()
    _common.compile_notice()
    assert printed == []
