"""``jaxrail wear``: a route's wear and the wheel profile it wears into
(:mod:`jaxrail.wear`)."""

import sys
from pathlib import Path

from .._constants import CONTACT_MODELS
from ._options import emit_json, json_option, plots_option, quiet_option

COARSE_STEP_MM = 0.5  # [mm] off the profile in one update: warned about


def wear_command(args):
    if args.host_devices is not None:  # before anything starts JAX's devices
        from .._devices import use_host_devices

        use_host_devices(args.host_devices)
    from ..wear.evolution import evolve, step_lengths
    from ..wear.route import load_route
    from ..wear.summary import evolution_summary

    steps = step_lengths(args.distance, args.step)  # checked before anything compiles
    route = load_route(args.route)
    if args.duration is not None:
        import dataclasses

        if not args.duration > 0.0:
            raise ValueError(f"--duration {args.duration:g}: must be > 0 s")
        route = dataclasses.replace(route, duration=float(args.duration))
    say = None if args.quiet else (lambda line: print(line, file=sys.stderr))
    print(f"jaxrail wear {route.name}: {len(route.sections)} sections of "
          f"{route.duration:g} s, {len(steps)} steps to {args.distance:g} km, "
          f"{args.contact} contact"
          + (" (the worn profile's table is built at every step)" if args.contact == "table"
             else ""), file=sys.stderr)
    max_depth = None if args.max_depth is None else 1e-3 * args.max_depth  # checked by evolve
    evolution = evolve(route, args.distance, args.step, args.contact, out=args.out,
                       progress=not args.quiet, overwrite=args.overwrite, say=say,
                       max_depth=max_depth)
    attrs = {"route": route.name, "wear_model": route.wear_model, "contact": args.contact}
    summary = evolution_summary(evolution, attrs)
    coarse = [k + 1 for k, v in enumerate(summary["max_height_loss_per_step_mm"])
              if v > COARSE_STEP_MM]
    if coarse and max_depth is None:
        print(f"jaxrail wear: warning: steps {coarse} took more than {COARSE_STEP_MM:g} mm "
              "off the profile at once: too coarse for these wear rates (a groove feeds "
              "itself); give --max-depth 0.1 or a smaller --step (docs/wear.md)",
              file=sys.stderr)
    emit_json(summary, args.json)
    if args.out:
        print(f"wrote {args.out}", file=sys.stderr)
    if args.plots:
        from ..plots.wear import plot_measures, plot_wear_distribution, plot_worn_profiles

        folder = Path(args.plots)
        for name, plot in (("worn-profiles.png", plot_worn_profiles),
                           ("measures.png", plot_measures),
                           ("wear-distribution.png", plot_wear_distribution)):
            plot(evolution, folder / name, title=f"{route.name}: {route.description}"[:90])
            print(f"wrote {folder / name}", file=sys.stderr)
    return 0


def add_parser(commands):
    wear = commands.add_parser(
        "wear", help="wear: a route's wheel and rail wear and the profile it wears into "
                     "over a distance")
    wear.add_argument("route", help="a built-in route (straight-route, curved-route, "
                                    "main-line-route) or a route .toml file")
    wear.add_argument("--distance", type=float, default=200000.0,
                      help="distance to run [km] (default 200000)")
    wear.add_argument("--step", type=float, default=20000.0,
                      help="distance per profile update [km] (default 20000)")
    wear.add_argument("--out", help="HDF5 file of the evolution, written after every step "
                                    "and sub-step; an interrupted evolution resumes from it")
    wear.add_argument("--max-depth", type=float, metavar="MM",
                      help="split each step so that no update takes more than MM off the "
                           "wheel profile (the route run again on the profile worn so far; "
                           "default: one update per step)")
    wear.add_argument("--host-devices", type=int, metavar="N",
                      help="split each batch of sections over N CPU devices run side by side "
                           "(e.g. one per core; sets XLA_FLAGS, see docs/montecarlo.md)")
    wear.add_argument("--overwrite", action="store_true",
                      help="start again even if --out holds another evolution")
    plots_option(wear, "write the figures (worn profiles, measures, wear distribution) "
                       "into this folder")
    json_option(wear, "--json", "summary as JSON")
    wear.add_argument("--contact", choices=CONTACT_MODELS, default="table",
                      help="contact model (default table: rebuilt for every worn profile)")
    wear.add_argument("--duration", type=float,
                      help="seconds of each section's run (default: the route's)")
    quiet_option(wear)
    wear.set_defaults(run=wear_command)
