"""Functions traced once per program.

A compiled simulation calls the contact search at every place the integrator evaluates
the loads: the initial step, each stage, the Jacobian, the outputs. Traced inline,
each call traces the whole search again in Python, about half of a simulation's compile
time. :func:`traced_once` jits such a function (equinox's ``filter_jit``: arrays are
traced, every other leaf is static): inside an enclosing trace JAX keeps the traced
jaxpr of a jitted function by its arguments' types and reuses it (and its batched and
differentiated forms) at every later call with the same types, and XLA inlines the call
when it compiles, so the compiled program runs the same operations.
"""

import equinox as eqx


def traced_once(function):
    """``function`` traced once per argument structure and types (module docstring)."""
    return eqx.filter_jit(function)
