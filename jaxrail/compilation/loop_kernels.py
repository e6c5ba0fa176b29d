"""Integration loops compiled as single kernels (XLA:CPU's small-while-loop hoisting).

XLA:CPU runs a program as one thunk per fused operation, and compiles a ``while`` loop
into one kernel instead when the loop's bytes accessed are under
``xla_cpu_small_while_loop_byte_threshold`` and it holds no custom call (LAPACK, an FFI
target, YNNPACK's dot fusions), scatter or sort. For a vehicle without joints IMEX's
stage loop holds none of them once YNNPACK's fusions are off (its inverse and the
projection are plain operations), so with the threshold raised XLA compiles the stages
of each step, right-hand sides included, as one kernel; the step loop around them keeps
the progress report (an FFI call) and stays as it is, so a run with a bar is the run
without one. That holds in both contact modes: the search finds its patches without
scatter or sort (:func:`jaxrail.contact.patches.find_patches`). Measured on 8 s of the
paper's curve: 0.52 of the time in table mode for 1.5 to 2 times the compile; online
0.63 of the time of the stage loop that was not one kernel (while the search still
held them), for 2.7 times its compile (docs/simulation.md, "Loops as kernels").

The threshold can only be set through ``XLA_FLAGS``, read once when JAX starts its
backend, and it applies to every program of the process: :func:`use_loop_kernels`
sets it (``jaxrail simulate`` does, for its own process); importing jaxrail does not.
While it is set, :func:`~jaxrail.compilation.compiler.compiler_options` turns
YNNPACK's fusions off in jaxrail's programs.
"""

import os

from .._switches import switched_off

THRESHOLD_OPTION = "xla_cpu_small_while_loop_byte_threshold"
THRESHOLD_FLAG = f"--xla_backend_extra_options={THRESHOLD_OPTION}=10000000000"
SWITCH = "JAXRAIL_LOOP_KERNELS"  # "off" keeps the jaxrail command from setting the flag
NO_YNNPACK = {"xla_cpu_experimental_ynn_fusion_type": ""}


def loop_kernels_on(environ=None) -> bool:
    """Whether ``XLA_FLAGS`` (in ``environ``, default ``os.environ``) raises XLA's
    small-while-loop threshold."""
    environ = os.environ if environ is None else environ
    return THRESHOLD_OPTION in environ.get("XLA_FLAGS", "")


def use_loop_kernels(required: bool = True) -> bool:
    """Raise XLA's small-while-loop threshold for this process (``XLA_FLAGS``), unless
    ``JAXRAIL_LOOP_KERNELS=off`` or ``XLA_FLAGS`` already passes its own
    ``--xla_backend_extra_options`` (which a second one would replace); returns whether
    the threshold is raised. Call it before anything runs on JAX: if JAX has started
    its backend without the threshold, raises ``RuntimeError``, or with ``required``
    False returns False (the ``jaxrail`` command run inside a Python process that
    already uses JAX)."""
    from jax._src import xla_bridge

    if loop_kernels_on():
        return True
    flags = os.environ.get("XLA_FLAGS", "")
    if switched_off(SWITCH) or "--xla_backend_extra_options" in flags:
        return False
    if xla_bridge.backends_are_initialized():
        if not required:
            return False
        raise RuntimeError("use_loop_kernels: JAX has already started its backend; call it "
                           "before running anything on JAX")
    os.environ["XLA_FLAGS"] = f"{flags} {THRESHOLD_FLAG}".strip()
    return True
