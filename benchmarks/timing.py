"""Shared timing helper of the benchmark scripts."""

from __future__ import annotations

import time
from collections.abc import Callable


def best_of(f: Callable[[], object], repeat: int = 5) -> float:
    """The shortest wall time (s) of `repeat` calls of f: the least disturbed by the machine."""
    t = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        f()
        t.append(time.perf_counter() - t0)
    return min(t)
