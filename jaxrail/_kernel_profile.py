"""Where a compiled program's time goes on XLA:CPU, kernel by kernel, from XLA's own trace.

XLA:CPU runs a program as a sequence of thunks (:mod:`jaxrail._hlo_operations`). With
:data:`TRACE_FLAG` in ``XLA_FLAGS`` (read when the CPU backend starts, so set before
the process's first computation) each thunk it runs is a trace event that names its
HLO instruction. :func:`kernel_profile` runs a function under ``jax.profiler.trace``
and sums those events per instruction: each one's own time (a loop's body runs inside
its ``while`` thunk: the body's time is taken out of the loop's) and how often it ran.

Tracing costs time per event (a few hundred ns, of the order of a small kernel's own
time), so the shares and the executions are what to read, not the absolute times;
``traced_us_per_evaluation`` against the untraced time shows the inflation.
"""

import collections
import os
import tempfile
from pathlib import Path

import jax

TRACE_FLAG = "--xla_cpu_enable_xprof_traceme=true"


def tracing_enabled() -> bool:
    """Whether this process's ``XLA_FLAGS`` ask XLA:CPU to trace its thunks."""
    return TRACE_FLAG in os.environ.get("XLA_FLAGS", "")


def _thunk_events(path):
    """(start [ns], duration [ns], instruction) of every traced thunk, per thread."""
    from jax.profiler import ProfileData

    data = ProfileData.from_file(str(path))
    for plane in data.planes:
        if not plane.name.startswith("/host:CPU"):
            continue
        for line in plane.lines:
            events = []
            for event in line.events:
                op = next((value for key, value in event.stats if key == "hlo_op"), None)
                if op is not None:
                    events.append((event.start_ns, event.duration_ns, op))
            yield sorted(events)


def own_times(events):
    """{instruction: [own time [ns], executions]} of one thread's sorted events: an
    event inside another (starting before it ends) is subtracted from it."""
    totals = collections.defaultdict(lambda: [0.0, 0])
    stack = []  # (end [ns], instruction) of the events that enclose the current one
    for start, duration, op in events:
        while stack and stack[-1][0] <= start:
            stack.pop()
        if stack:
            totals[stack[-1][1]][0] -= duration
        totals[op][0] += duration
        totals[op][1] += 1
        stack.append((start + duration, op))
    return totals


def kernel_profile(run, evaluations: int, top: int = 20) -> dict:
    """The kernels of the programs ``run()`` executes (it must block until they are
    done), per evaluation: ``run`` makes ``evaluations`` evaluations in all (e.g. calls
    times a loop's trip count).

    Returns ``{"kernels_per_evaluation", "traced_us_per_evaluation", "top_share",
    "kernels": [{"name", "share", "per_evaluation", "us_per_evaluation"}, ...]}``, the
    ``top`` kernels by own time. ValueError if the trace holds no thunk (the flag is
    missing: :func:`tracing_enabled`)."""
    with tempfile.TemporaryDirectory() as folder:
        with jax.profiler.trace(folder):
            run()
        totals = collections.defaultdict(lambda: [0.0, 0])
        for path in Path(folder).rglob("*.xplane.pb"):
            for events in _thunk_events(path):
                for op, (ns, count) in own_times(events).items():
                    totals[op][0] += ns
                    totals[op][1] += count
    if not totals:
        raise ValueError(f"kernel_profile: the trace holds no XLA:CPU thunk; start the "
                         f"process with {TRACE_FLAG} in XLA_FLAGS")
    time_ns = sum(ns for ns, _ in totals.values())
    ranked = sorted(totals.items(), key=lambda item: -item[1][0])
    kernels = [{"name": op, "share": round(ns / time_ns, 4),
                "per_evaluation": round(count / evaluations, 3),
                "us_per_evaluation": round(ns / evaluations / 1e3, 3)}
               for op, (ns, count) in ranked[:top]]
    return {"kernels_per_evaluation": round(sum(c for _, c in totals.values()) / evaluations, 2),
            "traced_us_per_evaluation": round(time_ns / evaluations / 1e3, 2),
            "top_share": round(sum(k["share"] for k in kernels), 4), "kernels": kernels}
