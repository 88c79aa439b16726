"""Print the reference-case table of docs/assessment.md: raw against processed indices.

    python tools/assessment_reference_table.py [--case config/reference_case.yaml]
        [--speeds 300 510] [--out-dir results/assessment_reference]

Runs the case with the EN 1990 A2 deck-check monitors (``ttbpipe assess-monitors``) at each
speed (``ttbpipe simulate``; time step and everything else as in the case), assesses every run
with every profile (``ttbpipe.assessment.assess_result``) and prints one Markdown row per index:
governing location at the first speed, then raw, processed, limit and utilisation per speed.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import yaml

from ttbpipe.assessment import assess_result, profiles
from ttbpipe.cli import main as cli

UNITS = {"N": (1e-3, " kN"), "m": (1e3, " mm"), "m/s^2": (1.0, " m/s²"), "1": (1.0, "")}


def _fmt(value: float, unit: str) -> str:
    if value != value:   # NaN
        return "-"
    scale, text = UNITS.get(unit, (1.0, f" {unit}"))
    return f"{value * scale:.3g}{text}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", default="config/reference_case.yaml")
    parser.add_argument("--speeds", type=float, nargs="+", default=[300.0, 510.0])
    parser.add_argument("--out-dir", default="results/assessment_reference")
    args = parser.parse_args()
    out = Path(args.out_dir)
    out.mkdir(parents=True, exist_ok=True)
    deck = out / "case_deck.yaml"
    assert cli(["assess-monitors", args.case, "--out", str(deck)]) == 0
    tables = {}
    for speed in args.speeds:
        case = yaml.safe_load(deck.read_text())
        case.setdefault("simulation", {})["speed_kmh"] = speed
        path = out / f"case_{speed:g}.yaml"
        path.write_text(yaml.safe_dump(case, sort_keys=False))
        result = out / f"result_{speed:g}.parquet"
        assert cli(["simulate", str(path), "--out", str(result)]) == 0
        tables[speed] = {name: assess_result(result, name) for name in sorted(profiles())}
    first = args.speeds[0]
    head = ["profile", "index", f"governing at {first:g} km/h"]
    for s in args.speeds:
        head += [f"raw, {s:g}", f"processed, {s:g}", f"limit, {s:g}", f"util., {s:g}"]
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for name, df in tables[first].items():
        for k, row in df.iterrows():
            cells = [name, f"`{row['index']}`", str(row["location"])]
            for s in args.speeds:
                r = tables[s][name].iloc[k]
                cells += [_fmt(r["raw_value"], r["unit"]), _fmt(r["processed_value"], r["unit"]),
                          _fmt(r["limit"], r["unit"]),
                          "-" if r["utilisation"] != r["utilisation"] else f"{r['utilisation']:.3f}"]
            print("| " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
