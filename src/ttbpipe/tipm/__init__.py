"""Track irregularity probabilistic model (TIPM) and spectral evolution (seed paper §3.2-3.3).

* :mod:`.population`   -- per-section PSDs of one or more campaigns as one array; equivalent TQI;
* :mod:`.distribution` -- per-frequency distribution of PSD ordinates: lognormal / gamma fits
  with goodness of fit;
* :mod:`.selection`    -- probability-preserving selection of representative PSD sets
  (:class:`TIPMSelector`);
* :mod:`.evolution`    -- spectral evolution between campaigns, eqs. 50-56
  (:class:`SpectralEvolution`);
* :mod:`.profiles`     -- space-domain profiles of representative and forecast sets (seeded);
* :mod:`.stages`       -- what the workflow scripts call (workflow/rules/tipm.smk);
* :mod:`.plots`        -- figures.

Design and validation: docs/tipm.md.
"""

from .evolution import SpectralEvolution, forecast_coverage
from .population import PSDPopulation, synthetic_population
from .selection import TIPMSelection, TIPMSelector, selection_metrics

__all__ = ["PSDPopulation", "synthetic_population", "TIPMSelection", "TIPMSelector",
           "selection_metrics", "SpectralEvolution", "forecast_coverage"]
