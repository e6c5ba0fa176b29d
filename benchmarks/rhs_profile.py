"""Where the time of one right-hand-side evaluation goes, per contact model.

For each contact model (``online``, the paper's search, and ``table``, its table, built
and cached first if needed, with the build time reported) the median cost of one
evaluation at the initial state of a scenario (default ``paper-curve``, the trailer),
with the parameters traced, measured as the integrator runs it: inside a compiled loop
of 50 evaluations, median of ``--calls`` loops (``single_call_us``: the median of ten
times as many jitted calls from Python, which add the dispatch and run the program
outside a loop; several times slower for these small programs):

- ``contact_us``: the contact patches of all wheels (the search, or the table lookup);
- ``loads_us``: the patches and the force laws (:func:`jaxrail.vehicles.contact_loads`);
  ``force_laws_us`` is its difference to ``contact_us``;
- ``multibody_us``: eq. (19) without wheel-rail loads (mass matrix, constraints,
  force elements, the solve);
- ``rhs_median_us``: the whole right-hand side (:func:`jaxrail.vehicles.vehicle_accelerations`);
  ``xla_defaults_us``: the same compiled with XLA's default options instead;
- ``imex_step_us``: one whole step of the IMEX integrator (KenCarp5, 1 ms: the load
  Jacobian, the inverse of the step's matrix and 8 right-hand sides), in the same loop;
  ``imex_step_kept_jacobian_us``: a step that keeps an earlier Jacobian (turned with the
  wheelsets, as 7 of 8 steps do with ``jacobian_every=8``); and two of
  its parts: ``imex_jacobian_us``, the right-hand side with the stiff Jacobian
  (:func:`jaxrail.multibody.imex.stiff_jacobian`: the loads, their Jacobian per
  wheelset and the accelerations' response to it), and ``projection_us``, the
  projection of the state onto the joints that ends each step;
- ``compile_s``: the compile time of each of these programs;
- ``operations``: the operations of each looped program that XLA:CPU runs as thunks
  (``jaxrail._hlo_operations``: fused kernels and unfused operations of the
  optimised HLO, each inner loop's body once), ``force_laws`` the difference of
  ``loads`` and ``contact``; ``us_per_operation``: the time per evaluation over them;
  ``operations_by_kind``: by HLO opcode;
- ``element_operations``: the work inside those operations, per looped program
  (:func:`jaxrail._hlo_operations.element_counts`: the elements the optimised HLO's
  instructions write, fused or not: ``arithmetic``, ``data_movement`` that writes
  memory and ``remapped_in_fusions``, each inner loop's body once), and ``elements_by_kind`` of the right-hand side (the 15 largest);
- ``arithmetic_by_source``: the right-hand side's arithmetic element operations by the
  jaxrail file and function that traced them (:func:`jaxrail._hlo_operations.arithmetic_by_source`,
  the 20 largest; ``unattributed`` where XLA dropped an instruction's metadata).

With ``--kernels``, per contact model the kernels of the right-hand side's and the IMEX
step's loops as XLA:CPU runs them (:func:`jaxrail._kernel_profile.kernel_profile`: each
kernel's share of the traced time and its executions per evaluation, the 25 largest;
at most ``KERNEL_CALLS`` runs of each loop):
``kernels``. The process then runs with XLA's thunk tracing on (it starts itself again
with the flag).

Each on rigid rails and on the co-moving flexible track (``--supports rigid flexible``,
its default values, :mod:`jaxrail.track.flexible`): there the loads and the right-hand
side also take the rails' state, at their rest deflection, and the right-hand side
returns the rails' derivatives too.

With ``--batch N`` also the whole right-hand side vmapped over N states (the initial
one with the whole vehicle shifted along the global y axis by 0-4 mm), per member.
Prints one JSON object with an object per track support, each with one per model, and
``online_over_table`` and ``flexible_over_rigid`` (whole right-hand sides).
Usage: ``python benchmarks/rhs_profile.py [--calls 40] [--scenario S] [--batch N]
[--supports rigid flexible] [--xla-defaults] [--kernels]`` (``--xla-defaults``: every program with
XLA's default options instead of jaxrail's, e.g. on a jaxlib that does not know them).
"""

import argparse
import json
import os
import statistics
import sys
import time

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp

from jaxrail import enable_float64
from jaxrail.compilation import compiler_options
from jaxrail._hlo_operations import arithmetic_by_source, element_counts, operation_counts
from jaxrail._kernel_profile import TRACE_FLAG, kernel_profile, tracing_enabled

enable_float64()

from jaxrail.multibody import State, accelerations, rhs as multibody_rhs  # noqa: E402
from jaxrail.multibody.imex import IMEX, stiff_jacobian  # noqa: E402
from jaxrail.multibody import project_state  # noqa: E402
from jaxrail.scenarios import load_scenario  # noqa: E402
from jaxrail.contact.table_cache import contact_table  # noqa: E402
from jaxrail.track import FlexibleTrack  # noqa: E402
from jaxrail.vehicles import (OnlineContact, TableContact, VehicleLoads,  # noqa: E402
                              contact_loads, initial_state, vehicle_accelerations)
from jaxrail.vehicles.vehicle import wheelset_states  # noqa: E402


LOOP_REPEATS = 50
# Runs of a loop under the thunk trace: its events are kept in memory (the online
# search's 40 runs, 2000 evaluations of thousands of kernels each, filled 24 GiB).
KERNEL_CALLS = 4
IMEX_STEP = 1e-3  # [s] about the IMEX steps of the paper's curve


def _median_call_s(compiled, args, calls):
    jax.block_until_ready(compiled(*args))
    times = []
    for _ in range(calls):
        start = time.perf_counter()
        jax.block_until_ready(compiled(*args))
        times.append(time.perf_counter() - start)
    return statistics.median(times)


# jaxrail's compiler options, or none (``--xla-defaults``)
_options = compiler_options


def timed(function, args, calls):
    """(median run time [us], compile time [s]) of ``jax.jit(function)(*args)``."""
    start = time.perf_counter()
    compiled = jax.jit(function).lower(*args).compile(_options())
    compile_s = time.perf_counter() - start
    return 1e6 * _median_call_s(compiled, args, calls), compile_s


def compiled_loop(function, args, repeats=LOOP_REPEATS, options=None):
    """``function(q, qdot, data)`` evaluated ``repeats`` times in a compiled loop, as the
    integrator runs it, compiled for ``args`` with jaxrail's compiler options
    (:mod:`jaxrail.compilation.compiler`; none with ``--xla-defaults``) or ``options``; the loop
    returns the sum of all outputs.

    Each evaluation sees the state moved by a tiny multiple of the previous outputs,
    so that nothing is hoisted out of the loop.
    """

    def loop(q, qdot, data):
        def body(_, carry):
            nudge = 1e-15 * carry
            out = function(q + nudge, qdot + nudge, data)
            return carry + sum(jnp.sum(leaf) for leaf in jax.tree_util.tree_leaves(out))
        return jax.lax.fori_loop(0, repeats, body, jnp.zeros(()))

    options = _options() if options is None else options
    return jax.jit(loop).lower(*args).compile(options)


def timed_in_loop(function, args, calls, repeats=LOOP_REPEATS, options=None):
    """(median run time [us] of one evaluation of ``function(q, qdot, data)`` inside
    :func:`compiled_loop` (median of ``calls`` runs of the loop), its
    :func:`operation_counts`, its :func:`element_counts`, the compiled loop)."""
    compiled = compiled_loop(function, args, repeats, options)
    return (1e6 * _median_call_s(compiled, args, calls) / repeats, operation_counts(compiled),
            element_counts(compiled), compiled)


def kernels_in_loop(compiled, args, calls, repeats=LOOP_REPEATS):
    """:func:`kernel_profile` of ``calls`` runs of a :func:`compiled_loop` program."""
    def run():
        for _ in range(calls):
            jax.block_until_ready(compiled(*args))
    return kernel_profile(run, calls * repeats, top=25)


def profile_model(model, vehicle, params, track, q, qdot, rails, calls, batch, kernels=False):
    """The JSON object of one contact model. Everything but the structure is traced,
    as in :func:`jaxrail.simulation.simulate` (the profiles, the track, the parameters
    and the contact table are arguments of the compiled program, not constants).
    ``rails``: a flexible track's rails ``(w, wdot)``, or None on rigid rails."""
    data, structure = eqx.partition((vehicle, params, track, model, rails), eqx.is_array)

    def parts_of(function):
        return lambda q, qdot, data: function(q, qdot, *eqx.combine(data, structure))

    @parts_of
    def contact(q, qdot, vehicle, params, track, model, rails):
        position, rotation, _, _ = wheelset_states(vehicle, q, qdot)
        if rails is None:
            return jax.vmap(lambda r, a: model.wheelset_patches(vehicle, params, track, r,
                                                                a))(position, rotation)
        return jax.vmap(lambda r, a, w: model.wheelset_patches(
            vehicle, params, track, r, a, w))(position, rotation, rails[0])

    @parts_of
    def loads(q, qdot, vehicle, params, track, model, rails):
        return contact_loads(vehicle, params, track, q, qdot, model, rails)[:2]

    @parts_of
    def multibody(q, qdot, vehicle, params, track, model, rails):
        return accelerations(vehicle.system, params.system, 0.0, q, qdot)[0]

    @parts_of
    def rhs(q, qdot, vehicle, params, track, model, rails):
        if rails is None:
            return vehicle_accelerations(vehicle, params, track, 0.0, q, qdot, model)
        loads = VehicleLoads(vehicle, params, track, model)
        return multibody_rhs(0.0, State.of(q, qdot, rails), loads)

    @parts_of
    def imex_step(q, qdot, vehicle, params, track, model, rails):
        loads = VehicleLoads(vehicle, params, track, model)
        y0 = State.of(q, qdot, rails)
        return IMEX().step(diffrax.ODETerm(multibody_rhs), 0.0, IMEX_STEP, y0, loads, None,
                           False)[0]

    @parts_of
    def imex_jacobian(q, qdot, vehicle, params, track, model, rails):
        loads = VehicleLoads(vehicle, params, track, model)
        return stiff_jacobian(0.0, State.of(q, qdot, rails), loads)

    # a load Jacobian at the start, for a step that keeps it (IMEX's jacobian_every)
    kept = jax.jit(imex_jacobian)(q, qdot, data)[1]

    @parts_of
    def imex_step_kept(q, qdot, vehicle, params, track, model, rails):
        loads = VehicleLoads(vehicle, params, track, model)
        y0 = State.of(q, qdot, rails)
        solver, term, args = IMEX(jacobian_every=8), diffrax.ODETerm(multibody_rhs), loads
        euler = solver.init(term, 0.0, IMEX_STEP, y0, args)[2]
        # one step old: kept and turned; an age known only at run time, as in a run (a
        # constant one would let XLA drop the Jacobian's branch from the program)
        age = jnp.where(q[0] > 1e30, 8, 1).astype(jnp.int32)
        state = (kept, age, euler)
        return solver.step(term, 0.0, IMEX_STEP, y0, args, state, False)[0]

    @parts_of
    def projection(q, qdot, vehicle, params, track, model, rails):
        return project_state(vehicle.system, params.system, q, qdot)

    args = (q, qdot, data)
    programs = (("contact", contact), ("loads", loads), ("multibody", multibody), ("rhs", rhs))
    step_parts = (("imex_jacobian", imex_jacobian), ("projection", projection),
                  ("imex_step", imex_step), ("imex_step_kept", imex_step_kept))
    parts = {name: timed(f, args, 10 * calls) for name, f in programs}
    looped = {name: timed_in_loop(f, args, calls) for name, f in programs + step_parts}
    us = {name: value[0] for name, value in looped.items()}
    out = {
        "rhs_median_us": round(us["rhs"], 1),
        "contact_us": round(us["contact"], 1),
        "force_laws_us": round(us["loads"] - us["contact"], 1),
        "loads_us": round(us["loads"], 1),
        "multibody_us": round(us["multibody"], 1),
        "imex_step_us": round(us["imex_step"], 1),
        "imex_step_kept_jacobian_us": round(us["imex_step_kept"], 1),
        "imex_jacobian_us": round(us["imex_jacobian"], 1),
        "projection_us": round(us["projection"], 1),
        "xla_defaults_us": round(timed_in_loop(rhs, args, calls, options={})[0], 1),
        "single_call_us": {name: round(value[0], 1) for name, value in parts.items()},
        "compile_s": {name: round(value[1], 2) for name, value in parts.items()},
        "operations": {name: value[1]["operations"] for name, value in looped.items()},
        "us_per_operation": {name: round(value[0] / value[1]["operations"], 3)
                             for name, value in looped.items()},
        "operations_by_kind": {name: value[1]["by_kind"] for name, value in looped.items()},
        "element_operations": {name: {k: value[2][k] for k in ("arithmetic", "data_movement",
                                                               "remapped_in_fusions")}
                               for name, value in looped.items()},
        "elements_by_kind": dict(list(looped["rhs"][2]["by_kind"].items())[:15]),
        "arithmetic_by_source": dict(list(arithmetic_by_source(looped["rhs"][3]).items())[:20]),
    }
    if kernels:
        out["kernels"] = {name: kernels_in_loop(looped[name][3], args, min(calls, KERNEL_CALLS))
                          for name in ("rhs", "imex_step")}
    out["operations"]["force_laws"] = out["operations"]["loads"] - out["operations"]["contact"]
    if batch:
        shifts = jnp.linspace(0.0, 4e-3, batch)
        q_batch = jax.vmap(lambda d: q.reshape(-1, 7).at[:, 1].add(d).reshape(-1))(shifts)
        qdot_batch = jnp.broadcast_to(qdot, (batch,) + qdot.shape)
        batched = jax.vmap(rhs, in_axes=(0, 0, None))
        member = timed_in_loop(batched, (q_batch, qdot_batch, data), calls)[0] / batch
        out.update(batch=batch, rhs_per_member_us=round(member, 1),
                   one_over_member=round(us["rhs"] / member, 3))
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--calls", type=int, default=40)
    parser.add_argument("--scenario", default="paper-curve")
    parser.add_argument("--batch", type=int, default=0, help="members of a vmapped batch")
    parser.add_argument("--supports", nargs="+", default=["rigid", "flexible"],
                        choices=("rigid", "flexible"))
    parser.add_argument("--kernels", action="store_true",
                        help="also each kernel's share of the time (XLA's thunk trace)")
    parser.add_argument("--xla-defaults", action="store_true",
                        help="compile every part with XLA's default options, none of "
                             "jaxrail's (e.g. on a jaxlib that does not know them)")
    args = parser.parse_args()
    if args.kernels and not tracing_enabled():  # the flag is read when the backend starts
        os.environ["XLA_FLAGS"] = os.environ.get("XLA_FLAGS", "") + " " + TRACE_FLAG
        os.execv(sys.executable, [sys.executable, *sys.argv])
    if args.xla_defaults:
        global _options
        _options = dict
    scenario = load_scenario(args.scenario)
    vehicle, params, track = scenario.build()
    table, table_info = contact_table(params.wheel, track.rails, vehicle.config, progress=True)
    models = {"online": OnlineContact(), "table": TableContact(table)}
    results, ratios = {}, {"online_over_table": {}, "flexible_over_rigid": {}}
    for support in args.supports:
        on = track.with_support(FlexibleTrack() if support == "flexible" else None)
        state = jax.jit(lambda p, t: initial_state(vehicle, p, t, scenario.speed,
                                                   scenario.misalignment))(params, on)
        results[support] = {name: profile_model(model, vehicle, params, on, state.q,
                                                state.qdot, state.track, args.calls, args.batch,
                                                args.kernels)
                            for name, model in models.items()}
        ratios["online_over_table"][support] = round(
            results[support]["online"]["rhs_median_us"]
            / results[support]["table"]["rhs_median_us"], 2)
    if len(results) == 2:
        ratios["flexible_over_rigid"] = {name: round(
            results["flexible"][name]["rhs_median_us"] / results["rigid"][name]["rhs_median_us"],
            2) for name in models}
    table = {key: table_info[key] for key in
             ("build_time_s", "cached", "nodes", "level_misses", "path") if key in table_info}
    print(json.dumps({
        "benchmark": "rhs_profile", "scenario": scenario.name, "calls": args.calls,
        **results, "table": table, **ratios, "load": os.getloadavg(),
        "jnp_dtype": str(jnp.zeros(1).dtype), "jax": jax.__version__,
        "compiler_options": "xla defaults" if args.xla_defaults else "jaxrail",
        "thunk_tracing": tracing_enabled(),
    }, indent=2))


if __name__ == "__main__":
    main()
