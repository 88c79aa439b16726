"""How a process that runs samples allocates memory: freed arrays reused, not mapped afresh.

glibc's malloc serves an allocation above its mmap threshold (128 KiB at start, raised to the
largest mapped block freed so far, at most 32 MiB) with fresh pages from the operating system
and returns them when it is freed; it also returns free memory at the top of its heap beyond
the trim threshold (twice the mmap threshold). A sample allocates and frees arrays of several
MB each (paper case 3: the 463-column history table, 13 MB, its copies in the finiteness check
and the tables of the run), and every fresh page costs a page fault on first touch. Measured on
case 3's Monte Carlo samples (``benchmarks/study_sample_stages.py``, 12 samples, the code of
2026-12-06): the finiteness check took 11-22 ms and the results table 8-13 ms a sample, against
1.5 and 4.3 ms when the memory is reused (docs/performance.md, "The work around each run of a
batch").

:func:`reuse_freed_memory` fixes both thresholds (``mallopt``), so that blocks below
:data:`MMAP_THRESHOLD_BYTES` come from the heap and are reused, and up to
:data:`TRIM_THRESHOLD_BYTES` of free heap stay in the process. It changes where arrays live,
never what is computed. The batch processes call it (:func:`ttbpipe.study.batch.simulate_batch`,
and the Dask workers through :func:`ttbpipe.study.batch.dask_client`); elsewhere (not glibc)
it does nothing.
"""

from __future__ import annotations

import ctypes
import logging
import sys

log = logging.getLogger(__name__)

#: Blocks below this size come from the heap (a sample's largest arrays are about 13 MB).
MMAP_THRESHOLD_BYTES = 64 * 2 ** 20
#: Free memory at the top of the heap kept in the process rather than returned.
TRIM_THRESHOLD_BYTES = 256 * 2 ** 20
#: mallopt parameter numbers (glibc's malloc.h).
_M_TRIM_THRESHOLD = -1
_M_MMAP_THRESHOLD = -3


def reuse_freed_memory() -> bool:
    """Set glibc's mmap and trim thresholds for this process (module docstring); True when set,
    False where the C library is not glibc or refuses."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = ctypes.CDLL("libc.so.6")
        mallopt = libc.mallopt
    except (OSError, AttributeError):
        log.debug("no glibc mallopt: the allocator's thresholds are left as they are")
        return False
    mallopt.argtypes = (ctypes.c_int, ctypes.c_int)
    mallopt.restype = ctypes.c_int
    done = (mallopt(_M_MMAP_THRESHOLD, MMAP_THRESHOLD_BYTES) == 1
            and mallopt(_M_TRIM_THRESHOLD, TRIM_THRESHOLD_BYTES) == 1)
    if not done:
        log.debug("mallopt refused the thresholds: the allocator's are left as they are")
    return done
