"""Host devices that run side by side: the XLA flags, the refusal once JAX has started,
and the warning for devices that share XLA's thread pool."""

from types import SimpleNamespace

import jax
import pytest

from jaxrail import use_host_devices
from jaxrail._devices import SINGLE_THREADED_OPS, devices_may_stall, host_device_flags


def test_flags_replace_an_earlier_count_and_keep_the_others():
    flags = host_device_flags(2, "--xla_backend_optimization_level=0 "
                                 "--xla_force_host_platform_device_count=8")
    assert flags.split() == ["--xla_backend_optimization_level=0",
                             "--xla_force_host_platform_device_count=2", SINGLE_THREADED_OPS]
    assert host_device_flags(1, flags).split() == ["--xla_backend_optimization_level=0",
                                                   "--xla_force_host_platform_device_count=1"]
    with pytest.raises(ValueError, match="count >= 1"):
        host_device_flags(0)


def test_too_late_once_jax_has_started():
    jax.devices()
    with pytest.raises(RuntimeError, match="already started"):
        use_host_devices(2)


def test_shared_pool_is_flagged(monkeypatch):
    cpus = [SimpleNamespace(platform="cpu")] * 2
    monkeypatch.setenv("XLA_FLAGS", "--xla_force_host_platform_device_count=2")
    assert devices_may_stall(cpus) and not devices_may_stall(cpus[:1])
    monkeypatch.setenv("XLA_FLAGS", host_device_flags(2))
    assert not devices_may_stall(cpus)
