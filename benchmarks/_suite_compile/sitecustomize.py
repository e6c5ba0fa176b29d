"""JAX's compile events of one Python process, summed per test: loaded by every Python
process that ``benchmarks/suite_compile.py`` starts (this folder is on their
``PYTHONPATH``), pytest's workers and the processes the tests start alike (the command
line, the README's and the how-to guides' commands).

Only when ``$SUITE_COMPILE_OUT`` is set: JAX's duration events (XLA's backend compile,
tracing to a jaxpr, lowering to MLIR; wall-clock seconds as JAX reports them) are added
up under the test running at that moment (``$PYTEST_CURRENT_TEST``, which pytest sets
and child processes inherit), and written at exit to ``$SUITE_COMPILE_OUT/<pid>.json``.
"""

import atexit
import json
import os
import sys
from collections import defaultdict
from pathlib import Path

EVENTS = {"/jax/core/compile/backend_compile_duration": "compile_s",
          "/jax/core/compile/jaxpr_trace_duration": "trace_s",
          "/jax/core/compile/jaxpr_to_mlir_module_duration": "lower_s"}
OUTSIDE = "<outside tests>"


def _install(out: Path):
    totals = defaultdict(lambda: defaultdict(float))

    def listener(event, duration_secs, **_):
        field = EVENTS.get(event)
        if field is None:
            return
        test = os.environ.get("PYTEST_CURRENT_TEST", OUTSIDE).rsplit(" (", 1)[0]
        totals[test][field] += duration_secs
        if field == "compile_s":
            totals[test]["programs"] += 1

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

    import jax.monitoring
    jax.monitoring.register_event_duration_secs_listener(listener)
    atexit.register(write)


if os.environ.get("SUITE_COMPILE_OUT"):
    _install(Path(os.environ["SUITE_COMPILE_OUT"]))
