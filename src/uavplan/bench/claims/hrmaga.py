"""HR-MAGA's claims (Yang, Liu & Li 2020): Fig. 8 (better than P-MAGA and GA, faster, less
variance) and Figs. 5a and 5b (the waypoints per optimization, the optimization per level).

Protocols: ``hrmaga-compare`` gives GA, P-MAGA and HR-MAGA one evaluation budget (ours); the
paper runs every P-MAGA call of HR-MAGA for G = 200 generations and plots per iteration, so
its HR-MAGA spends many times P-MAGA's evaluations. Runs under the paper's protocol are read
from ``hrmaga-compare-paper`` when stored.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pandas as pd
from scipy import stats as sps

from uavplan.bench.claims.base import (
    NOT_REPRODUCED,
    REPRODUCED,
    Claim,
    Finding,
    Results,
    combine,
    fmt,
    pvalue,
    register_claim,
)

PAPER = "HR-MAGA (Yang, Liu & Li)"
MAPS = ("hrmaga-spso", "hrmaga-jacksboro", "hrmaga-topobathy", "hrmaga-virtual")
PAPER_PLAN = "hrmaga-compare-paper"
#: the list columns the convergence claims read (the others are left unread)
HISTORIES = ("history", "evaluations_history")


def _short(m: str) -> str:
    return m.removeprefix("hrmaga-")


def _signs(df: pd.DataFrame, ref: str, other: str, value: Any) -> tuple[list[str], int, int]:
    """Per map the sign of ``ref`` against ``other`` (two-sided rank-sum, 5 %, + = ``ref``
    lower) on ``value(rows)``; and the counts of + and -."""
    from uavplan.bench.stats import ranksum_test

    cells, plus, minus = [], 0, 0
    for m in MAPS:
        a = value(df[(df.scenario == m) & (df.algorithm == ref)])
        b = value(df[(df.scenario == m) & (df.algorithm == other)])
        if not (len(a) and len(b)):
            continue
        _, p = ranksum_test(a, b)
        lower = float(np.median(a)) < float(np.median(b))
        s = "~" if p >= 0.05 else ("+" if lower else "-")
        plus, minus = plus + (s == "+"), minus + (s == "-")
        cells.append(
            f"{_short(m)} {s} (median {fmt(np.median(a))} vs {fmt(np.median(b))}, {pvalue(p)})"
        )
    return cells, plus, minus


def _final(g: pd.DataFrame) -> np.ndarray:
    return g["best_cost"].to_numpy(dtype=np.float64)


def _early(g: pd.DataFrame, share: float = 0.25) -> np.ndarray:
    """Each run's best loss when it had spent ``share`` of its evaluations."""
    out = []
    for h, e in zip(g["history"], g["evaluations_history"], strict=True):
        h, e = np.asarray(h, np.float64), np.asarray(e, np.float64)
        k = int(np.searchsorted(e, share * e[-1], side="right")) - 1
        out.append(h[max(k, 0)])
    return np.asarray(out)


def _runs(r: Results, algs: tuple[str, ...]) -> str:
    """The runs a Fig. 8 finding reads, per protocol."""
    out = [f"{int(r.frame('hrmaga-compare', HISTORIES).algorithm.isin(algs).sum())} at one budget"]
    if r.has(PAPER_PLAN):
        out.append(
            f"{int(r.frame(PAPER_PLAN, HISTORIES).algorithm.isin(algs).sum())} under the "
            "paper's protocol"
        )
    return " and ".join(out) + " runs"


def _verdict(ours_ok: bool, paper_ok: bool | None) -> str:
    """Here the paper's protocol is the optional one: not run, ours decides alone."""
    return combine(ours_ok, None) if paper_ok is None else combine(paper_ok, ours_ok)


def _paper_runs(r: Results, ref: str, other: str, value: Any) -> tuple[str, bool | None]:
    if not r.has(PAPER_PLAN):
        return (
            f"not run (G = 200 per P-MAGA call: `uavplan bench run {PAPER_PLAN} --scale paper`)",
            None,
        )
    cells, plus, minus = _signs(r.frame(PAPER_PLAN, HISTORIES), ref, other, value)
    return "; ".join(cells), plus >= 3 and minus == 0


def _faster(ref: str, other: str, fig: str) -> Claim:
    def judge(r: Results) -> Finding:
        df = r.frame("hrmaga-compare", HISTORIES)
        cells, plus, minus = _signs(df, ref, other, _early)
        paper_txt, paper_ok = _paper_runs(r, ref, other, _early)
        ours_ok = plus >= 3 and minus == 0
        why = (
            f"{ref.upper()}'s best loss after a quarter of its evaluations is significantly "
            f"lower on {plus} of 4 maps, higher on {minus}, at one budget"
            + ("" if paper_ok is not None else "; the paper's protocol is not run")
        )
        return Finding(
            paper_txt,
            "; ".join(cells),
            "two-sided rank-sum per map on each run's "
            f"best loss at a quarter of its evaluations, 5 %; + = {ref.upper()} "
            "lower",
            _verdict(ours_ok, paper_ok),
            why,
            _runs(r, (ref, other)),
        )

    return Claim(
        f"hrmaga-{ref}-faster-than-{other}",
        PAPER,
        "Fig. 8a",
        f"{ref.upper()} converges faster than {other.upper()}",
        fig,
        ("hrmaga-compare",),
        judge,
    )


register_claim(
    _faster(
        "hr-maga",
        "p-maga",
        '"absolute advantage in convergence speed" (curves only, normalized by Eq. 12, 40 runs)',
    )
)
register_claim(
    _faster(
        "p-maga",
        "ga",
        'P-MAGA reaches "the convergence result quickly" '
        'against GA; "higher search efficiency than GA" (Sect. V)',
    )
)


def _spread(df: pd.DataFrame) -> tuple[list[str], int]:
    """Per map HR-MAGA's spread against P-MAGA's and GA's; the maps where it is significantly
    smaller than both."""
    cells, less = [], 0
    for m in MAPS:
        a = _final(df[(df.scenario == m) & (df.algorithm == "hr-maga")])
        ok = True
        txt = [f"{_short(m)} sd {fmt(np.std(a))}"]
        for other in ("p-maga", "ga"):
            b = _final(df[(df.scenario == m) & (df.algorithm == other)])
            if not (len(a) and len(b)):
                continue
            p = float(sps.levene(a, b, center="median").pvalue)
            ok &= p < 0.05 and float(np.std(a)) < float(np.std(b))
            txt.append(f"{other} {fmt(np.std(b))} ({pvalue(p)})")
        less += ok
        cells.append(" vs ".join(txt))
    return cells, less


def _both(r: Results, measure: Any, holds: Any, what: str, test: str) -> Finding:
    """A Fig. 8 claim measured by ``measure(df) -> (cells, count)`` under both protocols."""
    df = r.frame("hrmaga-compare", HISTORIES)
    cells, k = measure(df)
    paper_txt, paper_ok, kp = "not run (G = 200 per P-MAGA call)", None, None
    if r.has(PAPER_PLAN):
        pc, kp = measure(r.frame(PAPER_PLAN, HISTORIES))
        paper_txt, paper_ok = "; ".join(pc), holds(kp)
    verdict = _verdict(holds(k), paper_ok)
    why = f"{what}: {k} of 4 maps at one budget" + (
        f", {kp} of 4 under the paper's protocol"
        if kp is not None
        else "; the paper's protocol is not run"
    )
    return Finding(
        paper_txt, "; ".join(cells), test, verdict, why, _runs(r, ("hr-maga", "p-maga", "ga"))
    )


def _variance(r: Results) -> Finding:
    return _both(
        r,
        _spread,
        lambda k: k == len(MAPS),
        "HR-MAGA's final loss varies significantly less than both",
        "Brown-Forsythe test of equal spread per map against each, 5 %",
    )


register_claim(
    Claim(
        "hrmaga-varies-least",
        PAPER,
        "Fig. 8b",
        "HR-MAGA's final loss varies less than P-MAGA's and GA's over 40 runs",
        '"the variance of HR-MAGA is smaller than P-MAGA and GA" (box plots, 4 maps)',
        ("hrmaga-compare",),
        _variance,
    )
)


def _goodness(df: pd.DataFrame) -> tuple[list[str], int]:
    from uavplan.bench.stats import ranksum_test

    cells, good = [], 0
    for m in MAPS:
        a = _final(df[(df.scenario == m) & (df.algorithm == "hr-maga")])
        worse = []
        for other in ("p-maga", "ga"):
            b = _final(df[(df.scenario == m) & (df.algorithm == other)])
            _, p = ranksum_test(a, b)
            if p < 0.05 and float(np.median(a)) > float(np.median(b)):
                worse.append(other)
        good += not worse
        cells.append(f"{_short(m)} " + ("good" if not worse else f"worse than {', '.join(worse)}"))
    return cells, good


def _good(r: Results) -> Finding:
    return _both(
        r,
        _goodness,
        lambda k: k >= 3,
        "HR-MAGA is good (significantly worse than neither) on",
        "two-sided rank-sum per map of HR-MAGA's final loss against P-MAGA's and GA's, "
        "5 %; good = significantly worse than neither; the paper: good on 3, poor on "
        "one it does not name",
    )


register_claim(
    Claim(
        "hrmaga-good-on-three-maps",
        PAPER,
        "Fig. 8b",
        "HR-MAGA's final loss is good on three of the four maps and poor on one",
        '"good performance in three environments. A poor performance appears in '
        'one"; "solution quality is also competitive"',
        ("hrmaga-compare",),
        _good,
    )
)


def _converge_iteration(h: Any, tol: float = 0.01) -> float:
    """The first iteration whose best loss is within ``tol`` of the run's final best."""
    h = np.asarray(h, dtype=np.float64)
    fin = np.isfinite(h)
    if not fin.any():
        return math.nan
    last = h[fin][-1]
    ok = fin & (h <= last + tol * abs(last))
    return float(np.argmax(ok))


def _waypoints(r: Results) -> Finding:
    df = r.frame("hrmaga-waypoints", HISTORIES)
    df = df.assign(
        k=df.algorithm.str.removeprefix("wp").astype(int),
        conv=[_converge_iteration(h) for h in df["history"]],
    )
    med = df.groupby("k")["conv"].median()
    rho, p = sps.spearmanr(df["k"], df["conv"], nan_policy="omit")
    ks = med.index.to_numpy(dtype=float)
    below, above = ks <= 8, ks >= 8
    slope_lo = float(np.polyfit(ks[below], med.to_numpy()[below], 1)[0]) if below.sum() > 1 else 0.0
    slope_hi = float(np.polyfit(ks[above], med.to_numpy()[above], 1)[0]) if above.sum() > 1 else 0.0
    # "greatly affected" above 8: the cost of a waypoint at least doubles past 8
    ok = bool(rho > 0 and p < 0.05 and slope_hi >= 2.0 * max(slope_lo, 1e-9))
    return Finding(
        "median iterations to within 1 % of the final loss, by waypoints optimized: "
        + ", ".join(f"{k}: {fmt(v)}" for k, v in med.items()),
        "as the paper's",
        f"Spearman rho {fmt(rho, 2)} ({pvalue(p)}); least-squares slope of the medians "
        f"{fmt(slope_lo)} iterations per waypoint up to 8, {fmt(slope_hi)} from 8 on (a break "
        "at 8: at least twice)",
        REPRODUCED if ok else NOT_REPRODUCED,
        "convergence slows with more waypoints and breaks at 8"
        if ok
        else "convergence slows steadily with the waypoints optimized, with no break at 8",
        f"{len(df)} runs (P-MAGA, 40 per map and count)",
    )


register_claim(
    Claim(
        "hrmaga-waypoints-above-8-slow",
        PAPER,
        "Fig. 5a",
        "optimizing more than 8 waypoints at once slows convergence greatly",
        '"when the number of optimized waypoint exceeds 8, the convergence speed '
        '... is greatly affected"; num = 3 chosen',
        ("hrmaga-waypoints",),
        _waypoints,
    )
)


def _layers(r: Results) -> Finding:
    df = r.frame("hrmaga-layers", ("level_history", "level_lengths"))
    drops = []
    for flat, lens in zip(df["level_history"], df["level_lengths"], strict=True):
        parts = np.split(np.asarray(flat, dtype=np.float64), np.cumsum(lens)[:-1])
        d = []
        for part in parts:
            f = part[np.isfinite(part)]
            d.append(float(f[0] - f[-1]) if f.size else math.nan)
        drops.append(d)
    D = np.asarray(drops, dtype=np.float64)
    span = D[:, :1]  # Eq. 13 scales by the first level's range
    N = D / np.where(span > 0, span, np.nan)
    med = np.nanmedian(N, axis=0)
    tests, ok = [], True
    for k in range(D.shape[1] - 1):
        a, b = D[:, k], D[:, k + 1]
        m = np.isfinite(a) & np.isfinite(b)
        p = float(sps.wilcoxon(a[m], b[m], alternative="greater").pvalue) if m.sum() > 1 else 1.0
        ok &= p < 0.05
        tests.append(f"level {k + 1} > {k + 2}: {pvalue(p)}")
    return Finding(
        "median loss drop per level, relative to level 1's: "
        + ", ".join(f"level {k + 1} {fmt(v, 2)}" for k, v in enumerate(med)),
        "as the paper's",
        "one-sided Wilcoxon signed-rank over runs, 5 %: " + "; ".join(tests),
        REPRODUCED if ok else NOT_REPRODUCED,
        "each deeper level lowers the loss less than the one before"
        if ok
        else "a deeper level does not lower the loss less than the one before",
        f"{len(df)} runs",
    )


register_claim(
    Claim(
        "hrmaga-deeper-levels-contribute-less",
        PAPER,
        "Fig. 5b",
        "each deeper recursion level contributes less of the optimization, the "
        "third much less than the second",
        '"the part of global optimization gradually decreases"; level 3 drops '
        '"sharply" against level 2 (curves only)',
        ("hrmaga-layers",),
        _layers,
    )
)
