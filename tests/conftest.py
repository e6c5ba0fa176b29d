import jax

# Physics is float64 (DESIGN.md §8); tests run with it on, as the CLI does.
jax.config.update("jax_enable_x64", True)
