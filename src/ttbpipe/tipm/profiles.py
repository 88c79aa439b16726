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

__all__ = ["profile_rng", "profiles_from_psd_sets", "STREAM_REPRESENTATIVE", "STREAM_FORECAST",
           "STREAM_MONTE_CARLO"]

log = logging.getLogger(__name__)

#: Stream ids of the campaign seed tree (:mod:`ttbpipe.streams`, the registry).
STREAM_REPRESENTATIVE = streams.TIPM_REPRESENTATIVE
STREAM_FORECAST = streams.TIPM_FORECAST
STREAM_MONTE_CARLO = streams.TIPM_MONTE_CARLO


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
