"""The process's compiled programs: one bounded cache (:class:`~.lru.LruCache`) and
the entry point :func:`compile_program` that fills it.

:func:`compile_program` compiles a function for its arguments once per static structure
and argument shapes (:func:`~.compiler.compile_function`: jaxrail's XLA options, no host
callbacks, the persistent caches) and keeps the program; :func:`kept` keeps other
values in the same cache under a key of the caller's own (identification's residual
functions and fit programs), so that the process holds one set of programs, bounded by
:data:`PROGRAMS_KEPT`, and drops the least recently used first.
"""

import time

import equinox as eqx
import jax

from .compiler import compile_function
from .lru import LruCache

PROGRAMS_KEPT = 32
"""Compiled programs (and :func:`kept` values) this process keeps; the least recently
used one goes first (a paper-curve run uses two: rest pose and run)."""
PROCESS_CACHE = LruCache(PROGRAMS_KEPT)


def compile_program(function, *args, **kwargs):
    """AOT-compile ``function`` (jitted, or a plain function: see
    :func:`~.compiler.compile_function`) for these arguments once per static structure
    and argument shapes; returns (compiled, compile time [s], 0 if it was already
    compiled in this process). The compiled program takes the same arguments (the
    arrays may change, not the rest)."""
    leaves, structure = jax.tree.flatten((args, kwargs))
    key = (function, structure, tuple((x.shape, x.dtype) if eqx.is_array(x) else x
                                      for x in leaves))
    start = time.perf_counter()
    compiled, made = PROCESS_CACHE.get_or_make(
        key, lambda: compile_function(function, *args, **kwargs))
    return compiled, (time.perf_counter() - start if made else 0.0)


def kept(key: tuple, make):
    """The value kept in the process's cache under ``key``, made by ``make()`` if absent.
    ``key``: a tuple whose first element names the caller (a string, so that it never
    equals a :func:`compile_program` key, which starts with a function)."""
    if not (isinstance(key, tuple) and key and isinstance(key[0], str)):
        raise ValueError(f"key must be a tuple starting with a string, got {key!r}")
    return PROCESS_CACHE.get_or_make(key, make)[0]


class CompileTimer:
    """Compiles through :func:`compile_program` and adds up the compile seconds."""

    def __init__(self):
        self.compile_s = 0.0

    def compile(self, function, *args, **kwargs):
        compiled, seconds = compile_program(function, *args, **kwargs)
        self.compile_s += seconds
        return compiled

    def run(self, function, *args, **kwargs):
        return self.compile(function, *args, **kwargs)(*args, **kwargs)
