"""Study design: samples, weights, seeds and batches (ttbpipe.study.design; docs/studies.md).

Exact checks (no tolerance): the project rule "a sample's random numbers depend only on the study
seed and the sample index" (docs/dev/contributing.md) and the batch partition are combinatorial.
"""

import numpy as np
import pandas as pd
import pytest

from ttbpipe.dates import add_months
from ttbpipe.study.design import (DESIGN_COLUMNS, batch_rows, batches, build_design,
                                  sample_seed_sequence, scenario_labels)


def tipm_tables(n=7):
    weights = pd.DataFrame({"sample_index": np.arange(n), "weight": np.linspace(1, 2, n)})
    states = []
    for h, target in ((6.0, "2026-06-15"), (12.0, "2026-12-15")):
        for level in (0.05, 0.5, 0.95):
            for i in range(n):
                states.append({"profile_index": len(states), "horizon_months": h,
                               "target_date": target, "level": level, "sample_index": i,
                               "weight": float(weights["weight"][i])})
    return weights, pd.DataFrame(states)


STUDY = {"seed": 11, "scenarios": {"fields": {"conditions": ["C1", "C4"], "samples": 5},
                                   "forecast": {"level": 0.95}}}


def test_design_lists_every_sample_with_weights_and_profiles():
    weights, states = tipm_tables()
    d = build_design(STUDY, latest_campaign="2025-12-15", tipm_weights=weights,
                     forecast_states=states, horizons_months=[6, 12])
    assert tuple(d.columns) == DESIGN_COLUMNS
    sizes = d.groupby("scenario").size().to_dict()
    assert sizes == {"2025-12-15": 7, "single": 1, "2026-06-15": 7, "2026-12-15": 7, "C1": 5, "C4": 5}
    # forecast rows point at the profile of their own level and horizon, with the TIPM weight
    f = d[d["scenario"] == "2026-12-15"].sort_values("sample_index")
    picked = states.set_index("profile_index").loc[f["profile_index"]]
    assert (picked["level"] == 0.95).all() and (picked["target_date"] == "2026-12-15").all()
    np.testing.assert_array_equal(f["weight"].to_numpy(), weights["weight"].to_numpy())
    assert not d.duplicated(["scenario", "sample_index"]).any()


def test_seed_depends_only_on_study_seed_scenario_and_index():
    a = sample_seed_sequence(11, "C1", 3).generate_state(4)
    assert np.array_equal(a, sample_seed_sequence(11, "C1", 3).generate_state(4))
    for other in (sample_seed_sequence(12, "C1", 3), sample_seed_sequence(11, "C2", 3),
                  sample_seed_sequence(11, "C1", 4)):
        assert not np.array_equal(a, other.generate_state(4))
    weights, states = tipm_tables()
    small = build_design({**STUDY, "scenarios": {**STUDY["scenarios"],
                                                 "fields": {"conditions": ["C1"], "samples": 2}}},
                         latest_campaign="2025-12-15", tipm_weights=weights,
                         forecast_states=states, horizons_months=[6, 12])
    big = build_design(STUDY, latest_campaign="2025-12-15", tipm_weights=weights,
                       forecast_states=states, horizons_months=[6, 12])
    merged = small.merge(big, on=["scenario", "sample_index"], suffixes=("_s", "_b"))
    assert len(merged) == len(small)
    assert (merged["seed_entropy_s"] == merged["seed_entropy_b"]).all()


@pytest.mark.parametrize("batch_size", [1, 2, 3, 5, 100])
def test_batches_partition_every_scenario_in_index_order(batch_size):
    weights, states = tipm_tables()
    d = build_design(STUDY, latest_campaign="2025-12-15", tipm_weights=weights,
                     forecast_states=states, horizons_months=[6, 12])
    seen = []
    for scenario, first, last in batches(d, batch_size):
        rows = batch_rows(d, scenario, first, last)
        assert 1 <= len(rows) <= batch_size
        assert rows["sample_index"].is_monotonic_increasing
        seen += [(scenario, int(i)) for i in rows["sample_index"]]
    assert sorted(seen) == sorted(zip(d["scenario"], d["sample_index"].astype(int)))
    assert len(seen) == len(set(seen))


def test_labels_from_configuration_and_errors():
    labels = scenario_labels(STUDY, "2025-12-15", [6, 12])
    assert labels["forecast"] == ["2026-06-15", "2026-12-15"]
    assert add_months("2025-08-31", 6) == "2026-02-28"
    study = {"seed": 1, "scenarios": {"forecast": {"horizons_months": [3]}}}
    with pytest.raises(ValueError, match="horizons_months"):
        scenario_labels(study, "2025-12-15", [6, 12])
    weights, states = tipm_tables()
    with pytest.raises(ValueError, match="level"):
        build_design({"seed": 1, "scenarios": {"forecast": {"level": 0.3}}},
                     latest_campaign="2025-12-15", tipm_weights=weights, forecast_states=states,
                     horizons_months=[6, 12])
    bad = weights.assign(weight=np.where(weights["sample_index"] == 2, 0.0, weights["weight"]))
    with pytest.raises(ValueError, match="2025-12-15/2"):
        build_design({"seed": 1, "scenarios": {"forecast": {"enabled": False}}},
                     latest_campaign="2025-12-15", tipm_weights=bad, horizons_months=[6])
