"""Track irregularities as the time loop reads them: per-rail profiles on a uniform grid.

:func:`build_irregularity` turns a run's ``irregularity:`` section (a synthetic profile of a
standard spectrum, a profile file, or a profile table handed over in memory) into an
:class:`Irregularity`: the four rail inputs z_left, z_right, y_left, y_right (m) and their
x-derivatives on a uniform grid, faded in ahead of the leading wheelset. The four spectral
channels become the rail inputs with :func:`ttbpipe.channels.rails_from_spectral`; each wheel
reads its rail's profile at its own x with :func:`irregularity_at`.

The track is perfect behind the leading wheelset's start and the irregularity fades in with a
raised cosine over ``fade_in_m`` ahead of it, starting two grid steps ahead so that the
interpolated value and slope are exactly 0 at the start: the gravity-loaded static state at
t = 0 is exact and every wheel sees the same profile at the same x. For a train running -x
(``direction=-1``) "ahead" is towards -x.
"""

from __future__ import annotations

from collections import namedtuple
from typing import Any, Mapping

import numpy as np
import pandas as pd

from ..channels import rails_from_spectral
from ..jit import kernel

#: Rail inputs (m) on a uniform grid starting at x0 with step dx: values[channel, i] and their
#: x-derivatives slopes[channel, i], channels z_left, z_right, y_left, y_right.
Irregularity = namedtuple("Irregularity", ["x0", "dx", "values", "slopes"])

#: Channels of a profile table (mm) and its abscissa.
PROFILE_COLUMNS = ("chainage_m", "vertical_mm", "alignment_mm", "cross_level_mm", "gauge_mm")
SPECTRAL = ("vertical", "alignment", "cross_level", "gauge")


def no_irregularity() -> Irregularity:
    """A perfect track (``irregularity.source: none``)."""
    return Irregularity(0.0, 1.0, np.zeros((4, 2)), np.zeros((4, 2)))


def check_profile(profile: pd.DataFrame, source: str) -> pd.DataFrame:
    """A profile table (``chainage_m`` uniform and increasing, the four channels in mm, finite);
    ValueError naming ``source``, the column and the row otherwise."""
    missing = [c for c in PROFILE_COLUMNS if c not in profile.columns]
    if missing:
        raise ValueError(f"{source}: missing column(s) {missing}")
    for c in PROFILE_COLUMNS:
        bad = np.flatnonzero(~np.isfinite(profile[c].to_numpy(float)))
        if bad.size:
            raise ValueError(f"{source}: non-finite value in column {c} at row {bad[0]}")
    steps = np.diff(profile["chainage_m"].to_numpy(float))
    if steps.size == 0 or np.any(steps <= 0) or np.ptp(steps) > 1e-6 * steps.mean():
        raise ValueError(f"{source}: chainage_m must be uniform and increasing")
    return profile


def read_profile_file(path: str) -> pd.DataFrame:
    """A profile table from a Parquet or CSV file (:data:`PROFILE_COLUMNS`)."""
    return pd.read_parquet(path) if str(path).endswith(".parquet") else pd.read_csv(path)


def build_irregularity(cfg: Mapping[str, Any] | None, x_start: float, x_end: float,
                       x_fade_start: float, profile: pd.DataFrame | None = None,
                       direction: int = 1) -> Irregularity:
    """Rail inputs over [x_start, x_end] from an ``irregularity`` section.

    ``source``: ``synthetic`` (``spectrum``, ``seed``, ``dx_m``, ``amplitudes``), ``file``
    (``file``: a profile table on disk), ``none``; or pass ``profile`` (a profile table in
    memory, x = chainage_m), which takes the place of the source. ``scale`` multiplies every
    channel, ``channels`` keeps some of them (the others zero), ``fade_in_m`` is the fade-in
    length, ahead of ``x_fade_start`` in the train's ``direction`` (+1: +x, -1: -x).
    ``amplitudes``: ``random_phase`` (default, deterministic amplitudes) or
    ``gaussian`` (random Fourier coefficients, a stationary Gaussian profile;
    :mod:`ttbpipe.irregularity.synthesis`, docs/irregularity.md "Gaussian representation").
    """
    cfg = dict(cfg or {})
    source = "profile" if profile is not None else cfg.get("source", "synthetic")
    if source == "none":
        return no_irregularity()
    dx = float(cfg.get("dx_m", 0.25))
    if source == "synthetic":
        from .synthesis import DEFAULT_AMPLITUDES, check_amplitudes, synthesize_profiles
        length = x_end - x_start + 2 * dx
        amplitudes = check_amplitudes(cfg.get("amplitudes", DEFAULT_AMPLITUDES),
                                      "irregularity.amplitudes")
        prof = synthesize_profiles(cfg.get("spectrum", "tbt3352"), length, dx,
                                   seed=int(cfg.get("seed", 1)), amplitudes=amplitudes)
        chain = prof["chainage_m"].to_numpy(float) + x_start - dx
    elif source in ("file", "profile"):
        if source == "file":
            path = cfg.get("file")
            if not path:
                raise ValueError("irregularity.file: a Parquet/CSV path is required for "
                                 "source: file")
            prof, where = read_profile_file(path), str(path)
        else:
            prof, where = profile, "irregularity profile"
        check_profile(prof, where)
        chain = prof["chainage_m"].to_numpy(float)
        dx = float(np.diff(chain).mean())
        if chain[0] > x_start or chain[-1] < x_end:
            raise ValueError(f"{where}: chainage {chain[0]:.1f}-{chain[-1]:.1f} m does not cover "
                             f"the wheel positions {x_start:.1f}-{x_end:.1f} m of this run")
    else:
        raise ValueError(f"irregularity.source: {source!r}; expected synthetic | file | none")
    channels = cfg.get("channels", list(SPECTRAL))
    scale = float(cfg.get("scale", 1.0)) * 1e-3  # mm -> m
    spec = {}
    for ch in SPECTRAL:
        spec[ch] = prof[f"{ch}_mm"].to_numpy(float) * scale if ch in channels else np.zeros(len(prof))
    rails = rails_from_spectral(spec["vertical"], spec["alignment"], spec["cross_level"], spec["gauge"])
    values = np.vstack([rails["z_left"], rails["z_right"], rails["y_left"], rails["y_right"]])
    fade = float(cfg.get("fade_in_m", 20.0))
    # start two grid steps ahead so that the interpolated value AND slope are exactly 0 at the
    # leading wheelset's start (central-difference slopes reach one point back)
    ahead = chain - x_fade_start if direction > 0 else x_fade_start - chain
    s = np.clip((ahead - 2.0 * dx) / max(fade, 1e-9), 0.0, 1.0)
    window = 0.5 - 0.5 * np.cos(np.pi * s)
    values = values * window
    slopes = np.gradient(values, dx, axis=1)
    return Irregularity(float(chain[0]), dx, np.ascontiguousarray(values),
                        np.ascontiguousarray(slopes))


@kernel(inline="always")
def irregularity_at(track, channel, x):
    """Value and x-derivative of rail input ``channel`` at x (linear interpolation; 0 outside)."""
    s = (x - track.x0) / track.dx
    n = track.values.shape[1]
    if s < 0.0 or s >= n - 1:
        return 0.0, 0.0
    i = int(s)
    w = s - i
    return (track.values[channel, i] * (1.0 - w) + track.values[channel, i + 1] * w,
            track.slopes[channel, i] * (1.0 - w) + track.slopes[channel, i + 1] * w)
