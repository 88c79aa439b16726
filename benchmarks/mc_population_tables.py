"""A Monte Carlo batch's population: the campaigns' PSD tables against the pooled table.

    python benchmarks/mc_population_tables.py ROOT [--rounds 3]

ROOT: a clone in which `snakemake --cores 2 --configfile config/case3.yaml` has written the PSD
tables (results/case3/psd/*.parquet: paper case 3's 36 campaigns of 85 sections). Pools them
once (`ttbpipe.tipm.population.write_pooled_population`, as the workflow's rule
study_mc_population does), then, in fresh processes, the two ways alternating, times what a
batch does before its first run: the imports of `ttbpipe.study.samples` and the first sample's
profile (`mc_profile`), from the 36 tables (``psd_paths``) or from the pooled table
(``pooled_path``). Prints each process's wall time and checks that both give the same profile.
"""

from __future__ import annotations

import argparse
import glob
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import yaml
from snakemake.utils import update_config

_CHILD = """
import sys, time, hashlib, json
start = time.perf_counter()
from ttbpipe.study.samples import mc_profile
population = json.loads(sys.argv[1])
profile = mc_profile(population, 12345, 17, sample_index=3)
print(time.perf_counter() - start, hashlib.sha256(profile.to_numpy().tobytes()).hexdigest()[:16])
"""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("root", type=Path)
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()

    from ttbpipe.study.plan import mc_profile_settings
    from ttbpipe.tipm.population import write_pooled_population

    config = yaml.safe_load((args.root / "config/config.yaml").read_text())
    update_config(config, yaml.safe_load((args.root / "config/case3.yaml").read_text()))
    paths = sorted(glob.glob(str(args.root / "results/case3/psd/*.parquet")))
    if not paths:
        raise SystemExit(f"{args.root}/results/case3/psd has no PSD tables: run case 3 there first")
    settings = {**mc_profile_settings(config), "date": max(Path(p).stem for p in paths)}
    with tempfile.TemporaryDirectory() as folder:
        pooled = Path(folder) / "mc_population.parquet"
        start = time.perf_counter()
        population = write_pooled_population(paths, settings["wavelength_band_m"], pooled)
        print(f"pooled {len(paths)} tables, {population.n_sections} sections, into "
              f"{pooled.stat().st_size / 1e6:.1f} MB in {time.perf_counter() - start:.2f} s")
        variants = {"36 campaign tables": {**settings, "psd_paths": paths},
                    "pooled table": {**settings, "pooled_path": str(pooled)}}
        seen: dict[str, set[str]] = {name: set() for name in variants}
        print("imports and the first profile, wall s per fresh process:")
        for round_ in range(args.rounds):
            for name, population_settings in variants.items():
                out = subprocess.run([sys.executable, "-c", _CHILD,
                                      json.dumps(population_settings)],
                                     check=True, capture_output=True, text=True).stdout.split()
                seen[name].add(out[1])
                print(f"  round {round_ + 1}  {name:20s} {float(out[0]):6.2f} s")
    digests = set.union(*seen.values())
    print("same profile from both:", "yes" if len(digests) == 1 else f"NO {seen}")


if __name__ == "__main__":
    main()
