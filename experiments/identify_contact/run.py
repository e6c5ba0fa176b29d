"""Identification study: contact stiffness scale and friction of the bogie-curve-entry
scenario from synthetic measurements (docs/identification.md).

``python experiments/identify_contact/run.py gradient OUT`` checks the gradient of the
fit's loss with respect to five parameters (contact stiffness, friction, restitution,
primary lateral stiffness, primary vertical damping; ``--parameters a,b`` for fewer)
against central differences (relative steps ``--steps``, default 1e-4,1e-5,1e-6).
``python experiments/identify_contact/run.py fit OUT`` fits stiffness and friction
from initial guesses 30 % off, on noise-free and on noisy measurements.
``python experiments/identify_contact/run.py batch OUT`` checks that the gradient of a
vmapped loss (three misalignments, 0.2 s) equals the sum of the members' gradients.
Both write JSON into the directory OUT (``fit`` also the measurements CSV files and a
figure per fit; ``--only noise_free|noisy`` runs one of the two fits).
``--integrator imex --fixed-step 1e-3`` replaces the scenario's solver (Tsit5, 0.5 ms)
for truth, gradients and fits alike.
"""

import argparse
import dataclasses
import json
import time
from pathlib import Path

import diffrax
import jax
import jax.numpy as jnp
import numpy as np

from jaxrail import enable_float64

enable_float64()

from jaxrail.identification.fit import loss_gradient_jacobian  # noqa: E402
from jaxrail.identification import (Measurements, get_values, identify,  # noqa: E402
                              set_values, simulate_channels, simulation_residuals,
                              write_measurements)
from jaxrail.plots.identification import plot_identification  # noqa: E402
from jaxrail.scenarios import load_scenario  # noqa: E402
from jaxrail.simulation import solve  # noqa: E402

SCENARIO = "bogie-curve-entry"
CHANNELS = {  # channel: noise standard deviation (realistic sensor scatter)
    "wheelset_lateral_1": 1e-4,  # [m] 0.1 mm, laser displacement sensor
    "wheelset_yaw_1": 1e-4,  # [rad] 0.1 mrad
    "wheel_lateral_force_1_right": 2e3,  # [N] instrumented wheelset, ~3 % of Q
    "wheel_vertical_force_1_right": 2e3,  # [N]
    "lateral_acceleration_frame": 0.05,  # [m/s^2] accelerometer on the bogie frame
}
SAMPLE_RATE = 100.0  # [Hz]
FIT = ("contact_stiffness", "friction")
GRADIENT = ("contact_stiffness", "friction", "restitution", "primary_lateral_stiffness",
            "primary_vertical_damping")
OFF_GRADIENT = {"contact_stiffness": 1.3, "friction": 0.7, "restitution": 0.9,
                "primary_lateral_stiffness": 1.2, "primary_vertical_damping": 0.8}
OFF = np.array([1.3, 0.7])  # initial guesses: stiffness 30 % high, friction 30 % low
SEED = 2026
SOLVER = {}  # scenario solver overrides from the command line (integrator, fixed_step)


def scenario_of_study():
    """The study's scenario with the command line's solver overrides."""
    return dataclasses.replace(load_scenario(SCENARIO), **SOLVER)


def truth(scenario):
    """Noise-free measurements of the scenario with its own (true) parameters."""
    vehicle, params, track = scenario.build()
    times = np.linspace(0.0, scenario.duration, int(round(scenario.duration * SAMPLE_RATE)) + 1)
    start = time.perf_counter()
    values = jax.jit(lambda p: simulate_channels(
        vehicle, p, track, tuple(CHANNELS), times, speed=scenario.speed,
        misalignment=scenario.misalignment, duration=scenario.duration,
        options=scenario.solver_options()))(params)
    values = np.asarray(values)
    print(f"truth simulated in {time.perf_counter() - start:.1f} s (with compile)", flush=True)
    return (vehicle, params, track), Measurements(times, tuple(CHANNELS), values,
                                                  np.array(list(CHANNELS.values())))


def gradient_check(out: Path, steps=(1e-4, 1e-5, 1e-6), names=GRADIENT, mode="reverse"):
    scenario = scenario_of_study()
    built, measured = truth(scenario)
    vehicle, params, track = built
    common = dict(speed=scenario.speed, misalignment=scenario.misalignment,
                  duration=scenario.duration, options=scenario.solver_options())
    residuals = simulation_residuals(vehicle, params, track, names, measured, **common)
    data = jnp.asarray(measured.values)
    loss = lambda v: 0.5 * jnp.sum(residuals(v, data) ** 2)  # noqa: E731
    if mode == "forward":  # J^T r with J by one forward-mode product per parameter
        forward = simulation_residuals(vehicle, params, track, names, measured, forward=True,
                                       **common)

        def loss_and_gradient(v):
            return loss_gradient_jacobian(lambda v: forward(v, data), v)[:2]
    else:
        loss_and_gradient = jax.value_and_grad(loss)
    truth_values = np.asarray(get_values(vehicle, params, names))
    at = truth_values * np.array([OFF_GRADIENT[n] for n in names])
    start = time.perf_counter()
    value_and_grad = jax.jit(loss_and_gradient).lower(jnp.asarray(at)).compile()
    grad_compile = time.perf_counter() - start
    start = time.perf_counter()
    value, grad = jax.block_until_ready(value_and_grad(jnp.asarray(at)))
    grad_run = time.perf_counter() - start
    start = time.perf_counter()
    forward = jax.jit(loss).lower(jnp.asarray(at)).compile()
    forward_compile = time.perf_counter() - start
    report = {"scenario": SCENARIO, "mode": mode, "parameters": list(names), "at": at.tolist(),
              "truth": truth_values.tolist(), "loss": float(value),
              "gradient": np.asarray(grad).tolist(), "gradient_compile_s": grad_compile,
              "gradient_run_s": grad_run, "forward_compile_s": forward_compile,
              "central_differences": {}}
    forward_runs = []
    for step in steps:
        fd = []
        for i in range(len(names)):
            h = step * at[i]
            e = np.zeros(len(names))
            e[i] = h
            t0 = time.perf_counter()
            up, down = float(forward(jnp.asarray(at + e))), float(forward(jnp.asarray(at - e)))
            forward_runs.append(0.5 * (time.perf_counter() - t0))
            fd.append((up - down) / (2 * h))
        fd = np.array(fd)
        report["central_differences"][str(step)] = {
            "values": fd.tolist(),
            "relative_difference": (np.abs(np.asarray(grad) - fd) / np.abs(fd)).tolist()}
        print(json.dumps(report["central_differences"][str(step)]), flush=True)
    report["forward_run_s_median"] = float(np.median(forward_runs))
    report["gradient_over_forward"] = grad_run / float(np.median(forward_runs))
    name = "gradient_check.json" if mode == "reverse" else "gradient_check_forward.json"
    (out / name).write_text(json.dumps(report, indent=2) + "\n")
    print(json.dumps(report, indent=2))


def noisy_measurements(clean, seed):
    """``clean`` plus Gaussian noise of its channels' levels (seed ``seed``)."""
    rng = np.random.default_rng(seed)
    return Measurements(clean.time, clean.channels,
                        clean.values + clean.noise * rng.standard_normal(clean.values.shape),
                        clean.noise)


def fits(out: Path, which=("noise_free", "noisy"), max_iterations=15, seeds=(SEED,)):
    """The noise-free fit and one noisy fit per seed (labelled ``noisy`` for the study's
    seed, ``noisy_seed<N>`` for others)."""
    scenario = scenario_of_study()
    built, clean = truth(scenario)
    truth_values = np.asarray(get_values(built[0], built[1], FIT))
    initial = dict(zip(FIT, truth_values * OFF))
    report = {"scenario": SCENARIO, "truth": dict(zip(FIT, truth_values.tolist())),
              "initial": {k: float(v) for k, v in initial.items()}, "channels": CHANNELS,
              "sample_rate_hz": SAMPLE_RATE}
    runs = [("noise_free", clean, None)] if "noise_free" in which else []
    if "noisy" in which:
        runs += [("noisy" if seed == SEED else f"noisy_seed{seed}",
                  noisy_measurements(clean, seed), seed) for seed in seeds]
    for label, measurements, seed in runs:
        report["seed"] = seed
        write_measurements(out / f"measurements_{label}.csv", measurements,
                           comment=f"synthetic {label} measurements of {SCENARIO} "
                                   f"(experiments/identify_contact/run.py, seed {seed})")
        start = time.perf_counter()
        result = identify(scenario, measurements, FIT, initial=initial,
                          max_iterations=max_iterations, progress=True, built=built)
        summary = result.as_dict()
        summary["wall_time_s"] = time.perf_counter() - start
        summary["error_relative_to_truth"] = (result.fit.values / truth_values - 1.0).tolist()
        summary["error_in_standard_errors"] = (
            (result.fit.values - truth_values) / result.fit.standard_error).tolist()
        report[label] = summary
        print(label, json.dumps({k: summary[k] for k in (
            "parameters", "iterations", "converged", "error_relative_to_truth",
            "error_in_standard_errors", "wall_time_s", "reduced_chi2")}, indent=1), flush=True)
        (out / f"fit_{label}.json").write_text(json.dumps(report | {label: summary},
                                                           indent=2) + "\n")
        plot_identification(result, out / f"fit_{label}.png",
                            truth=dict(zip(FIT, truth_values)))


def batch_check(out: Path, misalignments=(1e-3, 2e-3, 3e-3), duration=0.2):
    """grad of a vmapped loss (one member per initial misalignment, the parameters
    shared) against the sum of the members' gradients, through the whole simulation."""
    scenario = scenario_of_study()
    vehicle, params, track = scenario.build()
    options = scenario.solver_options(duration=duration)

    def member(values, misalignment):
        p = set_values(vehicle, params, FIT, values)
        result = solve(vehicle, p, track, duration, scenario.speed, misalignment,
                       options=options, adjoint=diffrax.RecursiveCheckpointAdjoint(
                           checkpoints=options.max_steps))
        return jnp.sum(result.wheelset_lateral[:, 0] ** 2) * 1e6  # [mm^2]

    x = jnp.array([1.1, 0.35])
    shifts = jnp.asarray(misalignments)
    start = time.perf_counter()
    batched = jax.jit(jax.grad(lambda v: jnp.sum(jax.vmap(lambda m: member(v, m))(shifts))))(x)
    batched_s = time.perf_counter() - start
    single = jax.jit(jax.grad(member))
    start = time.perf_counter()
    members = [np.asarray(single(x, m)) for m in shifts]
    members_s = time.perf_counter() - start
    total = np.sum(members, axis=0)
    report = {"scenario": SCENARIO, "duration_s": duration, "parameters": list(FIT),
              "at": x.tolist(), "misalignments_m": list(misalignments),
              "batched_gradient": np.asarray(batched).tolist(),
              "sum_of_member_gradients": total.tolist(),
              "relative_difference": (np.abs(np.asarray(batched) - total)
                                      / np.abs(total)).tolist(),
              "batched_s_with_compile": batched_s, "members_s_with_compile": members_s}
    (out / "batch_check.json").write_text(json.dumps(report, indent=2) + "\n")
    print(json.dumps(report, indent=2))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("what", choices=("gradient", "fit", "batch"))
    parser.add_argument("out", type=Path)
    parser.add_argument("--only", choices=("noise_free", "noisy"),
                        help="fit: only this data set")
    parser.add_argument("--iterations", type=int, default=15, help="fit: maximum iterations")
    parser.add_argument("--seeds", default=str(SEED),
                        help="fit: noise seeds of the noisy fits, comma-separated")
    parser.add_argument("--parameters", default=",".join(GRADIENT),
                        help="gradient: the parameters (default: all five)")
    parser.add_argument("--steps", default="1e-4,1e-5,1e-6",
                        help="gradient: relative steps of the differences")
    parser.add_argument("--mode", choices=("reverse", "forward"), default="reverse",
                        help="gradient: by reverse mode or by forward mode (J^T r)")
    parser.add_argument("--integrator", choices=("tsit5", "imex"),
                        help="replace the scenario's integrator")
    parser.add_argument("--fixed-step", type=float, help="replace the scenario's step [s]")
    args = parser.parse_args()
    SOLVER.update({k: v for k, v in (("integrator", args.integrator),
                                     ("fixed_step", args.fixed_step)) if v is not None})
    args.out.mkdir(parents=True, exist_ok=True)
    if args.what == "gradient":
        gradient_check(args.out, tuple(float(h) for h in args.steps.split(",")),
                       tuple(args.parameters.split(",")), args.mode)
    elif args.what == "batch":
        batch_check(args.out)
    else:
        fits(args.out, (args.only,) if args.only else ("noise_free", "noisy"),
             max_iterations=args.iterations,
             seeds=tuple(int(seed) for seed in args.seeds.split(",")))


if __name__ == "__main__":
    main()
