"""Session set-up shared by every test module.

The samples' numerical work runs single-threaded (ttbpipe.threads). numba reads
NUMBA_NUM_THREADS when it is imported and again at every later compilation, and refuses a
different value once its thread pool runs: a module that set the variable after another had
imported numba made every later compilation in that pytest worker fail. So the worker
environment goes in here, before any test module imports numba, numpy or scipy; a value the
caller set is kept.
"""

import os
from pathlib import Path

from ttbpipe import code_version
from ttbpipe.kernel_cache import refresh as refresh_kernel_cache
from ttbpipe.threads import WORKER_ENV

for _name, _value in WORKER_ENV.items():
    os.environ.setdefault(_name, _value)

# Test modules cache kernels of their own (``njit(cache=True)``) that call ttbpipe's; numba keys
# them on the test file alone, so after a change of ttbpipe they would run its old machine code
# (a changed array layout aborts the process). They are dropped with ttbpipe's own when its
# code changes (ttbpipe.kernel_cache).
refresh_kernel_cache(Path(__file__).resolve().parent, code_version())


def pytest_collection_modifyitems(config, items):
    """Tests marked ``slow`` first, each group in collection order (a stable sort, the same in
    every pytest-xdist worker): the scheduler hands out tests in this order, and a long test
    collected near the end would otherwise run alone on one core after the other has finished."""
    items.sort(key=lambda item: item.get_closest_marker("slow") is None)
