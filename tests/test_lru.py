"""The compiled-program caches are bounded and drop the least recently used entry."""

import pytest

from jaxrail._lru import LruCache


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


def test_the_process_caches_are_bounded():
    from jaxrail import identification, simulation
    from jaxrail.identification import fit

    for cache in (simulation.run._compiled, fit._COMPILED, identification._residual_cache):
        assert isinstance(cache, LruCache) and 1 <= cache.size <= 32
    with pytest.raises(ValueError, match="size must be >= 1"):
        LruCache(0)
