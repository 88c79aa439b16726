"""Statistics and reliability of per-sample results: schemas, aggregation, KDE, limits, report.

* :mod:`~ttbpipe.stats.schema`: per-sample extremes and time-history table schemas, validators;
* :mod:`~ttbpipe.stats.aggregate`: bounded-memory aggregation over batch files, Table 1,
  forecast envelopes;
* :mod:`~ttbpipe.stats.kde`: weighted KDE of extremes with boundary treatment;
* :mod:`~ttbpipe.stats.limits`: safety and comfort limits with sources;
* :mod:`~ttbpipe.stats.reliability`: exceedance probabilities, intervals, convergence, verdicts;
* :mod:`~ttbpipe.stats.report`: the report's first page (reStructuredText);
* :mod:`~ttbpipe.stats.plots`: figures.

Documentation: ``docs/results_schema.md`` and ``docs/reliability.md``.
"""
