"""Paper case studies: the new sample kinds and case-1 runs on tiny structures.

* plain Monte Carlo fields (case 2's MCM): exact marginal statistics, independent of the KLE
  samples of the same index (the two estimates of Fig. 10 must not share random numbers);
* Monte Carlo irregularity profiles (case 3's MCM): a section's profile has the section's
  variance (discrete Parseval);
* tiny designs through the batch runner (every new kind, batch-size independence);
* case 1: rail displacement under a wheel converges with the monitor spacing.

The small variants of the four cases under Snakemake: tests/test_cases_small.py.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from ttbpipe.study.samples import field_factors, mc_profile

TINY_STRUCTURE = {"layout": {"approach_length_m": 30.0, "spans_m": [32.0],
                             "approach_track": "ballasted", "bridge_track": "slab"}}
FIELDS = {"method": "kle", "kernel": "exponential", "correlation_length_m": 10.0,
          "variance_fraction": 0.95, "geometry": {"source": "structure"},
          "groups": {"C2": {"enabled": True, "distribution": "normal", "cov": 0.1,
                            "correlation": [[1.0, 0.8, 0.9, 0.7], [0.8, 1.0, 0.7, 0.8],
                                            [0.9, 0.7, 1.0, 0.7], [0.7, 0.8, 0.7, 1.0]]}}}


def test_mc_fields_have_the_target_statistics_and_are_independent_of_kle():
    """400 samples of pad_kz at one fastener: MC and KLE both have mean 1 and COV 0.1 (normal,
    paper case 2) within 4 standard errors; the correlation between MC sample i and KLE sample i
    is ~0 (|r| < 4/sqrt(N)): the MC scenario has its own seed stream."""
    n = 400
    mc = np.array([field_factors(FIELDS, TINY_STRUCTURE, 5, "C2", i, method="mc")["pad_kz"][40]
                   for i in range(n)])
    kle = np.array([field_factors(FIELDS, TINY_STRUCTURE, 5, "C2", i)["pad_kz"][40]
                    for i in range(n)])
    for x in (mc, kle):
        assert abs(x.mean() - 1.0) < 4 * 0.1 / np.sqrt(n)
        assert abs(x.std(ddof=1) - 0.1) < 4 * 0.1 / np.sqrt(2 * n)
    assert abs(np.corrcoef(mc, kle)[0, 1]) < 4 / np.sqrt(n)
    # deterministic: the same sample again
    again = field_factors(FIELDS, TINY_STRUCTURE, 5, "C2", 7, method="mc")["pad_kz"][40]
    assert again == mc[7]


def _population_file(tmp_path) -> tuple[str, np.ndarray]:
    """A PSD long table of 6 sections (synthetic population with known levels)."""
    from ttbpipe.irregularity.spectra import get_spectrum
    from ttbpipe.tipm.population import synthetic_population

    freq = np.arange(1, 501) * 0.001   # 1/1000 .. 0.5 1/m (2-1000 m)
    spec = get_spectrum("tbt3352")
    channels = ("vertical", "alignment", "cross_level", "gauge")
    mean = np.stack([spec.psd_mm2_m(ch, freq, extrapolate=True) for ch in channels], axis=1)
    pop = synthetic_population(6, freq, mean, np.random.default_rng(2))
    rows = [pd.DataFrame({"section": s, "section_start_m": 1000.0 * s,
                          "section_end_m": 1000.0 * (s + 1), "channel": ch,
                          "spatial_frequency_per_m": freq, "psd_mm2_m": pop.psd_mm2_m[s, :, c]})
            for s in range(6) for c, ch in enumerate(channels)]
    path = tmp_path / "2025-12-15.parquet"
    pd.concat(rows, ignore_index=True).to_parquet(path)
    band = (freq >= 1 / 20 - 1e-12) & (freq <= 1 / 2 + 1e-12)
    tqi = np.sqrt(pop.psd_mm2_m[:, band, :].sum(axis=1) * 0.001)
    return str(path), tqi


def test_mc_profile_has_the_sections_variance(tmp_path):
    """The profile of section s has the variance of section s's PSD over the band (discrete
    Parseval, physics.md section 2): RMS within 3 % of the section's TQI, per channel. Band
    2-20 m: at least 50 cycles of every component in the 1000 m profile, so the truncation of
    the FFT period to the profile length does not bias the sample variance (it does by up to
    ~30 % for 200 m waves)."""
    path, tqi = _population_file(tmp_path)
    population = {"psd_paths": [path], "wavelength_band_m": [2.0, 20.0], "length_m": 1000.0,
                  "dx_m": 0.25, "date": "2025-12-15"}
    for section in (0, 3):
        prof = mc_profile(population, 9, section, sample_index=section)
        rms = prof[["vertical_mm", "alignment_mm", "cross_level_mm", "gauge_mm"]].std(ddof=0).to_numpy()
        np.testing.assert_allclose(rms, tqi[section], rtol=0.03)
    with pytest.raises(ValueError, match="outside the population"):
        mc_profile(population, 9, 6, sample_index=0)


def test_mc_profile_from_the_pooled_table_is_the_same(tmp_path):
    """The workflow's batches read the pooled population table (rule study_mc_population); the
    profile is the one the campaigns' PSD tables give, bit for bit."""
    from ttbpipe.tipm.population import write_pooled_population

    path, _ = _population_file(tmp_path)
    pooled = tmp_path / "mc_population.parquet"
    write_pooled_population([path], [2.0, 20.0], pooled)
    common = {"wavelength_band_m": [2.0, 20.0], "length_m": 400.0, "dx_m": 0.25,
              "date": "2025-12-15"}
    for section in (1, 5):
        pd.testing.assert_frame_equal(
            mc_profile({**common, "psd_paths": [path]}, 9, section, sample_index=7),
            mc_profile({**common, "pooled_path": str(pooled)}, 9, section, sample_index=7),
            check_exact=True)
    with pytest.raises(ValueError, match="pooled over the wavelength band"):
        mc_profile({**common, "wavelength_band_m": [2.0, 200.0], "pooled_path": str(pooled)},
                   9, 1, sample_index=7)


@pytest.mark.slow
def test_new_kinds_through_the_batch_runner(tmp_path):
    """fields_mc, irregularity_mc and single on a tiny bridge (one span, one car, 10 m run):
    every sample runs, extremes are finite, and batch sizes 1 and 3 give identical rows."""
    from ttbpipe.study.batch import simulate_design
    from ttbpipe.study.design import build_design

    path, _ = _population_file(tmp_path)
    study = {"seed": 4, "scenarios": {"irregularity": {"enabled": False},
                                      "forecast": {"enabled": False},
                                      "fields": {"enabled": False},
                                      "fields_mc": {"enabled": True, "conditions": ["C2"], "samples": 2},
                                      "irregularity_mc": {"enabled": True, "samples": 2}}}
    design = build_design(study, latest_campaign="2025-12-15", n_population_sections=6)
    config = {"study": study, "structure": TINY_STRUCTURE, "fields": FIELDS,
              "simulation": {"train": {"composition": ["trailer"]}, "end_x_m": 35.0},
              "assessment": {"standard": []}}   # too short a run for the standards' filters
    profiles = {"irregularity_mc": {"psd_paths": [path], "wavelength_band_m": [2.0, 200.0],
                                    "length_m": 300.0, "dx_m": 0.25, "date": "2025-12-15"}}
    results = {}
    for size in (1, 3):
        root = tmp_path / f"b{size}"
        simulate_design(design, config, profiles, str(root), batch_size=size)
        ext = pd.concat([pd.read_parquet(p) for p in sorted(root.rglob("extremes_*.parquet"))])
        results[size] = ext.sort_values(["scenario", "sample_index"]).reset_index(drop=True)
    assert len(results[1]) == 4 and set(results[1]["scenario"]) == {"C2_mc", "mc"}
    numeric = results[1].select_dtypes("number")
    assert np.isfinite(numeric.to_numpy()).all()
    pd.testing.assert_frame_equal(results[1], results[3])
    # two MC irregularity samples differ (different sections / phases)
    mc = results[1][results[1]["scenario"] == "mc"]
    assert mc["max_wheel_vertical_force_N"].nunique() == 2


@pytest.mark.slow
def test_rail_displacement_under_the_wheel_converges_with_monitor_spacing():
    """Fig. 6's rail displacement under a wheel, interpolated between rail monitors: 0.25 m and
    0.125 m spacings agree within 2 % of the peak displacement (vertical) at every output time
    (second method: a finer interpolation grid; pads are 0.63 m apart)."""
    from ttbpipe.study.cases import time_history_run

    config = {"study": {"seed": 1}, "structure": TINY_STRUCTURE,
              "simulation": {"train": {"composition": ["trailer"]}, "end_x_m": 62.0,
                             "output_interval_s": 1e-3}}
    coarse, layout = time_history_run(config, 200.0, car=1, wheelset=1, spacing_m=0.25)
    fine, _ = time_history_run(config, 200.0, car=1, wheelset=1, spacing_m=0.125)
    ok = coarse["rail_vertical_disp_m"].notna() & fine["rail_vertical_disp_m"].notna()
    assert ok.sum() > 50
    a, b = coarse.loc[ok, "rail_vertical_disp_m"], fine.loc[ok, "rail_vertical_disp_m"]
    assert np.max(np.abs(a - b)) < 0.02 * np.max(np.abs(b))
    assert b.min() < 0      # the wheel presses the rail down (z up)
    assert layout["span"] == 1


def test_wheel_lift_is_reported_not_failed():
    """A wheel that lifts off with a lateral force (P = 0: the coupled table flags the step
    out of contact and writes Q/P = 0 there, Q/P being defined in contact only) does not stop
    the study: the extremes take the run's largest in-contact Q/P and its contact-loss index,
    and the history replaces the lifted steps by the wheel's largest in-contact Q/P (so the
    history statistics stay finite and conservative). Other non-finite indices still fail."""
    from ttbpipe.study.samples import extremes_from_run, history_from_run, resolve_simulation

    sim = resolve_simulation({})
    n = 50
    t = np.arange(n) * 2e-3
    qp = np.full(n, 0.1)
    qp[10] = 0.0
    qp[20] = 0.4
    table = pd.DataFrame({"time_s": t, "x_lead_m": 100 + 80 * t, "car1_ws1_left_QP": qp,
                          "car1_ws1_left_P_N": np.where(np.arange(n) == 10, 0.0, 7e4),
                          "car1_ws1_left_in_contact": (np.arange(n) != 10).astype(np.int8),
                          "car1_ws1_left_Q_N": 1e3, "car1_body_front_az_m_s2": 0.0,
                          "car1_body_front_ay_m_s2": 0.0})
    for axis in ("z", "y"):
        table[f"girder_span1_mid_{axis}_acc_m_s2"] = np.sin(t * 50)
        table[f"girder_span1_mid_{axis}_disp_mm"] = -0.5
        table[f"rail_left_span1_mid_{axis}_acc_m_s2"] = 1.0
    summary = {"speed_kmh": 300.0, "static_wheel_load_N": {"car1": [7e4]},
               "max_derailment_coefficient": 0.4, "max_wheel_unloading_ratio": 1.0,
               "max_lateral_wheelset_force_N": 2e3, "max_wheel_vertical_force_N": 9e4,
               "max_wheel_lateral_force_N": 1e3, "max_carbody_vertical_acc_m_s2": 0.1,
               "max_carbody_lateral_acc_m_s2": 0.1, "contact_loss_count": 1,
               "contact_loss_total_duration_s": 2e-3, "contact_loss_max_duration_s": 2e-3,
               "time_step_s": 1e-4, "sperling_vertical_car1": 1.5, "sperling_lateral_car1": 1.5,
               "dt_limits": {}, "sperling": {"car1_vertical": 1.5, "car1_lateral": 1.5},
               "monitor_peaks": {}}
    ext = extremes_from_run(summary)
    assert ext["max_derailment_coefficient"] == 0.4
    assert ext["contact_loss_count"] == 1 and ext["contact_loss_max_duration_s"] == 2e-3
    hist = history_from_run(table, sim, 1)
    assert hist["derailment_coefficient"].iloc[10] == 0.4 and np.isfinite(hist.to_numpy()).all()
    with pytest.raises(RuntimeError, match="non-finite"):
        extremes_from_run({**summary, "max_wheel_vertical_force_N": np.nan})
