"""The numba options of every ttbpipe kernel, in one place: ``@kernel`` instead of ``@njit``.

* ``cache=True``: compiled once per installation and code version (numba's on-disk cache, kept
  in step with the code by :mod:`ttbpipe.kernel_cache`).
* ``error_model="numpy"``: a float division by zero gives inf or NaN, as in numpy, instead of
  raising ``ZeroDivisionError``; an integer division or remainder by zero gives 0. numba's
  default ("python") tests every divisor before dividing; without those tests the reference
  case's step is 3-7 % shorter with bit-for-bit the same results (docs/performance.md). A
  non-finite value is not lost: the coupled loops check the state's finiteness and stop with
  the likely cause (:mod:`ttbpipe.simulation.diagnosis`). No kernel divides an integer by a
  value that can be zero (decimation factors, tap counts, table sizes).
"""

from __future__ import annotations

from numba import njit

#: Options of every kernel (module docstring).
KERNEL_OPTIONS = {"cache": True, "error_model": "numpy"}


def kernel(function=None, **options):
    """``numba.njit`` with :data:`KERNEL_OPTIONS`: ``@kernel`` or ``@kernel(inline="always")``
    (further options are added to them)."""
    if function is None:
        return njit(**KERNEL_OPTIONS, **options)
    return njit(**KERNEL_OPTIONS)(function)
