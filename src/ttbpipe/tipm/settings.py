"""The ``tipm:`` section of a study: its defaults, its validation and how many representative
PSD sets its selection takes.

Apart from :mod:`.stages` so that planning a study (the Snakefile, :mod:`ttbpipe.study.plan`)
needs neither SciPy's statistics nor the TIPM's compiled kernels, which the stages load.
"""

from __future__ import annotations

import math
from typing import Any, Mapping

from ..configuration import section_defaults, validate_section

__all__ = ["DEFAULTS", "resolve_config", "representative_count"]

#: Defaults of the ``tipm:`` section: the study schema's (its only home).
DEFAULTS: dict[str, Any] = section_defaults("tipm")


def resolve_config(tipm: Mapping[str, Any] | None) -> dict[str, Any]:
    """``tipm:`` validated against the study schema, missing keys filled from its defaults."""
    return validate_section(tipm, "tipm")


def representative_count(n_sections: int, fraction: float, min_samples: int,
                         max_samples: int | None = None) -> int:
    """M representative sets for a population of N sections: max(min_samples, floor(fraction N)),
    capped by ``max_samples`` and N, at least 1 (the selector's rule, docs/tipm.md)."""
    m = max(int(min_samples), math.floor(fraction * n_sections + 1e-9))
    if max_samples is not None:
        m = min(m, int(max_samples))
    return max(1, min(m, int(n_sections)))
