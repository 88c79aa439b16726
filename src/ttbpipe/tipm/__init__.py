"""Track irregularity probabilistic model (TIPM) and spectral evolution (seed paper §3.2-3.3).

* :mod:`.population`   -- per-section PSDs of one or more campaigns as one array; equivalent TQI;
* :mod:`.distribution` -- per-frequency distribution of PSD ordinates: lognormal / gamma fits
  with goodness of fit;
* :mod:`.selection`    -- probability-preserving selection of representative PSD sets
  (:class:`TIPMSelector`);
* :mod:`.evolution`    -- spectral evolution between campaigns, eqs. 50-56
  (:class:`SpectralEvolution`);
* :mod:`.profiles`     -- space-domain profiles of representative and forecast sets (seeded);
* :mod:`.settings`     -- the ``tipm:`` section (defaults, validation) and the number of
  representative sets, without the fitting modules (the Snakefile plans with it);
* :mod:`.stages`       -- what the workflow scripts call (workflow/rules/tipm.smk);
* :mod:`.plots`        -- figures.

Design and validation: docs/tipm.md.
"""

import importlib

#: Public name -> submodule. Loaded on first use, so that a process reading PSD tables
#: (``tipm.population``, ``tipm.profiles``: every Monte Carlo batch) does not import
#: ``scipy.stats`` with the selection and distribution modules (about 1 s per process).
_EXPORTS = {"PSDPopulation": "population", "synthetic_population": "population",
            "load_population": "population", "TIPMSelection": "selection",
            "TIPMSelector": "selection", "selection_metrics": "selection",
            "SpectralEvolution": "evolution", "forecast_coverage": "evolution"}

__all__ = list(_EXPORTS)


def __getattr__(name: str):
    if name in _EXPORTS:
        value = getattr(importlib.import_module(f".{_EXPORTS[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted([*globals(), *_EXPORTS])
