"""JAX's compile events of one Python process, summed per test: loaded by every Python
process that ``benchmarks/suite_compile.py`` starts (this folder is on their
``PYTHONPATH``), pytest's workers and the processes the tests start alike (the command
line, the README's and the how-to guides' commands).

Only when ``$SUITE_COMPILE_OUT`` is set: JAX's duration events (XLA's backend compile,
tracing to a jaxpr, lowering to MLIR; wall-clock seconds as JAX reports them) and the
process's CPU seconds in XLA's backend compile (``compile_cpu_s``, around
``jax._src.compiler.backend_compile_and_load``: what the machine's load does not
inflate, unlike the wall-clock events; it also counts any other thread of the process
busy meanwhile) are added up under the test running at that moment
(``$PYTEST_CURRENT_TEST``, which pytest sets and child processes inherit), and written
at exit to ``$SUITE_COMPILE_OUT/<pid>.json``.
"""

import atexit
import functools
import json
import os
import sys
import time
from collections import defaultdict
from pathlib import Path

EVENTS = {"/jax/core/compile/backend_compile_duration": "compile_s",
          "/jax/core/compile/jaxpr_trace_duration": "trace_s",
          "/jax/core/compile/jaxpr_to_mlir_module_duration": "lower_s"}
OUTSIDE = "<outside tests>"


def _install(out: Path):
    totals = defaultdict(lambda: defaultdict(float))

    def test():
        return os.environ.get("PYTEST_CURRENT_TEST", OUTSIDE).rsplit(" (", 1)[0]

    def listener(event, duration_secs, **_):
        field = EVENTS.get(event)
        if field is None:
            return
        totals[test()][field] += duration_secs
        if field == "compile_s":
            totals[test()]["programs"] += 1

    def write():
        if not totals:
            return
        out.mkdir(parents=True, exist_ok=True)
        payload = {"pid": os.getpid(), "argv": sys.argv[:3],
                   "worker": os.environ.get("PYTEST_XDIST_WORKER"),
                   "tests": {k: dict(v) for k, v in totals.items()}}
        path = out / f"{os.getpid()}.json"
        tmp = path.with_suffix(".part")
        tmp.write_text(json.dumps(payload))
        tmp.replace(path)

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
            totals[test()]["compile_cpu_s"] += time.process_time() - start

    compiler.backend_compile_and_load = timed_backend_compile
    atexit.register(write)


if os.environ.get("SUITE_COMPILE_OUT"):
    _install(Path(os.environ["SUITE_COMPILE_OUT"]))
