"""Counting the operations XLA:CPU runs as thunks in a compiled program: an elementwise
chain is one fused kernel, a loop of LAPACK solves keeps its loop and one set of custom
calls per solve, and the count grows with the number of unfusable operations."""

import jax
import jax.numpy as jnp

from jaxrail._hlo_operations import operation_counts


def _count(function, *args):
    return operation_counts(jax.jit(function).lower(*args).compile())


def test_an_elementwise_chain_is_one_kernel():
    counts = _count(lambda x: jnp.cos(jnp.sin(x) * 2.0 + 1.0), jnp.ones(8))
    assert counts == {"operations": 1, "by_kind": {"fusion": 1}}


def test_solves_in_a_loop_are_counted_once_each():
    def solves(k):
        def body(_, y):
            for _ in range(k):  # k solves that depend on each other: no fusing them
                y = jnp.linalg.solve(y + 3.0 * jnp.eye(3), y)
            return y
        return lambda x: jax.lax.fori_loop(0, 5, body, x)

    one, three = (_count(solves(k), jnp.eye(3)) for k in (1, 3))
    assert one["by_kind"]["while"] >= 1  # the loop (and the pivots' own loops)
    # each solve is an LU factorisation (a LAPACK custom call) and triangular solves
    per_solve = one["by_kind"]["custom-call"]
    assert per_solve >= 1 and three["by_kind"]["custom-call"] == 3 * per_solve
    assert three["operations"] > one["operations"]
