"""Hold a dask_jobqueue.SLURMCluster open for a Dask study run (tools/slurm_check.sh, docs/cluster.md).

    python tools/dask_slurm_cluster.py --account A --partition P --workers 2 --address-file F

starts a Dask scheduler in this process and ``--workers`` single-threaded Dask workers, one
SLURM job each (1 CPU, ``--memory``), waits until they have all connected, writes the scheduler
address to ``--address-file`` and then keeps the cluster alive until it receives SIGTERM/SIGINT
(or ``--lifetime`` seconds pass); the worker jobs are cancelled on exit. A study run then reaches
the cluster through ``TTBPIPE_DASK_SCHEDULER=$(cat F)`` with ``simulation.executor: dask``.

The workers run this interpreter (``sys.executable``: the environment must be on a file system
the compute nodes see) with NUMBA_NUM_THREADS = OMP_NUM_THREADS = OPENBLAS_NUM_THREADS =
MKL_NUM_THREADS = 1, as ttbpipe.study.batch expects of an external cluster.
"""

from __future__ import annotations

import argparse
import os
import signal
import sys
import threading
import time
from pathlib import Path

PIN = ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--account", required=True)
    ap.add_argument("--partition", required=True)
    ap.add_argument("--workers", type=int, default=2, help="SLURM jobs, one 1-thread worker each")
    ap.add_argument("--memory", default="2GB", help="per worker job")
    ap.add_argument("--walltime", default="00:30:00")
    ap.add_argument("--log-directory", default="logs/dask-slurm")
    ap.add_argument("--address-file", required=True)
    ap.add_argument("--lifetime", type=float, default=3600.0, help="s before the cluster closes")
    ap.add_argument("--timeout", type=float, default=300.0, help="s to wait for the workers")
    args = ap.parse_args(argv)

    from dask_jobqueue import SLURMCluster
    from distributed import Client

    Path(args.log_directory).mkdir(parents=True, exist_ok=True)
    cluster = SLURMCluster(
        cores=1, processes=1, memory=args.memory, walltime=args.walltime,
        account=args.account, queue=args.partition, python=sys.executable,
        job_script_prologue=[f"export {name}=1" for name in PIN],
        log_directory=args.log_directory, job_name="ttbpipe-dask",
    )
    stop = threading.Event()
    for sig in (signal.SIGTERM, signal.SIGINT):
        signal.signal(sig, lambda *_: stop.set())
    try:
        print(cluster.job_script(), flush=True)
        cluster.scale(jobs=args.workers)
        client = Client(cluster)
        t0 = time.monotonic()
        client.wait_for_workers(args.workers, timeout=args.timeout)
        print(f"dask_slurm_cluster: {args.workers} workers after {time.monotonic() - t0:.1f} s; "
              f"scheduler {cluster.scheduler_address}; jobs "
              f"{sorted(cluster.workers)}", flush=True)
        tmp = Path(args.address_file + ".tmp")
        tmp.write_text(cluster.scheduler_address + "\n")
        os.replace(tmp, args.address_file)
        stop.wait(args.lifetime)
        client.close()
    finally:
        cluster.close()
        Path(args.address_file).unlink(missing_ok=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
