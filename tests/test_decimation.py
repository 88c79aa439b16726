"""Anti-alias decimation of histories (ttbpipe.decimation) and the recorders that use it.

References: the streaming filter against numpy's convolution of the whole record (a slow,
obviously correct second method); sinusoids against the filter's design targets (pass band
flat to 0.8 f_N within the 1e-3 ripple, stop band from f_N on 60 dB down: Kaiser-window design,
Oppenheim & Schafer, Discrete-Time Signal Processing, 3rd ed., s. 7.6); a rail-acceleration
history of the coupled model against the full-rate history low-passed at the output's Nyquist
frequency by an independent filter (an FFT brick wall).
"""

import numpy as np
import pytest
from numba import njit

from ttbpipe.decimation import (PASS_FRACTION, STOP_ATTENUATION_DB, decimation_taps, decimator,
                                flush, push)
from ttbpipe.simulation.coupled import run_coupled


@njit(cache=True)
def _push_all(dec, x):
    for s in range(x.shape[0]):
        push(dec, x[s])
    flush(dec)


def decimate(x: np.ndarray, q: int) -> np.ndarray:
    """Streaming decimation of the columns of ``x`` (n_samples, n_channels)."""
    n_out = (x.shape[0] - 1) // q + 1
    dec = decimator(x.shape[1], n_out, q)
    _push_all(dec, np.ascontiguousarray(x, dtype=float))
    return dec.out


def convolve_reference(x: np.ndarray, q: int) -> np.ndarray:
    """Zero-phase FIR of the whole record (edges held at the end values), every q-th sample."""
    h = decimation_taps(q)
    d = (h.size - 1) // 2
    padded = np.concatenate([np.full(d, x[0]), x, np.full(d, x[-1])])
    return np.convolve(padded, h, mode="valid")[::q]


def brick_wall(x: np.ndarray, fs: float, cutoff_hz: float) -> np.ndarray:
    spectrum = np.fft.rfft(x - x.mean())
    spectrum[np.fft.rfftfreq(x.size, 1.0 / fs) > cutoff_hz] = 0.0
    return np.fft.irfft(spectrum, x.size) + x.mean()


@pytest.mark.parametrize("q", [2, 8, 16])
def test_streaming_decimation_equals_the_convolution_of_the_whole_record(q):
    rng = np.random.default_rng(q)
    x = np.cumsum(rng.standard_normal((3001, 3)), axis=0)
    out = decimate(x, q)
    for c in range(3):
        ref = convolve_reference(x[:, c], q)
        assert out.shape[0] == ref.size
        # round-off only (the same sums in another order)
        assert np.max(np.abs(out[:, c] - ref)) <= 1e-12 * np.max(np.abs(x[:, c]))


@pytest.mark.parametrize("n_samples", [1, 9, 150, 301])
def test_records_shorter_than_the_filter_hold_both_ends(n_samples):
    """Records shorter than the filter (293 taps at q = 8): every output row reaches back before
    the first sample or beyond the last, held at those values (the convolution reference pads
    them the same way)."""
    rng = np.random.default_rng(n_samples)
    x = np.cumsum(rng.standard_normal((n_samples, 2)), axis=0) + 5.0
    out = decimate(x, 8)
    for c in range(2):
        ref = convolve_reference(x[:, c], 8)
        assert out.shape[0] == ref.size
        assert np.max(np.abs(out[:, c] - ref)) <= 1e-12 * np.max(np.abs(x[:, c]))


def test_every_step_is_recorded_unfiltered_when_out_every_is_one():
    x = np.random.default_rng(0).standard_normal((50, 2))
    assert np.array_equal(decimate(x, 1), x)


@pytest.mark.parametrize("q", [4, 8, 16])
def test_pass_band_is_kept_and_the_stop_band_does_not_alias(q):
    fs = 8000.0
    f_nyq = fs / (2 * q)
    t = np.arange(40 * 2 * q * 64) / fs
    n_edge = 2 * decimation_taps(q).size // q            # rows that see the held edges
    ripple = 1e-3                                        # the design's pass-band ripple
    for fraction in (0.1, 0.5, PASS_FRACTION):
        x = np.sin(2 * np.pi * fraction * f_nyq * t)
        out = decimate(x[:, None], q)[n_edge:-n_edge, 0]
        expected = x[::q][n_edge:-n_edge]
        assert np.max(np.abs(out - expected)) <= 1.5 * ripple
    stop = 10.0 ** (-STOP_ATTENUATION_DB / 20.0)
    for fraction in (1.0, 1.3, 3.7):
        x = np.cos(2 * np.pi * fraction * f_nyq * t)
        out = decimate(x[:, None], q)[n_edge:-n_edge, 0]
        # picked samples would be a full-amplitude alias at or below f_N
        assert np.max(np.abs(x[::q][n_edge:-n_edge])) > 0.9
        assert np.max(np.abs(out)) <= 1.1 * stop


@pytest.mark.slow
def test_a_decimated_rail_acceleration_is_the_full_rate_history_low_passed():
    """The rail under a passing car, 8 kHz steps, recorded at 1 kHz (f_N = 500 Hz).

    A third of this history's variance (1.9 m/s^2 rms) lies above f_N (the rail on its pads
    under the wheels), so picking samples folds it into the band below. Compared up to
    0.8 f_N with the full-rate history brick-walled there, the recorder's history is equal
    within 1 % of the band's rms (expected: stop band 1e-3 of the content above f_N plus the
    1e-3 ripple, ~0.2 %; measured 0.18 %); the picked samples are 62 % off (regression
    values of this case, not references)."""
    q = 8
    dt = 1.25e-4
    case = {"structure": {"layout": {"approach_length_m": 30.0, "spans_m": [32.0],
                                     "approach_track": "ballasted", "bridge_track": "slab"}},
            "train": {"composition": ["trailer"]},
            "monitors": [{"name": "rail", "kind": "rail", "rail": 0, "x_m": 46.0,
                          "directions": ["z"], "quantities": ["acceleration"]}],
            "irregularity": {"source": "synthetic", "spectrum": "tbt3352", "seed": 3,
                             "dx_m": 0.25, "fade_in_m": 5.0},
            "simulation": {"speed_kmh": 300.0, "time_step_s": dt, "end_x_m": 80.0}}
    histories = {}
    for every in (1, q):
        table, _ = run_coupled({**case, "simulation": {**case["simulation"],
                                                       "output_every": every}})
        histories[every] = table["rail_z_acc_m_s2"].to_numpy()
    # the run's step count is a multiple of the output interval: a few steps more with q
    n_rows = (histories[1].size - 1) // q + 1
    full, recorded = histories[1], histories[q][:n_rows]
    fs = 1.0 / dt
    f_nyq = fs / (2 * q)
    above = full - brick_wall(full, fs, f_nyq)
    assert np.var(above) > 0.25 * np.var(full)         # the case is a test of aliasing
    band = PASS_FRACTION * f_nyq
    reference = brick_wall(full, fs, band)[::q]
    interior = slice(150, -150)                        # away from the brick wall's wrap-around
    scale = np.std(reference[interior])
    error = brick_wall(recorded, fs / q, band) - reference
    naive = brick_wall(full[::q], fs / q, band) - reference
    assert np.sqrt(np.mean(error[interior] ** 2)) <= 0.01 * scale
    assert np.sqrt(np.mean(naive[interior] ** 2)) >= 0.3 * scale
