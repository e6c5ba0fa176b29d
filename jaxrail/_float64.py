"""Float64 guard.

Wheel-rail contact needs float64: the track spans kilometres while penetrations are
hundredths of a millimetre. jaxrail does not switch JAX's global configuration on
import (that would surprise other libraries in the same process); instead its
constructors call :func:`require_float64`, and the command line and the studies
call :func:`enable_float64` once at start-up. :func:`f64` is the converter of every
traced float field.
"""

import jax
import jax.numpy as jnp


def enable_float64() -> None:
    """Turn on JAX's float64 mode (``jax_enable_x64``) for this process."""
    jax.config.update("jax_enable_x64", True)


def require_float64(what: str) -> None:
    """Raise ``RuntimeError`` naming `what` unless JAX runs in float64 mode."""
    if not jax.config.jax_enable_x64:
        raise RuntimeError(
            f"{what} needs float64: call jaxrail.enable_float64() (or "
            "jax.config.update('jax_enable_x64', True)) before building it."
        )


def f64(x) -> jax.Array:
    """``x`` as a float64 JAX array (the ``eqx.field`` converter of traced numbers: an
    explicit dtype, never a weakly typed scalar)."""
    return jnp.asarray(x, dtype=jnp.float64)
