"""The per-kernel profile (jaxrail._kernel_profile) against the optimised HLO: a loop's
body runs, per iteration, exactly the thunks its computations hold; and the own time of
nested events."""

import os
import subprocess
import sys

from jaxrail._kernel_profile import TRACE_FLAG, own_times

# A loop of n iterations, profiled at two trip counts: the executions per iteration
# (their difference) against the thunks of the while's body and condition, counted in
# the optimised HLO (jaxrail._hlo_operations). Printed as "traced static".
_SCRIPT = """
import re
import jax, jax.numpy as jnp
jax.config.update("jax_enable_x64", True)
from jaxrail._hlo_operations import _NO_WORK, _computations
from jaxrail._kernel_profile import kernel_profile

def loop(x, n):
    def body(i, c):
        return jnp.sin(c) @ jnp.full((8, 8), 0.1) + jnp.cos(c).sum() * c[::-1]
    return jax.lax.fori_loop(0, n, body, x)

compiled = jax.jit(loop).lower(jnp.ones(8), 1).compile()
text = compiled.as_text()
(line,) = [l for l in text.splitlines() if " while(" in l]
parts = [re.search(key + r"=%?([\\w.\\-]+)", line).group(1) for key in ("body", "condition")]
computations = _computations(text)
static = sum(op not in _NO_WORK for name in parts for op, _ in computations[name])
run = lambda n: kernel_profile(lambda: compiled(jnp.ones(8), n).block_until_ready(), n)
low, high = run(40), run(140)
traced = (high["kernels_per_evaluation"] * 140 - low["kernels_per_evaluation"] * 40) / 100
print(traced, static)
"""


def test_a_loops_kernels_per_iteration_are_the_thunks_of_its_body():
    env = dict(os.environ, XLA_FLAGS=os.environ.get("XLA_FLAGS", "") + " " + TRACE_FLAG)
    done = subprocess.run([sys.executable, "-c", _SCRIPT], env=env, capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    traced, static = (float(x) for x in done.stdout.split()[-2:])
    assert static >= 3  # fusions and the dot: a real body
    assert abs(traced - static) < 0.05  # kernels_per_evaluation is rounded to 0.01


def test_nested_events_count_their_own_time_only():
    # a loop from 0 to 100 ns holding two kernels, then a kernel after it
    events = [(0, 100, "while"), (10, 20, "a"), (40, 30, "b"), (200, 5, "c")]
    assert {k: tuple(v) for k, v in own_times(events).items()} == {
        "while": (50, 1), "a": (20, 1), "b": (30, 1), "c": (5, 1)}
