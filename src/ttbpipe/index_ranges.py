"""Runs of indices stored as rows [start, end) of an (n, 2) int64 array: the one reading of a
row, for every kernel that loops over such runs.

The moving track window (:mod:`ttbpipe.structure.window`) keeps the elements it evaluates and
the DOFs that move as such rows; the structure's element kernels
(:mod:`ttbpipe.structure.kernels`), the clearing of the loads and the Zhai update of the moving
DOFs (:func:`ttbpipe.timestepping.zhai.zhai_predict_ranges`) read them. ``end`` -1 means "to
the last index" (the single row a structure without a window evaluates).
"""

from __future__ import annotations

import numpy as np

from .jit import kernel


@kernel
def range_span(ranges, k, n):
    """Row k of ``ranges`` as unsigned [start, end), end -1 read as ``n``. Unsigned, so that
    numba drops the negative-index test on every access made with these indices (10-15 % of
    the beam and pad loops), which would also keep a loop from being vectorised."""
    end = ranges[k, 1]
    return np.uint64(ranges[k, 0]), np.uint64(end if end >= 0 else n)
