"""Random per-element properties of a case: the ``properties:`` section -> factors per carrier.

Either one sample of the fields stage (``field_samples``: a table written by
``ttbpipe.fields``) or independent lognormal factors per carrier (``independent``: mean 1, seeded
by (seed, sample_index)); :func:`ttbpipe.structure.apply_factors` multiplies them into the
structure's per-element properties. A study hands its field factors over in memory instead
(``run_coupled(..., factors=...)``).
"""

from __future__ import annotations

import logging
from typing import Any, Mapping

import numpy as np

from .assembly import CARRIER_PARAMETERS, PARAMETER_CARRIER, carrier_positions

log = logging.getLogger(__name__)


def property_factors(props_cfg: Mapping[str, Any] | None, model) -> dict[str, np.ndarray]:
    """Factors per carrier from the case's ``properties:`` section ({} if none)."""
    if not props_cfg:
        return {}
    factors: dict[str, np.ndarray] = {}
    positions = carrier_positions(model)
    if "field_samples" in props_cfg:
        from ..fields import load_field_factors

        fs = props_cfg["field_samples"]
        factors.update(load_field_factors(fs["path"], int(fs["sample_index"])))
        log.info("properties: %d parameters from %s sample %d", len(factors), fs["path"],
                 fs["sample_index"])
    if "independent" in props_cfg:
        ind = props_cfg["independent"]
        # SeedSequence([seed, index]): a sample's numbers depend only on seed and index
        rng = np.random.default_rng(np.random.SeedSequence([int(ind["seed"]),
                                                            int(ind.get("sample_index", 0))]))
        s = np.sqrt(np.log1p(float(ind["cov"]) ** 2))
        for name in sorted(CARRIER_PARAMETERS, key=str):
            for p in CARRIER_PARAMETERS[name]:
                n = positions[name].size
                draw = rng.lognormal(-0.5 * s * s, s, size=n)   # mean 1, drawn for every name
                if p in ind["parameters"]:
                    factors[p] = factors.get(p, 1.0) * draw
    n_rails = max(int(model.packed.n_rails), 2)
    for p, f in factors.items():
        n = positions[PARAMETER_CARRIER[p]].size
        rails = PARAMETER_CARRIER[p] in ("rail_element", "fastener")
        if np.size(f) not in ((n, n_rails * n) if rails else (n, 2 * n)):
            raise ValueError(f"properties: {p} has {np.size(f)} factors but the structure has {n} "
                             f"{PARAMETER_CARRIER[p]} carriers; sample the fields at "
                             "ttbpipe.structure.carrier_positions(model)")
    return factors
