"""``jaxrail montecarlo``: many runs of a scenario over drawn inputs
(:func:`jaxrail.montecarlo.run_montecarlo`), their table, statistics and figures."""

import sys
from pathlib import Path

from ._options import (check_seed, contact_option, duration, duration_option, emit_json,
                       json_option, plots_option, quiet_option, scenario_argument,
                       seed_option, with_integrator)


def montecarlo_command(args):
    if args.host_devices is not None:  # before anything starts JAX's devices
        from .._devices import use_host_devices

        use_host_devices(args.host_devices)
    import numpy as np

    from ..montecarlo import (parse_variation, run_montecarlo, study_statistics, successful,
                              write_table)
    from ..montecarlo.checkpoint import checkpoint_path, resumes
    from ..montecarlo.sampling import check_names
    from ..montecarlo.table import FORMATS
    from ..scenarios import load_scenario
    from ..vehicles.parameters import vehicle_parameters

    if args.distributed:
        import jax

        jax.distributed.initialize(args.coordinator, args.num_processes, args.process_id)
    if args.samples < 1:
        raise ValueError(f"--samples must be >= 1, got {args.samples}")
    check_seed(args.seed)
    for path in args.out or ():
        if Path(path).suffix.lower() not in FORMATS:
            raise ValueError(f"--out {path}: the suffix must be .csv or .parquet")
    variations = [parse_variation(v) for v in args.vary or ()]
    scenario = with_integrator(load_scenario(args.scenario), args)
    built = scenario.build()
    check_names([v.name for v in variations], vehicle_parameters(*built[:2]))
    run_duration = duration(scenario, args)
    import jax

    devices = jax.devices()
    print(f"jaxrail montecarlo {scenario.name}: {args.samples} samples of {run_duration:g} s "
          f"({args.design}, seed {args.seed}) on {len(devices)} device(s); compiling the "
          "batched simulation first ...", file=sys.stderr)
    checkpoint = None
    if args.out and jax.process_index() == 0:
        checkpoint = checkpoint_path(args.out[0])
        if resumes(checkpoint, args.overwrite):
            print(f"resuming from the finished chunks in {checkpoint}", file=sys.stderr)
    result = run_montecarlo(scenario, variations, args.samples, seed=args.seed,
                            design=args.design, duration=run_duration, chunk=args.chunk,
                            progress=not args.quiet, contact=args.contact,
                            checkpoint=checkpoint, overwrite=args.overwrite, built=built)
    table = result.table
    print(f"{result.statuses} in {result.run_time_s:.1f} s (+ {result.compile_time_s:.1f} s "
          f"compiling), {result.throughput(run_duration):.3g} simulated s per wall s, "
          f"chunks of {result.chunk}", file=sys.stderr)
    if jax.process_index() == 0:
        for path in args.out or ():
            Path(path).parent.mkdir(parents=True, exist_ok=True)
            write_table(path, table)
            print(f"wrote {path}", file=sys.stderr)
        if checkpoint is not None:
            checkpoint.unlink(missing_ok=True)  # the tables hold every row now
        if args.plots:
            from ..plots.montecarlo import plot_distributions, plot_maps

            directory = Path(args.plots)
            directory.mkdir(parents=True, exist_ok=True)
            axes = [v.name for v in variations][:2]
            if len(axes) == 2:
                plot_maps(table, directory / "maps.png", x=axes[0], y=axes[1])
            plot_distributions(table, directory / "distributions.png")
            print(f"wrote figures to {directory}", file=sys.stderr)
    if jax.process_index() == 0:  # every process has the whole table; one writes
        emit_json(study_statistics(result, scenario.name, run_duration), args.summary)
    return 0 if np.all(successful(table)) else 1


def add_parser(commands):
    mc = commands.add_parser(
        "montecarlo", help="many runs of a scenario over drawn speeds, misalignments, parameters")
    scenario_argument(mc)
    mc.add_argument("--samples", type=int, required=True, help="number of samples N")
    mc.add_argument("--vary", action="append", metavar="NAME=SPREAD",
                    help="an input and its spread: lo:hi (uniform), normal:mean,sd, or "
                         "a,b,c; inputs speed [m/s], misalignment [m], or a parameter name "
                         "(friction, contact_stiffness, ...). Repeat for several")
    mc.add_argument("--design", choices=("latin", "random", "grid"), default="latin",
                    help="sampling design (default: latin hypercube)")
    seed_option(mc)
    mc.add_argument("--chunk", type=int, help="samples per compiled batch (default: "
                                              "min(N, 64) on a CPU, min(N, 4096) on a "
                                              "GPU, rounded to the devices)")
    duration_option(mc)
    mc.add_argument("--out", action="append", help="write the table to this .csv or "
                                                   ".parquet file (repeat for both)")
    mc.add_argument("--overwrite", action="store_true",
                    help="start afresh over a checkpoint of another study (OUT.chunks.json, "
                         "the finished chunks kept while the study runs)")
    json_option(mc, "--summary", "JSON statistics")
    plots_option(mc, "write the maps and distributions (PNG) here")
    mc.add_argument("--host-devices", type=int, metavar="N",
                    help="split each chunk over N CPU devices run side by side (e.g. one "
                         "per core; sets XLA_FLAGS, see docs/montecarlo.md)")
    mc.add_argument("--distributed", action="store_true",
                    help="call jax.distributed.initialize first (several hosts)")
    mc.add_argument("--coordinator", help="with --distributed: host:port of process 0")
    mc.add_argument("--num-processes", type=int, help="with --distributed")
    mc.add_argument("--process-id", type=int, help="with --distributed")
    quiet_option(mc)
    contact_option(mc)
    mc.set_defaults(run=montecarlo_command)
