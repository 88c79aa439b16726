"""Assessment of a run against a standard: each index processed as the standard prescribes.

A run's raw indices (:mod:`ttbpipe.response_indices`) are maxima over every time step of
unfiltered forces and accelerations; no standard evaluates them that way. A *profile* (one
module per standard) post-processes the run's histories the way its clause says - filters,
sliding means over distance windows, percentiles, window statistics (:mod:`.processing`) - and
returns one row per index with the processed value beside its raw counterpart and the limit:

* ``en14363`` (:mod:`.en14363`): EN 14363:2016 running safety and track loading;
* ``gb5599`` (:mod:`.gb5599`): GB/T 5599-2019 running safety and ride quality;
* ``en1990`` (:mod:`.en1990`): EN 1990 Annex A2 deck checks (needs the run's structure for its
  modal analysis, :mod:`.modal`, and the twist monitors of :mod:`.monitors`);
* ``en12299`` (:mod:`.en12299`): EN 12299 mean comfort N_MV with its weighting filters.

API: :func:`assess` (table, summary, standard), :func:`assess_result` (a ``ttbpipe simulate``
Parquet), :func:`profiles` (the registry); command line ``ttbpipe assess RESULT.parquet
--standard NAME --out ASSESSMENT.parquet`` and ``ttbpipe assess-monitors CASE.yaml --out
CASE_DECK.yaml``. Documentation: docs/assessment.md.
"""

from .api import assess, assess_result
from .base import COLUMNS, Profile, Row
from .registry import get_profile, profiles

__all__ = ["COLUMNS", "Profile", "Row", "assess", "assess_result", "get_profile", "profiles"]
