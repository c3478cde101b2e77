"""Runs record the source commit also when uavplan was installed by pip (issue 17 item 5)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from uavplan.bench import execute


class _Dist:
    def __init__(self, record: dict[str, Any] | None) -> None:
        self.record = record

    def read_text(self, name: str) -> str | None:
        assert name == "direct_url.json"
        return None if self.record is None else json.dumps(self.record)


@pytest.mark.parametrize(
    "record, want",
    [({"url": "https://github.com/x/uavplan", "vcs_info": {"vcs": "git", "commit_id": "abc123"}},
      "abc123"),
     ({"url": "file:///nowhere/uavplan", "dir_info": {}}, None),
     (None, None)],
)  # fmt: skip
def test_commit_from_the_install_record(monkeypatch: pytest.MonkeyPatch, record: Any,
                                        want: str | None) -> None:  # fmt: skip
    import importlib.metadata

    monkeypatch.setattr(execute, "_rev_parse", lambda folder: None)  # not run from a checkout
    monkeypatch.setattr(importlib.metadata, "distribution", lambda name: _Dist(record))
    execute.git_commit.cache_clear()
    try:
        assert execute.git_commit() == want
    finally:
        execute.git_commit.cache_clear()


def test_commit_of_the_checkout_it_was_installed_from(monkeypatch: pytest.MonkeyPatch,
                                                      tmp_path: Path) -> None:  # fmt: skip
    import importlib.metadata

    calls: list[Path] = []

    def rev_parse(folder: Path) -> str | None:
        calls.append(folder)
        return "def456" if folder == tmp_path else None

    monkeypatch.setattr(execute, "_rev_parse", rev_parse)
    rec = {"url": tmp_path.as_uri(), "dir_info": {}}
    monkeypatch.setattr(importlib.metadata, "distribution", lambda name: _Dist(rec))
    execute.git_commit.cache_clear()
    try:
        assert execute.git_commit() == "def456" and calls[-1] == tmp_path
    finally:
        execute.git_commit.cache_clear()
