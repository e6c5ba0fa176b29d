"""Several XLA devices on one CPU, set up so that they run side by side.

XLA shows one CPU device unless ``--xla_force_host_platform_device_count`` asks for
more. Those devices share the CPU client's thread pool, a thread per core unless the
environment variable ``NPROC`` sets another size, and each device's program holds one
of its threads while it runs. A batched LAPACK call (the LU of every member's
equations of motion) splits its batch over the same pool and waits for it
(``jax::ParallelBatchMap``). With two devices on two cores each program waits for a
thread the other holds: one device stalls until the other's program ends, or both wait
forever (``tests/montecarlo/test_devices.py``: a sharded loop of batched solves hangs
at once with a 2-thread pool and runs with 4; docs/montecarlo.md). A pool of one thread per core plus one per
device leaves threads free for the batched kernels. ``--xla_cpu_multi_thread_eigen=false``
(Eigen's own kernels single-threaded) is set too; on its own it does not prevent the
hang.
"""

import os

FORCE_DEVICES = "--xla_force_host_platform_device_count"
SINGLE_THREADED_OPS = "--xla_cpu_multi_thread_eigen=false"
POOL_THREADS = "NPROC"  # read by XLA's CPU client for the size of its thread pool


def host_device_flags(count: int, flags: str = "") -> str:
    """``flags`` (an XLA_FLAGS value) with ``count`` host devices (any earlier device
    count replaced)."""
    if int(count) < 1:
        raise ValueError(f"host devices: need a count >= 1, got {count}")
    kept = [f for f in flags.split() if not f.startswith((FORCE_DEVICES, SINGLE_THREADED_OPS))]
    extra = [f"{FORCE_DEVICES}={int(count)}"] + ([SINGLE_THREADED_OPS] if count > 1 else [])
    return " ".join(kept + extra)


def host_device_environment(count: int, environ=None) -> dict[str, str]:
    """The environment variables (``XLA_FLAGS``, and ``NPROC`` for several devices) of
    a process with ``count`` host devices that run side by side; ``environ`` (default
    ``os.environ``) gives the flags to keep."""
    environ = os.environ if environ is None else environ
    updates = {"XLA_FLAGS": host_device_flags(count, environ.get("XLA_FLAGS", ""))}
    if count > 1:
        updates[POOL_THREADS] = str((os.cpu_count() or 1) + int(count))
    return updates


def use_host_devices(count: int) -> None:
    """Ask XLA for ``count`` CPU devices that run side by side (sets ``XLA_FLAGS`` and
    ``NPROC``). Call it before anything runs on JAX (importing most of jaxrail already
    does): XLA reads both once, when it starts; raises ``RuntimeError`` if it has."""
    from jax._src import xla_bridge

    updates = host_device_environment(count)
    if xla_bridge.backends_are_initialized():
        raise RuntimeError("use_host_devices: JAX has already started its devices; call it "
                           "before importing jaxrail's modules or running anything on JAX")
    os.environ.update(updates)


def pool_threads() -> int:
    """Threads of the CPU client's pool: ``NPROC`` if it is a number, else the cores."""
    value = os.environ.get(POOL_THREADS, "")
    return int(value) if value.strip().isdigit() else (os.cpu_count() or 1)


def devices_may_stall(devices, process_index: int = 0) -> bool:
    """True when ``devices`` hold several CPU devices of process ``process_index``
    (only those share its pool) whose programs can take every thread of the shared
    pool (see the module docstring)."""
    cpu = [d for d in devices if d.platform == "cpu" and d.process_index == process_index]
    return len(cpu) > 1 and pool_threads() <= len(cpu)


def warn_if_devices_may_stall(devices, process_index: int = 0) -> None:
    """A warning when ``devices`` may stall each other (:func:`devices_may_stall`)."""
    if devices_may_stall(devices, process_index):
        import warnings

        warnings.warn(f"{len(devices)} CPU devices share XLA's thread pool of "
                      f"{pool_threads()} threads: a batch may run its parts one after the "
                      "other or hang; start the process with jaxrail.use_host_devices(N) "
                      f"(or set {POOL_THREADS} to the cores plus the devices), see "
                      "docs/montecarlo.md", stacklevel=3)


def split_rows(x, devices, axis: str = "batch"):
    """``x`` (host, leading batch axis) as a global array whose rows are split over
    ``devices``; on several hosts each feeds the rows its own devices hold."""
    import jax
    import jax.numpy as jnp
    import numpy as np
    from jax.sharding import Mesh, NamedSharding, PartitionSpec

    devices = list(devices)
    if len(devices) == 1:
        return jax.device_put(jnp.asarray(x), devices[0])
    sharding = NamedSharding(Mesh(np.array(devices), (axis,)), PartitionSpec(axis))
    if jax.process_count() == 1:
        return jax.device_put(jnp.asarray(x), sharding)
    return jax.make_array_from_callback(x.shape, sharding, lambda index: x[index])


def over_devices(function, devices, shared: tuple, rows: tuple, axis: str = "batch"):
    """``function(*shared, *rows)`` with the leading axis of every array in ``rows``
    split over ``devices`` (``jax.shard_map``: each device runs its own rows, with no
    communication) and ``shared`` replicated; the result is split likewise. On one
    device, the plain call. Traceable: call it inside a jitted function."""
    if len(devices) == 1:
        return function(*shared, *rows)
    import equinox as eqx
    import jax
    import numpy as np
    from jax.sharding import Mesh, PartitionSpec

    arrays, fixed = eqx.partition(shared, eqx.is_array)
    spec = PartitionSpec(axis)

    def local(arrays, *rows):
        return function(*eqx.combine(arrays, fixed), *rows)

    return jax.shard_map(local, mesh=Mesh(np.array(devices), (axis,)),
                         in_specs=(PartitionSpec(),) + (spec,) * len(rows), out_specs=spec,
                         check_vma=False)(arrays, *rows)
