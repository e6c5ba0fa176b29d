"""Counting the operations XLA:CPU runs as thunks in a compiled program: an elementwise
chain is one fused kernel, a loop of LAPACK solves keeps its loop and one set of custom
calls per solve, and the count grows with the number of unfusable operations."""

import jax
import jax.numpy as jnp

from jaxrail._hlo_operations import element_counts, operation_counts


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


def _elements(function, *args):
    return element_counts(jax.jit(function).lower(*args).compile())


def test_element_operations_against_hand_counts():
    """Counted by hand: x * y + z on 7 elements is 14 operations and moves nothing; a
    concatenation of two 5-vectors moves 10 elements; (4 x 3) @ (3 x 4) is 48
    multiply-adds, and summing a (3, 4) array reads 12 elements."""
    v = jnp.ones(7)
    chain = _elements(lambda x, y, z: x * y + z, v, v, v)
    assert (chain["arithmetic"], chain["data_movement"]) == (14, 0)
    assert chain["by_kind"] == {"multiply": 7, "add": 7}
    joined = _elements(lambda x, y: jnp.concatenate([x, y]), jnp.ones(5), jnp.ones(5))
    assert (joined["arithmetic"], joined["data_movement"]) == (0, 10)
    # a kernel that scales a transpose and writes every other element: it writes 600,
    # the transpose inside only changes the indices of the 1200 it multiplies
    strided = _elements(lambda x: (x.T * 2.0).reshape(-1)[::2], jnp.ones((30, 40)))
    assert strided["by_kind"]["multiply"] == 1200 and strided["data_movement"] == 600
    assert strided["remapped_in_fusions"] >= 1200
    a = jnp.ones((3, 4))
    work = _elements(lambda x: (jnp.sin(x).T @ x, x.sum(0)), a)
    assert work["by_kind"]["dot"] == 48 and work["by_kind"]["reduce"] == 12
    assert work["by_kind"]["sine"] == 12


def _scaled_sines(x):
    return jnp.sin(x) * 2.0


def test_arithmetic_is_attributed_to_the_function_that_traced_it():
    """The sine and the product of :func:`_scaled_sines` (16 each on an 8-vector) are
    this file's, by the innermost frame inside its directory; the sum of the two
    vectors, made in the lambda below, is the lambda's; nothing is left over."""
    import pathlib

    from jaxrail._hlo_operations import arithmetic_by_source

    here = pathlib.Path(__file__).resolve()
    compiled = jax.jit(lambda x, y: _scaled_sines(x) + y).lower(jnp.ones(8), jnp.ones(8)).compile()
    counts = arithmetic_by_source(compiled, root=here.parent)
    assert counts == {f"{here.name}:_scaled_sines": 16,
                      f"{here.name}:test_arithmetic_is_attributed_to_the_function_that_"
                      "traced_it.<locals>.<lambda>": 8}
    assert sum(counts.values()) == element_counts(compiled)["arithmetic"]
    assert arithmetic_by_source(compiled) == {"unattributed": 24}  # no jaxrail frame
