"""Two simulation settings on a study's own samples: loop time and every result, side by side.

    NUMBA_NUM_THREADS=1 python benchmarks/study_variants.py ROOT [--configfile config/case3.yaml]
        [--scenario mc] [--base track_window_m=null] [--variant track_window_m=20]
        [--samples 8] [--first 1]

ROOT: a clone in which `snakemake --cores 2 --configfile config/case3.yaml` has written at least
the Monte Carlo design, the pooled population (or the PSD tables) and the span frequencies (as
for benchmarks/study_sample_stages.py), or, for a fields scenario of paper case 2 (``--configfile
config/case2.yaml --scenario C1``; C1 .. C4, C4_mc), that scenario's design and the span
frequencies. Runs the design's samples ``first .. first + samples - 1`` through
`ttbpipe.study.samples.run_sample`, as a batch does, with the configuration's ``simulation:``
settings changed by ``--base`` (the reference) and by ``--variant`` (each ``KEY=VALUE``,
repeatable, the value read as YAML: ``null`` removes the key), the two alternating sample by
sample in one process. The defaults compare the whole track with the moving window of 20 m
(docs/performance.md, "Moving window over the approach track"); ``--variant time_step_s=1.25e-4``
compares two time steps. Prints

* the CPU time of the time loops per sample and per step (median over the samples, each
  variant) and their ratios;
* for every column of the extremes row (the raw indices and every assessed standard's value),
  the largest difference over the samples relative to the reference's value, and the same
  difference relative to the column's spread over the samples (its standard deviation: what a
  study estimates), the largest first;
* for every history channel the study keeps (``simulation.history``), the largest difference
  relative to the channel's peak over the run, with the output rows where it happens, and the
  largest difference of the samples' standard-deviation curve relative to its peak.
"""

from __future__ import annotations

import argparse
import copy
import functools
import os
import time
from pathlib import Path

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import yaml  # noqa: E402
from _study_samples import study_sample_inputs  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("root", type=Path)
    parser.add_argument("--configfile", default="config/case3.yaml")
    parser.add_argument("--scenario", default="mc",
                        help="the design's scenario (results/<case>/study/design/<scenario>.parquet)")
    parser.add_argument("--base", action="append", metavar="KEY=VALUE",
                        help="simulation setting of the reference (default: track_window_m=null)")
    parser.add_argument("--variant", action="append", metavar="KEY=VALUE",
                        help="simulation setting of the variant (default: track_window_m=20)")
    parser.add_argument("--samples", type=int, default=8)
    parser.add_argument("--first", type=int, default=1,
                        help="first design row (0 pays the population's and the cache's loading)")
    args = parser.parse_args()

    import ttbpipe.simulation.coupled as coupled
    from ttbpipe.study import samples

    loop_cpu: list[float] = []
    steps: list[int] = []
    integrate = coupled.integrate

    @functools.wraps(integrate)
    def timed_integrate(setup, *a, **k):
        start = time.process_time()
        try:
            return integrate(setup, *a, **k)
        finally:
            loop_cpu.append(time.process_time() - start)
            steps.append(int(setup.n_steps))

    coupled.integrate = timed_integrate

    _, design_rows, kwargs = study_sample_inputs(args.root, args.configfile, args.scenario)
    variants = {}
    for settings in (args.base or ["track_window_m=null"], args.variant or ["track_window_m=20"]):
        sample_kwargs = copy.deepcopy(kwargs)
        for setting in settings:
            key, _, value = setting.partition("=")
            if not key or not _:
                parser.error(f"{setting!r}: give KEY=VALUE")
            value = yaml.safe_load(value)
            if value is None:
                sample_kwargs["sim"].pop(key, None)
            else:
                sample_kwargs["sim"][key] = value
        variants[" ".join(settings)] = sample_kwargs
    if len(variants) != 2:
        parser.error("--base and --variant give the same settings")

    rows = design_rows[args.first:args.first + args.samples]
    extremes: dict[str, list[dict]] = {name: [] for name in variants}
    histories: dict[str, list] = {name: [] for name in variants}
    per_step: dict[str, list[float]] = {name: [] for name in variants}
    per_sample: dict[str, list[float]] = {name: [] for name in variants}
    n_steps: dict[str, int] = {}
    for row in rows:
        for name, sample_kwargs in variants.items():
            row_extremes, history = samples.run_sample(row, **sample_kwargs)
            per_step[name].append(loop_cpu[-1] / steps[-1])
            per_sample[name].append(loop_cpu[-1])
            n_steps[name] = steps[-1]
            extremes[name].append(row_extremes)
            histories[name].append(history)
    names = list(variants)
    base, other = names
    print(f"{args.root / args.configfile}: {len(rows)} samples of scenario {args.scenario} (design rows "
          f"{args.first}-{args.first + len(rows) - 1})")
    for label, name in (("reference", base), ("variant", other)):
        median = float(np.median(per_step[name]))
        ratio = median / float(np.median(per_step[base]))
        sample = float(np.median(per_sample[name]))
        sample_ratio = sample / float(np.median(per_sample[base]))
        print(f"{label:9s} {name}: {n_steps[name]} steps; loop CPU {sample:.3f} s per sample "
              f"(ratio {sample_ratio:.3f}), {1e6 * median:7.2f} us per step (min "
              f"{1e6 * min(per_step[name]):7.2f}, ratio {ratio:.3f})")
        print(f"FIGURE study_variants_{label}_cpu_s_per_sample = {sample:.3f} s")

    columns = [c for c, v in extremes[base][0].items()
               if isinstance(v, (int, float)) and not isinstance(v, bool)
               and c not in ("sample_index", "weight")]
    rows_out = []
    for column in columns:
        a = np.array([e[column] for e in extremes[base]], dtype=float)
        b = np.array([e[column] for e in extremes[other]], dtype=float)
        diff = np.abs(b - a)
        scale = np.where(a != 0.0, np.abs(a), np.nan)
        relative = float(np.nanmax(diff / scale)) if np.isfinite(scale).any() else 0.0
        spread = float(np.std(a, ddof=1)) if len(a) > 1 else 0.0
        of_spread = float(diff.max() / spread) if spread > 0 else (0.0 if diff.max() == 0 else np.inf)
        rows_out.append((relative, of_spread, column))
    rows_out.sort(key=lambda r: -r[0] if np.isfinite(r[0]) else 0.0)
    print(f"\nextremes: {len(columns)} columns; largest |difference| over the samples, relative to "
          "the reference's value and to the column's standard deviation over the samples")
    for relative, of_spread, column in rows_out[:15]:
        print(f"  {column:48s} {relative:9.2e} of the value {of_spread:9.2e} of the std")
    print(f"  ... all {len(columns)} columns: at most {max(r[0] for r in rows_out):.2e} of the "
          f"value, {max(r[1] for r in rows_out):.2e} of the std")
    print(f"FIGURE study_variants_extremes_max_relative = {max(r[0] for r in rows_out):.3e}")

    print("\nhistories: largest |difference| relative to the channel's peak over the run "
          "(output row of the largest), and of the samples' std curve relative to its peak")
    channels = [c for c in histories[base][0].columns
                if c not in ("sample_index", "scenario", "weight", "position_m")]
    n_rows = len(histories[base][0])
    for channel in channels:
        a = np.stack([h[channel].to_numpy(float) for h in histories[base]])
        b = np.stack([h[channel].to_numpy(float) for h in histories[other]])
        peak = np.abs(a).max(axis=1, keepdims=True)
        relative = np.abs(b - a) / np.where(peak > 0, peak, 1.0)
        worst = np.unravel_index(np.argmax(relative), relative.shape)
        inner = relative[:, :max(n_rows - 40, 1)].max()
        std_a, std_b = a.std(axis=0, ddof=1), b.std(axis=0, ddof=1)
        std_rel = float(np.abs(std_b - std_a).max() / std_a.max()) if std_a.max() > 0 else 0.0
        print(f"  {channel:32s} {relative.max():9.2e} (row {worst[1]} of {n_rows}); "
              f"without the last 40 rows {inner:9.2e}; std curve {std_rel:9.2e}")


if __name__ == "__main__":
    main()
