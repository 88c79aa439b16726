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


def export_revision(rev: str, dest: Path) -> str:
    """``git archive`` of ``rev`` unpacked into ``dest``; returns the short hash."""
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", rev],
                             check=True, capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(dest)], input=archive, check=True)
    return subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", rev],
                          capture_output=True, text=True, check=True).stdout.strip()


def alternate(script: Path, old: Path, rounds: int, extra: list[str],
              progress=None) -> dict[str, list[dict]]:
    """The script's figures on the exported tree ``old`` and on this tree, ``rounds`` times
    each, old/new and new/old alternately, after one warm-up run each (numba compiles into each
    tree's own cache)."""
    trees = {"old": (old / "src", old), "new": (ROOT / "src", ROOT)}
    for name, (src, cwd) in trees.items():
        run(script, src, cwd, extra)
    results: dict[str, list[dict]] = {"old": [], "new": []}
    for i in range(rounds):
        for name in (("old", "new") if i % 2 == 0 else ("new", "old")):
            results[name].append(run(script, *trees[name], extra))
            if progress:
                progress(f"{script.name} round {i + 1}/{rounds} {name}")
    return results


def side_by_side(results: dict[str, list[dict]]) -> list[tuple]:
    """(figure, old median, new median, ratio, old min, new min, ratio, unit) of every figure
    both sides printed."""
    rows = []
    for name in results["new"][0]:
        if name not in results["old"][0]:
            continue
        o = [r[name][0] for r in results["old"]]
        n = [r[name][0] for r in results["new"]]
        om, nm = statistics.median(o), statistics.median(n)
        rows.append((name, om, nm, nm / om if om else float("nan"), min(o), min(n),
                     min(n) / min(o) if min(o) else float("nan"), results["new"][0][name][1]))
    return rows


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
        rev = export_revision(args.rev, Path(tmp))
        results = alternate(script, Path(tmp), args.rounds, args.extra)
    print(f"{script.name}: revision {rev} (old) vs working tree (new), {args.rounds} rounds, "
          f"load average now {os.getloadavg()[0]:.1f}")
    print(f"{'figure':44s} {'old median':>10s} {'new median':>10s} {'ratio':>6s} "
          f"{'old min':>10s} {'new min':>10s} {'ratio':>6s}  unit")
    for name, om, nm, ratio, omin, nmin, ratio_min, unit in side_by_side(results):
        print(f"{name:44s} {om:10.4g} {nm:10.4g} {ratio:6.3f} {omin:10.4g} {nmin:10.4g} "
              f"{ratio_min:6.3f}  {unit}")
    if args.figure in results["new"][0]:
        print(f"{args.figure} per round, old: "
              + ", ".join(f"{r[args.figure][0]:.4g}" for r in results["old"]))
        print(f"{args.figure} per round, new: "
              + ", ".join(f"{r[args.figure][0]:.4g}" for r in results["new"]))


if __name__ == "__main__":
    main()
