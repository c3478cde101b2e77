"""The files an open-source project carries agree with each other: the licence in LICENSE is
the one pyproject.toml declares, CITATION.cff names the project's version and licence and the
four papers it implements, the changelog has the version."""

from __future__ import annotations

import tomllib
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]


def test_licence_citation_and_changelog_agree_with_pyproject() -> None:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert project["license"] == "BSD-3-Clause"
    assert (ROOT / "LICENSE").read_text().startswith("BSD 3-Clause License")
    cff = yaml.safe_load((ROOT / "CITATION.cff").read_text())
    assert cff["cff-version"] == "1.2.0" and cff["license"] == project["license"]
    assert cff["version"] == project["version"]
    titles = " | ".join(r["title"] for r in cff["references"])
    for name in ("RGG-PSO+", "hybrid optimization algorithm for multi-agent",
                 "Hierarchical Recursive Multiagent Genetic Algorithm", "PPSwarm"):  # fmt: skip
        assert name in titles
    assert f"({project['version']})" in (ROOT / "CHANGELOG.md").read_text()
