"""Compare the results of two sweeps bit for bit: every column but the measured ones
(:data:`uavplan.bench.store.MEASURED_COLUMNS`: times, memory, host), NaN equal to NaN, arrays
element by element."""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from uavplan.bench.store import MEASURED_COLUMNS


def result_frame(df: pd.DataFrame) -> pd.DataFrame:
    """The columns that are a function of the run alone, indexed and sorted by run id."""
    keep = [c for c in df.columns if c not in MEASURED_COLUMNS]
    return df[keep].set_index("run_id").sort_index()


def same_values(a: Any, b: Any) -> bool:
    """Bit-identical values of one cell: numbers equal (NaN equals NaN), arrays and lists
    element by element, nested lists too."""
    seq = (np.ndarray, list, tuple)
    if isinstance(a, seq) or isinstance(b, seq):
        if not (isinstance(a, seq) and isinstance(b, seq)):
            return False
        x, y = a, b
        if isinstance(x, np.ndarray) and isinstance(y, np.ndarray) and x.dtype != object:
            nan = x.dtype.kind == "f" and y.dtype.kind == "f"
            return x.shape == y.shape and bool(np.array_equal(x, y, equal_nan=nan))
        return len(a) == len(b) and all(same_values(u, v) for u, v in zip(a, b, strict=True))
    if a is None or b is None:
        return (a is None or _nan(a)) and (b is None or _nan(b))
    if _nan(a) and _nan(b):
        return True
    return bool(a == b)


def _nan(v: Any) -> bool:
    try:
        return bool(np.isnan(v))
    except (TypeError, ValueError):
        return v is pd.NA


def differing_cells(got: pd.DataFrame, want: pd.DataFrame, limit: int = 10) -> list[str]:
    """Where two result frames (:func:`result_frame`, same index) differ: ``run_id: column``."""
    out: list[str] = []
    cols = sorted(set(got.columns) | set(want.columns))
    for rid in got.index:
        for c in cols:
            if c not in got.columns or c not in want.columns:
                out.append(f"{rid}: column {c} only in one")
            elif not same_values(got.at[rid, c], want.at[rid, c]):
                out.append(f"{rid}: {c} = {got.at[rid, c]!r}, expected {want.at[rid, c]!r}")
            if len(out) >= limit:
                return out
    return out
