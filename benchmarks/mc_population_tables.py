"""A Monte Carlo batch's population: the campaigns' PSD tables against the pooled table.

    python benchmarks/mc_population_tables.py ROOT [--rounds 3] [--baseline-src DIR]

ROOT: a clone in which `snakemake --cores 2 --configfile config/case3.yaml` has written the PSD
tables (results/case3/psd/*.parquet: paper case 3's 36 campaigns of 85 sections). Pools them
once (`ttbpipe.tipm.population.write_pooled_population`, as the workflow's rule
study_mc_population does), then, in fresh processes, the two ways alternating, times what a
batch does before its first run: the imports of `ttbpipe.study.samples` and the first sample's
profile (`mc_profile`), from the 36 tables (``psd_paths``) or from the pooled table
(``pooled_path``). Prints each process's wall time and checks that both give the same profile.
The child synthesises the profiles of eight sections (``SECTIONS``), as a batch's first
samples do. ``--baseline-src DIR``: also the pooled table of the code of another revision (its
``src`` folder, e.g. from ``git archive``), pooled and read by that code, in the same rounds:
side by side, old and new.
"""

from __future__ import annotations

import argparse
import glob
import json
import os
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
digest = hashlib.sha256()
for section in json.loads(sys.argv[2]):
    profile = mc_profile(population, 12345, section, sample_index=section + 3)
    digest.update(profile.to_numpy().tobytes())
print(time.perf_counter() - start, digest.hexdigest()[:16])
"""

_POOL = """
import sys, json
from ttbpipe.tipm.population import write_pooled_population
write_pooled_population(json.loads(sys.argv[1]), json.loads(sys.argv[2]), sys.argv[3])
"""

#: Population sections whose profiles the child synthesises (the first, the last, and some
#: neighbours and strangers, as a batch draws them).
SECTIONS = [17, 0, 3059, 1500, 16, 15, 31, 32]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("root", type=Path)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--baseline-src", type=Path, default=None,
                        help="the src folder of another revision: its pooled-table reading too")
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
        sections = [s for s in SECTIONS if s < population.n_sections]
        variants = {"36 campaign tables": ({**settings, "psd_paths": paths}, None),
                    "pooled table": ({**settings, "pooled_path": str(pooled)}, None)}
        if args.baseline_src is not None:
            # the baseline's own pooled table (its row groups), pooled by its code
            src = str(args.baseline_src.resolve())
            old_pooled = Path(folder) / "mc_population_baseline.parquet"
            subprocess.run([sys.executable, "-c", _POOL, json.dumps(paths),
                            json.dumps(settings["wavelength_band_m"]), str(old_pooled)],
                           check=True, env={**os.environ, "PYTHONPATH": src})
            print(f"the baseline's pooled table: {old_pooled.stat().st_size / 1e6:.1f} MB")
            variants["pooled table, baseline"] = ({**settings, "pooled_path": str(old_pooled)},
                                                  src)
        seen: dict[str, set[str]] = {name: set() for name in variants}
        print(f"imports and the profiles of {len(sections)} sections, wall s per fresh process:")
        for round_ in range(args.rounds):
            for name, (population_settings, src) in variants.items():
                env = dict(os.environ)
                if src is not None:
                    env["PYTHONPATH"] = src + os.pathsep + env.get("PYTHONPATH", "")
                out = subprocess.run([sys.executable, "-c", _CHILD,
                                      json.dumps(population_settings), json.dumps(sections)],
                                     check=True, capture_output=True, text=True,
                                     env=env).stdout.split()
                seen[name].add(out[1])
                print(f"  round {round_ + 1}  {name:24s} {float(out[0]):6.2f} s")
    digests = set.union(*seen.values())
    print("same profiles from all:", "yes" if len(digests) == 1 else f"NO {seen}")


if __name__ == "__main__":
    main()
