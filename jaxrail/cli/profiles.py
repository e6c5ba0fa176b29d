"""``jaxrail profile`` and ``jaxrail geometry``: a wheel or rail profile, and the
quasi-static wheel-rail geometry of a pair."""

import math
import sys

from ._options import check_gauge, gauge_option, inclination_option

MAX_PROFILE_POINTS = 100_001  # a point every 0.7 um across a 70 mm profile


def profile_command(args):
    from .. import profiles
    from ..plots.profiles import plot_wheel_on_rail
    from ..profiles.named import profile_by_name

    check_gauge(args.gauge)
    if not 2 <= args.points <= MAX_PROFILE_POINTS:
        raise ValueError(f"--points must be within [2, {MAX_PROFILE_POINTS}], got {args.points}")
    if args.kind is not None:
        kind, profile = args.kind, profiles.read_profile(args.name, kind=args.kind)
    else:
        kind, profile = profile_by_name(args.name, args.inclination)
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


def geometry_command(args):
    from .. import profiles
    from ..geometry.report import geometry_report, report_csv, report_json, shift_grid_mm, write_text
    from ..profiles.named import profile_of_kind

    def load(option, name, kind):
        try:
            return profile_of_kind(name, kind, args.inclination)
        except ValueError as error:
            raise ValueError(f"{option}: {error}") from None

    shifts_mm = shift_grid_mm(args.shift_from, args.shift_to, args.shift_step)
    check_gauge(args.gauge)
    if not math.isfinite(args.yaw_per_shift):
        raise ValueError(f"--yaw-per-shift must be finite, got {args.yaw_per_shift}")
    if args.rail.lower() == "uic60":
        try:
            profiles.uic60(args.inclination)
        except ValueError as error:
            raise ValueError(f"--inclination: {error}") from None
    wheel = load("--wheel", args.wheel, "wheel")
    rail = load("--rail", args.rail, "rail")
    settings = {"wheel": args.wheel, "rail": args.rail, "inclination": args.inclination,
                "gauge_mm": args.gauge, "yaw_per_shift": args.yaw_per_shift,
                "yaw_per_shift_unit": "mrad/mm", "shift_from_mm": args.shift_from,
                "shift_to_mm": args.shift_to, "shift_step_mm": args.shift_step}
    report, _ = geometry_report(wheel, rail, shifts_mm, args.gauge, args.yaw_per_shift, settings)
    unsolved = [row["shift_mm"] for row in report["rows"] if not row["converged"]]
    if unsolved:
        print(f"jaxrail geometry: warning: the contact solve did not converge at shifts "
              f"{unsolved} mm; those rows are marked \"converged\": false", file=sys.stderr)
    missing = [c["amplitude_mm"] for c in report["conicity"] if c["tan_gamma_e"] is None]
    if missing:
        print(f"jaxrail geometry: note: the shift range does not cover amplitudes {missing} mm;"
              " their conicity is null", file=sys.stderr)
    text = report_json(report) if args.format == "json" else report_csv(report)
    if args.out:
        write_text(args.out, text)
        print(f"wrote {len(report['rows'])} shifts to {args.out}", file=sys.stderr)
    else:
        sys.stdout.write(text)
    if args.plot:
        from ..plots.geometry import plot_geometry

        offset_mm = 1e3 * float(profiles.rail_offset(rail, 1e-3 * args.gauge))
        plot_geometry(report, wheel, rail, offset_mm, args.plot)
        print(f"wrote {args.plot}", file=sys.stderr)
    return 0


def add_parsers(commands):
    """The ``profile`` and ``geometry`` commands."""
    profile = commands.add_parser("profile", help="write a wheel or rail profile (mm) and plot it")
    profile.add_argument("name", help="s1002, s1002-simplified, uic60, or a .prw/.prr/.csv file")
    inclination_option(profile, "rail inclination: 1:40, 1:20, none")
    profile.add_argument("--kind", choices=("wheel", "rail"), help="kind of a text profile file")
    gauge_option(profile, "track gauge for the plot [mm]")
    profile.add_argument("--points", type=int, default=401, help="number of points written")
    profile.add_argument("--csv", help="write the points (y_mm,z_mm) to this CSV file")
    profile.add_argument("--plot", help="write a PNG of the wheel on the rail")
    profile.set_defaults(run=profile_command)

    geometry = commands.add_parser(
        "geometry", help="quasi-static wheel-rail geometry: contact points, delta r, conicity")
    geometry.add_argument("--wheel", default="s1002",
                          help="s1002, s1002-simplified, or a .prw/.csv wheel profile file")
    geometry.add_argument("--rail", default="uic60", help="uic60 or a .prr rail profile file")
    inclination_option(geometry, "uic60 inclination: 1:40, 1:20, none")
    gauge_option(geometry, "track gauge [mm]")
    geometry.add_argument("--shift-from", type=float, default=-10.0, help="first shift [mm], + left")
    geometry.add_argument("--shift-to", type=float, default=10.0, help="last shift [mm]")
    geometry.add_argument("--shift-step", type=float, default=0.5, help="shift step [mm]")
    geometry.add_argument("--yaw-per-shift", type=float, default=0.0,
                          help="yaw angle per shift [mrad/mm] (= rad/m), + turns left")
    geometry.add_argument("--format", choices=("json", "csv"), default="json", help="output format")
    geometry.add_argument("--out", help="write the table to this file (default: stdout)")
    geometry.add_argument("--plot", help="write a PNG of delta r, contact angles and contact points")
    geometry.set_defaults(run=geometry_command)
