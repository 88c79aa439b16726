"""Print the TIPM must-show figures (docs/tipm.md) on the synthetic 36-campaign series.

    python benchmarks/tipm_validation.py                    # generate the data in a temp folder
    python benchmarks/tipm_validation.py --psd-dir results/psd   # use the workflow's PSD tables

Prints, per channel: the selection's max relative error of the per-frequency PSD mean and std
and the KS p-value of the section RMS for the population of every campaign with >= 20 sections;
the distribution-fit summary of the last campaign's population; the hold-out forecast coverage
(fit on 1-24, forecast 25-36) for several partition settings; and timings.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd


def generate(folder: Path, length_km: float, campaigns: int) -> list[Path]:
    from ttbpipe.inspection import check_campaign
    from ttbpipe.inspection.synthetic import campaign_dates, write_synthetic_campaigns
    from ttbpipe.io import write_table
    from ttbpipe.irregularity.psd import estimate_campaign_psd

    dates = campaign_dates("2023-01-15", campaigns, 1)
    write_synthetic_campaigns(folder / "raw", dates=dates, length_km=length_km, seed=1)
    out = []
    for d in dates:
        clean, _ = check_campaign(folder / "raw" / f"{d}.parquet")
        path = folder / "psd" / f"{d}.parquet"
        path.parent.mkdir(parents=True, exist_ok=True)
        write_table(estimate_campaign_psd(clean, {"section_length_m": 1000.0,
                                                  "segment_length_m": 1000.0}), path)
        out.append(path)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--psd-dir", default=None)
    parser.add_argument("--length-km", type=float, default=5.0)
    parser.add_argument("--holdout", type=int, default=12)
    args = parser.parse_args()
    from ttbpipe.tipm import PSDPopulation, TIPMSelector, selection_metrics
    from ttbpipe.tipm.distribution import fit_ordinate_distributions, summarize_fits
    from ttbpipe.tipm.stages import load_population, validation_stage

    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        paths = (sorted(Path(args.psd_dir).glob("*.parquet")) if args.psd_dir
                 else generate(Path(tmp), args.length_km, 36))
        print(f"data: {len(paths)} campaigns ({time.perf_counter() - t0:.1f} s)")
        pops = load_population(paths, (2.0, 200.0))
        rows = []
        t0 = time.perf_counter()
        for t in range(len(pops)):
            population = PSDPopulation.concat(pops[:t + 1])
            if population.n_sections < 20:
                continue
            for method in ("copula", "sections"):
                m = selection_metrics(population, TIPMSelector(method=method).select(population))
                m.insert(0, "campaign", t + 1)
                m.insert(1, "method", method)
                rows.append(m)
        print(f"selection of every campaign, both methods: {time.perf_counter() - t0:.1f} s")
        metrics = pd.concat(rows)
        with pd.option_context("display.width", 200):
            last = metrics[metrics["campaign"] == len(pops)]
            print("\nlast campaign (population = all campaigns):\n", last.round(4).to_string(index=False))
            worst = metrics.groupby(["method", "channel"]).agg(
                max_err_mean=("max_rel_error_mean", "max"), max_err_std=("max_rel_error_std", "max"),
                min_ks_p=("rms_ks_pvalue", "min"), n_campaigns=("campaign", "size"))
            print("\nworst over campaigns with >= 20 sections:\n", worst.round(4).to_string())
            t0 = time.perf_counter()
            fits = fit_ordinate_distributions(PSDPopulation.concat(pops))
            print(f"\ndistribution fits ({time.perf_counter() - t0:.1f} s):\n",
                  summarize_fits(fits).round(3).to_string(index=False))
            for z, scale in ((5, "log"), (3, "log"), (8, "log"), (5, "linear"), (5, "quantile")):
                t0 = time.perf_counter()
                cfg = {"evolution": {"n_partitions": z, "partition_scale": scale},
                       "validation": {"holdout_campaigns": args.holdout}}
                coverage, _, summary = validation_stage(paths, cfg, {"wavelength_band_m": [2.0, 200.0]}, 1)
                print(f"\ncoverage Z={z} {scale} ({time.perf_counter() - t0:.1f} s), nominal "
                      f"{summary['nominal_coverage']:.2f}:")
                print(coverage.groupby("channel", sort=False)[["coverage_mc", "coverage_fixed_p",
                                                               "below_mc", "above_mc"]].mean().round(3).to_string())
                if (z, scale) == (5, "log"):
                    print(coverage.pivot(index="horizon_months", columns="channel",
                                         values="coverage_mc").round(3).to_string())


if __name__ == "__main__":
    main()
