"""The ``jaxrail`` command line (a thin layer over the Python API)."""

import argparse
import os
import sys
from pathlib import Path

from . import (assess, identify, montecarlo, profiles, simulate, stability, track, vehicle,
               wear)


def build_parser():
    """The parser of every command; each command's module adds its own options and sets
    ``run``, the function that runs it."""
    parser = argparse.ArgumentParser(prog="jaxrail", description=__doc__)
    commands = parser.add_subparsers(dest="command", required=True)
    profiles.add_parsers(commands)  # profile, geometry
    simulate.add_simulate_parser(commands)
    identify.add_parser(commands)
    montecarlo.add_parser(commands)
    track.add_parser(commands)
    simulate.add_tables_parser(commands)
    stability.add_parser(commands)
    assess.add_parser(commands)
    vehicle.add_parser(commands)
    wear.add_parser(commands)
    return parser


EXIT_FILE_ERROR = 3
"""Exit status of a file that cannot be written or read (0: done, 1: a run stopped
early or a fit did not converge, 2: bad input)."""


def prepare_outputs(args):
    """Check every output path of the command before anything runs: the folder of each
    output file, and the figures folder, are made if missing and must be writable;
    raises OSError naming the flag."""
    options = vars(args)
    out = options.get("out")
    files = [("--out", path) for path in (out if isinstance(out, list) else [out])]
    files += [(f"--{name}", options.get(name)) for name in ("csv", "summary", "plot", "json")]
    targets = [(flag, Path(path), Path(path).parent) for flag, path in files if path]
    if options.get("plots"):  # a folder of figures
        targets.append(("--plots", Path(options["plots"]), Path(options["plots"])))
    for flag, path, folder in targets:
        if folder != path and path.is_dir():
            raise OSError(f"{flag} {path}: is a folder, not a file")
        try:
            folder.mkdir(parents=True, exist_ok=True)
        except OSError as error:
            raise OSError(f"{flag} {path}: cannot make the folder {folder}: "
                          f"{error.strerror or error}") from None
        if not os.access(folder, os.W_OK):
            raise OSError(f"{flag} {path}: the folder {folder} is not writable")


def main(argv=None):
    """Run the command of ``argv`` (default ``sys.argv[1:]``); returns its exit status."""
    from .._float64 import enable_float64
    from .._xla_alarms import hidden_xla_alarms

    enable_float64()
    args = build_parser().parse_args(argv)
    with hidden_xla_alarms():
        try:
            prepare_outputs(args)
            return args.run(args)
        except ValueError as error:
            print(f"jaxrail {args.command}: error: {error}", file=sys.stderr)
            return 2
        except OSError as error:
            print(f"jaxrail {args.command}: file error: {error}", file=sys.stderr)
            return EXIT_FILE_ERROR
