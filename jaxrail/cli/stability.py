"""``jaxrail stability``: the hunting mode against speed, the linear critical speed and
the nonlinear one (:mod:`jaxrail.stability.report`)."""

import sys
from pathlib import Path

from .._constants import CONTACT_MODELS
from ._options import emit_json, json_option, quiet_option, scenario_argument


def stability_command(args):
    from ..scenarios import load_scenario
    from ..stability.report import (curve_option, default_speed_range, format_nonlinear,
                                    format_study, nonlinear_options, nonlinear_study,
                                    speed_range, stability_study, study_setup)

    scenario = load_scenario(args.scenario)
    low, high = speed_range(args.speeds) if args.speeds else default_speed_range(scenario)
    if args.points < 2:
        raise ValueError(f"--points {args.points}: need at least 2 speeds")
    nonlinear = None if args.nonlinear is None else speed_range(args.nonlinear, "--nonlinear")
    if not (args.ramp_rate > 0.0 and args.resolution > 0.0):
        raise ValueError(f"--ramp-rate {args.ramp_rate:g} and --resolution "
                         f"{args.resolution:g} must be > 0")
    curve = None if args.curve is None else curve_option(args.curve)
    if curve is not None and nonlinear is not None:
        raise ValueError("--nonlinear runs on straight track only: leave out --curve")
    vehicle, params, track, model = study_setup(scenario, curve, args.contact,
                                                progress=not args.quiet)
    print(f"jaxrail stability {scenario.name}: {low:g}-{high:g} m/s, compiling ...",
          file=sys.stderr)
    study = stability_study(vehicle, params, track, low, high, args.points, model)
    study["scenario"] = scenario.name
    print(format_study(study), file=sys.stderr)
    if nonlinear is not None:
        print(f"nonlinear critical speed over {nonlinear[0]:g}-{nonlinear[1]:g} m/s: "
              "ramp-down, then brute force (minutes) ...", file=sys.stderr)
        say = None if args.quiet else (lambda line: print(line, file=sys.stderr))
        study["nonlinear"] = nonlinear_study(
            vehicle, params, track, *nonlinear, rate=args.ramp_rate / 3.6,
            resolution=args.resolution, options=nonlinear_options(scenario), model=model,
            progress=say)
        print(format_nonlinear(study["nonlinear"]), file=sys.stderr)
    emit_json(study, args.json)
    if args.plot:
        from ..plots.stability import plot_root_locus

        plot_root_locus(study, args.plot)
        print(f"wrote {args.plot}", file=sys.stderr)
        if nonlinear is not None:
            from ..plots.stability import plot_bifurcation

            path = Path(args.plot)
            path = path.with_name(f"{path.stem}-nonlinear{path.suffix or '.png'}")
            plot_bifurcation(study["nonlinear"], path, study["linear_critical_speed_m_s"])
            print(f"wrote {path}", file=sys.stderr)
    return 0


def add_parser(commands):
    stability = commands.add_parser(
        "stability", help="stability: the hunting mode against speed, the linear critical "
                          "speed and, with --nonlinear, the nonlinear one (straight, ideal, "
                          "rigid track; with --curve the linear one in a curve)")
    scenario_argument(stability, "a built-in scenario (e.g. suspended-wheelset) or a scenario "
                                 ".toml file (its vehicle, profiles and friction)")
    stability.add_argument("--speeds", help="speed range LO:HI [m/s] holding the crossing "
                                            "(default: 0.25 to 3 times the scenario's speed)")
    stability.add_argument("--points", type=int, default=9,
                           help="speeds of the root locus over the range (default 9)")
    json_option(stability, "--json", "study as JSON")
    stability.add_argument("--plot", help="write the root locus figure (PNG) here; with "
                                          "--nonlinear also the bifurcation diagram beside "
                                          "it (NAME-nonlinear.png)")
    stability.add_argument("--contact", choices=CONTACT_MODELS, default="online",
                           help="contact model (default: the paper's search)")
    stability.add_argument("--curve", metavar="RADIUS[:CANT]",
                           help="the linear analysis in a left curve of this radius [m] and "
                                "cant [m] (default 0), about the steady curving state")
    stability.add_argument("--nonlinear", metavar="LO:HI",
                           help="also the nonlinear critical speed in LO:HI [m/s]: ramp-down "
                                "from HI, then brute force (minutes of simulation)")
    stability.add_argument("--ramp-rate", type=float, default=5.0,
                           help="ramp-down rate [km/h per s] (default 5, GENSYS's example)")
    stability.add_argument("--resolution", type=float, default=0.5,
                           help="brute force's speed resolution [m/s] (default 0.5)")
    quiet_option(stability)
    stability.set_defaults(run=stability_command)
