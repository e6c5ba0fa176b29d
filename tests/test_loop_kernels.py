"""Integration loops as single kernels (jaxrail.compilation.loop_kernels): the flag is
set before JAX starts, not twice, not over the user's own extra options, and with it
XLA compiles a loop of plain operations (the block inverse of IMEX) as one kernel and
jaxrail's programs leave YNNPACK's fusions out. Each case in a fresh process: XLA reads
its flags once."""

import os
import subprocess
import sys
import textwrap

import pytest

from jaxrail.compilation.loop_kernels import SWITCH, THRESHOLD_FLAG, loop_kernels_on

PROGRAM = textwrap.dedent("""
    import json, os, sys
    import jaxrail
    on = jaxrail.use_loop_kernels()
    import jax, jax.numpy as jnp
    jaxrail.enable_float64()
    from jaxrail.compilation.compiler import compiler_options
    from jaxrail.multibody.block_inverse import block_inverses
    a = 3.0 * jnp.broadcast_to(jnp.eye(7), (4, 7, 7)) + 0.01
    loop = jax.jit(lambda a: jax.lax.fori_loop(0, 50, lambda i, a: a + 1e-3 * block_inverses(a), a))
    text = loop.lower(a).compile(compiler_options()).as_text()
    try:
        jaxrail.use_loop_kernels()
        late = "no error"
    except RuntimeError as error:
        late = str(error)
    print(json.dumps({"on": on, "flags": os.environ.get("XLA_FLAGS", ""),
                      "one_kernel": 'xla_cpu_small_call="true"' in text,
                      "options": compiler_options(), "late": late}))
""")


def run_program(**environ):
    env = {k: v for k, v in os.environ.items() if k not in ("XLA_FLAGS", SWITCH)}
    env.update(environ)
    done = subprocess.run([sys.executable, "-c", PROGRAM], capture_output=True, text=True,
                          env=env, check=True)
    import json
    return json.loads(done.stdout.splitlines()[-1])


def test_the_flag_makes_a_loop_of_plain_operations_one_kernel_and_turns_ynnpack_off():
    out = run_program(XLA_FLAGS="--xla_cpu_multi_thread_eigen=false")
    assert out["on"] and out["one_kernel"]
    assert out["flags"] == f"--xla_cpu_multi_thread_eigen=false {THRESHOLD_FLAG}"
    assert out["options"]["xla_cpu_experimental_ynn_fusion_type"] == ""
    assert out["late"] == "no error"  # already on: nothing to change


@pytest.mark.parametrize("environ", [{SWITCH: "off"},
                                     {"XLA_FLAGS": "--xla_backend_extra_options=xla_cpu_parallel_codegen_split_count=2"}],
                         ids=["switched-off", "user-extra-options"])
def test_left_alone_when_switched_off_or_the_user_passes_extra_options(environ):
    out = run_program(**environ)
    assert not out["on"] and not out["one_kernel"]
    assert out["flags"] == environ.get("XLA_FLAGS", "")
    assert "xla_cpu_experimental_ynn_fusion_type" not in out["options"]


def test_after_jax_has_started_it_refuses_or_declines(monkeypatch):
    """In this test process JAX has started (the suite runs on it): ``required`` raises,
    as the jaxrail command's call declines (with the suite's switch turned on)."""
    import jax.numpy as jnp

    monkeypatch.setenv(SWITCH, "on")
    from jaxrail.compilation.loop_kernels import use_loop_kernels

    jnp.zeros(1).block_until_ready()
    if loop_kernels_on():  # the suite was started with the threshold: nothing to change
        assert use_loop_kernels() is True
        return
    with pytest.raises(RuntimeError, match="already started"):
        use_loop_kernels()
    assert use_loop_kernels(required=False) is False
    assert not loop_kernels_on()
