"""Statistics over tidy run tables: summary tables, effect sizes, tests and rankings.

Every function here is pure: it reads a :class:`pandas.DataFrame` of tidy run rows (one row per
run, with at least the columns ``plan``, ``scenario``, ``algorithm``, ``run_index``, ``status`` and
numeric metrics such as ``best_cost``) or plain arrays, and returns new frames, arrays or numbers.
No I/O, no printing.

Conventions shared by the whole module
--------------------------------------
* **Only rows with** ``status == "ok"`` **enter statistics.** Rows of runs that crashed
  (``status == "error"``) are dropped before anything is computed; a group in which every run of an
  algorithm errored still shows up in the tables, with ``n = 0`` and NaN statistics, so failures do
  not vanish silently.
* **Lower is better** (costs, lengths, times) unless a function says otherwise.
* **Infinite values are outcomes, NaN values are missing.** A run that never found a finite cost
  has ``best_cost = +inf``: it is a (very bad) result that must count, and rank-based methods order
  it correctly (``+inf`` is worse than every finite value and ties with other ``+inf``). A NaN
  metric in a table (e.g. a path length that was never measured) is treated as missing and dropped
  from that metric's statistics; the ``n`` columns report how many values were used. The low-level
  array functions (effect sizes, tests) refuse NaN input instead of guessing.

Methods and references
----------------------
* Summary table: best / worst / mean / std / median per (scenario, algorithm), the layout of
  PPSwarm Table 3 (Meng, Chen, Qu, *Drones* 2024).
* Wilcoxon rank-sum (Mann-Whitney U) test, SciPy ``mannwhitneyu``; Wilcoxon signed-rank test,
  SciPy ``wilcoxon`` (Wilcoxon 1945; Mann & Whitney 1947).
* Cliff's delta (Cliff 1993), identical to the rank-biserial correlation of the rank-sum test
  (Glass 1966); Vargha-Delaney A12 (Vargha & Delaney 2000); matched-pairs rank-biserial
  correlation (Kerby 2014, "The simple difference formula", *Comprehensive Psychology* 3).
* Win/tie/loss signs "+", "~", "-" of a reference algorithm against every competitor, RSCDWOA
  Table 5 (Zhang et al.).
* Benjamini-Hochberg false discovery rate control (Benjamini & Hochberg 1995), SciPy
  ``false_discovery_control``.
* Friedman test over blocks (scenarios / functions) with average ranks, Nemenyi post-hoc test and
  critical difference (Demšar 2006, "Statistical comparisons of classifiers over multiple data
  sets", *JMLR* 7:1-30).
* Min-max normalized path lengths and normalized best-so-far histories with penalty 5 before the
  first feasible path, RGG-PSO+ Eq. 2 and Fig. 5 (Liu et al. 2024).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Hashable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from uavplan._lazy import lazy_module

if TYPE_CHECKING:
    import pandas as pd
    from scipy import stats as sps
else:
    pd = lazy_module("pandas")
    sps = lazy_module("scipy.stats")

__all__ = [
    "FriedmanResult",
    "bh_adjust",
    "cliffs_delta",
    "compare_to_reference",
    "critical_difference",
    "friedman_test",
    "nemenyi_posthoc",
    "normalization_bounds",
    "normalized_history",
    "normalized_lengths",
    "rank_biserial_paired",
    "ranksum_test",
    "signed_rank_test",
    "summary_table",
    "vargha_delaney_a12",
    "win_tie_loss",
]

#: Value of the ``status`` column of rows that enter statistics.
OK_STATUS = "ok"

FloatArray = NDArray[np.float64]


# --------------------------------------------------------------------------------------------
# helpers
# --------------------------------------------------------------------------------------------


def stack_histories(histories: Sequence[ArrayLike], fill: float = np.nan) -> NDArray[np.float64]:
    """Per-run curves of different lengths as one ``(runs, longest)`` array: each padded with
    its last value (``fill`` for an empty one); values that are not finite or at least 1e7 (the
    feasibility-first numbers of infeasible candidates) become ``fill``."""
    n = max((len(np.atleast_1d(h)) for h in histories), default=0)
    M = np.full((len(histories), n), fill, dtype=np.float64)
    for k, h in enumerate(histories):
        a = np.atleast_1d(np.asarray(h, dtype=np.float64))
        M[k, : len(a)] = a
        M[k, len(a) :] = a[-1] if len(a) else fill
    M[~np.isfinite(M) | (M >= 1e7)] = fill
    return M


def _as_columns(cols: str | Sequence[str] | None) -> list[str]:
    """``"scenario"`` -> ``["scenario"]``; sequences are copied; ``None`` -> ``[]``."""
    if cols is None:
        return []
    if isinstance(cols, str):
        return [cols]
    return list(cols)


def _require_columns(df: pd.DataFrame, cols: Sequence[str]) -> None:
    missing = [c for c in cols if c not in df.columns]
    if missing:
        raise KeyError(f"run table lacks column(s) {missing}; it has {list(df.columns)}")


def _ok_mask(df: pd.DataFrame) -> pd.Series:
    """Boolean mask of the rows that enter statistics (``status == "ok"``)."""
    _require_columns(df, ["status"])
    return df["status"] == OK_STATUS


def _iter_groups(
    df: pd.DataFrame, by: list[str]
) -> Iterator[tuple[tuple[Hashable, ...], pd.DataFrame]]:
    """Yield ``(key tuple, sub-frame)`` per group, sorted by key; one group if ``by`` is empty."""
    if not by:
        yield (), df
        return
    for key, sub in df.groupby(by, sort=True, dropna=False):
        yield (key if isinstance(key, tuple) else (key,)), sub


def _sample(x: ArrayLike, name: str) -> FloatArray:
    """One-dimensional float64 copy of ``x``; rejects NaN and empty samples."""
    arr = np.asarray(x, dtype=np.float64).ravel()
    if arr.size == 0:
        raise ValueError(f"sample {name!r} is empty")
    if np.isnan(arr).any():
        raise ValueError(
            f"sample {name!r} contains NaN; encode runs without a result as +inf, "
            "or drop missing values before calling"
        )
    return arr


def _pair(a: ArrayLike, b: ArrayLike) -> tuple[FloatArray, FloatArray]:
    x = _sample(a, "a")
    y = _sample(b, "b")
    if x.shape != y.shape:
        raise ValueError(f"paired samples differ in length: {x.size} vs {y.size}")
    return x, y


def _paired_differences(x: FloatArray, y: FloatArray) -> FloatArray:
    """``x - y`` with equal values (including ``inf`` vs ``inf``) giving exactly 0.

    Infinite differences (one side infinite, the other not) are kept as ``±inf`` here and made
    finite by :func:`_finite_ordered` where SciPy needs it.
    """
    with np.errstate(invalid="ignore"):
        d = x - y
    d[x == y] = 0.0
    return d


def _finite_ordered(d: FloatArray) -> FloatArray:
    """Replace ``±inf`` by ``±M`` with ``M`` above every finite ``|d|``; order and ties kept.

    All infinite entries of one sign become the same number, so they tie with each other and rank
    above every finite magnitude, exactly as ``rankdata`` ranks them.
    """
    inf = np.isinf(d)
    if not inf.any():
        return d
    finite_abs = np.abs(d[~inf])
    big = 2.0 * float(finite_abs.max()) + 1.0 if finite_abs.size else 1.0
    out = d.copy()
    out[inf] = np.sign(d[inf]) * big
    return out


def _greater_less_counts(x: FloatArray, y: FloatArray) -> tuple[int, int]:
    """Number of pairs ``(i, j)`` with ``x_i > y_j`` and with ``x_i < y_j`` (inf-safe)."""
    gt = int(np.count_nonzero(x[:, None] > y[None, :]))
    lt = int(np.count_nonzero(x[:, None] < y[None, :]))
    return gt, lt


# --------------------------------------------------------------------------------------------
# 1. summary table
# --------------------------------------------------------------------------------------------


def _describe(values: FloatArray) -> dict[str, float | int]:
    """best / worst / mean / std / median / n / n_finite of one group (NaN already removed)."""
    n = int(values.size)
    n_finite = int(np.count_nonzero(np.isfinite(values)))
    if n == 0:
        nan = math.nan
        return {
            "best": nan,
            "worst": nan,
            "mean": nan,
            "std": nan,
            "median": nan,
            "n": 0,
            "n_finite": 0,
        }
    with np.errstate(invalid="ignore"):
        mean = float(np.mean(values))
        median = float(np.median(values))
    std = float(np.std(values, ddof=1)) if n >= 2 and n_finite == n else math.nan
    return {
        "best": float(np.min(values)),
        "worst": float(np.max(values)),
        "mean": mean,
        "std": std,
        "median": median,
        "n": n,
        "n_finite": n_finite,
    }


def summary_table(
    df: pd.DataFrame,
    value: str = "best_cost",
    by: str | Sequence[str] = ("scenario", "algorithm"),
) -> pd.DataFrame:
    """Best / worst / mean / std / median of ``value`` per group, PPSwarm Table 3 layout.

    PPSwarm (Meng, Chen, Qu, *Drones* 2024) Table 3 reports, per scenario and algorithm, the best
    (minimum), worst (maximum), mean and standard deviation of the final cost over independent
    runs. This adds the median and the counts.

    Only rows with ``status == "ok"`` are used. NaN values of ``value`` are treated as missing and
    dropped. Infinite values are kept, because a run that never found a finite cost is a result:

    * ``best`` / ``worst`` are the min / max over all values (``worst`` is ``inf`` if any run never
      found a finite cost; ``best`` is ``inf`` only if none did);
    * ``mean`` and ``median`` are over all values (``mean`` is ``inf`` as soon as one value is
      ``inf``; the median stays finite while fewer than half of the runs are infinite);
    * ``std`` is the sample standard deviation (``ddof=1``); it is NaN when a value is not finite
      (undefined) or fewer than two values exist;
    * ``n`` counts the values used, ``n_finite`` the finite ones among them.

    Args:
        df: tidy run table with a ``status`` column, the ``by`` columns and ``value``.
        value: numeric metric column, e.g. ``"best_cost"``, ``"path_length"``, ``"wall_time"``.
        by: grouping column(s); groups are sorted by key. Groups are taken from all rows, so an
            algorithm whose runs all errored appears with ``n = 0`` and NaN statistics.

    Returns:
        One row per group: the ``by`` columns, then ``best``, ``worst``, ``mean``, ``std``,
        ``median`` (float) and ``n``, ``n_finite`` (int).
    """
    by_cols = _as_columns(by)
    _require_columns(df, [*by_cols, value, "status"])
    rows: list[dict[str, Any]] = []
    for key, sub in _iter_groups(df, by_cols):
        vals = sub.loc[_ok_mask(sub), value].to_numpy(dtype=np.float64)
        vals = vals[~np.isnan(vals)]
        rows.append({**dict(zip(by_cols, key, strict=True)), **_describe(vals)})
    columns = [*by_cols, "best", "worst", "mean", "std", "median", "n", "n_finite"]
    out = pd.DataFrame(rows, columns=columns)
    return out.astype({"n": "int64", "n_finite": "int64"})


# --------------------------------------------------------------------------------------------
# 2. effect sizes
# --------------------------------------------------------------------------------------------


def cliffs_delta(a: ArrayLike, b: ArrayLike) -> float:
    """Cliff's delta: ``P(a > b) - P(a < b)`` over all cross pairs, in ``[-1, 1]``.

    Cliff (1993), "Dominance statistics: ordinal analyses to answer ordinal questions",
    *Psychological Bulletin* 114(3). It equals the rank-biserial correlation of the Wilcoxon
    rank-sum test, ``2 U_a / (n_a n_b) - 1`` with ``U_a`` SciPy's ``mannwhitneyu`` statistic of
    ``a`` (Glass 1966).

    Sign: **negative when values of ``a`` tend to be smaller** than those of ``b`` (for costs:
    ``a`` tends to be better); -1 when every ``a`` is below every ``b``. Ties count for neither
    side. Only comparisons are used, so ``+inf`` is simply larger than every finite value and ties
    with ``+inf``.

    Raises:
        ValueError: if a sample is empty or contains NaN.
    """
    x = _sample(a, "a")
    y = _sample(b, "b")
    gt, lt = _greater_less_counts(x, y)
    return (gt - lt) / (x.size * y.size)


def vargha_delaney_a12(a: ArrayLike, b: ArrayLike) -> float:
    """Vargha-Delaney A12: ``P(a > b) + 0.5 P(a = b)``, in ``[0, 1]``.

    Vargha & Delaney (2000), "A critique and improvement of the CL common language effect size
    statistics of McGraw and Wong", *J. Educational and Behavioral Statistics* 25(2). It is the
    probability that a random value of ``a`` is larger than a random value of ``b``, ties counting
    one half; ``A12 = (1 + delta) / 2`` with ``delta`` Cliff's delta, and ``A12 = U_a / (n_a n_b)``.

    0.5 means no effect; **below 0.5 when ``a`` tends to be smaller** (for costs: better). Handles
    ``inf`` (comparisons only) and ties.

    Raises:
        ValueError: if a sample is empty or contains NaN.
    """
    x = _sample(a, "a")
    y = _sample(b, "b")
    gt, lt = _greater_less_counts(x, y)
    ties = x.size * y.size - gt - lt
    return (gt + 0.5 * ties) / (x.size * y.size)


def rank_biserial_paired(a: ArrayLike, b: ArrayLike) -> float:
    """Matched-pairs rank-biserial correlation of the Wilcoxon signed-rank test, in ``[-1, 1]``.

    Kerby (2014), "The simple difference formula: an approach to teaching nonparametric
    correlation", *Comprehensive Psychology* 3: with ``d_i = a_i - b_i``, the absolute non-zero
    differences are ranked (ties get average ranks) and ``r = (R+ - R-) / (R+ + R-)``, where ``R+``
    (``R-``) is the rank sum of the positive (negative) differences.

    Zero differences are dropped, as in the signed-rank test with ``zero_method="wilcox"``; if all
    differences are zero the result is 0. Sign: **negative when ``a`` tends to be smaller** than
    its partner in ``b``. Pairs where both values are ``+inf`` are equal (difference 0); an
    ``inf`` against a finite value is a difference larger than every finite one, and such
    differences tie with each other.

    Raises:
        ValueError: if the samples are empty, contain NaN or differ in length.
    """
    x, y = _pair(a, b)
    d = _paired_differences(x, y)
    d = d[d != 0]
    if d.size == 0:
        return 0.0
    ranks = sps.rankdata(np.abs(d))
    r_plus = float(ranks[d > 0].sum())
    r_minus = float(ranks[d < 0].sum())
    return (r_plus - r_minus) / (r_plus + r_minus)


# --------------------------------------------------------------------------------------------
# 3. two-sample tests
# --------------------------------------------------------------------------------------------


def ranksum_test(a: ArrayLike, b: ArrayLike) -> tuple[float, float]:
    """Two-sided Wilcoxon rank-sum (Mann-Whitney U) test; returns ``(U_a, p)``.

    Calls ``scipy.stats.mannwhitneyu(a, b, alternative="two-sided", method="auto")``. ``U_a`` is
    SciPy's statistic for ``a`` (number of pairs with ``a > b``, ties counting one half).

    Infinite values: **the pooled sample is ranked first** (``scipy.stats.rankdata``, ties
    averaged, ``+inf`` above every finite value and tied with other ``+inf``) and the test is run
    on the ranks. The test depends on the data only through these ranks (U, the tie correction and
    SciPy's exact/asymptotic choice), so for finite data the result is identical to calling
    ``mannwhitneyu`` on the raw values, and ``inf`` never reaches floating-point arithmetic.

    If every pooled value is equal, the test has no information: returns ``(n_a n_b / 2, 1.0)``.

    Raises:
        ValueError: if a sample is empty or contains NaN.
    """
    x = _sample(a, "a")
    y = _sample(b, "b")
    pooled = np.concatenate([x, y])
    if np.all(pooled == pooled[0]):
        return 0.5 * x.size * y.size, 1.0
    ranks = sps.rankdata(pooled)
    res = sps.mannwhitneyu(ranks[: x.size], ranks[x.size :], alternative="two-sided", method="auto")
    return float(res.statistic), float(res.pvalue)


def signed_rank_test(
    a: ArrayLike,
    b: ArrayLike,
    zero_method: Literal["wilcox", "pratt", "zsplit"] = "wilcox",
) -> tuple[float, float]:
    """Two-sided Wilcoxon signed-rank test of paired samples; returns ``(statistic, p)``.

    Calls ``scipy.stats.wilcoxon(d, zero_method=zero_method, alternative="two-sided")`` on the
    differences ``d = a - b`` (SciPy computes the same differences when given ``a, b``, so for
    finite data the result equals ``wilcoxon(a, b)``). The statistic is SciPy's (the smaller of the
    positive and negative rank sums for the two-sided test).

    Infinite values: a pair of equal values (including ``+inf`` vs ``+inf``) has difference 0;
    a difference involving one infinite value is replaced by ``±M`` with ``M`` larger than every
    finite ``|d|``, so it ranks above all finite differences and ties with the other infinite ones,
    which is how ranks order infinities. No ``inf - inf = NaN`` can occur.

    If every pair is equal (all differences zero), returns ``(0.0, 1.0)`` instead of SciPy's
    warning.

    Raises:
        ValueError: if the samples are empty, contain NaN or differ in length.
    """
    x, y = _pair(a, b)
    d = _paired_differences(x, y)
    if np.all(d == 0):
        return 0.0, 1.0
    res = sps.wilcoxon(_finite_ordered(d), zero_method=zero_method, alternative="two-sided")
    return float(res.statistic), float(res.pvalue)


# --------------------------------------------------------------------------------------------
# 6. multiple-comparison correction (used by 4.)
# --------------------------------------------------------------------------------------------


def bh_adjust(pvalues: ArrayLike) -> FloatArray:
    """Benjamini-Hochberg adjusted p-values; NaN entries stay NaN, the rest are adjusted together.

    Benjamini & Hochberg (1995), "Controlling the false discovery rate", *JRSS B* 57(1). A thin
    wrapper around ``scipy.stats.false_discovery_control(p, method="bh")``, which refuses NaN:
    the finite p-values are adjusted as one family (``m`` = number of non-NaN p-values) and put
    back in place.

    Args:
        pvalues: any shape; values in ``[0, 1]`` or NaN.

    Returns:
        float64 array of the same shape.
    """
    p = np.asarray(pvalues, dtype=np.float64)
    out = np.full(p.shape, np.nan)
    present = ~np.isnan(p)
    if present.any():
        out[present] = sps.false_discovery_control(p[present], method="bh")
    return out


# --------------------------------------------------------------------------------------------
# 4. comparison against a reference algorithm
# --------------------------------------------------------------------------------------------

_COMPARISON_COLUMNS = [
    "algorithm",
    "reference",
    "test",
    "n_reference",
    "n_algorithm",
    "median_reference",
    "median_algorithm",
    "statistic",
    "p",
    "p_adjusted",
    "effect_size",
    "effect_measure",
    "outcome",
]


def _values(sub: pd.DataFrame, value: str) -> FloatArray:
    vals = sub[value].to_numpy(dtype=np.float64)
    return vals[~np.isnan(vals)]


def _median(x: FloatArray) -> float:
    if x.size == 0:
        return math.nan
    with np.errstate(invalid="ignore"):
        return float(np.median(x))


def compare_to_reference(
    df: pd.DataFrame,
    reference: str,
    value: str = "best_cost",
    by: str | Sequence[str] = "scenario",
    test: Literal["ranksum", "signed-rank"] = "ranksum",
    pair_on: str | Sequence[str] = "run_index",
    alpha: float = 0.05,
    correction: Literal["bh", "none"] = "bh",
    *,
    treatment: str = "algorithm",
    lower_is_better: bool = True,
) -> pd.DataFrame:
    """Test the reference algorithm against every other algorithm in every group.

    For each group of ``by`` (a scenario, a benchmark function, ...) and each algorithm other than
    ``reference`` that has rows in that group, the ``status == "ok"`` values of ``value`` of the
    two algorithms are compared with

    * ``test="ranksum"``: the two-sided Wilcoxon rank-sum test (:func:`ranksum_test`, as in
      RSCDWOA Table 5), effect size Cliff's delta (:func:`cliffs_delta`, equal to the rank-biserial
      correlation of the rank-sum test);
    * ``test="signed-rank"``: the two-sided Wilcoxon signed-rank test (:func:`signed_rank_test`)
      on runs paired by ``pair_on`` (same run index, hence same seed / same instance; unmatched
      runs are dropped), effect size the matched-pairs rank-biserial correlation
      (:func:`rank_biserial_paired`, Kerby 2014).

    Effect sizes are computed as ``effect(reference, algorithm)``: **negative means the reference
    tends to have the lower value.** With ``correction="bh"`` the p-values of *all* comparisons in
    the returned table (all groups x algorithms) are adjusted together by Benjamini-Hochberg
    (:func:`bh_adjust`); with ``"none"`` ``p_adjusted`` equals ``p``.

    ``outcome`` follows RSCDWOA Table 5 (Zhang et al.), from the reference's point of view:
    ``"+"`` when ``p_adjusted < alpha`` and the reference is better (lower value, i.e. negative
    effect size, when ``lower_is_better``), ``"-"`` when ``p_adjusted < alpha`` and it is worse,
    ``"~"`` otherwise. The direction comes from the effect size, which is the quantity the test
    measures (medians can be equal while the distributions differ). A comparison without data (no
    usable value for one side) has NaN ``p`` and outcome ``"~"``; its ``n_*`` columns show 0.

    NaN values of ``value`` are dropped as missing (pairs with a NaN on either side for the
    signed-rank test); ``+inf`` values are results and are ranked (see the test functions).

    Args:
        df: tidy run table with ``status``, ``treatment``, the ``by`` columns, ``value`` and, for
            the signed-rank test, the ``pair_on`` column(s).
        reference: the algorithm whose point of view the outcomes take (e.g. ``"RSCDWOA"``).
        value: metric column.
        by: grouping column(s), e.g. ``"scenario"`` or ``("plan", "scenario")``; an empty sequence
            makes one group of the whole table.
        test: ``"ranksum"`` (independent samples) or ``"signed-rank"`` (paired samples).
        pair_on: column(s) identifying matched runs for ``"signed-rank"``; each key may appear at
            most once per group and algorithm.
        alpha: significance level applied to ``p_adjusted``.
        correction: ``"bh"`` (Benjamini-Hochberg over the whole table) or ``"none"``.
        treatment: column naming the algorithm.
        lower_is_better: set False for metrics where higher is better (e.g. a success rate).

    Returns:
        One row per (group, algorithm), groups sorted, algorithms in order of first appearance in
        ``df``: the ``by`` columns, ``algorithm``, ``reference``, ``test``, ``n_reference``,
        ``n_algorithm`` (for the signed-rank test both are the number of pairs), the two medians of
        the values tested, ``statistic``, ``p``, ``p_adjusted``, ``effect_size``,
        ``effect_measure`` (``"cliffs_delta"`` or ``"rank_biserial_paired"``) and ``outcome``.

    Raises:
        ValueError: unknown ``test`` / ``correction``, ``reference`` absent from ``df``, or a
            ``pair_on`` key repeated within a group and algorithm.
    """
    if test not in ("ranksum", "signed-rank"):
        raise ValueError(f"test must be 'ranksum' or 'signed-rank', not {test!r}")
    if correction not in ("bh", "none"):
        raise ValueError(f"correction must be 'bh' or 'none', not {correction!r}")
    if not 0.0 < alpha < 1.0:
        raise ValueError(f"alpha must lie in (0, 1), not {alpha}")
    by_cols = _as_columns(by)
    pair_cols = _as_columns(pair_on) if test == "signed-rank" else []
    _require_columns(df, [*by_cols, *pair_cols, treatment, value, "status"])
    if not (df[treatment] == reference).any():
        raise ValueError(f"reference {reference!r} does not occur in column {treatment!r}")

    algorithms = [a for a in pd.unique(df[treatment]) if a != reference]
    paired = test == "signed-rank"
    measure = "rank_biserial_paired" if paired else "cliffs_delta"
    rows: list[dict[str, Any]] = []
    for key, sub_all in _iter_groups(df, by_cols):
        present = set(sub_all[treatment])
        sub = sub_all[_ok_mask(sub_all)]
        ref_rows = sub[sub[treatment] == reference]
        for alg in algorithms:
            if alg not in present:
                continue
            alg_rows = sub[sub[treatment] == alg]
            if paired:
                x, y = _paired_values(ref_rows, alg_rows, value, pair_cols, key, alg, reference)
            else:
                x, y = _values(ref_rows, value), _values(alg_rows, value)
            stat = p = effect = math.nan
            if x.size and y.size:
                if paired:
                    stat, p = signed_rank_test(x, y)
                    effect = rank_biserial_paired(x, y)
                else:
                    stat, p = ranksum_test(x, y)
                    effect = cliffs_delta(x, y)
            rows.append(
                {
                    **dict(zip(by_cols, key, strict=True)),
                    "algorithm": alg,
                    "reference": reference,
                    "test": test,
                    "n_reference": int(x.size),
                    "n_algorithm": int(y.size),
                    "median_reference": _median(x),
                    "median_algorithm": _median(y),
                    "statistic": stat,
                    "p": p,
                    "effect_size": effect,
                    "effect_measure": measure,
                }
            )

    out = pd.DataFrame(rows, columns=[*by_cols, *_COMPARISON_COLUMNS])
    pvals = out["p"].to_numpy(dtype=np.float64)
    out["p_adjusted"] = bh_adjust(pvals) if correction == "bh" else pvals
    out["outcome"] = [
        _outcome(pa, eff, alpha, lower_is_better)
        for pa, eff in zip(out["p_adjusted"], out["effect_size"], strict=True)
    ]
    return out.astype({"n_reference": "int64", "n_algorithm": "int64"})


def _paired_values(
    ref_rows: pd.DataFrame,
    alg_rows: pd.DataFrame,
    value: str,
    pair_cols: list[str],
    key: tuple[Hashable, ...],
    alg: Hashable,
    reference: str,
) -> tuple[FloatArray, FloatArray]:
    """Reference and ``alg`` values on runs matched by ``pair_cols``; NaN pairs dropped."""
    for name, rows in ((reference, ref_rows), (alg, alg_rows)):
        if rows.duplicated(pair_cols).any():
            raise ValueError(
                f"pair_on={pair_cols} does not identify runs uniquely for {name!r} in group "
                f"{key}: add the missing key column(s) to `by` or `pair_on`"
            )
    merged = ref_rows[[*pair_cols, value]].merge(
        alg_rows[[*pair_cols, value]], on=pair_cols, how="inner", suffixes=("_ref", "_alg")
    )
    x = merged[f"{value}_ref"].to_numpy(dtype=np.float64)
    y = merged[f"{value}_alg"].to_numpy(dtype=np.float64)
    keep = ~(np.isnan(x) | np.isnan(y))
    return x[keep], y[keep]


def _outcome(p_adjusted: float, effect: float, alpha: float, lower_is_better: bool) -> str:
    """RSCDWOA Table 5 sign from the reference's point of view."""
    if not (p_adjusted < alpha) or not np.isfinite(effect) or effect == 0:
        return "~"
    reference_lower = effect < 0
    return "+" if reference_lower == lower_is_better else "-"


def win_tie_loss(comparison_df: pd.DataFrame) -> pd.DataFrame:
    """Count the outcomes ``"+"``, ``"~"``, ``"-"`` per algorithm (the "+/~/-" summary row).

    The bottom row of RSCDWOA Table 5 (Zhang et al.): for every competitor, in how many groups the
    reference was significantly better (``+``), not significantly different (``~``) and
    significantly worse (``-``).

    Args:
        comparison_df: output of :func:`compare_to_reference`.

    Returns:
        Indexed by algorithm (order of first appearance) with int columns ``"+"``, ``"~"``,
        ``"-"`` (all present, zero-filled) and a string column ``"+/~/-"`` such as ``"7/2/0"``.
    """
    _require_columns(comparison_df, ["algorithm", "outcome"])
    order = list(pd.unique(comparison_df["algorithm"]))
    counts = pd.crosstab(comparison_df["algorithm"], comparison_df["outcome"])
    counts = counts.reindex(index=order, columns=["+", "~", "-"], fill_value=0).astype("int64")
    counts.columns.name = None
    counts.index.name = "algorithm"
    counts["+/~/-"] = [f"{w}/{t}/{l}" for w, t, l in counts[["+", "~", "-"]].to_numpy()]
    return counts


# --------------------------------------------------------------------------------------------
# 5. Friedman test, Nemenyi post-hoc, critical difference
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class FriedmanResult:
    """Outcome of :func:`friedman_test`.

    Attributes:
        statistic: Friedman chi-square statistic (with SciPy's tie correction).
        p: its p-value (chi-square approximation with ``k - 1`` degrees of freedom).
        average_ranks: average rank of each treatment over the blocks, sorted ascending; rank 1 is
            the best (lowest value) in a block, ties get average ranks.
        n_blocks: number of blocks used ``N`` (blocks lacking a treatment are dropped).
        k: number of treatments.
        matrix: the aggregated ``N x k`` block-by-treatment values that were ranked.
    """

    statistic: float
    p: float
    average_ranks: pd.Series
    n_blocks: int
    k: int
    matrix: pd.DataFrame


def friedman_test(
    df: pd.DataFrame,
    value: str = "best_cost",
    block: str = "scenario",
    treatment: str = "algorithm",
    aggregate: str | Callable[[pd.Series], float] = "mean",
    *,
    lower_is_better: bool = True,
) -> FriedmanResult:
    """Friedman test of ``k`` treatments over ``N`` blocks, with average ranks (Demšar 2006).

    The ``status == "ok"`` runs are aggregated per (block, treatment) with ``aggregate`` (``"mean"``
    by default, e.g. the mean best cost of 10 runs on a scenario; ``"median"`` is a robust
    alternative; NaN values are skipped, ``inf`` propagates: the mean of a cell with an infinite
    run is ``inf``, which ranks last). Blocks in which a treatment has no value are dropped. The
    resulting ``N x k`` matrix goes to ``scipy.stats.friedmanchisquare`` (one sample per
    treatment), and the ranks within each block (``scipy.stats.rankdata``, ties averaged, rank 1
    = lowest value, or highest if ``lower_is_better`` is False) are averaged over blocks.

    Raises:
        ValueError: if fewer than 3 treatments or 2 complete blocks remain (SciPy's Friedman test
            needs ``k >= 3``).
    """
    _require_columns(df, [block, treatment, value, "status"])
    ok = df[_ok_mask(df)]
    cells = ok.groupby([block, treatment], sort=True)[value].agg(aggregate)
    matrix = cells.unstack(treatment).astype(np.float64)
    matrix = matrix.dropna(axis=0, how="any")
    n_blocks, k = matrix.shape
    if k < 3:
        raise ValueError(f"the Friedman test needs at least 3 treatments, got {k}")
    if n_blocks < 2:
        raise ValueError(f"the Friedman test needs at least 2 complete blocks, got {n_blocks}")
    values = matrix.to_numpy(dtype=np.float64)
    if not lower_is_better:
        values = -values
    res = sps.friedmanchisquare(*values.T)
    ranks = sps.rankdata(values, axis=1)
    average_ranks = pd.Series(ranks.mean(axis=0), index=matrix.columns, name="average_rank")
    average_ranks = average_ranks.sort_values(kind="stable")
    average_ranks.index.name = treatment
    return FriedmanResult(
        statistic=float(res.statistic),
        p=float(res.pvalue),
        average_ranks=average_ranks,
        n_blocks=int(n_blocks),
        k=int(k),
        matrix=matrix,
    )


def _rank_standard_error(k: int, n_blocks: int) -> float:
    """``sqrt(k (k + 1) / (6 N))``, the standard error of a difference of average ranks."""
    if k < 2:
        raise ValueError(f"need at least 2 treatments, got k={k}")
    if n_blocks < 1:
        raise ValueError(f"need at least 1 block, got n_blocks={n_blocks}")
    return math.sqrt(k * (k + 1) / (6.0 * n_blocks))


def critical_difference(k: int, n_blocks: int, alpha: float = 0.05) -> float:
    """Nemenyi critical difference ``CD = q_alpha sqrt(k (k + 1) / (6 N))`` (Demšar 2006, 3.2.2).

    ``q_alpha`` is the upper-``alpha`` quantile of the studentized range of ``k`` means with
    infinite degrees of freedom divided by ``sqrt(2)`` (Demšar's Table 5a: 2.569 for ``k = 4`` at
    ``alpha = 0.05``), computed with ``scipy.stats.studentized_range``. Two treatments whose
    average ranks differ by more than ``CD`` differ significantly.
    """
    if not 0.0 < alpha < 1.0:
        raise ValueError(f"alpha must lie in (0, 1), not {alpha}")
    se = _rank_standard_error(k, n_blocks)
    q_alpha = float(sps.studentized_range.ppf(1.0 - alpha, k, np.inf)) / math.sqrt(2.0)
    return q_alpha * se


def nemenyi_posthoc(
    result_or_ranks: FriedmanResult | pd.Series | Mapping[Hashable, float],
    n_blocks: int | None = None,
    k: int | None = None,
    alpha: float = 0.05,
) -> pd.DataFrame:
    """Nemenyi all-pairs post-hoc test on Friedman average ranks (Demšar 2006, Sect. 3.2.2).

    For treatments ``i, j`` with average ranks ``R_i, R_j`` over ``N`` blocks, the statistic
    ``q = |R_i - R_j| / sqrt(k (k + 1) / (6 N)) * sqrt(2)`` follows the studentized range
    distribution of ``k`` means with infinite degrees of freedom, so
    ``p = studentized_range.sf(q, k, inf)``; ``p < alpha`` exactly when ``|R_i - R_j|`` exceeds
    :func:`critical_difference`. The p-values already control the family-wise error over all
    pairs.

    Args:
        result_or_ranks: a :class:`FriedmanResult` (then ``n_blocks`` and ``k`` are taken from it)
            or the average ranks by treatment.
        n_blocks: number of blocks ``N``; required with plain ranks.
        k: number of treatments; defaults to the number of ranks given.
        alpha: significance level of the ``significant`` column and of the critical difference.

    Returns:
        Tidy, one row per unordered pair (treatments in ascending average-rank order):
        ``treatment_a``, ``treatment_b``, ``rank_a``, ``rank_b``, ``rank_difference``
        (``|R_a - R_b|``), ``q``, ``p``, ``significant`` (``p < alpha``). ``attrs`` holds
        ``critical_difference``, ``alpha``, ``n_blocks`` and ``k``. Use
        ``out.pivot(index="treatment_a", columns="treatment_b", values="p")`` for a matrix.
    """
    if isinstance(result_or_ranks, FriedmanResult):
        ranks = result_or_ranks.average_ranks
        if n_blocks is not None and n_blocks != result_or_ranks.n_blocks:
            raise ValueError("n_blocks contradicts the FriedmanResult")
        if k is not None and k != result_or_ranks.k:
            raise ValueError("k contradicts the FriedmanResult")
        n_blocks, k = result_or_ranks.n_blocks, result_or_ranks.k
    else:
        ranks = pd.Series(result_or_ranks, dtype=np.float64)
        if n_blocks is None:
            raise ValueError("n_blocks is required when average ranks are given directly")
        k = len(ranks) if k is None else k
    if len(ranks) > k:
        raise ValueError(f"{len(ranks)} ranks given for k={k} treatments")
    ranks = ranks.sort_values(kind="stable")
    se = _rank_standard_error(k, n_blocks)
    names = list(ranks.index)
    rows: list[dict[str, Any]] = []
    for i, a in enumerate(names):
        for b in names[i + 1 :]:
            diff = abs(float(ranks[a]) - float(ranks[b]))
            q = diff / se * math.sqrt(2.0)
            p = min(1.0, float(sps.studentized_range.sf(q, k, np.inf))) if q > 0 else 1.0
            rows.append(
                {
                    "treatment_a": a,
                    "treatment_b": b,
                    "rank_a": float(ranks[a]),
                    "rank_b": float(ranks[b]),
                    "rank_difference": diff,
                    "q": q,
                    "p": p,
                    "significant": p < alpha,
                }
            )
    columns = [
        "treatment_a",
        "treatment_b",
        "rank_a",
        "rank_b",
        "rank_difference",
        "q",
        "p",
        "significant",
    ]
    out = pd.DataFrame(rows, columns=columns).astype({"significant": bool})
    out.attrs.update(
        critical_difference=critical_difference(k, n_blocks, alpha),
        alpha=alpha,
        n_blocks=n_blocks,
        k=k,
    )
    return out


# --------------------------------------------------------------------------------------------
# 7. RGG-PSO+ normalized path lengths
# --------------------------------------------------------------------------------------------


def normalization_bounds(values_by_run: ArrayLike) -> tuple[float, float]:
    """``(min, max)`` over the finite values, the bounds of RGG-PSO+ Eq. 2; NaN if none is finite.

    Non-finite finals (runs that never found a feasible path: ``inf``, or NaN) are excluded: the
    paper's ``min(x)`` / ``max(x)`` are the shortest and longest *paths* found.
    """
    x = np.asarray(values_by_run, dtype=np.float64).ravel()
    finite = x[np.isfinite(x)]
    if finite.size == 0:
        return math.nan, math.nan
    return float(finite.min()), float(finite.max())


def _minmax(x: FloatArray, lo: float, hi: float, fill: float) -> FloatArray:
    out = np.full(x.shape, fill, dtype=np.float64)
    finite = np.isfinite(x)
    span = hi - lo
    out[finite] = 0.0 if span == 0 else (x[finite] - lo) / span
    return out


def normalized_lengths(values_by_run: ArrayLike, *, nonfinite: float = math.nan) -> FloatArray:
    """Min-max normalized final values of one scenario, RGG-PSO+ Eq. 2 (Liu et al. 2024).

    ``z_i = (x_i - min(x)) / (max(x) - min(x))`` where ``x`` holds the final values (path lengths
    or costs) of **all runs of all compared algorithms in one scenario together**, as in the
    paper ("distances of all paths obtained in a scenario"), so z = 0 is the best path any
    algorithm found there and z = 1 the worst.

    Rules:

    * non-finite finals (``inf``: no feasible path; NaN) are excluded from ``min`` / ``max`` and
      map to ``nonfinite`` (NaN by default; pass e.g. 5.0 for the paper's penalty);
    * if ``max == min`` (one distinct finite value), every finite value maps to 0;
    * if no value is finite, everything maps to ``nonfinite``.

    Works per scenario with ``df.groupby("scenario")["path_length"].transform(normalized_lengths)``.

    Args:
        values_by_run: final values, any shape (e.g. ``(n_algorithms, n_runs)``).
        nonfinite: value returned for non-finite inputs.

    Returns:
        float64 array of the same shape as ``values_by_run``.
    """
    x = np.asarray(values_by_run, dtype=np.float64)
    lo, hi = normalization_bounds(x)
    if math.isnan(lo):
        return np.full(x.shape, nonfinite, dtype=np.float64)
    return _minmax(x, lo, hi, nonfinite)


def normalized_history(
    histories: ArrayLike,
    lo: float,
    hi: float,
    penalty: float = 5.0,
    *,
    cumulative: bool = True,
) -> FloatArray:
    """Per-iteration normalized best value with a penalty before the first feasible path.

    RGG-PSO+ Fig. 5 (Liu et al. 2024): the best-so-far value ``g*_i`` of every run at every
    iteration is normalized with the scenario's ``lo = min(x)`` and ``hi = max(x)`` of the *final*
    values (Eq. 2, e.g. from :func:`normalization_bounds`), so early values may exceed 1; while
    the best-so-far is not finite (no feasible path yet, "absolute path lengths are infinite") the
    normalized value is the fixed ``penalty`` 5.

    Args:
        histories: ``(n_runs, n_iter)`` (or ``(n_iter,)``) best values per iteration; ``inf`` or
            NaN where no feasible path exists yet.
        lo, hi: finite normalization bounds with ``lo <= hi``; if ``hi == lo`` every finite value
            maps to 0 (the rule of :func:`normalized_lengths`).
        penalty: value for iterations without a finite best-so-far.
        cumulative: take the running minimum along iterations first (a no-op for histories that
            already are best-so-far values; turns per-iteration population bests into best-so-far).

    Returns:
        float64 array of the same shape as ``histories``; average over axis 0 for a Fig. 5 curve.
    """
    h = np.asarray(histories, dtype=np.float64)
    if h.ndim not in (1, 2):
        raise ValueError(f"histories must be (n_runs, n_iter) or (n_iter,), got shape {h.shape}")
    if not (math.isfinite(lo) and math.isfinite(hi)) or hi < lo:
        raise ValueError(f"need finite bounds lo <= hi, got lo={lo}, hi={hi}")
    if cumulative and h.size:
        h = np.minimum.accumulate(np.where(np.isnan(h), np.inf, h), axis=-1)
    return _minmax(h, lo, hi, penalty)
