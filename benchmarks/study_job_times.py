"""Where a study's wall time went, per rule, from the log of a finished Snakemake run.

    snakemake --cores 2 > run.log 2>&1;  python benchmarks/study_job_times.py run.log [--root .]

Pairs each job's start (the time stamp before ``rule X:`` / ``localrule X:``) with its
``Finished jobid: N`` stamp (one-second resolution) and prints, per rule, the number of jobs and
the sum of their wall times, largest first, with the run's wall time. For the ``simulate_batch``
jobs it also reads each batch's own log (``--root``: the folder the study ran in) and splits the
job's wall time into the part the batch logged (first to last log line: field set-up, runs,
assessment, writing) and the part before and after it (interpreter start, imports, Snakemake's
script preamble), and sums the coupled runs' own wall times ("coupled run done: X s wall"):
the rest is the workflow's overhead around the runs. When the log also holds the report of
``/usr/bin/time -v`` (``/usr/bin/time -v snakemake --cores 2 2> run.err``: its lines follow
Snakemake's own), it also prints that share of the run's CPU time (user + system of Snakemake and
every job), the measure of the workflow target in docs/performance.md. Timings only; compare runs
made side by side on the same machine.
"""

from __future__ import annotations

import argparse
import collections
import datetime
import re
from pathlib import Path

_STAMP = re.compile(r"^\[(\w{3} \w{3} +\d+ [\d:]+ \d{4})\]$")
_LOG_LINE = re.compile(r"^(\d{4}-\d{2}-\d{2} \d{2}:\d{2}:\d{2},\d{3}) ")


def jobs_of(log_text: str) -> list[dict]:
    """Every finished job of a Snakemake log: rule, start, end, its log file."""
    stamp, pending, started, ended = None, None, {}, {}
    for line in log_text.splitlines():
        if m := _STAMP.match(line):
            stamp = datetime.datetime.strptime(m.group(1), "%a %b %d %H:%M:%S %Y")
        elif m := re.match(r"^(?:local)?rule (\w+):$", line):
            pending = {"rule": m.group(1), "start": stamp, "log": None}
        elif pending and (m := re.match(r"^\s+log: (\S+)", line)):
            pending["log"] = m.group(1)
        elif pending and (m := re.match(r"^\s+jobid: (\d+)", line)):
            started[int(m.group(1))], pending = pending, None
        elif m := re.match(r"^Finished jobid: (\d+)", line):
            ended[int(m.group(1))] = stamp
    return [{**job, "end": ended[j]} for j, job in started.items() if j in ended]


def coupled_run_seconds(batch_log_text: str) -> float:
    """Sum of the coupled runs' own wall times a batch log reports ("coupled run done: X s")."""
    return sum(float(t) for t in re.findall(r"coupled run done: ([\d.]+) s wall", batch_log_text))


def cpu_seconds(log_text: str) -> float | None:
    """User plus system seconds of ``/usr/bin/time -v``'s report in the log, or None."""
    found = {m.group(1): float(m.group(2)) for m in re.finditer(
        r"^\s*(User|System) time \(seconds\): ([\d.]+)$", log_text, re.MULTILINE)}
    return found["User"] + found["System"] if len(found) == 2 else None


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("log", type=Path)
    parser.add_argument("--root", type=Path, default=Path("."))
    args = parser.parse_args()
    log_text = args.log.read_text()
    jobs = jobs_of(log_text)
    if not jobs:
        raise SystemExit(f"{args.log}: no finished job found (is it a Snakemake log?)")
    total, count = collections.defaultdict(float), collections.Counter()
    for job in jobs:
        total[job["rule"]] += (job["end"] - job["start"]).total_seconds()
        count[job["rule"]] += 1
    wall = (max(j["end"] for j in jobs) - min(j["start"] for j in jobs)).total_seconds()
    print(f"wall {wall:.0f} s, {len(jobs)} jobs, sum of job wall times {sum(total.values()):.0f} s")
    for rule in sorted(total, key=total.get, reverse=True):
        print(f"  {rule:24s} {count[rule]:4d} jobs {total[rule]:7.0f} s {total[rule] / count[rule]:6.1f} s/job")
    inside = outside = runs = 0.0
    n = 0
    for job in jobs:
        if job["rule"] != "simulate_batch" or not job["log"]:
            continue
        path = args.root / job["log"]
        if not path.is_file():
            continue
        text = path.read_text()
        stamps = [datetime.datetime.strptime(m.group(1), "%Y-%m-%d %H:%M:%S,%f")
                  for line in text.splitlines() if (m := _LOG_LINE.match(line))]
        runs += coupled_run_seconds(text)
        if stamps:
            logged = (stamps[-1] - stamps[0]).total_seconds()
            inside += logged
            outside += (job["end"] - job["start"]).total_seconds() - logged
            n += 1
    if n:
        print(f"simulate_batch: {n} jobs, {inside:.0f} s inside the batch's log, {outside:.0f} s "
              f"before and after it ({outside / n:.1f} s per job)")
        share = 1.0 - runs / sum(total.values())
        print(f"coupled runs (their time loops, as the batches logged them): {runs:.0f} s; "
              f"everything else {100 * share:.0f} % of the sum of job wall times")
        cpu = cpu_seconds(log_text)
        if cpu:
            print(f"CPU (user + system, /usr/bin/time): {cpu:.0f} s; everything but the coupled "
                  f"runs {100 * (1.0 - runs / cpu):.1f} % of it")


if __name__ == "__main__":
    main()
