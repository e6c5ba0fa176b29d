"""Float64 guard.

Wheel-rail contact needs float64: the track spans kilometres while penetrations are
hundredths of a millimetre. jaxrail does not switch JAX's global configuration on
import (that would surprise other libraries in the same process); instead its
constructors call :func:`require_float64`, and the command line and the studies
call :func:`enable_float64` once at start-up.
"""

import jax


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
