"""A field per rail for the rail (C1) and rail-pad (C2) groups (fields.left_right_correlation)."""

import copy

import numpy as np
import pytest

from ttbpipe.fields.sampling import FieldSampler, sample_generator

R_RAIL = [[1.0, 0.7, 0.7, 0.7], [0.7, 1.0, 0.8, 0.8], [0.7, 0.8, 1.0, 0.9], [0.7, 0.8, 0.9, 1.0]]
FIELDS = {
    "method": "kle", "kernel": "exponential", "correlation_length_m": 5.0,
    "variance_fraction": 0.95,
    "geometry": {"spans_m": [10.0], "approach_length_m": 5.0, "fastener_spacing_m": 0.63},
    "groups": {"C1": {"correlation": R_RAIL},
               "C2": {"correlation": R_RAIL, "distribution": "lognormal", "cov": 0.2},
               "C3": {"correlation": R_RAIL}},
}


def _with(rho, **group_rho):
    cfg = copy.deepcopy(FIELDS)
    if rho is not None:
        cfg["left_right_correlation"] = rho
    for g, r in group_rho.items():
        cfg["groups"][g]["left_right_correlation"] = r
    return cfg


def test_rho_one_is_the_single_shared_field_of_before():
    """Default (and explicit rho = 1): one array of n values per rail parameter, equal to the
    single-field construction of the sampler (normals (m, P) from the group's generator, KL
    basis, Nataf) with no extra draw; slab factors unchanged by any rho."""
    default, explicit = FieldSampler(FIELDS, 11), FieldSampler(_with(1.0), 11)
    for sampler in default.samplers:
        assert sampler.n_rails == 1
    a, b = default.sample(4), explicit.sample(4)
    for s in default.samplers:
        rng = sample_generator(11, 4, s.group.stream)
        eta = rng.standard_normal((s.n_coefficients, len(s.group.parameters)))
        old = s.nataf.to_physical(s.gaussian_fields(eta)).T
        for p, name in enumerate(s.group.parameters):
            assert a[name].shape == (s.positions_m.size,)
            assert np.array_equal(a[name], old[p]) and np.array_equal(b[name], old[p])
    split = FieldSampler(_with(0.3), 11).sample(4)
    for name in ("ca_kz", "ca_cy"):
        assert np.array_equal(split[name], a[name])
    # the left rail keeps the shared field of the same seed: its normals are drawn first
    for name in ("rail_E", "pad_kz"):
        n = a[name].size
        assert split[name].shape == (2 * n,)
        assert np.array_equal(split[name][:n], a[name])
        assert not np.allclose(split[name][n:], a[name])


def test_left_right_correlation_of_the_sampled_fields():
    """rho = 0.5, 1500 samples, one carrier mid-line: the normal rail factors (C1) correlate by
    0.5 and the lognormal pad factors (C2, cov 0.2) by the Nataf image
    (exp(rho s²) − 1)/(exp(s²) − 1) = 0.495, s² = ln(1 + cov²); standard error (1 − r²)/sqrt(M)
    = 0.019, tolerance 4 SE. A group override (C2: -0.4) takes precedence over the section key."""
    m = 1500
    sampler = FieldSampler(_with(0.5), 3)
    draws = [sampler.sample(i) for i in range(m)]
    n_rail = sampler.positions["rail_element"].size
    n_pad = sampler.positions["fastener"].size
    i, j = n_rail // 2, n_pad // 2
    tol = 4 * (1 - 0.25) / np.sqrt(m)
    r_rail = np.corrcoef([d["rail_E"][i] for d in draws], [d["rail_E"][n_rail + i] for d in draws])
    assert abs(r_rail[0, 1] - 0.5) < tol
    s2 = np.log1p(0.2 ** 2)
    expected = np.expm1(0.5 * s2) / np.expm1(s2)
    r_pad = np.corrcoef([d["pad_kz"][j] for d in draws], [d["pad_kz"][n_pad + j] for d in draws])
    assert abs(r_pad[0, 1] - expected) < tol
    # cross-parameter, cross-rail: rho R_g[E, Iz] = 0.5 * 0.7 (normal marginals: R_g = R_x)
    r_cross = np.corrcoef([d["rail_E"][i] for d in draws], [d["rail_Iz"][n_rail + i] for d in draws])
    assert abs(r_cross[0, 1] - 0.35) < 4 * (1 - 0.35 ** 2) / np.sqrt(m)
    override = FieldSampler(_with(0.5, C2=-0.4), 3)
    assert {s.group.name: s.left_right_correlation for s in override.samplers} == \
        {"C1": 0.5, "C2": -0.4, "C3": None}


def test_only_rail_groups_take_a_left_right_correlation():
    with pytest.raises(ValueError, match="not on the rails"):
        FieldSampler(_with(None, C3=0.5), 1)
    from ttbpipe.configuration import validate_section
    with pytest.raises(Exception, match="left_right_correlation"):
        validate_section(_with(1.5), "fields")


def test_table_carries_both_rails_for_the_loader():
    """With two rails the table has 2n carriers (right rail at the same x) and the loader gives
    back the 2n arrays of the sample."""
    from ttbpipe.fields.sampling import load_field_factors

    sampler = FieldSampler(_with(0.2), 5)
    table = sampler.table([0, 1])
    back = load_field_factors(table, 1)
    direct = sampler.sample(1)
    for name, values in direct.items():
        assert np.array_equal(back[name], values)
    x = table[(table["sample_index"] == 0) & (table["parameter"] == "pad_kz")]["x_m"].to_numpy()
    n = sampler.positions["fastener"].size
    assert np.array_equal(x[:n], x[n:])


def test_coupled_run_receives_distinct_rail_arrays(monkeypatch):
    """One 32 m span, one car, 10 m of run: the study's field factors with rho = 0.3 reach
    apply_factors as 2n arrays whose rails differ, and the assembled structure's left and right
    pad stiffnesses differ accordingly."""
    import ttbpipe.structure as structure_pkg
    from ttbpipe.simulation.coupled import run_coupled
    from ttbpipe.study import samples as study_samples

    structure = {"layout": {"approach_length_m": 30.0, "spans_m": [32.0],
                            "approach_track": "ballasted", "bridge_track": "slab"}}
    fields = {"method": "kle", "correlation_length_m": 10.0, "variance_fraction": 0.9,
              "left_right_correlation": 0.3, "geometry": {"source": "structure"},
              "groups": {"C2": {"correlation": R_RAIL}}}
    factors = study_samples.field_factors(fields, structure, 5, "all", 0)
    received = {}
    original = structure_pkg.apply_factors

    def spy(model, f):
        received.update(f)
        out = original(model, f)
        received["_model"] = out
        return out

    monkeypatch.setattr(structure_pkg, "apply_factors", spy)
    sim = study_samples.resolve_simulation({"train": {"composition": ["trailer"]},
                                            "end_x_m": 40.0})
    case = study_samples.build_case(sim, structure, irregularity={"source": "none"})
    table, summary = run_coupled(case, factors=factors)
    n = received["_model"].properties["pad_kz"].shape[-1]
    assert received["pad_kz"].shape == (2 * n,)
    assert not np.allclose(received["pad_kz"][:n], received["pad_kz"][n:])
    kz = received["_model"].properties["pad_kz"]
    assert kz.shape == (2, n) and not np.allclose(kz[0], kz[1])
    assert len(table) > 0
