"""Anti-alias decimation of time histories inside a time loop (valid to the output's Nyquist).

A loop at step dt records every ``out_every``-th sample of its histories. Picking samples alone
folds everything above the output Nyquist frequency f_N = 1 / (2 out_every dt) back below it:
rail accelerations carry much of their energy at hundreds of hertz, so their 500 Hz histories
were aliased. The :class:`Decimator` low-passes every channel with one linear-phase FIR filter
before it takes the sample, in the loop, in polyphase form (each sample is added to the output
rows whose window holds it; :func:`push`):

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

#: Filter taps; the accumulators buffer[row mod n_rows, channel] of the output rows not yet
#: complete; state = (samples pushed, rows written); decimation factor and delay in steps; the
#: output rows out[row, channel]; the last sample pushed (held by :func:`flush`).
Decimator = namedtuple("Decimator", ["taps", "buffer", "state", "out_every", "delay", "out",
                                     "last"])


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
    # a row is open from its oldest sample to its newest, (n_taps - 1) samples; the slot of row
    # k is reused by row k + n_rows, which opens after row k is written
    n_rows = (taps.size - 1) // int(out_every) + 2
    return Decimator(taps, np.zeros((n_rows, n_channels)), np.zeros(2, dtype=np.int64),
                     int(out_every), (taps.size - 1) // 2, np.zeros((n_out, n_channels)),
                     np.zeros(n_channels))


@kernel(creates_arrays=False)
def _add_sample(dec, s, values):
    """Add sample s (the first sample's value for s < 0: the history held at its start) to
    every output row whose filter window holds it: row k takes taps[j] x[s] with
    j = k out_every + delay - s in [0, n_taps)."""
    n_taps = dec.taps.shape[0]
    q = dec.out_every
    n_rows = dec.buffer.shape[0]
    # k from ceil((s - delay) / q) (and >= 0) to floor((s - delay + n_taps - 1) / q)
    k_first = max(np.int64(0), -((dec.delay - s) // q))
    k_last = min(dec.out.shape[0] - 1, (s - dec.delay + n_taps - 1) // q)
    for k in range(k_first, k_last + 1):
        tap = dec.taps[k * q + dec.delay - s]
        row = dec.buffer[k % n_rows]
        for c in range(values.shape[0]):
            row[c] += tap * values[c]


@kernel(creates_arrays=False)
def push(dec, values):
    """Push the next sample of every channel; write the output row that becomes due.

    Polyphase form: each sample is added, weighted by its tap, to the accumulator of every
    output row whose window holds it, so only the (n_taps - 1) / out_every + 2 open rows are
    kept, not the last n_taps samples (a working set of 81 KB instead of 623 KB for the
    reference case's 266 channels, beside the structure's in the 1 MiB L2 cache). Before the
    first sample the history is held at its value. Row k, centred on sample k out_every, is
    complete, and written, once sample k out_every + delay is in.
    """
    s = dec.state[0]
    if s == 0:
        for held in range(-dec.delay, 0):      # row 0 reaches back to sample -delay
            _add_sample(dec, held, values)
    _add_sample(dec, s, values)
    for c in range(values.shape[0]):
        dec.last[c] = values[c]
    dec.state[0] = s + 1
    k = dec.state[1]
    if k < dec.out.shape[0] and k * dec.out_every + dec.delay == s:
        row = dec.buffer[k % dec.buffer.shape[0]]
        for c in range(values.shape[0]):
            dec.out[k, c] = row[c]
            row[c] = 0.0
        dec.state[1] = k + 1


@kernel
def flush(dec):
    """After the last step: hold the last sample until every output row is written."""
    last = dec.last.copy()
    while dec.state[1] < dec.out.shape[0]:
        push(dec, last)
