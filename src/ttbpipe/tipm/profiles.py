"""Space-domain irregularity profiles of representative and forecast PSD sets.

Seed paper §3.2 step 4 and §3.3 ("time-frequency transformation"): each selected (or forecast)
PSD set becomes one profile per channel by the spectral representation with random phases,
:func:`ttbpipe.irregularity.synthesis.synthesize_from_psd_table` (physics.md §2), or, with
``tipm.profiles.amplitudes: gaussian``, with random Gaussian Fourier coefficients (a stationary
Gaussian profile; docs/irregularity.md, "Gaussian representation").

Seeds (project rule: a sample's random numbers depend only on the study seed and its index):
profile ``sample_index`` of campaign ``date`` uses
``SeedSequence([study_seed, yyyymmdd(date), stream, sample_index])`` with ``stream`` =
:data:`STREAM_REPRESENTATIVE` (0) for the representative sets of that campaign and
:data:`STREAM_FORECAST` (1) for the forecast states based on that campaign (every stream id:
:mod:`ttbpipe.streams`), so adding campaigns, changing the number of samples elsewhere or the core
count never changes a profile.
"""

from __future__ import annotations

import datetime as _dt
import logging
from typing import Sequence

import numpy as np
import pandas as pd

from .. import streams
from ..irregularity.synthesis import DEFAULT_AMPLITUDES, synthesize_from_psd_table

__all__ = ["profile_rng", "profiles_from_psd_sets", "write_profiles", "STREAM_REPRESENTATIVE",
           "STREAM_FORECAST", "STREAM_MONTE_CARLO", "PROFILES_PER_ROW_GROUP", "PROFILE_ID_COLUMN"]

log = logging.getLogger(__name__)

#: Stream ids of the campaign seed tree (:mod:`ttbpipe.streams`, the registry).
STREAM_REPRESENTATIVE = streams.TIPM_REPRESENTATIVE
STREAM_FORECAST = streams.TIPM_FORECAST
STREAM_MONTE_CARLO = streams.TIPM_MONTE_CARLO

#: Profiles per Parquet row group of a profiles table (:func:`write_profiles`). A study sample
#: reads its one profile with a filter on the id column
#: (:func:`ttbpipe.study.samples.read_profile`); the row groups' statistics then skip every group
#: but the one that holds it. Written in pyarrow's default groups of about a million rows, a
#: table of 300 forecast profiles (1.2 million rows, 42 MB) cost a sample of a batch 34-73 ms;
#: in groups of four profiles 7 ms (docs/performance.md, "A sample's profile read from its own
#: row group").
PROFILES_PER_ROW_GROUP = 4
#: The id column of each profiles table, by the study scenario kind that reads it: the
#: representative sets' profiles (rule tipm_select) by their set, the forecast profiles (rule
#: tipm_forecast) by their profile; written by :func:`write_profiles`, read by
#: :func:`ttbpipe.study.samples.read_profile`.
PROFILE_ID_COLUMN = {"irregularity": "sample_index", "forecast": "profile_index"}


def date_key(date: str) -> int:
    """YYYYMMDD integer of an ISO date (raises ValueError naming the bad date)."""
    try:
        return int(_dt.date.fromisoformat(str(date)).strftime("%Y%m%d"))
    except ValueError:
        raise ValueError(f"campaign date {date!r} is not YYYY-MM-DD") from None


def profile_rng(study_seed: int, date: str, stream: int, sample_index: int) -> np.random.Generator:
    """Generator of one profile: SeedSequence([study_seed, yyyymmdd, stream, sample_index])."""
    return np.random.default_rng(np.random.SeedSequence(
        [int(study_seed), date_key(date), int(stream), int(sample_index)]))


def profiles_from_psd_sets(psd_mm2_m: np.ndarray, frequency_per_m: np.ndarray,
                           channels: Sequence[str], sample_indices: Sequence[int], *,
                           length_m: float, dx_m: float, study_seed: int, date: str, stream: int,
                           wavelength_band_m: tuple[float, float] = (2.0, 200.0),
                           amplitudes: str = DEFAULT_AMPLITUDES) -> pd.DataFrame:
    """Profiles of PSD sets ``psd_mm2_m[sample, frequency, channel]``.

    Returns a long table ``sample_index, chainage_m, <channel>_mm ...`` (mm), one block of
    rows per sample. The wavelength band must lie inside the tabulated frequencies.
    ``amplitudes``: ``random_phase`` (default) or ``gaussian``
    (:func:`ttbpipe.irregularity.synthesis.synthesize_channel`); either way a profile draws
    only from its own generator :func:`profile_rng`.
    """
    psd_mm2_m = np.asarray(psd_mm2_m, dtype=float)
    if psd_mm2_m.shape[0] != len(sample_indices):
        raise ValueError(f"{psd_mm2_m.shape[0]} PSD sets but {len(sample_indices)} sample indices")
    blocks = []
    for row, index in enumerate(sample_indices):
        table = synthesize_from_psd_table(
            frequency_per_m, {ch: psd_mm2_m[row, :, c] for c, ch in enumerate(channels)},
            length_m=length_m, dx_m=dx_m, rng=profile_rng(study_seed, date, stream, index),
            wavelength_band_m=tuple(wavelength_band_m), amplitudes=amplitudes)
        table.insert(0, "sample_index", int(index))
        blocks.append(table)
    out = pd.concat(blocks, ignore_index=True)
    log.info("%d profiles of %g m at dx %g m (campaign %s, stream %d, amplitudes %s)", len(blocks),
             length_m, dx_m, date, stream, amplitudes)
    return out


def write_profiles(profiles: pd.DataFrame, path, *, id_column: str, **provenance):
    """Write a profiles table (rows sorted by ``id_column``, the profile's id) atomically with
    its provenance (:func:`ttbpipe.io.write_table`), in row groups of
    :data:`PROFILES_PER_ROW_GROUP` profiles of its longest profile's length. Only the reading
    speed depends on the grouping: a group may hold parts of two profiles if lengths differ."""
    from ..io import write_table

    ids = profiles[id_column].to_numpy()
    if ids.size and (np.diff(ids) < 0).any():
        raise ValueError(f"{path}: profiles not sorted by {id_column}; a sample's row group "
                         "could not be found by its statistics")
    longest = int(profiles.groupby(id_column, sort=False).size().max()) if ids.size else 1
    return write_table(profiles, path, row_group_size=longest * PROFILES_PER_ROW_GROUP,
                       **provenance)
