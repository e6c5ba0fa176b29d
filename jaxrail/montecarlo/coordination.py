"""The coordination service of JAX's distributed runtime, as a study on several
processes uses it (barriers before gathers, the checkpoint's rows): the one place that
reaches JAX's distributed client, and the names of its keys and barriers.

JAX offers no public barrier or key-value store outside its collectives, hence its
(private) ``jax._src.distributed`` client. Each process asks for names in the same
order (the same calls in the same sequence), so the n-th name is the same on every
process and a second study in the same session gets names of its own."""

import itertools

_calls = itertools.count()


def client():
    """JAX's distributed client (``jax.distributed.initialize`` made it)."""
    from jax._src import distributed

    return distributed.global_state.client


def next_key(kind: str) -> str:
    """``jaxrail/<kind>/<n>``: the n-th key or barrier name asked for on this process."""
    return f"jaxrail/{kind}/{next(_calls)}"
