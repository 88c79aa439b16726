"""One thread for the numerical work of a sample: results independent of the thread settings.

A sample's results must depend only on the study seed and the sample's index, never on the
batch size, core count, thread count or scheduler. Multi-threaded BLAS/LAPACK (OpenBLAS, MKL,
BLIS) splits dot products, matrix products and factorisations across threads and sums the
partial results in an order that depends on the thread count, so the last bits of a static
solve or an eigen-decomposition change with ``OPENBLAS_NUM_THREADS`` (measured: the static wheel
load differed by 1e-5 relative between a run inheriting two BLAS threads and a Dask worker
pinned to one). Every simulation path (local batches, Dask workers, ``ttbpipe simulate``)
therefore runs its numerical work inside :func:`single_threaded`, which limits every BLAS and
OpenMP pool loaded in the process to one thread with threadpoolctl (it acts on the libraries at
run time, whatever the environment variables said when they were loaded) and sets numba's
thread count to one for any parallel kernel. Parallelism comes from running samples side by side
(Snakemake jobs, Dask workers), which is also faster for these memory-bound small problems.
"""

from __future__ import annotations

import contextlib
import functools
import os
import threading
from typing import Any, Callable, Iterator, TypeVar

#: Threads of the numerical work of one sample (BLAS, OpenMP, numba).
SAMPLE_THREADS = 1

#: Environment of worker processes started by ttbpipe (Dask LocalCluster): set before numpy,
#: scipy and numba load, so that their pools start at one thread (belt and braces beside
#: :func:`single_threaded`, which every sample still enters).
WORKER_ENV = {"NUMBA_NUM_THREADS": str(SAMPLE_THREADS), "OMP_NUM_THREADS": str(SAMPLE_THREADS),
              "OPENBLAS_NUM_THREADS": str(SAMPLE_THREADS), "MKL_NUM_THREADS": str(SAMPLE_THREADS)}

F = TypeVar("F", bound=Callable[..., Any])


def apply_worker_environment() -> None:
    """Put :data:`WORKER_ENV` into ``os.environ`` of this process (a worker's initializer).

    numba reads ``NUMBA_NUM_THREADS`` when it is imported and re-reads it at every later
    compilation, refusing a different value once its thread pool runs ("Cannot set
    NUMBA_NUM_THREADS to a different value once the threads have been launched"). A forked
    worker inherits numba, and its pool, from the parent, so there the variable is left as numba
    has it; :func:`single_threaded` sets numba's thread count at run time instead."""
    import sys

    for name, value in WORKER_ENV.items():
        if name == "NUMBA_NUM_THREADS" and "numba" in sys.modules:
            continue
        os.environ[name] = value


#: How deep the current thread is inside :func:`single_threaded`.
_DEPTH = threading.local()


@contextlib.contextmanager
def single_threaded() -> Iterator[None]:
    """Limit BLAS/OpenMP pools (threadpoolctl) to :data:`SAMPLE_THREADS` inside; numba's
    parallel pool is set to one thread too (and left there: every ttbpipe kernel is a serial
    ``@njit``, so this only keeps a parallel kernel from oversubscribing the cores; numba
    refuses to raise the count again once its pool runs with fewer threads).

    Entered again inside itself (a pinned sample calling a pinned run), it does nothing: the
    outer entry holds the limits. The libraries are found by :func:`_threadpool_controller`."""
    depth = getattr(_DEPTH, "value", 0)
    if depth:
        _DEPTH.value = depth + 1
        try:
            yield
        finally:
            _DEPTH.value = depth
        return
    import numba

    # numba first: its first call loads the threading layer, which the scan then sees
    numba.set_num_threads(SAMPLE_THREADS)
    with _threadpool_controller().limit(limits=SAMPLE_THREADS):
        _DEPTH.value = 1
        try:
            yield
        finally:
            _DEPTH.value = 0


#: threadpoolctl's controller of the loaded libraries and the module count it was made at.
_CONTROLLER: dict[str, Any] = {}


def _threadpool_controller():
    """threadpoolctl's ``ThreadpoolController`` of the BLAS/OpenMP libraries loaded in this
    process, scanned again whenever a module has been imported since the last scan: native
    libraries are loaded by the extension modules that need them, so a process that imports
    nothing new keeps the same libraries. A scan reads ``/proc/self/maps``: 1-3 ms in a batch
    process, which each sample paid when every entry scanned (``threadpool_limits``)."""
    import sys

    from threadpoolctl import ThreadpoolController

    modules = len(sys.modules)
    if _CONTROLLER.get("modules") != modules:
        _CONTROLLER["controller"] = ThreadpoolController()
        _CONTROLLER["modules"] = len(sys.modules)
    return _CONTROLLER["controller"]


def pinned(function: F) -> F:
    """Decorator: run ``function`` inside :func:`single_threaded`."""

    @functools.wraps(function)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        with single_threaded():
            return function(*args, **kwargs)

    return wrapper  # type: ignore[return-value]
