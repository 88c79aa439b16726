"""Studies end to end: the sample design, the batch runner (local or Dask) and the study's outputs.

* :mod:`~ttbpipe.study.design`: samples (scenario, sample_index), weights, seeds, batches;
* :mod:`~ttbpipe.study.samples`: one sample's case, coupled run, extremes and time histories;
* :mod:`~ttbpipe.study.batch`: a batch of samples here or on a Dask cluster, written atomically;
* :mod:`~ttbpipe.study.outputs`: the one pipeline from batch files, design and configuration to
  every table, figure and report page (rule aggregate_study and ``ttbpipe stats-report``);
* :mod:`~ttbpipe.study.report_pages`: the text of every report page, from one computed summary;
* :mod:`~ttbpipe.study.cli_report`: the ``ttbpipe stats-report`` command.

Documentation: docs/studies.md.
"""
