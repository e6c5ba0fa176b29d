"""Inverses of small square blocks in plain XLA operations.

:class:`~jaxrail.multibody.imex.IMEX` inverts I - h gamma J once per step. For a vehicle
without joints that matrix is block-diagonal, one (7, 7) block per wheelset (more with
a flexible track's states), and each block is inverted here by Gauss-Jordan elimination
with partial pivoting, unrolled over the block's columns: elementwise operations,
reductions and selects only, with no LAPACK call, scatter or loop. So XLA can fuse them
with their neighbours and compile the integration loop that holds them as one kernel
(``docs/simulation.md``), which a LAPACK custom call prevents.
"""

import jax.numpy as jnp


def block_inverses(a):
    """The inverse of each (b, b) matrix of ``a`` (..., b, b), by Gauss-Jordan
    elimination with partial pivoting (the row of the largest magnitude at or below the
    diagonal). A singular or non-finite block gives entries that are not finite.
    Differentiable (the pivot choice is piecewise constant)."""
    b = a.shape[-1]
    if a.shape[-2] != b:
        raise ValueError(f"block_inverses needs square blocks, got shape {a.shape}")
    rows = jnp.arange(b)
    m = jnp.concatenate([a, jnp.broadcast_to(jnp.eye(b, dtype=a.dtype), a.shape)], axis=-1)
    for j in range(b):
        candidates = jnp.where(rows >= j, jnp.abs(m[..., :, j]), -1.0)
        is_pivot = (rows == jnp.argmax(candidates, axis=-1)[..., None])[..., :, None]
        row_p = jnp.sum(jnp.where(is_pivot, m, 0.0), axis=-2)  # (..., 2 b)
        row_j = m[..., j, :]
        # swap rows j and p (the row p takes row j, then row j takes row p)
        m = jnp.where(is_pivot, row_j[..., None, :], m)
        at_j = (rows == j)[:, None]
        m = jnp.where(at_j, row_p[..., None, :], m)
        pivot = row_p / row_p[..., j:j + 1]
        m = jnp.where(at_j, pivot[..., None, :], m - m[..., :, j:j + 1] * pivot[..., None, :])
    return m[..., b:]
