"""A one-row frame of the engine's row schema, for tests of what is written from rows."""

from __future__ import annotations

import math

import pandas as pd

from gtsp_bench.bench.rows import COLUMNS


def row_frame(**over) -> pd.DataFrame:
    """One row with every column set to a plausible value, ``over`` replacing some."""
    base = {c: "" for c in COLUMNS}
    base.update(benchmark="b", set="s", instance="i1", K=3, N=4, omega=0.5, solver="lns", label="lns",
                seed=0, time_limit=1.0, status="feasible", objective=100.0, lower_bound=math.nan,
                runtime_s=0.5, reference_value=100.0, reference_kind="optimal", gap_pct=0.0,
                bound_gap_pct=math.nan, primal_integral=0.1, time_to_1pct_s=0.2, time_to_0p1pct_s=0.3)
    base.update(over)
    return pd.DataFrame([base], columns=list(COLUMNS))
