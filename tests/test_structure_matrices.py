"""The vectorised assembly of (M, K, C) against the element-by-element one.

``assemble_matrices`` computes every element of a kind at once; ``assemble_matrices_by_element``
is the obviously correct reference that loops over the elements (and against which the kernels
are tested, tests/test_structure_kernels.py). They must give the same CSR matrices bit for bit
(same structure, same values: the same COO entries in the same order), on every kind of element
the structures hold: beams, bearing and pier links, CA link triples, rail pads on slab, sleepers
and rigid ground, the ballast, girder and tall-pier blocks, with random property factors, a
double-track deck and a canted curve.
"""

import copy
from pathlib import Path

import numpy as np
import pytest
import yaml

from ttbpipe.simulation.setup import nominal_structure
from ttbpipe.structure import CARRIER_PARAMETERS, apply_factors, build_structure, carrier_positions
from ttbpipe.structure.matrices import assemble_matrices, assemble_matrices_by_element

REPO = Path(__file__).resolve().parents[1]
SMALL = {"layout": {"approach_length_m": 12.0, "spans_m": [16.0, 12.0],
                    "approach_track": "ballasted"},
         "girder": {"element_length_m": 2.0}}


def _assert_same(model):
    fast, reference = assemble_matrices(model.packed), assemble_matrices_by_element(model.packed)
    for name, a, b in zip("MKC", fast, reference):
        assert a.shape == b.shape, name
        np.testing.assert_array_equal(a.indptr, b.indptr, err_msg=name)
        np.testing.assert_array_equal(a.indices, b.indices, err_msg=name)
        np.testing.assert_array_equal(a.data, b.data, err_msg=name)
        assert b.nnz > 0


def _random_factors(model, seed):
    """Every carrier parameter times a random factor per carrier (0.6 to 1.4)."""
    rng = np.random.default_rng(seed)
    positions = carrier_positions(model)
    return {p: rng.uniform(0.6, 1.4, positions[kind].size)
            for kind, names in CARRIER_PARAMETERS.items() if positions[kind].size
            for p in names}


@pytest.mark.parametrize("approach,slab,bridge", [
    ("ballasted", "continuous", "slab"), ("slab", "discrete", "slab"),
    ("rigid", "continuous", "slab"), ("ballasted", "continuous", "rigid")])
def test_vectorised_assembly_equals_the_element_loops(approach, slab, bridge):
    cfg = {**SMALL, "layout": {**SMALL["layout"], "approach_track": approach,
                               "bridge_track": bridge},
           "slab": {"type": slab}}
    model = build_structure(cfg)
    _assert_same(model)
    _assert_same(apply_factors(model, _random_factors(model, 7)))


def test_vectorised_assembly_on_tall_piers_and_a_double_track_deck():
    cfg = copy.deepcopy(SMALL)
    cfg["pier"] = {"height_m": 12.0}
    _assert_same(build_structure(cfg))
    cfg = copy.deepcopy(SMALL)
    cfg["layout"]["tracks"] = 2
    model = build_structure(cfg)
    assert model.n_tracks == 2
    _assert_same(model)


def test_vectorised_assembly_on_the_curved_reference_bridge():
    case = yaml.safe_load((REPO / "config" / "curved_bridge.yaml").read_text())
    model = nominal_structure(case)
    assert model.cant is not None and model.plan is not None
    _assert_same(model)


def test_the_comparison_sees_a_changed_entry():
    """The check above fails when one element's contribution differs (it is not vacuous)."""
    model = build_structure(SMALL)
    packed = model.packed
    changed = packed._replace(pad_k=packed.pad_k.copy())
    changed.pad_k[4] *= 1.0 + 1e-12
    a = assemble_matrices(changed)[1]
    b = assemble_matrices_by_element(packed)[1]
    assert not np.array_equal(a.data, b.data)



def _packed_arrays(model):
    return {name: value for name, value in zip(model.packed._fields, model.packed)
            if isinstance(value, np.ndarray)}


def _structure_builder(variant):
    """A function building one of the structures the at-once assemblies are checked on."""
    cfg = copy.deepcopy(SMALL)
    if variant == "curved_random":
        case = yaml.safe_load((REPO / "config" / "curved_bridge.yaml").read_text())
        nominal = nominal_structure(case)
        assert nominal.cant is not None and nominal.plan is not None
        factors = _random_factors(nominal, 11)
        return lambda: apply_factors(nominal, factors)
    if variant == "double_track":
        cfg["layout"]["tracks"] = 2
        return lambda: build_structure(cfg)
    if variant == "discrete_slab_approaches_random":   # gaps: pads off every slab element
        cfg["layout"]["approach_track"] = "slab"
        cfg["slab"] = {"type": "discrete"}
    elif variant == "rigid_approaches_random":
        cfg["layout"]["approach_track"] = "rigid"
    nominal = build_structure(cfg)
    factors = _random_factors(nominal, 5)
    return lambda: apply_factors(nominal, factors)


@pytest.mark.parametrize("at_once,by_one", [("_ca_triples", "_ca_triples_by_point"),
                                            ("_rail_pads", "_rail_pads_by_node")])
@pytest.mark.parametrize("variant", ["discrete_slab_approaches_random", "rigid_approaches_random",
                                     "double_track", "curved_random"])
def test_assembly_at_once_equals_the_loop_one_by_one(at_once, by_one, variant, monkeypatch):
    """`_ca_triples` builds the CA mortar and slab-foundation link triples of every quadrature
    point at once, `_rail_pads` every rail pad at once; `_ca_triples_by_point` and
    `_rail_pads_by_node` are the loops they replaced, one point or rail node at a time. The
    structures they give hold the same arrays bit for bit (values, signs of zeros, order):
    on discrete slab approaches (the foundation's coefficients; rail nodes in the gaps between
    slab units, seated on the nearest element's end), on rigid approaches, each with a
    bridge of random factors, on a double-track deck, and on the canted, curved reference
    bridge (the deck rows rotated into the track plane, the centre line off the girder's axis)
    with random factors."""
    import ttbpipe.structure.assembly as assembly

    build = _structure_builder(variant)
    fast_model = build()
    calls = []
    reference = getattr(assembly, by_one)

    def one_by_one(*args):
        calls.append(1)
        return reference(*args)

    monkeypatch.setattr(assembly, at_once, one_by_one)
    slow_model = build()
    assert calls and fast_model.packed.tri_ptr.size > 1 and fast_model.packed.pad_rail.size
    assert fast_model.triple_kinds == slow_model.triple_kinds
    fast, slow = _packed_arrays(fast_model), _packed_arrays(slow_model)
    assert fast.keys() == slow.keys()
    for name in fast:
        assert fast[name].dtype == slow[name].dtype, name
        np.testing.assert_array_equal(fast[name], slow[name], err_msg=name)
        if fast[name].dtype.kind == "f":
            np.testing.assert_array_equal(np.signbit(fast[name]), np.signbit(slow[name]),
                                          err_msg=name)
