"""Filter designs shared by the run's reductions and the standards' processing."""

from __future__ import annotations

import functools

import numpy as np


def butterworth_sos(order: int, cutoff_hz: float | tuple[float, float], btype: str,
                    fs_hz: float) -> np.ndarray:
    """Second-order sections of a digital Butterworth filter (``scipy.signal.butter``,
    ``output="sos"``), designed once per (order, cut-off, type, sampling rate) in a process:
    every sample of a study filters its records with the same few designs, and a design costs
    more than filtering a short record. A copy each call (scipy's filters take writable
    arrays)."""
    return _butterworth_design(int(order), cutoff_hz, str(btype), float(fs_hz)).copy()


@functools.lru_cache(maxsize=256)
def _butterworth_design(order: int, cutoff_hz, btype: str, fs_hz: float) -> np.ndarray:
    from scipy import signal

    return signal.butter(order, cutoff_hz, btype=btype, fs=fs_hz, output="sos")
