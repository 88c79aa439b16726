"""Schemas of the per-sample result tables the simulation stage writes (``docs/results_schema.md``).

Two tables per batch of samples, both Parquet, both written with :func:`ttbpipe.io.write_table`:

* the **extremes table**: one row per sample with the identification columns
  (:data:`EXTREMES_KEY_COLUMNS`), optional context columns (:data:`EXTREMES_CONTEXT_COLUMNS`)
  and one column per response index (:data:`RESPONSE_INDEX_COLUMNS`);
* the **time-history table**, long format: one row per sample and abscissa point with the
  identification columns (:data:`HISTORY_KEY_COLUMNS`), exactly one abscissa column
  (``time_s`` or ``position_m``) and any number of float quantity columns whose names carry their
  unit (:func:`unit_of`).

:func:`validate_extremes` and :func:`validate_histories` check a table and raise
:class:`ResultsSchemaError`, whose message names the file, the column and, where one is at fault,
the row.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from ..constants import STANDARD_GRAVITY as G_STANDARD  # noqa: F401  (limits given in g)
from ..response_indices import RESPONSE_INDEX_REGISTRY


class ResultsSchemaError(ValueError):
    """A results table does not follow ``docs/results_schema.md``."""


@dataclass(frozen=True)
class ColumnSpec:
    """One column of a results table.

    ``dtype`` is the pandas/numpy kind the column must have: ``int64``, ``float64`` or
    ``string``. ``lower``/``upper`` are the physically possible range (inclusive); a value outside
    it is an error. ``required`` columns must be present.
    """

    name: str
    dtype: str
    unit: str
    description: str
    required: bool = False
    lower: float = -math.inf
    upper: float = math.inf


# --- extremes table -------------------------------------------------------------------------

EXTREMES_KEY_COLUMNS: tuple[ColumnSpec, ...] = (
    ColumnSpec("sample_index", "int64", "1",
               "sample index i; the sample's random numbers derive from (study seed, i) only",
               required=True, lower=0),
    ColumnSpec("scenario", "string", "1",
               "scenario label: campaign date (YYYY-MM-DD), forecast horizon, randomness "
               "condition (C1..C4), 'full'/'single' excitation; (scenario, sample_index) is unique",
               required=True),
    ColumnSpec("weight", "float64", "1",
               "probability weight of the sample (TIPM representative probability; 1 for plain "
               "Monte Carlo); > 0; estimators normalise by the sum per scenario",
               required=True, lower=0.0),
    ColumnSpec("seed_entropy", "string", "1",
               "entropy of the sample's numpy SeedSequence as a decimal string (reproducibility)",
               required=True),
)

EXTREMES_CONTEXT_COLUMNS: tuple[ColumnSpec, ...] = (
    ColumnSpec("train_speed_m_s", "float64", "m/s",
               "train speed of the run; selects the wheel-unloading limit (0.65 up to 160 km/h, "
               "0.8 above)", lower=0.0),
    ColumnSpec("static_wheel_load_N", "float64", "N",
               "smallest static wheel load of the train (static equilibrium of the run)",
               lower=0.0),
    ColumnSpec("static_axle_load_N", "float64", "N",
               "smallest static axle load P0 of the train; sets the lateral wheelset force "
               "limit 15 kN + P0/3 (GB/T 5599-2019)", lower=0.0),
)

RESPONSE_INDEX_COLUMNS: tuple[ColumnSpec, ...] = tuple(
    ColumnSpec(i.name, "float64", i.unit, i.description, lower=i.lower, upper=i.upper)
    for i in RESPONSE_INDEX_REGISTRY)

EXTREMES_COLUMNS: tuple[ColumnSpec, ...] = (
    EXTREMES_KEY_COLUMNS + EXTREMES_CONTEXT_COLUMNS + RESPONSE_INDEX_COLUMNS)

#: Column name -> spec for every documented extremes column.
EXTREMES_SPEC: dict[str, ColumnSpec] = {c.name: c for c in EXTREMES_COLUMNS}

#: Names of the response index columns, in the documented order.
RESPONSE_INDICES: tuple[str, ...] = tuple(c.name for c in RESPONSE_INDEX_COLUMNS)

# --- time-history table ---------------------------------------------------------------------

HISTORY_KEY_COLUMNS: tuple[ColumnSpec, ...] = (
    EXTREMES_SPEC["sample_index"], EXTREMES_SPEC["scenario"], EXTREMES_SPEC["weight"])

#: Admissible abscissa columns of a time-history table; exactly one must be present.
HISTORY_ABSCISSAE: tuple[ColumnSpec, ...] = (
    ColumnSpec("time_s", "float64", "s", "time since the first wheelset entered the model"),
    ColumnSpec("position_m", "float64", "m",
               "position along the track (x, direction of travel) of the monitor or wheelset"),
)

#: Unit suffixes recognised at the end of a quantity column name (longest first), -> unit.
UNIT_SUFFIXES: tuple[tuple[str, str], ...] = (
    ("_m_s2", "m/s^2"), ("_rad_s2", "rad/s^2"), ("_m_s", "m/s"), ("_rad_s", "rad/s"),
    ("_N_m", "N m"), ("_Pa", "Pa"), ("_rad", "rad"), ("_N", "N"), ("_m", "m"), ("_s", "s"),
)

#: Dimensionless quantity stems that need no suffix (the unit is 1).
DIMENSIONLESS_STEMS: tuple[str, ...] = (
    "derailment_coefficient", "wheel_unloading_ratio", "sperling", "Y_Q", "N_MV",
    "deflection_ratio", "utilisation")

def unit_of(column: str) -> str:
    """Unit of a quantity column from its name (suffix rule of ``docs/results_schema.md``).

    Raises :class:`ValueError` when the name carries no recognised unit and is not a known
    dimensionless quantity.
    """
    if column in EXTREMES_SPEC:
        return EXTREMES_SPEC[column].unit
    for suffix, unit in UNIT_SUFFIXES:
        if column.endswith(suffix) and len(column) > len(suffix):
            return unit
    if any(stem in column for stem in DIMENSIONLESS_STEMS):
        return "1"
    raise ValueError(
        f"column {column!r} carries no unit: end its name with one of "
        f"{[s for s, _ in UNIT_SUFFIXES]} or use a dimensionless stem {list(DIMENSIONLESS_STEMS)}")


def describe_extremes() -> pd.DataFrame:
    """The extremes schema as a table (name, dtype, unit, required, range, description)."""
    return pd.DataFrame([{
        "name": c.name, "dtype": c.dtype, "unit": c.unit, "required": c.required,
        "lower": c.lower, "upper": c.upper, "description": c.description,
    } for c in EXTREMES_COLUMNS])


# --- validation -----------------------------------------------------------------------------

def _where(source: str | os.PathLike[str] | None) -> str:
    return str(source) if source is not None else "<in-memory table>"


def _check_dtype(df: pd.DataFrame, spec: ColumnSpec, where: str) -> None:
    series = df[spec.name]
    if spec.dtype == "string":
        ok = (pd.api.types.is_string_dtype(series) or pd.api.types.is_object_dtype(series)) and \
            all(isinstance(v, str) for v in series.dropna().head(1000))
    elif spec.dtype == "int64":
        ok = pd.api.types.is_integer_dtype(series)
    else:
        ok = pd.api.types.is_float_dtype(series)
    if not ok:
        raise ResultsSchemaError(
            f"{where}: column {spec.name!r} has dtype {series.dtype}, expected {spec.dtype} "
            f"({spec.description})")


def _first_bad_row(mask: np.ndarray) -> int:
    return int(np.flatnonzero(mask)[0])


def _check_values(df: pd.DataFrame, spec: ColumnSpec, where: str) -> None:
    series = df[spec.name]
    missing = series.isna().to_numpy()
    if missing.any():
        row = _first_bad_row(missing)
        raise ResultsSchemaError(
            f"{where}: column {spec.name!r} is missing a value in row {row} "
            f"({int(missing.sum())} rows in all); the simulation must stop on numerical trouble "
            "rather than write NaN")
    if spec.dtype == "string":
        return
    values = series.to_numpy(dtype=float)
    bad = ~np.isfinite(values) | (values < spec.lower) | (values > spec.upper)
    if spec.name == "weight":
        bad |= values <= 0.0
    if bad.any():
        row = _first_bad_row(bad)
        raise ResultsSchemaError(
            f"{where}: column {spec.name!r}, row {row}: value {values[row]!r} is outside the "
            f"admissible range [{spec.lower}, {spec.upper}] {spec.unit}"
            + (" (weights must be > 0)" if spec.name == "weight" else "")
            + f"; {int(bad.sum())} rows in all")


def validate_extremes(df: pd.DataFrame, source: str | os.PathLike[str] | None = None) -> pd.DataFrame:
    """Check an extremes table against :data:`EXTREMES_SPEC`; return it unchanged.

    Checks: required columns present; documented columns have their dtype and contain finite
    values within their physical range; at least one response index; weights > 0;
    (scenario, sample_index) unique. Columns that are not documented must be numeric and their
    names must carry a unit (:func:`unit_of`). Raises :class:`ResultsSchemaError` naming
    ``source``, the column and the first offending row.
    """
    where = _where(source)
    missing = [c.name for c in EXTREMES_KEY_COLUMNS if c.name not in df.columns]
    if missing:
        raise ResultsSchemaError(f"{where}: missing required column(s) {missing} "
                                 f"(see docs/results_schema.md)")
    present = [c for c in EXTREMES_COLUMNS if c.name in df.columns]
    for spec in present:
        _check_dtype(df, spec, where)
        _check_values(df, spec, where)
    if not any(name in df.columns for name in RESPONSE_INDICES):
        raise ResultsSchemaError(f"{where}: no response index column; expected at least one of "
                                 f"{list(RESPONSE_INDICES)}")
    for name in df.columns:
        if name in EXTREMES_SPEC:
            continue
        try:
            unit_of(name)
        except ValueError as exc:
            raise ResultsSchemaError(f"{where}: {exc}") from None
        spec = ColumnSpec(name, "float64", unit_of(name), "additional response index")
        _check_dtype(df, spec, where)
        _check_values(df, spec, where)
    dup = df.duplicated(subset=["scenario", "sample_index"], keep="first").to_numpy()
    if dup.any():
        row = _first_bad_row(dup)
        raise ResultsSchemaError(
            f"{where}: column 'sample_index', row {row}: sample {int(df['sample_index'].iloc[row])} "
            f"of scenario {df['scenario'].iloc[row]!r} appears more than once")
    return df


def response_columns(df: pd.DataFrame) -> list[str]:
    """Response index columns of an extremes table: documented ones first, then additional ones."""
    documented = [c for c in RESPONSE_INDICES if c in df.columns]
    known = {c.name for c in EXTREMES_KEY_COLUMNS + EXTREMES_CONTEXT_COLUMNS}
    extra = [c for c in df.columns if c not in known and c not in RESPONSE_INDICES]
    return documented + extra


def history_abscissa(columns) -> str:
    """Name of the abscissa column of a time-history table (``time_s`` or ``position_m``)."""
    found = [a.name for a in HISTORY_ABSCISSAE if a.name in columns]
    if len(found) != 1:
        raise ValueError(f"expected exactly one abscissa column of "
                         f"{[a.name for a in HISTORY_ABSCISSAE]}, found {found}")
    return found[0]


def history_quantities(columns) -> list[str]:
    """Quantity columns of a time-history table (everything but keys and the abscissa)."""
    skip = {c.name for c in HISTORY_KEY_COLUMNS} | {a.name for a in HISTORY_ABSCISSAE}
    return [c for c in columns if c not in skip]


def sample_starts(scenario_codes: np.ndarray, sample_index: np.ndarray) -> np.ndarray:
    """Boolean mask of the rows where a new (scenario, sample) block starts in a long table."""
    starts = np.ones(len(sample_index), dtype=bool)
    starts[1:] = (scenario_codes[1:] != scenario_codes[:-1]) | (sample_index[1:] != sample_index[:-1])
    return starts


def validate_histories(df: pd.DataFrame, source: str | os.PathLike[str] | None = None) -> pd.DataFrame:
    """Check a long-format time-history table; return it unchanged.

    Checks: key columns and exactly one abscissa column present with their dtypes; at least one
    quantity column, each float with a unit in its name and finite values; the weight is constant
    within a sample; every sample of a scenario has the same, strictly increasing abscissa grid
    (rows of one sample contiguous). Raises :class:`ResultsSchemaError` naming ``source``, the
    column and the row.
    """
    where = _where(source)
    original, df = df, df.reset_index(drop=True)
    missing = [c.name for c in HISTORY_KEY_COLUMNS if c.name not in df.columns]
    if missing:
        raise ResultsSchemaError(f"{where}: missing required column(s) {missing} "
                                 f"(see docs/results_schema.md, time-history table)")
    try:
        abscissa = history_abscissa(df.columns)
    except ValueError as exc:
        raise ResultsSchemaError(f"{where}: {exc}") from None
    specs = list(HISTORY_KEY_COLUMNS) + [a for a in HISTORY_ABSCISSAE if a.name == abscissa]
    quantities = history_quantities(df.columns)
    if not quantities:
        raise ResultsSchemaError(f"{where}: no quantity column besides the keys and {abscissa!r}")
    for name in quantities:
        try:
            unit = unit_of(name)
        except ValueError as exc:
            raise ResultsSchemaError(f"{where}: {exc}") from None
        specs.append(ColumnSpec(name, "float64", unit, "time-history quantity"))
    for spec in specs:
        _check_dtype(df, spec, where)
        _check_values(df, spec, where)
    codes, scenarios = pd.factorize(df["scenario"], sort=False)
    index = df["sample_index"].to_numpy()
    starts = sample_starts(codes, index)
    first = np.flatnonzero(starts)
    key = codes[first].astype(np.int64) * (int(index.max()) + 1) + index[first]
    _, unique_pos = np.unique(key, return_index=True)
    if unique_pos.size != first.size:
        repeated = np.setdiff1d(np.arange(first.size), unique_pos)[0]
        row = int(first[repeated])
        raise ResultsSchemaError(f"{where}: column 'sample_index', row {row}: sample "
                                 f"{int(index[row])} appears again; the rows of one sample must "
                                 "be contiguous")
    group = np.cumsum(starts) - 1
    weights = df["weight"].to_numpy(dtype=float)
    changed = weights != weights[first][group]
    if changed.any():
        row = _first_bad_row(changed)
        raise ResultsSchemaError(f"{where}: column 'weight', row {row}: the weight changes within "
                                 f"sample {int(index[row])}")
    x = df[abscissa].to_numpy(dtype=float)
    counts = np.diff(np.r_[first, len(df)])
    for code, scenario in enumerate(scenarios):
        mine = codes[first] == code
        if np.unique(counts[mine]).size != 1:
            row = int(first[mine][_first_bad_row(counts[mine] != counts[mine][0])])
            raise ResultsSchemaError(f"{where}: column {abscissa!r}, row {row}: samples of "
                                     f"scenario {scenario!r} have different numbers of points")
        n_points = int(counts[mine][0])
        pos = (first[mine][:, None] + np.arange(n_points)).ravel()
        grid = x[pos].reshape(-1, n_points)
        if n_points > 1 and not (np.diff(grid[0]) > 0).all():
            row = int(pos[_first_bad_row(np.diff(grid[0]) <= 0) + 1])
            raise ResultsSchemaError(f"{where}: column {abscissa!r}, row {row}: the abscissa must "
                                     "increase strictly within a sample")
        tol = 1e-9 * max(1.0, float(np.abs(grid[0]).max()))
        off = np.abs(grid - grid[0]) > tol
        if off.any():
            flat = _first_bad_row(off.ravel())
            raise ResultsSchemaError(f"{where}: column {abscissa!r}, row {int(pos[flat])}: every "
                                     f"sample of scenario {scenario!r} must use the same grid")
    return original


def read_validated(path: str | os.PathLike[str], kind: str, columns: list[str] | None = None) -> pd.DataFrame:
    """Read one Parquet results file and validate it (``kind``: 'extremes' or 'histories')."""
    import pyarrow.parquet as pq

    path = Path(path)
    if not path.exists():
        raise ResultsSchemaError(f"{path}: no such results file")
    df = pq.read_table(path, columns=columns).to_pandas()
    if kind == "extremes":
        return validate_extremes(df, path)
    if kind == "histories":
        return validate_histories(df, path)
    raise ValueError(f"unknown results table kind {kind!r}")


# --- example tables (documentation, tests, benchmarks) ----------------------------------------

#: Plausible medians (SI) of the response indices for :func:`example_extremes`.
_EXAMPLE_MEDIANS = {
    "max_derailment_coefficient": 0.25, "max_wheel_unloading_ratio": 0.3,
    "max_lateral_wheelset_force_N": 12e3, "max_wheel_vertical_force_N": 95e3,
    "max_wheel_lateral_force_N": 10e3, "max_carbody_vertical_acc_m_s2": 0.6,
    "max_carbody_lateral_acc_m_s2": 0.4, "sperling_vertical": 2.2, "sperling_lateral": 2.1,
    "max_deck_vertical_acc_m_s2": 1.5, "max_deck_lateral_acc_m_s2": 0.3,
    "max_rail_vertical_acc_m_s2": 60.0, "max_rail_lateral_acc_m_s2": 25.0,
    "max_girder_vertical_disp_m": 4e-3,
}


def example_extremes(sample_indices, scenario: str = "C1", *, seed: int = 0,
                     weights=None, spread: float = 0.25) -> pd.DataFrame:
    """A synthetic extremes table following the schema (lognormal indices about plausible medians).

    For documentation, tests and benchmarks only: not a physical result. Sample i's values depend
    only on (seed, i).
    """
    sample_indices = np.asarray(sample_indices, dtype=np.int64)
    rows = []
    for i in sample_indices:
        seq = np.random.SeedSequence([seed, int(i)])
        z = np.random.default_rng(seq).standard_normal(len(_EXAMPLE_MEDIANS))
        row = {name: med * math.exp(spread * zi) for (name, med), zi in zip(_EXAMPLE_MEDIANS.items(), z)}
        row["max_wheel_unloading_ratio"] = min(row["max_wheel_unloading_ratio"], 1.0)
        row["seed_entropy"] = str(seq.entropy)
        rows.append(row)
    df = pd.DataFrame(rows)
    df.insert(0, "sample_index", sample_indices)
    df.insert(1, "scenario", pd.Series([scenario] * len(df), dtype="string"))
    df.insert(2, "weight", np.ones(len(df)) if weights is None else np.asarray(weights, dtype=float))
    df.insert(3, "seed_entropy", df.pop("seed_entropy").astype("string"))
    df.insert(4, "train_speed_m_s", np.full(len(df), 300 / 3.6))
    df.insert(5, "static_wheel_load_N", np.full(len(df), 70e3))
    df.insert(6, "static_axle_load_N", np.full(len(df), 140e3))
    return df


def example_histories(sample_indices, scenario: str = "C1", *, n_points: int = 200,
                      seed: int = 0, weights=None, abscissa: str = "time_s") -> pd.DataFrame:
    """A synthetic long-format time-history table following the schema (random-amplitude waves).

    For documentation, tests and benchmarks only. Columns: ``rail_vertical_acc_m_s2`` and
    ``girder_vertical_disp_m`` against ``time_s`` (or ``position_m``).
    """
    sample_indices = np.asarray(sample_indices, dtype=np.int64)
    grid = np.linspace(0.0, 2.0, n_points)
    n = sample_indices.size
    acc = np.empty((n, n_points))
    disp = np.empty((n, n_points))
    for row, i in enumerate(sample_indices):
        rng = np.random.default_rng(np.random.SeedSequence([seed, int(i)]))
        amp, phase = rng.lognormal(0.0, 0.3), rng.uniform(0, 2 * np.pi)
        acc[row] = amp * 10.0 * np.sin(2 * np.pi * 3.0 * grid + phase) + rng.normal(0, 2.0, n_points)
        disp[row] = -3e-3 * amp * np.sin(np.pi * grid / 2.0) ** 2 + rng.normal(0, 1e-4, n_points)
    w = np.ones(n) if weights is None else np.asarray(weights, dtype=float)
    return pd.DataFrame({
        "sample_index": np.repeat(sample_indices, n_points),
        "scenario": pd.Series([scenario] * (n * n_points), dtype="string"),
        "weight": np.repeat(w, n_points),
        abscissa: np.tile(grid, n),
        "rail_vertical_acc_m_s2": acc.ravel(),
        "girder_vertical_disp_m": disp.ravel(),
    })
