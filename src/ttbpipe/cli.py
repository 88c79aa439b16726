"""The ``ttbpipe`` command line.

Each subcommand lives in its own module, which provides ``add_arguments(parser)`` and
``run(args) -> int``. Modules are imported only when their subcommand runs, so that
``ttbpipe --help`` stays fast and each command loads only the dependencies it needs.
"""

from __future__ import annotations

import argparse
import importlib
import logging
import sys

from . import __version__
from .logs import setup_logging

# name -> (module, one-line help)
COMMANDS: dict[str, tuple[str, str]] = {
    "check-inspection": ("ttbpipe.inspection.cli_check",
                         "validate and clean one inspection campaign file; non-zero exit on failure"),
    "synth-inspections": ("ttbpipe.inspection.cli_synth",
                          "write a synthetic series of inspection campaigns"),
    "psd": ("ttbpipe.irregularity.cli_psd",
            "estimate per-section, per-channel PSDs of one inspection campaign"),
    "simulate": ("ttbpipe.simulation.cli",
                 "run one deterministic case from a YAML configuration"),
    "sample-fields": ("ttbpipe.fields.cli",
                      "draw random-field samples of track and bridge parameters"),
    "stats-report": ("ttbpipe.study.cli_report",
                     "the study's tables, figures and report pages from per-batch results"),
    "assess": ("ttbpipe.assessment.cli",
               "evaluate a simulate result as a standard prescribes (EN 14363, GB/T 5599, "
               "EN 1990 A2, EN 12299)"),
    "assess-monitors": ("ttbpipe.assessment.cli_monitors",
                        "add the monitors of the EN 1990 A2 deck checks to a case"),
    "trains": ("ttbpipe.trains.cli",
               "the train library (HSLM-A1..A10 of EN 1991-2): list it, write a train's axles"),
    "contact-geometry": ("ttbpipe.vehicle.cli_contact_geometry",
                         "wheel-rail contact geometry of real profiles vs lateral displacement, "
                         "EN 15302 equivalent conicity"),
}


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="ttbpipe",
        description="Probabilistic dynamic assessment of railway train-track-bridge systems.")
    parser.add_argument("--version", action="version", version=f"ttbpipe {__version__}")
    parser.add_argument("--log", default=None, help="also write the log to this file")
    parser.add_argument("-v", "--verbose", action="store_true", help="debug logging")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, (module_name, help_text) in COMMANDS.items():
        sub.add_parser(name, help=help_text, add_help=False)
    return parser


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    parser = build_parser()
    # Parse the global options and the command name; the command parses the rest itself.
    known, rest = parser.parse_known_args(argv)
    if known.command is None:
        parser.print_help()
        return 2
    setup_logging(known.log, logging.DEBUG if known.verbose else logging.INFO)
    module_name, help_text = COMMANDS[known.command]
    module = importlib.import_module(module_name)
    sub_parser = argparse.ArgumentParser(prog=f"ttbpipe {known.command}", description=help_text)
    module.add_arguments(sub_parser)
    args = sub_parser.parse_args(rest)
    return int(module.run(args) or 0)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
