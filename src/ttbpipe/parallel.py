"""Independent pieces of one job spread over its cores, results independent of the split.

The aggregation job runs alone at the end of a study with the cores of the whole machine (its
rule asks for two threads); its tail fits and figures are independent of each other.
:func:`process_map` runs them in forked worker processes: a fork starts without re-importing
the package and shares the parent's tables copy-on-write, so the workers cost milliseconds.
Elsewhere than on Linux (:func:`can_fork`), or with one worker, the items run in order in this
process. Every item must be seeded by its own inputs (never by a shared generator), so
that the results do not depend on the number of workers.
"""

from __future__ import annotations

import multiprocessing
import sys
from concurrent.futures import ProcessPoolExecutor
from typing import Any, Callable, Sequence


def can_fork() -> bool:
    """Whether worker processes are forked here: on Linux (Python's documentation calls a fork
    unsafe on macOS, where system libraries may hold threads; Windows cannot fork)."""
    return sys.platform.startswith("linux") and "fork" in multiprocessing.get_all_start_methods()


def process_map(function: Callable[[Any], Any], items: Sequence[Any], workers: int) -> list[Any]:
    """``[function(item) for item in items]``, in ``workers`` forked processes when > 1.

    ``function`` must be a module-level function (it is sent to the workers by name); what it
    reads from module globals set before this call, the forked workers see too."""
    items = list(items)
    workers = min(int(workers), len(items))
    if workers <= 1 or not can_fork():
        return [function(item) for item in items]
    with ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("fork")) as pool:
        # one item at a time: items are few (fits, figures) and of uneven cost
        return list(pool.map(function, items))
