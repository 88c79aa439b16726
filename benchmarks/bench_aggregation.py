"""Benchmark: aggregate 10 000 synthetic samples from batch files; print wall time and memory.

    NUMBA_NUM_THREADS=1 python benchmarks/bench_aggregation.py [--samples 10000] [--batch 250]
        [--points 1000] [--bins 256] [--keep DIR]

Writes per-batch extremes and long-format time-history tables (ttbpipe.stats.schema examples,
two quantities, one scenario with TIPM-like random weights) to a temporary folder, then times
``read_extremes``, ``assess_limits`` and ``aggregate_histories``. Memory: peak resident set size
of the process (``resource.getrusage``, includes the writing phase) and the peak RSS growth
during aggregation measured by a sampling thread, and the accumulator state in bytes.
"""

from __future__ import annotations

import argparse
import resource
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

from ttbpipe import io
from ttbpipe.stats import streaming as A
from ttbpipe.stats.limits import default_limits, LimitContext
from ttbpipe.stats.reliability import assess_limits
from ttbpipe.stats.schema import example_extremes, example_histories


def _rss_mb() -> float:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * resource.getpagesize() / 1e6


class _PeakRSS:
    """Samples the resident set size every 10 ms in a thread; keeps the peak."""

    def __enter__(self):
        self.start = _rss_mb()
        self.peak = self.start
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()
        return self

    def _run(self):
        while not self._stop.is_set():
            self.peak = max(self.peak, _rss_mb())
            time.sleep(0.01)

    def __exit__(self, *exc):
        self._stop.set()
        self._thread.join()
        self.peak = max(self.peak, _rss_mb())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--samples", type=int, default=10_000)
    parser.add_argument("--batch", type=int, default=250)
    parser.add_argument("--points", type=int, default=1000)
    parser.add_argument("--bins", type=int, default=256)
    parser.add_argument("--keep", type=Path, default=None, help="write the batches here and keep them")
    args = parser.parse_args()

    folder = args.keep or Path(tempfile.mkdtemp(prefix="ttbpipe_bench_"))
    folder.mkdir(parents=True, exist_ok=True)
    weights = np.random.default_rng(0).dirichlet(np.ones(args.samples)) * args.samples
    t0 = time.perf_counter()
    ext_paths, hist_paths = [], []
    for start in range(0, args.samples, args.batch):
        index = np.arange(start, min(start + args.batch, args.samples))
        ext_paths.append(io.write_table(example_extremes(index, "tipm", weights=weights[index]),
                                        folder / f"extremes_{start:06d}.parquet", kind="extremes"))
        hist_paths.append(io.write_table(
            example_histories(index, "tipm", n_points=args.points, weights=weights[index]),
            folder / f"histories_{start:06d}.parquet", kind="histories"))
    t_write = time.perf_counter() - t0
    disk_mb = sum(p.stat().st_size for p in hist_paths + ext_paths) / 1e6
    print(f"samples {args.samples}, batch {args.batch}, points {args.points}, "
          f"{len(hist_paths)} history files ({disk_mb:.0f} MB on disk), written in {t_write:.1f} s")

    t0 = time.perf_counter()
    extremes = A.read_extremes(ext_paths)
    table = assess_limits(extremes, default_limits(), LimitContext())
    t_ext = time.perf_counter() - t0
    print(f"read_extremes + assess_limits ({len(extremes)} rows, {len(table)} limit rows): "
          f"{t_ext:.2f} s")

    trace = A.AggregationTrace()
    with _PeakRSS() as rss:
        t0 = time.perf_counter()
        stats = A.aggregate_histories(hist_paths, n_bins=args.bins, trace=trace)
        t_agg = time.perf_counter() - t0
    values = args.samples * args.points * 2
    print(f"aggregate_histories: {t_agg:.1f} s wall ({values / t_agg / 1e6:.1f} M values/s, two "
          f"passes), {trace.files_read} file reads")
    # machine-readable figures for benchmarks/run_all.py
    print(f"FIGURE aggregation_{args.samples}_samples = {t_agg:.4g} s")
    print(f"FIGURE extremes_and_limits_{args.samples}_samples = {t_ext:.4g} s")
    print(f"  largest batch held: {trace.max_rows_in_memory} rows; accumulator state "
          f"{trace.state_nbytes / 1e6:.1f} MB; RSS {rss.start:.0f} -> peak {rss.peak:.0f} MB "
          f"(+{rss.peak - rss.start:.0f} MB during aggregation)")
    print(f"  all data in memory would be {values * 8 / 1e6:.0f} MB of float64")
    print(f"process peak RSS (ru_maxrss): {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e3:.0f} MB")
    r = stats[("tipm", "rail_vertical_acc_m_s2")]
    print(f"  n_effective {r.n_effective:.0f}; median percentile bin width "
          f"{np.median(r.bin_width):.3g} m/s^2 (percentile error bound)")
    if args.keep is None:
        for p in hist_paths + ext_paths:
            p.unlink()
        folder.rmdir()


if __name__ == "__main__":
    main()
