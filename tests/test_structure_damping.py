"""Girder damping: EN 1991-2 Table 6.6 / eq. 6.13 values and the damping every mode receives.

References: EN 1991-2:2003 Table 6.6 (standards sheet, docs/reference/standards.md) for the
values; for the matrices, the damping ratio of each undamped mode phi^T C phi / (2 omega) from
the structure's modal analysis (the global M, K, C the time loop uses) against the closed forms:
modal damping gives every mode zeta exactly (to round-off, 1e-9), Rayleigh damping gives
alpha / (2 omega) + beta omega / 2 (Clough & Penzien, Dynamics of Structures, eq. 12-39).
The resonant amplitude of the second vertical mode integrated by the moving-load loop gives the
same ratio (a third, time-domain method; within 1 %).
"""

from pathlib import Path

import numpy as np
import pytest

from ttbpipe.simulation.config import load_case
from ttbpipe.structure import build_structure
from ttbpipe.structure.damping import (additional_damping_ratio, girder_damping_ratio,
                                       table_6_6_damping_ratio)
from ttbpipe.structure.modal import modal_analysis

CONFIG = Path(__file__).resolve().parents[1] / "config" / "validation"


def test_table_6_6_values():
    # EN 1991-2 Table 6.6 rows at L = 10 m and L >= 20 m, in per cent
    assert table_6_6_damping_ratio(32.0, "prestressed_concrete") == pytest.approx(0.010)
    assert table_6_6_damping_ratio(10.0, "prestressed_concrete") == pytest.approx(0.017)
    assert table_6_6_damping_ratio(10.0, "steel_composite") == pytest.approx(0.0175)
    assert table_6_6_damping_ratio(25.0, "steel_composite") == pytest.approx(0.005)
    assert table_6_6_damping_ratio(10.0, "reinforced_concrete") == pytest.approx(0.022)
    assert table_6_6_damping_ratio(40.0, "reinforced_concrete") == pytest.approx(0.015)
    with pytest.raises(ValueError, match="construction.*Table 6.6"):
        table_6_6_damping_ratio(10.0, "timber")


def test_additional_damping_follows_eq_6_13():
    # eq. 6.13 evaluated by hand at L = 10 m: 0.123 / 0.374 = 0.3289 %; none from 30 m on
    assert additional_damping_ratio(10.0) == pytest.approx(0.003289, rel=1e-3)
    assert additional_damping_ratio(30.0) == 0.0
    assert additional_damping_ratio(45.0) == 0.0
    peak = max(additional_damping_ratio(L) for L in np.arange(1.0, 30.0, 0.5))
    assert 0.005 < peak < 0.008                       # Figure 6.15 peaks near 15 m at ~0.6 %
    girder = {"damping_ratio": None, "construction": "prestressed_concrete",
              "additional_damping": True}
    assert girder_damping_ratio(10.0, girder) == pytest.approx(0.017 + 0.003289, rel=1e-3)
    assert girder_damping_ratio(10.0, {**girder, "damping_ratio": 0.02}) == pytest.approx(
        0.02 + 0.003289, rel=1e-3)


def girder_only(**girder):
    case = load_case(CONFIG / "girder_modal.yaml")
    structure = {**case["structure"], "girder": {**case["structure"].get("girder", {}), **girder}}
    return build_structure(structure)


def vertical_modes(result):
    hit = result.shares["girder_vertical"] > 0.9
    return result.frequencies_hz[hit], result.damping_ratios[hit]


def test_modal_damping_gives_every_span_mode_the_table_value():
    model = girder_only()                      # 32 m prestressed: Table 6.6 gives 1.0 %
    result = modal_analysis(model, n_modes=16)
    f_v, zeta_v = vertical_modes(result)
    assert f_v.size >= 4                       # the modes up to 120 Hz that matter
    assert np.allclose(zeta_v, 0.010, rtol=1e-9, atol=0)
    kept = result.frequencies_hz <= model.spans[0].mode_frequencies_hz[0].max() * 1.001
    assert np.allclose(result.damping_ratios[kept], 0.010, rtol=1e-9, atol=0)


def test_rayleigh_damping_is_exact_only_at_its_pair():
    model = girder_only(damping_model="rayleigh", damping_ratio=0.02)
    red = model.spans[0]
    result = modal_analysis(model, n_modes=16)
    f_v, zeta_v = vertical_modes(result)
    omega = 2 * np.pi * f_v
    closed_form = red.rayleigh_alpha / (2 * omega) + red.rayleigh_beta * omega / 2
    assert np.allclose(zeta_v, closed_form, rtol=1e-9)
    assert zeta_v[0] == pytest.approx(0.02, rel=1e-9)      # the first mode is one of the pair
    # the pair is the first vertical and the first torsion mode: the second to fourth vertical
    # modes get 2.6 %, 5.3 % and 9.2 % for the nominal 2 %
    assert zeta_v[1] > 1.3 * 0.02 and zeta_v[3] > 4.5 * 0.02


@pytest.mark.slow
def test_resonant_amplitude_of_the_second_vertical_mode_has_the_modal_ratio():
    """Two harmonic forces F at the quarter points, in opposite phase, at the second vertical
    frequency: only the antisymmetric modes are driven, the second at resonance. Its steady
    amplitude at the quarter point is 2 F / (2 zeta K_2), K_2 = omega_2^2 m L / 2 (simply
    supported beam, modal mass m L / 2; mode 6, the next one driven, adds 2F/(81 K_2): 2.5e-4
    of it). The moving-load loop's steady amplitude gives zeta within 1 % of 1.0 % (transient
    left: exp(-zeta omega_2 t) < 1e-3)."""
    from ttbpipe.simulation.moving_load_case import run_moving_loads

    model = girder_only()
    f2 = float(model.spans[0].mode_frequencies_hz[0][1])
    force = 1.0e5
    case = load_case(CONFIG / "girder_modal.yaml")
    drive = {"Fz_amplitude_N": force, "frequency_hz": f2, "phase_rad": 0.0}
    case["loads"] = {"target": "girder", "point_loads": [
        {"x0_m": 8.0, "speed_kmh": 0.0, "Fz_N": 0.0, "harmonic": drive},
        {"x0_m": 24.0, "speed_kmh": 0.0, "Fz_N": 0.0, "harmonic": {**drive, "phase_rad": np.pi}}]}
    settle = 7.0 / (0.010 * 2 * np.pi * f2)
    case["simulation"] = {"time_step_s": 2.0e-4, "duration_s": settle + 4.0 / f2,
                          "output_every": 1}
    case["monitors"] = [{"name": "quarter", "kind": "girder", "span": 0, "position": 0.25,
                         "directions": ["z"], "quantities": ["displacement"]}]
    table, _ = run_moving_loads(case)
    t = table["time_s"].to_numpy()
    z = table["quarter_z_disp_mm"].to_numpy() / 1e3
    amplitude = np.max(np.abs(z[t > settle]))
    length, mass = 32.0, 2.972e4
    stiffness_2 = (2 * np.pi * f2) ** 2 * mass * length / 2
    zeta = force / (amplitude * stiffness_2)
    assert zeta == pytest.approx(0.010, rel=0.01)   # measured 1.001 %
