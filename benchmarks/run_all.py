"""Run every ``benchmarks/bench_*.py`` script repeatedly and write ``benchmarks/results.md``.

    python benchmarks/run_all.py [--repeat 3] [--only reference_case tipm] [--out benchmarks/results.md]
        [--baseline REV | --no-baseline]

Each script runs in a subprocess pinned to one thread (NUMBA_NUM_THREADS=1,
OPENBLAS_NUM_THREADS=1, OMP_NUM_THREADS=1, MKL_NUM_THREADS=1) ``--repeat`` times. Convention:
a script prints its machine-readable figures as lines ``FIGURE <name> = <value> <unit>`` next to
its human-readable output; this runner collects them, takes the median over the runs and writes
a Markdown table (figure, median, unit, runs, min-max) with the machine described (CPU model from
/proc/cpuinfo, cores, memory, Python/numpy/numba versions, load average at the start and end).
A script that fails is reported in the table's notes with its exit code and the last line of its
error output; the others still run. Timings only: nothing is asserted (docs/dev/contributing.md).

Side by side with a baseline: the scripts of :data:`BASELINE_SCRIPTS` (the reference case and a
study of a few hundred samples through Snakemake) also run on the pinned revision
:data:`BASELINE_REVISION` (``git archive`` into a scratch folder, its package first on
``PYTHONPATH``; ``compare_revisions.py``), old and new alternating in the same run, ``--repeat``
rounds each after one warm-up; the table gives both medians and their ratio new/old.
"""

from __future__ import annotations

import argparse
import datetime as _dt
import os
import platform
import re
import statistics
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
FIGURE_RE = re.compile(r"^FIGURE\s+(?P<name>\S+)\s*=\s*(?P<value>[-+0-9.eEinfa]+)\s*(?P<unit>.*)$")
THREAD_ENV = {"NUMBA_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1",
              "MKL_NUM_THREADS": "1"}
#: The code the speed targets (docs/performance.md) are measured against: main on 2026-12-01
#: before the history decimator, when the targets were set.
BASELINE_REVISION = "8caed1b"
#: Scripts also timed on the baseline revision, side by side.
BASELINE_SCRIPTS = ("bench_reference_case.py", "bench_study_workflow.py")


def parse_figures(text: str) -> list[tuple[str, float, str]]:
    """(name, value, unit) of every ``FIGURE name = value unit`` line of a script's output."""
    out = []
    for line in text.splitlines():
        m = FIGURE_RE.match(line.strip())
        if m:
            try:
                out.append((m["name"], float(m["value"]), m["unit"].strip()))
            except ValueError:
                continue
    return out


def machine_description() -> dict[str, str]:
    """CPU model, cores, memory, Python and library versions, load average."""
    cpu = "unknown"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.lower().startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        cpu = platform.processor() or "unknown"
    mem = "unknown"
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemTotal"):
                mem = f"{int(line.split()[1]) / 1024 ** 2:.1f} GiB"
                break
    except OSError:
        pass
    versions = {}
    for mod in ("numpy", "numba", "scipy", "pandas"):
        try:
            versions[mod] = __import__(mod).__version__
        except Exception:  # noqa: BLE001 - report what is there
            versions[mod] = "not installed"
    return {"cpu": cpu, "cores": str(os.cpu_count()), "memory": mem,
            "python": platform.python_version(), "platform": platform.platform(),
            **versions}


def run_script(path: Path, timeout: float) -> tuple[int, str, str, float]:
    env = dict(os.environ, **THREAD_ENV)
    t0 = time.perf_counter()
    try:
        proc = subprocess.run([sys.executable, str(path)], capture_output=True, text=True,
                              env=env, timeout=timeout, cwd=HERE.parent)
        code, out, err = proc.returncode, proc.stdout, proc.stderr
    except subprocess.TimeoutExpired as exc:
        code, out, err = -1, exc.stdout or "", f"timeout after {timeout:.0f} s"
        out = out.decode() if isinstance(out, bytes) else out
    return code, out, err, time.perf_counter() - t0


def _side_by_side(script: Path, revision: str, rounds: int) -> tuple[str, dict]:
    """(short hash, {"old": [figures per round], "new": [...]}) of ``script`` on ``revision``
    and on this tree, alternating (compare_revisions.py)."""
    import tempfile

    from compare_revisions import alternate, export_revision

    with tempfile.TemporaryDirectory(prefix="ttbpipe_baseline_") as tmp:
        short = export_revision(revision, Path(tmp))
        results = alternate(script, Path(tmp), rounds, [],
                            progress=lambda text: print(f"{text} (baseline {short})", flush=True))
    return short, results


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3, help="runs per script (median reported)")
    parser.add_argument("--only", nargs="*", default=None,
                        help="script names without bench_ and .py (default: every bench_*.py)")
    parser.add_argument("--out", type=Path, default=HERE / "results.md")
    parser.add_argument("--timeout", type=float, default=1800.0, help="per run, seconds")
    parser.add_argument("--baseline", default=BASELINE_REVISION,
                        help="git revision timed side by side with this tree (BASELINE_SCRIPTS)")
    parser.add_argument("--no-baseline", action="store_true", help="no side-by-side timing")
    args = parser.parse_args(argv)
    if args.repeat < 1:
        parser.error("--repeat must be >= 1")
    scripts = sorted(HERE.glob("bench_*.py"))
    if args.only:
        wanted = {f"bench_{n.removeprefix('bench_').removesuffix('.py')}.py" for n in args.only}
        missing = wanted - {s.name for s in scripts}
        if missing:
            parser.error(f"no such benchmark(s): {sorted(missing)}")
        scripts = [s for s in scripts if s.name in wanted]
    machine = machine_description()
    load_start = os.getloadavg()
    started = _dt.datetime.now(_dt.timezone.utc)
    rows: list[tuple[str, str, list[float], str]] = []
    notes: list[str] = []
    compared: list[tuple[str, list[tuple]]] = []
    baseline = ""
    for script in scripts:
        values: dict[str, list[float]] = {}
        units: dict[str, str] = {}
        if script.name in BASELINE_SCRIPTS and not args.no_baseline:
            try:
                baseline, results = _side_by_side(script, args.baseline, args.repeat)
            except (SystemExit, subprocess.CalledProcessError) as exc:
                last = (str(exc).strip().splitlines() or ["(no message)"])[-1]
                notes.append(f"{script.name} against {args.baseline}: {last}")
                continue
            from compare_revisions import side_by_side

            compared.append((script.name, side_by_side(results)))
            for figures in results["new"]:
                for name, (value, unit) in figures.items():
                    values.setdefault(name, []).append(value)
                    units[name] = unit
            for name, vals in values.items():
                rows.append((script.name, name, vals, units[name]))
            continue
        for run in range(args.repeat):
            code, out, err, wall = run_script(script, args.timeout)
            print(f"{script.name} run {run + 1}/{args.repeat}: exit {code}, {wall:.1f} s",
                  flush=True)
            if code != 0:
                last = (err.strip().splitlines() or ["(no error output)"])[-1]
                notes.append(f"{script.name} run {run + 1}: exit {code}: {last}")
                continue
            figures = parse_figures(out)
            if not figures:
                notes.append(f"{script.name} run {run + 1}: printed no FIGURE line")
            for name, value, unit in figures:
                values.setdefault(name, []).append(value)
                units[name] = unit
        for name, vals in values.items():
            rows.append((script.name, name, vals, units[name]))
    load_end = os.getloadavg()
    lines = [
        "# Benchmark results",
        "",
        f"Written by `python benchmarks/run_all.py --repeat {args.repeat}` on "
        f"{started:%Y-%m-%d %H:%M} UTC. Each figure is the median of the runs of its script "
        "(subprocess, one thread: " + ", ".join(f"{k}={v}" for k, v in THREAD_ENV.items())
        + "); min-max over the runs. Wall times depend on the machine's load (below).",
        "",
        "## Machine",
        "",
        f"- CPU: {machine['cpu']}; {machine['cores']} cores visible; memory {machine['memory']}",
        f"- Python {machine['python']}, numpy {machine['numpy']}, numba {machine['numba']}, "
        f"scipy {machine['scipy']}, pandas {machine['pandas']}; {machine['platform']}",
        f"- load average (1, 5, 15 min) at start {load_start[0]:.2f}, {load_start[1]:.2f}, "
        f"{load_start[2]:.2f}; at end {load_end[0]:.2f}, {load_end[1]:.2f}, {load_end[2]:.2f}",
        "",
        "## Figures",
        "",
        "| script | figure | median | unit | runs | min-max |",
        "|---|---|---|---|---|---|",
    ]
    for script, name, vals, unit in rows:
        lines.append(f"| {script} | {name} | {statistics.median(vals):.4g} | {unit} | {len(vals)} "
                     f"| {min(vals):.4g} - {max(vals):.4g} |")
    if compared:
        lines += ["", f"## Side by side with {baseline} (the baseline)", "",
                  f"Old ({baseline}) and new (this tree) alternating in this run, {args.repeat} "
                  "round(s) each after a warm-up; ratio new / old (below 1: faster).", "",
                  "| script | figure | old median | new median | ratio | old min | new min | unit |",
                  "|---|---|---|---|---|---|---|---|"]
        for script_name, table in compared:
            for name, om, nm, ratio, omin, nmin, _, unit in table:
                lines.append(f"| {script_name} | {name} | {om:.4g} | {nm:.4g} | {ratio:.3f} | "
                             f"{omin:.4g} | {nmin:.4g} | {unit} |")
    if notes:
        lines += ["", "## Notes", ""] + [f"- {n}" for n in notes]
    text = "\n".join(lines) + "\n"
    args.out.parent.mkdir(parents=True, exist_ok=True)
    tmp = args.out.with_suffix(args.out.suffix + ".tmp")
    tmp.write_text(text)
    tmp.replace(args.out)   # atomic: never a partial table
    print(text)
    return 1 if notes and not rows else 0


if __name__ == "__main__":
    raise SystemExit(main())
