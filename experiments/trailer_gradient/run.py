"""Gradients through a whole trailer simulation (initial equilibrium, contact search,
forces, diffrax with recursive checkpointing) against central differences.

The loss is the leading wheelset's lateral displacement [mm] at the end of a run at
18.3 m/s from a 2 mm misalignment on straight track; the parameters are the contact
stiffness scale and the friction coefficient. Prints JSON: the loss, its gradient,
the central differences (relative step ``--step``), their relative difference, and the
compile and run times of the gradient and of a forward run.
Usage: ``python experiments/trailer_gradient/run.py [--duration 1.0] [--rtol 1e-3]
[--step 1e-3]``.
"""

import argparse
import json
import time

import equinox as eqx
import jax
import jax.numpy as jnp

from jaxrail import enable_float64

enable_float64()

from jaxrail.simulation import SolverOptions, solve  # noqa: E402
from jaxrail.track import straight_track  # noqa: E402
from jaxrail.vehicles import trailer  # noqa: E402


def timed(function, *args):
    start = time.perf_counter()
    compiled = function.lower(*args).compile()
    compile_time = time.perf_counter() - start
    start = time.perf_counter()
    out = jax.block_until_ready(compiled(*args))
    return compiled, out, compile_time, time.perf_counter() - start


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--duration", type=float, default=1.0, help="[s]")
    parser.add_argument("--rtol", type=float, default=1e-3)
    parser.add_argument("--step", type=float, default=1e-3, help="relative FD step")
    args = parser.parse_args()
    vehicle, params = trailer()
    track = straight_track(18.3 * args.duration + 60.0)
    options = SolverOptions(rtol=args.rtol, atol=args.rtol * 1e-3, n_outputs=2,
                            max_steps=200_000)

    def loss(x):
        p = eqx.tree_at(lambda p: (p.contact.stiffness_scale, p.contact.friction), params,
                        (x[0], x[1]))
        return 1e3 * solve(vehicle, p, track, args.duration, 18.3, 2e-3,
                           options=options).wheelset_lateral[-1, 0]

    x = jnp.array([1.0, 0.4])
    _, (value, grad), grad_compile, grad_run = timed(jax.jit(jax.value_and_grad(loss)), x)
    forward, _, forward_compile, forward_run = timed(jax.jit(loss), x)
    differences = []
    for i in range(2):
        h = args.step * float(x[i])
        e = jnp.zeros(2).at[i].set(h)
        differences.append(float((forward(x + e) - forward(x - e)) / (2 * h)))
    print(json.dumps({
        "duration_s": args.duration, "rtol": args.rtol, "atol": args.rtol * 1e-3,
        "parameters": ["stiffness_scale", "friction"], "at": [1.0, 0.4],
        "loss_mm": float(value), "gradient": [float(g) for g in grad],
        "central_differences": differences, "relative_step": args.step,
        "relative_difference": [abs(float(g) - d) / abs(d) for g, d in zip(grad, differences)],
        "gradient_finite": bool(jnp.all(jnp.isfinite(grad))),
        "gradient_compile_s": round(grad_compile, 1), "gradient_run_s": round(grad_run, 2),
        "forward_compile_s": round(forward_compile, 1), "forward_run_s": round(forward_run, 2),
        "gradient_over_forward": round(grad_run / forward_run, 2),
    }, indent=2))


if __name__ == "__main__":
    main()
