"""Random fields of track and bridge parameters (paper section 3.1, case 2 of section 5.2).

Parameters are random multiplicative factors on nominal values. Main entry points:

* :class:`~ttbpipe.fields.nataf.NatafTransform` -- correlated variables with arbitrary marginals;
* :class:`~ttbpipe.fields.kle.KarhunenLoeve` -- truncated KL expansion of a 1-D field;
* :class:`~ttbpipe.fields.sampling.FieldSampler` -- a study's cross-correlated fields;
* :func:`~ttbpipe.fields.sampling.sample_study` -- draw and write the Parquet sample table;
* :func:`~ttbpipe.fields.sampling.load_field_factors` -- read one sample for the simulation;
* :func:`~ttbpipe.fields.groups.carrier_positions` -- carriers along the line from the geometry.

See docs/random_fields.md.
"""

from .groups import GROUP_DEFINITIONS, carrier_positions, line_length_m, make_marginal, segment_index
from .kle import KarhunenLoeve, exponential_kernel_eigenvalues, modes_for_fractions
from .nataf import InfeasibleCorrelationError, NatafTransform, nearest_correlation_matrix
from .sampling import (STREAM_ID, FieldSampler, GroupFieldSampler, load_field_factors,
                       sample_study)

__all__ = [
    "GROUP_DEFINITIONS", "carrier_positions", "line_length_m", "make_marginal", "segment_index",
    "KarhunenLoeve", "exponential_kernel_eigenvalues", "modes_for_fractions",
    "InfeasibleCorrelationError", "NatafTransform", "nearest_correlation_matrix",
    "STREAM_ID", "FieldSampler", "GroupFieldSampler", "load_field_factors", "sample_study",
]
