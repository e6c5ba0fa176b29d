"""XLA compiler options for jaxrail's compiled programs.

A right-hand side of the trailer is a few hundred small operations (tens of elements
each), run hundreds of thousands of times inside the integrator's loop. On the CPU,
XLA's default scheduler orders them for concurrent execution on its thread pool,
which for operations this small costs more in hand-over than it gains; the
memory-optimised scheduler runs them in order. The loop-emitter fusions (instead of
the newer fusion emitters) are cheaper for these small shapes too. Together they make
the trailer's right-hand side 1.4 times cheaper in table mode and 1.15 times online,
inside a compiled loop (``benchmarks/rhs_profile.py``: ``rhs_median_us`` against
``xla_defaults_us``). The operations are the same; results differ by rounding (1e-14
m/s^2 in accelerations of 400 m/s^2).

Options go to each compilation (``jax.jit(..., compiler_options=...)`` or
``Lowered.compile``), never to the process-wide ``XLA_FLAGS``: importing jaxrail
changes nothing for other code in the process.
"""

import jax

_CPU_OPTIONS = {
    "xla_cpu_scheduler_type": "CPU_SCHEDULER_TYPE_MEMORY_OPTIMIZED",
    "xla_cpu_use_fusion_emitters": False,
}


def compiler_options() -> dict:
    """The options for a program compiled for JAX's default backend: the CPU ones
    above, none elsewhere."""
    return dict(_CPU_OPTIONS) if jax.default_backend() == "cpu" else {}


def compile_lowered(lowered):
    """``lowered.compile()`` with :func:`compiler_options`."""
    return lowered.compile(compiler_options())
