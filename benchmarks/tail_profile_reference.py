"""A finished study's profile-likelihood intervals against the slow multi-start reference.

    python benchmarks/tail_profile_reference.py RESULTS [--old OLD_RELIABILITY]
        [--configfile config/config.yaml]

RESULTS: a study's results folder (``results/case4`` after ``snakemake --cores 2 --configfile
config/case4.yaml``), with its batches and ``study/reliability.parquet``. For every row of the
reliability table whose tail is an unweighted GEV of the raw index at a fixed threshold (the
limits as benchmarks/study_reliability_time.py builds them), recomputes the 95 % profile
interval with the slow reference of tests/test_reliability_tail.py (`_reference_profile_ends`:
each profile point from the 6 best points of a 25 x 34 grid, Nelder-Mead to 1e-10 and scipy's
Powell) and prints the rows whose ends differ from the table's by more than 2e-3 in log P, then
the largest difference. ``--old``: another reliability table of the same study (an older
revision's), compared the same way. About 0.15 s a row. Nothing asserted (the test asserts
eight such cases).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from study_reliability_time import study_limits

from ttbpipe.stats.limits import ConstantLimit

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from test_reliability_tail import _reference_profile_ends  # noqa: E402


def log_difference(got: float, ref: float) -> float:
    """|log got - log ref|, 0 when both are 0 (an end below 1e-30 is reported as 0)."""
    if got == 0.0 and ref == 0.0:
        return 0.0
    if not (got > 0 and ref > 0):
        return np.inf
    return abs(float(np.log(got) - np.log(ref)))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("results", type=Path)
    parser.add_argument("--old", type=Path, help="another reliability.parquet of the same study")
    parser.add_argument("--configfile", type=Path, default=Path("config/config.yaml"),
                        help="the configuration whose limits the study assessed")
    args = parser.parse_args()
    table = pd.read_parquet(args.results / "study/reliability.parquet")
    old = pd.read_parquet(args.old) if args.old else None
    extremes, limits, _, _ = study_limits(args.results, args.configfile)
    thresholds = {(lim.name, lim.category): float(lim.threshold) for lim in limits
                  if isinstance(lim, ConstantLimit)}
    worst = {"table": 0.0, "old": 0.0}
    rows = 0
    for i, row in table.iterrows():
        if (str(row.tail_model) != "GEV" or "raw index" not in str(row.tail_method)
                or bool(row.weighted) or not np.isfinite(row.tail_probability)):
            continue
        limit = thresholds.get((row.limit, row.category))
        if limit is None:       # a threshold that varies from sample to sample
            continue
        x = extremes.loc[extremes.scenario == row.scenario, row.column].to_numpy(float)
        _, low, high = _reference_profile_ends(x, limit)
        rows += 1
        found = {"table": (row.tail_ci_low, row.tail_ci_high)}
        if old is not None and str(old.tail_model.iloc[i]) == "GEV":
            found["old"] = (old.tail_ci_low.iloc[i], old.tail_ci_high.iloc[i])
        differences = {name: max(log_difference(lo, low), log_difference(hi, high))
                       for name, (lo, hi) in found.items()}
        for name, d in differences.items():
            worst[name] = max(worst[name], d)
        if max(differences.values()) > 2e-3:
            print(f"{row.scenario} {row.limit}: reference [{low:.3e}, {high:.3e}]"
                  + "".join(f", {name} [{lo:.3e}, {hi:.3e}] ({differences[name]:.2g})"
                            for name, (lo, hi) in found.items()))
    print(f"{rows} rows: largest |log P| difference of an interval end, table {worst['table']:.2g}"
          + (f", old {worst['old']:.2g}" if old is not None else ""))


if __name__ == "__main__":
    main()
