"""A bounded least-recently-used map for the compiled programs a process keeps."""

from collections import OrderedDict


class LruCache:
    """At most ``size`` entries; :meth:`get_or_make` moves a hit to the front, and a new
    entry evicts the least recently used one (its compiled program is then freed)."""

    def __init__(self, size: int):
        if size < 1:
            raise ValueError(f"size must be >= 1, got {size}")
        self.size = size
        self._entries = OrderedDict()

    def __len__(self):
        return len(self._entries)

    def __contains__(self, key):
        return key in self._entries

    def get_or_make(self, key, make):
        """``(value, made)``: the entry for ``key``, made by ``make()`` if absent."""
        if key in self._entries:
            self._entries.move_to_end(key)
            return self._entries[key], False
        value = make()
        self._entries[key] = value
        if len(self._entries) > self.size:
            self._entries.popitem(last=False)
        return value, True

    def values(self) -> list:
        """The entries' values, the least recently used first."""
        return list(self._entries.values())
