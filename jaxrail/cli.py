"""The ``jaxrail`` command line (a thin layer over the Python API)."""

import argparse
import sys
from pathlib import Path

BUILTIN_WHEELS = ("s1002", "s1002-simplified")
BUILTIN_RAILS = ("uic60",)


def _load_profile(name, inclination):
    """A built-in profile by name, or a profile file (.prw/.prr/.csv/.txt)."""
    from . import profiles

    key = name.lower()
    if key == "s1002":
        return "wheel", profiles.s1002()
    if key == "s1002-simplified":
        return "wheel", profiles.simplified_s1002()
    if key == "uic60":
        return "rail", profiles.uic60(inclination)
    path = Path(name)
    if path.suffix.lower() in (".prw", ".prr") and path.exists():
        profile = profiles.read_profile(path)
        return ("wheel" if isinstance(profile, profiles.WheelProfile) else "rail"), profile
    if path.exists():
        raise ValueError(f"{name}: for a text profile file use --kind wheel|rail")
    known = ", ".join(BUILTIN_WHEELS + BUILTIN_RAILS)
    raise ValueError(f"unknown profile {name!r}: use one of {known} or a .prw/.prr/.csv file")


def _profile_command(args):
    from . import profiles
    from .plots.profiles import plot_wheel_on_rail

    if args.kind is not None:
        kind, profile = args.kind, profiles.read_profile(args.name, kind=args.kind)
    else:
        kind, profile = _load_profile(args.name, args.inclination)
    y_mm, z_mm = profiles.sample_profile(profile, n=args.points)
    label = getattr(profile, "name", args.name)
    if args.csv:
        header = (f"jaxrail profile {label} ({kind}); y_mm toward the field side"
                  f" ({'from the taping line, z radially outward' if kind == 'wheel' else 'z up'})")
        profiles.write_profile_csv(args.csv, y_mm, z_mm, header=header)
        print(f"wrote {len(y_mm)} points of {label} to {args.csv}")
    if args.plot:
        wheel = profile if kind == "wheel" else profiles.s1002()
        rail = profile if kind == "rail" else profiles.uic60(args.inclination)
        plot_wheel_on_rail(wheel, rail, args.plot, gauge=args.gauge * 1e-3)
        print(f"wrote {args.plot}")
    if not args.csv and not args.plot:
        for y, z in zip(y_mm, z_mm):
            print(f"{y:.6f},{z:.6f}")
    return 0


def build_parser():
    parser = argparse.ArgumentParser(prog="jaxrail", description=__doc__)
    commands = parser.add_subparsers(dest="command", required=True)

    profile = commands.add_parser("profile", help="write a wheel or rail profile (mm) and plot it")
    profile.add_argument("name", help="s1002, s1002-simplified, uic60, or a .prw/.prr/.csv file")
    profile.add_argument("--inclination", default="1:40", help="rail inclination: 1:40, 1:20, none")
    profile.add_argument("--kind", choices=("wheel", "rail"), help="kind of a text profile file")
    profile.add_argument("--gauge", type=float, default=1435.0, help="track gauge for the plot [mm]")
    profile.add_argument("--points", type=int, default=401, help="number of points written")
    profile.add_argument("--csv", help="write the points (y_mm,z_mm) to this CSV file")
    profile.add_argument("--plot", help="write a PNG of the wheel on the rail")
    profile.set_defaults(run=_profile_command)
    return parser


def main(argv=None):
    from ._float64 import enable_float64

    enable_float64()
    args = build_parser().parse_args(argv)
    try:
        return args.run(args)
    except ValueError as error:
        print(f"jaxrail {args.command}: error: {error}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
