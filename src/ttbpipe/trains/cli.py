"""``ttbpipe trains --list`` and ``ttbpipe trains NAME --out AXLES.csv``.

``--list`` prints the library (name, number of axles, length first to last axle, total static
load and mass, source). ``NAME --out`` writes the train's axles as CSV: ``axle`` (1-based, in
running order), ``position_m`` (behind the first axle), ``axle_load_kN``; without ``--out`` the
table is printed. Exit status 1 with the valid names on stderr for an unknown name.
"""

from __future__ import annotations

import argparse
import logging
import sys

log = logging.getLogger(__name__)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("name", nargs="?", help="train name, e.g. HSLM-A1 (see --list)")
    parser.add_argument("--list", action="store_true", help="list the trains of the library")
    parser.add_argument("--out", help="CSV file of the train's axles")


def run(args: argparse.Namespace) -> int:
    from .library import axle_table, get_train, library_table

    if args.list:
        table = library_table()
        print(f"{'name':12s} {'axles':>5s} {'length_m':>9s} {'load_kN':>8s} {'mass_t':>7s}  source")
        for r in table.itertuples():
            print(f"{r.name:12s} {r.n_axles:5d} {r.length_m:9.3f} {r.total_load_kN:8.0f} "
                  f"{r.mass_t:7.1f}  {r.source}")
        return 0
    if not args.name:
        print("ttbpipe trains: give a train NAME or --list", file=sys.stderr)
        return 2
    try:
        train = get_train(args.name)
    except ValueError as err:
        print(f"ttbpipe trains: {err}", file=sys.stderr)
        return 1
    table = axle_table(train)
    if args.out:
        table.to_csv(args.out, index=False, float_format="%.4f")
        log.info("%s: %d axles, %.3f m, %.0f kN -> %s", train.name, train.n_axles,
                 train.length_m, train.total_load_N / 1e3, args.out)
    else:
        print(table.to_string(index=False))
    return 0
