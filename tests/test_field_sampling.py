"""Cross-correlated parameter fields: determinism, spatial and cross-parameter statistics, table.

Statistical references: the target kernel rho(d) = exp(-d/b) and the Nataf target R_x; tolerances
are a few standard errors of the estimates (stated per test).
"""

import copy

import numpy as np
import pandas as pd
import pytest
import yaml

from ttbpipe.fields.groups import build_groups, carrier_positions, segment_index
from ttbpipe.fields.sampling import (STREAM_ID, FieldSampler, GroupFieldSampler,
                                     load_field_factors, sample_generator, sample_study)
from ttbpipe.io import read_provenance

R_RAIL = [[1.0, 0.7, 0.7, 0.7], [0.7, 1.0, 0.8, 0.8], [0.7, 0.8, 1.0, 0.9], [0.7, 0.8, 0.9, 1.0]]
R_PAD = [[1.0, 0.8, 0.9, 0.7], [0.8, 1.0, 0.7, 0.8], [0.9, 0.7, 1.0, 0.7], [0.7, 0.8, 0.7, 1.0]]

SMALL_FIELDS = {
    "method": "kle",
    "samples": 4,
    "kernel": "exponential",
    "correlation_length_m": 5.0,
    "variance_fraction": 0.95,
    "geometry": {"spans_m": [10.0, 10.0], "approach_length_m": 5.0,
                 "fastener_spacing_m": 0.63, "girder_element_m": 1.0},
    "groups": {
        "C1": {"correlation": R_RAIL},
        "C2": {"correlation": R_PAD, "distribution": "lognormal", "cov": 0.2},
        "C3": {"correlation": R_PAD},
        "C4": {"correlation": R_RAIL},
    },
}


def test_sample_independent_of_batch_and_count():
    """Sample i is bit-identical whether drawn alone, in a batch, or with other groups disabled."""
    sampler = FieldSampler(SMALL_FIELDS, 123)
    batch = sampler.table(range(10))
    alone = sampler.table([7])
    pd.testing.assert_frame_equal(batch[batch.sample_index == 7].reset_index(drop=True), alone)
    only_c2 = copy.deepcopy(SMALL_FIELDS)
    for g in ("C1", "C3", "C4"):
        only_c2["groups"][g]["enabled"] = False
    c2_alone = FieldSampler(only_c2, 123).sample(7)
    np.testing.assert_array_equal(c2_alone["pad_kz"], sampler.sample(7)["pad_kz"])
    assert not np.array_equal(sampler.sample(6)["pad_kz"], sampler.sample(7)["pad_kz"])
    assert not np.array_equal(FieldSampler(SMALL_FIELDS, 124).sample(7)["pad_kz"],
                              sampler.sample(7)["pad_kz"])


def test_seed_tree_is_the_documented_one():
    """Group g of sample i draws from child g of SeedSequence([seed, STREAM_ID, i])."""
    expected = np.random.default_rng(np.random.SeedSequence([123, STREAM_ID, 7]).spawn(4)[1])
    np.testing.assert_array_equal(sample_generator(123, 7, 1).standard_normal(5),
                                  expected.standard_normal(5))


def _many_gaussian_fields(sampler, n_samples, seed=0):
    rng = np.random.default_rng(seed)
    return np.stack([sampler.gaussian_fields(rng.standard_normal((sampler.n_coefficients, 4)))
                     for _ in range(n_samples)])  # (samples, carriers, P)


def test_mc_field_has_target_spatial_and_cross_correlation():
    """MC fields: Cov(G_p(x), G_q(y)) = R_g[p,q] exp(-|x-y|/b) within 4 standard errors.

    Standard error of a sample correlation near r: (1 - r^2)/sqrt(N) (normal theory).
    """
    group = build_groups({"groups": {"C1": {"correlation": R_RAIL}}, "correlation_length_m": 3.0})[0]
    x = np.arange(30) * 0.63
    sampler = GroupFieldSampler(group, x, method="mc")
    n = 6000
    g = _many_gaussian_fields(sampler, n)
    r_g = sampler.nataf.gaussian_correlation
    for lag in (1, 5, 10):
        for p, q in ((0, 0), (2, 3), (0, 1)):
            expected = r_g[p, q] * np.exp(-lag * 0.63 / 3.0)
            estimate = np.corrcoef(g[:, 0, p], g[:, lag, q])[0, 1]
            assert abs(estimate - expected) < 4 * (1 - expected ** 2) / np.sqrt(n) + 1e-3
    np.testing.assert_allclose(g.var(axis=0).mean(), 1.0, atol=4 * np.sqrt(2 / n))


def test_kle_field_factors_match_marginals_and_cross_correlation():
    """KLE fields with lognormal COV 0.2 factors: mean 1, COV 0.2, and Pearson R_x at one carrier.

    Tolerances: 4 standard errors (mean: 0.2/sqrt(N); std: about 0.2/sqrt(2N) inflated to
    0.2*sqrt(2/N) for skewness; correlation: (1 - r^2)/sqrt(N) * 1.5 for non-normality).
    """
    fields = {"groups": {"C2": {"correlation": R_PAD, "distribution": "lognormal", "cov": 0.2}},
              "correlation_length_m": 5.0}
    group = build_groups(fields)[0]
    x = np.arange(40) * 0.63
    sampler = GroupFieldSampler(group, x, method="kle", variance_fraction=0.9)
    n = 8000
    rng = np.random.default_rng(11)
    factors = np.stack([sampler.sample(rng) for _ in range(n)])  # (samples, P, carriers)
    at_end, inside = factors[:, :, 0], factors[:, :, 20]
    for values in (at_end, inside):  # rescaling makes the ends as variable as the inside
        np.testing.assert_allclose(values.mean(axis=0), 1.0, atol=4 * 0.2 / np.sqrt(n))
        np.testing.assert_allclose(values.std(axis=0), 0.2, atol=4 * 0.2 * np.sqrt(2 / n))
        r = np.corrcoef(values.T)
        target = np.asarray(R_PAD)
        assert np.all(np.abs(r - target) < 4 * 1.5 * (1 - target ** 2) / np.sqrt(n) + 1e-3)


def test_segments_are_independent():
    """Eq. 34: carriers in different segments are uncorrelated; (0, S/N] closes on the right."""
    np.testing.assert_array_equal(segment_index(np.array([0.1, 5.0, 5.01, 10.0]), 10.0, 2),
                                  [0, 0, 1, 1])
    group = build_groups({"groups": {"C1": {"correlation": R_RAIL}},
                          "correlation_length_m": 50.0})[0]
    x = np.arange(32) * 0.63 + 0.3
    sampler = GroupFieldSampler(group, x, method="kle", segments=2, total_length_m=20.16)
    assert len(sampler.segments) == 2
    g = _many_gaussian_fields(sampler, 3000)
    first, second = sampler.segments[0].carrier_indices, sampler.segments[1].carrier_indices
    across = np.corrcoef(g[:, first[-1], 0], g[:, second[0], 0])[0, 1]
    within = np.corrcoef(g[:, first[-2], 0], g[:, first[-1], 0])[0, 1]
    assert abs(across) < 4 / np.sqrt(3000)
    assert within > 0.9


def test_carrier_positions_of_default_geometry():
    """Paper case 2 layout: 3 x 32 m spans between 30 m approaches, fasteners every 0.63 m."""
    pos = carrier_positions({"spans_m": [32.0, 32.0, 32.0], "approach_length_m": 30.0,
                             "fastener_spacing_m": 0.63, "girder_element_m": 1.0})
    assert pos["fastener"].size == int(156 // 0.63)
    np.testing.assert_allclose(np.diff(pos["fastener"]), 0.63)
    assert pos["girder_element"].size == 96
    assert pos["girder_element"].min() > 30.0 and pos["girder_element"].max() < 126.0
    assert pos["rail_element"].size == pos["slab_element"].size == 248
    with pytest.raises(ValueError, match="spans_m or line_length_m"):
        carrier_positions({"approach_length_m": 10.0})


def test_negative_factor_stops_with_remedy():
    fields = copy.deepcopy(SMALL_FIELDS)
    fields["groups"] = {"C1": {"correlation": R_RAIL, "cov": 0.6}}
    sampler = FieldSampler(fields, 1)
    with pytest.raises(ValueError, match="lognormal"):
        for i in range(20):
            sampler.sample(i)


def test_table_round_trip_cli_and_loader(tmp_path):
    """`ttbpipe sample-fields` writes the documented table; load_field_factors reads one sample."""
    from ttbpipe.cli import main

    config = {"study": {"name": "t", "seed": 5}, "fields": SMALL_FIELDS}
    config_path = tmp_path / "config.yaml"
    config_path.write_text(yaml.safe_dump(config))
    out = tmp_path / "samples.parquet"
    assert main(["sample-fields", str(config_path), "--out", str(out), "--samples", "3",
                 "--method", "mc"]) == 0
    df = pd.read_parquet(out)
    assert list(df.columns) == ["sample_index", "parameter", "carrier_index", "x_m", "factor"]
    assert df["sample_index"].dtype == np.int64 and df["carrier_index"].dtype == np.int64
    assert sorted(df.sample_index.unique()) == [0, 1, 2]
    meta = read_provenance(out)
    assert meta["kind"] == "field_samples" and meta["method"] == "mc"
    factors = load_field_factors(out, 2)
    direct = FieldSampler(SMALL_FIELDS, 5, method="mc").sample(2)
    assert set(factors) == set(direct)
    for name in direct:
        np.testing.assert_array_equal(factors[name], direct[name])
    np.testing.assert_array_equal(load_field_factors(df, 2)["rail_E"], direct["rail_E"])
    with pytest.raises(KeyError, match="sample_index 9"):
        load_field_factors(out, 9)
    broken = df[~((df.sample_index == 1) & (df.parameter == "rail_E") & (df.carrier_index == 3))]
    with pytest.raises(ValueError, match="carrier_index"):
        load_field_factors(broken, 1)


def test_default_config_fields_section(tmp_path):
    """The shipped config/config.yaml fields section samples (2 samples, KLE) and is positive."""
    from pathlib import Path

    config = yaml.safe_load((Path(__file__).parents[1] / "config" / "config.yaml").read_text())
    df = sample_study(config, tmp_path / "s.parquet", n_samples=2)
    assert set(df.parameter) == {p for g in build_groups(config["fields"]) for p in g.parameters}
    assert (df.factor > 0).all()


def test_samples_on_structure_mesh_are_accepted_by_apply_factors(tmp_path):
    """geometry.source: structure -> one factor per carrier of ttbpipe.structure's default mesh.

    Integration with docs/dev/structure_interface.md: apply_factors raises on a count mismatch.
    """
    structure = pytest.importorskip("ttbpipe.structure")
    if not hasattr(structure, "apply_factors"):
        pytest.skip("ttbpipe.structure has no apply_factors yet")
    fields = copy.deepcopy(SMALL_FIELDS)
    fields["geometry"] = {"source": "structure"}
    config = {"study": {"seed": 3}, "fields": fields, "structure": {}}
    out = tmp_path / "s.parquet"
    sample_study(config, out, n_samples=1)
    factors = load_field_factors(out, 0)
    model = structure.build_structure({})
    positions = structure.carrier_positions(model)
    for name, values in factors.items():
        kind = next(g.carrier for g in build_groups(fields) if name in g.parameters)
        assert values.size == positions[kind].size
    structure.apply_factors(model, factors)
