"""Random-stream ids (ttbpipe.streams): distinct within each seed tree, and the old names of the
stages are the registry's values. Exact checks (integers and the generated seed words)."""

import re

import numpy as np
import pytest

from ttbpipe import streams
from ttbpipe.dates import DATE_PATTERN


@pytest.mark.parametrize("tree", sorted(streams.TREES))
def test_ids_within_a_tree_are_distinct(tree):
    ids = list(streams.TREES[tree].values())
    assert len(set(ids)) == len(ids), streams.TREES[tree]
    assert all(isinstance(i, int) and 0 <= i < 2 ** 32 for i in ids)


def test_field_group_spawn_keys_are_distinct():
    keys = list(streams.FIELD_GROUPS.values())
    assert len(set(keys)) == len(keys)


def test_campaign_tree_never_meets_the_study_tree():
    """The campaign tree's second word is the date as YYYYMMDD, the study tree's a stage id."""
    from ttbpipe.tipm.profiles import date_key

    assert date_key("0001-01-01") > max(streams.TREES["study"].values())


def test_reserved_labels_are_no_scenario_label():
    from ttbpipe.study.design import FIELD_CONDITIONS, MC_IRREGULARITY, SINGLE

    labels = {SINGLE, MC_IRREGULARITY, *FIELD_CONDITIONS, *(f"{c}_mc" for c in FIELD_CONDITIONS)}
    for reserved in streams.SIMULATION_RESERVED_LABELS:
        assert reserved not in labels
        assert not re.match(DATE_PATTERN, reserved)  # dated (campaign, forecast) labels


def test_stage_names_are_the_registry_ids():
    from ttbpipe.fields import groups, sampling
    from ttbpipe.inspection import synthetic
    from ttbpipe.study import design, samples
    from ttbpipe.tipm import profiles

    assert sampling.STREAM_ID == streams.FIELDS
    assert dict(groups.GROUP_STREAM) == dict(streams.FIELD_GROUPS)
    assert design.STREAM_ID == streams.SIMULATION
    assert (profiles.STREAM_REPRESENTATIVE, profiles.STREAM_FORECAST,
            profiles.STREAM_MONTE_CARLO) == (streams.TIPM_REPRESENTATIVE, streams.TIPM_FORECAST,
                                             streams.TIPM_MONTE_CARLO)
    assert samples.STREAM_MC_PROFILES == streams.STUDY_MC_PROFILES
    assert (synthetic._STREAM_LAYOUT, synthetic._STREAM_CAMPAIGN) == (streams.SYNTHETIC_LAYOUT,
                                                                      streams.SYNTHETIC_CAMPAIGN)


def test_the_sequences_drawn_are_distinct():
    """Every seed sequence a study draws from (one seed for the study and the synthetic series,
    a few dates, scenarios and indices, index 0 included: SeedSequence pads short entropy with
    zeros) gives different numbers."""
    from ttbpipe.fields.sampling import sample_generator
    from ttbpipe.study.design import sample_seed_sequence
    from ttbpipe.study.samples import mc_fields_seed, mean_spectrum_seed
    from ttbpipe.tipm.profiles import date_key, profile_rng

    seed = 20261121
    sequences = {}
    for i in range(3):
        for g, key in streams.FIELD_GROUPS.items():
            sequences[f"fields {g} {i}"] = sample_generator(seed, i, key).bit_generator.seed_seq
        for label in ("2025-12-15", "2026-06-15_p0.5", "single", "mc", "C1", "all", "C2_mc"):
            sequences[f"sample {label} {i}"] = sample_seed_sequence(seed, label, i)
        for date in ("2025-11-15", "2025-12-15"):
            for stream in (streams.TIPM_REPRESENTATIVE, streams.TIPM_FORECAST,
                           streams.STUDY_MC_PROFILES):
                sequences[f"profile {date} {stream} {i}"] = \
                    profile_rng(seed, date, stream, i).bit_generator.seed_seq
        sequences[f"synthetic campaign {i}"] = np.random.SeedSequence(
            [seed, streams.SYNTHETIC_CAMPAIGN, i])
    for date in ("2025-11-15", "2025-12-15"):
        base = [seed, date_key(date), streams.TIPM_MONTE_CARLO]
        sequences[f"tipm envelope {date}"] = np.random.SeedSequence(base)
        sequences[f"tipm validation {date}"] = np.random.SeedSequence(
            base + [streams.TIPM_VALIDATION_SUBSTREAM])
    sequences["synthetic layout"] = np.random.SeedSequence([seed, streams.SYNTHETIC_LAYOUT])
    sequences["mean spectrum"] = np.random.SeedSequence(mean_spectrum_seed(seed))
    sequences["mc fields"] = np.random.SeedSequence(mc_fields_seed(seed))
    states = {name: tuple(seq.generate_state(4)) for name, seq in sequences.items()}
    assert len(set(states.values())) == len(states)
