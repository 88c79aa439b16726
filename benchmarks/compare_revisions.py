"""Time a benchmark script on an older revision and on this working tree, alternately.

    python benchmarks/compare_revisions.py [--rev HEAD] [--rounds 5]
        [--script benchmarks/bench_reference_case.py] [--figure reference_case_us_per_step]
        [-- script arguments, e.g. --case my_case.yaml]

The old revision is exported with ``git archive`` into a temporary folder (no checkout, the
working tree is untouched); both run the same script file of this tree (so they measure the
same thing) in subprocesses pinned to one thread (as ``run_all.py``), the old one with
``PYTHONPATH=<folder>/src`` (a path entry, ahead of the editable install). After one warm-up
run each (numba compiles into each tree's own cache), the rounds alternate old/new and
new/old so that a drift of the machine load hits both. Prints every figure's median and
minimum for both (on a loaded machine the minimum is the better estimate of the cost), the
ratios new/old and the per-round values of ``--figure``. Timings only, nothing asserted.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))
from run_all import THREAD_ENV, parse_figures  # noqa: E402


def run(script: Path, src: Path, cwd: Path, extra: list[str]) -> dict[str, tuple[float, str]]:
    env = {**os.environ, **THREAD_ENV, "PYTHONPATH": str(src)}
    proc = subprocess.run([sys.executable, str(script), *extra], cwd=cwd, env=env,
                          capture_output=True, text=True)
    if proc.returncode != 0:
        raise SystemExit(f"{script} failed with PYTHONPATH={src}:\n{proc.stderr[-2000:]}")
    return {name: (value, unit) for name, value, unit in parse_figures(proc.stdout)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rev", default="HEAD", help="git revision to compare with")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--script", default=str(HERE / "bench_reference_case.py"))
    parser.add_argument("--figure", default="reference_case_us_per_step")
    parser.add_argument("extra", nargs="*", help="arguments passed to the script (after --)")
    args = parser.parse_args()
    script = Path(args.script).resolve()
    with tempfile.TemporaryDirectory(prefix="ttbpipe_rev_") as tmp:
        old = Path(tmp)
        archive = subprocess.run(["git", "-C", str(ROOT), "archive", args.rev],
                                 check=True, capture_output=True).stdout
        subprocess.run(["tar", "-x", "-C", str(old)], input=archive, check=True)
        trees = {"old": (old / "src", old), "new": (ROOT / "src", ROOT)}
        for name, (src, cwd) in trees.items():   # warm-up: compile into each tree's cache
            run(script, src, cwd, args.extra)
        results: dict[str, list[dict]] = {"old": [], "new": []}
        for i in range(args.rounds):
            order = ("old", "new") if i % 2 == 0 else ("new", "old")
            for name in order:
                results[name].append(run(script, *trees[name], args.extra))
    rev = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", args.rev],
                         capture_output=True, text=True).stdout.strip()
    print(f"{script.name}: revision {rev} (old) vs working tree (new), {args.rounds} rounds, "
          f"load average now {os.getloadavg()[0]:.1f}")
    print(f"{'figure':44s} {'old median':>10s} {'new median':>10s} {'ratio':>6s} "
          f"{'old min':>10s} {'new min':>10s} {'ratio':>6s}  unit")
    for name in results["new"][0]:
        if name not in results["old"][0]:
            continue
        o = [r[name][0] for r in results["old"]]
        n = [r[name][0] for r in results["new"]]
        om, nm = statistics.median(o), statistics.median(n)
        print(f"{name:44s} {om:10.4g} {nm:10.4g} {nm / om if om else float('nan'):6.3f} "
              f"{min(o):10.4g} {min(n):10.4g} {min(n) / min(o) if min(o) else float('nan'):6.3f}"
              f"  {results['new'][0][name][1]}")
    if args.figure in results["new"][0]:
        print(f"{args.figure} per round, old: "
              + ", ".join(f"{r[args.figure][0]:.4g}" for r in results["old"]))
        print(f"{args.figure} per round, new: "
              + ", ".join(f"{r[args.figure][0]:.4g}" for r in results["new"]))


if __name__ == "__main__":
    main()
