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

``@kernel(creates_arrays=False)`` marks the kernels of the time step, which work on arrays their
caller holds: they are compiled without numba's runtime (its private target option ``_nrt``),
so without reference counting. numba counts the references to every array a kernel receives,
reads from a tuple or hands to an inlined helper, with an atomic increment and decrement that
its reference-count pruning cannot remove across branches and loops; in the coupled loop they
were about 15 % of the CPU time (``perf record`` on the reference case: ``NRT_incref`` and
``NRT_decref``, docs/performance.md). Such a kernel only borrows arrays: numba refuses to
compile it if it creates one (tests/test_jit.py), and it may call kernels that count.
"""

from __future__ import annotations

from numba import njit

#: Options of every kernel (module docstring).
KERNEL_OPTIONS = {"cache": True, "error_model": "numpy"}


def kernel(function=None, *, creates_arrays=True, **options):
    """``numba.njit`` with :data:`KERNEL_OPTIONS`: ``@kernel``, ``@kernel(inline="always")``
    or ``@kernel(creates_arrays=False)`` (a kernel without reference counting, module
    docstring); further options are added to them or replace them."""
    # _nrt set either way: numba lets a kernel without it inherit the setting of the kernel
    # whose compilation first calls it, so a kernel that creates arrays, first compiled from
    # a borrowing one, would be refused
    options["_nrt"] = bool(creates_arrays)
    if function is None:
        return njit(**{**KERNEL_OPTIONS, **options})
    return njit(**KERNEL_OPTIONS, **options)(function)
