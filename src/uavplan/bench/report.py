"""``uavplan report DIR``: one self-contained HTML report and a Markdown summary of a sweep.

The HTML embeds its figures (base64 PNG) and tables, so it opens offline as a single file; the
figures are also written as PNG files under ``DIR/figures/``. Everything is computed from the
results store only.
"""

from __future__ import annotations

import base64
import html
import io
import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from uavplan.bench import plots, stats
from uavplan.bench.catalog import find_plan
from uavplan.bench.store import ResultStore
from uavplan.io.atomic import write_bytes_atomic, write_text_atomic

_CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,sans-serif;margin:2em auto;max-width:1200px;
color:#222;padding:0 1em}
table{border-collapse:collapse;margin:0.6em 0 1.4em;font-size:13px}
th,td{border:1px solid #ccc;padding:3px 8px;text-align:right}
th{background:#f2f2f2} td:first-child,th:first-child{text-align:left}
img{max-width:100%;border:1px solid #ddd;margin:0.5em 0}
.note{color:#555;font-size:13px} code{background:#f5f5f5;padding:0 3px}
.scroll{overflow-x:auto;max-width:100%}
"""


def _fmt(v: Any) -> str:
    if isinstance(v, float | np.floating):
        v = float(v)
        if math.isnan(v):
            return ""
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        if v != 0 and (abs(v) >= 1e6 or abs(v) < 1e-3):
            return f"{v:.3e}"
        return f"{v:,.4g}" if abs(v) < 1e4 else f"{v:,.1f}"
    return str(v)


def _nanmean(s: pd.Series) -> float:
    """Mean of the non-missing values (NaN when there are none), without a warning."""
    v = np.asarray(s, dtype=np.float64)
    v = v[~np.isnan(v)]
    return float(v.mean()) if len(v) else math.nan


def _html_table(df: pd.DataFrame) -> str:
    d = df.reset_index() if not isinstance(df.index, pd.RangeIndex) else df
    head = "".join(f"<th>{html.escape(str(c))}</th>" for c in d.columns)
    rows = "".join(
        "<tr>" + "".join(f"<td>{html.escape(_fmt(v))}</td>" for v in r) + "</tr>"
        for r in d.itertuples(index=False)
    )
    return f"<div class='scroll'><table><tr>{head}</tr>{rows}</table></div>"  # wide: it scrolls


def _md_table(df: pd.DataFrame) -> str:
    d = df.reset_index() if not isinstance(df.index, pd.RangeIndex) else df
    cols = [str(c) for c in d.columns]
    lines = ["| " + " | ".join(cols) + " |", "|" + "|".join("---" for _ in cols) + "|"]
    for r in d.itertuples(index=False):
        lines.append("| " + " | ".join(_fmt(v) for v in r) + " |")
    return "\n".join(lines)


def _png(fig: Any) -> bytes:
    import matplotlib.pyplot as plt

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100)
    plt.close(fig)
    return buf.getvalue()


#: Above this many scenarios the per-scenario tables and figures give way to pooled ones.
MAX_SCENARIO_ROWS = 12


def _pooled_sections(df: pd.DataFrame) -> list[tuple[str, str, Any]]:
    """Per-algorithm summaries over every scenario (for plans with many scenarios)."""
    ok = df[df["status"] == "ok"]
    table = ok.groupby("algorithm").agg(
        runs=("run_id", "size"),
        scenarios=("scenario", "nunique"),
        feasible=("feasible", lambda s: float(np.mean(s.astype(bool)))),
        first_feasible_iteration=("first_feasible_iteration", _nanmean),
        evaluations=("evaluations", "mean"),
        wall_time_s=("wall_time", "mean"),
    )
    gate = _gate_columns(ok, ["algorithm"])
    if gate is not None:
        table = table.join(gate)
    note = (
        f"{ok['scenario'].nunique()} scenarios: per-scenario tables and figures are left out; "
        "means over every run of every scenario" + GATE_NOTE * (gate is not None)
    )
    return [("Runs per algorithm", note, table)]


GATE_NOTE = (
    "; verified = runs whose plan, called feasible, the independent verifier passes; rejected "
    "= runs where it rejects something called feasible (must be 0); band_paper_criterion = "
    "polylines feasible under the papers' altitude criterion (the band at the waypoints) whose "
    "band the verifier rejects along whole segments (what is flown is gated on it)"
)


def _gate_columns(ok: pd.DataFrame, by: list[str]) -> pd.DataFrame | None:
    """The verifier's verdicts per group (``verifier_ok``, see :mod:`uavplan.bench.kinds`):
    runs verified and runs rejected; None for runs without the column (benchmark functions,
    results stored before it existed)."""
    if "verifier_ok" not in ok or ok["verifier_ok"].isna().all():
        return None
    v = ok["verifier_ok"].astype("boolean")
    g = pd.DataFrame({"verified": v.eq(True), "rejected": v.eq(False)}).fillna(False).astype(int)
    if "band_paper_criterion" in ok:
        g["band_paper_criterion"] = ok["band_paper_criterion"].fillna(0).astype(int)
    return g.groupby([ok[c] for c in by]).sum()


def build_sections(df: pd.DataFrame, manifest: dict[str, Any]) -> list[tuple[str, str, Any]]:
    """(title, note, DataFrame) sections of the report."""
    sections: list[tuple[str, str, Any]] = []
    ok = df[df["status"] == "ok"]
    if ok.empty:
        return sections
    if ok["scenario"].nunique() > MAX_SCENARIO_ROWS:
        return sections + _pooled_sections(df)
    sections.append(
        (
            "Final cost",
            "best / worst / mean / std over runs (PPSwarm Table 3 layout)",
            stats.summary_table(df, "best_cost"),
        )
    )
    extra = ok.groupby(["scenario", "algorithm"]).agg(
        runs=("run_id", "size"),
        feasible=("feasible", lambda s: float(np.mean(s.astype(bool)))),
        first_feasible_iteration=(
            "first_feasible_iteration",
            _nanmean,
        ),
        evaluations=("evaluations", "mean"),
        wall_time_s=("wall_time", "mean"),
    )
    if "path_length" in ok and ok["path_length"].notna().any():
        extra["path_length"] = ok.groupby(["scenario", "algorithm"])["path_length"].mean()
    gate = _gate_columns(ok, ["scenario", "algorithm"])
    if gate is not None:
        extra = extra.join(gate)
    sections.append(
        (
            "Feasibility, F-Measure and effort",
            "feasible = share of runs whose final path is feasible (exact, continuous segments); "
            "first_feasible_iteration = mean 1-based iteration of the first feasible candidate "
            "(RGG-PSO+'s F-Measure counts the iterations before it); wall time per run in seconds"
            + GATE_NOTE
            * (gate is not None),
            extra,
        )
    )
    ref = str(manifest.get("reference"))
    algs = sorted(ok["algorithm"].unique())
    if ref in algs and len(algs) > 1:
        cmp = stats.compare_to_reference(df, ref, "best_cost", by="scenario", test="ranksum")
        sections.append(
            (
                f"Wilcoxon rank-sum tests against {ref}",
                "two-sided, Benjamini-Hochberg adjusted over all rows; effect = Cliff's delta "
                f"(negative: {ref} lower); outcome from {ref}'s view: + better, ~ no significant "
                "difference, - worse (RSCDWOA Table 5 style)",
                cmp,
            )
        )
        sections.append((f"+/~/- of {ref}", "", stats.win_tie_loss(cmp)))
    n_sc = ok["scenario"].nunique()
    if n_sc >= 2 and len(algs) >= 3:
        try:
            fr = stats.friedman_test(df, "best_cost", block="scenario")
            ranks = fr.average_ranks.rename("average rank").to_frame()
            note = (
                f"Friedman chi2 = {fr.statistic:.3f}, p = {fr.p:.3g} over {fr.n_blocks} "
                f"scenarios (mean cost per scenario); Nemenyi CD = "
                f"{stats.critical_difference(fr.k, fr.n_blocks):.3f}"
            )
            sections.append(("Friedman test and average ranks", note, ranks))
            sections.append(("Nemenyi post-hoc", "", stats.nemenyi_posthoc(fr)))
        except ValueError as exc:
            sections.append(("Friedman test", f"not computed: {exc}", None))
    return sections


def write_report(folder: str | Path) -> tuple[Path, Path]:
    """Write ``folder/report.html`` and ``folder/report.md`` (and ``folder/figures/*.png``)."""
    root = Path(folder)
    store = ResultStore(root)
    df = store.read()
    manifest: dict[str, Any] = {}
    if (root / "manifest.json").exists():
        manifest = json.loads((root / "manifest.json").read_text())
    if manifest.get("runs") and not df.empty and "run_index" in df:
        # the last sweep asked for fewer runs per cell than the folder holds: report those
        df = df[df["run_index"] < int(manifest["runs"])]
    figdir = root / "figures"
    figdir.mkdir(exist_ok=True)
    figures: list[tuple[str, str, bytes]] = []
    makers = [
        ("convergence", "Convergence (best cost so far)", lambda: plots.convergence_figure(df)),
        (
            "convergence_normalized",
            "Normalized convergence (RGG-PSO+ Eq. 2; penalty 5 before the first feasible path)",
            lambda: plots.convergence_figure(
                df,
                normalized=True,
                history="feasible_history" if "feasible_history" in df else "history",
            ),
        ),
        ("boxplot", "Final cost over runs (PPSwarm Fig. 6 style)", lambda: plots.box_figure(df)),
        ("best_paths", "Best run's path per algorithm", lambda: plots.best_paths_figure(df)),
    ]
    plan = str(manifest.get("plan", ""))
    many = not df.empty and df["scenario"].nunique() > MAX_SCENARIO_ROWS
    for name, title, make in makers:
        fig = make() if not df.empty and not many else None
        if fig is not None:
            data = _png(fig)
            write_bytes_atomic(figdir / f"{name}.png", data)
            figures.append((name, title, data))

    sections = build_sections(df, manifest)
    registered = find_plan(plan)
    maker = registered.report if registered is not None else None
    if maker is not None and not df.empty:
        paper_sections, paper_figures = maker(df, plan)
        sections = paper_sections + sections
        for name, title, fig in paper_figures:
            data = _png(fig)
            write_bytes_atomic(figdir / f"{name}.png", data)
            figures.insert(0, (name, title, data))
    n = len(df)
    n_err = int((df["status"] != "ok").sum()) if n else 0
    meta_rows = {
        "plan": manifest.get("plan", ""),
        "scale": manifest.get("scale", ""),
        "root seed": manifest.get("root_seed", ""),
        "runs planned": manifest.get("total_runs", ""),
        "runs finished": n,
        "runs failed": n_err,
        "compute time (s)": f"{float(df['wall_time'].sum()):,.1f}" if n else "0",
    }
    for col in ("version", "git_commit", "host", "cpu", "python"):
        if col in df and n:
            meta_rows[col] = ", ".join(sorted({str(v) for v in df[col].dropna().unique()}))
    meta = pd.DataFrame({"": list(meta_rows), "value": [str(v) for v in meta_rows.values()]})
    failures = df[df["status"] != "ok"][["run_id", "error"]] if n_err else None

    title = f"uavplan report: {manifest.get('plan', root.name)} ({manifest.get('scale', '')})"
    parts = [
        f"<!doctype html><html><head><meta charset='utf-8'><title>{html.escape(title)}"
        f"</title><style>{_CSS}</style></head><body><h1>{html.escape(title)}</h1>",
        "<h2>Runs</h2>",
        _html_table(meta),
    ]
    md = [f"# {title}", "", "## Runs", "", _md_table(meta), ""]
    for sec_title, note, table in sections:
        parts.append(f"<h2>{html.escape(sec_title)}</h2>")
        md += [f"## {sec_title}", ""]
        if note:
            parts.append(f"<p class='note'>{html.escape(note)}</p>")
            md += [note, ""]
        if table is not None:
            parts.append(_html_table(table))
            md += [_md_table(table), ""]
    for name, ftitle, data in figures:
        b64 = base64.b64encode(data).decode()
        parts.append(
            f"<h2>{html.escape(ftitle)}</h2><img alt='{name}' src='data:image/png;base64,{b64}'>"
        )
        md += [f"## {ftitle}", "", f"![{name}](figures/{name}.png)", ""]
    if failures is not None:
        parts += ["<h2>Failed runs</h2>", _html_table(failures)]
        md += ["## Failed runs", "", _md_table(failures), ""]
    parts.append("</body></html>")
    html_path = write_text_atomic(root / "report.html", "\n".join(parts))
    md_path = write_text_atomic(root / "report.md", "\n".join(md) + "\n")
    return html_path, md_path
