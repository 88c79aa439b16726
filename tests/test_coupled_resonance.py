"""Resonance of a simply supported span under a regular train (seed paper eq. 55)."""

import copy
from pathlib import Path

import numpy as np
import pytest

from ttbpipe.simulation.config import load_case
from ttbpipe.simulation.coupled import run_coupled
from ttbpipe.structure import build_structure
from ttbpipe.structure.modal import modal_analysis

CASE = load_case(Path(__file__).resolve().parents[1] / "config" / "validation"
                 / "vehicle_resonance_single_span.yaml")
CAR_LENGTH_M = 25.0   # regular train: identical trailer cars, so the load pattern repeats every 25 m


def _deck_peak(speed_kmh: float) -> float:
    case = copy.deepcopy(CASE)
    case["simulation"]["speed_kmh"] = float(speed_kmh)
    _, summary = run_coupled(case)
    return summary["monitor_peaks"]["deck_z_acc_m_s2"]


@pytest.mark.slow
def test_deck_acceleration_peaks_at_resonance_speed():
    """Speed sweep of six identical 25 m cars (perfect track) over one 32 m span: the peak
    mid-span vertical acceleration is largest at V = 3.6 f1 d / i (seed paper eq. 55, Xia et al.;
    i = 1), with f1 the first vertical girder mode of the same structure model (modal analysis)
    and d = 25 m. The sweep covers -20..+20 % of the prediction, in 5 % steps near it; the peak speed is
    refined by a parabola through the three highest points. Tolerance 5 % (project requirement). The
    i = 2 resonance (~254 km/h) is not used: there f1 L / V = 2.55, close to the cancellation
    condition of a 32 m span (free-vibration amplitude ~ |cos(pi f1 L / V)| = 0.15), so its peak
    is suppressed; at i = 1 the factor is 0.63 and grows with V, which tilts the (broad, six-car)
    resonance peak slightly towards higher speeds (measured: +3 %)."""
    assert CASE["train"]["composition"] == ["trailer"] * 6
    f1 = modal_analysis(build_structure(CASE["structure"]), n_modes=4).first("girder_vertical")
    v_pred = 3.6 * f1 * CAR_LENGTH_M
    factors = np.array([0.80, 0.90, 0.95, 1.0, 1.05, 1.10, 1.20])
    peaks = np.array([_deck_peak(v_pred * k) for k in factors])
    i = int(np.argmax(peaks))
    assert 0 < i < factors.size - 1, f"peak at the edge of the sweep: {peaks}"
    # parabola through the three highest neighbours
    x, y = factors[i - 1:i + 2], peaks[i - 1:i + 2]
    a, b, _ = np.polyfit(x, y, 2)
    k_peak = -b / (2 * a)
    assert abs(k_peak - 1.0) < 0.05, f"peak at {k_peak:.3f} x prediction; peaks {peaks}"
    # a resonance, not a monotone growth: the peak clearly exceeds the sweep's ends
    assert peaks[i] > 1.15 * max(peaks[0], peaks[-1])
