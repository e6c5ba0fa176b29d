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

Persistent compilation cache. Before its first compilation jaxrail turns on JAX's
persistent compilation cache, so that a second run of the same scenario (in a new
process) loads its programs instead of compiling them: in ``$JAX_COMPILATION_CACHE_DIR``
when that is set (or wherever ``jax_compilation_cache_dir`` already points), else in
``~/.cache/jaxrail/xla`` (``$JAXRAIL_CACHE_DIR/xla``). ``JAXRAIL_COMPILATION_CACHE=off``
(or JAX's own ``JAX_ENABLE_COMPILATION_CACHE=false``) leaves it off. The cache is
keyed by the program, the compiler options, the jax version and the machine; JAX
keeps only programs that took over a second to compile. The traced programs are kept
too, in ``<cache>/programs`` (:mod:`.programs`), so that a second process
skips tracing as well; the same switch turns both off. JAX does not keep programs
that call back to Python, so jaxrail's programs are traced with equinox's runtime
checks (``eqx.error_if``, e.g. diffrax's checks of its inputs) returning NaN instead
of raising through a callback: a run that fails them ends with a non-finite state
and the status "failed".
"""

import contextlib

import equinox._errors
import jax

from .._files import cache_root
from .._switches import switched_off
from .._time_report import register as register_time_report
from .loop_kernels import NO_YNNPACK, loop_kernels_on
from .programs import compile_through_program_cache

_CPU_OPTIONS = {
    "xla_cpu_scheduler_type": "CPU_SCHEDULER_TYPE_MEMORY_OPTIMIZED",
    "xla_cpu_use_fusion_emitters": False,
}


def compiler_options() -> dict:
    """The options for a program compiled for JAX's default backend: the CPU ones
    above, and YNNPACK's fusions off while loops compile as kernels
    (:mod:`.loop_kernels`); none elsewhere."""
    if jax.default_backend() != "cpu":
        return {}
    return dict(_CPU_OPTIONS, **(NO_YNNPACK if loop_kernels_on() else {}))


@contextlib.contextmanager
def _checks_as_nan():
    """Trace ``eqx.error_if`` as NaN-returning (no host callback) inside the block."""
    saved = equinox._errors.EQX_ON_ERROR
    equinox._errors.EQX_ON_ERROR = "nan"
    try:
        yield
    finally:
        equinox._errors.EQX_ON_ERROR = saved


def persistent_cache_folder():
    """The folder :func:`use_persistent_cache` puts compiled programs in, or None if the
    cache is turned off (module docstring)."""
    if switched_off("JAXRAIL_COMPILATION_CACHE"):
        return None
    if not jax.config.jax_enable_compilation_cache:
        return None
    return jax.config.jax_compilation_cache_dir or str(cache_root() / "xla")


def use_persistent_cache() -> None:
    """Turn JAX's persistent compilation cache on in :func:`persistent_cache_folder`
    (nothing if it is off or already configured)."""
    folder = persistent_cache_folder()
    if folder is not None and jax.config.jax_compilation_cache_dir != folder:
        jax.config.update("jax_compilation_cache_dir", folder)


def program_folder():
    """Where traced programs are kept (:mod:`.programs`): beside jaxrail's
    other caches, or None when the persistent cache is off."""
    return None if persistent_cache_folder() is None else cache_root() / "programs"


def compile_function(function, *args, **kwargs):
    """``function`` compiled for these arguments with :func:`compiler_options`, without
    host callbacks, through the persistent cache (:func:`use_persistent_cache`).

    ``function``: a jitted function (it has ``.lower``): lowered here; or a plain
    Python function: through the traced-program cache of :mod:`.programs`
    (single-device programs). Returns the compiled callable."""
    use_persistent_cache()
    register_time_report()  # a program loaded from a cache may report its time
    with _checks_as_nan():
        if hasattr(function, "lower"):
            return function.lower(*args, **kwargs).compile(compiler_options())
        return compile_through_program_cache(function, program_folder(), compiler_options(),
                                             *args, **kwargs)


def jit(function, **kwargs):
    """``jax.jit(function)`` with :func:`compiler_options`, the persistent cache on
    (:func:`use_persistent_cache`): for programs compiled by JAX at their first call
    (identification's fit programs), with equinox's checks as it traces them."""
    options = compiler_options()
    use_persistent_cache()
    return jax.jit(function, compiler_options=options, **kwargs)
