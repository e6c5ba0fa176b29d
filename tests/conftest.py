import os

# The suite is dominated by XLA compilation (the contact search and the simulations are
# large programs run a few times each): LLVM optimisation level 0 compiles them about
# 2.4 times faster and runs them about 1.5 times slower (measured on the 8-wheel
# search); without LLVM's expensive passes the forward-mode run of
# tests/vehicles/test_irregular_track.py compiled in 54 s instead of 58 s. At level 1
# the trailer's 0.4 s Tsit5 run compiles in 33 s instead of 24-27 s and runs in 3.6 s
# instead of 15-16 s, but the whole suite took longer (1228 s against 1171 s, clean
# clones) and one finite-difference check moved by rounding. Benchmarks and the
# command line keep XLA's default.
os.environ.setdefault("XLA_FLAGS", "--xla_backend_optimization_level=0 "
                                   "--xla_llvm_disable_expensive_passes=true")
# The jaxrail command compiles IMEX's stage loops as single kernels
# (jaxrail.compilation.loop_kernels), which takes about 1.7 times as long to compile;
# the suite's commands, in this process or in the processes it starts, do not.
os.environ.setdefault("JAXRAIL_LOOP_KERNELS", "off")

import importlib.util  # noqa: E402
from pathlib import Path  # noqa: E402

import jax  # noqa: E402
import pytest  # noqa: E402

import jaxrail.compilation.cache  # noqa: E402
import jaxrail.compilation.compiler  # noqa: E402
from jaxrail.compilation import LruCache  # noqa: E402
from jaxrail.vehicles.initial import initial_state  # noqa: E402

# Physics is float64 (docs/design.md §8); tests run with it on, as the CLI does.
jax.config.update("jax_enable_x64", True)


@pytest.fixture(scope="module")
def integrations_at_level_1():
    """For a module whose runs are long: the integrations jaxrail compiles
    (jaxrail.compilation.compile_program's programs but the rest pose) at LLVM level 1 with its
    full pass list, everything else at the suite's level 0. A free wheelset's 0.3 s
    Tsit5 run takes 0.48 s at level 1 against 2.6 s at level 0, for 17.5 s to compile
    instead of 13.9 s (IMEX: 0.5 s against 1.3 s, 21.8 s to compile against 14.7 s), so
    it pays only where a module runs for many seconds (tests/vehicles/test_trailer.py:
    the README's example, 1 s of the paper's curve, 15 s instead of 35 s; its 0.4 s
    runs of IMEX against Tsit5, 51-57 s instead of 63 s with empty caches, measured when
    they had a module of their own)."""
    level_0_options = jaxrail.compilation.compiler.compiler_options
    compile_function = jaxrail.compilation.cache.compile_function
    integration = [False]

    def options():
        chosen = level_0_options()
        if integration[0]:
            chosen.update(xla_backend_optimization_level=1,
                          xla_llvm_disable_expensive_passes=False)
        return chosen

    def compile_integrations_at_level_1(function, *args, **kwargs):
        integration[0] = function is not initial_state
        try:
            return compile_function(function, *args, **kwargs)
        finally:
            integration[0] = False

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(jaxrail.compilation.compiler, "compiler_options", options)
        patch.setattr(jaxrail.compilation.cache, "compile_function",
                      compile_integrations_at_level_1)
        # the module's programs in a cache of their own, dropped after it: the process's
        # cache is keyed without the compiler options, and later modules run level 0
        patch.setattr(jaxrail.compilation.cache, "PROCESS_CACHE",
                      LruCache(jaxrail.compilation.PROGRAMS_KEPT))
        yield

# The slowest test files, slowest first (seconds per file from --durations=0 on a clean
# clone, 2 workers: 150 down to 27 s), collected first: pytest-xdist's --dist loadfile
# hands files to the workers in collection order (with --no-loadscope-reorder; by
# default it sorts them by their number of tests, which put the long files of one or
# two tests last, one worker running them while the other idled for about 65 s), so
# these start at once and the many short files fill in around them.
_SLOWEST_FIRST = (
    "tests/vehicles/test_flexible_track.py",
    "tests/vehicles/test_irregular_track.py",
    "tests/wear/test_route_wear.py",
    "tests/wear/test_wear_gradient.py",
    "tests/wear/test_steady_wear.py",
    "tests/vehicles/test_trailer.py",
    "tests/montecarlo/test_batch.py",
    "tests/stability/test_curving.py",
    "tests/contact/test_table.py",
    "tests/montecarlo/test_distributed.py",
    "tests/stability/test_linear_stability.py",
    "tests/test_progress.py",
    "tests/multibody/test_lean_solve.py",
    "tests/contact/test_search.py",
    "tests/multibody/test_imex.py",
    "tests/geometry/test_geometry.py",
    "tests/vehicles/test_parameters.py",
    "tests/vehicles/test_imex_trailer.py",
    "tests/montecarlo/test_resume.py",
    "tests/contact/test_irregular_rails.py",
    "tests/vehicles/test_klingel.py",
    "tests/multibody/test_pendulum.py",
    "tests/contact/test_patches.py",
    "tests/identification/test_fit.py",
    "tests/contact/test_strip.py",
    "tests/vehicles/test_wheel_rail.py",
)


def pytest_collection_modifyitems(items):
    rank = {path: k for k, path in enumerate(_SLOWEST_FIRST)}
    items.sort(key=lambda item: rank.get(item.nodeid.split("::")[0], len(rank)))


def load_xdist_crashes():
    """tests/xdist_crashes.py, the plugin that keeps ``--dist loadfile`` from hanging
    when a worker dies (loaded by path: the tests are not a package)."""
    spec = importlib.util.spec_from_file_location(
        "jaxrail_tests_xdist_crashes", Path(__file__).with_name("xdist_crashes.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def pytest_configure(config):
    if config.pluginmanager.hasplugin("xdist"):
        config.pluginmanager.register(load_xdist_crashes(), "jaxrail-xdist-crashes")
