"""Values the compiled program computes once, however many kernels read them.

XLA:CPU fuses a cheap elementwise expression into every kernel that reads it, so an
expression with several consumers is computed again in each: a patch's normal force
and creep forces in the force, the moment, the outputs and the Jacobian; a profile's
height, slope and curvature in each quantity made from them. In the trailer's
table-mode right-hand side those copies were a fifth of the arithmetic
(docs/simulation.md, "Values computed once"). A dot is never fused into its consumers, so
the product of the values with the identity is computed once, stored and read by all.
"""

import jax.numpy as jnp


def computed_once(*arrays):
    """``arrays`` (of one shape and float dtype) unchanged, each computed once in the
    compiled program (module docstring); one array: its last axis as the values (at
    least two: XLA turns a product over one into a multiply, which it fuses).

    The product with the identity is exact for finite values; a NaN or infinite entry
    makes its fellows NaN, so pass only values that are finite wherever the state is."""
    if len(arrays) == 1:
        (x,) = arrays
        return x @ jnp.eye(x.shape[-1], dtype=x.dtype)
    stacked = jnp.stack(arrays, axis=-1)
    out = stacked @ jnp.eye(len(arrays), dtype=stacked.dtype)
    return tuple(out[..., i] for i in range(len(arrays)))
