"""Compare two results folders of the same study: which tables and figures differ, and by how much.

    python benchmarks/compare_results.py <tree A>/results <tree B>/results

Run the same study in two trees (for example the code before and after a change, each in a fresh
clone) and compare what they wrote. Tables (Parquet) are compared with ``DataFrame.equals``;
for a table that differs, every non-numeric column (labels, verdicts, booleans) must be equal,
and each numeric column's largest difference is printed relative to that column's largest
magnitude (a changed NaN pattern counts as infinite). Figures (PNG) are compared byte for byte.
The study's batch files sit under a folder named by the settings digest, which includes the
model version and so differs between trees: files are matched with that folder left out.
Prints one line per differing file and a summary; exits 1 if a file is only in one folder or a
non-numeric column differs.
"""

from __future__ import annotations

import argparse
import math
import re
from pathlib import Path

import numpy as np
import pandas as pd

_DIGEST_FOLDER = re.compile(r"batches/[0-9a-f]{12}/")


def _files(root: Path) -> dict[str, Path]:
    return {_DIGEST_FOLDER.sub("batches/", str(p.relative_to(root))): p
            for p in root.rglob("*") if p.is_file() and p.suffix in (".parquet", ".png")}


def column_differences(a: pd.DataFrame, b: pd.DataFrame) -> dict[str, float]:
    """Per differing column: the largest |a - b| over the column's largest |a| (numeric), or
    inf (a non-numeric column that differs, or a changed NaN pattern)."""
    out = {}
    for column in a.columns:
        x, y = a[column], b[column]
        if x.equals(y):
            continue
        if pd.api.types.is_numeric_dtype(x) and not pd.api.types.is_bool_dtype(x):
            u, v = x.to_numpy(float), y.to_numpy(float)
            if not np.array_equal(np.isnan(u), np.isnan(v)):
                out[column] = math.inf
                continue
            finite = np.isfinite(u) & np.isfinite(v)
            if not np.array_equal(u[~finite], v[~finite], equal_nan=True):
                out[column] = math.inf
                continue
            delta = float(np.max(np.abs(u[finite] - v[finite]), initial=0.0))
            scale = float(np.max(np.abs(u[finite]), initial=0.0))
            out[column] = delta / scale if scale > 0 else delta
        else:
            out[column] = math.inf
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("a", type=Path)
    parser.add_argument("b", type=Path)
    args = parser.parse_args()
    fa, fb = _files(args.a), _files(args.b)
    only = sorted(set(fa) ^ set(fb))
    for key in only:
        print(f"only in {'A' if key in fa else 'B'}: {key}")
    tables = figures = differing = 0
    worst, broken = 0.0, bool(only)
    for key in sorted(set(fa) & set(fb)):
        if key.endswith(".png"):
            figures += 1
            if fa[key].read_bytes() != fb[key].read_bytes():
                differing += 1
                print(f"figure differs: {key}")
            continue
        tables += 1
        a, b = pd.read_parquet(fa[key]), pd.read_parquet(fb[key])
        if a.equals(b):
            continue
        differing += 1
        if list(a.columns) != list(b.columns) or a.shape != b.shape:
            print(f"table differs in shape or columns: {key}")
            broken = True
            continue
        diffs = column_differences(a, b)
        column = max(diffs, key=diffs.get)
        worst = max(worst, diffs[column])
        broken |= math.isinf(diffs[column])
        print(f"table differs: {key}: largest relative difference {diffs[column]:.3g} in {column}")
    print(f"{tables} tables and {figures} figures compared, {differing} differ; largest relative "
          f"difference of a numeric column {worst:.3g}")
    return 1 if broken else 0


if __name__ == "__main__":
    raise SystemExit(main())
