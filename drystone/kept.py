"""What a process keeps of its own results, by their inputs: one home for the memo that
saves a long run of checks the same work twice (a sweep checks every run's case before it
runs it, and the run reads the case again; a study's walls share a site response, a limit
analysis, a generated geometry). Nothing is written to disk; a new process starts empty.

``Kept(size)`` holds up to ``size`` results, the oldest dropped first. ``get(key, compute)``
returns a deep copy of the result kept for ``key``, computing and keeping it the first time,
so a caller may change what it gets. Keys must hold every input the result depends on (the
file's bytes, not its name).
"""
from __future__ import annotations

import copy


class Kept:
    """A process's results by their inputs (module docstring)."""

    def __init__(self, size: int):
        self.size = int(size)
        self._results: dict = {}

    def __contains__(self, key) -> bool:
        return key in self._results

    def __len__(self) -> int:
        return len(self._results)

    def get(self, key, compute=None):
        """A copy of the result kept for ``key``; computed by ``compute()`` and kept when
        there is none (None when there is none and no ``compute``)."""
        if key not in self._results:
            if compute is None:
                return None
            self.put(key, compute())
        return copy.deepcopy(self._results[key])

    def put(self, key, value) -> None:
        """Keep a copy of ``value`` for ``key`` (the oldest dropped past ``size``)."""
        self._results.pop(key, None)
        while len(self._results) >= self.size:
            self._results.pop(next(iter(self._results)))
        self._results[key] = copy.deepcopy(value)

    def clear(self) -> None:
        self._results.clear()
