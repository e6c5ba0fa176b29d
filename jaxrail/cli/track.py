"""``jaxrail track irregularities``: a realisation of an irregularity spectrum as a
measured-file CSV and its PSD."""

import sys

from ._options import check_seed, seed_option

MAX_IRREGULARITY_LENGTH_M = 1.0e6


def band(text):
    """(shortest, longest) wavelength [m] of ``--band LO:HI``; ValueError names the flag."""
    lo, sep, hi = (text or "").partition(":")
    try:
        return float(lo), float(hi)
    except ValueError:
        raise ValueError(f"--band must be LO:HI wavelengths in m, e.g. 3:150, got "
                         f"{text!r}") from None


def track_command(args):
    from ..track.measured import write_irregularity
    from ..track.spectra import realisation, spectrum

    spec = spectrum(args.spectrum)
    if not 0.0 < args.length <= MAX_IRREGULARITY_LENGTH_M:  # also NaN
        raise ValueError(f"--length must be within (0, {MAX_IRREGULARITY_LENGTH_M:g}] m, got "
                         f"{args.length}")
    check_seed(args.seed)
    if not args.scale >= 0.0:
        raise ValueError(f"--scale must be >= 0, got {args.scale}")
    try:
        wavelengths = band(args.band)
        irregularity = realisation(spec, args.length, args.step, args.seed, wavelengths,
                                   args.scale)
    except ValueError as error:
        raise ValueError(f"--band/--step: {error}") from None
    comment = (f"jaxrail track irregularities: {spec.name}, seed {args.seed}, band "
               f"{wavelengths[0]:g}-{wavelengths[1]:g} m, step {args.step:g} m, scale "
               f"{args.scale:g}")
    if args.csv:
        write_irregularity(args.csv, irregularity, comment)
        print(f"wrote {len(irregularity.values)} samples to {args.csv}", file=sys.stderr)
    if args.plot:
        from ..plots.track import plot_irregularity_psd

        plot_irregularity_psd(irregularity, spec, wavelengths, args.plot,
                              title=f"{spec.name}, seed {args.seed}, {args.length:g} m")
        print(f"wrote {args.plot}", file=sys.stderr)
    if not args.csv and not args.plot:
        from ..track.measured import COLUMNS, irregularity_table

        distance, millimetres = irregularity_table(irregularity)
        print(",".join(COLUMNS))
        for x, row in zip(distance, millimetres):
            print(",".join(f"{v:.6f}" for v in (x, *row)))
    return 0


def add_parser(commands):
    track = commands.add_parser("track", help="track irregularities: write a realisation")
    track_commands = track.add_subparsers(dest="track_command", required=True)
    irregular = track_commands.add_parser(
        "irregularities", help="a realisation of an irregularity spectrum as a measured-file "
                               "CSV (mm) and its PSD")
    irregular.add_argument("--spectrum", required=True,
                           help="german-low, german-high, fra-1 ... fra-6")
    irregular.add_argument("--length", type=float, required=True, help="track length [m]")
    irregular.add_argument("--step", type=float, default=0.25, help="sample spacing [m]")
    seed_option(irregular)
    irregular.add_argument("--band", default="3:150",
                           help="wavelengths LO:HI [m] (default 3:150)")
    irregular.add_argument("--scale", type=float, default=1.0, help="factor on every channel")
    irregular.add_argument("--csv", help="write the realisation here (format: docs/track.md)")
    irregular.add_argument("--plot", help="write a PNG of its PSD against the spectrum")
    irregular.set_defaults(run=track_command)
