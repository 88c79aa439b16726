"""Limit states of the coupled train-track-bridge model in standard-normal space.

``g(u) = 1 - index(u) / limit``: failure (g <= 0) when the response index of the run whose
random inputs are the image of u reaches the limit; g is the utilisation margin, continuous in
the inputs, as subset simulation needs (a clipped or saturated g stalls its thresholds).

The map u -> (irregularity profile, parameter-field factors) is an *inputs* object with
``n_dims`` and ``map(u) -> (profile table, factors or None)``
(:class:`ttbpipe.reliability.inputs.StandardNormalInputs`). Each point is one coupled run
(:func:`ttbpipe.simulation.coupled.run_coupled`) and depends on u only, so a batch of points can
be spread over processes in any way without changing a value.
"""

from __future__ import annotations

import copy
import logging
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from typing import Any, Callable, Mapping, Protocol

import numpy as np
import pandas as pd

from ..threads import apply_worker_environment, pinned

log = logging.getLogger(__name__)

__all__ = ["InputMap", "CoupledLimitState", "run_point"]


class InputMap(Protocol):
    n_dims: int

    def map(self, u: np.ndarray) -> tuple[pd.DataFrame, Mapping[str, np.ndarray] | None]: ...


@pinned
def run_point(case: Mapping[str, Any], input_map: InputMap, u: np.ndarray) -> dict[str, float]:
    """Response indices (the extremes row of :func:`ttbpipe.study.samples.extremes_from_run`)
    of the coupled run at standard-normal point u; the profile's chainage is the structure's
    (the inputs map places it, lead-in included)."""
    from ..simulation.coupled import run_coupled
    from ..study.samples import extremes_from_run

    track, factors = input_map.map(np.asarray(u, dtype=float))
    _, summary = run_coupled(copy.deepcopy(dict(case)), track=track, factors=factors)
    return extremes_from_run(summary)


_WORKER: dict[str, Any] = {}


def _init_worker(case, input_map) -> None:
    apply_worker_environment()
    _WORKER.update(case=case, input_map=input_map)


def _worker_run(u: np.ndarray) -> dict[str, float]:
    return run_point(_WORKER["case"], _WORKER["input_map"], u)


@dataclass
class CoupledLimitState:
    """Vectorised ``g(u) = 1 - index / limit`` of the coupled model.

    ``case``: a case configuration of :func:`run_coupled` without irregularity source (built by
    :func:`ttbpipe.study.samples.build_case`); ``index``: a column of the extremes table
    (``max_wheel_unloading_ratio``, an assessed ``<profile>_<index>`` column...); ``limit``:
    its limit (same unit), or a function of the run's extremes row giving it (a threshold that
depends on the train speed or the static axle load). ``executor='local'``: ``workers``
processes evaluate a batch (1: in this process); ``'dask'``: the points go to the study's Dask
cluster (``simulation.dask``: the scheduler at ``$TTBPIPE_DASK_SCHEDULER`` or
``dask.scheduler``, else a LocalCluster; :func:`ttbpipe.study.batch.dask_client`). Every
    evaluated row is kept in :attr:`evaluations` (u's index in call order, all indices), so
    that one set of runs can serve several thresholds and the tail model.
    """

    case: Mapping[str, Any]
    input_map: InputMap
    index: str
    limit: float | Callable[[Mapping[str, float]], float]
    workers: int = 1
    executor: str = "local"
    dask: Mapping[str, Any] | None = None

    def __post_init__(self) -> None:
        if not callable(self.limit) and not (np.isfinite(self.limit) and self.limit > 0):
            raise ValueError(f"limit of {self.index} must be finite and > 0, got {self.limit}")
        self.n_dims = int(self.input_map.n_dims)
        self.evaluations: list[dict[str, float]] = []
        self._pool: ProcessPoolExecutor | None = None
        self._dask: tuple | None = None
        if self.executor not in ("local", "dask"):
            raise ValueError(f"executor {self.executor!r}; expected local | dask")

    def rows(self, points: np.ndarray) -> list[dict[str, float]]:
        """The extremes row of each point (runs in parallel when ``workers`` > 1)."""
        points = np.atleast_2d(np.asarray(points, dtype=float))
        if points.shape[1] != self.n_dims:
            raise ValueError(f"points of dimension {points.shape[1]}, the inputs have {self.n_dims}")
        if self.executor == "dask":
            return self._rows_dask(points)
        if self.workers <= 1:
            return [run_point(self.case, self.input_map, u) for u in points]
        if self._pool is None:
            self._pool = ProcessPoolExecutor(
                self.workers, initializer=_init_worker,
                initargs=(self.case, self.input_map))
        return list(self._pool.map(_worker_run, list(points),
                                   chunksize=max(1, len(points) // (4 * self.workers))))

    def _rows_dask(self, points: np.ndarray) -> list[dict[str, float]]:
        if self._dask is None:
            from ..study.batch import dask_client

            client, cluster = dask_client(self.dask)
            # the case and the inputs map go to the workers once, not with every point
            case, input_map = client.scatter([dict(self.case), self.input_map], broadcast=True)
            self._dask = (client, cluster, case, input_map)
        client, _, case, input_map = self._dask
        futures = client.map(run_point, [case] * len(points), [input_map] * len(points),
                             list(points), pure=False)
        return client.gather(futures)

    def __call__(self, points: np.ndarray) -> np.ndarray:
        rows = self.rows(points)
        missing = [i for i, r in enumerate(rows) if self.index not in r]
        if missing:
            raise KeyError(f"the coupled run has no index {self.index!r}; available: "
                           f"{sorted(rows[0])}")
        self.evaluations.extend(rows)
        values = np.array([r[self.index] for r in rows], dtype=float)
        limits = np.array([self.limit(r) if callable(self.limit) else self.limit for r in rows],
                          dtype=float)
        return 1.0 - values / limits

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown()
            self._pool = None
        if self._dask is not None:
            client, cluster = self._dask[:2]
            client.close()
            if cluster is not None:
                cluster.close()
            self._dask = None

    def __enter__(self) -> "CoupledLimitState":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __getstate__(self):
        state = dict(self.__dict__)
        state["_pool"] = None
        state["_dask"] = None
        return state

