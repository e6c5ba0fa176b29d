"""Compiling and keeping jaxrail's programs: the one layer that
:func:`jaxrail.simulation.simulate`, Monte Carlo (:mod:`jaxrail.montecarlo`), the
nonlinear stability search (:mod:`jaxrail.stability.nonlinear`) and identification
(:mod:`jaxrail.identification`) compile through.

- :func:`compile_program` (the entry point, :mod:`.cache`): AOT-compile a function for
  its arguments once per static structure and shapes, kept in the process's one bounded
  cache (:data:`PROGRAMS_KEPT`); :func:`kept` keeps other values (identification's
  residual functions and fit programs) in that same cache; :class:`CompileTimer` adds
  up the compile seconds of a run.
- :mod:`.compiler`: the XLA:CPU options, equinox's checks traced as NaN (no host
  callback), JAX's persistent compilation cache (``JAXRAIL_COMPILATION_CACHE``,
  ``JAXRAIL_CACHE_DIR``, ``JAX_COMPILATION_CACHE_DIR``) and :func:`jit` for programs
  JAX compiles at their first call.
- :mod:`.programs`: traced programs kept on disk (``jax.export``), so that a second
  process neither traces nor compiles.
- :mod:`.tracing`: :func:`traced_once`, a function traced once per program (the contact
  search, the joints, the force elements).
- :mod:`.fusion`: :func:`computed_once`, values XLA computes once instead of in each
  kernel that reads them.
- :mod:`.windows`: ``window_map``, a linear map of a table's window at run-time indices,
  one slice per member of a small ``vmap`` instead of a gather.
- :mod:`.seldom`: ``seldom``, a branch computed under one conditional for a whole
  ``vmap``, only when some member needs it, instead of a select of both branches.
- :mod:`.lru`: the bounded least-recently-used map.
"""

from .cache import PROGRAMS_KEPT as PROGRAMS_KEPT
from .cache import CompileTimer as CompileTimer
from .cache import compile_program as compile_program
from .cache import kept as kept
from .compiler import compile_function as compile_function
from .compiler import compiler_options as compiler_options
from .compiler import jit as jit
from .compiler import persistent_cache_folder as persistent_cache_folder
from .compiler import use_persistent_cache as use_persistent_cache
from .fusion import computed_once as computed_once
from .lru import LruCache as LruCache
from .tracing import traced_once as traced_once

__all__ = ["CompileTimer", "LruCache", "PROGRAMS_KEPT", "compile_function", "compile_program",
           "compiler_options", "computed_once", "jit", "kept", "persistent_cache_folder",
           "traced_once", "use_persistent_cache"]
