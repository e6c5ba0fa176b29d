"""The ``jaxrail`` command line (a thin layer over the Python API)."""

import argparse
import os
import sys
from pathlib import Path

from ._constants import CONTACT_MODELS


def _load_profile(name, inclination):
    """A built-in profile by name, or a SIMPACK profile file (.prw/.prr)."""
    from .profiles.named import named_profile

    if Path(name).exists() and Path(name).suffix.lower() not in (".prw", ".prr"):
        raise ValueError(f"{name}: for a text profile file use --kind wheel|rail")
    return named_profile(name, inclination)


def _check_gauge(gauge_mm):
    """ValueError unless ``--gauge`` [mm] is within the range of the ``track_gauge``
    parameter (:mod:`jaxrail.vehicles.parameters`)."""
    from .vehicles.parameters import PARAMETERS

    low, high = (1e3 * x for x in PARAMETERS["track_gauge"].range)
    if not low <= gauge_mm <= high:  # also NaN
        raise ValueError(f"--gauge must be a track gauge within [{low:g}, {high:g}] mm, got "
                         f"{gauge_mm}")


MAX_PROFILE_POINTS = 100_001  # a point every 0.7 um across a 70 mm profile


def _profile_command(args):
    from . import profiles
    from .plots.profiles import plot_wheel_on_rail

    _check_gauge(args.gauge)
    if not 2 <= args.points <= MAX_PROFILE_POINTS:
        raise ValueError(f"--points must be within [2, {MAX_PROFILE_POINTS}], got {args.points}")
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


def _geometry_command(args):
    import math

    from . import profiles
    from .geometry.report import geometry_report, report_csv, report_json, shift_grid_mm, write_text

    def load(option, name, kind):
        path = Path(name)
        try:
            if path.suffix.lower() in (".csv", ".txt") and path.exists():
                return profiles.read_profile(path, kind=kind)
            found, profile = _load_profile(name, args.inclination)
        except ValueError as error:
            raise ValueError(f"{option}: {error}") from None
        if found != kind:
            raise ValueError(f"{option}: {name} is a {found} profile, not a {kind} profile")
        return profile

    shifts_mm = shift_grid_mm(args.shift_from, args.shift_to, args.shift_step)
    _check_gauge(args.gauge)
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
        from .plots.geometry import plot_geometry

        offset_mm = 1e3 * float(profiles.rail_offset(rail, 1e-3 * args.gauge))
        plot_geometry(report, wheel, rail, offset_mm, args.plot)
        print(f"wrote {args.plot}", file=sys.stderr)
    return 0


def _emit_json(data, path):
    """Write ``data`` as indented JSON to ``path`` (whole or not at all), or print it."""
    import json

    from ._files import write_text

    text = json.dumps(data, indent=2)
    if path:
        write_text(path, text + "\n")
        print(f"wrote {path}", file=sys.stderr)
    else:
        print(text)


def _simulate_command(args):
    from . import __version__
    from .results import summarize, write_results
    from .scenarios import load_scenario, prepare_scenario, run_scenario

    scenario = _with_integrator(load_scenario(args.scenario), args)  # reads a measured file
    duration = _duration(scenario, args)
    print(f"jaxrail simulate {scenario.name}: {scenario.description}", file=sys.stderr)
    prepared = prepare_scenario(scenario, duration)  # the irregularity covers the run
    print(f"compiling, then simulating {duration:g} s ...", file=sys.stderr)
    result, vehicle, params, _ = run_scenario(scenario, duration, progress=not args.quiet,
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
    _emit_json(summary, args.summary)
    if args.plots:
        from .plots import curve

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


MAX_IRREGULARITY_LENGTH_M = 1.0e6


def _band(text):
    """(shortest, longest) wavelength [m] of ``--band LO:HI``; ValueError names the flag."""
    lo, sep, hi = (text or "").partition(":")
    try:
        return float(lo), float(hi)
    except ValueError:
        raise ValueError(f"--band must be LO:HI wavelengths in m, e.g. 3:150, got "
                         f"{text!r}") from None


def _track_command(args):
    from .track.measured import write_irregularity
    from .track.spectra import realisation, spectrum

    spec = spectrum(args.spectrum)
    if not 0.0 < args.length <= MAX_IRREGULARITY_LENGTH_M:  # also NaN
        raise ValueError(f"--length must be within (0, {MAX_IRREGULARITY_LENGTH_M:g}] m, got "
                         f"{args.length}")
    _check_seed(args.seed)
    if not args.scale >= 0.0:
        raise ValueError(f"--scale must be >= 0, got {args.scale}")
    try:
        band = _band(args.band)
        irregularity = realisation(spec, args.length, args.step, args.seed, band, args.scale)
    except ValueError as error:
        raise ValueError(f"--band/--step: {error}") from None
    comment = (f"jaxrail track irregularities: {spec.name}, seed {args.seed}, band "
               f"{band[0]:g}-{band[1]:g} m, step {args.step:g} m, scale {args.scale:g}")
    if args.csv:
        write_irregularity(args.csv, irregularity, comment)
        print(f"wrote {len(irregularity.values)} samples to {args.csv}", file=sys.stderr)
    if args.plot:
        from .plots.track import plot_irregularity_psd

        plot_irregularity_psd(irregularity, spec, band, args.plot,
                              title=f"{spec.name}, seed {args.seed}, {args.length:g} m")
        print(f"wrote {args.plot}", file=sys.stderr)
    if not args.csv and not args.plot:
        from .track.measured import COLUMNS, irregularity_table

        distance, millimetres = irregularity_table(irregularity)
        print(",".join(COLUMNS))
        for x, row in zip(distance, millimetres):
            print(",".join(f"{v:.6f}" for v in (x, *row)))
    return 0


def _assignments(text, option, parse=float):
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


def _identify_command(args):
    from .identification import identify, read_measurements
    from .scenarios import load_scenario

    if args.cutoff is not None and not args.cutoff > 0.0:
        raise ValueError(f"--cutoff must be > 0 Hz, got {args.cutoff}")
    scenario = _with_integrator(load_scenario(args.scenario), args)
    measurements = read_measurements(args.measured)
    names = [n.strip() for n in args.fit.split(",") if n.strip()]
    initial = _assignments(args.initial, "--initial")
    bounds = _assignments(args.bounds, "--bounds",
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
    _emit_json(summary, args.out)
    if args.plot:
        from .plots.identification import plot_identification

        plot_identification(result, args.plot)
        print(f"wrote {args.plot}", file=sys.stderr)
    return 0 if result.fit.converged else 1


def _montecarlo_command(args):
    if args.host_devices is not None:  # before anything starts JAX's devices
        from ._devices import use_host_devices

        use_host_devices(args.host_devices)
    import numpy as np

    from .montecarlo import (parse_variation, run_montecarlo, study_statistics, successful,
                             write_table)
    from .montecarlo.sampling import check_names
    from .scenarios import load_scenario
    from .vehicles.parameters import vehicle_parameters

    if args.distributed:
        import jax

        jax.distributed.initialize(args.coordinator, args.num_processes, args.process_id)
    if args.samples < 1:
        raise ValueError(f"--samples must be >= 1, got {args.samples}")
    _check_seed(args.seed)
    for path in args.out or ():
        if Path(path).suffix.lower() not in (".csv", ".parquet"):
            raise ValueError(f"--out {path}: the suffix must be .csv or .parquet")
    variations = [parse_variation(v) for v in args.vary or ()]
    scenario = _with_integrator(load_scenario(args.scenario), args)
    built = scenario.build()
    check_names([v.name for v in variations], vehicle_parameters(*built[:2]))
    duration = _duration(scenario, args)
    import jax

    devices = jax.devices()
    print(f"jaxrail montecarlo {scenario.name}: {args.samples} samples of {duration:g} s "
          f"({args.design}, seed {args.seed}) on {len(devices)} device(s); compiling the "
          "batched simulation first ...", file=sys.stderr)
    checkpoint = None
    if args.out and jax.process_index() == 0:
        checkpoint = Path(f"{args.out[0]}.chunks.json")
        if checkpoint.exists() and not args.overwrite:
            print(f"resuming from the finished chunks in {checkpoint}", file=sys.stderr)
    result = run_montecarlo(scenario, variations, args.samples, seed=args.seed,
                            design=args.design, duration=duration, chunk=args.chunk,
                            progress=not args.quiet, contact=args.contact,
                            checkpoint=checkpoint, overwrite=args.overwrite, built=built)
    table = result.table
    print(f"{result.statuses} in {result.run_time_s:.1f} s (+ {result.compile_time_s:.1f} s "
          f"compiling), {result.throughput(duration):.3g} simulated s per wall s, "
          f"chunks of {result.chunk}", file=sys.stderr)
    if jax.process_index() == 0:
        for path in args.out or ():
            Path(path).parent.mkdir(parents=True, exist_ok=True)
            write_table(path, table)
            print(f"wrote {path}", file=sys.stderr)
        if checkpoint is not None:
            checkpoint.unlink(missing_ok=True)  # the tables hold every row now
        if args.plots:
            from .plots.montecarlo import plot_distributions, plot_maps

            directory = Path(args.plots)
            directory.mkdir(parents=True, exist_ok=True)
            axes = [v.name for v in variations][:2]
            if len(axes) == 2:
                plot_maps(table, directory / "maps.png", x=axes[0], y=axes[1])
            plot_distributions(table, directory / "distributions.png")
            print(f"wrote figures to {directory}", file=sys.stderr)
    if jax.process_index() == 0:  # every process has the whole table; one writes
        _emit_json(study_statistics(result, scenario.name, duration), args.summary)
    return 0 if np.all(successful(table)) else 1


def _duration(scenario, args) -> float:
    """The run's duration [s]: ``--duration`` (checked, with the run's size) or the
    scenario's."""
    from .scenarios import checks

    if args.duration is None:
        return scenario.duration
    duration = checks.number(args.duration, "duration", "command line", "--duration")
    checks.run_size(duration, scenario.output_rate, scenario.fixed_step, "--duration")
    return duration


def _with_integrator(scenario, args):
    """``scenario`` with the integrator of ``--integrator``, when given."""
    import dataclasses

    if getattr(args, "integrator", None) is None:
        return scenario
    return dataclasses.replace(scenario, integrator=args.integrator)


def _tables_command(args):
    from .contact.table_cache import contact_table, load_table, table_path
    from .scenarios import load_scenario

    scenario = _with_integrator(load_scenario(args.scenario), args)
    vehicle, params, _ = scenario.build()
    where = (params.wheel, params.rail, params.rail_offset, vehicle.config)
    if args.action == "build":
        _, info = contact_table(*where, progress=not args.quiet, cache=True)
    else:
        path = table_path(*where)
        if not path.exists():
            _emit_json({"scenario": scenario.name, "path": str(path), "cached": False}, None)
            return 1
        _, info = load_table(path)
        info = {**info, "path": str(path), "cached": True}
    _emit_json({"scenario": scenario.name, **info}, None)
    return 0


def _stability_command(args):
    from .scenarios import load_scenario
    from .simulation import SolverOptions
    from .stability.report import (curve_option, curve_track, format_nonlinear,
                                   format_study, nonlinear_study, speed_range,
                                   stability_study)
    from .vehicles import contact_model

    scenario = load_scenario(args.scenario)
    low, high = (speed_range(args.speeds) if args.speeds
                 else (0.25 * scenario.speed, 3.0 * scenario.speed))
    if args.points < 2:
        raise ValueError(f"--points {args.points}: need at least 2 speeds")
    nonlinear = None if args.nonlinear is None else speed_range(args.nonlinear, "--nonlinear")
    if not (args.ramp_rate > 0.0 and args.resolution > 0.0):
        raise ValueError(f"--ramp-rate {args.ramp_rate:g} and --resolution "
                         f"{args.resolution:g} must be > 0")
    curve = None if args.curve is None else curve_option(args.curve)
    if curve is not None and nonlinear is not None:
        raise ValueError("--nonlinear runs on straight track only: leave out --curve")
    vehicle, params, track = scenario.build(None if curve is None else curve[0])
    if curve is not None:
        track = curve_track(*curve, rail_centre_distance=track.rail_centre_distance)
    model = (contact_model(args.contact, vehicle, params, progress=not args.quiet)
             if args.contact == "table" else None)
    print(f"jaxrail stability {scenario.name}: {low:g}-{high:g} m/s, compiling ...",
          file=sys.stderr)
    study = stability_study(vehicle, params, track.with_irregularity(None).with_support(None),
                            low, high, args.points, model)
    study["scenario"] = scenario.name
    print(format_study(study), file=sys.stderr)
    if nonlinear is not None:
        print(f"nonlinear critical speed over {nonlinear[0]:g}-{nonlinear[1]:g} m/s: "
              "ramp-down, then brute force (minutes) ...", file=sys.stderr)
        options = SolverOptions(rtol=scenario.rtol, atol=scenario.atol, integrator="imex",
                                jacobian_every=scenario.jacobian_every)
        say = None if args.quiet else (lambda line: print(line, file=sys.stderr))
        study["nonlinear"] = nonlinear_study(
            vehicle, params, track.with_irregularity(None).with_support(None), *nonlinear,
            rate=args.ramp_rate / 3.6, resolution=args.resolution, options=options,
            model=model, progress=say)
        print(format_nonlinear(study["nonlinear"]), file=sys.stderr)
    _emit_json(study, args.json)
    if args.plot:
        from .plots.stability import plot_root_locus

        plot_root_locus(study, args.plot)
        print(f"wrote {args.plot}", file=sys.stderr)
        if nonlinear is not None:
            from .plots.stability import plot_bifurcation

            path = Path(args.plot)
            path = path.with_name(f"{path.stem}-nonlinear{path.suffix or '.png'}")
            plot_bifurcation(study["nonlinear"], path, study["linear_critical_speed_m_s"])
            print(f"wrote {path}", file=sys.stderr)
    return 0


def _assess_command(args):
    from .standards.comfort import comfort_of_file, format_comfort
    from .standards.en14363 import assess_file, format_table

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
    _emit_json(assessment, args.json)
    return 0 if assessment["passed"] else 1


def _vehicle_command(args):
    from .vehicles.report import format_report, vehicle_list, vehicle_report

    if args.vehicle_command == "list":
        for name, description in vehicle_list():
            print(f"{name:<24}{description}")
        return 0
    from .compilation import use_persistent_cache
    from .vehicles.from_file import vehicle_file_path

    path = vehicle_file_path(args.name)  # a bad name fails here, before compiling
    use_persistent_cache()
    print(f"jaxrail vehicle show {args.name}: the rest pose and the modes (compiling) ...",
          file=sys.stderr)
    report = vehicle_report(path)
    print(format_report(report))
    if args.json:
        _emit_json(report, args.json)
    if args.plot:
        from .plots.vehicle import plot_vehicle
        from .vehicles import vehicle_from_file

        plot_vehicle(*vehicle_from_file(path), args.plot)
        print(f"wrote {args.plot}", file=sys.stderr)
    return 0


# Options that several commands share, each written once so that its name, default and
# help read the same in every command (argparse lists options in the order they are added).

STANDARD_GAUGE_MM = 1435.0
SCENARIO_HELP = "a built-in scenario or a .toml file"


def _scenario_argument(parser, help=SCENARIO_HELP):
    """The positional ``scenario``: a built-in name or a scenario .toml file
    (:func:`jaxrail.scenarios.load_scenario`)."""
    parser.add_argument("scenario", help=help)


def _duration_option(parser):
    """``--duration`` [s], the scenario's unless given (checked by :func:`_duration`)."""
    parser.add_argument("--duration", type=float,
                        help="simulated time [s] (default: the scenario's)")


def _quiet_option(parser):
    parser.add_argument("--quiet", action="store_true", help="no progress bar")


def _json_option(parser, flag, what):
    """``flag``: the file :func:`_emit_json` writes (stdout without it); its help reads
    "write the ``what`` here"."""
    parser.add_argument(flag, help=f"write the {what} here (default: stdout)")


def _plots_option(parser, help):
    """``--plots``: a folder of figures, made if missing (:func:`_prepare_outputs`)."""
    parser.add_argument("--plots", help=help)


def _seed_option(parser):
    """``--seed``, checked by :func:`_check_seed`."""
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")


def _check_seed(seed):
    if seed < 0:
        raise ValueError(f"--seed must be >= 0, got {seed}")


def _inclination_option(parser, help):
    """``--inclination`` of the UIC60 rail: 1:40 unless given."""
    parser.add_argument("--inclination", default="1:40", help=help)


def _gauge_option(parser, help):
    """``--gauge`` [mm], standard gauge unless given (checked by :func:`_check_gauge`)."""
    parser.add_argument("--gauge", type=float, default=STANDARD_GAUGE_MM, help=help)


def _contact_option(parser):
    parser.add_argument("--contact", choices=CONTACT_MODELS,
                        help="contact model: the paper's search at every evaluation (online) "
                        "or its table, built once and cached (default: the scenario's "
                        "[contact] mode)")
    parser.add_argument("--integrator", choices=("tsit5", "imex"),
                        help="tsit5: explicit; imex: creep and contact stiffness implicit, "
                        "steps about 3 times longer (default: the scenario's [solver] "
                        "integrator)")


def build_parser():
    parser = argparse.ArgumentParser(prog="jaxrail", description=__doc__)
    commands = parser.add_subparsers(dest="command", required=True)

    profile = commands.add_parser("profile", help="write a wheel or rail profile (mm) and plot it")
    profile.add_argument("name", help="s1002, s1002-simplified, uic60, or a .prw/.prr/.csv file")
    _inclination_option(profile, "rail inclination: 1:40, 1:20, none")
    profile.add_argument("--kind", choices=("wheel", "rail"), help="kind of a text profile file")
    _gauge_option(profile, "track gauge for the plot [mm]")
    profile.add_argument("--points", type=int, default=401, help="number of points written")
    profile.add_argument("--csv", help="write the points (y_mm,z_mm) to this CSV file")
    profile.add_argument("--plot", help="write a PNG of the wheel on the rail")
    profile.set_defaults(run=_profile_command)

    geometry = commands.add_parser(
        "geometry", help="quasi-static wheel-rail geometry: contact points, delta r, conicity")
    geometry.add_argument("--wheel", default="s1002",
                          help="s1002, s1002-simplified, or a .prw/.csv wheel profile file")
    geometry.add_argument("--rail", default="uic60", help="uic60 or a .prr rail profile file")
    _inclination_option(geometry, "uic60 inclination: 1:40, 1:20, none")
    _gauge_option(geometry, "track gauge [mm]")
    geometry.add_argument("--shift-from", type=float, default=-10.0, help="first shift [mm], + left")
    geometry.add_argument("--shift-to", type=float, default=10.0, help="last shift [mm]")
    geometry.add_argument("--shift-step", type=float, default=0.5, help="shift step [mm]")
    geometry.add_argument("--yaw-per-shift", type=float, default=0.0,
                          help="yaw angle per shift [mrad/mm] (= rad/m), + turns left")
    geometry.add_argument("--format", choices=("json", "csv"), default="json", help="output format")
    geometry.add_argument("--out", help="write the table to this file (default: stdout)")
    geometry.add_argument("--plot", help="write a PNG of delta r, contact angles and contact points")
    geometry.set_defaults(run=_geometry_command)

    simulate = commands.add_parser(
        "simulate", help="run a scenario: results file, JSON summary, figures")
    _scenario_argument(simulate, "paper-curve, paper-curve-simplified, straight, or a scenario "
                                 ".toml file")
    _duration_option(simulate)
    simulate.add_argument("--out", help="write the time histories to this HDF5 file")
    _json_option(simulate, "--summary", "JSON summary")
    _plots_option(simulate, "write the figures (PNG) into this directory")
    _quiet_option(simulate)
    _contact_option(simulate)
    simulate.set_defaults(run=_simulate_command)

    ident = commands.add_parser(
        "identify", help="fit contact or suspension parameters to measured time histories")
    _scenario_argument(ident, "a built-in scenario (e.g. bogie-curve-entry) or a .toml file")
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
    _json_option(ident, "--out", "JSON result")
    ident.add_argument("--plot", help="write a PNG of the loss, parameters and channels")
    _quiet_option(ident)
    _contact_option(ident)
    ident.set_defaults(run=_identify_command)

    mc = commands.add_parser(
        "montecarlo", help="many runs of a scenario over drawn speeds, misalignments, parameters")
    _scenario_argument(mc)
    mc.add_argument("--samples", type=int, required=True, help="number of samples N")
    mc.add_argument("--vary", action="append", metavar="NAME=SPREAD",
                    help="an input and its spread: lo:hi (uniform), normal:mean,sd, or "
                         "a,b,c; inputs speed [m/s], misalignment [m], or a parameter name "
                         "(friction, contact_stiffness, ...). Repeat for several")
    mc.add_argument("--design", choices=("latin", "random", "grid"), default="latin",
                    help="sampling design (default: latin hypercube)")
    _seed_option(mc)
    mc.add_argument("--chunk", type=int, help="samples per compiled batch (default: "
                                              "min(N, 64) on a CPU, min(N, 4096) on a "
                                              "GPU, rounded to the devices)")
    _duration_option(mc)
    mc.add_argument("--out", action="append", help="write the table to this .csv or "
                                                   ".parquet file (repeat for both)")
    mc.add_argument("--overwrite", action="store_true",
                    help="start afresh over a checkpoint of another study (OUT.chunks.json, "
                         "the finished chunks kept while the study runs)")
    _json_option(mc, "--summary", "JSON statistics")
    _plots_option(mc, "write the maps and distributions (PNG) here")
    mc.add_argument("--host-devices", type=int, metavar="N",
                    help="split each chunk over N CPU devices run side by side (e.g. one "
                         "per core; sets XLA_FLAGS, see docs/montecarlo.md)")
    mc.add_argument("--distributed", action="store_true",
                    help="call jax.distributed.initialize first (several hosts)")
    mc.add_argument("--coordinator", help="with --distributed: host:port of process 0")
    mc.add_argument("--num-processes", type=int, help="with --distributed")
    mc.add_argument("--process-id", type=int, help="with --distributed")
    _quiet_option(mc)
    _contact_option(mc)
    mc.set_defaults(run=_montecarlo_command)

    track = commands.add_parser("track", help="track irregularities: write a realisation")
    track_commands = track.add_subparsers(dest="track_command", required=True)
    irregular = track_commands.add_parser(
        "irregularities", help="a realisation of an irregularity spectrum as a measured-file "
                               "CSV (mm) and its PSD")
    irregular.add_argument("--spectrum", required=True,
                           help="german-low, german-high, fra-1 ... fra-6")
    irregular.add_argument("--length", type=float, required=True, help="track length [m]")
    irregular.add_argument("--step", type=float, default=0.25, help="sample spacing [m]")
    _seed_option(irregular)
    irregular.add_argument("--band", default="3:150",
                           help="wavelengths LO:HI [m] (default 3:150)")
    irregular.add_argument("--scale", type=float, default=1.0, help="factor on every channel")
    irregular.add_argument("--csv", help="write the realisation here (format: docs/track.md)")
    irregular.add_argument("--plot", help="write a PNG of its PSD against the spectrum")
    irregular.set_defaults(run=_track_command)

    tables = commands.add_parser(
        "tables", help="build or describe the contact table of a scenario's profiles")
    tables.add_argument("action", choices=("build", "info"),
                        help="build: build and cache it (if not cached); info: where it is "
                        "and how it was built")
    _scenario_argument(tables)
    _quiet_option(tables)
    tables.set_defaults(run=_tables_command)
    stability = commands.add_parser(
        "stability", help="stability: the hunting mode against speed, the linear critical "
                          "speed and, with --nonlinear, the nonlinear one (straight, ideal, "
                          "rigid track; with --curve the linear one in a curve)")
    _scenario_argument(stability, "a built-in scenario (e.g. suspended-wheelset) or a scenario "
                                  ".toml file (its vehicle, profiles and friction)")
    stability.add_argument("--speeds", help="speed range LO:HI [m/s] holding the crossing "
                                            "(default: 0.25 to 3 times the scenario's speed)")
    stability.add_argument("--points", type=int, default=9,
                           help="speeds of the root locus over the range (default 9)")
    _json_option(stability, "--json", "study as JSON")
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
    _quiet_option(stability)
    stability.set_defaults(run=_stability_command)

    assess = commands.add_parser(
        "assess", help="EN 14363 running safety and track loading, and EN 12299 ride "
                       "comfort, of a results file")
    assess.add_argument("results", help="a results file (HDF5) of jaxrail simulate --out")
    _json_option(assess, "--json", "assessment as JSON")
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
    assess.set_defaults(run=_assess_command)

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
    vehicle.set_defaults(run=_vehicle_command)
    return parser


EXIT_FILE_ERROR = 3
"""Exit status of a file that cannot be written or read (0: done, 1: a run stopped
early or a fit did not converge, 2: bad input)."""


def _prepare_outputs(args):
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
    from ._float64 import enable_float64
    from ._xla_alarms import hidden_xla_alarms

    enable_float64()
    args = build_parser().parse_args(argv)
    with hidden_xla_alarms():
        try:
            _prepare_outputs(args)
            return args.run(args)
        except ValueError as error:
            print(f"jaxrail {args.command}: error: {error}", file=sys.stderr)
            return 2
        except OSError as error:
            print(f"jaxrail {args.command}: file error: {error}", file=sys.stderr)
            return EXIT_FILE_ERROR


if __name__ == "__main__":
    sys.exit(main())
