"""Registry of the random-stream ids: which numbers seed what.

Every random number of a study comes from a ``numpy.random.SeedSequence`` whose entropy is a list
of integers: the seed, then the stream id of the stage that draws, then what identifies the draw
(a date, a scenario, a sample index). A sample's numbers therefore depend only on the seed and its
own identifiers, never on the batch, the number of samples drawn or the core count
(docs/dev/contributing.md, "Determinism"). Three seed trees use stream ids:

**Study tree** ``SeedSequence([study.seed, stage, ...])``:

* :data:`FIELDS` (5): random-field sample ``i``, group ``g``: child ``g``
  (``spawn_key=(FIELD_GROUPS[g],)``) of ``[seed, 5, i]`` (:mod:`ttbpipe.fields.sampling`).
* :data:`SIMULATION` (7): study sample ``(scenario s, index i)``: ``[seed, 7, crc32(s), i]``
  (:func:`ttbpipe.study.design.sample_seed_sequence`); also, from the reserved labels
  :data:`SIMULATION_RESERVED_LABELS`, the seed of the mean-spectrum profile
  ``[seed, 7, crc32("mean_spectrum")]`` and the seed of the plain Monte Carlo fields
  ``[seed, 7, crc32("fields_mc")]`` (:mod:`ttbpipe.study.samples`).
* :data:`RARE_EVENT` (11): the rare-event estimators of :mod:`ttbpipe.reliability`: plain Monte
  Carlo point ``i``, ``[seed, 11, 0, i]``; subset simulation level-0 point ``i``,
  ``[seed, 11, 1, 0, i]``, and the Markov chain seeded by seed point ``c`` at level ``l >= 1``,
  ``[seed, 11, 1, l, c]``; line sampling's line ``i``, ``[seed, 11, 2, i]``. The seed is the study seed in a study, the caller's seed in
  :func:`ttbpipe.reliability.estimate_failure_probability`.

**Campaign tree** ``SeedSequence([study.seed, yyyymmdd(date), stream, ...])`` (the campaign date
as an integer, :func:`ttbpipe.tipm.profiles.date_key`; always > 10000, so never a stage id of the
study tree):

* :data:`TIPM_REPRESENTATIVE` (0): profile ``i`` of the campaign's representative sets,
  ``[seed, date, 0, i]``;
* :data:`TIPM_FORECAST` (1): profile ``i`` of the forecast states based on the campaign;
* :data:`TIPM_MONTE_CARLO` (2): the Monte Carlo envelope of the spectral-evolution forecast,
  ``[seed, date, 2]``, and its hold-out validation, ``[seed, date, 2,
  TIPM_VALIDATION_SUBSTREAM]`` (:mod:`ttbpipe.tipm.stages`);
* :data:`STUDY_MC_PROFILES` (3): profile ``i`` of the study's plain Monte Carlo irregularity
  scenario (:func:`ttbpipe.study.samples.mc_profile`).

**Synthetic-inspection tree** ``SeedSequence([inspections.synthetic.seed, stream, ...])``
(:mod:`ttbpipe.inspection.synthetic`):

* :data:`SYNTHETIC_LAYOUT` (0): base line, blocks, growth rates and defects, ``[seed, 0]``;
* :data:`SYNTHETIC_CAMPAIGN` (1): campaign ``k``'s increment and measurement artefacts,
  ``[seed, 1, k]``.

Ids within one tree must differ (tests/test_streams.py). Two properties of ``SeedSequence``
(numpy.random.SeedSequence: the entropy is a list of 32-bit words hashed into a pool of four):
an entropy shorter than four words is padded with zeros, so ``[a, b]``, ``[a, b, 0]`` and
``[a, b, 0, 0]`` draw the same numbers (representative profile 0, ``[seed, date, 0, 0]``, is
also ``[seed, date]``, which nothing else uses; the test compares the sequences actually drawn,
not only the ids); and an integer of 2**32 or more takes several words, so the ids above are
the second word only for seeds below 2**32. Changing any id changes every result drawn from it.

Not in a tree: fixed seeds of numerical probes (the sign convention of the KLE eigenvectors, the
start vector of the structure's time-step eigensolver), and a case's own
``properties.independent.seed`` (``[seed, sample_index]``, :mod:`ttbpipe.simulation.run`).
"""

from __future__ import annotations

from types import MappingProxyType
from typing import Mapping

# --- study tree: SeedSequence([study.seed, stage, ...]) ---------------------------------------
#: Random-field samples (ttbpipe.fields.sampling).
FIELDS = 5
#: Study samples and their scenario inputs (ttbpipe.study.design, ttbpipe.study.samples).
SIMULATION = 7
#: Scenario-key label under :data:`SIMULATION` of the mean-spectrum profile's seed.
MEAN_SPECTRUM_LABEL = "mean_spectrum"
#: Scenario-key label under :data:`SIMULATION` of the plain Monte Carlo fields' seed.
MC_FIELDS_LABEL = "fields_mc"
#: Labels that seed study-wide inputs rather than samples: never a scenario label.
SIMULATION_RESERVED_LABELS: tuple[str, ...] = (MEAN_SPECTRUM_LABEL, MC_FIELDS_LABEL)
#: Spawn key of each parameter group under :data:`FIELDS`: a group's numbers do not depend on
#: which other groups are enabled.
FIELD_GROUPS: Mapping[str, int] = MappingProxyType({"C1": 0, "C2": 1, "C3": 2, "C4": 3})

#: Rare-event estimators (ttbpipe.reliability): Monte Carlo and subset simulation points.
RARE_EVENT = 11
#: Word after :data:`RARE_EVENT` naming the estimator.
RARE_EVENT_MONTE_CARLO = 0
RARE_EVENT_SUBSET = 1
RARE_EVENT_LINE = 2

# --- campaign tree: SeedSequence([study.seed, yyyymmdd(date), stream, ...]) --------------------
#: Profiles of a campaign's representative PSD sets (ttbpipe.tipm.stages.profiles_stage).
TIPM_REPRESENTATIVE = 0
#: Profiles of the forecast states based on a campaign (ttbpipe.tipm.stages.forecast_stage).
TIPM_FORECAST = 1
#: Monte Carlo envelope of the spectral-evolution forecast from a campaign.
TIPM_MONTE_CARLO = 2
#: Word after :data:`TIPM_MONTE_CARLO` for the hold-out validation's Monte Carlo paths.
TIPM_VALIDATION_SUBSTREAM = 1
#: Profiles of the study's plain Monte Carlo irregularity scenario (ttbpipe.study.samples).
STUDY_MC_PROFILES = 3

# --- synthetic-inspection tree: SeedSequence([inspections.synthetic.seed, stream, ...]) ---------
#: Geometry of the synthetic line: base profiles, blocks, growth rates, defects.
SYNTHETIC_LAYOUT = 0
#: Per-campaign degradation increment and measurement artefacts.
SYNTHETIC_CAMPAIGN = 1

#: The stream ids of each tree (tests/test_streams.py checks they are distinct within a tree).
TREES: Mapping[str, Mapping[str, int]] = MappingProxyType({
    "study": MappingProxyType({"FIELDS": FIELDS, "SIMULATION": SIMULATION,
                               "RARE_EVENT": RARE_EVENT}),
    "campaign": MappingProxyType({"TIPM_REPRESENTATIVE": TIPM_REPRESENTATIVE,
                                  "TIPM_FORECAST": TIPM_FORECAST,
                                  "TIPM_MONTE_CARLO": TIPM_MONTE_CARLO,
                                  "STUDY_MC_PROFILES": STUDY_MC_PROFILES}),
    "synthetic": MappingProxyType({"SYNTHETIC_LAYOUT": SYNTHETIC_LAYOUT,
                                   "SYNTHETIC_CAMPAIGN": SYNTHETIC_CAMPAIGN}),
})
