"""Statistics and reliability of per-sample results.

* :mod:`~ttbpipe.stats.schema`: per-sample extremes and time-history table schemas, validators;
* :mod:`~ttbpipe.stats.streaming`: bounded-memory reductions of batch files (extremes, weighted
  moments and percentiles of time histories);
* :mod:`~ttbpipe.stats.tables`: Table 1 and forecast envelopes from the reduced results;
* :mod:`~ttbpipe.stats.kde`: weighted KDE of extremes with boundary treatment;
* :mod:`~ttbpipe.stats.limits`: safety and comfort limits with sources;
* :mod:`~ttbpipe.stats.reliability`: exceedance probabilities, intervals, convergence, verdicts;
* :mod:`~ttbpipe.stats.plots`: figures.

The study's tables, figures and report pages built from these: :mod:`ttbpipe.study.outputs`
(text of the pages: :mod:`ttbpipe.study.report_pages`). Documentation: ``docs/results_schema.md``
and ``docs/reliability.md``.
"""
