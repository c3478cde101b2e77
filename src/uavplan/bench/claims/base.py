"""The claims ledger's frame: a paper's headline claim (:class:`Claim`), what the stored
results say about it (:class:`Finding`), the verdicts, and the registry the ledger is built
from (:func:`register_claim`, :func:`build_ledger`).

A claim is judged from the stored runs of ``results/`` alone (one folder per experiment
plan, as ``uavplan bench run`` writes them): nothing is run while the ledger is built, so
the ledger changes only when the results do. Each finding states the figure under the
paper's own protocol and under ours (equal evaluations) where the two differ, the test that
decides, and a verdict with its reason in a sentence. A claim whose runs are not stored is
reported as such ("not run"), never guessed.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from uavplan.bench.simulation import wilson  # noqa: F401  (for the papers' claims)

#: The verdicts.
REPRODUCED = "reproduced"
NOT_REPRODUCED = "not reproduced"
PAPER_ONLY = "reproduced only under the paper's protocol"
OURS_ONLY = "reproduced only under uavplan's protocol"
NOT_TESTABLE = "not testable as written"
NOT_RUN = "not run"
VERDICTS = (REPRODUCED, NOT_REPRODUCED, PAPER_ONLY, OURS_ONLY, NOT_TESTABLE, NOT_RUN)


def combine(paper_ok: bool, ours_ok: bool | None) -> str:
    """The verdict from whether the claim holds under the paper's protocol and under ours
    (None: ours not run, or the same as the paper's)."""
    if paper_ok and ours_ok is not False:
        return REPRODUCED
    if paper_ok:
        return PAPER_ONLY
    return OURS_ONLY if ours_ok else NOT_REPRODUCED


@dataclass(frozen=True)
class Finding:
    """What the stored results say about a claim.

    Attributes:
        paper_protocol: our figure under the paper's own protocol (or why there is none).
        our_protocol: our figure under uavplan's protocol (equal evaluations), or "as the
            paper's" where the two protocols are the same.
        test: the test that decides, with its statistic and p-value or interval.
        verdict: one of :data:`VERDICTS`.
        reason: the verdict's reason, one sentence.
        runs: the stored runs the finding reads (counts per protocol).
    """

    paper_protocol: str
    our_protocol: str
    test: str
    verdict: str
    reason: str
    runs: str = ""

    def __post_init__(self) -> None:
        if self.verdict not in VERDICTS:
            raise ValueError(f"verdict {self.verdict!r}: one of {', '.join(VERDICTS)}")


@dataclass(frozen=True)
class Claim:
    """One headline claim of a paper.

    Attributes:
        id: a short unique name.
        paper: the paper (as the ledger's sections name it).
        where: the table, figure or section of the paper.
        statement: the claim in a sentence.
        paper_figure: the paper's own figure for it.
        needs: the result folders (plan names) the finding reads.
        judge: the finding from those folders' runs (:class:`Results`).
    """

    id: str
    paper: str
    where: str
    statement: str
    paper_figure: str
    needs: tuple[str, ...]
    judge: Callable[[Results], Finding]


class Results:
    """The stored runs under a results root, read once per plan (``status == "ok"`` rows
    only)."""

    def __init__(self, root: str | Path) -> None:
        self.root = Path(root)
        self._cache: dict[str, pd.DataFrame | None] = {}
        self._derived: dict[tuple[str, str], Any] = {}

    def has(self, plan: str) -> bool:
        return (self.root / plan / "runs").is_dir()

    def frame(self, plan: str, lists: tuple[str, ...] | bool = ()) -> pd.DataFrame:
        """The ok runs of ``plan`` (KeyError when the plan has no stored runs), without the
        per-run list columns (histories, waypoints) but ``lists`` (True: all): they hold most
        of the stored bytes, and most claims read none."""
        key = f"{plan}|{lists if isinstance(lists, bool) else ','.join(sorted(lists))}"
        if key not in self._cache:
            if not self.has(plan):
                self._cache[key] = None
            else:
                from uavplan.bench.store import ResultStore

                runs = ResultStore(self.root / plan).read(lists=lists)
                self._cache[key] = runs[runs["status"] == "ok"].reset_index(drop=True)
        found = self._cache[key]
        if found is None:
            raise KeyError(plan)
        return found

    def derived(
        self, what: str, plan: str, make: Callable[[pd.DataFrame], Any],
        lists: tuple[str, ...] | bool = (),
    ) -> Any:  # fmt: skip
        """``make(self.frame(plan, lists))``, computed once per ``what`` and plan (several
        claims read the same measures of one plan's runs)."""
        key = (what, plan)
        if key not in self._derived:
            self._derived[key] = make(self.frame(plan, lists))
        return self._derived[key]


#: Every registered claim, in registration order (paper by paper).
CLAIMS: dict[str, Claim] = {}


def register_claim(claim: Claim) -> Claim:
    if claim.id in CLAIMS:
        raise ValueError(f"claim {claim.id!r} registered twice")
    CLAIMS[claim.id] = claim
    return claim


def judge(claim: Claim, results: Results) -> Finding:
    """The claim's finding, or "not run" naming the result folders that are missing."""
    missing = [p for p in claim.needs if not results.has(p)]
    if missing:
        cmd = "; ".join(f"`uavplan bench run {p} --scale paper --out results/{p}`" for p in missing)
        return Finding(
            "no stored runs",
            "no stored runs",
            "-",
            NOT_RUN,
            f"the runs of {', '.join(missing)} are not stored: {cmd}",
        )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # means of empty cells: NaN, shown "-"
        try:
            return claim.judge(results)  # a plan stored without some of its runs: below
        except (KeyError, ValueError, IndexError, StopIteration, ZeroDivisionError) as exc:
            return Finding(
                "incomplete runs",
                "incomplete runs",
                "-",
                NOT_RUN,
                f"the stored runs of {', '.join(claim.needs)} lack what this claim reads "
                f"({type(exc).__name__}: {exc}); run the plans to the end",
            )


def build_ledger(root: str | Path) -> list[tuple[Claim, Finding]]:
    """Every registered claim with its finding from the runs stored under ``root``."""
    from uavplan.bench import claims as _registers  # noqa: F401  (the papers' claims)

    results = Results(root)
    return [(c, judge(c, results)) for c in CLAIMS.values()]


def _cell(text: str) -> str:
    return " ".join(str(text).split()).replace("|", "\\|")


def render_markdown(ledger: list[tuple[Claim, Finding]], root: str | Path) -> str:
    """The ledger as Markdown: a count of verdicts, then per paper one row per claim."""
    counts = {v: sum(1 for _, f in ledger if f.verdict == v) for v in VERDICTS}
    lines = [
        "# Claims ledger",
        "",
        "Every headline claim of the four papers, judged from the runs stored under "
        f"`{Path(root).as_posix()}/` (rebuilt by `uavplan report {Path(root).as_posix()} "
        '--claims --out docs/claims.md`). "Paper\'s protocol" is our figure under the '
        "paper's own experiment (its generations, restarts or budget split); \"uavplan's "
        'protocol" is ours (equal evaluations, or the variant that isolates the claim) where '
        "the two differ. The test decides the verdict.",
        "",
        "Verdicts: " + ", ".join(f"{v} {counts[v]}" for v in VERDICTS if counts[v]) + ".",
        "",
    ]
    papers: dict[str, list[tuple[Claim, Finding]]] = {}
    for c, f in ledger:
        papers.setdefault(c.paper, []).append((c, f))
    for paper, rows in papers.items():
        lines += [
            f"## {paper}",
            "",
            "| claim | where | the paper | ours, paper's protocol | ours, uavplan's "
            "protocol | test | verdict | why | runs |",
            "|---|---|---|---|---|---|---|---|---|",
        ]
        for c, f in rows:
            lines.append(
                "| "
                + " | ".join(
                    _cell(x)
                    for x in (
                        f"**{c.id}**: {c.statement}",
                        c.where,
                        c.paper_figure,
                        f.paper_protocol,
                        f.our_protocol,
                        f.test,
                        f"**{f.verdict}**",
                        f.reason,
                        f.runs,
                    )
                )
                + " |"
            )
        lines.append("")
    return "\n".join(lines)


# ------------------------------------------------------------------------------ helpers


def fmt(x: Any, digits: int = 3) -> str:
    """A number for a ledger cell (3 significant digits; scientific when tiny or huge)."""
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "-"
    x = float(x)
    if abs(x) < 1e-9:
        return "0"
    if 1e-3 <= abs(x) < 1e5:
        return f"{x:.{digits}g}"
    return f"{x:.2e}"


def pvalue(p: float) -> str:
    return "p < 1e-4" if p < 1e-4 else f"p = {p:.2g}"


def values(df: pd.DataFrame, **where: Any) -> np.ndarray:
    """``best_cost`` (or ``where['value']``) of the rows matching ``where``'s columns."""
    col = where.pop("value", "best_cost")
    m = np.ones(len(df), dtype=bool)
    for k, v in where.items():
        m &= (df[k] == v).to_numpy()
    return df.loc[m, col].to_numpy(dtype=np.float64)
