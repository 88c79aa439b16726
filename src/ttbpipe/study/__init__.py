"""Studies end to end: the sample design, the batch runner (local or Dask) and the aggregation.

* :mod:`~ttbpipe.study.design`: samples (scenario, sample_index), weights, seeds, batches;
* :mod:`~ttbpipe.study.samples`: one sample's case, coupled run, extremes and time histories;
* :mod:`~ttbpipe.study.batch`: a batch of samples here or on a Dask cluster, written atomically;
* :mod:`~ttbpipe.study.aggregate`: tables, figures and the report pages over all batches.

Documentation: docs/studies.md.
"""
