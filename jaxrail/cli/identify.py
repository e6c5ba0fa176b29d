"""``jaxrail identify``: fit contact or suspension parameters to measured time
histories (:func:`jaxrail.identification.identify`)."""

import sys

from ._options import (contact_option, emit_json, json_option, quiet_option,
                       scenario_argument, with_integrator)


def assignments(text, option, parse=float):
    """{name: value} from "a=1,b=2" (``parse`` converts each value)."""
    out = {}
    for item in filter(None, (text or "").split(",")):
        name, sep, value = item.partition("=")
        if not sep:
            raise ValueError(f"{option}: expected name=value, got {item!r}")
        try:
            out[name.strip()] = parse(value)
        except ValueError:
            raise ValueError(f"{option}: bad value in {item!r}") from None
    return out


def identify_command(args):
    from ..identification import identify, read_measurements
    from ..scenarios import load_scenario

    if args.cutoff is not None and not args.cutoff > 0.0:
        raise ValueError(f"--cutoff must be > 0 Hz, got {args.cutoff}")
    scenario = with_integrator(load_scenario(args.scenario), args)
    measurements = read_measurements(args.measured)
    names = [n.strip() for n in args.fit.split(",") if n.strip()]
    initial = assignments(args.initial, "--initial")
    bounds = assignments(args.bounds, "--bounds",
                         lambda v: tuple(float(x) for x in v.split(":", 1)))
    if any(len(b) != 2 for b in bounds.values()):
        raise ValueError("--bounds: expected name=lower:upper")
    print(f"jaxrail identify {scenario.name}: fitting {', '.join(names)} to "
          f"{len(measurements.channels)} channels x {len(measurements.time)} samples "
          "(compiling the simulation and its gradient first) ...", file=sys.stderr)
    result = identify(scenario, measurements, names, initial=initial, bounds=bounds,
                      method=args.method, max_iterations=args.iterations,
                      progress=not args.quiet, cutoff=args.cutoff, contact=args.contact)
    summary = result.as_dict()
    summary["scenario"] = scenario.name
    for name, entry in summary["parameters"].items():
        print(f"{name} = {entry['value']:.6g} +- {entry['standard_error']:.2g}",
              file=sys.stderr)
    emit_json(summary, args.out)
    if args.plot:
        from ..plots.identification import plot_identification

        plot_identification(result, args.plot)
        print(f"wrote {args.plot}", file=sys.stderr)
    return 0 if result.fit.converged else 1


def add_parser(commands):
    ident = commands.add_parser(
        "identify", help="fit contact or suspension parameters to measured time histories")
    scenario_argument(ident, "a built-in scenario (e.g. bogie-curve-entry) or a .toml file")
    ident.add_argument("--measured", required=True,
                       help="CSV of measured channels (format: docs/identification.md)")
    ident.add_argument("--fit", required=True,
                       help="comma-separated parameter names, e.g. contact_stiffness,friction")
    ident.add_argument("--initial", help="initial guesses name=value,... (default: the "
                                         "scenario's values)")
    ident.add_argument("--bounds", help="bounds name=lower:upper,... (default: a factor "
                                        "10 either side of the initial guess)")
    ident.add_argument("--method", choices=("lbfgs", "adam"), default="lbfgs")
    ident.add_argument("--iterations", type=int, default=30, help="maximum iterations")
    ident.add_argument("--cutoff", type=float,
                       help="low-pass cutoff [Hz] the measured channels were filtered with "
                            "(default: a fifth of their sample rate)")
    json_option(ident, "--out", "JSON result")
    ident.add_argument("--plot", help="write a PNG of the loss, parameters and channels")
    quiet_option(ident)
    contact_option(ident)
    ident.set_defaults(run=identify_command)
