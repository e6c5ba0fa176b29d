"""Functions traced once per program.

A compiled simulation calls the contact search at every place the integrator evaluates
the loads: the initial step, each stage, the Jacobian, the outputs. Traced inline,
each call traces the whole search again in Python, about half of a simulation's compile
time. :func:`traced_once` jits such a function (equinox's ``filter_jit``: arrays are
traced, every other leaf is static): inside an enclosing trace JAX keeps the traced
jaxpr of a jitted function by its arguments' types and reuses it (and its batched and
differentiated forms) at every later call with the same types, and XLA inlines the call
when it compiles, so the compiled program runs the same operations.

The kept jaxpr also keeps how ``eqx.error_if`` was traced: as a host callback that
raises (equinox's default) or as NaN (inside :mod:`jaxrail.compilation`'s programs, which
the persistent caches keep and which therefore hold no callback). So the mode is part
of the key: a function first called eagerly, then inside a compiled program, is traced
once for each.
"""

import functools

import equinox as eqx
import equinox._errors


def traced_once(function):
    """``function`` traced once per argument structure and types, and per
    ``eqx.error_if`` mode (module docstring)."""
    jitted = eqx.filter_jit(lambda on_error, *args, **kwargs: function(*args, **kwargs))

    @functools.wraps(function)
    def call(*args, **kwargs):
        return jitted(equinox._errors.EQX_ON_ERROR, *args, **kwargs)

    return call
