"""The traced-program cache (jaxrail.compilation.programs): keys that change with whatever
the program depends on, a round trip through the disk without tracing."""

import dataclasses
import importlib.util
import sys
import types

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from jax import export

from jaxrail.compilation import programs
from jaxrail.compilation.programs import compile_through_program_cache, program_key


@dataclasses.dataclass(frozen=True)
class Settings:
    steps: int = 3


def damped(x, gain, settings=Settings()):
    for _ in range(settings.steps):
        x = x - gain * jnp.sin(x)
    return {"x": x, "norm": jnp.sum(x**2)}


def _key(*args, **kwargs):
    leaves, treedef = jax.tree.flatten((args, kwargs))
    return program_key(damped, leaves, treedef, {"option": 1})


def test_key_follows_shapes_dtypes_and_static_values():
    x = jnp.ones(3)
    base = _key(x, 0.5)
    assert base is not None and base == _key(jnp.zeros(3), 0.5)  # values: same program
    assert _key(jnp.ones(4), 0.5) != base
    assert _key(jnp.ones(3, dtype=jnp.int32), 0.5) != base
    assert _key(x, 0.25) != base  # a Python float is static
    assert _key(x, 0.5, settings=Settings(4)) != base
    leaves, treedef = jax.tree.flatten(((x, 0.5), {}))
    assert program_key(damped, leaves, treedef, {"option": 2}) != base


def test_what_cannot_be_keyed_is_not():
    assert _key(jnp.ones(3), lambda y: y) is None  # repr holds a memory address
    module = types.ModuleType("made_in_memory")  # no source file
    module.Gain = type("Gain", (eqx.Module,), {"__annotations__": {"value": float},
                                                 "__module__": "made_in_memory"})
    sys.modules["made_in_memory"] = module
    try:
        assert _key(jnp.ones(3), module.Gain(0.5)) is None
    finally:
        del sys.modules["made_in_memory"]


def test_key_follows_the_source_of_a_users_own_types(tmp_path):
    path = tmp_path / "user_profile.py"

    def key_with(body):
        path.write_text("import equinox as eqx\nclass Gain(eqx.Module):\n"
                        f"    value: float\n    def scale(self):\n        return {body}\n")
        spec = importlib.util.spec_from_file_location("user_profile", path)
        module = importlib.util.module_from_spec(spec)
        sys.modules["user_profile"] = module
        spec.loader.exec_module(module)
        return _key(jnp.ones(3), module.Gain(0.5))

    try:
        assert key_with("2.0") != key_with("3.0")
    finally:
        del sys.modules["user_profile"]


def test_round_trip_through_the_folder_without_tracing(tmp_path, monkeypatch):
    x = jnp.array([0.3, -1.2, 2.0])
    fresh = compile_through_program_cache(damped, tmp_path, {}, x, 0.5)(x, 0.5)
    assert len(list(tmp_path.glob("*.jaxprogram"))) == 1

    def no_tracing(*args, **kwargs):
        raise AssertionError("traced although the program was on disk")

    monkeypatch.setattr(programs.export, "export", no_tracing)
    loaded = compile_through_program_cache(damped, tmp_path, {}, x, 0.5)
    y = jnp.array([1.0, 0.1, -0.4])
    out = loaded(y, 0.5)
    np.testing.assert_array_equal(loaded(x, 0.5)["x"], fresh["x"])
    np.testing.assert_allclose(out["x"], damped(y, 0.5)["x"], rtol=1e-15)
    assert float(out["norm"]) == pytest.approx(float(damped(y, 0.5)["norm"]), rel=1e-15)


def test_a_damaged_file_is_traced_again(tmp_path):
    x = jnp.ones(2)
    compile_through_program_cache(damped, tmp_path, {}, x, 0.5)
    (file,) = tmp_path.glob("*.jaxprogram")
    file.write_bytes(b"not a program")
    out = compile_through_program_cache(damped, tmp_path, {}, x, 0.5)(x, 0.5)
    np.testing.assert_allclose(out["x"], damped(x, 0.5)["x"], rtol=1e-15)
    assert isinstance(export.deserialize(programs.pickle.loads(file.read_bytes())[0]),
                      export.Exported)


def test_an_inner_function_traced_with_host_callbacks_is_traced_again():
    """An inner jitted function first traced with equinox's check as a host callback
    would bring that callback into the exported program: the export clears JAX's trace
    caches and traces again."""
    import equinox as eqx
    import jax
    import jax.numpy as jnp

    from jaxrail.compilation.compiler import _checks_as_nan
    from jaxrail.compilation.programs import compile_through_program_cache

    @jax.jit
    def inner(x):
        return eqx.error_if(x, x < 0.0, "negative") * 2.0

    x = jnp.ones(3)
    inner(x)  # traced with the check as a host callback (equinox's default)
    calls = []
    original = jax.clear_caches

    def counting():
        calls.append(1)
        original()

    jax.clear_caches = counting
    try:
        with _checks_as_nan():  # as jaxrail's compiler traces
            run = compile_through_program_cache(lambda y: inner(y) + 1.0, None, None, x)
    finally:
        jax.clear_caches = original
    assert float(run(x)[0]) == 3.0
    assert len(calls) == 1  # the first export met the cached callback
