"""Figures of a sweep: convergence curves (raw and normalized), box plots, best paths.

Every function takes the tidy run table (``ResultStore.read()``) and returns a matplotlib
figure; :mod:`uavplan.bench.report` saves them.
"""

from __future__ import annotations

import warnings
from types import SimpleNamespace
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from uavplan.bench.stats import normalization_bounds, normalized_history


def _ok(df: pd.DataFrame) -> pd.DataFrame:
    return df[df["status"] == "ok"]


def _stack(histories: pd.Series) -> np.ndarray:
    """Ragged histories -> (n_runs, n_iter) padded with each run's last value."""
    hs = [np.asarray(h, dtype=np.float64) for h in histories if h is not None and len(h)]
    if not hs:
        return np.zeros((0, 0))
    n = max(len(h) for h in hs)
    out = np.empty((len(hs), n))
    for i, h in enumerate(hs):
        out[i, : len(h)] = h
        out[i, len(h) :] = h[-1]
    return out


def _grid(n: int) -> tuple[Figure, list[Any]]:
    cols = min(n, 3)
    rows = int(np.ceil(n / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(5.2 * cols, 3.8 * rows), squeeze=False)
    flat = list(axes.ravel())
    for ax in flat[n:]:
        ax.set_visible(False)
    return fig, flat[:n]


def convergence_figure(
    df: pd.DataFrame, normalized: bool = False, history: str = "history"
) -> Figure | None:
    """Best-so-far value over iterations per scenario: median over runs with the 25-75 %
    band (raw, log scale), or RGG-PSO+'s normalized form (Eq. 2 with the final values of all
    runs of the scenario; penalty 5 while no feasible path exists, Fig. 5)."""
    ok = _ok(df)
    if ok.empty or history not in ok:
        return None
    by_evals = "evaluations_history" in ok and ok["evaluations_history"].notna().all()
    scenarios = sorted(ok["scenario"].unique())
    fig, axes = _grid(len(scenarios))
    for ax, sc in zip(axes, scenarios, strict=True):
        sub = ok[ok["scenario"] == sc]
        positive = False
        if normalized:
            stacks = [_stack(g[history]) for _, g in sub.groupby("algorithm")]
            finals = [H[:, -1] for H in stacks if H.size]
            lo, hi = normalization_bounds(np.concatenate(finals) if finals else np.zeros(0))
        for alg, g in sub.groupby("algorithm", sort=True):
            H = _stack(g[history])
            if H.size == 0:
                continue
            if normalized:
                if np.isnan(lo):
                    continue
                H = normalized_history(H, lo, hi, 5.0)
            x = np.arange(1, H.shape[1] + 1, dtype=np.float64)
            if by_evals:
                E = _stack(g["evaluations_history"])
                if E.shape == H.shape:
                    x = E.mean(axis=0)
            with np.errstate(invalid="ignore"), warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                med = np.nanmedian(np.where(np.isfinite(H), H, np.nan), axis=0)
                q1 = np.nanpercentile(np.where(np.isfinite(H), H, np.nan), 25, axis=0)
                q3 = np.nanpercentile(np.where(np.isfinite(H), H, np.nan), 75, axis=0)
            if not np.isfinite(med).any():  # every run infeasible throughout: no line to draw
                continue
            positive = positive or bool(np.any(med > 0))
            line = ax.plot(x, med, lw=1.6, label=f"{alg} (n={len(H)})")[0]
            ax.fill_between(x, q1, q3, color=line.get_color(), alpha=0.2, lw=0)
        ax.set_title(str(sc))
        ax.set_xlabel("evaluations" if by_evals else "iteration")
        ax.set_ylabel("normalized best value" if normalized else "best cost so far")
        if not normalized and positive:  # nothing finite to draw (every run infeasible)
            ax.set_yscale("log")
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=7)
        else:
            ax.text(0.5, 0.5, "no finite value in any run\n(every run infeasible)",
                    ha="center", va="center", transform=ax.transAxes, color="#555")  # fmt: skip
        ax.grid(alpha=0.3)
    fig.suptitle(
        "Convergence, median and 25-75 % over runs" + (" (normalized)" if normalized else "")
    )
    fig.tight_layout()
    return fig


def box_figure(df: pd.DataFrame, value: str = "best_cost") -> Figure | None:
    """Box plots of ``value`` per algorithm and scenario (PPSwarm Fig. 6); runs with an
    infinite value are counted in the label, not drawn."""
    ok = _ok(df)
    if ok.empty or value not in ok:
        return None
    scenarios = sorted(ok["scenario"].unique())
    fig, axes = _grid(len(scenarios))
    for ax, sc in zip(axes, scenarios, strict=True):
        sub = ok[ok["scenario"] == sc]
        labels, data = [], []
        for alg, g in sub.groupby("algorithm", sort=True):
            v = g[value].to_numpy(dtype=np.float64)
            fin = v[np.isfinite(v)]
            n_inf = int(np.sum(~np.isfinite(v)))
            labels.append(f"{alg}" + (f"\n({n_inf} inf)" if n_inf else ""))
            data.append(fin if len(fin) else np.array([np.nan]))
        ax.boxplot(data, tick_labels=labels)
        ax.set_title(str(sc))
        ax.set_ylabel(value)
        ax.grid(alpha=0.3)
    fig.suptitle(f"{value} over runs")
    fig.tight_layout()
    return fig


def best_paths_figure(df: pd.DataFrame) -> Figure | None:
    """The best run's path of each algorithm, per scenario, over the scenario's top view."""
    from uavplan.scenarios import resolve
    from uavplan.viz.figures import draw_top

    ok = _ok(df)
    if ok.empty or "waypoints" not in ok:
        return None
    scenarios = sorted(ok["scenario"].unique())
    fig, axes = _grid(len(scenarios))
    for ax, sc in zip(axes, scenarios, strict=True):
        try:
            scenario = resolve(sc)
        except Exception:
            ax.set_visible(False)
            continue
        paths = []
        for alg, g in ok[ok["scenario"] == sc].groupby("algorithm", sort=True):
            g = g[g["waypoints"].notna()]
            if g.empty:
                continue
            best = g.loc[g["best_cost"].astype(float).idxmin()]
            w = np.asarray(best["waypoints"], dtype=np.float64).reshape(-1, int(best["n_dim"]))
            paths.append(
                SimpleNamespace(waypoints=w, uav_id=str(alg), feasible=bool(best["feasible"]))
            )
        draw_top(ax, scenario, paths, colorbar=False)
        ax.set_title(f"{sc}: best run per algorithm")
    fig.tight_layout()
    return fig
