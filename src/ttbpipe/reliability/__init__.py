"""Rare-event reliability: failure probabilities of limit states in standard-normal space.

Public entry point: :func:`estimate_failure_probability` for any vectorised limit-state
function ``g`` (points of shape (n, n_dims) in standard-normal space -> values of shape (n,),
failure where g <= 0). Every estimator returns a :class:`FailureProbability` with the
probability, its confidence interval, its coefficient of variation and the number of model
evaluations. Methods: ``"monte_carlo"`` (the reference), ``"subset"`` (subset simulation,
Au & Beck 2001) and ``"line_sampling"`` (line sampling along a direction found by a short subset
simulation, Koutsourelakis et al. 2004); docs/reliability.md, "Rare events". The coupled model as a limit state:
:class:`ttbpipe.reliability.coupled.CoupledLimitState` with the inputs map
:class:`ttbpipe.reliability.inputs.StandardNormalInputs` (u -> irregularity profile and field
factors of a study sample).
"""

from __future__ import annotations

from typing import Any, Callable

import numpy as np

from .line_sampling import line_sampling
from .monte_carlo import monte_carlo
from .result import FailureProbability, reliability_index
from .subset import SubsetSettings, SubsetSimulation, subset_simulation

__all__ = ["estimate_failure_probability", "FailureProbability", "reliability_index",
           "SubsetSettings", "SubsetSimulation", "METHODS"]

#: Estimators of :func:`estimate_failure_probability` and the function that implements each.
METHODS: dict[str, Callable[..., FailureProbability]] = {
    "subset": subset_simulation,
    "monte_carlo": monte_carlo,
    "line_sampling": line_sampling,
}


def estimate_failure_probability(g: Callable[[np.ndarray], np.ndarray], n_dims: int,
                                 method: str = "subset", seed: int = 0,
                                 **options: Any) -> FailureProbability:
    """``P(g(U) <= 0)`` for ``U ~ N(0, I_n_dims)``.

    ``method="subset"``: options of :class:`SubsetSettings` (``n_per_level``,
    ``level_probability``, ``max_levels``, ``target_acceptance``, ``initial_scale``,
    ``confidence_level``, ``lineage_lag``, ``sampler`` ``"acs"`` or ``"plane"`` with
    ``plane_min_r2`` and ``plane_margin``). ``method="monte_carlo"``: ``n_samples``, ``batch_size``,
    ``confidence_level``, ``interval`` (``"wilson"`` or ``"clopper-pearson"``).
    ``method="line_sampling"``: ``n_lines``, ``direction`` (``"subset"`` or an array),
    ``direction_n_per_level``, ``direction_levels``, ``direction_lines``, ``c_max``,
    ``root_tolerance``, ``max_iterations``, ``confidence_level``, ``max_missing_fraction``. The result
    depends only on ``seed``, the method and its options (ttbpipe.streams, RARE_EVENT).
    """
    if method not in METHODS:
        raise ValueError(f"unknown method {method!r}; choose one of {sorted(METHODS)}")
    return METHODS[method](g, int(n_dims), seed=int(seed), **options)
