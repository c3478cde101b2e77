"""The claims ledger: the registry's contract, judging from stored runs, the command, and the
committed ledger rebuilt from ``results/``."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from uavplan.bench.claims import CLAIMS, VERDICTS, build_ledger
from uavplan.bench.claims.base import NOT_RUN, Finding, render_markdown
from uavplan.cli import app

ROOT = Path(__file__).resolve().parents[2]
PAPERS = {"RSCDWOA (Zhang et al.)", "HR-MAGA (Yang, Liu & Li)", "PPSwarm (Meng, Chen & Qu)",
          "RGG-PSO+ (Liu et al.)"}  # fmt: skip


def test_every_claim_names_its_paper_figure_and_the_runs_it_reads() -> None:
    from uavplan.bench.catalog import available_plans

    plans = available_plans()
    assert len(CLAIMS) >= 25
    assert {c.paper for c in CLAIMS.values()} == PAPERS
    for c in CLAIMS.values():
        assert c.statement and c.paper_figure and c.where, c.id
        # every plan a claim reads is a registered experiment (or a protocol variant of one)
        for plan in c.needs:
            assert plan in plans, (c.id, plan)


def test_without_stored_runs_every_claim_is_not_run_and_says_how(tmp_path: Path) -> None:
    ledger = build_ledger(tmp_path)
    assert len(ledger) == len(CLAIMS)
    for c, f in ledger:
        assert f.verdict == NOT_RUN
        assert all(f"uavplan bench run {p}" in f.reason for p in c.needs)
    text = render_markdown(ledger, tmp_path)
    assert f"not run {len(CLAIMS)}" in text and text.count("\n| **") == len(CLAIMS)


def test_a_finding_takes_only_the_verdicts() -> None:
    with pytest.raises(ValueError, match="verdict 'maybe'"):
        Finding("a", "b", "c", "maybe", "d")


@pytest.fixture(scope="module")
def smoke_results(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("results")
    for plan in ("functions", "functions-iterations"):
        r = CliRunner().invoke(app, ["bench", "run", plan, "--out", str(root / plan),
                                     "--executor", "serial", "--no-report"])  # fmt: skip
        assert r.exit_code == 0, r.output
    return root


def test_claims_are_judged_from_the_stored_runs(smoke_results: Path) -> None:
    ledger = dict((c.id, f) for c, f in build_ledger(smoke_results))
    f = ledger["rscdwoa-beats-woa-f1-f9"]
    assert f.verdict in VERDICTS and f.verdict != NOT_RUN
    assert f.paper_protocol.startswith("+/~/- ") and f.our_protocol.startswith("+/~/- ")
    # the nine functions' signs, whatever they are
    assert sum(f.paper_protocol.count(f"f{i}") for i in range(1, 10)) == 9
    assert ledger["ppswarm-beats-spso"].verdict == NOT_RUN  # its runs are not stored here


def test_the_verdict_follows_the_data(tmp_path: Path) -> None:
    """Fabricated runs where RSCDWOA is lower than WOA on every function under both protocols
    reproduce the claim; the same runs with the roles swapped do not."""
    from uavplan.bench.claims.rscdwoa import _wtl

    rows = []
    for f in range(1, 10):
        for i in range(30):
            rows.append({"scenario": f"f{f}", "algorithm": "rscdwoa", "best_cost": 1.0 + i})
            rows.append({"scenario": f"f{f}", "algorithm": "woa", "best_cost": 100.0 + i})
    df = pd.DataFrame(rows)
    assert _wtl(df, "rscdwoa", "woa")[:3] == (9, 0, 0)
    assert _wtl(df, "woa", "rscdwoa")[:3] == (0, 0, 9)
    df.loc[df.scenario == "f3", "best_cost"] = np.tile([5.0, 5.0], 30)
    assert _wtl(df, "rscdwoa", "woa")[:3] == (8, 1, 0)


def test_the_report_command_writes_the_ledger(smoke_results: Path, tmp_path: Path) -> None:
    out = tmp_path / "claims.md"
    r = CliRunner().invoke(app, ["report", str(smoke_results), "--claims", "--out", str(out)])
    assert r.exit_code == 0, r.output
    assert out.read_text().startswith("# Claims ledger") and "rscdwoa-beats-woa-f1-f9" in r.output
    bad = CliRunner().invoke(app, ["report", str(tmp_path / "none"), "--claims"])
    assert bad.exit_code == 2 and "no such folder" in bad.output


def test_the_committed_ledger_is_rebuilt_from_the_results() -> None:
    """docs/claims.md is what `uavplan report results --claims` writes from results/."""
    expected = render_markdown(build_ledger(ROOT / "results"), "results")
    assert (ROOT / "docs" / "claims.md").read_text() == expected


def test_the_results_pages_claim_summaries_say_what_the_ledger_says() -> None:
    """Each paper's section of docs/results.md opens with its claims by verdict (between
    ``<!-- claims -->`` markers): every claim of docs/claims.md once, under its verdict."""
    import re

    ledger = (ROOT / "docs" / "claims.md").read_text()
    verdicts = dict(re.findall(r"^\| \*\*([\w-]+)\*\*:.*?\| \*\*([^*|]+)\*\* \|", ledger, re.M))
    assert len(verdicts) == len(CLAIMS)
    page = (ROOT / "docs" / "results.md").read_text()
    said: dict[str, str] = {}
    for block in re.findall(r"<!-- claims -->\n(.*?)\n<!-- /claims -->", page, re.S):
        for part in block.split("`): ", 1)[-1].split("; "):
            verdict, names = part.split(": ", 1)
            for name in re.findall(r"`([\w-]+)`", names):
                assert name not in said, f"{name} summarized twice"
                said[name] = verdict.strip()
    assert said == verdicts
