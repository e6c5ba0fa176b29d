"""``jaxrail vehicle list`` and ``jaxrail vehicle show``: the built-in vehicles, and a
vehicle's bodies, wheel loads at rest and modes standing on the track."""

import sys

from ._options import emit_json


def vehicle_command(args):
    from ..stability.vehicle_report import format_report, vehicle_list, vehicle_report

    if args.vehicle_command == "list":
        for name, description in vehicle_list():
            print(f"{name:<24}{description}")
        return 0
    from ..compilation import use_persistent_cache
    from ..vehicles.from_file import vehicle_file_path

    path = vehicle_file_path(args.name)  # a bad name fails here, before compiling
    use_persistent_cache()
    print(f"jaxrail vehicle show {args.name}: the rest pose and the modes (compiling) ...",
          file=sys.stderr)
    report = vehicle_report(path)
    print(format_report(report))
    if args.json:
        emit_json(report, args.json)
    if args.plot:
        from ..plots.vehicle import plot_vehicle
        from ..vehicles import vehicle_from_file

        plot_vehicle(*vehicle_from_file(path), args.plot)
        print(f"wrote {args.plot}", file=sys.stderr)
    return 0


def add_parser(commands):
    vehicle = commands.add_parser(
        "vehicle", help="the built-in vehicles; a vehicle's bodies, wheel loads at rest and "
                        "modes standing on the track")
    vehicle_commands = vehicle.add_subparsers(dest="vehicle_command", required=True)
    vehicle_commands.add_parser("list", help="the built-in vehicles and their descriptions")
    show = vehicle_commands.add_parser(
        "show", help="bodies and masses, wheel loads at rest and the modes with the "
                     "wheelsets clamped (creep forces vanish at rest)")
    show.add_argument("name", help="a built-in vehicle (jaxrail vehicle list) or a vehicle "
                                   ".toml file")
    show.add_argument("--json", help="write the report as JSON here (the tables go to "
                                     "stdout either way)")
    show.add_argument("--plot", help="write a side and plan view of the vehicle (PNG) here")
    vehicle.set_defaults(run=vehicle_command)
