"""``jaxrail simulate`` (a scenario's run: results file, summary, figures) and
``jaxrail tables`` (the contact table of a scenario's profiles)."""

import sys
from pathlib import Path

from ._options import (contact_option, duration, duration_option, emit_json, json_option,
                       plots_option, quiet_option, scenario_argument, with_integrator)


def simulate_command(args):
    from ..compilation.loop_kernels import use_loop_kernels

    use_loop_kernels(required=False)  # before anything starts JAX: stage loops as kernels
    from .. import __version__
    from ..results import summarize, write_results
    from ..scenarios import load_scenario, prepare_scenario, run_scenario

    scenario = with_integrator(load_scenario(args.scenario), args)  # reads a measured file
    run_duration = duration(scenario, args)
    print(f"jaxrail simulate {scenario.name}: {scenario.description}", file=sys.stderr)
    prepared = prepare_scenario(scenario, run_duration)  # the irregularity covers the run
    print(f"compiling, then simulating {run_duration:g} s ...", file=sys.stderr)
    result, vehicle, params, _ = run_scenario(scenario, run_duration, progress=not args.quiet,
                                              contact=args.contact, prepared=prepared)
    summary = summarize(result, friction=float(params.contact.friction))
    summary["scenario"] = scenario.name
    print(f"{result.status}: {result.simulated_time_s:g} s simulated in "
          f"{float(result.wall_time_s):.1f} s (+ {float(result.compile_time_s):.1f} s "
          f"compiling), {int(result.steps)} steps", file=sys.stderr)
    if args.out:
        write_results(args.out, result, metadata={
            "scenario": scenario.name, "description": scenario.description,
            "jaxrail_version": __version__, "body_names": list(vehicle.system.body_names)})
        print(f"wrote {args.out}", file=sys.stderr)
    emit_json(summary, args.summary)
    if args.plots:
        from ..plots import curve

        directory = Path(args.plots)
        directory.mkdir(parents=True, exist_ok=True)
        results = {scenario.name: result}
        friction = float(params.contact.friction)
        for name, plot in (("contact_positions", curve.plot_contact_positions),
                           ("lateral_displacements", curve.plot_lateral_displacements),
                           ("forces", curve.plot_forces)):
            plot(results, directory / f"{name}.png")
        curve.plot_derailment_ratio(results, directory / "derailment_ratio.png",
                                    friction=friction)
        print(f"wrote figures to {directory}", file=sys.stderr)
    return 0 if result.status == "successful" else 1


def tables_command(args):
    from ..contact.table_cache import contact_table, load_table, table_path
    from ..scenarios import load_scenario

    scenario = with_integrator(load_scenario(args.scenario), args)
    vehicle, params, track = scenario.build()
    where = (params.wheel, track.rails, vehicle.config)
    if args.action == "build":
        _, info = contact_table(*where, progress=not args.quiet, cache=True)
    else:
        path = table_path(*where)
        if not path.exists():
            emit_json({"scenario": scenario.name, "path": str(path), "cached": False}, None)
            return 1
        _, info = load_table(path)
        info = {**info, "path": str(path), "cached": True}
    emit_json({"scenario": scenario.name, **info}, None)
    return 0


def add_simulate_parser(commands):
    simulate = commands.add_parser(
        "simulate", help="run a scenario: results file, JSON summary, figures")
    scenario_argument(simulate, "paper-curve, paper-curve-simplified, straight, or a scenario "
                                ".toml file")
    duration_option(simulate)
    simulate.add_argument("--out", help="write the time histories to this HDF5 file")
    json_option(simulate, "--summary", "JSON summary")
    plots_option(simulate, "write the figures (PNG) into this directory")
    quiet_option(simulate)
    contact_option(simulate)
    simulate.set_defaults(run=simulate_command)


def add_tables_parser(commands):
    tables = commands.add_parser(
        "tables", help="build or describe the contact table of a scenario's profiles")
    tables.add_argument("action", choices=("build", "info"),
                        help="build: build and cache it (if not cached); info: where it is "
                        "and how it was built")
    scenario_argument(tables)
    quiet_option(tables)
    tables.set_defaults(run=tables_command)
