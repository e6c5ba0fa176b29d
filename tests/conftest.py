import os

# The suite is dominated by XLA compilation (the contact search and the simulations are
# large programs run a few times each): LLVM optimisation level 0 compiles them about
# 2.4 times faster and runs them about 1.5 times slower (measured on the 8-wheel
# search). Benchmarks and the command line keep XLA's default.
os.environ.setdefault("XLA_FLAGS", "--xla_backend_optimization_level=0")

import jax  # noqa: E402

# Physics is float64 (docs/design.md §8); tests run with it on, as the CLI does.
jax.config.update("jax_enable_x64", True)
