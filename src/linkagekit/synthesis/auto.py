"""``--topology auto``: path generation over every built-in topology within a joint limit.

The budget is split in three. First the four-bar search of a single topology with its atlas
(:data:`FOUR_BAR_SHARE` of the time, :func:`four_bar_engine`), a candidate of its own. Then a
*screen* (:data:`SCREEN` of the time): for every
topology of :func:`~.topologies.enumerate_topologies` (the four-bar, Watt II and
Stephenson III first, then the others in a seeded order, until the screen's time is up),
random designs of its space are solved over a turn, and the tracer's best place on its
link with the curve's similarity placement is fitted to the targets over every cyclic shift
of the correspondence (:func:`~.tracer.fit_shifts`). Each topology is ranked by its best
fit. Then the engine searches the :data:`SEARCHED` best-ranked topologies (or as many more
as fill whole rounds of the workers: :func:`searched`), each for an equal share of the rest
of the time; every design's tracer is at its best place on its link for the targets' nearest
points (:meth:`Projected.placed`: the fit over the shifts, then :data:`ICP_ROUNDS` rounds of
nearest points and a linear fit, each kept where it lowers the distance). The best design of
all, by the two-sided distance (feasible first, :func:`two_sided`), is written; its topology
is named. Each stage, and every :data:`TICK` seconds of the searches, is reported to
``progress`` as a :class:`Stage`.

Examples
--------
>>> import numpy as np
>>> from linkagekit.synthesis.auto import synthesize_auto
>>> t = np.linspace(0, 2 * np.pi, 12, endpoint=False)
>>> out = synthesize_auto(np.stack([np.cos(t), 0.6 * np.sin(t)], 1), max_joints=5, seconds=1)
>>> out.topology, out.feasible
('fourbar', True)
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, replace
from functools import cached_property
from typing import Any

import numpy as np

from ..errors import InputError
from ..threads import one_blas_thread_with_scipy
from .autosave import ROUND_SECONDS, Best, Checkpoint, Saved
from .base import Objective, Score, digest
from .distribute import Evaluator, usable, workers_lost
from .objective import (
    MARGIN,
    MIN_CURVE_SIZE,
    MIN_LINK,
    PENALTY,
    Problem,
    _too_small,
    best_index,
    degenerate,
    transmission_limit,
)
from .optimize import Outcome, Progress, Settings, check_settings, optimize
from .run import Synthesis, _unpack, make_problem, named
from .topologies import MAX_JOINTS, Topology, enumerate_topologies
from .tracer import TracerFit, chords_to, fit, fit_shifts, spectra

#: the fraction of the time the screen of topologies takes
SCREEN = 0.2
#: topologies the engine searches after the screen
SEARCHED = 3
#: random designs per topology in the screen
SCREEN_DESIGNS = 96
#: the topologies screened first, by name
FIRST = ("fourbar", "watt2", "stephenson3")
#: seconds between two of the progress lines :func:`synthesize_auto` reports while its searches run
TICK = 5.0


@dataclass(frozen=True)
class Stage:
    """What :func:`synthesize_auto` reports to its ``progress`` (``method="local"``): a line at each stage of the run
    and every :data:`TICK` seconds of its searches.

    Attributes
    ----------
    elapsed : float
        Seconds of the run so far.
    seconds : float
        The run's budget.
    what : str
        The stage, in words ("searching eightbar-16, fourbar, watt2").
    best : float
        A bound on the best candidate's two-sided distance / the targets' diagonal so far (how the run chooses:
        the design written is never further): the four-bar candidate's (the searches report only when they end);
        NaN before it.
    """

    elapsed: float
    seconds: float
    what: str
    best: float = float("nan")

    def line(self, before: float = 0.0, seconds: float | None = None) -> str:
        """The stage as one progress line; ``before``: seconds spent before the run started (reading the targets),
        counted in its time and its budget (``seconds``; None: the run's).

        >>> Stage(12.4, 60, "searching fourbar", 0.0123).line()
        'searching fourbar; best so far at most 1.23 % of the diagonal (two-sided distance); 12 of 60 s'
        """
        best = (
            ""
            if self.best != self.best
            else f"; best so far at most {100 * self.best:.3g} % of the diagonal (two-sided distance)"
        )
        total = self.seconds + before if seconds is None else seconds
        return f"{self.what}{best}; {self.elapsed + before:.0f} of {total:g} s"


@dataclass
class _Ticker:
    """Reports :class:`Stage` lines to ``progress`` (None: nothing): at once for a new stage, and again every
    :data:`TICK` seconds when called between the searches' steps."""

    progress: Callable[[Any], None] | None
    t0: float
    seconds: float
    what: str = ""
    best: float = float("nan")
    last: float = -np.inf

    def stage(self, what: str, best: float | None = None) -> None:
        self.what = what
        if best is not None and not best >= self.best:  # the first candidate (NaN before it), or a better one
            self.best = best
        self.last = -np.inf
        self()

    def start(self, saved: Saved, topologies: int) -> None:
        """The first stage: what the run does first, or, resumed from a checkpoint (``saved``), the time it had used."""
        if saved.fourbar is None:
            self.stage(f"the four-bar from its atlas, then a screen of {topologies} topologies")
        else:
            self.stage(f"resumed from its checkpoint after {saved.elapsed:.0f} s (the four-bar and the screen done)")

    def found(self, four_bar: Synthesis, xy: np.ndarray, screening: bool) -> None:
        """The stage after the four-bar search (``screening``: the screen comes next): its two-sided distance /
        diagonal (:func:`two_sided`, as the run chooses) bounds the answer's when it is feasible (a feasible design
        is chosen before one that is not)."""
        best = two_sided(four_bar, xy) / four_bar.diagonal if four_bar.feasible else None
        self.stage("the four-bar found" + ("; screening" if screening else ""), best)

    def __call__(self) -> None:
        now = time.monotonic()
        if self.progress is not None and now - self.last >= TICK:
            self.last = now
            self.progress(Stage(now - self.t0, self.seconds, self.what, self.best))


@dataclass(frozen=True)
class Tried:
    """One topology of an ``auto`` run: its screen figure and, if searched, its result.

    Attributes
    ----------
    name : str
    joints : int
    screen : float
        The best screened design's RMS fit / the targets' diagonal (inf: none assembled).
    error : float
        The searched design's RMS error / diagonal (NaN if not searched; inf: infeasible).
    two_sided : float
        What the choice between the topologies compares (:func:`two_sided`) / diagonal: the mean distance from the
        targets to the design's curve plus the mean from its curve to the targets (NaN if not searched).
    """

    name: str
    joints: int
    screen: float
    error: float = float("nan")
    two_sided: float = float("nan")


@one_blas_thread_with_scipy
def synthesize_auto(
    targets: Any,
    *,
    max_joints: int = MAX_JOINTS,
    seconds: float = 60.0,
    seed: int = 0,
    restarts: int = 32,
    generations: int = 500,
    popsize: int = 15,
    goal: float = 1e-5,
    workers: int = 1,
    scheduler: str | None = None,
    progress: Callable[[Progress], None] | None = None,
    method: str = "local",
    checkpoint: str | None = None,
    **problem: Any,
) -> Synthesis:
    """Path generation over the built-in topologies of at most ``max_joints`` joints; the best is returned.

    ``problem``: the keywords of :func:`~.run.make_problem` (``units``, ``ordered``,
    ``min_transmission``, ...) and ``partial`` (the targets lie on a part of the curve).
    ``method``: ``"local"`` (:func:`multistart`, the default) or ``"engine"`` (the engine's
    differential evolution and CMA-ES, with ``restarts`` ... ``scheduler``, ``progress``).
    The result's ``topology`` names the topology chosen and ``tried`` lists what was
    searched (:class:`Tried`). ``checkpoint``: a file the run's progress is saved in, and
    resumed from when it exists (:mod:`~.autosave`; the local searches then run in rounds
    of :data:`~.autosave.ROUND_SECONDS`, a checkpoint after each).
    """
    t0 = time.monotonic()
    check_settings(seconds=seconds, restarts=restarts, generations=generations, popsize=popsize, goal=goal)
    check_settings(workers=workers)
    workers = usable(workers)  # its shares of the time assume the workers run side by side
    xy, units, source, partial = _arguments(targets, problem)
    topologies = enumerate_topologies(max_joints)
    make = Maker(xy, units, partial, tuple(problem.items()))
    ck = _checkpoint(checkpoint, make, topologies, (xy, units, partial, problem, max_joints, seed, method))
    saved = (ck.load() if ck else None) or Saved()
    t0 -= saved.elapsed  # the clock goes on from the runs before
    save, tick = _Saver(ck, saved, t0), _Ticker(progress if method == "local" else None, t0, seconds)
    with save.on_interrupt():
        tick.start(saved, len(topologies))
        engine = _four_bar(saved, save, targets, units, partial, problem, seed, FOUR_BAR_SHARE * seconds, workers, goal)
        tick.found(engine, xy, screening=saved.order is None)
        if saved.order is None:
            deadline = time.monotonic() + SCREEN * seconds  # its share whatever the four-bar took
            _screened(saved, topologies, make, np.random.default_rng(seed), deadline, workers, method)
            save()
        assert saved.order is not None and saved.seeds is not None
        projs = [make(next(t for t in topologies if t.name == name)) for name in saved.order]
        left = max(seconds * (1 - RESERVE) - (time.monotonic() - t0), 1e-3)  # the screening may have used it all
        starts = [x for _, x in saved.screen]
        tick.stage(f"searching {', '.join(saved.order)}")
        if method == "engine":
            each = Settings(seed, left / len(projs), restarts, generations, popsize, goal, workers, scheduler)
            outs = [optimize(p, each, progress) for p in projs]
        elif ck is None:
            outs = local_searches(projs, saved.seeds, starts, left, workers, tick)
        else:
            outs = saved_searches(projs, saved, left, workers, save, tick)
    return _chosen(saved, {t.name: t.n_joints for t in topologies}, projs, starts, outs, engine, (xy, source, t0))


@dataclass
class _Saver:
    """Saves an auto run's progress (``saved``) in its checkpoint (``ck``; None: nothing), with the time since
    ``t0``."""

    ck: Checkpoint | None
    saved: Saved
    t0: float

    def __call__(self) -> None:
        if self.ck is not None:
            self.saved.elapsed = time.monotonic() - self.t0
            self.ck.save(self.saved)

    @contextmanager
    def on_interrupt(self) -> Iterator[None]:
        """On Ctrl-C the time used is saved too: the work since the last checkpoint is lost, not its time (resumed,
        the runs together took up to 10 s more than ``--seconds``)."""
        try:
            yield
        except KeyboardInterrupt:
            self()
            raise


def _arguments(targets: Any, problem: dict[str, Any]) -> tuple[np.ndarray, str, str | None, bool]:
    """The targets' points, unit and source, and whether they are ``partial``; ``problem`` (changed in place) keeps
    the keywords of :func:`~.run.make_problem` with the transmission bound set."""
    xy, inputs, units, source = _unpack(targets, problem.pop("inputs", None), problem.pop("units", "m"))
    if inputs is not None:
        raise InputError("--topology auto: targets with input angles (timing) are not supported")
    partial = bool(problem.pop("partial", False))
    problem.pop("shape_only", None)  # the projected search always places the curve
    problem.setdefault("min_transmission", 20.0)
    return xy, units, source, partial


def _screened(
    saved: Saved,
    topologies: Sequence[Topology],
    make: Maker,
    rng: np.random.Generator,
    deadline: float,
    workers: int,
    method: str,
) -> None:
    """The screen (:func:`screen`) until ``deadline``: the topologies it chooses, their figures and designs, and
    the local searches' seeds, into ``saved``."""
    screened = screen(topologies, make, rng, deadline, workers)
    order = sorted(screened, key=lambda k: screened[k][0])[: searched(workers if method == "local" else 1)]
    saved.order, saved.screen = order, [screened[n] for n in order]
    saved.seeds = [int(k) for k in rng.integers(0, 2**32, len(order))]


def _chosen(
    saved: Saved,
    joints: dict[str, int],
    projs: Sequence[Projected],
    starts: Sequence[np.ndarray],
    outs: Sequence[Outcome],
    engine: Synthesis,
    run: tuple[np.ndarray, str | None, float],
) -> Synthesis:
    """The best of the topologies' searches and the four-bar's, by :func:`two_sided` (feasible first), with what
    was tried and how the whole run went (``run``: the targets, their source and when the run started)."""
    assert saved.order is not None
    xy, source, t0 = run
    tried = []
    found: list[Synthesis] = []
    for name, (figure, _), proj, x0, out in zip(saved.order, saved.screen, projs, starts, outs, strict=True):
        x = _best_of(proj, [out.x, x0])
        syn = written(proj, x, replace(out, x=x), source)
        tried.append(Tried(name, joints[name], figure, _relative(syn), two_sided(syn, xy) / syn.diagonal))
        found.append(syn)
    runs = (*tried, Tried(FOUR_BAR_ENGINE, 5, np.nan, _relative(engine), two_sided(engine, xy) / engine.diagonal))
    best = min(zip(runs, [*found, engine], strict=True), key=lambda r: (not r[1].feasible, r[0].two_sided))[1]
    return replace(best, tried=runs, outcome=_whole_run(best.outcome, [*outs, engine.outcome], t0))


def _checkpoint(path: str | None, make: Maker, topologies: Sequence[Topology], run: tuple[Any, ...]) -> Any:
    """The run's :class:`~.autosave.Checkpoint` at ``path`` (None: none); ``run``: what it must agree on."""
    if path is None:
        return None
    xy, units, partial, problem, max_joints, seed, method = run
    names = {t.name: t for t in topologies}
    four = _four_bar_problem(xy, units, partial, problem)
    key = digest(np.asarray(xy), units, partial, sorted(problem.items()), max_joints, seed, method, SEARCHED)
    return Checkpoint(path, key, lambda name: len(make(names[name]).bounds[0]), four.dim)


def _relative(syn: Synthesis) -> float:
    """A result's RMS error / the targets' diagonal, as :class:`Tried` lists it (inf: infeasible)."""
    return syn.rms_error / syn.diagonal if syn.feasible else np.inf


#: the share of the time the four-bar search of a single topology (its atlas's answer, then the engine) takes
FOUR_BAR_SHARE = 0.15
#: its name among the topologies tried
FOUR_BAR_ENGINE = "fourbar (atlas)"


#: samples of a candidate's sweep that :func:`two_sided` measures
TWO_SIDED_SAMPLES = 721


def two_sided(syn: Synthesis, targets: Any) -> float:
    """The mean distance from the targets to a candidate's curve plus the mean from its curve to the targets (its
    sweep at :data:`TWO_SIDED_SAMPLES` inputs): how candidates of ``auto`` are judged. The targets' own errors miss a
    curve that runs on past them: a four-bar's partial sweep won letter C on them, twice as far off on both sides.

    >>> import types, numpy as np, linkagekit as lk
    >>> mech = lk.load("examples/seed000_fourbar.yaml")  # targets on its own curve: only the far side counts
    >>> T = lk.analyze(mech, {"crank": np.arange(0.0, 360.0, 30.0)}).xy("P")
    >>> P = lk.analyze(mech, {"crank": np.linspace(0.0, 360.0, 721)}).xy("P")
    >>> far = np.mean(np.min(np.hypot(*(P[:, None] - T[None]).T), axis=0))
    >>> bool(abs(two_sided(types.SimpleNamespace(mechanism=mech), T) - far) < 1e-9)
    True
    """
    from ..api import analyze

    mech = syn.mechanism
    sweep = mech.drivers[0].sweep.values()
    res = analyze(mech, {mech.drivers[0].name: np.linspace(sweep[0], sweep[-1], TWO_SIDED_SAMPLES)}, rates=False)
    xy = res.xy("P")
    P = (xy[:, 0] + 1j * xy[:, 1])[np.all(np.isfinite(xy), axis=1)]
    T = np.asarray(targets)
    Tz = T[:, 0] + 1j * T[:, 1] if T.ndim == 2 else T.astype(complex)
    if not len(P):
        return float("inf")
    d = np.abs(P[:, None] - Tz[None, :])
    return float(np.mean(np.min(d, axis=0)) + np.mean(np.min(d, axis=1)))


def four_bar_engine(
    targets: Any,
    units: str,
    partial: bool,
    problem: dict[str, Any],
    seed: int,
    seconds: float,
    workers: int,
    goal: float,
) -> Synthesis:
    """``synthesize --topology fourbar --shape-only`` for ``seconds``: a candidate of its own. The projected search
    over many topologies is built for shapes no four-bar draws (the letters); on an arc of 7 points it ended at
    0.17 % of the diagonal in 15 s where the four-bar search, from its atlas, reaches 0.003 % in 5 s."""
    from .run import synthesize_path

    return synthesize_path(
        targets, "fourbar", units=units, shape_only=True, partial=partial, seed=seed, seconds=max(seconds, 1e-3),
        workers=workers, goal=goal, **problem,
    )  # fmt: skip


def _four_bar(
    saved: Saved, save: Callable[[], None], targets: Any, units: str, partial: bool, *search: Any
) -> Synthesis:
    """:func:`four_bar_engine`'s result (``search``: its problem, seed, seconds, workers and goal), saved; a
    checkpoint's (``saved.fourbar``) again without the search."""
    problem = search[0]
    if saved.fourbar is not None:
        return four_bar_again(targets, units, partial, problem, saved.fourbar)
    engine = four_bar_engine(targets, units, partial, *search)
    saved.fourbar = engine.outcome
    save()
    return engine


def _four_bar_problem(xy: np.ndarray, units: str, partial: bool, problem: dict[str, Any]) -> Problem:
    """The problem :func:`four_bar_engine` searches."""
    return make_problem(xy, "fourbar", None, units, **problem, shape_only=True, partial=partial)


def four_bar_again(targets: Any, units: str, partial: bool, problem: dict[str, Any], outcome: Outcome) -> Synthesis:
    """:func:`four_bar_engine`'s result again from its outcome (a checkpoint's: the search is not run again)."""
    from .run import finish

    xy, _, _, source = _unpack(targets, None, units)
    return finish(_four_bar_problem(xy, units, partial, problem), outcome, source)


def saved_searches(
    projs: Sequence[Projected],
    saved: Saved,
    seconds: float,
    workers: int,
    save: Callable[[], None],
    tick: Callable[[], None] | None = None,
) -> list[Outcome]:
    """:func:`local_searches` in rounds of :data:`~.autosave.ROUND_SECONDS` within ``seconds``, each round from the
    best designs so far (``saved.best``, else the screen's), ``save()`` after each: each objective's outcome.

    A round's seeds are the searches' own (``saved.seeds``) moved on by the rounds done, so a resumed run does not
    draw the designs it drew before.
    """
    deadline = time.monotonic() + seconds
    assert saved.seeds is not None
    saved.best = saved.best or [None] * len(projs)
    while any(b is None for b in saved.best) or deadline - time.monotonic() > ROUND_SECONDS / 100:
        span = max(min(ROUND_SECONDS, deadline - time.monotonic()), 1e-3)
        seeds = [(s + 7919 * saved.rounds) % 2**32 for s in saved.seeds]
        x0 = [x if b is None else b.x for b, (_, x) in zip(saved.best, saved.screen, strict=True)]
        outs = local_searches(projs, seeds, x0, span, workers, tick)
        saved.best = [Best.first(o) if b is None else b.merged(o) for b, o in zip(saved.best, outs, strict=True)]
        saved.rounds += 1
        save()
    return [b.outcome() for b in saved.best if b is not None]


def searched(workers: int) -> int:
    """How many topologies the search takes from the screen: :data:`SEARCHED`, rounded up to a whole number of
    rounds of ``workers`` (three on two workers would leave one idle while the third runs alone)."""
    w = max(workers, 1)
    return -(-SEARCHED // w) * w


@dataclass(frozen=True)
class Maker:
    """The projected objective of each topology for the targets (picklable: the screen's workers make their own)."""

    xy: np.ndarray
    units: str
    partial: bool
    problem: tuple[tuple[str, Any], ...]

    def __call__(self, t: Topology) -> Projected:
        return Projected(make_problem(self.xy, t.name, None, self.units, **dict(self.problem)), self.partial)


def _pool(workers: int) -> Evaluator:
    """``workers`` local processes for whole tasks (:meth:`~.distribute.Evaluator.submit`), used as a context.

    The engine's own pool: forked where the system can (a script needs no ``__main__`` guard), its processes
    deaf to Ctrl-C (the parent's to handle: one line, not a traceback from a process waiting for a task), and on
    Ctrl-C or an error killed at once, not waited for through the tasks queued behind (whole shares of the time).
    """
    return Evaluator((), workers)


def _results(tasks: Sequence[Any], tick: Callable[[], None] | None = None) -> list[Any]:
    """The results of tasks on :func:`_pool`'s processes, ``tick()`` five times a :data:`TICK` while they run; one
    killed (say by the system, out of memory) is :class:`~.distribute.WorkersLost` (one line, exit status 1), not an
    internal error."""
    from concurrent.futures import wait

    with workers_lost("a local worker process of the topology search died (killed?)"):
        while tick is not None and wait(tasks, timeout=TICK / 5).not_done:
            tick()
        return [t.result() for t in tasks]


def _summed(best: Outcome, outs: Sequence[Outcome]) -> Outcome:
    """``best`` with the searches, generations and designs of all of ``outs`` counted."""
    return replace(
        best,
        restarts=sum(o.restarts for o in outs),
        generations=sum(o.generations for o in outs),
        evaluations=sum(o.evaluations for o in outs),
    )


def _whole_run(best: Outcome, outs: list[Outcome], t0: float) -> Outcome:
    """How the whole run went: the best design's outcome with every topology's searches and the time since ``t0``."""
    return replace(_summed(best, outs), seconds=time.monotonic() - t0)


#: the fraction of the time kept for the dense checks of the results
RESERVE = 0.03


def local_searches(
    projs: Sequence[Projected],
    seeds: Sequence[int],
    starts: Sequence[np.ndarray],
    seconds: float,
    workers: int,
    tick: Callable[[], None] | None = None,
) -> list[Outcome]:
    """:func:`multistart` on each objective, ``workers`` at a time on local processes, within ``seconds`` in all.

    Each gets ``seconds / ceil(k / workers)`` (``k`` objectives: that many rounds of
    ``workers`` at a time), its own seed and start. A worker a round leaves without one (one
    topology within ``--max-joints 5``, or three on two workers when the screen got no further)
    searches one again, from another seed (:func:`_replicas`): each objective's outcome is its
    best search's, with every search counted.
    """
    k = len(projs)
    share = max(seconds / -(-k // max(workers, 1)), 1e-3)
    if workers <= 1:
        return [_multistart(p, s, share, x, tick) for p, s, x in zip(projs, seeds, starts, strict=True)]
    owner, task_seeds, task_starts = _replicas(seeds, starts, workers)
    with _pool(min(workers, len(owner))) as pool:
        jobs = zip(owner, task_seeds, task_starts, strict=True)
        tasks = [pool.submit(_multistart, projs[i], s, share, x) for i, s, x in jobs]
        done = _results(tasks, tick)
    return [_merged([o for o, i in zip(done, owner, strict=True) if i == j]) for j in range(k)]


def _replicas(
    seeds: Sequence[int], starts: Sequence[np.ndarray], workers: int
) -> tuple[list[int], list[int], list[np.ndarray | None]]:
    """The tasks' objectives, seeds and starts: one each, then more of them in turn until every worker has one in
    every round (each more from a seed of its own, without the screen's start).

    >>> _replicas([7, 9], [None, None], 5)[0]
    [0, 1, 0, 1, 0]
    >>> _replicas([7, 9, 11], [None, None, None], 2)[0]
    [0, 1, 2, 0]
    """
    k = len(seeds)
    owner = [j % k for j in range(-(-k // workers) * workers)]
    task_seeds = [int(seeds[i]) if j < k else int(seeds[i]) + 7919 * (j // k) for j, i in enumerate(owner)]
    return owner, task_seeds, [starts[i] if j < k else None for j, i in enumerate(owner)]


def _merged(outs: Sequence[Outcome]) -> Outcome:
    """The best of one objective's searches, with all of their searches and designs counted."""
    return _summed(min(outs, key=lambda o: o.cost), outs)


def _multistart(
    proj: Projected, seed: int, seconds: float, x0: np.ndarray | None, tick: Callable[[], None] | None = None
) -> Outcome:
    """:func:`multistart` for ``seconds`` from now (a worker process's task)."""
    return multistart(proj, np.random.default_rng(seed), time.monotonic() + seconds, x0, tick)


#: random designs drawn at once by :func:`multistart`; the best few of them start a local search
BATCH, STARTS = 1024, 4
#: residual evaluations of one local search at most
LOCAL_NFEV = 60


def multistart(
    proj: Projected,
    rng: np.random.Generator,
    deadline: float,
    x0: np.ndarray | None = None,
    tick: Callable[[], None] | None = None,
) -> Outcome:
    """Local searches from the best of random designs until ``deadline``: the best design found (``tick()`` after
    each local search).

    Each round draws :data:`BATCH` designs, scores them at once, and runs :func:`local_search`
    from the :data:`STARTS` best (the first round also from ``x0``). Bounded least squares
    from good random starts reach, in seconds, what a population search reaches in tens.
    """
    t0 = time.monotonic()
    lo, hi = proj.bounds
    best_x, best_cost, starts, designs = None, np.inf, 0, 0
    while time.monotonic() < deadline or best_x is None:
        X = lo + rng.random((BATCH, len(lo))) * (hi - lo)
        if x0 is not None and best_x is None:
            X[0] = x0
        cost = proj.cost(X)
        designs += BATCH
        for i in np.argsort(cost)[:STARTS]:
            if time.monotonic() > deadline and best_x is not None:
                break
            x, c, n = local_search(proj, X[i], deadline=deadline)
            starts, designs = starts + 1, designs + n
            if tick is not None:
                tick()
            if c < best_cost:
                best_x, best_cost = x, c
    assert best_x is not None
    return Outcome(best_x, float(best_cost), starts, 0, designs, time.monotonic() - t0, "time")


class _Stop(Exception):
    """The local search's deadline passed."""


def local_search(
    proj: Projected, x0: np.ndarray, max_nfev: int = LOCAL_NFEV, deadline: float = np.inf
) -> tuple[np.ndarray, float, int]:
    """Bounded least squares (scipy's ``trf``) on :meth:`Projected.residuals` from ``x0``: (x, cost, designs).

    The Jacobian by forward differences, every column in one batch of designs. Past
    ``deadline`` (``time.monotonic``) it stops with the best design it has evaluated.
    """
    from scipy.optimize import least_squares

    lo, hi = proj.bounds
    h = 1e-6 * proj.scale
    count = [0]
    best: list[Any] = [np.inf, np.clip(x0, lo, hi)]

    def fun(x: np.ndarray) -> np.ndarray:
        if time.monotonic() > deadline:
            raise _Stop
        count[0] += 1
        r = np.asarray(proj.residuals(x[None])[0])
        if float(r @ r) < best[0]:
            best[:] = [float(r @ r), x.copy()]
        return r

    def jac(x: np.ndarray) -> np.ndarray:
        if time.monotonic() > deadline:
            raise _Stop
        step = np.where(x + h <= hi, h, -h)
        X = np.vstack([x, x + np.diag(step)])
        R = proj.residuals(X)
        count[0] += len(X)
        return np.asarray(((R[1:] - R[0]) / step[:, None]).T)

    try:
        x = least_squares(fun, best[1], jac=jac, bounds=(lo, hi), method="trf", x_scale="jac", max_nfev=max_nfev).x
    except _Stop:
        x = best[1]
    return x, float(proj.cost(x[None])[0]), count[0]


def _best_of(problem: Objective, xs: Sequence[np.ndarray | None]) -> np.ndarray:
    X = np.stack([x for x in xs if x is not None])
    err, cost = problem.measure(X)
    return np.asarray(X[best_index(err, cost)])


# ------------------------------------------------------------------------------- the screen
def screen(
    topologies: Sequence[Topology],
    make: Callable[[Topology], Projected],
    rng: np.random.Generator,
    deadline: float,
    workers: int = 1,
) -> dict[str, tuple[float, np.ndarray]]:
    """``name -> (best relative RMS fit, its design)`` of the topologies screened before ``deadline``.

    :data:`SCREEN_DESIGNS` random designs of each (:class:`Projected`: the tracer and the
    placement fitted); the first three (:data:`FIRST`) always, the rest in a random order of ``rng``.
    With ``workers`` (more than one) the list is dealt out to that many local processes
    (``make`` must pickle, as :class:`Maker` does), each screening its share until the deadline;
    each topology's designs come from its own seed, so a topology screened is screened alike
    whatever the number of workers.
    """
    first = [t for t in topologies if t.name in FIRST]
    rest = [t for t in topologies if t.name not in FIRST]
    order = first + [rest[i] for i in rng.permutation(len(rest))]
    seeds = [int(x) for x in rng.integers(0, 2**63, len(order))]
    w = max(1, min(workers, len(order)))
    if w == 1:
        return _screen_share(make, order, seeds, deadline)
    with _pool(w) as pool:
        tasks = [pool.submit(_screen_share, make, order[k::w], seeds[k::w], deadline, k == 0) for k in range(w)]
        return {name: got for share in _results(tasks) for name, got in share.items()}


def _screen_share(
    make: Callable[[Topology], Projected],
    topologies: Sequence[Topology],
    seeds: Sequence[int],
    deadline: float,
    one: bool = True,
) -> dict[str, tuple[float, np.ndarray]]:
    """:func:`screen` of ``topologies`` in turn, each from its seed, until ``deadline`` (those of :data:`FIRST`
    always, and with ``one`` at least one; a worker process's task)."""
    out: dict[str, tuple[float, np.ndarray]] = {}
    for t, seed in zip(topologies, seeds, strict=True):
        if (out or not one) and time.monotonic() > deadline and t.name not in FIRST:
            break
        proj = make(t)
        lo, hi = proj.bounds
        X = lo + np.random.default_rng(seed).random((SCREEN_DESIGNS, len(lo))) * (hi - lo)
        sc = proj.score(X)
        rms = np.where(sc.violation > 0, np.inf, sc.error)
        i = int(np.argmin(np.where(np.isfinite(rms), rms, sc.cost + 1e6)))
        out[t.name] = (float(rms[i]), X[i])
    return out


def _tracer_base(problem: Problem) -> tuple[int, int]:
    """Joint indices ``i, j`` of the first two other joints of the tracer's link."""
    sp = problem.space
    link = next(ln for ln in sp.template.links if sp.tracer in ln.joints and ln.name != "ground")
    a, b = [j for j in link.joints if j != sp.tracer][:2]
    return sp.joint(a), sp.joint(b)


def _shape_only(problem: Problem) -> bool:
    return bool(getattr(problem, "shape_only", False))


# ------------------------------------------------------------------ the projected objective
#: samples of the turn the projected objective solves each design at
PROJECTED_SAMPLES = 128
#: designs scored at once (the nearest points take designs x targets x samples)
CHUNK = 64
#: targets the projected search fits at most (a dense drawing is thinned evenly)
SEARCH_TARGETS = 100
#: rounds of nearest points and tracer fit after the fit over the shifts
ICP_ROUNDS = 2
#: the crank ranges (fractions of a turn) a partial curve is fitted over; the least is 90 deg
PARTIAL_WIDTHS = (0.27, 0.375, 0.5, 0.75)


def partial_widths(n: int, m: int) -> list[int]:
    """The widths, in samples of a turn of ``n``, a partial curve of ``m`` targets is fitted over: each of
    :data:`PARTIAL_WIDTHS`, widened where needed so that its window (from the first target to the last,
    ``((m - 1) w) // m`` steps: :meth:`Projected._refined`) turns the crank at least a quarter of the turn.

    >>> partial_widths(128, 100), partial_widths(128, 10), partial_widths(128, 3)
    ([35, 48, 64, 96], [36, 48, 64, 96], [48, 64, 96])
    >>> [((10 - 1) * w) // 10 * 360 / 128 for w in partial_widths(128, 10)][0]
    90.0
    """
    quarter = -(-n // 4)
    least = -(-m * quarter // (m - 1))
    return list(dict.fromkeys(min(max(int(round(w * n)), least), n) for w in PARTIAL_WIDTHS))  # each once


@dataclass(frozen=True)
class Placed:
    """Designs solved over a turn, their tracer and placement fitted (:meth:`Projected.placed`).

    Attributes
    ----------
    params, solution : Params, Solution
        The compiled designs and their joints over the turn (``solution.z``: joints x designs x samples).
    fit : TracerFit
        The tracer ``c``, the placement ``a, b``, the shift and direction of the correspondence.
    window : ndarray (N, n) bool
        The samples of the range fitted (all of the turn for a closed curve).
    distance : ndarray (N,)
        Two-sided mean squared distance between the window's samples and the targets.
    span : ndarray (N,) int
        The window's span in samples.
    parts : ndarray (N, m + n)
        The squared residuals that sum to ``distance`` (:func:`_chamfer`).
    """

    params: Any
    solution: Any
    fit: Any
    window: np.ndarray
    distance: np.ndarray
    span: np.ndarray
    parts: np.ndarray


@dataclass(frozen=True, eq=False)
class Projected(Objective):
    """Path generation with the tracer and the similarity placement eliminated (variable projection).

    The design vector is the problem's without the tracer. Each design is solved at
    :data:`PROJECTED_SAMPLES` inputs over a turn; the tracer's place on its link, the curve's
    placement and the shift of the correspondence come from :func:`~.tracer.fit_shifts`
    (targets spread evenly in crank angle over the whole turn, or, ``partial``, over each
    range of :data:`PARTIAL_WIDTHS`). Cost: mean squared placed distance / ``L^2`` plus
    ``PENALTY`` times the violation (assembly over the turn when closed, transmission angles,
    the curve's size; a partial design with no range where it assembles: 1).
    """

    problem: Problem
    partial: bool = False
    samples: int = PROJECTED_SAMPLES

    @cached_property
    def targets(self) -> np.ndarray:
        """The targets the search fits: every one, or a drawing of more than :data:`SEARCH_TARGETS` points resampled
        to that many evenly by arc length along it (:func:`along`; closed unless ``partial``: the whole turn's
        curve goes from the last target back to the first)."""
        T = self.problem.targets
        return T if len(T) <= SEARCH_TARGETS else along(T, SEARCH_TARGETS, closed=not self.partial)

    @property
    def keep(self) -> np.ndarray:
        """Indices of the problem's design vector this one keeps (all but the tracer's two)."""
        k = self.problem.space.free.index(self.problem.space.tracer)
        return np.delete(np.arange(self.problem.dim), [2 * k, 2 * k + 1])

    @property
    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        lo, hi = self.problem.bounds
        return lo[self.keep], hi[self.keep]

    @property
    def scale(self) -> float:
        return self.problem.scale

    def fingerprint(self) -> str:
        return digest(self.problem.fingerprint(), self.partial, self.samples)

    def full(self, X: np.ndarray) -> np.ndarray:
        """The problem's design vectors of ``X``, the tracer anywhere off its link's line (it is fitted later)."""
        X = np.atleast_2d(X)
        sp = self.problem.space
        out = np.zeros((len(X), self.problem.dim))
        out[:, self.keep] = X
        k = sp.free.index(sp.tracer)
        i, j = (sp.free.index(sp.template.joint_names[a]) for a in _tracer_base(self.problem))
        zi = out[:, 2 * i] + 1j * out[:, 2 * i + 1]
        zp = zi + (0.5 + 0.5j) * (out[:, 2 * j] + 1j * out[:, 2 * j + 1] - zi)
        out[:, 2 * k], out[:, 2 * k + 1] = zp.real, zp.imag
        return out

    def fitted(self, X: np.ndarray) -> tuple[Any, Any, list[tuple[TracerFit, int]]]:
        """``(params, solution, fits)`` of designs ``X``: the best fit over the shifts, for each range's width."""
        from ..params import compile as compile_params
        from ..positions import solve

        sp = self.problem.space
        params = compile_params(sp.template, sp.poses(self.full(X)), sp.plan)
        n = self.samples
        theta = params.pose_inputs[0][:, None] + (2 * np.pi / n) * np.arange(n)
        sol = solve(params, theta[None])
        i, j = _tracer_base(self.problem)
        widths = partial_widths(n, len(self.targets)) if self.partial else [n]
        spec = spectra(sol.z[i], sol.z[j])  # one design's spectra serve every width
        return params, sol, [(fit_shifts(sol.z[i], sol.z[j], self.targets, w, spec=spec), w) for w in widths]

    def score(self, X: np.ndarray) -> Score:
        X = np.atleast_2d(X)
        parts = [self._score(X[k : k + CHUNK]) for k in range(0, len(X), CHUNK)]
        return Score(*(np.concatenate([getattr(p, f) for p in parts]) for f in ("cost", "error", "violation")))

    def _score(self, X: np.ndarray) -> Score:
        p = self.placed(X)
        viol = self._violation(p.params, p.solution, p.fit, p.window)
        mse = p.distance / self.problem.scale**2
        err = np.sqrt(mse)
        return Score(
            np.where(np.isfinite(mse), mse, 1.0) + PENALTY * viol, np.where(np.isfinite(err), err, np.inf), viol
        )

    def placed(self, X: np.ndarray) -> Placed:
        """The designs ``X`` solved, their tracer and placement fitted and refined on nearest points.

        From the fit over the shifts (:meth:`fitted`), :data:`ICP_ROUNDS` rounds of: each
        target's nearest sample of the placed curve within the window, then :func:`~.tracer.fit`
        on those pairs; per design the round of least two-sided mean squared distance
        (targets to the curve's samples plus the window's samples to the targets) is kept.
        """
        params, sol, fits = self.fitted(X)
        best: Placed | None = None
        for f, width in fits:  # each range's width refined, the best kept per design
            p = self._refined(params, sol, f, width)
            if best is None:
                best = p
                continue
            take = p.distance < best.distance
            best = Placed(
                params,
                sol,
                _choose(take, p.fit, best.fit),
                np.where(take[:, None], p.window, best.window),
                np.where(take, p.distance, best.distance),
                np.where(take, p.span, best.span),
                np.where(take[:, None], p.parts, best.parts),
            )
        assert best is not None
        return best

    def _refined(self, params: Any, sol: Any, f: TracerFit, width: int) -> Placed:
        """The fit ``f`` over the shifts at one range's ``width``, refined on nearest points.

        The nearest points are searched among the window's samples only (:func:`_window`: a partial curve's
        range is a quarter to three quarters of the turn), then set back in their places on the turn."""
        N, n = len(f.sse), self.samples
        m = len(self.targets)
        last = ((m - 1) * width) // m
        rows, cols = np.arange(N)[:, None], _window(f.shift, last + 1, n)
        i, j = _tracer_base(self.problem)
        Xi, Xj = sol.z[i][rows, cols], sol.z[j][rows, cols]
        inside = np.isfinite(Xi) & np.isfinite(Xj)
        best_d, k, parts = _chamfer(f, Xi, Xj, self.targets, inside)
        for _ in range(ICP_ROUNDS):
            g = replace(fit(Xi[rows, k], Xj[rows, k], self.targets), shift=f.shift, direction=f.direction)
            d, k2, p2 = _chamfer(g, Xi, Xj, self.targets, inside)
            take = d < best_d
            f, best_d = _choose(take, g, f), np.where(take, d, best_d)
            k, parts = np.where(take[:, None], k2, k), np.where(take[:, None], p2, parts)
        window = np.zeros((N, n), bool)
        window[rows, cols] = inside
        on_turn = np.zeros((N, m + n))
        on_turn[:, :m] = parts[:, :m]
        on_turn[rows, m + cols] = parts[:, m:]
        summed = np.where(np.isfinite(best_d), on_turn.sum(axis=1), np.inf)  # as the widths' sums: a tie stays one
        return Placed(params, sol, f, window, summed, np.full(N, last), on_turn)

    def residuals(self, X: np.ndarray) -> np.ndarray:
        """Each target's and each window sample's distance (the chamfer's parts) / ``L``, and the penalty's root."""
        p = self.placed(np.atleast_2d(X))
        viol = self._violation(p.params, p.solution, p.fit, p.window)
        r = np.sqrt(np.where(np.isfinite(p.parts), p.parts, 1.0 / p.parts.shape[1])) / self.problem.scale
        out: np.ndarray = np.concatenate([r, np.sqrt(PENALTY * viol)[:, None]], axis=1)
        return out

    def _violation(self, params: Any, sol: Any, f: Any, window: np.ndarray) -> np.ndarray:
        sp = self.problem.space
        z = sol.z
        with np.errstate(invalid="ignore"):
            if self.partial:
                v = np.where(np.isfinite(f.sse), 0.0, 1.0)
            else:
                short = np.nan_to_num(np.maximum(-sol.margin, 0.0), nan=0.0)
                v = short.sum(axis=0).mean(axis=-1) if short.size else np.zeros(len(f.sse))
            v = np.where(params.valid, v, v + 1.0)
            cos_lim = np.cos(np.radians(transmission_limit(self.problem.min_transmission, MARGIN)))
            for jn, a, b in sp.transmission:
                zj = z[sp.joint(jn)]
                u, w = z[sp.joint(a)] - zj, z[sp.joint(b)] - zj
                c = np.abs((np.conj(u) * w).real / (np.abs(u) * np.abs(w)))
                c = np.where(np.isfinite(c) & window, c, 0.0)
                v = v + np.maximum(np.max(c, axis=-1) - cos_lim, 0.0)
            i, j = _tracer_base(self.problem)
            P = np.where(window, z[i] + f.c[:, None] * (z[j] - z[i]), np.nan)
            pose = params.pose.copy()
            pose[sp.joint(sp.tracer)] = pose[i] + f.c * (pose[j] - pose[i])
            v = v + _too_small(P, pose, 1.0) / MIN_CURVE_SIZE + degenerate(sp, pose) / MIN_LINK
        return np.asarray(v)


def along(T: np.ndarray, n: int, closed: bool = False) -> np.ndarray:
    """``n`` points evenly spaced in arc length along the polyline through the points ``T`` (complex), from its first
    point to its last; ``closed``: round the loop that goes on from the last back to the first (the first point not
    repeated at the end: the gap from the last point to the first is a spacing like the others).

    A drawing is a line, not its vertices: where its points are unevenly spaced (a long straight stroke given by its
    two ends, as between the strokes of a letter E, or a closed curve's stroke from its last point to its first),
    thinning them by index would leave that part without targets and the search free to draw anything there.

    >>> along(np.array([0, 1, 3 + 0j]), 4).real.tolist()
    [0.0, 1.0, 2.0, 3.0]
    >>> along(np.array([0, 1, 1 + 1j, 1j]), 8, closed=True).tolist()  # a square's corners: its fourth side too
    [0j, (0.5+0j), (1+0j), (1+0.5j), (1+1j), (0.5+1j), 1j, 0.5j]
    """
    P = np.append(T, T[:1]) if closed else T
    run = np.concatenate([[0.0], np.cumsum(np.abs(np.diff(P)))])
    s = np.linspace(0.0, run[-1], n, endpoint=not closed)
    out: np.ndarray = np.interp(s, run, P.real) + 1j * np.interp(s, run, P.imag)
    return out


def _chamfer(
    f: Any, Xi: np.ndarray, Xj: np.ndarray, T: np.ndarray, window: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Two-sided mean squared distance (N,) between the placed curves' window samples and the targets.

    Also each target's nearest window sample (N, m), and the squared residuals (N, m + n)
    that sum to the distance: each target's squared distance to the curve (its nearest
    sample or either chord there) over ``m``, each window sample's to its nearest target over
    the window's size. The curve is ``a + b (X_i + c (X_j - X_i))``. The nearest pairs come from
    the expanded square (:func:`_nearest_pairs`); their distances are taken again directly.
    """
    P = f.a[:, None] + f.b[:, None] * (Xi + f.c[:, None] * (Xj - Xi))
    P = np.where(window & np.isfinite(P), P, 0.0)
    k, near = _nearest_pairs(P, T, window)
    rows = np.arange(len(P))[:, None]
    to_curve = np.minimum(np.abs(P[rows, k] - T[None, :]) ** 2, chords_to(P, window, T, k)) / len(T)
    to_targets = np.where(window, np.abs(P - T[near]) ** 2, 0.0) / np.maximum(window.sum(axis=1), 1)[:, None]
    parts = np.concatenate([to_curve, to_targets], axis=1)  # (N, m + n): squared residuals
    d = parts.sum(axis=1)
    return np.where(np.isfinite(d) & np.isfinite(f.sse), d, np.inf), k, parts


def _nearest_pairs(P: np.ndarray, T: np.ndarray, window: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each target's nearest window sample (N, m) and each sample's nearest target (N, n).

    The expanded square of the centred points, ``|p - t|^2 = |p|^2 + |t|^2 - 2 p.t``, as one product of
    ``[-2 t, 1, |t|^2]`` and ``[p, |p|^2, 1]`` (``|p|^2`` infinite off the window: such a sample is never
    chosen), laid out twice, (N, m, n) and (N, n, m), so that each search runs along memory. (Single
    precision would halve the memory but pair wrongly where distances are 1e-3 of the curves' size
    or less, near a good fit: its rounding on the squared size is 1e-7.)
    """
    c = T.mean()
    Pc, Tc = P - c, T - c
    t = np.stack([-2 * Tc.real, -2 * Tc.imag, np.ones(len(T)), Tc.real**2 + Tc.imag**2], axis=-1)  # (m, 4)
    p2 = np.where(window, Pc.real**2 + Pc.imag**2, np.inf)
    p = np.stack([Pc.real, Pc.imag, p2, np.ones(P.shape)], axis=-1)  # (N, n, 4)
    return np.argmin(t @ p.transpose(0, 2, 1), axis=2), np.argmin(p @ t.T, axis=2)


def _window(shift: np.ndarray, width: int, n: int) -> np.ndarray:
    """The samples (N, width) of each design's window, in their order along the turn of ``n`` samples: from
    ``shift`` on, round the turn.

    >>> _window(np.array([0, 6]), 3, 8).tolist()
    [[0, 1, 2], [6, 7, 0]]
    """
    return np.asarray(np.mod(shift[:, None] + np.arange(width)[None, :], n))


def _choose(take: np.ndarray, f: Any, g: Any) -> Any:
    return type(f)(*(np.where(take, getattr(f, k), getattr(g, k)) for k in f.__dataclass_fields__))


#: samples of the dense check of a written design's sweep
CHECK_SAMPLES = 3601


def written(proj: Projected, x: np.ndarray, outcome: Outcome, source: str | None = None) -> Synthesis:
    """The mechanism of a projected design: tracer placed, moved onto the targets, its sweep, densely checked.

    The sweep is the whole turn, or (partial) the range the targets were fitted over. The
    check solves :data:`CHECK_SAMPLES` inputs over the sweep: it must assemble at all of them,
    keep the transmission angles, and its curve's size (:data:`MIN_CURVE_SIZE`); a partial
    sweep is at least 90 deg by construction (:func:`partial_widths`). Each target's error is
    its distance to the nearest of those samples.
    """
    from ..params import compile as compile_params
    from ..positions import solve
    from .run import describe

    prob, sp = proj.problem, proj.problem.space
    placed = proj.placed(np.asarray(x, float)[None])
    params, f, last = placed.params, placed.fit, int(placed.span[0])
    i, j = _tracer_base(prob)
    pose = params.pose[:, 0].copy()
    pose[sp.joint(sp.tracer)] = pose[i] + f.c[0] * (pose[j] - pose[i])
    pose = f.a[0] + f.b[0] * pose
    xfull = np.concatenate([[pose[sp.joint(n)].real, pose[sp.joint(n)].imag] for n in sp.free])
    moved = compile_params(sp.template, sp.poses(xfull[None]), sp.plan)
    n, m = proj.samples, len(prob.targets)
    start = float(moved.pose_inputs[0][0]) + 2 * np.pi * int(f.shift[0]) / n
    span = 2 * np.pi * last / n if proj.partial else 2 * np.pi
    th = start + np.linspace(0.0, span, CHECK_SAMPLES)
    z = solve(moved, th[None, None]).z[:, 0, :]
    P = z[sp.joint(sp.tracer)]
    d = np.abs(P[None, :] - prob.targets[:, None])
    near = np.argmin(np.where(np.isfinite(d), d, np.inf), axis=1)
    errors = d[np.arange(m), near]
    mu = _smallest_transmission(sp, z)
    ok = bool(np.all(np.isfinite(P))) and mu >= prob.min_transmission - 1e-9
    ok = ok and float(_too_small(P[None], pose[:, None], 0.0)[0]) == 0.0 and not degenerate(sp, pose[:, None])[0]
    mech = _swept(sp.mechanism(xfull), np.degrees(start), np.degrees(start + span), sp.topology)
    mech = replace(mech, name=named(mech.name, errors, sp.template.length_unit, prob.scale))  # as one topology's
    if not ok:  # as a single topology's search names it: the file says so where a reader looks first
        mech = replace(mech, name=f"INFEASIBLE {mech.name} (it breaks a constraint)")
    sweep = (float(np.degrees(start)), float(np.degrees(start + span))) if proj.partial else None
    out = Synthesis(
        mech, xfull, errors, np.degrees(th[near]), None, prob.scale, ok, mu, outcome, sweep, topology=sp.topology,
        bound=prob.min_transmission,
    )  # fmt: skip
    text = f"topology {sp.topology} ({len(sp.template.joint_names)} joints), crank {np.degrees(span):.4g} deg\n"
    return replace(out, mechanism=replace(mech, description=text + describe(out, prob, source)))


def _smallest_transmission(sp: Any, z: np.ndarray) -> float:
    """The smallest transmission angle (degrees, folded to [0, 90]) of a space's dyads over the samples ``z``."""
    mu = 90.0
    with np.errstate(invalid="ignore"):
        for jn, a, b in sp.transmission:
            u, w = z[sp.joint(a)] - z[sp.joint(jn)], z[sp.joint(b)] - z[sp.joint(jn)]
            c = np.abs((np.conj(u) * w).real / (np.abs(u) * np.abs(w)))
            mu = min(mu, float(np.degrees(np.arccos(np.clip(np.nanmax(c), 0.0, 1.0)))))
    return mu


def _swept(mech: Any, start: float, stop: float, topology: str) -> Any:
    """The mechanism with its driver sweeping ``start`` to ``stop`` (degrees), named by its topology."""
    from ..model import Mechanism

    data = mech.to_dict()
    step = (stop - start) / max(1, int(np.ceil(abs(stop - start))))
    data["drivers"][0]["angles"] = {"start": float(start), "stop": float(stop), "step": float(step)}
    data["name"] = f"synthesised {topology}"
    return Mechanism.from_dict(data, source=f"synthesised {topology}")
