"""The ``amplitudes`` choice of profile synthesis (random phases | Gaussian coefficients) as a
configuration key: a run's ``irregularity:`` section, the study's ``simulation.irregularity``
(mean-spectrum profile) and ``tipm.profiles`` (TIPM, forecast and Monte Carlo profiles).

Theory (ttbpipe.irregularity.synthesis, docs/irregularity.md "Gaussian representation"): over
one full FFT period (profile samples = FFT size) the mean square of a realisation is, by
Parseval for ``irfft``, exactly

    S = Σ_k w_k E_k,   w_k = G(n_k) Δn,   E_k = (a_k² + b_k²)/2 ~ Exp(1) independent

for the Gaussian form (chi-square with 2 degrees of freedom per frequency, halved), and exactly
S = Σ_k w_k for random phases. Hence E[S] = Σ w_k (the grid sum of ∫G dn over the band),
Var[S] = Σ w_k², i.e. the relative variance Var[S]/E[S]² = Σ G_k²/(Σ G_k)²; the cumulants of
S are κ_r = (r − 1)! Σ w_k^r, so its excess kurtosis is γ = 6 Σ w⁴/(Σ w²)², which sets the
standard error of the sample variance of S: Var[s²] ≈ Var[S]² (2 + γ)/M for M realisations
(e.g. Kendall & Stuart, The Advanced Theory of Statistics, vol. 1, §10.5). Every tolerance below
is 4 such standard errors (fixed seeds), unless it is round-off.
"""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml
from scipy import stats

from ttbpipe.channels import SPECTRAL_CHANNELS
from ttbpipe.configuration import ConfigurationError, section_defaults, validate_study_config
from ttbpipe.io import write_table
from ttbpipe.irregularity.spectra import get_spectrum
from ttbpipe.irregularity.synthesis import (AMPLITUDES, DEFAULT_AMPLITUDES,
                                            gaussian_band_frequencies, synthesize_channel,
                                            synthesize_from_psd_table, synthesize_profiles)
from ttbpipe.irregularity.track_input import build_irregularity

REPO = Path(__file__).resolve().parents[1]
SPECTRUM = get_spectrum("tbt3352")
DX = 0.25
N_FFT = 8000                    # FFT-friendly (2^6 · 5^3) and even: the profile is one period
LENGTH = (N_FFT - 1) * DX       # 8000 samples, Δn = 1/(8000 · 0.25 m) = 0.0005 1/m
BAND = (2.0, 200.0)             # both edges on the grid (n = 0.005 and 0.5 1/m)


def _band_weights(channel: str) -> np.ndarray:
    """w_k = G(n_k) Δn over the in-band FFT frequencies of the full-period grid."""
    n = gaussian_band_frequencies(LENGTH, DX, BAND)
    return SPECTRUM.psd_mm2_m(channel, n) / (N_FFT * DX)


def _moments(amplitudes: str, channel: str, m: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """(mean z², mean z⁴) over the whole profile of each of m realisations (mm², mm⁴)."""
    psd = SPECTRUM.as_function(channel)
    rng = np.random.default_rng(seed)
    m2, m4 = np.empty(m), np.empty(m)
    for i in range(m):
        z = synthesize_channel(psd, LENGTH, DX, rng, BAND, amplitudes=amplitudes)
        assert z.size == N_FFT
        m2[i], m4[i] = np.mean(z ** 2), np.mean(z ** 4)
    return m2, m4


@pytest.fixture(scope="module")
def vertical_moments():
    """TB/T 3352 vertical (steep, n^-3.39 at long waves: few frequencies carry most of the
    variance, so one realisation's variance scatters by sqrt(0.091) = 30 %)."""
    return {"gaussian": _moments("gaussian", "vertical", 4000, 11),
            "random_phase": _moments("random_phase", "vertical", 1000, 12)}


def _pooled_kurtosis(m2: np.ndarray, m4: np.ndarray) -> tuple[float, float]:
    """Excess kurtosis of the values of all realisations pooled, mean(m4)/mean(m2)² − 3 (each
    profile's mean is exactly 0: the k = 0 bin is zero), and its standard error by the delta
    method over the realisations, which are independent (the values within one are not)."""
    a, b = m4.mean(), m2.mean()
    grad = np.array([1.0 / b ** 2, -2.0 * a / b ** 3])
    se = float(np.sqrt(grad @ np.cov(np.vstack([m4, m2])) @ grad / m2.size))
    return float(a / b ** 2 - 3.0), se


# ---------------------------------------------------------------------------------------------
# default path unchanged


def test_the_default_is_random_phase_bit_for_bit():
    """Leaving ``amplitudes`` out gives exactly the random-phase profiles (same generator draws),
    in the functions and in a run's ``irregularity:`` section."""
    assert DEFAULT_AMPLITUDES == "random_phase" and AMPLITUDES == ("random_phase", "gaussian")
    psd = SPECTRUM.as_function("vertical")
    a = synthesize_channel(psd, 500.0, DX, np.random.default_rng(3), BAND)
    b = synthesize_channel(psd, 500.0, DX, np.random.default_rng(3), BAND,
                           amplitudes="random_phase")
    assert np.array_equal(a, b)
    pd.testing.assert_frame_equal(synthesize_profiles("tbt3352", 500.0, DX, seed=4),
                                  synthesize_profiles("tbt3352", 500.0, DX, seed=4,
                                                      amplitudes="random_phase"), check_exact=True)
    freq = np.arange(5, 501) / 1000.0                     # 1/m, the 2-200 m band
    table = {ch: SPECTRUM.psd_mm2_m(ch, freq) for ch in SPECTRAL_CHANNELS}
    pd.testing.assert_frame_equal(
        synthesize_from_psd_table(freq, table, 300.0, DX, 5, BAND),
        synthesize_from_psd_table(freq, table, 300.0, DX, 5, BAND, amplitudes="random_phase"),
        check_exact=True)
    run = {"source": "synthetic", "spectrum": "tbt3352", "seed": 6, "dx_m": DX}
    default = build_irregularity(run, 0.0, 300.0, 10.0)
    explicit = build_irregularity({**run, "amplitudes": "random_phase"}, 0.0, 300.0, 10.0)
    gaussian = build_irregularity({**run, "amplitudes": "gaussian"}, 0.0, 300.0, 10.0)
    assert np.array_equal(default.values, explicit.values)
    assert np.array_equal(default.slopes, explicit.slopes)
    assert not np.allclose(default.values, gaussian.values)
    assert np.array_equal(gaussian.values,
                          build_irregularity({**run, "amplitudes": "gaussian"}, 0.0, 300.0,
                                             10.0).values)


# ---------------------------------------------------------------------------------------------
# statistics of the two representations


def test_gaussian_band_variance_is_random_with_the_chi_square_spread(vertical_moments):
    """Gaussian: over M = 4000 full-period realisations, the mean of the per-realisation
    variance S is Σ w_k within 4 standard errors sqrt(Σ w²/M) (SE 0.5 %), and its relative
    variance s²/mean² is Σ G²/(Σ G)² = 0.091 within 4 standard errors, relative SE
    sqrt((2 + γ)/M) = 3 % with γ = 6 Σ w⁴/(Σ w²)² = 1.6 (module docstring). Σ w_k is the grid
    sum of ∫G dn: with the band edges on the grid it is the trapezoid rule plus half an edge bin
    at each end, and the trapezoid rule is within 1 % of the quadrature integral (0.63 % for
    the steep vertical spectrum). Random phases: S = Σ w_k in every realisation (round-off)."""
    w = _band_weights("vertical")
    integral = SPECTRUM.band_rms_mm("vertical", BAND) ** 2
    assert w.sum() - 0.5 * (w[0] + w[-1]) == pytest.approx(integral, rel=0.01)

    m2, _ = vertical_moments["gaussian"]
    m = m2.size
    assert abs(m2.mean() - w.sum()) < 4.0 * np.sqrt(np.sum(w ** 2) / m)
    theory = np.sum(w ** 2) / w.sum() ** 2
    g = SPECTRUM.psd_mm2_m("vertical", gaussian_band_frequencies(LENGTH, DX, BAND))
    assert theory == pytest.approx(np.sum(g ** 2) / np.sum(g) ** 2, rel=1e-12)
    gamma = 6.0 * np.sum(w ** 4) / np.sum(w ** 2) ** 2
    relative = m2.var(ddof=1) / m2.mean() ** 2
    assert relative == pytest.approx(theory, rel=4.0 * np.sqrt((2.0 + gamma) / m))
    assert relative > 0.05                 # the spread is real, not round-off

    fixed, _ = vertical_moments["random_phase"]
    assert np.ptp(fixed) < 1e-12 * w.sum()
    assert fixed[0] == pytest.approx(w.sum(), rel=1e-12)


def test_gaussian_values_are_normal_and_random_phase_values_are_not(vertical_moments):
    """Pooled over realisations, every value of the Gaussian form is N(0, Σ w) (a linear map
    of normals): pooled excess kurtosis within 4 delta-method standard errors of 0 (SE 0.01
    for M = 4000). The random-phase sum of cosines has the excess kurtosis
    −1.5 Σ A⁴/(Σ A²)² = −1.5 Σ w²/(Σ w)² = −0.136 (A_k² = 2 w_k; docs/irregularity.md), within
    4 SE (0.013 for M = 1000): 10 SE away from 0, so the test can tell them apart. The moment
    estimate equals ``scipy.stats.kurtosis`` of the pooled values (checked on 40 profiles)."""
    w = _band_weights("vertical")
    kurt, se = _pooled_kurtosis(*vertical_moments["gaussian"])
    assert se < 0.015 and abs(kurt) < 4.0 * se
    kurt_phase, se_phase = _pooled_kurtosis(*vertical_moments["random_phase"])
    expected = -1.5 * np.sum(w ** 2) / w.sum() ** 2
    assert abs(kurt_phase - expected) < 4.0 * se_phase
    assert abs(kurt_phase) > 8.0 * se_phase

    rng = np.random.default_rng(13)
    psd = SPECTRUM.as_function("vertical")
    values = np.concatenate([synthesize_channel(psd, LENGTH, DX, rng, BAND, amplitudes="gaussian")
                             for _ in range(40)])
    m2 = values.reshape(40, -1) ** 2
    assert _pooled_kurtosis(m2.mean(axis=1), (m2 ** 2).mean(axis=1))[0] == pytest.approx(
        stats.kurtosis(values), abs=1e-9)


# ---------------------------------------------------------------------------------------------
# the study path

FREQ = np.arange(5, 501, 5) / 1000.0
DATE = "2024-06-15"
PSD_CFG = {"wavelength_band_m": [2.0, 200.0]}
TIPM_CFG = {"profiles": {"length_m": 200.0, "dx_m": 0.25}}
GAUSSIAN_TIPM = {"profiles": {**TIPM_CFG["profiles"], "amplitudes": "gaussian"}}


@pytest.fixture(scope="module")
def psd_file(tmp_path_factory):
    """One campaign of six 1 km sections (TB/T 3352 levels with Welch scatter)."""
    from ttbpipe.tipm import synthetic_population

    mean = np.stack([SPECTRUM.psd_mm2_m(c, FREQ) for c in SPECTRAL_CHANNELS], axis=1)
    pop = synthetic_population(6, FREQ, mean, np.random.default_rng(0), welch_dof=2.0)
    rows = [pd.DataFrame({"section": s, "section_start_m": 1000.0 * s,
                          "section_end_m": 1000.0 * (s + 1), "channel": ch,
                          "spatial_frequency_per_m": FREQ, "psd_mm2_m": pop.psd_mm2_m[s, :, c]})
            for s in range(6) for c, ch in enumerate(SPECTRAL_CHANNELS)]
    path = tmp_path_factory.mktemp("psd") / f"{DATE}.parquet"
    write_table(pd.concat(rows, ignore_index=True), path)
    return str(path)


def test_tipm_profiles_follow_the_key_and_stay_seeded_by_index(psd_file):
    """tipm.profiles.amplitudes reaches the representative profiles (the forecast stage passes
    the same resolved key): gaussian differs from the default, which is the random-phase
    synthesis bit for bit; the same seed gives the same profiles; one sample alone equals the
    same sample among the others (its numbers depend only on the study seed and its index)."""
    from ttbpipe.tipm.profiles import STREAM_REPRESENTATIVE, profiles_from_psd_sets
    from ttbpipe.tipm.selection import TIPMSelection
    from ttbpipe.tipm.stages import profiles_stage, resolve_config, select_stage

    assert resolve_config(TIPM_CFG)["profiles"]["amplitudes"] == "random_phase"
    selection, weights, _ = select_stage([psd_file], TIPM_CFG, PSD_CFG)
    default = profiles_stage(selection, weights, DATE, TIPM_CFG, PSD_CFG, study_seed=7)
    gauss = profiles_stage(selection, weights, DATE, GAUSSIAN_TIPM, PSD_CFG, study_seed=7)
    again = profiles_stage(selection, weights, DATE, GAUSSIAN_TIPM, PSD_CFG, study_seed=7)
    other = profiles_stage(selection, weights, DATE, GAUSSIAN_TIPM, PSD_CFG, study_seed=8)
    pd.testing.assert_frame_equal(gauss, again, check_exact=True)
    assert list(gauss.columns) == list(default.columns)
    assert np.array_equal(gauss["chainage_m"], default["chainage_m"])
    for column in ("vertical_mm", "alignment_mm", "cross_level_mm", "gauge_mm"):
        assert not np.allclose(gauss[column], default[column])
        assert not np.allclose(gauss[column], other[column])

    sel = TIPMSelection.from_long_table(selection, weights)
    indices = sel.samples["sample_index"].to_list()
    explicit = profiles_from_psd_sets(sel.psd_mm2_m, sel.frequency_per_m, sel.channels, indices,
                                      length_m=200.0, dx_m=0.25, study_seed=7, date=DATE,
                                      stream=STREAM_REPRESENTATIVE, amplitudes="random_phase")
    pd.testing.assert_frame_equal(default, explicit, check_exact=True)
    alone = profiles_from_psd_sets(sel.psd_mm2_m[3:4], sel.frequency_per_m, sel.channels,
                                   [indices[3]], length_m=200.0, dx_m=0.25, study_seed=7,
                                   date=DATE, stream=STREAM_REPRESENTATIVE, amplitudes="gaussian")
    one = gauss[gauss["sample_index"] == indices[3]].reset_index(drop=True)
    pd.testing.assert_frame_equal(alone, one, check_exact=True)


def _study_config(**sections) -> dict:
    """The shipped study configuration (config/config.yaml) with ``sections`` deep-merged in,
    validated and its defaults filled (as the workflow does)."""
    from ttbpipe.study.cases import _merge

    config = yaml.safe_load((REPO / "config" / "config.yaml").read_text())
    _merge(config, copy.deepcopy(sections))
    return validate_study_config(config, "study.yaml")


def test_monte_carlo_profiles_follow_tipm_profiles_and_the_digest_sees_it(psd_file):
    """irregularity_mc: the batch builds its population from the digest's profile settings
    (plan.mc_profile_settings, as workflow/scripts/simulate_batch.py does), so the key reaches
    mc_profile and changes the batch digest, hence the batch path (reruns); same seed and
    index, same profile."""
    from ttbpipe.study.plan import batch_settings, mc_profile_settings, settings_digest
    from ttbpipe.study.samples import mc_profile

    base = _study_config(tipm=TIPM_CFG)
    gauss = _study_config(tipm=GAUSSIAN_TIPM)

    def population(config):
        return {**mc_profile_settings(config), "psd_paths": [psd_file], "date": DATE}

    assert population(base)["amplitudes"] == "random_phase"
    default = mc_profile(population(base), 9, 2, sample_index=4)
    a = mc_profile(population(gauss), 9, 2, sample_index=4)
    b = mc_profile(population(gauss), 9, 2, sample_index=4)
    pd.testing.assert_frame_equal(a, b, check_exact=True)
    assert not np.allclose(a["vertical_mm"], default["vertical_mm"])
    assert not np.allclose(a["vertical_mm"], mc_profile(population(gauss), 9, 2,
                                                        sample_index=5)["vertical_mm"])
    explicit = {**population(base), "amplitudes": "random_phase"}
    pd.testing.assert_frame_equal(default, mc_profile(explicit, 9, 2, sample_index=4),
                                  check_exact=True)

    digest = {name: {kind: settings_digest(batch_settings(cfg, kind, "v"))
                     for kind in ("irregularity_mc", "single", "fields")}
              for name, cfg in (("base", base), ("gauss", gauss))}
    assert digest["base"]["irregularity_mc"] != digest["gauss"]["irregularity_mc"]
    # the mean-spectrum scenarios do not read tipm.profiles: their batches stay
    assert digest["base"]["single"] == digest["gauss"]["single"]
    assert digest["base"]["fields"] == digest["gauss"]["fields"]


def test_mean_spectrum_profile_follows_simulation_irregularity():
    """simulation.irregularity.amplitudes reaches the mean-spectrum profile of the single and
    fields scenarios (run_sample and case 1's sweep build it with one function) and their batch
    digests; the profile depends only on the study seed."""
    from ttbpipe.study.cases import sweep_irregularity
    from ttbpipe.study.plan import batch_settings, settings_digest
    from ttbpipe.study.samples import mean_spectrum_irregularity, resolve_simulation

    base = _study_config()
    gauss = _study_config(simulation={"irregularity": {"amplitudes": "gaussian"}})
    assert base["simulation"]["irregularity"]["amplitudes"] == "random_phase"
    cases = {name: mean_spectrum_irregularity(resolve_simulation(cfg["simulation"])["irregularity"],
                                              cfg["study"]["seed"])
             for name, cfg in (("base", base), ("gauss", gauss))}
    assert cases["gauss"]["amplitudes"] == "gaussian"
    assert sweep_irregularity(gauss) == cases["gauss"]
    tracks = {name: build_irregularity(case, -20.0, 300.0, 0.0) for name, case in cases.items()}
    assert not np.allclose(tracks["base"].values, tracks["gauss"].values)
    again = build_irregularity(mean_spectrum_irregularity(
        resolve_simulation(gauss["simulation"])["irregularity"], gauss["study"]["seed"]),
        -20.0, 300.0, 0.0)
    assert np.array_equal(again.values, tracks["gauss"].values)
    explicit = build_irregularity({**cases["base"], "amplitudes": "random_phase"}, -20.0, 300.0,
                                  0.0)
    assert np.array_equal(explicit.values, tracks["base"].values)
    for kind in ("single", "fields"):
        assert (settings_digest(batch_settings(base, kind, "v"))
                != settings_digest(batch_settings(gauss, kind, "v")))


# ---------------------------------------------------------------------------------------------
# schemas


def test_schemas_offer_exactly_the_code_s_choices_with_its_default():
    """The study schema's key (both places) and the case schema's key list AMPLITUDES, and the
    study default is DEFAULT_AMPLITUDES (the code's one tuple and default)."""
    from ttbpipe.configuration import CASE_SCHEMA, STUDY_SCHEMA, _node

    for path in (("simulation", "irregularity", "amplitudes"), ("tipm", "profiles", "amplitudes")):
        node, _ = _node(STUDY_SCHEMA, path)
        assert tuple(node["enum"]) == AMPLITUDES and node["default"] == DEFAULT_AMPLITUDES
        assert node["description"]
    node, _ = _node(CASE_SCHEMA, ("irregularity", "amplitudes"))
    assert tuple(node["enum"]) == AMPLITUDES and "default" not in node
    assert section_defaults("tipm")["profiles"]["amplitudes"] == DEFAULT_AMPLITUDES
    assert section_defaults("simulation")["irregularity"]["amplitudes"] == DEFAULT_AMPLITUDES


@pytest.mark.parametrize("section,path", [
    ("tipm", "tipm.profiles.amplitudes"),
    ("simulation", "simulation.irregularity.amplitudes"),
])
def test_the_schema_rejects_an_invalid_value_with_a_clear_error(section, path):
    key = path.split(".")[1]
    with pytest.raises(ConfigurationError) as info:
        _study_config(**{section: {key: {"amplitudes": "gausian"}}})
    message = str(info.value)
    assert (f"study.yaml: {path}: 'gausian' is not one of ['random_phase', 'gaussian']; "
            "did you mean 'gaussian'?") in message, message


def test_a_case_and_an_in_memory_section_reject_an_invalid_value():
    from ttbpipe.simulation.config import validate_case

    case = {"train": {"composition": ["trailer"]},
            "irregularity": {"source": "synthetic", "amplitudes": "uniform"}}
    with pytest.raises(ValueError, match=r"irregularity.amplitudes: 'uniform' is not one of "
                                         r"\['random_phase', 'gaussian'\]"):
        validate_case(case, "case.yaml")
    validate_case({**case, "irregularity": {"source": "synthetic", "amplitudes": "gaussian"}})
    with pytest.raises(ValueError, match=r"irregularity.amplitudes: 'uniform'; expected one of"):
        build_irregularity({"source": "synthetic", "amplitudes": "uniform"}, 0.0, 100.0, 0.0)
