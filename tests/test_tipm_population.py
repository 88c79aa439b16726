"""PSDPopulation.from_long_table against a slow, obviously correct reference (DataFrame.pivot).

The population is built with integer keys instead of a pivot (docs/performance.md). The
reference below is the pivot path it replaced; both must give the same arrays, section table and
error messages, whatever the row order, the channels present and the band.
"""

import numpy as np
import pandas as pd
import pytest

from ttbpipe.channels import SPECTRAL_CHANNELS
from ttbpipe.tipm.population import LONG_COLUMNS, PSDPopulation, synthetic_population


def pivot_reference(table, campaign_date="", wavelength_band_m=None, source="PSD table"):
    """The population by DataFrame.pivot, with the same checks in the same order."""
    missing = [c for c in LONG_COLUMNS if c not in table.columns]
    if missing:
        raise ValueError(f"{source}: missing columns {missing}; expected {list(LONG_COLUMNS)}")
    table = table.loc[:, list(LONG_COLUMNS)]
    if wavelength_band_m is not None:
        lam_min, lam_max = (float(v) for v in wavelength_band_m)
        n = table["spatial_frequency_per_m"].to_numpy()
        keep = (n >= (1 / lam_max) * (1 - 1e-9)) & (n <= (1 / lam_min) * (1 + 1e-9))
        table = table.loc[keep]
    present = set(table["channel"].astype(str).unique())
    channels = tuple(c for c in SPECTRAL_CHANNELS if c in present)
    unknown = present - set(SPECTRAL_CHANNELS)
    if unknown:
        raise ValueError(f"{source}: unknown channels {sorted(unknown)}")
    duplicated = table.duplicated(["section", "channel", "spatial_frequency_per_m"])
    if duplicated.any():
        row = int(np.flatnonzero(duplicated)[0])
        raise ValueError(f"{source}: duplicate (section, channel, frequency) at row {row}")
    wide = table.pivot(index=["section", "spatial_frequency_per_m"], columns="channel",
                       values="psd_mm2_m")
    wide = wide.reindex(columns=list(channels)).sort_index()
    sections_idx = wide.index.get_level_values(0).unique()
    freqs = np.sort(wide.index.get_level_values(1).unique().to_numpy(dtype=float))
    full = pd.MultiIndex.from_product([sections_idx, freqs])
    if len(wide) != len(full):
        raise ValueError(f"{source}: sections do not share one frequency grid "
                         f"({len(wide)} rows, {len(full)} expected)")
    wide = wide.reindex(full)
    if wide.isna().any().any():
        raise ValueError(f"{source}: missing PSD values for some (section, channel, frequency)")
    psd = wide.to_numpy(dtype=float).reshape(len(sections_idx), freqs.size, len(channels))
    sec = (table.drop_duplicates("section").set_index("section")
           .loc[sections_idx, ["section_start_m", "section_end_m"]].reset_index())
    sec.insert(0, "campaign_date", str(campaign_date))
    return PSDPopulation(psd, freqs, channels, sec)


def long_table(n_sections=7, seed=3):
    """A long PSD table as ttbpipe.irregularity.psd.section_psds writes it (rows shuffled)."""
    rng = np.random.default_rng(seed)
    freqs = np.arange(1, 41) / 200.0
    mean = np.outer(1.0 / (freqs + 0.05) ** 2, np.arange(1, len(SPECTRAL_CHANNELS) + 1))
    pop = synthetic_population(n_sections, freqs, mean, rng)
    rows = []
    for s in range(n_sections):
        section = 10 + 3 * s                         # not 0..n-1: keys are the values
        for c, name in enumerate(pop.channels):
            rows.append(pd.DataFrame({
                "section": section, "section_start_m": 1000.0 * s,
                "section_end_m": 1000.0 * (s + 1), "channel": name,
                "spatial_frequency_per_m": freqs, "psd_mm2_m": pop.psd_mm2_m[s, :, c]}))
    table = pd.concat(rows, ignore_index=True)
    table["channel"] = table["channel"].astype("string")
    return table.sample(frac=1.0, random_state=seed).reset_index(drop=True)


def same(a, b):
    return (np.array_equal(a.psd_mm2_m, b.psd_mm2_m)
            and np.array_equal(a.frequency_per_m, b.frequency_per_m)
            and a.channels == b.channels and a.sections.equals(b.sections))


def outcome(build, table):
    try:
        return build(table, "2025-01-15")
    except ValueError as err:
        return f"ValueError: {err}"


@pytest.mark.parametrize("band", [None, (2.0, 200.0), (10.0, 50.0)])
@pytest.mark.parametrize("seed", [0, 1])
def test_population_equals_the_pivot_reference(band, seed):
    table = long_table(seed=seed)
    for variant in (table, table.sort_values(["section", "channel", "spatial_frequency_per_m"]),
                    table[table["channel"] != SPECTRAL_CHANNELS[1]]):
        fast = PSDPopulation.from_long_table(variant, "2025-01-15", band)
        assert same(fast, pivot_reference(variant, "2025-01-15", band))


def test_bad_tables_get_the_reference_messages():
    table = long_table()
    first = (table["section"] == table["section"].iloc[0]) & (
        table["spatial_frequency_per_m"] == table["spatial_frequency_per_m"].iloc[0])
    cases = {
        "duplicate": pd.concat([table, table.iloc[[40, 7]]], ignore_index=True),
        "duplicate inside": pd.concat([table.iloc[:90], table.iloc[[60]], table.iloc[90:]],
                                      ignore_index=True),
        "missing value": table.drop(index=[11]),
        "NaN value": table.assign(psd_mm2_m=table["psd_mm2_m"].where(table.index != 5)),
        "unknown channel": table.assign(channel=table["channel"].where(table.index != 4, "gauge")),
        "grid": table[~first],
        "negative": table.assign(psd_mm2_m=table["psd_mm2_m"].where(table.index != 9, -1.0)),
        "missing column": table.drop(columns=["section_end_m"]),
    }
    for name, bad in cases.items():
        expected = outcome(pivot_reference, bad)
        got = outcome(PSDPopulation.from_long_table, bad)
        assert isinstance(expected, str), name      # every case is an error
        assert got == expected, name


@pytest.mark.parametrize("band", [None, (10.0, 50.0)])
def test_pooled_table_gives_back_the_campaigns_population(tmp_path, band):
    """The pooled table of several campaigns' PSD tables (the study's Monte Carlo population,
    one file) reads back the population the campaigns' tables give, bit for bit; its band is
    checked on reading."""
    from ttbpipe.tipm.population import (pooled_population, read_pooled_population,
                                         write_pooled_population)

    paths = []
    for seed, date in ((0, "2025-01-15"), (1, "2025-02-15"), (2, "2024-12-15")):
        path = tmp_path / f"{date}.parquet"
        long_table(n_sections=4 + seed, seed=seed).to_parquet(path)
        paths.append(path)
    out = tmp_path / "pooled.parquet"
    written = write_pooled_population(paths, band, out)
    expected = pooled_population(paths, band)
    assert same(written, expected)
    assert list(expected.sections["campaign_date"].unique()) == ["2024-12-15", "2025-01-15",
                                                                 "2025-02-15"]
    assert same(read_pooled_population(out, band), expected)
    assert same(read_pooled_population(out, None if band is None else list(band)), expected)
    with pytest.raises(ValueError, match="pooled over the wavelength band"):
        read_pooled_population(out, (2.0, 200.0))


def _written_pooled(tmp_path, n_sections, **parquet_options):
    """A pooled table of ``n_sections`` synthetic sections, as write_pooled_population writes
    it (``parquet_options``: pyarrow.parquet.write_table's, to write it another way)."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    from ttbpipe.io import PROVENANCE_KEY, write_table
    from ttbpipe.tipm.population import POOLED_SECTIONS_PER_ROW_GROUP

    population = synthetic_population(n_sections, np.arange(1, 12) / 100.0, np.ones((11, 4)),
                                      np.random.default_rng(n_sections))
    path = tmp_path / f"pooled_{n_sections}_{len(parquet_options)}.parquet"
    if parquet_options:
        table = pa.Table.from_pandas(population.to_pooled_table(), preserve_index=False)
        meta = {PROVENANCE_KEY: b'{"wavelength_band_m": null}'}
        pq.write_table(table.replace_schema_metadata(meta), path, **parquet_options)
    else:
        write_table(population.to_pooled_table(), path, kind="pooled_psd_population",
                    row_group_size=11 * POOLED_SECTIONS_PER_ROW_GROUP, wavelength_band_m=None)
    return population, path


@pytest.mark.parametrize("options", [{}, {"row_group_size": 5}, {"write_statistics": False}],
                         ids=["as written", "sections across row groups", "no statistics"])
def test_pooled_sections_are_the_populations_sections(tmp_path, options):
    """PooledSections (a Monte Carlo batch reads its sections one by one) gives every section
    bit for bit as the whole table's population has it: from the row groups that hold it
    (sections of several groups, 5 rows a group against 11 frequencies a section), or from the
    whole table when the file has no statistics to locate it."""
    import pyarrow.parquet as pq

    from ttbpipe.tipm.population import PooledSections, read_pooled_population

    population, path = _written_pooled(tmp_path, 37, **options)
    assert same(read_pooled_population(path, None), population)
    reader = PooledSections(path, None)
    assert reader.n_sections == 37
    for s in (36, 0, 15, 16, 17, 31, 32, 5, 36):
        assert same(reader.section(s), population.subset([s])), s
    assert len(reader._groups) <= PooledSections.KEPT_GROUPS
    if not options:   # the sections of one group of 16 are read from that group alone
        assert pq.ParquetFile(path).metadata.num_row_groups == 3
        fresh = PooledSections(path, None)
        fresh.section(20)
        assert list(fresh._groups) == [1]
    with pytest.raises(ValueError, match="outside the population of 37 sections"):
        reader.section(37)
    with pytest.raises(ValueError, match="pooled over the wavelength band"):
        PooledSections(path, (2.0, 200.0))


def test_pooled_sections_refuse_bad_tables(tmp_path):
    """A table not section-major from 0, a section without rows and a section on another
    frequency grid are refused with the file, the section and the cause."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    from ttbpipe.io import PROVENANCE_KEY
    from ttbpipe.tipm.population import PooledSections

    table = synthetic_population(6, np.arange(1, 12) / 100.0, np.ones((11, 4)),
                                 np.random.default_rng(0)).to_pooled_table()

    def written(df, name):
        path = tmp_path / f"{name}.parquet"
        arrow = pa.Table.from_pandas(df, preserve_index=False)
        pq.write_table(arrow.replace_schema_metadata(
            {PROVENANCE_KEY: b'{"wavelength_band_m": null}'}), path, row_group_size=22)
        return path

    reversed_groups = pd.concat([table.iloc[22:44], table.iloc[:22], table.iloc[44:]])
    with pytest.raises(ValueError, match="row group 0 holds population_section 2-3 after -1"):
        PooledSections(written(reversed_groups, "reversed"), None)
    gap = table.assign(population_section=table["population_section"].where(
        table["population_section"] != 3, 4))
    with pytest.raises(ValueError, match="population_section 3: no rows"):
        PooledSections(written(gap, "gap"), None).section(3)
    other_grid = table.assign(spatial_frequency_per_m=np.where(
        table["population_section"] == 4, table["spatial_frequency_per_m"] * 1.5,
        table["spatial_frequency_per_m"]))
    reader = PooledSections(written(other_grid, "grid"), None)
    reader.section(1)
    with pytest.raises(ValueError, match="population_section 4: sections do not share"):
        reader.section(4)


def test_bad_pooled_tables_are_refused():
    table = synthetic_population(3, np.arange(1, 11) / 100.0, np.ones((10, 4)),
                                 np.random.default_rng(0)).to_pooled_table()
    assert same(PSDPopulation.from_pooled_table(table), PSDPopulation.from_pooled_table(
        table.copy()))
    cases = {
        "rows out of order": (table.iloc[::-1].reset_index(drop=True), "section-major"),
        "a row missing": (table.drop(index=[12]).reset_index(drop=True), "section-major"),
        "another grid": (table.assign(spatial_frequency_per_m=table["spatial_frequency_per_m"]
                                      .where(table.index != 13, 0.555)), "row 13"),
        "no channel": (table.drop(columns=[c for c in table.columns if c.endswith("_psd_mm2_m")]),
                       "PSD columns"),
        "unknown channel": (table.rename(columns={"gauge_psd_mm2_m": "twist_psd_mm2_m"}),
                            "twist_psd_mm2_m"),
        "missing column": (table.drop(columns=["population_section"]), "missing columns"),
        "no rows": (table.iloc[:0], "no rows"),
        "NaN value": (table.assign(vertical_psd_mm2_m=table["vertical_psd_mm2_m"]
                                   .where(table.index != 5)), "not finite"),
    }
    for name, (bad, message) in cases.items():
        with pytest.raises(ValueError, match=message):
            PSDPopulation.from_pooled_table(bad, source=name)
