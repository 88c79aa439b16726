"""Where a coupled run's CPU goes, by compiled kernel: `perf` samples named by `gdb`.

    python benchmarks/step_profile.py [--case config/reference_case.yaml] [--runs 3]
        [--seconds 12] [--addresses 600]

numba's machine code has no symbols for `perf`, but numba registers its in-memory objects with
`gdb`'s JIT interface. So the script starts a child process that runs the case once to warm
up (numba's cache, imports) and then ``--runs`` times, records it with `perf record -p`
for ``--seconds`` of those runs, and, while the child still lives, asks `gdb` (attached,
batch mode) which function holds each of the ``--addresses`` most sampled addresses. Prints
each kernel's share of all the child's samples (numba inlines most helpers: a share is that
of the kernel the code was inlined into), the shares of the shared libraries' symbols at the
top (libm, libpython, numba's runtime ``NRT_incref`` / ``NRT_decref``), and a ``FIGURE`` line
for the reference counts' share. Needs `perf` and `gdb` (Debian: linux-perf, gdb) and the
right to attach to a child. Timings only: docs/performance.md, "Reference counting in the
step" and "The step by function".
"""

from __future__ import annotations

import argparse
import collections
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: The child: warm-up, a ready file, the timed runs, then it waits to be read by gdb.
CHILD = """
import os, sys, time
from pathlib import Path
import yaml
from ttbpipe.simulation.coupled import run_coupled
case = yaml.safe_load(Path(sys.argv[1]).read_text())
run_coupled(dict(case, simulation=dict(case["simulation"], duration_s=0.05)))
Path(sys.argv[3]).write_text(str(os.getpid()))
time.sleep(1.0)
for _ in range(int(sys.argv[2])):
    run_coupled(case)
Path(sys.argv[4]).write_text("done")
time.sleep(600)
"""


def _wait_for(path: Path, child: subprocess.Popen, what: str) -> None:
    while not path.exists():
        if child.poll() is not None:
            raise SystemExit(f"the child process stopped before {what}:\n"
                             f"{child.stderr.read()[-2000:]}")
        time.sleep(0.2)


def kernel_name(symbol: str) -> str:
    """A readable kernel name from gdb's symbol: numba's mangled ``_ZN7ttbpipe...`` or its
    demangled ``ttbpipe::...::name[abi:...]``."""
    if symbol.startswith("_ZN"):
        parts, rest = [], symbol[3:]
        while rest and rest[0].isdigit():
            n = int(re.match(r"\d+", rest).group())
            digits = len(str(n))
            parts.append(rest[digits:digits + n])
            rest = rest[digits + n:]
        return ".".join(parts) or symbol
    return symbol.split("[abi:")[0].split("(")[0].replace("::", ".")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", default=str(ROOT / "config" / "reference_case.yaml"))
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--seconds", type=float, default=12.0)
    parser.add_argument("--addresses", type=int, default=600)
    args = parser.parse_args()
    env = {**os.environ, "NUMBA_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
           "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
    with tempfile.TemporaryDirectory() as scratch:
        ready, done, data = (Path(scratch) / name for name in ("ready", "done", "perf.data"))
        child = subprocess.Popen([sys.executable, "-c", CHILD, args.case, str(args.runs),
                                  str(ready), str(done)], env=env, stdout=subprocess.DEVNULL,
                                 stderr=subprocess.PIPE, text=True)
        try:
            _wait_for(ready, child, "its warm-up run ended")
            subprocess.run(["perf", "record", "-q", "-F", "2000", "-p", str(child.pid), "-o",
                            str(data), "--", "sleep", str(args.seconds)],
                           check=True, capture_output=True)
            _wait_for(done, child, "its runs ended")
            report = subprocess.run(["perf", "report", "-i", str(data), "--sort", "symbol",
                                     "--stdio"], check=True, capture_output=True,
                                    text=True).stdout
            rows = []
            for line in report.splitlines():
                match = re.match(r"\s*([\d.]+)%\s+\[[.k]\]\s+(\S+)", line)
                if match:
                    rows.append((float(match.group(1)), match.group(2)))
            addresses = [(share, sym) for share, sym in rows if sym.startswith("0x")]
            addresses = addresses[:args.addresses]
            commands = [arg for _, sym in addresses for arg in ("-ex", f"info symbol {sym}")]
            named = subprocess.run(["gdb", "-p", str(child.pid), "-batch", *commands],
                                   capture_output=True, text=True).stdout
        finally:
            child.kill()
            child.wait()
    answers = [line for line in named.splitlines()
               if " in section " in line or line.startswith("No symbol")]
    by_kernel: dict[str, float] = collections.defaultdict(float)
    for (share, _), answer in zip(addresses, answers):
        symbol = answer.split(" + ")[0].split(" in section")[0] if " in section" in answer \
            else "(no symbol)"
        by_kernel[kernel_name(symbol)] += share
    for share, sym in rows:
        if not sym.startswith("0x"):
            by_kernel[sym] += share
    named_share = sum(share for share, _ in addresses)
    print(f"{args.case}: {args.runs} runs, {args.seconds:g} s recorded; the {len(addresses)} "
          f"hottest JIT addresses ({named_share:.1f} % of the samples) named by gdb")
    print("| kernel or symbol | share of the samples |\n|---|---|")
    for name, share in sorted(by_kernel.items(), key=lambda item: -item[1])[:25]:
        print(f"| {name} | {share:.2f} % |")
    refcounts = by_kernel.get("NRT_incref", 0.0) + by_kernel.get("NRT_decref", 0.0)
    print(f"FIGURE step_profile_refcount_share = {refcounts:.3g} %")


if __name__ == "__main__":
    main()
