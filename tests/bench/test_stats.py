"""Statistics of run tables: hand-computed cases and agreement with SciPy."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from scipy import stats as sps

from uavplan.bench.stats import (
    FriedmanResult,
    bh_adjust,
    cliffs_delta,
    compare_to_reference,
    critical_difference,
    friedman_test,
    nemenyi_posthoc,
    normalization_bounds,
    normalized_history,
    normalized_lengths,
    rank_biserial_paired,
    ranksum_test,
    signed_rank_test,
    summary_table,
    vargha_delaney_a12,
    win_tie_loss,
)

INF = math.inf


def _runs(values: dict[tuple[str, str], list[float]], status: str = "ok") -> pd.DataFrame:
    """Tidy rows from ``{(scenario, algorithm): [value per run_index]}``."""
    rows = [
        {
            "plan": "p",
            "scenario": scenario,
            "algorithm": algorithm,
            "run_index": i,
            "status": status,
            "best_cost": v,
        }
        for (scenario, algorithm), vals in values.items()
        for i, v in enumerate(vals)
    ]
    return pd.DataFrame(rows)


# ---------------------------------------------------------------- summary table


def test_summary_table_values_inf_and_error_rows() -> None:
    ok = _runs({("s1", "A"): [3.0, 1.0, 2.0, 6.0], ("s1", "B"): [5.0, INF, 4.0]})
    bad = _runs({("s1", "A"): [-100.0], ("s1", "B"): [-100.0], ("s1", "C"): [7.0]}, "error")
    table = summary_table(pd.concat([ok, bad], ignore_index=True))
    assert list(table.columns) == [
        "scenario",
        "algorithm",
        "best",
        "worst",
        "mean",
        "std",
        "median",
        "n",
        "n_finite",
    ]
    a = table.set_index("algorithm").loc["A"]
    assert (a.best, a.worst, a["mean"], a["median"]) == (1.0, 6.0, 3.0, 2.5)
    assert a["std"] == pytest.approx(np.std([3.0, 1.0, 2.0, 6.0], ddof=1))
    assert (a.n, a.n_finite) == (4, 4)
    b = table.set_index("algorithm").loc["B"]
    assert (b.best, b.worst, b["mean"], b["median"]) == (4.0, INF, INF, 5.0)
    assert math.isnan(b["std"])
    assert (b.n, b.n_finite) == (3, 2)
    # an algorithm whose runs all errored still shows, with n = 0
    c = table.set_index("algorithm").loc["C"]
    assert c.n == 0 and math.isnan(c.best)
    assert table["n"].dtype == np.int64


def test_summary_table_drops_nan_and_groups_by_one_column() -> None:
    df = _runs({("s1", "A"): [1.0, math.nan, 3.0], ("s2", "A"): [5.0]})
    table = summary_table(df, by="scenario")
    assert list(table["scenario"]) == ["s1", "s2"]
    assert table.loc[0, "n"] == 2 and table.loc[0, "mean"] == 2.0
    assert table.loc[1, "n"] == 1 and math.isnan(table.loc[1, "std"])


# ---------------------------------------------------------------- effect sizes


def test_cliffs_delta_and_a12_hand_cases() -> None:
    assert cliffs_delta([1, 2, 3], [4, 5, 6]) == -1.0
    assert cliffs_delta([4, 5, 6], [1, 2, 3]) == 1.0
    assert vargha_delaney_a12([1, 2, 3], [4, 5, 6]) == 0.0
    assert vargha_delaney_a12([4, 5, 6], [1, 2, 3]) == 1.0
    assert cliffs_delta([1, 2], [1, 2]) == 0.0
    assert vargha_delaney_a12([1, 2], [1, 2]) == 0.5
    # with inf and ties: pairs (a > b, a < b, tie) = (2, 4, 2) of 8
    a, b = [1.0, 2.0, 3.0, INF], [2.0, INF]
    assert cliffs_delta(a, b) == pytest.approx(-0.25)
    assert vargha_delaney_a12(a, b) == pytest.approx(0.375)


def test_effect_sizes_agree_with_mannwhitney_u() -> None:
    rng = np.random.default_rng(3)
    a = rng.integers(0, 6, 12).astype(float)
    b = rng.integers(1, 8, 9).astype(float)
    u = sps.mannwhitneyu(a, b).statistic
    assert cliffs_delta(a, b) == pytest.approx(2 * u / (a.size * b.size) - 1)
    assert vargha_delaney_a12(a, b) == pytest.approx(u / (a.size * b.size))


def test_rank_biserial_paired_hand_case() -> None:
    # d = [-1, 0, 2, -4]: zero dropped, |d| ranks 1, 2, 3; R+ = 2, R- = 4 -> -1/3
    assert rank_biserial_paired([1, 2, 3, 4], [2, 2, 1, 8]) == pytest.approx(-1 / 3)
    assert rank_biserial_paired([1, 2, 3], [2, 3, 4]) == -1.0
    assert rank_biserial_paired([1, 2, 3], [1, 2, 3]) == 0.0
    # inf vs inf is a zero difference, inf vs finite the largest one
    assert rank_biserial_paired([INF, 1.0, 5.0], [INF, 2.0, INF]) == pytest.approx(-1.0)
    assert rank_biserial_paired([INF, 1.0], [3.0, 2.0]) == pytest.approx((2 - 1) / 3)


def test_effect_sizes_refuse_nan_and_empty() -> None:
    with pytest.raises(ValueError):
        cliffs_delta([1.0, math.nan], [2.0])
    with pytest.raises(ValueError):
        vargha_delaney_a12([], [2.0])
    with pytest.raises(ValueError):
        rank_biserial_paired([1.0, 2.0], [1.0])


# ---------------------------------------------------------------- tests vs SciPy


def test_ranksum_matches_scipy_mannwhitneyu() -> None:
    rng = np.random.default_rng(0)
    for n1, n2, ties in [(5, 6, False), (10, 10, False), (12, 9, True), (30, 25, False)]:
        a = rng.normal(size=n1)
        b = rng.normal(0.7, size=n2)
        if ties:
            a, b = np.round(a), np.round(b)
        ref = sps.mannwhitneyu(a, b, alternative="two-sided", method="auto")
        stat, p = ranksum_test(a, b)
        assert stat == pytest.approx(ref.statistic)
        assert p == pytest.approx(ref.pvalue, rel=1e-12)


def test_ranksum_inf_same_as_large_finite_and_all_equal() -> None:
    a = [1.0, 2.0, INF, 3.0, INF]
    b = [4.0, INF, 5.0, 6.0, 7.0, 8.0]
    big = [1e9 if math.isinf(v) else v for v in a], [1e9 if math.isinf(v) else v for v in b]
    ref = sps.mannwhitneyu(*big, alternative="two-sided", method="auto")
    assert ranksum_test(a, b) == pytest.approx((ref.statistic, ref.pvalue))
    assert ranksum_test([INF, INF], [INF, INF, INF]) == (3.0, 1.0)
    assert ranksum_test([2.0, 2.0], [2.0]) == (1.0, 1.0)


def test_signed_rank_matches_scipy_wilcoxon() -> None:
    rng = np.random.default_rng(1)
    for n in (6, 10, 25, 60):
        a = rng.normal(size=n)
        b = a + rng.normal(0.4, 1.0, size=n)
        ref = sps.wilcoxon(a, b, zero_method="wilcox")
        stat, p = signed_rank_test(a, b)
        assert stat == pytest.approx(ref.statistic)
        assert p == pytest.approx(ref.pvalue, rel=1e-12)
    # with zero differences and ties
    a = np.array([1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0])
    b = np.array([1.0, 3.0, 5.0, 4.0, 7.0, 9.0, 9.0, 9.0])
    ref = sps.wilcoxon(a, b, zero_method="wilcox")
    assert signed_rank_test(a, b) == pytest.approx((ref.statistic, ref.pvalue))


def test_signed_rank_inf_and_all_equal() -> None:
    assert signed_rank_test([1.0, 2.0, INF], [1.0, 2.0, INF]) == (0.0, 1.0)
    a = [1.0, 2.0, 3.0, INF, INF, 4.0, 5.0]
    b = [2.0, 4.0, 6.0, INF, 8.0, 9.0, INF]
    # inf-inf is a zero difference; inf vs finite ties above all finite |d|
    d = np.array([-1.0, -2.0, -3.0, 0.0, 100.0, -5.0, -100.0])
    ref = sps.wilcoxon(d, zero_method="wilcox")
    stat, p = signed_rank_test(a, b)
    assert np.isfinite(p)
    assert (stat, p) == pytest.approx((ref.statistic, ref.pvalue))


# ---------------------------------------------------------------- BH


def test_bh_adjust_hand_case_and_nan() -> None:
    # sorted p 0.01, 0.03, 0.04, 0.20 -> m p / i = 0.04, 0.06, 0.0533, 0.20 -> step-up min
    expected = [0.04, 0.16 / 3, 0.16 / 3, 0.20]
    np.testing.assert_allclose(bh_adjust([0.01, 0.04, 0.03, 0.20]), expected)
    out = bh_adjust([0.01, math.nan, 0.04, 0.03, 0.20])
    assert math.isnan(out[1])
    np.testing.assert_allclose(out[[0, 2, 3, 4]], expected)
    assert bh_adjust([]).shape == (0,)
    assert np.isnan(bh_adjust([math.nan, math.nan])).all()


# ---------------------------------------------------------------- compare_to_reference


def _comparison_table() -> pd.DataFrame:
    ok = _runs(
        {
            ("s1", "R"): [1, 2, 3, 4, 5, 6, 7, 8],
            ("s1", "A"): [11, 12, 13, 14, 15, 16, 17, INF],  # R clearly lower: "+"
            ("s1", "B"): [-8, -7, -6, -5, -4, -3, -2, -1],  # R clearly higher: "-"
            ("s1", "C"): [1.5, 2.5, 3.5, 4.5, 5.5, 6.5, 7.5, 0.5],  # no difference: "~"
            ("s2", "R"): [INF, INF, INF, INF, INF, INF, INF, INF],
            ("s2", "A"): [1, 2, 3, 4, 5, 6, 7, 8],  # R never feasible: "-"
            ("s2", "B"): [INF, INF, INF, INF, INF, INF, INF, INF],  # all tied: "~"
        }
    )
    # error rows that would flip s1/A and s1/B if they were used
    bad = _runs({("s1", "A"): [-1000.0] * 20, ("s1", "B"): [1000.0] * 20}, "error")
    bad["run_index"] += 100
    return pd.concat([ok, bad], ignore_index=True)


def test_compare_to_reference_ranksum_outcomes_and_scipy_p() -> None:
    df = _comparison_table()
    out = compare_to_reference(df, "R")
    key = out.set_index(["scenario", "algorithm"])
    assert list(out["scenario"]) == ["s1", "s1", "s1", "s2", "s2"]
    assert key.loc[("s1", "A"), "outcome"] == "+"
    assert key.loc[("s1", "B"), "outcome"] == "-"
    assert key.loc[("s1", "C"), "outcome"] == "~"
    assert key.loc[("s2", "A"), "outcome"] == "-"
    assert key.loc[("s2", "B"), "outcome"] == "~"
    assert key.loc[("s1", "A"), "effect_size"] == -1.0
    assert key.loc[("s1", "B"), "effect_size"] == 1.0
    assert key.loc[("s1", "A"), "effect_measure"] == "cliffs_delta"
    # error rows are excluded
    assert (out["n_algorithm"] == 8).all() and (out["n_reference"] == 8).all()
    assert key.loc[("s1", "A"), "median_algorithm"] == 14.5
    # p is SciPy's; p_adjusted is BH over the whole table
    ref = sps.mannwhitneyu(
        [1, 2, 3, 4, 5, 6, 7, 8], [-8, -7, -6, -5, -4, -3, -2, -1], alternative="two-sided"
    )
    assert key.loc[("s1", "B"), "p"] == pytest.approx(ref.pvalue)
    np.testing.assert_allclose(out["p_adjusted"], sps.false_discovery_control(out["p"]))
    none = compare_to_reference(df, "R", correction="none")
    np.testing.assert_array_equal(none["p_adjusted"], none["p"])


def test_compare_to_reference_signed_rank() -> None:
    df = _comparison_table().sample(frac=1.0, random_state=0)  # pairing must not rely on order
    out = compare_to_reference(df, "R", test="signed-rank")
    key = out.set_index(["scenario", "algorithm"])
    assert key.loc[("s1", "A"), "outcome"] == "+"
    assert key.loc[("s1", "B"), "outcome"] == "-"
    assert key.loc[("s1", "C"), "outcome"] == "~"
    assert key.loc[("s1", "A"), "effect_measure"] == "rank_biserial_paired"
    assert key.loc[("s1", "A"), "effect_size"] == -1.0
    assert key.loc[("s2", "B"), "p"] == 1.0
    ref = sps.wilcoxon([1, 2, 3, 4, 5, 6, 7, 8], [1.5, 2.5, 3.5, 4.5, 5.5, 6.5, 7.5, 0.5])
    assert key.loc[("s1", "C"), "p"] == pytest.approx(ref.pvalue)
    assert key.loc[("s1", "C"), "statistic"] == pytest.approx(ref.statistic)
    # unmatched runs are dropped from the pairs
    partial = df[~((df["algorithm"] == "A") & (df["run_index"] == 0))]
    out2 = compare_to_reference(partial, "R", test="signed-rank", correction="none")
    row = out2.set_index(["scenario", "algorithm"]).loc[("s1", "A")]
    assert (row.n_reference, row.n_algorithm) == (7, 7)


def test_compare_to_reference_errors_and_empty_sides() -> None:
    df = _comparison_table()
    with pytest.raises(ValueError, match="reference"):
        compare_to_reference(df, "nope")
    with pytest.raises(ValueError, match="pair_on"):
        compare_to_reference(df, "R", test="signed-rank", by=[])  # run_index repeats over s1, s2
    only_errors = pd.concat([df, _runs({("s1", "D"): [1.0, 2.0]}, "error")], ignore_index=True)
    out = compare_to_reference(only_errors, "R")
    row = out.set_index(["scenario", "algorithm"]).loc[("s1", "D")]
    assert row.n_algorithm == 0 and math.isnan(row.p) and row.outcome == "~"
    assert ("s2", "D") not in out.set_index(["scenario", "algorithm"]).index


def test_win_tie_loss_counts() -> None:
    out = compare_to_reference(_comparison_table(), "R")
    wtl = win_tie_loss(out)
    assert list(wtl.index) == ["A", "B", "C"]
    assert wtl.loc["A", ["+", "~", "-"]].tolist() == [1, 0, 1]
    assert wtl.loc["B", ["+", "~", "-"]].tolist() == [0, 1, 1]
    assert wtl.loc["C", ["+", "~", "-"]].tolist() == [0, 1, 0]
    assert wtl.loc["C", "+/~/-"] == "0/1/0"


# ---------------------------------------------------------------- Friedman / Nemenyi


def _friedman_frame() -> pd.DataFrame:
    # block x treatment (two runs per cell, mean = listed value)
    cells = {
        "b1": {"A": 1.0, "B": 2.0, "C": 3.0},
        "b2": {"A": 2.0, "B": 1.0, "C": 3.0},
        "b3": {"A": 1.0, "B": 3.0, "C": 3.0},
    }
    rows = []
    for block, cell in cells.items():
        for alg, v in cell.items():
            for i, dv in enumerate((-0.25, 0.25)):
                rows.append(
                    {
                        "scenario": block,
                        "algorithm": alg,
                        "run_index": i,
                        "status": "ok",
                        "best_cost": v + dv,
                    }
                )
    rows.append(
        {"scenario": "b1", "algorithm": "A", "run_index": 9, "status": "error", "best_cost": 99.0}
    )
    # a block missing treatment C is dropped
    rows.append(
        {"scenario": "b4", "algorithm": "A", "run_index": 0, "status": "ok", "best_cost": 1.0}
    )
    return pd.DataFrame(rows)


def test_friedman_average_ranks_hand_case_and_scipy_statistic() -> None:
    res = friedman_test(_friedman_frame(), "best_cost")
    assert isinstance(res, FriedmanResult)
    assert (res.n_blocks, res.k) == (3, 3)
    # ranks: b1 1,2,3; b2 2,1,3; b3 1,2.5,2.5
    assert list(res.average_ranks.index) == ["A", "B", "C"]
    np.testing.assert_allclose(res.average_ranks.to_numpy(), [4 / 3, 5.5 / 3, 8.5 / 3])
    ref = sps.friedmanchisquare([1.0, 2.0, 1.0], [2.0, 1.0, 3.0], [3.0, 3.0, 3.0])
    assert res.statistic == pytest.approx(ref.statistic)
    assert res.p == pytest.approx(ref.pvalue)


def test_friedman_inf_ranks_last_and_needs_three_treatments() -> None:
    df = _runs(
        {
            ("s1", "A"): [1.0],
            ("s1", "B"): [INF],
            ("s1", "C"): [2.0],
            ("s2", "A"): [1.0],
            ("s2", "B"): [3.0],
            ("s2", "C"): [INF],
        }
    )
    res = friedman_test(df, "best_cost")
    assert res.average_ranks.to_dict() == {"A": 1.0, "B": 2.5, "C": 2.5}
    with pytest.raises(ValueError, match="3 treatments"):
        friedman_test(df[df["algorithm"] != "C"], "best_cost")


def test_critical_difference_matches_demsar_table() -> None:
    # Demšar (2006) Table 5a: q_0.05 = 2.569 for k = 4, 2.343 for k = 3; q_0.10 = 2.291 for k = 4
    assert critical_difference(4, 10, 0.05) == pytest.approx(2.569 * math.sqrt(20 / 60), abs=1e-3)
    assert critical_difference(4, 10, 0.05) == pytest.approx(1.483, abs=1e-3)
    assert critical_difference(3, 1, 0.05) == pytest.approx(2.343 * math.sqrt(2), abs=1e-3)
    assert critical_difference(4, 10, 0.10) == pytest.approx(2.291 * math.sqrt(20 / 60), abs=1e-3)


def test_nemenyi_posthoc_pairs() -> None:
    ranks = pd.Series({"B": 2.5, "A": 1.0, "D": 3.5, "C": 3.0})
    out = nemenyi_posthoc(ranks, n_blocks=10)
    assert len(out) == 6
    assert out.attrs["critical_difference"] == pytest.approx(1.483, abs=1e-3)
    pair = out.set_index(["treatment_a", "treatment_b"])
    assert pair.loc[("A", "B"), "rank_difference"] == 1.5
    # |dR| > CD <=> p < alpha
    np.testing.assert_array_equal(
        out["significant"], out["rank_difference"] > out.attrs["critical_difference"]
    )
    assert pair.loc[("A", "D"), "significant"] and pair.loc[("A", "B"), "significant"]
    assert not pair.loc[("B", "D"), "significant"]
    se = math.sqrt(4 * 5 / 60)
    assert pair.loc[("B", "D"), "p"] == pytest.approx(
        sps.studentized_range.sf(1.0 / se * math.sqrt(2), 4, np.inf)
    )
    # a rank difference equal to CD has p = alpha
    cd = critical_difference(4, 10)
    edge = nemenyi_posthoc({"x": 1.0, "y": 1.0 + cd}, n_blocks=10, k=4)
    assert edge.loc[0, "p"] == pytest.approx(0.05, abs=1e-6)
    # from a FriedmanResult
    res = friedman_test(_friedman_frame(), "best_cost")
    from_res = nemenyi_posthoc(res)
    assert from_res.attrs["k"] == 3 and from_res.attrs["n_blocks"] == 3
    assert ((from_res["p"] > 0) & (from_res["p"] <= 1)).all()


# ---------------------------------------------------------------- RGG-PSO+ normalization


def test_normalized_lengths_eq2() -> None:
    z = normalized_lengths([[10.0, 12.0, INF], [14.0, 11.0, 10.0]])
    np.testing.assert_allclose(z[0, :2], [0.0, 0.5])
    assert math.isnan(z[0, 2])
    np.testing.assert_allclose(z[1], [1.0, 0.25, 0.0])
    assert normalization_bounds([10.0, INF, 14.0, math.nan]) == (10.0, 14.0)
    np.testing.assert_array_equal(normalized_lengths([3.0, 3.0, INF], nonfinite=5.0), [0, 0, 5])
    assert np.isnan(normalized_lengths([INF, INF])).all()
    df = pd.DataFrame({"scenario": ["a", "a", "b", "b"], "path_length": [1.0, 3.0, 5.0, 6.0]})
    per = df.groupby("scenario")["path_length"].transform(normalized_lengths)
    np.testing.assert_allclose(per, [0.0, 1.0, 0.0, 1.0])


def test_normalized_history_penalty_before_first_feasible() -> None:
    h = np.array([[INF, INF, 20.0, 18.0, 19.0], [INF, 30.0, 12.0, 10.0, 10.0]])
    z = normalized_history(h, lo=10.0, hi=18.0)
    np.testing.assert_allclose(z[0], [5.0, 5.0, 1.25, 1.0, 1.0])  # running min, may exceed 1
    np.testing.assert_allclose(z[1], [5.0, 2.5, 0.25, 0.0, 0.0])
    raw = normalized_history(h, lo=10.0, hi=18.0, penalty=7.0, cumulative=False)
    assert raw[0, 4] == pytest.approx(9 / 8) and raw[0, 0] == 7.0
    np.testing.assert_array_equal(normalized_history([INF, 4.0], 4.0, 4.0), [5.0, 0.0])
    with pytest.raises(ValueError):
        normalized_history(h, lo=math.nan, hi=1.0)
