"""Options that several commands share, each written once so that its name, default and
help read the same in every command (argparse lists options in the order they are
added), and the checks and outputs they share."""

import sys

from .._constants import CONTACT_MODELS, INTEGRATORS

STANDARD_GAUGE_MM = 1435.0
SCENARIO_HELP = "a built-in scenario or a .toml file"


def scenario_argument(parser, help=SCENARIO_HELP):
    """The positional ``scenario``: a built-in name or a scenario .toml file
    (:func:`jaxrail.scenarios.load_scenario`)."""
    parser.add_argument("scenario", help=help)


def duration_option(parser):
    """``--duration`` [s], the scenario's unless given (checked by :func:`duration`)."""
    parser.add_argument("--duration", type=float,
                        help="simulated time [s] (default: the scenario's)")


def quiet_option(parser):
    parser.add_argument("--quiet", action="store_true", help="no progress bar")


def json_option(parser, flag, what):
    """``flag``: the file :func:`emit_json` writes (stdout without it); its help reads
    "write the ``what`` here"."""
    parser.add_argument(flag, help=f"write the {what} here (default: stdout)")


def plots_option(parser, help):
    """``--plots``: a folder of figures, made if missing
    (:func:`jaxrail.cli.prepare_outputs`)."""
    parser.add_argument("--plots", help=help)


def seed_option(parser):
    """``--seed``, checked by :func:`check_seed`."""
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")


def check_seed(seed):
    if seed < 0:
        raise ValueError(f"--seed must be >= 0, got {seed}")


def inclination_option(parser, help):
    """``--inclination`` of the UIC60 rail: 1:40 unless given."""
    parser.add_argument("--inclination", default="1:40", help=help)


def gauge_option(parser, help):
    """``--gauge`` [mm], standard gauge unless given (checked by :func:`check_gauge`)."""
    parser.add_argument("--gauge", type=float, default=STANDARD_GAUGE_MM, help=help)


def check_gauge(gauge_mm):
    """ValueError unless ``--gauge`` [mm] is within the range of the ``track_gauge``
    parameter (:mod:`jaxrail.vehicles.parameters`)."""
    from ..vehicles.parameters import PARAMETERS

    low, high = (1e3 * x for x in PARAMETERS["track_gauge"].range)
    if not low <= gauge_mm <= high:  # also NaN
        raise ValueError(f"--gauge must be a track gauge within [{low:g}, {high:g}] mm, got "
                         f"{gauge_mm}")


def contact_option(parser):
    parser.add_argument("--contact", choices=CONTACT_MODELS,
                        help="contact model: the paper's search at every evaluation (online) "
                        "or its table, built once and cached (default: the scenario's "
                        "[contact] mode)")
    parser.add_argument("--integrator", choices=INTEGRATORS,
                        help="tsit5: explicit; imex: creep and contact stiffness implicit, "
                        "steps about 3 times longer (default: the scenario's [solver] "
                        "integrator)")


def duration(scenario, args) -> float:
    """The run's duration [s]: ``--duration`` (checked, with the run's size) or the
    scenario's."""
    from ..scenarios import checks

    if args.duration is None:
        return scenario.duration
    duration = checks.number(args.duration, "duration", "command line", "--duration")
    checks.run_size(duration, scenario.output_rate, scenario.fixed_step, "--duration")
    return duration


def with_integrator(scenario, args):
    """``scenario`` with the integrator of ``--integrator``, when given."""
    import dataclasses

    if getattr(args, "integrator", None) is None:
        return scenario
    return dataclasses.replace(scenario, integrator=args.integrator)


def emit_json(data, path):
    """Write ``data`` as indented JSON to ``path`` (whole or not at all), or print it."""
    import json

    from .._files import write_text

    text = json.dumps(data, indent=2)
    if path:
        write_text(path, text + "\n")
        print(f"wrote {path}", file=sys.stderr)
    else:
        print(text)
