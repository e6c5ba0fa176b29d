"""Dense solves in plain XLA operations, for ``loop_hoisting.py``: stand-ins for the
LAPACK routines jaxrail's integration loop calls (``jax.scipy.linalg.cho_factor`` and
``cho_solve``, ``jnp.linalg.inv`` and ``solve``), so that the loop holds no custom
call and XLA may compile it into one kernel. Each is a ``fori_loop`` over the matrix's
columns or rows (Cholesky: a matrix-vector product per column; substitution: a dot per
row; Gauss-Jordan: a rank-one update per column). Values only: the benchmark does not
differentiate.
"""

import jax.numpy as jnp
from jax import lax


def _row(matrix, i):
    return lax.dynamic_index_in_dim(matrix, i, 0, keepdims=False)


def cholesky(a):
    """Lower L with L L^T = a, a symmetric positive definite (n, n)."""
    n = a.shape[-1]
    rows = jnp.arange(n)

    def column(j, lower):
        v = lax.dynamic_index_in_dim(a, j, 1, keepdims=False) - lower @ _row(lower, j)
        root = jnp.sqrt(_row(v, j))
        new = jnp.where(rows > j, v / root, jnp.where(rows == j, root, 0.0))
        return lax.dynamic_update_index_in_dim(lower, new, j, 1)

    return lax.fori_loop(0, n, column, jnp.zeros_like(a))


def substitute(lower, b, transposed):
    """x with L x = b, or L^T x = b when ``transposed``; b (n,) or (n, m)."""
    n = lower.shape[-1]
    matrix = lower.T if transposed else lower

    def row(k, x):
        i = n - 1 - k if transposed else k
        r = _row(matrix, i)
        # x is zero in row i and in the rows not solved yet
        return lax.dynamic_update_index_in_dim(x, (_row(b, i) - r @ x) / _row(r, i), i, 0)

    return lax.fori_loop(0, n, row, jnp.zeros_like(b))


def cho_factor(a, lower=False, **_):
    """``(L, True)``: as ``jax.scipy.linalg.cho_factor``, always the lower factor."""
    return cholesky(a), True


def cho_solve(factor, b, **_):
    """x with L L^T x = b, ``factor`` from :func:`cho_factor`."""
    l_factor, _ = factor
    return substitute(l_factor, substitute(l_factor, b, False), True)


def inv(a):
    """a^-1 by Gauss-Jordan elimination with partial pivoting."""
    n = a.shape[-1]
    rows = jnp.arange(n)

    def eliminate(j, m):
        column = lax.dynamic_index_in_dim(m, j, 1, keepdims=False)
        p = jnp.argmax(jnp.where(rows >= j, jnp.abs(column), -1.0))
        row_j, row_p = _row(m, j), _row(m, p)
        swapped = lax.dynamic_update_index_in_dim(
            lax.dynamic_update_index_in_dim(m, row_j, p, 0), row_p, j, 0)
        pivot = row_p / _row(row_p, j)
        factor = lax.dynamic_index_in_dim(swapped, j, 1, keepdims=False)
        return jnp.where((rows == j)[:, None], pivot[None, :],
                         swapped - factor[:, None] * pivot[None, :])

    augmented = jnp.concatenate([a, jnp.eye(n, dtype=a.dtype)], axis=1)
    return lax.fori_loop(0, n, eliminate, augmented)[:, n:]


def solve(a, b):
    """x with a x = b, as ``inv(a) @ b``."""
    return inv(a) @ b
