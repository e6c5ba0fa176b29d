"""Many runs of one scenario at once: one vmapped simulation over a batch axis,
sharded across devices, in chunks.

Every sample has its own speed [m/s], initial misalignment [m] and values of named
parameters (:mod:`jaxrail.vehicles.parameters`): the batch is the scenario's
``VehicleParams`` and track with a leading batch axis, written by
``set_values_and_track`` inside the vmapped function (``track_gauge`` is the track's).
A chunk of K samples is one call of a compiled program; all chunks are padded to K
(repeating the last sample, whose copies are dropped), so the program compiles once.
With several devices the chunk is split over them with ``jax.shard_map`` along the
batch axis: each device integrates its own members with its own while loop, with no
communication between devices.

Members are independent: each has its own step sizes, derailment event and diffrax
result code, so one sample that derails or diverges stops alone (its outputs after the
stop are NaN and flagged not valid) and the others run on. The batched while loop
runs until the last member is done, so a batch costs about its slowest member.

Several hosts: call :func:`jax.distributed.initialize` first (``jaxrail montecarlo
--distributed``); ``jax.devices()`` then lists every host's devices, the mesh spans
them, and each host feeds the rows of the chunk that its own devices hold
(docs/montecarlo.md has the commands).
"""

import time

import equinox as eqx
import jax
import numpy as np

from .._devices import over_devices, split_rows, warn_if_devices_may_stall
from . import coordination
from ..compilation import compile_program
from ..vehicles.parameters import set_values_and_track
from ..simulation import DerailmentLimits, SolverOptions, solve

AXIS = "batch"


def sample_track(track, realise, seed, scale):
    """``track`` with one sample's irregularity: the realisation ``realise(seed)`` of its
    spectrum (``realise`` a :class:`~jaxrail.scenarios.irregularities.IrregularitySpec`
    of given length, or None to keep the track's own), times ``scale``; an ideal track
    as it is."""
    if track.irregularity is None:
        return track
    irregularity = track.irregularity if realise is None else realise.realise(seed)
    return track.with_irregularity(eqx.tree_at(lambda i: i.scale, irregularity, scale))


def batched_solve(vehicle, params, track, contact, values, speed, misalignment, seed, scale,
                  *, names, duration, options: SolverOptions,
                  limits: DerailmentLimits | None = None, realise=None):
    """:func:`jaxrail.simulation.solve` of every sample: ``values`` (B, len(names)) of the
    named parameters, ``speed`` (B,) [m/s], ``misalignment`` (B,) [m], the irregularity's
    ``seed`` (B,) and ``scale`` (B,) (:func:`sample_track`, ``realise`` static);
    everything else shared, ``contact`` the contact model (:mod:`jaxrail.vehicles.loads`),
    ``limits`` the :class:`~jaxrail.simulation.DerailmentLimits` (default ones). Returns a
    SimulationResult with a leading batch axis B."""
    def one(v, s, m, k, a):
        p, t = set_values_and_track(vehicle, params, track, names, v)
        return solve(vehicle, p, sample_track(t, realise, k, a), duration, s, m,
                     options=options, limits=limits, contact_model=contact)

    return jax.vmap(one)(values, speed, misalignment, seed, scale)


def _sharded_solve(vehicle, params, track, contact, values, speed, misalignment, seed, scale,
                   *, devices, **static):
    """:func:`batched_solve` with the batch split over ``devices`` (a tuple): each
    device runs its rows alone (:func:`jaxrail._devices.over_devices`), the model
    replicated."""
    return over_devices(lambda *args: batched_solve(*args, **static), devices,
                        (vehicle, params, track, contact),
                        (values, speed, misalignment, seed, scale), AXIS)


_sharded_jit = eqx.filter_jit(_sharded_solve)


BARRIER_TIMEOUT_S = 24 * 3600  # a chunk may run for hours; a dead host ends it sooner


def _host(tree):
    """A (possibly multi-host) result as NumPy on every host. On several hosts they
    first meet at a barrier of the coordination service (a new one per gather): the
    gather's first collective sets up Gloo and fails when a host comes more
    than 30 s after another (compiling or integrating longer), a limit that
    ``--xla_cpu_collective_timeout_seconds`` does not change
    (:mod:`jaxrail.montecarlo.coordination`)."""
    if jax.process_count() == 1:
        return jax.tree.map(np.asarray, tree)
    from jax.experimental import multihost_utils

    coordination.client().wait_at_barrier(coordination.next_key("gather"),
                                          BARRIER_TIMEOUT_S * 1000)
    return jax.tree.map(np.asarray, multihost_utils.process_allgather(tree, tiled=True))


# Samples per chunk by platform, DEFAULT_CHUNK_ELSEWHERE on the others. On a GPU a
# batch's run time grows far slower than its size (an H200: 2.7 s for 256 members of
# bogie-curve-entry, 9.2 s for 4096, online), so chunks there are large
# (docs/montecarlo.md, "On a GPU").
DEFAULT_CHUNK = {"cpu": 64}
DEFAULT_CHUNK_ELSEWHERE = 4096


def chunk_size(requested, n_samples, n_devices, platform="cpu"):
    """The chunk actually used: ``requested`` (default: all samples, at most 64 on a
    CPU and 4096 on other platforms, :data:`DEFAULT_CHUNK`) rounded up to a multiple of
    the number of devices."""
    limit = DEFAULT_CHUNK.get(platform, DEFAULT_CHUNK_ELSEWHERE)
    k = min(n_samples, limit) if requested is None else int(requested)
    if k < 1:
        raise ValueError(f"chunk must be >= 1, got {requested}")
    return -(-k // n_devices) * n_devices


def run_chunks(model, inputs, chunk, devices=None, progress=False, on_chunk=None, done=None,
               **static):
    """Run :func:`batched_solve` on ``model`` = (vehicle, params, track, contact model) and
    ``inputs`` = (values, speed, misalignment, seed, scale) host arrays with a common
    leading axis N, in chunks of ``chunk`` rows (the last one padded), sharded over
    ``devices`` (default: all); ``static``: names, duration, options, limits, realise.
    ``on_chunk(start, stop, result)`` receives each chunk's host result without the
    padding. ``done`` (N,) bool: samples already run (a chunk of only those is
    skipped). The compiled program is cached per structure, options and chunk
    (:func:`jaxrail.compilation.compile_program`, as for
    :func:`jaxrail.simulation.simulate`): a second study of the same vehicle does not
    recompile. Returns (compile time [s], 0 if cached; run time [s]; the chunk used,
    :func:`chunk_size`)."""
    devices = tuple(jax.devices() if devices is None else devices)
    warn_if_devices_may_stall(devices, jax.process_index())
    n = len(inputs[0])
    chunk = chunk_size(chunk, n, len(devices), devices[0].platform)
    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=n, unit="sample", desc="montecarlo", ncols=100)
    compile_s, run_s = 0.0, 0.0
    for start in range(0, n, chunk):
        stop = min(start + chunk, n)
        if done is not None and np.all(done[start:stop]):
            if bar is not None:
                bar.update(stop - start)
            continue
        rows = np.concatenate([np.arange(start, stop), np.full(chunk - (stop - start), stop - 1)])
        args = model + tuple(split_rows(np.asarray(x)[rows], devices, AXIS) for x in inputs)
        compiled, seconds = compile_program(_sharded_jit, *args, devices=devices, **static)
        compile_s += seconds
        t0 = time.perf_counter()
        result = jax.block_until_ready(compiled(*args, devices=devices, **static))
        run_s += time.perf_counter() - t0
        host = jax.tree.map(lambda x: x[: stop - start], _host(result))
        if on_chunk is not None:
            on_chunk(start, stop, host)
        if bar is not None:
            bar.update(stop - start)
    if bar is not None:
        bar.close()
    return compile_s, run_s, chunk
