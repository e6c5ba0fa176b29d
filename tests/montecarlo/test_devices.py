"""Host devices that run side by side: the environment, the refusal once JAX has
started, the warning for devices that can take the whole thread pool, and a sharded
loop of batched LAPACK solves that hangs in a pool of one thread per core; the
default chunk per platform."""

import os
import subprocess
import sys
import textwrap
from types import SimpleNamespace

import jax
import pytest

from jaxrail import use_host_devices
from jaxrail._devices import (POOL_THREADS, SINGLE_THREADED_OPS, devices_may_stall,
                              host_device_environment, host_device_flags)
from jaxrail.montecarlo.batch import chunk_size


def test_flags_replace_an_earlier_count_and_keep_the_others():
    flags = host_device_flags(2, "--xla_backend_optimization_level=0 "
                                 "--xla_force_host_platform_device_count=8")
    assert flags.split() == ["--xla_backend_optimization_level=0",
                             "--xla_force_host_platform_device_count=2", SINGLE_THREADED_OPS]
    assert host_device_flags(1, flags).split() == ["--xla_backend_optimization_level=0",
                                                   "--xla_force_host_platform_device_count=1"]
    with pytest.raises(ValueError, match="count >= 1"):
        host_device_flags(0)


def test_environment_gives_a_thread_per_core_and_per_device():
    env = host_device_environment(3, {"XLA_FLAGS": "--xla_cpu_enable_fast_math=false"})
    assert env["XLA_FLAGS"].split()[0] == "--xla_cpu_enable_fast_math=false"
    assert env[POOL_THREADS] == str(os.cpu_count() + 3)
    assert POOL_THREADS not in host_device_environment(1, {})


def test_default_chunk_is_larger_off_the_cpu():
    assert chunk_size(None, 1000, 1) == 64
    assert chunk_size(None, 1000, 1, "gpu") == 1000
    assert chunk_size(None, 10_000, 1, "gpu") == 4096
    assert chunk_size(None, 10, 1, "gpu") == 10
    assert chunk_size(None, 1000, 3) == 66  # rounded up to the devices
    assert chunk_size(100, 1000, 1, "gpu") == 100
    with pytest.raises(ValueError, match="chunk must be >= 1"):
        chunk_size(0, 1000, 1)


def test_too_late_once_jax_has_started():
    jax.devices()
    with pytest.raises(RuntimeError, match="already started"):
        use_host_devices(2)


def test_devices_that_can_take_the_whole_pool_are_flagged(monkeypatch):
    cpus = [SimpleNamespace(platform="cpu", process_index=0)] * 2
    monkeypatch.setenv(POOL_THREADS, "2")
    assert devices_may_stall(cpus) and not devices_may_stall(cpus[:1])
    # two processes with one device each: each pool serves one device
    spread = [SimpleNamespace(platform="cpu", process_index=k) for k in (0, 1)]
    assert not devices_may_stall(spread, 0) and not devices_may_stall(spread, 1)
    monkeypatch.setenv(POOL_THREADS, host_device_environment(2, {})[POOL_THREADS])
    assert not devices_may_stall(cpus)


SHARDED_SOLVES = textwrap.dedent("""
    import jax, jax.numpy as jnp
    from jax.sharding import Mesh, NamedSharding, PartitionSpec
    jax.config.update("jax_enable_x64", True)
    mesh = Mesh(jax.devices()[:2], ("batch",))

    def step(i, x):
        a = 3.0 * jnp.eye(40) + 0.01 * jnp.sin(x[:, :, None] * jnp.arange(40.0))
        return x + 1e-3 * jnp.linalg.solve(a, x[..., None])[..., 0]

    x = jax.device_put(jnp.ones((64, 40)), NamedSharding(mesh, PartitionSpec("batch")))
    for _ in range(3):
        jax.block_until_ready(jax.jit(lambda x: jax.lax.fori_loop(0, 300, step, x))(x))
    print(len(jax.devices()))
""")


def test_sharded_batched_solves_finish():
    """Two devices on a pool of one thread per core hang here at once (both pool
    threads in ParallelBatchMap under getrf); with the environment they finish."""
    env = dict(os.environ)
    env.update(host_device_environment(2, env))
    out = subprocess.run([sys.executable, "-c", SHARDED_SOLVES], env=env, timeout=300,
                         capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "2"
