"""Several XLA devices on one CPU, set up so that they run side by side.

XLA shows one CPU device unless ``--xla_force_host_platform_device_count`` asks for
more. Those devices share XLA's intra-op thread pool (a thread per core), and each
device's program holds one of its threads while it runs; a batched LAPACK call (the LU
of every member's equations of motion) splits its batch over the same pool and waits
for it. With two devices on two cores each waits for the thread the other holds: one
device stalls until the other's whole program ends, or both wait forever (seen here in
the Monte Carlo study, with gdb: both pool threads inside LAPACK's getrf / gesdd).
``--xla_cpu_multi_thread_eigen=false`` takes the pool away: each device runs its
program, LAPACK calls included, on its own thread.
"""

import os


FORCE_DEVICES = "--xla_force_host_platform_device_count"
SINGLE_THREADED_OPS = "--xla_cpu_multi_thread_eigen=false"


def host_device_flags(count: int, flags: str = "") -> str:
    """``flags`` (an XLA_FLAGS value) with ``count`` host devices that run side by side
    (any earlier device count replaced)."""
    if int(count) < 1:
        raise ValueError(f"host devices: need a count >= 1, got {count}")
    kept = [f for f in flags.split() if not f.startswith((FORCE_DEVICES, SINGLE_THREADED_OPS))]
    extra = [f"{FORCE_DEVICES}={int(count)}"] + ([SINGLE_THREADED_OPS] if count > 1 else [])
    return " ".join(kept + extra)


def use_host_devices(count: int) -> None:
    """Ask XLA for ``count`` CPU devices that run side by side (sets ``XLA_FLAGS``).
    Call it before anything runs on JAX (importing most of jaxrail already does):
    XLA reads the flags once, when it starts; raises ``RuntimeError`` if it has."""
    from jax._src import xla_bridge

    flags = host_device_flags(count, os.environ.get("XLA_FLAGS", ""))
    if xla_bridge.backends_are_initialized():
        raise RuntimeError("use_host_devices: JAX has already started its devices; call it "
                           "before importing jaxrail's modules or running anything on JAX")
    os.environ["XLA_FLAGS"] = flags


def devices_may_stall(devices) -> bool:
    """True when ``devices`` are several CPU devices sharing XLA's thread pool (see the
    module docstring), i.e. XLA_FLAGS lacks ``--xla_cpu_multi_thread_eigen=false``."""
    cpu = [d for d in devices if d.platform == "cpu"]
    return len(cpu) > 1 and SINGLE_THREADED_OPS not in os.environ.get("XLA_FLAGS", "")
