"""Where a generation's candidates are evaluated: here, on local processes, or on a Dask cluster.

Each generation is split into chunks of designs; every chunk is one call of
:func:`~linkagekit.synthesis.objective.evaluate` (vectorized over its designs). The chunks
and their order do not depend on where they run, and the score of a design does not
depend on the chunk it is in (every operation is elementwise or reduces over that design's
own samples), so the same seed gives the same result on one process, on ``N`` local
processes and on a cluster.

Examples
--------
>>> import numpy as np
>>> chunks(np.zeros((10, 3)), 3)[0].shape
(4, 3)
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np

from ..errors import InputError, LinkageError
from ..threads import limit_for_good
from .base import Objective

#: the problems a worker process evaluates (set once per process by the pool's initializer)
_PROBLEMS: tuple[Objective, ...] = ()
#: a worker's line to the parent while it runs a whole search (:meth:`Evaluator.submit`): see :class:`Channel`
_CHANNEL: Channel | None = None
#: designs per chunk at most (bounds each call's memory; see objective.CHUNK)
MAX_CHUNK = 4096
#: glibc's mallopt parameters (malloc.h)
M_TRIM_THRESHOLD, M_MMAP_THRESHOLD = -1, -3
_TUNED = False


def daemonic() -> bool:
    """Whether this process may not start processes of its own (a :class:`multiprocessing.pool.Pool`'s worker)."""
    import multiprocessing

    return bool(multiprocessing.current_process().daemon)


def usable(workers: int) -> int:
    """``workers``, or 1 (with a warning) in a daemonic process, which cannot start them: the work runs in it.

    A :class:`multiprocessing.pool.Pool`'s worker that calls ``synthesize(..., workers=2)`` got Python's
    ``AssertionError: daemonic processes are not allowed to have children`` from the first search.
    """
    if not isinstance(workers, int | np.integer) or isinstance(workers, bool) or workers < 1:
        raise InputError(f"workers: expected a whole number of processes, at least 1, got {workers!r}")
    if workers > 1 and daemonic():
        import warnings

        text = f"workers={workers}: this is a daemonic worker process, which cannot start processes; working in it"
        warnings.warn(text, RuntimeWarning, stacklevel=3)
        return 1
    return workers


def chunks(X: np.ndarray, parts: int) -> list[np.ndarray]:
    """``X`` split along its designs into ``parts`` nearly equal chunks (more if a chunk would exceed ``MAX_CHUNK``)."""
    k = max(1, parts, -(-len(X) // MAX_CHUNK))
    return [c for c in np.array_split(X, min(k, len(X))) if len(c)]


def keep_freed_memory() -> None:
    """Have the C library's ``malloc`` keep freed memory for reuse (process-wide; glibc only).

    An evaluation makes many temporaries of a megabyte or more. By default glibc hands such
    blocks back to the operating system when they are freed, and the next one comes back as
    fresh pages the kernel must zero one by one: in a generation loop that costs as much as
    the arithmetic (benchmarks/bench_synthesis.py: the objective at 200 ns per design-sample
    without, 95 with). Blocks up to 32 MiB now come from the heap, and up to 1 GiB of freed
    heap is kept; the peak memory changes little (an atlas build's workers: 289 MB without,
    310-324 MB with, a review measured). Elsewhere (another C library) nothing
    happens. Called by the :class:`Evaluator` in every process that evaluates.
    """
    global _TUNED
    if _TUNED:
        return
    _TUNED = True
    import ctypes
    import ctypes.util

    try:
        mallopt = ctypes.CDLL(ctypes.util.find_library("c")).mallopt
    except (OSError, AttributeError, TypeError):  # no mallopt: not glibc
        return
    mallopt.argtypes = [ctypes.c_int, ctypes.c_int]
    mallopt(M_MMAP_THRESHOLD, 32 << 20)
    mallopt(M_TRIM_THRESHOLD, 1 << 30)


class Channel:
    """What the parent and its local workers share while the workers run whole searches.

    ``queue``: the workers' progress messages (any picklable value) to the parent; ``limit``: a
    number the parent sets and the workers read (the optimizer's first restart to drop);
    ``stop``: set by the parent when every search is to end now.
    """

    def __init__(self, ctx: Any) -> None:
        self.queue = ctx.SimpleQueue()
        self.limit = ctx.Value("q", 1 << 62, lock=False)
        self.stop = ctx.Value("b", 0, lock=False)

    def messages(self) -> list[Any]:
        """The progress messages that arrived (in the parent)."""
        out = []
        while not self.queue.empty():
            out.append(self.queue.get())
        return out


def installed() -> tuple[Objective, ...]:
    """In a local worker process: the problems it was started with."""
    return _PROBLEMS


def channel() -> Channel | None:
    """In a local worker process: its :class:`Channel` to the parent (None elsewhere)."""
    return _CHANNEL


def _install(problems: tuple[Objective, ...], line: Channel | None = None) -> None:
    """A local worker process's start: Ctrl-C is the parent's to handle (no traceback per worker), SIGTERM ends it
    as the system's default does (a forked worker does not inherit the ``linkagekit`` script's handler, which would
    print a traceback from a worker waiting for its next task), its problems."""
    global _PROBLEMS, _CHANNEL
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if callable(signal.getsignal(signal.SIGTERM)):  # the script's handler, forked: the default again (not an ignore)
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
    _die_with_parent()
    # the engine's BLAS calls are small (the polish's least-squares steps), but after each one OpenBLAS's threads
    # spin: a one-worker run of 2.0 s burned 2.7 CPU-s, and two workers ran two searches in 2.4 s where with one
    # BLAS thread each they took 1.9 s, as one search alone does
    limit_for_good()
    keep_freed_memory()
    _PROBLEMS, _CHANNEL = problems, line


#: Linux's prctl option: the signal a process gets when its parent dies (linux/prctl.h)
PR_SET_PDEATHSIG = 1


def _die_with_parent() -> None:
    """A worker process killed with its parent (Linux; elsewhere nothing happens).

    A worker waits for its next task; if the parent is killed (SIGKILL: no clean-up), nothing
    would end it, and it would hold the parent's stderr open, so that whoever reads it (a pipe,
    a test) waits forever.
    """
    import ctypes
    import ctypes.util
    import signal

    try:
        prctl = ctypes.CDLL(ctypes.util.find_library("c"), use_errno=True).prctl
    except (OSError, AttributeError, TypeError):  # not Linux
        return
    prctl(PR_SET_PDEATHSIG, signal.SIGKILL)


def _cost_here(which: int, X: np.ndarray) -> np.ndarray:
    return _PROBLEMS[which].cost(X)


def _cost_of(problem: Objective, X: np.ndarray) -> np.ndarray:
    keep_freed_memory()  # once per process (a Dask worker's too)
    return problem.cost(X)


def _check_address(address: str) -> None:
    """Refuse an address that is not ``tcp://host:port`` or ``tls://host:port`` (before Dask tries it)."""
    from distributed.comm.addressing import parse_address, parse_host_port

    try:
        protocol, loc = parse_address(address, strict=True)
        parse_host_port(loc)
    except (ValueError, TypeError) as e:
        raise InputError(f"--scheduler: '{address}' is not a scheduler address like tcp://host:8786 ({e})") from None
    if protocol not in ("tcp", "tls"):
        raise InputError(f"--scheduler: '{address}': only tcp:// and tls:// scheduler addresses are supported")


class WorkersLost(LinkageError):
    """The processes or the cluster that evaluate a generation are gone for good (the run cannot go on)."""

    exit_code = 1


#: seconds to wait for a ``--scheduler`` to answer before it is said unreachable
CONNECT_SECONDS = 10.0
#: a generation is sent again this many times when workers die under it
RETRIES = 3
#: seconds a Dask cluster may go without any worker before the run stops; between looks at it
NO_WORKER_WAIT, DASK_POLL = 60.0, 1.0
#: seconds a killed pool's manager thread is given to end before the search's process goes on (or exits)
KILLED_POOL_WAIT = 5.0


@contextmanager
def workers_lost(what: str) -> Iterator[None]:
    """Within it, a pool that lost a process (killed, say by the system, out of memory) is :class:`WorkersLost`
    saying ``what`` (one line, exit status 1), not a :class:`~concurrent.futures.process.BrokenProcessPool` shown
    as an internal error."""
    from concurrent.futures.process import BrokenProcessPool

    try:
        yield
    except BrokenProcessPool:
        raise WorkersLost(what) from None


def kill_pool(pool: Any) -> None:
    """A :class:`~concurrent.futures.ProcessPoolExecutor` stopped at once: its processes killed, its pending tasks
    cancelled (after a Ctrl-C or an error: what the workers compute is not waited for)."""
    for proc in list((getattr(pool, "_processes", None) or {}).values()):
        proc.kill()
    manager = getattr(pool, "_executor_manager_thread", None)
    # not waited for (a Ctrl-C that lands inside the pool's own bookkeeping, say while a lost worker is being
    # replaced, can leave its manager thread waiting on a worker that is gone)
    pool.shutdown(wait=False, cancel_futures=True)
    if manager is not None:
        # but its manager thread given a moment to end: one that closes its wake-up pipe while the interpreter's
        # exit writes to it prints "Exception ignored ... Bad file descriptor" (Python 3.11)
        manager.join(KILLED_POOL_WAIT)


class Evaluator:
    """Scores of a generation, ``cost(X)``, evaluated where asked.

    Parameters
    ----------
    problem : Objective or tuple of Objective
        What to score; with several (variants of one problem), ``cost(X, which)`` picks one.
    workers : int
        Local processes (1: in this process).
    scheduler : str, optional
        Address of a running Dask distributed scheduler (``tcp://host:port``); the chunks
        go to its workers (``dask[distributed]`` must be installed).
    """

    def __init__(
        self, problem: Objective | tuple[Objective, ...], workers: int = 1, scheduler: str | None = None
    ) -> None:
        if workers < 1:
            raise InputError(f"--workers: expected a positive number of processes, got {workers}")
        self.problems = problem if isinstance(problem, tuple) else (problem,)
        self.workers = workers if scheduler is not None else usable(workers)
        keep_freed_memory()
        self._pool: Any = None
        self.channel: Channel | None = None  # with local workers: the parent's side of their Channel
        self._handlers: list[tuple[Any, int]] = []  # Dask's log handlers and their levels, while quiet
        self._client: Any = None
        self._remote: Any = None
        if scheduler is not None:
            try:
                from distributed import Client
            except ImportError:
                raise InputError("--scheduler needs Dask: pip install 'dask[distributed]'") from None
            _check_address(scheduler)
            self._quiet_dask()
            try:
                connect: Any = Client  # distributed leaves Client.__init__ unannotated
                self._client = connect(scheduler, timeout=CONNECT_SECONDS, set_as_default=False)
            except (OSError, TimeoutError, ValueError) as e:
                raise InputError(f"--scheduler: cannot reach the Dask scheduler at {scheduler} ({e})") from None
            self._remote = [self._client.scatter(p, broadcast=True) for p in self.problems]
            self.parts = max(1, sum(self._client.nthreads().values()))
        elif self.workers > 1:
            self._pool = self._new_pool()
            self.parts = self.workers
        else:
            self.parts = 1

    def _quiet_dask(self) -> None:
        """Dask's own log off while this client runs: a lost scheduler is one line of ours, not its traceback.

        Dask logs through handlers on the ``distributed`` logger (its children propagate to them
        whatever their own level), so those handlers' levels are raised, and restored by :meth:`close`.
        """
        import logging

        names = [n for n in logging.root.manager.loggerDict if n == "distributed" or n.startswith("distributed.")]
        handlers = {h for n in names for h in logging.getLogger(n).handlers}
        self._handlers = [(h, h.level) for h in handlers]
        for h, _ in self._handlers:
            h.setLevel(logging.CRITICAL + 1)

    def _new_pool(self) -> Any:
        """A pool of ``workers`` local processes, each with the problems installed."""
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor

        # fork where there is one: a script that calls synthesize() needs no `if __name__ == "__main__"`
        # guard (spawn re-imports the main module); the workers only evaluate NumPy over arrays
        methods = multiprocessing.get_all_start_methods()
        ctx = multiprocessing.get_context("fork" if "fork" in methods else "spawn")
        self.channel = self.channel or Channel(ctx)
        args = (self.problems, self.channel)
        return ProcessPoolExecutor(self.workers, mp_context=ctx, initializer=_install, initargs=args)

    @property
    def local(self) -> bool:
        """Whether the designs are scored on local worker processes (not here, not on a cluster)."""
        return self._pool is not None

    def renew(self) -> None:
        """A new pool for one that lost a process."""
        self._pool.shutdown(wait=True, cancel_futures=True)
        self._pool = self._new_pool()

    def submit(self, fn: Any, *args: Any) -> Any:
        """``fn(*args)`` on a local worker process (a :class:`concurrent.futures.Future`): a whole search."""
        return self._pool.submit(fn, *args)

    @property
    def where(self) -> str:
        if self._client is not None:
            return f"Dask cluster ({self.parts} threads)"
        return f"{self.workers} local processes" if self._pool is not None else "this process"

    def cost(self, X: np.ndarray, which: int = 0) -> np.ndarray:
        """The cost of every design of ``X`` (N, dim) in problem ``which``."""
        parts = chunks(np.asarray(X, float), self.parts)
        if self._client is not None:
            got = self._on_cluster(which, parts)
        elif self._pool is not None:
            got = self._on_pool(which, parts)
        else:
            got = [_cost_of(self.problems[which], p) for p in parts]
        return np.concatenate(got)

    def _on_pool(self, which: int, parts: list[np.ndarray]) -> list[np.ndarray]:
        """The chunks' costs on the local pool; a pool that lost a process is replaced and the chunks sent again."""
        from concurrent.futures.process import BrokenProcessPool

        for _ in range(RETRIES + 1):
            try:
                return list(self._pool.map(_cost_here, [which] * len(parts), parts))
            except BrokenProcessPool:
                self._pool.shutdown(wait=True, cancel_futures=True)
                self._pool = self._new_pool()
        raise WorkersLost(f"the local worker processes died {RETRIES + 1} times during one generation")

    def _on_cluster(self, which: int, parts: list[np.ndarray]) -> list[np.ndarray]:
        """The chunks' costs on the Dask cluster; chunks lost with their workers are sent again while it is up."""
        from concurrent.futures import CancelledError  # what distributed raises for a future cancelled

        from distributed import KilledWorker

        for _ in range(RETRIES + 1):
            try:
                futures = self._client.map(_cost_of, [self._remote[which]] * len(parts), parts, pure=False)
                return list(self._wait(futures))
            except KilledWorker:  # the chunk's workers died under it: again, on the workers there are
                self._remote = [self._client.scatter(p, broadcast=True) for p in self.problems]
            except (OSError, TimeoutError, CancelledError) as e:
                raise WorkersLost(
                    f"lost the Dask cluster: its scheduler or every worker ({type(e).__name__})"
                ) from None
        raise WorkersLost(f"the Dask workers died {RETRIES + 1} times during one generation")

    def _wait(self, futures: list[Any]) -> list[np.ndarray]:
        """The futures' results; ``WorkersLost`` after ``NO_WORKER_WAIT`` seconds without a worker or a scheduler."""
        import time

        alone = None
        while True:
            end = time.monotonic() + DASK_POLL
            while time.monotonic() < end:
                if all(f.done() for f in futures):  # finished, failed or cancelled: gather says which
                    return list(self._client.gather(futures))
                time.sleep(0.002)
            if self._client.status != "running":
                raise WorkersLost("lost the Dask scheduler")
            if self._client.scheduler_info().get("workers"):
                alone = None
            elif alone is None:
                alone = time.monotonic()
            elif time.monotonic() - alone > NO_WORKER_WAIT:
                raise WorkersLost(f"no Dask worker for {NO_WORKER_WAIT:.0f} s")

    def close(self, kill: bool = False) -> None:
        """Shut the workers down (``kill``: at once, not after what they are computing)."""
        if self._pool is not None:
            if kill:
                kill_pool(self._pool)
            else:
                self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None
        if self._client is not None:
            self._client.close()
            self._client = None
        for h, level in self._handlers:
            h.setLevel(level)
        self._handlers = []

    def __enter__(self) -> Evaluator:
        return self

    def __exit__(self, kind: object, *exc: object) -> None:
        self.close(kill=kind is not None)  # Ctrl-C or an error: the workers' searches are not waited for
