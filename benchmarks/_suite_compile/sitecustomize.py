"""JAX's compile events of one Python process, summed per test: loaded by every Python
process that ``benchmarks/suite_compile.py`` starts (this folder is on their
``PYTHONPATH``), pytest's workers and the processes the tests start alike (the command
line, the README's and the how-to guides' commands).

Only when ``$SUITE_COMPILE_OUT`` is set: JAX's duration events (XLA's backend compile,
tracing to a jaxpr, lowering to MLIR; wall-clock seconds as JAX reports them) and the
process's CPU seconds in XLA's backend compile (``compile_cpu_s``, around
``jax._src.compiler.backend_compile_and_load``: what the machine's load does not
inflate, unlike the wall-clock events; it also counts any other thread of the process
busy meanwhile), each under the test running at that moment (``$PYTEST_CURRENT_TEST``,
which pytest sets and child processes inherit), appended as they come to
``$SUITE_COMPILE_OUT/<pid>.jsonl``, one ``[test, field, seconds]`` line each: pytest-xdist's
workers end without running ``atexit``, so nothing waits for the process's end.

Each compile that goes through JAX's persistent cache also writes
``[test, "program", [cache key, module name, seconds]]``: the key is JAX's own (the
program, its compile options, the backend), so a key compiled twice in the run is one
program compiled twice, however it was reached.
"""

import functools
import json
import os
import time
from pathlib import Path

EVENTS = {"/jax/core/compile/backend_compile_duration": "compile_s",
          "/jax/core/compile/jaxpr_trace_duration": "trace_s",
          "/jax/core/compile/jaxpr_to_mlir_module_duration": "lower_s"}
OUTSIDE = "<outside tests>"


def _install(out: Path):
    out.mkdir(parents=True, exist_ok=True)
    path = out / f"{os.getpid()}.jsonl"

    def record(field, seconds):
        test = os.environ.get("PYTEST_CURRENT_TEST", OUTSIDE).rsplit(" (", 1)[0]
        with open(path, "a") as file:
            file.write(json.dumps([test, field, seconds]) + "\n")

    def listener(event, duration_secs, **_):
        field = EVENTS.get(event)
        if field is not None:
            record(field, duration_secs)

    import jax._src.compiler as compiler
    import jax.monitoring
    jax.monitoring.register_event_duration_secs_listener(listener)
    backend_compile = compiler.backend_compile_and_load

    @functools.wraps(backend_compile)
    def timed_backend_compile(*args, **kwargs):
        start = time.process_time()
        try:
            return backend_compile(*args, **kwargs)
        finally:
            record("compile_cpu_s", time.process_time() - start)

    compiler.backend_compile_and_load = timed_backend_compile
    compile_and_write = compiler._compile_and_write_cache

    @functools.wraps(compile_and_write)
    def keyed_compile(backend, computation, devices, options, callbacks, module_name,
                      cache_key):
        start = time.perf_counter()
        try:
            return compile_and_write(backend, computation, devices, options, callbacks,
                                     module_name, cache_key)
        finally:
            record("program", [cache_key, module_name, time.perf_counter() - start])

    compiler._compile_and_write_cache = keyed_compile


if os.environ.get("SUITE_COMPILE_OUT"):
    _install(Path(os.environ["SUITE_COMPILE_OUT"]))
