"""The compiled-program cache is bounded, drops the least recently used entry, and is the
process's only one (jaxrail.compilation)."""

import pytest

from jaxrail.compilation import LruCache


def test_holds_at_most_its_size_and_drops_the_least_recently_used():
    made = []
    cache = LruCache(2)

    def make(key):
        made.append(key)
        return key * 10

    assert cache.get_or_make(1, lambda: make(1)) == (10, True)
    assert cache.get_or_make(2, lambda: make(2)) == (20, True)
    assert cache.get_or_make(1, lambda: make(1)) == (10, False)  # a hit: 1 is now recent
    assert cache.get_or_make(3, lambda: make(3)) == (30, True)  # evicts 2, not 1
    assert len(cache) == 2 and 1 in cache and 3 in cache and 2 not in cache
    assert cache.get_or_make(2, lambda: make(2)) == (20, True)
    assert made == [1, 2, 3, 2]


def test_the_process_keeps_one_bounded_cache():
    import sys

    from jaxrail import compilation, identification, montecarlo, simulation  # noqa: F401
    from jaxrail.stability import nonlinear  # noqa: F401

    cache = compilation.cache.PROCESS_CACHE
    assert isinstance(cache, LruCache) and 1 <= cache.size <= 32
    # no second cache: simulate, Monte Carlo, stability and identification keep their
    # programs in the compile layer's
    others = [name for name, module in list(sys.modules.items())
              if name.startswith("jaxrail.") and name != "jaxrail.compilation.cache"
              and any(isinstance(v, LruCache) for v in vars(module).values())]
    assert others == []
    with pytest.raises(ValueError, match="size must be >= 1"):
        LruCache(0)
    with pytest.raises(ValueError, match="key must be a tuple starting with a string"):
        compilation.kept((1, 2), lambda: 0)
