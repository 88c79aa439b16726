"""benchmarks/compare_results.py, the comparison of two results folders that the performance
notes quote (docs/performance.md): equal folders give no difference, a numeric change is
reported relative to the column's peak, and a changed label, verdict or NaN pattern counts as
infinite (exit status 1)."""

import importlib.util
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd

_PATH = Path(__file__).resolve().parents[1] / "benchmarks" / "compare_results.py"
_spec = importlib.util.spec_from_file_location("compare_results", _PATH)
compare = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(compare)


def _table():
    return pd.DataFrame({"value": [2.0, -4.0, np.nan], "verdict": ["pass", "fail", "pass"],
                         "exceeded": [False, True, False]})


def test_column_differences_relative_to_the_peak_and_infinite_for_labels():
    a = _table()
    assert compare.column_differences(a, a.copy()) == {}
    b = a.copy()
    b.loc[0, "value"] = 2.0 + 4e-9
    differences = compare.column_differences(a, b)
    assert list(differences) == ["value"]
    assert math.isclose(differences["value"], 4e-9 / 4.0, rel_tol=1e-6)   # over the peak |-4|
    b = a.copy()
    b.loc[2, "value"] = 1.0              # NaN pattern changed
    assert math.isinf(compare.column_differences(a, b)["value"])
    b = a.copy()
    b.loc[1, "verdict"] = "pass"
    assert math.isinf(compare.column_differences(a, b)["verdict"])
    b = a.copy()
    b.loc[1, "exceeded"] = False
    assert math.isinf(compare.column_differences(a, b)["exceeded"])


def test_folders_matched_without_the_digest_folder(tmp_path):
    for tree, digest, value in (("A", "0123456789ab", 2.0), ("B", "ba9876543210", 2.0 + 1e-12)):
        folder = tmp_path / tree / "study" / "batches" / digest / "C1"
        folder.mkdir(parents=True)
        table = _table()
        table.loc[0, "value"] = value
        table.to_parquet(folder / "extremes_00000-00009.parquet")
    run = subprocess.run([sys.executable, str(_PATH), str(tmp_path / "A"), str(tmp_path / "B")],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stdout + run.stderr
    assert "1 tables and 0 figures compared, 1 differ" in run.stdout
    assert "study/batches/C1/extremes_00000-00009.parquet" in run.stdout
    (tmp_path / "B" / "study" / "batches" / "ba9876543210" / "C1" / "extra.png").write_bytes(b"x")
    run = subprocess.run([sys.executable, str(_PATH), str(tmp_path / "A"), str(tmp_path / "B")],
                         capture_output=True, text=True)
    assert run.returncode == 1 and "only in B" in run.stdout
