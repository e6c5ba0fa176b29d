"""``jaxrail assess``: EN 14363 running safety and track loading, and EN 12299 ride
comfort, of a results file."""

import sys

from ._options import emit_json, json_option


def assess_command(args):
    from ..standards.comfort import comfort_of_file, format_comfort
    from ..standards.en14363 import assess_file, format_table

    assessment = assess_file(args.results, vehicle_type=args.vehicle_type,
                             static_wheel_load=args.static_wheel_load,
                             max_speed_kmh=args.max_speed, curve_radius=args.curve_radius)
    print(format_table(assessment), file=sys.stderr)
    try:
        assessment["en12299"] = comfort_of_file(args.results)
        print(format_comfort(assessment["en12299"]), file=sys.stderr)
    except ValueError as error:  # no carbody or no accelerations: EN 14363 alone
        assessment["en12299"] = {"not_assessed": str(error)}
        print(f"EN 12299: not assessed: {error}", file=sys.stderr)
    emit_json(assessment, args.json)
    return 0 if assessment["passed"] else 1


def add_parser(commands):
    assess = commands.add_parser(
        "assess", help="EN 14363 running safety and track loading, and EN 12299 ride "
                       "comfort, of a results file")
    assess.add_argument("results", help="a results file (HDF5) of jaxrail simulate --out")
    json_option(assess, "--json", "assessment as JSON")
    assess.add_argument("--vehicle-type", choices=("passenger", "locomotive", "freight"),
                        default="passenger", help="sets Prud'homme's alpha and the carbody "
                                                  "limits (default passenger)")
    assess.add_argument("--static-wheel-load", type=float,
                        help="Q0 [N] (default: each wheelset's mean Q over the record)")
    assess.add_argument("--max-speed", type=float,
                        help="the vehicle's permissible speed [km/h] (caps Qlim; default: "
                             "the run's top speed)")
    assess.add_argument("--curve-radius", type=float,
                        help="curve radius of the section [m] (default: straight track, "
                             "no quasi-static checks)")
    assess.set_defaults(run=assess_command)
