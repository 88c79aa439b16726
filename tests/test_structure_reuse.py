"""Samples that share a structure share one model (ttbpipe.simulation.setup._nominal_structure):
its global matrices, stability analysis and static factorisation are made once per process
(ttbpipe.structure.StructureModel.derived), with its compiled monitors; samples that share a
train share its assembled model (ttbpipe.simulation.setup._train_model) and a conical tread's
contact table (ttbpipe.vehicle.contact._conical_table). Reference: the same run on a freshly
built model (the caches emptied first); the shared model must give it bit for bit (the project's
determinism rule: a sample's results depend on its inputs only, not on the samples run before
it in the process). Real coupled runs on one 32 m span, one car, 10 m of run (a few seconds)."""

import copy

import numpy as np
import pandas as pd
import pytest

from ttbpipe.simulation import setup as coupled_setup  # not "setup": a pytest hook name
from ttbpipe.simulation.coupled import run_coupled
from ttbpipe.study import samples as study_samples
from ttbpipe.timestepping.limits import stable_time_step
from ttbpipe.vehicle import contact as vehicle_contact

STRUCTURE = {"layout": {"approach_length_m": 30.0, "spans_m": [32.0],
                        "approach_track": "ballasted", "bridge_track": "slab"}}
SIM = study_samples.resolve_simulation({"train": {"composition": ["trailer"]}, "end_x_m": 40.0})


def case(seed: int) -> dict:
    return study_samples.build_case(SIM, STRUCTURE, irregularity={
        "source": "synthetic", "spectrum": "fra_class6", "seed": seed})


def run(seed: int, factors=None):
    table, summary = run_coupled(case(seed), factors=factors)
    return table, summary


@pytest.fixture(scope="module")
def fresh_runs():
    """Seeds 1 and 2, each on a freshly built structure (nothing cached before it)."""
    out = {}
    for seed in (1, 2):
        clear_caches()
        out[seed] = run(seed)
    clear_caches()
    return out


def clear_caches():
    coupled_setup._NOMINAL_STRUCTURES.clear()
    coupled_setup._TRAINS.clear()
    vehicle_contact._conical_table.cache_clear()


def assert_same_run(a, b):
    pd.testing.assert_frame_equal(a[0], b[0], check_exact=True)
    for key in ("derailment_coefficient", "girder_acc_max_m_s2", "dt_limits", "static_wheel_load_N"):
        if key in a[1]:
            assert a[1][key] == b[1][key], key


def test_a_shared_model_gives_the_fresh_models_results_bit_for_bit(fresh_runs):
    """Seed 1, then seed 2, then seed 1 again on one shared model: each equals its run on a
    fresh model; the model (and its matrices and factorisation) was built once."""
    coupled_setup._NOMINAL_STRUCTURES.clear()
    first = coupled_setup.prepare(case(1))
    for seed in (1, 2, 1):
        assert_same_run(run(seed), fresh_runs[seed])
    again = coupled_setup.prepare(case(2))
    assert again.structure is first.structure
    assert again.model is first.model
    assert again.structure.matrices() is first.structure.matrices()
    assert set(first.structure._derived) >= {"matrices", "static", ("stability", 6)}
    assert again.monitors is first.monitors
    # the contact table is shared as numbers, not as an array a run could write into
    assert again.geom.table is not first.geom.table
    np.testing.assert_array_equal(again.geom.table, first.geom.table)


def test_compiled_monitors_follow_the_monitor_list_and_the_contact_table_its_cone():
    """Another monitor list compiles its own rows on the shared model, equal to a fresh
    compilation; another conicity fills another contact table, equal to a fresh one."""
    from ttbpipe.structure.monitors import compile_monitors, default_monitors

    clear_caches()
    first = coupled_setup.prepare(case(1))
    specs = default_monitors(first.structure)[:3]
    fewer = coupled_setup.prepare({**case(1), "monitors": specs})
    assert fewer.structure is first.structure and fewer.monitors is not first.monitors
    fresh = compile_monitors(first.structure, specs)
    assert fewer.monitors.names == fresh.names
    for name in ("ptr", "dof", "coef", "qty", "scale"):
        np.testing.assert_array_equal(getattr(fewer.monitors, name), getattr(fresh, name))
    # a list that is not plain data (a numpy integer) is compiled for its run alone
    numpy_rail = [{**specs[0], "rail": np.int64(specs[0].get("rail", 0))}]
    a = coupled_setup.prepare({**case(1), "monitors": numpy_rail}).monitors
    assert a is not coupled_setup.prepare({**case(1), "monitors": numpy_rail}).monitors
    assert a.names == compile_monitors(first.structure, numpy_rail).names
    steeper = copy.deepcopy(case(1))
    steeper["train"]["contact"] = {"profile": "conical", "conicity": 0.1}
    table = coupled_setup.prepare(steeper).geom.table
    radius = vehicle_contact.COL_R
    assert not np.array_equal(table[:, radius], first.geom.table[:, radius])
    vehicle_contact._conical_table.cache_clear()
    np.testing.assert_array_equal(coupled_setup.prepare(steeper).geom.table, table)


def test_property_factors_build_their_own_model_and_leave_the_shared_one_unchanged(fresh_runs):
    """A fields sample between two nominal ones: its factors give a new model (a changed pad
    stiffness, another static state), and the nominal runs after it are unchanged."""
    coupled_setup._NOMINAL_STRUCTURES.clear()
    nominal = coupled_setup.prepare(case(1)).structure
    n = nominal.properties["pad_kz"].shape[-1]
    factors = {"pad_kz": np.linspace(0.7, 1.3, n)}
    factored = coupled_setup.prepare(case(1), factors=factors)
    assert factored.structure is not nominal
    assert not np.array_equal(factored.structure.properties["pad_kz"], nominal.properties["pad_kz"])
    assert not np.array_equal(factored.disp0, coupled_setup.prepare(case(1)).disp0)
    run(1, factors=factors)
    assert coupled_setup.prepare(case(1)).structure is nominal
    assert_same_run(run(1), fresh_runs[1])


def test_the_model_is_keyed_on_its_configuration_and_does_not_follow_the_callers_dict():
    """Another span length builds another model; editing the configuration a model was built
    from afterwards does not change that model (it keeps its own copy)."""
    coupled_setup._NOMINAL_STRUCTURES.clear()
    config = copy.deepcopy(case(1))
    a = coupled_setup.prepare(config).structure
    longer = copy.deepcopy(config)
    longer["structure"]["layout"]["spans_m"] = [40.0]
    b = coupled_setup.prepare(longer).structure
    assert b is not a and b.rail_x_range[1] > a.rail_x_range[1]
    config["structure"]["layout"]["spans_m"][0] = 24.0     # the caller edits its own dict
    assert a.config["layout"]["spans_m"] == [32.0]
    assert coupled_setup.prepare(case(1)).structure is a
    assert len(coupled_setup._NOMINAL_STRUCTURES) <= coupled_setup._NOMINAL_STRUCTURES_KEPT


def test_stability_analysis_once_per_model_and_safety_applied_per_call():
    """The cached analysis serves every safety factor: dt_s = safety x dt_limit_s for each call,
    and an earlier result is not changed by a later call."""
    coupled_setup._NOMINAL_STRUCTURES.clear()
    structure = coupled_setup.prepare(case(1)).structure
    full = stable_time_step(structure, safety=1.0)
    part = stable_time_step(structure, safety=0.9)
    assert full["dt_s"] == full["dt_limit_s"]
    assert part["dt_s"] == 0.9 * part["dt_limit_s"] and part["dt_limit_s"] == full["dt_limit_s"]
    assert full["dt_s"] == full["dt_limit_s"]


def test_the_train_model_is_keyed_on_its_configuration_and_does_not_follow_the_callers_dict():
    """Another composition or car mass builds another train model; editing the train section a
    model was built from afterwards does not change that model."""
    coupled_setup._TRAINS.clear()
    config = copy.deepcopy(case(1))
    config["train"] = {"composition": ["trailer"], "trailer": {"car_mass": 40000.0}}
    a = coupled_setup.prepare(config).model
    mass = a.mass.copy()
    heavier = copy.deepcopy(config)
    heavier["train"]["trailer"]["car_mass"] = 45000.0
    b = coupled_setup.prepare(heavier).model
    assert b is not a and b.mass[0] == 45000.0 and a.mass[0] == 40000.0
    config["train"]["trailer"]["car_mass"] = 50000.0      # the caller edits its own dict
    np.testing.assert_array_equal(a.mass, mass)
    config["train"]["trailer"]["car_mass"] = 40000.0
    assert coupled_setup.prepare(config).model is a
    assert len(coupled_setup._TRAINS) <= coupled_setup._TRAINS_KEPT
