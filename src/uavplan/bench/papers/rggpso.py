"""RGG-PSO+ (Liu et al. 2024, J. Intell. Robot. Syst.): its experiments (Sect. 5, the plans
``rggpso-rq1/2/3``: 1000 scenes x 10 runs) and its measures (Sect. 5.3 and 6) over a sweep's
run table, shown by the plans' report hook (:func:`sections`).

Each measure takes the tidy run table of a ``rggpso-rq*`` plan (``ResultStore.read()``) and
returns a DataFrame (or a figure).

Definitions (the paper is terse; our readings):

* **Final length** of a run: its returned path's length if that path is feasible, else ``inf``
  (a run that never found a feasible path has no path to measure).
* **Normalized length** (Eq. 2): per scenario, ``z = (x - min x) / (max x - min x)`` over the
  final lengths of **all runs of all compared methods** of the plan in that scenario (pooled:
  with per-method bounds every method's mean would sit near the middle and Table 2's spread
  between methods could not appear). A final ``inf`` scores the penalty 5, and runs without a
  feasible path are counted in their own column.
* **Fig. 5**: per run and iteration the best feasible length so far (``feasible_history``),
  normalized with the scenario's bounds of final lengths, 5 while no feasible path exists; the
  curve is the mean over every run of every scenario, per method.
* **F-Measure** (Table 1): iterations executed before the first feasible particle, i.e.
  ``first_feasible_iteration - 1`` (our iteration 1 is the initial swarm's evaluation, the
  paper's iteration 0); runs that never find one are left out of the mean and counted.
  The length of that first feasible path is the first finite value of ``feasible_history``
  (for ``length2d`` a feasible path's cost is its length), normalized with the plan's bounds.
* **Variance**: the sample variance (ddof = 1) over runs, as we read the paper's "Var".
* **Ratio to the reference**: final length over the scene's reference shortest path
  (``reference_length``, visibility graph), a scale that means the same in every scene.
* **Orderings**: for a claim "A < B" the per-scenario means of A and B are paired over the
  scenes and tested with a one-sided Wilcoxon signed-rank test (``alternative="less"``);
  ``A better`` / ``B better`` count scenes; the effect is the matched-pairs rank-biserial
  correlation (negative: A smaller).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from uavplan._lazy import lazy_module
from uavplan.bench import stats
from uavplan.bench.plans import Algorithm, ExperimentPlan, Scale, register_plan

if TYPE_CHECKING:
    import pandas as pd
    import scipy.stats as sps
    from matplotlib.figure import Figure
else:
    pd = lazy_module("pandas")
    sps = lazy_module("scipy.stats")

#: Penalty of the normalized length where no feasible path exists (Sect. 6.1).
PENALTY = 5.0

#: The paper's Table 1 (RQ2) and Table 2 (RQ3): (mean, variance).
PAPER_TABLE1 = {
    "rgg-pso": {"F-Measure": (4.139, 24.140), "first feasible normalized length": (0.593, 0.074)},
    "pso": {"F-Measure": (13.984, 48.365), "first feasible normalized length": (3.210, 1.555)},
}
PAPER_TABLE2 = {"rgg-pso+": (0.248, 0.086), "rgg-pso": (0.307, 0.089), "pso": (0.872, 0.781)}

#: The methods whose runs Table 1 (RQ2) and Table 2 (RQ3) normalize together.
TABLE1_METHODS = ("rgg-pso", "pso")
TABLE2_METHODS = ("rgg-pso+", "rgg-pso", "pso")

#: The orderings the paper claims: (methods pooled for Eq. 2, measure, better, worse). ``None``:
#: every method of the plan (RQ1's Fig. 5 set).
CLAIMS: tuple[tuple[tuple[str, ...] | None, str, str, str], ...] = (
    (TABLE1_METHODS, "f_measure", "rgg-pso", "pso"),
    (TABLE1_METHODS, "first_feasible_normalized", "rgg-pso", "pso"),
    (TABLE2_METHODS, "normalized_length", "rgg-pso+", "rgg-pso"),
    (TABLE2_METHODS, "normalized_length", "rgg-pso", "pso"),
    (TABLE2_METHODS, "normalized_length", "rgg-pso+", "pso"),
    (None, "normalized_length", "rgg-pso+", "ga"),
    (None, "normalized_length", "rgg-pso+", "de"),
    (None, "normalized_length", "rgg-pso+", "spso"),
    (None, "normalized_length", "spso", "rgg-pso+"),
)


def _first_finite(h: object) -> float:
    a = np.asarray(h, dtype=np.float64) if h is not None else np.zeros(0)
    idx = np.flatnonzero(np.isfinite(a))
    return float(a[idx[0]]) if idx.size else math.inf


def measures(df: pd.DataFrame) -> pd.DataFrame:
    """One row per finished run with the paper's measures added: ``final_length``,
    ``normalized_length``, ``f_measure``, ``first_feasible_length``,
    ``first_feasible_normalized``, ``reference_ratio``, ``n_obstacles``."""
    ok = df[df["status"] == "ok"].copy()
    if ok.empty:
        return ok
    feas = ok["feasible"].astype(bool).to_numpy()
    ok["final_length"] = np.where(feas, ok["path_length"].astype(float).to_numpy(), np.inf)
    ok["normalized_length"] = ok.groupby("scenario")["final_length"].transform(
        lambda s: stats.normalized_lengths(s.to_numpy(), nonfinite=PENALTY)
    )
    bounds = ok.groupby("scenario")["final_length"].agg(stats.normalization_bounds)
    lo = ok["scenario"].map(bounds.map(lambda b: b[0])).astype(float)  # per scene, then joined
    hi = ok["scenario"].map(bounds.map(lambda b: b[1])).astype(float)
    ffi = ok["first_feasible_iteration"].astype(float)
    ok["f_measure"] = ffi - 1.0
    if "feasible_history" in ok:
        first = ok["feasible_history"].map(_first_finite).astype(float)
    else:
        first = pd.Series(np.inf, index=ok.index)
    ok["first_feasible_length"] = first
    span = (hi - lo).where(hi > lo, np.nan)
    z = ((first - lo) / span).where(hi > lo, 0.0)
    ok["first_feasible_normalized"] = z.where(np.isfinite(first) & np.isfinite(lo), PENALTY)
    ref = ok["reference_length"].astype(float) if "reference_length" in ok else np.nan
    ok["reference_ratio"] = ok["final_length"] / ref
    ok["n_obstacles"] = ok["scenario"].str.extract(r"rgg-n(\d+)-", expand=False).astype(float)
    return ok


def _mean_var(x: pd.Series) -> tuple[float, float, int]:
    v = x.to_numpy(dtype=np.float64)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return math.nan, math.nan, 0
    return float(v.mean()), float(v.var(ddof=1)) if v.size > 1 else 0.0, int(v.size)


def table1(m: pd.DataFrame) -> pd.DataFrame:
    """Table 1: F-Measure and first feasible path's normalized length, ours beside the paper's."""
    rows = []
    for alg, g in m.groupby("algorithm", sort=False):
        fm, fv, fn = _mean_var(g["f_measure"])
        lm, lv, _ = _mean_var(g["first_feasible_normalized"][np.isfinite(g["f_measure"])])
        paper = PAPER_TABLE1.get(str(alg), {})
        pf = paper.get("F-Measure", (math.nan, math.nan))
        pl = paper.get("first feasible normalized length", (math.nan, math.nan))
        rows.append(
            {
                "method": alg,
                "F-Measure mean": fm,
                "F-Measure var": fv,
                "first feasible normalized length mean": lm,
                "first feasible normalized length var": lv,
                "runs": len(g),
                "runs never feasible": len(g) - fn,
                "share feasible at iteration 0": float(np.mean(g["f_measure"] == 0)),
                "paper F-Measure mean": pf[0],
                "paper F-Measure var": pf[1],
                "paper length mean": pl[0],
                "paper length var": pl[1],
            }
        )
    return pd.DataFrame(rows).set_index("method")


def table2(m: pd.DataFrame) -> pd.DataFrame:
    """Table 2 (and RQ1's final values): final normalized length per method, with the ratio to
    the reference shortest path, ours beside the paper's."""
    rows = []
    for alg, g in m.groupby("algorithm", sort=False):
        nm, nv, _ = _mean_var(g["normalized_length"])
        r = g["reference_ratio"].to_numpy(dtype=np.float64)
        r = r[np.isfinite(r)]
        paper = PAPER_TABLE2.get(str(alg), (math.nan, math.nan))
        rows.append(
            {
                "method": alg,
                "normalized length mean": nm,
                "normalized length var": nv,
                "runs": len(g),
                "runs without a feasible path": int((~np.isfinite(g["final_length"])).sum()),
                "length / reference mean": float(r.mean()) if r.size else math.nan,
                "length / reference median": float(np.median(r)) if r.size else math.nan,
                "length / reference p90": float(np.percentile(r, 90)) if r.size else math.nan,
                "share within 1 % of reference": float(np.mean(r <= 1.01)) if r.size else math.nan,
                "mean wall time (s)": float(g["wall_time"].mean()),
                "mean evaluations": float(g["evaluations"].mean()),
                "paper mean": paper[0],
                "paper var": paper[1],
            }
        )
    return pd.DataFrame(rows).set_index("method").sort_values("normalized length mean")


def by_setting(m: pd.DataFrame, value: str = "normalized_length") -> pd.DataFrame:
    """Mean of ``value`` per obstacle-count setting (rows) and method (columns)."""
    return m.pivot_table(index="n_obstacles", columns="algorithm", values=value, aggfunc="mean")


def ordering_tests(
    m: pd.DataFrame, claims: Sequence[tuple[str, str, str]], alpha: float = 0.05
) -> pd.DataFrame:
    """One-sided paired tests of "better < worse" on per-scenario means (module docstring)."""
    rows = []
    algs = set(m["algorithm"].unique())
    for metric, better, worse in claims:
        if better not in algs or worse not in algs:
            continue
        sub = m[m["algorithm"].isin([better, worse])]
        sub = sub.assign(v=sub[metric].where(np.isfinite(sub[metric]), np.nan))
        per = sub.pivot_table(
            index="scenario", columns="algorithm", values="v", aggfunc="mean"
        ).dropna()
        if per.empty:
            continue
        a = per[better].to_numpy()
        b = per[worse].to_numpy()
        d = a - b
        if np.all(d == 0):
            p = 1.0
        else:
            p = float(sps.wilcoxon(a, b, alternative="less", zero_method="wilcox").pvalue)
        rows.append(
            {
                "claim": f"{better} < {worse}",
                "measure": metric,
                "scenes": len(per),
                "A mean": float(a.mean()),
                "B mean": float(b.mean()),
                "better wins": int((d < 0).sum()),
                "ties": int((d == 0).sum()),
                "worse wins": int((d > 0).sum()),
                "rank-biserial": stats.rank_biserial_paired(a, b),
                "p (one-sided)": p,
                "holds": bool(p < alpha),
            }
        )
    out = pd.DataFrame(rows)
    return out.set_index("claim") if not out.empty else out


def fig5_curves(m: pd.DataFrame) -> pd.DataFrame:
    """Mean normalized best length per iteration (rows) and method (columns): Fig. 5."""
    bounds = m.groupby("scenario")["final_length"].agg(stats.normalization_bounds)
    curves: dict[str, np.ndarray] = {}
    for alg, g in m.groupby("algorithm", sort=False):
        acc: np.ndarray | None = None
        n = 0
        for sc, gs in g.groupby("scenario"):
            lo, hi = bounds[sc]
            hs = [np.asarray(h, dtype=np.float64) for h in gs["feasible_history"]]
            L = max(len(h) for h in hs)
            H = np.vstack([np.pad(h, (0, L - len(h)), mode="edge") for h in hs])
            if math.isnan(lo):
                Z = np.full(H.shape, PENALTY)
            else:
                Z = stats.normalized_history(H, lo, hi, PENALTY)
            s = Z.sum(axis=0)
            if acc is None:
                acc = s
            else:
                k = max(len(acc), len(s))
                acc = np.pad(acc, (0, k - len(acc)), mode="edge") + np.pad(
                    s, (0, k - len(s)), mode="edge"
                )
            n += len(Z)
        if acc is not None:
            curves[str(alg)] = acc / n
    k = max(len(c) for c in curves.values())
    data = {a: np.pad(c, (0, k - len(c)), mode="edge") for a, c in curves.items()}
    # row i: after iteration i (0 = the initial swarm's evaluation, the paper's iteration 0)
    return pd.DataFrame(data, index=pd.RangeIndex(k, name="iteration"))


def fig5_figure(curves: pd.DataFrame) -> Figure:
    """Fig. 5: best normalized path length over iterations, mean over all runs and scenes."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7.5, 4.5))
    ax = fig.add_subplot()
    for alg in curves.columns:
        ax.plot(curves.index, curves[alg], lw=1.6, label=str(alg))
    ax.set_xlabel("iteration (0 = initial swarm)")
    ax.set_ylabel("mean best normalized length (penalty 5)")
    ax.set_ylim(0, PENALTY * 1.05)
    ax.grid(alpha=0.3)
    ax.legend()
    ax.set_title("Best normalized path length over iterations (RGG-PSO+ Fig. 5)")
    fig.tight_layout()
    return fig


def _subset(df: pd.DataFrame, methods: Sequence[str]) -> pd.DataFrame:
    return df[df["algorithm"].isin(methods)]


def sections(
    df: pd.DataFrame, plan: str = ""
) -> tuple[list[tuple[str, str, pd.DataFrame | None]], list[tuple[str, str, Figure]]]:
    """The report sections and figures of an ``rggpso-rq*`` plan (or any run table with those
    methods): the paper's tables are computed on the paper's method sets, whichever plan ran
    them (rq1 holds every method, so its runs give all three research questions)."""
    m = measures(df)
    if m.empty:
        return [], []
    algs = set(m["algorithm"])
    pooled: dict[tuple[str, ...] | None, pd.DataFrame] = {None: m}
    for methods in (TABLE1_METHODS, TABLE2_METHODS):
        if set(methods) <= algs:
            pooled[methods] = m if algs == set(methods) else measures(_subset(df, methods))
    out: list[tuple[str, str, pd.DataFrame | None]] = []
    n_sc = m["scenario"].nunique()
    common = (
        f"{n_sc} scenes; penalty 5 for a run without a feasible path; variance ddof = 1; "
        "length / reference: final length over the scene's visibility-graph shortest path "
        "(feasible runs)"
    )
    out.append(
        (
            f"Final normalized path length, all methods of this plan ({', '.join(sorted(algs))})",
            "Eq. 2 per scene over the final lengths of every run of every method here (RQ1, "
            f"the methods of Fig. 5); {common}. The paper's numbers beside rgg-pso+, rgg-pso and "
            "pso are Table 2's, normalized over those three only: compare them with the next "
            "table, not this one.",
            table2(m),
        )
    )
    if TABLE2_METHODS in pooled and algs != set(TABLE2_METHODS):
        out.append(
            (
                "Final normalized path length as in the paper's Table 2 (RQ3)",
                f"Eq. 2 over the runs of {', '.join(TABLE2_METHODS)} only; {common}",
                table2(pooled[TABLE2_METHODS]),
            )
        )
    if TABLE1_METHODS in pooled:
        out.append(
            (
                "F-Measure and first feasible path as in the paper's Table 1 (RQ2)",
                "F-Measure: iterations executed before the first feasible particle (0: the "
                "initial swarm has one); the first feasible path's length normalized with the "
                f"per-scene bounds of the final lengths of {', '.join(TABLE1_METHODS)} (may "
                "exceed 1); means over the runs that found one.",
                table1(pooled[TABLE1_METHODS]),
            )
        )
    tests = pd.concat(
        [
            ordering_tests(pooled[key], [(metric, better, worse)])
            for key, metric, better, worse in CLAIMS
            if key in pooled
        ]
        or [pd.DataFrame()]
    )
    if not tests.empty:
        out.append(
            (
                "The paper's orderings, tested",
                "per-scene means paired over scenes (normalized over the method set of the "
                "table the claim comes from); one-sided Wilcoxon signed-rank test of A < B; wins "
                "count scenes; rank-biserial < 0: A smaller; holds: p < 0.05. spso < rgg-pso+ "
                "and rgg-pso+ < spso are both tested: the paper says SPSO ends better but "
                "converges slower.",
                tests,
            )
        )
    out.append(
        (
            "Normalized final length by obstacle count",
            "mean over the 100 scenes x runs of each setting; all methods of this plan pooled",
            by_setting(m),
        )
    )
    figs: list[tuple[str, str, Figure]] = []
    if "feasible_history" in m:
        curves = fig5_curves(m)
        figs.append(
            ("fig5", "Best normalized path length over iterations (Fig. 5)", fig5_figure(curves))
        )
        pick = [i for i in (0, 1, 5, 10, 20, 50, 100, 150, len(curves) - 1) if i < len(curves)]
        out.append(
            (
                "Fig. 5 values",
                "mean best normalized length after these iterations (0: the initial swarm); "
                "all methods of this plan pooled for Eq. 2",
                curves.loc[sorted(set(pick))],
            )
        )
    return out, figs


# ------------------------------------------------------------------------------ the plans
def plans() -> list[ExperimentPlan]:
    """RGG-PSO+ (Liu et al. 2024) Sect. 5: 1000 scenes x 10 runs, 100 particles, 200 iterations,
    N = 20 waypoints (the scenes' default); smoke scale: two scenes, one run, a small budget."""
    from uavplan.scenarios.names import family_names

    paper_scenes = tuple(family_names())
    smoke_scenes = ("rgg-n05-i000", "rgg-n14-i000")
    scales = {
        "smoke": Scale(runs=1, iterations=15, pop_size=20, scenarios=smoke_scenes),
        "paper": Scale(runs=10, iterations=200, pop_size=100, scenarios=paper_scenes),
    }

    def alg(label: str) -> Algorithm:
        return Algorithm(label, label)

    return [
        ExperimentPlan(
            name="rggpso-rq1",
            description=(
                "RGG-PSO+ vs RGG-PSO, PSO, SPSO, GA, DE on the 1000-scene family, 10 runs: best "
                "normalized path length over iterations (Fig. 5)"
            ),
            scenarios=smoke_scenes,
            algorithms=tuple(alg(a) for a in ("rgg-pso+", "rgg-pso", "pso", "spso", "ga", "de")),
            scales=scales,
            reference="rgg-pso+",
            metric="path_length",
            report=sections,
        ),
        ExperimentPlan(
            name="rggpso-rq2",
            description=(
                "RGG-PSO vs PSO: F-Measure (iterations before the first feasible particle) and "
                "the first feasible path's normalized length (Table 1)"
            ),
            scenarios=smoke_scenes,
            algorithms=(alg("rgg-pso"), alg("pso")),
            scales=scales,
            reference="rgg-pso",
            metric="path_length",
            report=sections,
        ),
        ExperimentPlan(
            name="rggpso-rq3",
            description="RGG-PSO+ vs RGG-PSO vs PSO final normalized lengths (Table 2)",
            scenarios=smoke_scenes,
            algorithms=(alg("rgg-pso+"), alg("rgg-pso"), alg("pso")),
            scales=scales,
            reference="rgg-pso+",
            metric="path_length",
            report=sections,
        ),
    ]


for _plan in plans():
    register_plan(_plan)
