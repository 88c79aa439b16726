"""The map u -> (profile, field factors) for the rare-event code (ttbpipe.reliability.inputs)."""

import copy
from pathlib import Path

import numpy as np
import pytest
import yaml

from ttbpipe.irregularity.synthesis import n_gaussian_coefficients
from ttbpipe.reliability.inputs import StandardNormalInputs

REPO = Path(__file__).resolve().parents[1]
DEFAULT = yaml.safe_load((REPO / "config" / "config.yaml").read_text())

R = [[1.0, 0.7, 0.7, 0.7], [0.7, 1.0, 0.8, 0.8], [0.7, 0.8, 1.0, 0.9], [0.7, 0.8, 0.9, 1.0]]
SMALL = {
    "structure": {"layout": {"approach_length_m": 30.0, "spans_m": [32.0],
                             "approach_track": "ballasted", "bridge_track": "slab"}},
    "simulation": {"irregularity": {"spectrum": "tbt3352", "dx_m": 0.25}},
    "fields": {"method": "kle", "correlation_length_m": 10.0, "variance_fraction": 0.9,
               "left_right_correlation": 0.5, "geometry": {"source": "structure"},
               "groups": {"C1": {"correlation": R},
                          "C2": {"correlation": R, "distribution": "lognormal", "cov": 0.15},
                          "C4": {"correlation": R}}},
}


@pytest.fixture(scope="module")
def small():
    return StandardNormalInputs(SMALL)


def _covering(slices, n_dims):
    bounds = sorted((s.start, s.stop) for s in slices.values())
    return (bounds[0][0] == 0 and bounds[-1][1] == n_dims
            and all(a[1] == b[0] for a, b in zip(bounds, bounds[1:]))
            and all(a < b for a, b in bounds))


def test_slices_are_disjoint_and_cover_u(small):
    assert _covering(small.slices, small.n_dims)
    assert set(small.slices) >= {"fields/C1/left", "fields/C1/right_innovation",
                                 "fields/C2/left", "fields/C2/right_innovation", "fields/C4",
                                 "irregularity/vertical/coefficients"}
    per_channel = n_gaussian_coefficients(small.length_m, small.dx_m, (2.0, 200.0))
    fields = sum(s.n_rails * s.n_coefficients * 4 for s in small.field_samplers)
    assert small.n_dims == 4 * per_channel + fields


def test_map_is_deterministic_and_pure(small):
    u = np.random.default_rng(3).standard_normal(small.n_dims)
    keep = u.copy()
    p1, f1 = small.map(u)
    p2, f2 = small(u.copy())
    assert np.array_equal(u, keep)
    assert p1.equals(p2)
    assert f1.keys() == f2.keys() and all(np.array_equal(f1[k], f2[k]) for k in f1)
    # each slice moves only its own input
    v = u.copy()
    v[small.slices["fields/C4"]] += 1.0
    p3, f3 = small.map(v)
    assert p3.equals(p1)
    assert np.array_equal(f3["pad_kz"], f1["pad_kz"]) and not np.allclose(f3["girder_E"],
                                                                            f1["girder_E"])
    w = u.copy()
    w[small.slices["fields/C2/right_innovation"]] = 0.0
    _, f4 = small.map(w)
    n = f1["pad_kz"].size // 2
    assert np.array_equal(f4["pad_kz"][:n], f1["pad_kz"][:n])
    assert not np.allclose(f4["pad_kz"][n:], f1["pad_kz"][n:])


def test_zero_is_the_median_input(small):
    """u = 0: zero profile; normal marginals give factor 1 (= mean); the lognormal pads give
    the median exp(−s²/2) (mean 1, s² = ln(1 + cov²)); both rails equal."""
    profile, factors = small.map(np.zeros(small.n_dims))
    assert np.all(profile.drop(columns="chainage_m").to_numpy() == 0.0)
    assert profile["chainage_m"].iloc[0] == pytest.approx(-20.0)   # 20 m lead-in before x = 0
    for name in ("rail_E", "rail_Iz", "girder_mass"):
        assert np.array_equal(factors[name], np.ones_like(factors[name]))
    s2 = np.log1p(0.15 ** 2)
    assert np.allclose(factors["pad_kz"], np.exp(-0.5 * s2), rtol=1e-12)


def test_profile_and_factors_fit_the_coupled_run(small):
    """The profile covers the structure's rails and the factors have one value per carrier
    (2n on the rails): the structure accepts them."""
    from ttbpipe.structure import apply_factors, build_structure

    model = build_structure(SMALL["structure"])
    profile, factors = small.map(np.random.default_rng(1).standard_normal(small.n_dims))
    x0, x1 = model.rail_x_range
    assert profile["chainage_m"].iloc[0] <= x0 - 20.0 + 1e-9
    assert profile["chainage_m"].iloc[-1] >= x1
    new = apply_factors(model, factors)
    assert new.properties["pad_kz"].shape[0] == 2
    assert not np.allclose(new.properties["pad_kz"][0], new.properties["pad_kz"][1])


def test_population_source_has_level_dimensions():
    """A PSD population as source: one level normal per channel, median PSD at u = 0."""
    from ttbpipe.irregularity.spectra import get_spectrum
    from ttbpipe.tipm.population import synthetic_population

    sp = get_spectrum("tbt3352")
    f = np.linspace(0.004, 0.55, 80)
    mean = np.stack([sp.psd_mm2_m(c, f, extrapolate=True)
                     for c in ("vertical", "alignment", "cross_level", "gauge")], axis=1)
    pop = synthetic_population(60, f, mean, np.random.default_rng(2))
    config = copy.deepcopy(SMALL)
    del config["fields"]
    inputs = StandardNormalInputs(config, spectrum=pop)
    assert [k for k in inputs.slices if k.endswith("/level")] == [
        f"irregularity/{c}/level" for c in ("vertical", "alignment", "cross_level", "gauge")]
    assert _covering(inputs.slices, inputs.n_dims)
    profile, factors = inputs.map(np.zeros(inputs.n_dims))
    assert factors == {} and np.all(profile["vertical_mm"] == 0.0)
    u = np.zeros(inputs.n_dims)
    u[inputs.slices["irregularity/vertical/level"]] = 2.0
    assert np.all(inputs.irregularity.band_psd(u)["vertical"]
                  > inputs.irregularity.band_psd(np.zeros(inputs.n_dims))["vertical"])


def test_default_study_dimension(capsys):
    """The default study (config/config.yaml): its u dimension, printed for the docs."""
    inputs = StandardNormalInputs(DEFAULT)
    assert _covering(inputs.slices, inputs.n_dims)
    sizes = inputs.describe()
    assert {k.split("/")[1] for k in sizes if k.startswith("fields/")} == {"C1", "C2", "C3", "C4"}
    with capsys.disabled():
        print(f"\ndefault study: n_dims = {inputs.n_dims}: {sizes}")
    profile, factors = inputs.map(np.zeros(inputs.n_dims))
    assert all(np.array_equal(v, np.ones_like(v)) for v in factors.values())
