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

import jax  # noqa: E402

# Physics is float64 (docs/design.md §8); tests run with it on, as the CLI does.
jax.config.update("jax_enable_x64", True)

# The slowest test files (measured with --durations=0), collected first: pytest-xdist's
# --dist loadfile hands files to the two workers in collection order, so these start at
# once and the many short files fill in around them, instead of one long file starting
# last while the other worker idles.
_SLOWEST_FIRST = (
    "tests/vehicles/test_imex_trailer.py",
    "tests/montecarlo/test_batch.py",
    "tests/contact/test_table.py",
    "tests/vehicles/test_irregular_track.py",
    "tests/vehicles/test_flexible_track.py",
    "tests/stability/test_curving.py",
    "tests/stability/test_linear_stability.py",
    "tests/vehicles/test_trailer.py",
    "tests/montecarlo/test_distributed.py",
    "tests/test_progress.py",
    "tests/geometry/test_geometry.py",
    "tests/multibody/test_lean_solve.py",
    "tests/vehicles/test_parameters.py",
    "tests/contact/test_search.py",
    "tests/test_cli_identify.py",
    "tests/contact/test_strip.py",
    "tests/montecarlo/test_resume.py",
    "tests/multibody/test_imex.py",
    "tests/vehicles/test_klingel.py",
)


def pytest_collection_modifyitems(items):
    rank = {path: k for k, path in enumerate(_SLOWEST_FIRST)}
    items.sort(key=lambda item: rank.get(item.nodeid.split("::")[0], len(rank)))
