"""Anti-alias decimation of time histories inside a time loop (valid to the output's Nyquist).

A loop at step dt records every ``out_every``-th sample of its histories. Picking samples alone
folds everything above the output Nyquist frequency f_N = 1 / (2 out_every dt) back below it:
rail accelerations carry much of their energy at hundreds of hertz, so their 500 Hz histories
were aliased. The :class:`Decimator` low-passes every channel with one linear-phase FIR filter
before it takes the sample, in the loop, with a ring buffer per channel:

* design (:func:`decimation_taps`): a Kaiser-window FIR (scipy.signal.kaiserord/firwin, the
  window method of Oppenheim & Schafer) with its pass band flat to 0.8 f_N (ripple 1e-3) and its
  stop band from f_N on (60 dB down), so no component above f_N lands below it more than
  attenuated 1000 times; odd length, symmetric taps, so the filter delays every frequency by
  exactly (n - 1)/2 steps;
* the output row k (t = k out_every dt) is the filter's output at step k out_every + delay,
  i.e. the zero-phase low-passed history sampled at t: no time shift;
* edges: before the first sample the history is held at its first value (a run starts from a
  static state), after the last at its last value (:func:`flush`).

Peaks are not affected: the loops take them at every step from the unfiltered values.
``out_every = 1`` records every step without filtering.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from .jit import kernel

#: Pass-band edge (fraction of the output Nyquist frequency), stop-band attenuation (dB).
PASS_FRACTION = 0.8
STOP_ATTENUATION_DB = 60.0

#: Filter taps, the ring buffer buffer[tap, channel] (one row per sample: a push writes one
#: contiguous row), state = (next write position, samples pushed, rows written), decimation
#: factor and delay in steps, and the output rows out[row, channel].
Decimator = namedtuple("Decimator", ["taps", "buffer", "state", "out_every", "delay", "out"])


def decimation_taps(out_every: int) -> np.ndarray:
    """FIR taps of the anti-alias filter for decimation by ``out_every`` (module docstring)."""
    from scipy import signal

    q = int(out_every)
    if q <= 1:
        return np.ones(1)
    nyquist_out = 0.5 / q                       # in units of the input rate (cycles per step)
    width = (1.0 - PASS_FRACTION) * nyquist_out / 0.5   # transition width, fraction of Nyquist
    n, beta = signal.kaiserord(STOP_ATTENUATION_DB, width)
    n += 1 - n % 2                              # odd: an integer delay
    cutoff = 0.5 * (1.0 + PASS_FRACTION) * nyquist_out
    return signal.firwin(n, cutoff, window=("kaiser", beta), fs=1.0)


def decimator(n_channels: int, n_out: int, out_every: int) -> Decimator:
    """A decimator for ``n_channels`` histories giving ``n_out`` output rows."""
    taps = decimation_taps(out_every)
    return Decimator(taps, np.zeros((taps.size, n_channels)), np.zeros(3, dtype=np.int64),
                     int(out_every), (taps.size - 1) // 2, np.zeros((n_out, n_channels)))


@kernel
def _emit(dec, newest):
    """Write the next output row: the filter output centred ``delay`` samples behind sample
    ``newest`` (the row's own time)."""
    row = dec.state[2]
    n_taps = dec.taps.shape[0]
    n_channels = dec.buffer.shape[1]
    out = dec.out
    for c in range(n_channels):
        out[row, c] = 0.0
    # tap by tap over contiguous rows (each channel sums its taps in the order j = 0, 1, ...)
    for j in range(n_taps):
        sample = dec.buffer[(newest - j) % n_taps]
        tap = dec.taps[j]
        for c in range(n_channels):
            out[row, c] += tap * sample[c]
    dec.state[2] = row + 1


@kernel
def push(dec, values):
    """Push the next sample of every channel; write the output row that becomes due.

    Sample s goes to ring position s mod n_taps; before the first, the ring holds the first
    sample (the history held at its start value). Row k, centred on sample k out_every, is due
    once sample k out_every + delay is in.
    """
    n_taps = dec.taps.shape[0]
    s = dec.state[1]
    if s == 0:
        for j in range(n_taps):
            for c in range(values.shape[0]):
                dec.buffer[j, c] = values[c]
    pos = s % n_taps
    for c in range(values.shape[0]):
        dec.buffer[pos, c] = values[c]
    dec.state[1] = s + 1
    k = dec.state[2]
    if k < dec.out.shape[0] and k * dec.out_every + dec.delay == s:
        _emit(dec, s)


@kernel
def flush(dec):
    """After the last step: hold the last sample until every output row is written."""
    n_taps = dec.taps.shape[0]
    last = np.empty(dec.buffer.shape[1])
    pos = (dec.state[1] - 1) % n_taps
    for c in range(dec.buffer.shape[1]):
        last[c] = dec.buffer[pos, c]
    while dec.state[2] < dec.out.shape[0]:
        push(dec, last)
