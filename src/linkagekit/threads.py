"""One BLAS thread while linkagekit computes.

The solvers' linear algebra is many small matrices at once (a group's Jacobian per sample,
the kinetostatic system per sample): NumPy hands LAPACK one small matrix at a time, and a
threaded OpenBLAS then wakes and waits for its threads on every call. On a busy machine
that wait is the whole cost: ``analyze --method numerical`` of a 98-dyad strip took 128 s
with OpenBLAS's default threads and 5.0 s with one, on 2 cores shared with one other process
(docs/method.md, "One BLAS thread"). The limit is threadpoolctl's, for the duration of a call
(of the last of overlapping calls): the caller's NumPy work before and after keeps its threads.

>>> from threadpoolctl import threadpool_info
>>> @one_blas_thread
... def blas_threads():
...     return {lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"}
>>> blas_threads()
{1}
"""

from __future__ import annotations

import functools
import sys
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any, TypeVar

F = TypeVar("F", bound=Callable[..., Any])

_LOCK = threading.Lock()
_CONTROLLER: list[Any] = []  # [controller, whether SciPy's OpenBLAS was loaded when it looked]
_ACTIVE: list[Any] = []  # [threadpoolctl's limiter, how many calls are inside it]


def _controller() -> Any:
    """threadpoolctl's view of the BLAS libraries loaded; looked at again once SciPy has loaded its own (under
    ``_LOCK``)."""
    from threadpoolctl import ThreadpoolController

    scipy_loaded = "scipy.linalg" in sys.modules
    if not _CONTROLLER or (scipy_loaded and not _CONTROLLER[1]):
        _CONTROLLER[:] = [ThreadpoolController(), scipy_loaded]
    return _CONTROLLER[0]


@contextmanager
def blas_limited(with_scipy: bool = False) -> Iterator[None]:
    """Every loaded BLAS library on one thread inside the block, as it was once the last block running in any
    thread has ended; ``with_scipy``: SciPy's own OpenBLAS (its least squares', its integrators') loaded first, so
    that it is among them.

    BLAS's thread counts belong to the process, not to a thread: the first block to enter sets the limit and the
    last to leave puts back the counts from before the first (two overlapping calls in the editor's handler
    threads, each saving and restoring on its own, left the second unlimited and the process on one thread).
    """
    if with_scipy:
        import scipy.linalg  # noqa: F401
    with _LOCK:
        if not _ACTIVE:
            _ACTIVE[:] = [_controller().limit(limits=1, user_api="blas"), 0]
        _ACTIVE[1] += 1
    try:
        yield
    finally:
        with _LOCK:
            _ACTIVE[1] -= 1
            if _ACTIVE[1] == 0:
                _ACTIVE[0].restore_original_limits()
                _ACTIVE.clear()


def _limiting(with_scipy: bool) -> Callable[[F], F]:
    """A decorator that runs its function with :func:`blas_limited` ``(with_scipy)``."""

    def decorate(fn: F) -> F:
        @functools.wraps(fn)
        def limited(*args: Any, **kwargs: Any) -> Any:
            with blas_limited(with_scipy):
                return fn(*args, **kwargs)

        return limited  # type: ignore[return-value]

    return decorate


#: ``fn`` run with :func:`blas_limited`
one_blas_thread = _limiting(with_scipy=False)
#: ``fn`` run with :func:`blas_limited` ``(with_scipy=True)`` (a search that polishes, or an integration, with SciPy)
one_blas_thread_with_scipy = _limiting(with_scipy=True)


def limit_for_good() -> None:
    """Every BLAS library loaded now on one thread for the rest of the process (a synthesis worker's;
    SciPy's is loaded first, so that it is among them)."""
    import scipy.linalg  # noqa: F401 -- loads SciPy's own OpenBLAS, which NumPy's does not cover

    with _LOCK:
        _controller().limit(limits=1, user_api="blas")
