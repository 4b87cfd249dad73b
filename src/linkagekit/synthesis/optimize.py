"""Differential evolution and CMA-ES over whole generations, a least-squares polish, restarts, checkpoints.

The engine of every synthesis task: it searches an :class:`~linkagekit.synthesis.base.Objective`
(path, motion, function generation or a user's own), seeing only its bounds, costs,
residuals, dense check and fingerprint.

One restart
    Either :class:`scipy.optimize.differential_evolution`'s solver (``rand1bin``, dithered
    mutation, ``updating="deferred"``, ``vectorized=True``) or CMA-ES
    (:mod:`linkagekit.synthesis.cmaes`); they take turns from restart to restart. Every
    generation's designs go to :class:`~linkagekit.synthesis.distribute.Evaluator` as one
    array. Stepping a search one generation at a time is what lets the run save its state
    after every generation and stop on the clock.
Polish
    The ``POLISHED`` best distinct members are refined by
    :func:`scipy.optimize.least_squares` on the objective's residuals (for a path:
    ``e_i / (L sqrt(m))`` and ``sqrt(PENALTY * violation)``), each by both of its bounded methods (trust-region
    reflective suits untimed problems, whose exact solutions form a manifold; dogbox suits
    timed ones; see :func:`polish_method`), with the Jacobian by forward differences
    computed as one batch of ``dim + 1`` designs; the refinement of the nearest points is
    run to convergence there (3 Newton steps), so the residuals are smooth in the design.
Restarts
    Up to ``restarts`` independent runs, each from its own child of ``SeedSequence(seed)``;
    the run stops early once a design meets every target within ``goal * L``.

The same seed gives the same result (on any number of processes or a cluster) unless the
clock stops the run (``seconds``); the result says which.

Checkpoints
    A ``.npz`` file (NumPy arrays and one JSON header, read with ``allow_pickle=False``, so
    loading a checkpoint never executes anything), written atomically after every
    generation: the restart and generation, the solver's population, energies, random
    generator state and dither, and the results of the restarts already done. A run given
    the same checkpoint continues where the file left off and ends with the result of an
    uninterrupted run.
"""

from __future__ import annotations

import json
import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import InputError, LinkageError, shorten, shorten_path
from ..files import stray_temporaries, write_atomic
from ..geometry import FloatArray
from .base import Objective
from .distribute import RETRIES, Evaluator, WorkersLost, daemonic
from .objective import best_index

if TYPE_CHECKING:
    from ..model import Mechanism

#: designs polished per restart
POLISHED = 5
#: residual evaluations of each of them
POLISH_NFEV = 100
#: residual evaluations of the last polish of the best design
FINAL_POLISH = 2000
#: the solver's fields that change from generation to generation (all else follows from its arguments)
_SOLVER_STATE = ("population", "population_energies", "_random_population_index", "feasible", "constraint_violation")
CHECKPOINT_VERSION = 4  # 4: the polish is saved and the best is chosen by max error; 3: CMA-ES changed
#: the search a restart runs, as a function of its cost: (designs, dim) -> (designs,)
Cost = Callable[[np.ndarray], np.ndarray]


@dataclass(frozen=True)
class Limit:
    """The values one search setting may take: a number from ``low`` to ``high``, whole or not.

    ``low`` is excluded when ``low_open`` (a time must be over 0); NaN is never within.

    >>> LIMITS["seconds"].check(float("nan"), "seconds")
    Traceback (most recent call last):
    ...
    linkagekit.errors.InputError: seconds: expected a positive time up to 1e7 s, got nan
    >>> LIMITS["restarts"].check(0, "restarts")
    Traceback (most recent call last):
    ...
    linkagekit.errors.InputError: restarts: expected a whole number from 1 to 10000, got 0
    """

    low: float
    high: float
    whole: bool = False
    low_open: bool = False
    what: str = ""

    def check(self, value: Any, name: str) -> Any:
        """``value`` when it is within; otherwise an :class:`InputError` naming ``name`` (the argument or option)."""
        number = isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)
        whole = isinstance(value, (int, np.integer)) and not isinstance(value, bool)
        above = number and (value > self.low if self.low_open else value >= self.low)
        if not (above and value <= self.high and (whole or not self.whole)):
            kind = self.what or f"{'a whole number' if self.whole else 'a number'} from {self.low:g} to {self.high:g}"
            raise InputError(f"{name}: expected {kind}, got {shorten(repr(value))}")
        return value


#: what each search setting may be: :class:`Settings` (the Python API) and the command line's options check these
LIMITS: dict[str, Limit] = {
    "seconds": Limit(0.0, 1e7, low_open=True, what="a positive time up to 1e7 s"),
    "restarts": Limit(1, 10_000, whole=True),
    "generations": Limit(1, 10_000_000, whole=True),
    "popsize": Limit(1, 10_000, whole=True),
    "goal": Limit(0.0, 1e300, what="a finite error, at least 0"),
    "workers": Limit(1, 1024, whole=True),
}


def check_settings(**values: Any) -> None:
    """Each of ``values`` (search settings by name, None: the default) within its :data:`LIMITS`.

    For the ways in that do not always build :class:`Settings` (which checks its own), so
    that a bad argument is refused even when the engine is not run.

    >>> check_settings(seconds=5.0, workers=None)
    """
    for name, value in values.items():
        if value is not None:
            LIMITS[name].check(value, name)


@dataclass(frozen=True)
class Settings:
    """How to search.

    Attributes
    ----------
    seed : int
    seconds : float
        Time budget of the whole run (checked between generations).
    restarts : int
        Independent searches at most (differential evolution and CMA-ES in turn).
    generations : int
        Generations of a differential-evolution search at most; a CMA-ES search evaluates
        at most as many designs (``generations * popsize * dim``).
    popsize : int
        Population = ``popsize * dim`` (scipy's convention).
    goal : float
        Stop once every target is within ``goal * L`` (relative to the targets' diagonal).
    workers : int
        Local processes. With two or more (and no ``scheduler`` or ``checkpoint``), as many
        searches run at once, each generation of one of them on one process (see :class:`_Run`);
        otherwise the searches run one after another, each generation split over the processes.
    scheduler : str, optional
    checkpoint : str, optional
    pareto : bool
        Also search at raised transmission bounds (``Objective.raised``) and keep the designs not
        beaten in both the error and the smallest transmission angle (``Outcome.front``).
    """

    seed: int = 0
    seconds: float = 60.0
    restarts: int = 1000
    generations: int = 500
    popsize: int = 15
    goal: float = 1e-5
    workers: int = 1
    scheduler: str | None = None
    checkpoint: str | None = None
    pareto: bool = False

    def __post_init__(self) -> None:
        for name, limit in LIMITS.items():  # every way into the engine passes here: checked once, by the argument
            limit.check(getattr(self, name), name)

    def key(self) -> dict[str, Any]:
        """What a checkpoint must agree on to be continued."""
        key = {"seed": self.seed, "restarts": self.restarts, "generations": self.generations, "popsize": self.popsize}
        return {**key, "pareto": True} if self.pareto else key


def default_workers() -> int:
    """Every core this process may run on (``os.sched_getaffinity``, else ``os.cpu_count()``): the default workers;
    1 in a daemonic process (a :class:`multiprocessing.pool.Pool`'s worker), which cannot start processes."""
    if daemonic():
        return 1
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # no affinity on this platform
        return max(1, os.cpu_count() or 1)


@dataclass
class Progress:
    """What the progress callback sees after every generation.

    Attributes
    ----------
    restart : int
        The restart under way (counted from 0; after a restart's polish, the next one's number).
    generation : int
        Generations of this restart so far (0 right after a polish).
    best_cost : float
        The lowest cost found so far in the run.
    best_error : float
        The largest target error of the best polished design so far, relative to the targets'
        diagonal ``L`` (NaN until a restart is finished).
    evaluations : int
        Designs scored in the run so far.
    elapsed : float
        Seconds of the run so far.
    """

    restart: int
    generation: int
    best_cost: float
    best_error: float
    evaluations: int
    elapsed: float
    source: str = "search"  # "atlas": the atlas's answer, before any search (synthesis.atlas)


@dataclass
class Outcome:
    """The best design of a run and how the run went.

    Attributes
    ----------
    x : ndarray (dim,)
        The best design vector found.
    cost : float
        Its cost (mean squared relative error plus the constraint penalty).
    restarts : int
        Restarts finished (each search ended by its polish), those of a checkpoint included.
    generations : int
        Generations run over all restarts.
    evaluations : int
        Designs scored over all restarts.
    seconds : float
        Wall-clock time of the run.
    stopped_by : str
        What ended the run: ``"goal"``, ``"restarts"`` or ``"time"``.
    history : list of (float, float)
        ``(cost, max error / L)`` of each restart's best design.
    front : list of (ndarray, float, float)
        With ``Settings.pareto``: ``(x, max error / L, smallest transmission angle)`` of every polished
        design no other beats in both (:func:`~linkagekit.synthesis.front.non_dominated`), the most
        accurate first; otherwise empty.
    """

    x: np.ndarray
    cost: float
    restarts: int
    generations: int
    evaluations: int
    seconds: float
    stopped_by: str  # "goal", "restarts" or "time"
    history: list[tuple[float, float]] = field(default_factory=list)  # (cost, max error / L) per restart
    front: list[tuple[np.ndarray, float, float]] = field(default_factory=list)


def optimize(
    problem: Objective,
    settings: Settings,
    progress: Callable[[Progress], None] | None = None,
    initial: Callable[[], np.ndarray] | None = None,
) -> Outcome:
    """Search ``problem`` as ``settings`` say; returns the best design found (by :func:`objective.measure`).

    ``initial()``: designs (k, dim), best first, that seed the first searches (:func:`_search`); called
    once the run is set up (its checkpoint read, its workers started), its time within the budget. When
    the first of them meets the goal, it is the run's result.
    """
    # The searches take turns with the objective's cheaper variants (a path problem's order dropped: a fit
    # found without the order may well be in order); the polish and the choice of the best use the objective.
    # With --pareto, every other search is of the objective at a raised transmission bound (RAISES, in turn).
    variants = problem.variants()
    raised = tuple(r for r in (problem.raised(d) for d in RAISES) if r is not None) if settings.pareto else ()
    objectives = variants + raised
    run = _Run.begin(problem, settings, progress, len(variants), objectives)
    if run.finished is None:  # a finished checkpoint's result is just written again
        with Evaluator(objectives, settings.workers, settings.scheduler) as ev:
            if not run.seed(initial):
                run.search(ev)
        run.finished = run.stopped_by
        if settings.checkpoint:
            run.save()
    return run.outcome()


@dataclass(frozen=True)
class Optimum:
    """The outcome of a search of any :class:`~linkagekit.synthesis.base.Objective` (:func:`search`).

    Attributes
    ----------
    x : ndarray (dim,)
        The best design vector found.
    error : float
        Its error by the objective's dense check (``inf`` if it is infeasible there).
    cost : float
    feasible : bool
    mechanism : Mechanism or None
        ``objective.mechanism(x)``, or None when the objective builds none.
    outcome : Outcome
    """

    x: np.ndarray
    error: float
    cost: float
    feasible: bool
    mechanism: Mechanism | None
    outcome: Outcome


def search(
    objective: Objective,
    *,
    seed: int = 0,
    seconds: float = 60.0,
    restarts: int = 1000,
    generations: int = 500,
    popsize: int = 15,
    goal: float = 1e-5,
    workers: int | None = None,
    scheduler: str | None = None,
    checkpoint: str | None = None,
    progress: Callable[[Progress], None] | None = None,
) -> Optimum:
    """Search any objective with the synthesis engine (``synthesize(objective=...)`` calls this).

    ``workers``: local processes, by default every core (:func:`default_workers`) if the objective
    pickles (a class defined where pickle cannot find it again runs in this process).

    Examples
    --------
    >>> from linkagekit.synthesis.base import Objective, Score
    >>> class Nearest(Objective):  # the point of the unit square nearest to (0.3, 0.7)
    ...     bounds = (np.zeros(2), np.ones(2))
    ...     def score(self, X):
    ...         r = X - [0.3, 0.7]
    ...         return Score(np.sum(r * r, axis=1), np.abs(r).max(axis=1), np.zeros(len(X)))
    ...     def residuals(self, X):
    ...         return X - [0.3, 0.7]
    ...     def fingerprint(self):
    ...         return "nearest"
    >>> out = search(Nearest(), restarts=1, generations=5)
    >>> bool(out.error < 1e-9), out.mechanism is None
    (True, True)
    """
    if workers is None:  # every core, if the objective can be sent to worker processes
        workers = default_workers() if _picklable(objective) else 1
    settings = Settings(seed, seconds, restarts, generations, popsize, goal, workers, scheduler, checkpoint)
    outcome = optimize(objective, settings, progress)
    s = objective.check(outcome.x[None])
    try:
        mech = objective.mechanism(outcome.x)
    except NotImplementedError:
        mech = None
    feasible = bool(s.violation[0] == 0)
    error = float(s.error[0]) if feasible else float("inf")
    return Optimum(outcome.x, error, float(s.cost[0]), feasible, mech, outcome)


#: degrees above the transmission bound of --pareto's searches
RAISES = (10.0, 20.0, 30.0)
#: generations between two measures of the best design of the search under way (the progress reports it, so it is
#: kept: a candidate of every polish after; by generations, not seconds, so that the result does not hang on the clock)
MEASURE_EVERY = 10


def _picklable(objective: Objective) -> bool:
    """Whether ``objective`` can be sent to a worker process."""
    import pickle

    try:
        pickle.dumps(objective)
    except (pickle.PicklingError, AttributeError, TypeError):
        return False
    return True


@dataclass
class _Run:
    """One :func:`optimize` run: its restarts so far, the one under way, the clock (continued from a checkpoint).

    Restart ``r`` is planned by its number alone (:meth:`plan`, :meth:`seed`), so the searches do
    not depend on where or in which order they run. With several local workers and no checkpoint,
    as many restarts run at once, each whole on one worker process (a *lane*: :meth:`in_lanes`);
    the restarts kept are those one worker would have finished (up to the first that meets the
    goal), so a run that the clock does not stop gives the same result on any number of workers.
    """

    problem: Objective
    settings: Settings
    progress: Callable[[Progress], None] | None
    start: float
    n_variants: int = 1
    objectives: tuple[Objective, ...] = ()  # what the searches score: the variants, then the raised bounds
    state: dict[str, Any] | None = None  # a checkpoint's, until its unfinished search is restored
    done: list[dict[str, Any]] = field(default_factory=list)  # the finished restarts
    restart: int = 0
    generation: int = 0
    evaluations: int = 0
    elapsed0: float = 0.0  # the checkpointed runs' time
    stopped_by: str = "restarts"
    finished: str | None = None  # what stopped the run, once it is over
    polished: list[np.ndarray] | None = None  # the polish under way: the candidates polished so far
    polish_time: float = 0.0  # seconds of the longest whole polish of a search so far
    generation_time: float = 0.0  # seconds of the last generation
    front: list[tuple[np.ndarray, float, float]] = field(default_factory=list)  # --pareto's designs
    seen: float = np.inf  # the smallest max error measured so far, a search under way's best included
    kept: tuple[float, np.ndarray] | None = None  # the restart under way's best measured design (its max error, x)
    lane: Any = None  # on a worker running a lane's restart: its line to the parent (_WorkerLane)
    initial: np.ndarray | None = None  # designs that seed the first searches, best first
    close: bool = False  # the first of them is within SEED_LIMIT: differential evolution is seeded too

    @classmethod
    def begin(
        cls,
        problem: Objective,
        settings: Settings,
        progress: Callable[[Progress], None] | None,
        n_variants: int = 1,
        objectives: tuple[Objective, ...] = (),
    ) -> _Run:
        """A new run, or the checkpoint's when there is one."""
        run = cls(problem, settings, progress, time.monotonic(), n_variants, objectives or (problem,))
        state = _load(settings, problem, run.template) if settings.checkpoint else None
        if state is not None:
            run.state, run.done, run.restart = state, state["done"], state["restart"]
            run.generation, run.evaluations, run.elapsed0 = state["generation"], state["evaluations"], state["elapsed"]
            run.finished = state["stopped_by"]
            run.stopped_by = run.finished or run.stopped_by
            if state["kept"] is not None:
                run.kept = state["kept"]
                run.seen = state["kept"][0]
        if run.finished is None and any(d["max_error"] <= settings.goal for d in run.done):
            run.stopped_by, run.restart = "goal", settings.restarts
        if settings.pareto and run.done:  # a checkpoint's: its searches' best designs (their other ones are gone)
            run.keep(np.array([d["x"] for d in run.done]))
        return run

    def seed_of(self, restart: int) -> np.random.SeedSequence:
        """Restart ``restart``'s seed: the ``restart``-th child of ``SeedSequence(seed)`` (as ``spawn`` makes it)."""
        return np.random.SeedSequence(self.settings.seed, spawn_key=(restart,))

    def plan(self, restart: int) -> tuple[int, int]:
        """Restart ``restart``'s objective (an index into ``objectives``) and its turn of the two strategies.

        The variants take turns; with raised bounds (--pareto), every other restart is of one of
        them, in turn (its polish too).
        """
        nv, raised = self.n_variants, len(self.objectives) - self.n_variants
        if raised and restart % 2:
            k = restart // 2
            return nv + k % raised, k // raised
        r = restart // 2 if raised else restart
        return r % nv, r // nv

    def polished_by(self, restart: int) -> int:
        """The objective (index) whose residuals polish restart ``restart``: the problem, or its raised bound."""
        which, _ = self.plan(restart)
        return which if which >= self.n_variants else 0

    def template(self, restart: int) -> Search:
        """The search of ``restart`` as it starts (what a checkpoint of it must match)."""
        return _search(self.plan(restart)[1], self.problem, self.settings, self.seed_of(restart), _no_cost)

    def seed(self, initial: Callable[[], np.ndarray] | None) -> bool:
        """Take the seeds of the first searches; True when the first of them meets the goal (a new run's result)."""
        X = None if initial is None else initial()
        if X is None or not len(X):
            return False
        self.initial = np.asarray(X, float)
        err, cost = self.problem.measure(self.initial[:1])
        self.close = bool(err[0] <= SEED_LIMIT)
        if self.done or self.state is not None or not err[0] <= self.settings.goal:  # a checkpoint's run: under way
            return False
        entry = {"x": self.initial[0], "cost": float(cost[0]), "max_error": float(err[0])}
        self.done.append({**entry, "generations": 0, "designs": len(X), "deep": True})
        self.evaluations, self.restart, self.stopped_by = len(X), 1, "goal"
        self.report()
        return True

    def clock(self) -> float:
        """Seconds of the run, the checkpointed ones included."""
        return self.elapsed0 + time.monotonic() - self.start

    def deadline(self) -> float:
        """The end of the time budget, as a ``time.monotonic()`` value."""
        return self.start + self.settings.seconds - self.elapsed0

    def reserve(self) -> float:
        """Seconds a search leaves when it stops on the clock: its polish and the best design's last polish."""
        return 2.0 * self.polish_time if self.polish_time > 0 else 0.1 * self.settings.seconds

    def best(self) -> int:
        """The best finished restart: the smallest max error among the feasible (:func:`objective.best_index`)."""
        return best_index(np.array([d["max_error"] for d in self.done]), np.array([d["cost"] for d in self.done]))

    def best_so_far(self) -> tuple[float, float]:
        """Cost and max error / L of the best finished restart (inf, NaN before the first)."""
        if not self.done:
            return np.inf, np.nan
        d = self.done[self.best()]
        return d["cost"], d["max_error"]

    def search(self, ev: Evaluator) -> None:
        """Restarts until the goal, the last one or the clock, then the best polished longer; time left: more."""
        lanes = ev.workers if ev.local and not self.settings.checkpoint else 1
        while True:
            if lanes > 1:
                self.in_lanes(ev, lanes)
            while lanes == 1 and self.restart < self.settings.restarts and not self.search_once(ev):
                pass
            if self.stopped_by == "goal":
                return
            self.deepen()
            more = self.clock() + self.reserve() + 5 * self.generation_time < self.settings.seconds
            if self.restart >= self.settings.restarts or not more:
                return
            self.stopped_by = "restarts"  # the last polish ended early: the time left goes to another search

    def search_once(self, ev: Evaluator) -> bool:
        """Restart ``self.restart``: its search, then its polish; True when the run is to stop."""
        which, turn = self.plan(self.restart)

        def cost(X: np.ndarray, which: int = which) -> np.ndarray:  # X is (designs, dim)
            return ev.cost(X, which)

        seed = self.seed_of(self.restart)
        search = _search(turn, self.problem, self.settings, seed, cost, self.initial, self.close)
        designs, out_of_time = self._resume(search)
        if self.polished is None:  # still searching
            designs, out_of_time = self._generations(search, designs)
            self.polished = []
        x, c, err = self._polish(search, designs, out_of_time)
        self.done.append(
            {"x": x, "cost": c, "max_error": err, "generations": self.generation, "designs": designs, "deep": False}
        )
        self.evaluations += designs
        self.restart += 1
        self.generation = 0
        self.polished, self.kept = None, None
        if self.settings.checkpoint:
            self.save()
        self.report()
        if err <= self.settings.goal:
            self.stopped_by = "goal"
        elif out_of_time or self.clock() + self.reserve() > self.settings.seconds:
            self.stopped_by = "time"
        else:
            return False
        return True

    def measure_under_way(self, search: Search) -> None:
        """Every ``MEASURE_EVERY`` generations, the best design of the search under way measured; the smallest max
        error of the restart under way kept with its design (:attr:`kept`), which its polish takes as a candidate: a
        design the progress line reported is never lost, and a restart ends alike on one worker or several."""
        if self.generation % MEASURE_EVERY or not np.isfinite(search.best):
            return
        x = np.array(search.candidates()[0][0], float)
        err = float(self.problem.measure(x[None])[0][0])
        self.seen = min(self.seen, err)
        if self.kept is None or err < self.kept[0]:  # the restart's own (workers or not, the same per restart)
            self.kept = (err, x)

    def report(self, designs: int = 0, best: float = np.inf) -> None:
        """Tell the progress callback where the run is (the designs under way included: :meth:`measure_under_way`)."""
        if self.progress is None:
            return
        cost, err = self.best_so_far()
        if np.isfinite(self.seen) and not err <= self.seen:  # NaN (nothing polished yet) or worse
            err = self.seen
        n = self.evaluations + designs
        self.progress(Progress(self.restart, self.generation, min(cost, best), err, n, self.clock()))

    def _resume(self, search: Search) -> tuple[int, bool]:
        """A checkpoint's unfinished search restored: (the designs it has scored, out of time); else (0, False)."""
        designs, out_of_time = 0, False
        if self.state is not None and self.state.get("solver") is not None:
            try:
                search.restore(self.state["solver"])
            except (ValueError, TypeError, KeyError, IndexError, OverflowError) as e:
                raise InputError(f"{self.settings.checkpoint}: not a readable linkagekit checkpoint ({e})") from None
            self.evaluations = sum(d["designs"] for d in self.done)  # the finished searches'; the rest is this one's
            designs = self.state["evaluations"] - self.evaluations
            self.polished, out_of_time = self.state["polished"], self.state["out_of_time"]
        self.state = None
        return designs, out_of_time

    def _generations(self, search: Search, designs: int) -> tuple[int, bool]:
        """Generations until ``search`` is finished or the time is up: (designs scored, out of time)."""
        while not search.finished(self.generation):
            t0 = time.monotonic()
            designs += search.step()
            self.generation += 1
            self.generation_time = time.monotonic() - t0
            self.measure_under_way(search)
            self.report(designs, search.best)
            if self.settings.checkpoint:
                self.save(search.capture(), designs)
            if self.lane is not None and self.lane.dropped(self.restart):
                raise _Dropped
            if self.clock() + self.reserve() > self.settings.seconds:  # leave time to polish within the budget
                return designs, True
        return designs, False

    def _polish(self, search: Search, designs: int, out_of_time: bool) -> tuple[np.ndarray, float, float]:
        """The best of the ``POLISHED`` best distinct candidates, each polished both ways, one by one (checkpointed).

        The best is chosen by the printed measure (:func:`objective.measure`): the least-squares
        polish lowers the cost (the mean squared error), the result is the smallest max error.
        A restart at a raised bound (--pareto) is polished at that bound.
        """
        assert self.polished is not None
        t0, fresh = self.clock(), not self.polished
        k = self.polished_by(self.restart)
        objective = self.objectives[k]
        picked = _picked(self.problem, *search.candidates())
        tasks = [(p, m) for p in picked for m in _both_methods(self.problem)]
        for p, m in tasks[len(self.polished) :]:
            self.polished.append(polish(objective, p, POLISH_NFEV, self.deadline(), m))
            if self.settings.checkpoint:
                self.save(search.capture(), designs, out_of_time)
            self.report(designs, search.best)
        if fresh and time.monotonic() < self.deadline():  # a whole polish, not one cut by the clock
            self.polish_time = max(self.polish_time, self.clock() - t0)
        seeds = [] if self.initial is None or self.restart >= self.n_variants else [self.initial[0]]
        if self.kept is not None:  # a design the progress line may have reported
            seeds.append(self.kept[1])
        cands = np.array(self.polished + picked + seeds)  # the first searches end no worse than their seed
        err, cost = self.problem.measure(cands)
        if self.settings.pareto:
            self.keep(cands, err)
        j = best_index(err, cost)
        return cands[j], float(cost[j]), float(err[j])

    def keep(self, X: np.ndarray, err: np.ndarray | None = None) -> None:
        """--pareto: designs ``X`` (k, dim) added to the front (max error by the measure); the beaten ones dropped."""
        from .front import non_dominated

        err = self.problem.measure(X)[0] if err is None else err
        mu = self.problem.transmission(X)
        ok = np.isfinite(err) & np.isfinite(mu)
        xs = [f[0] for f in self.front] + list(X[ok])
        e = np.array([f[1] for f in self.front] + list(err[ok]), float)
        m = np.array([f[2] for f in self.front] + list(mu[ok]), float)
        keep = non_dominated(e, m)
        self.front = [(xs[i], float(e[i]), float(m[i])) for i in keep]

    def deepen(self) -> None:
        """The best design polished once more, longer, by both methods (unless it meets the goal or was already)."""
        k = self.best()
        best = self.done[k]
        if best["deep"] or best["max_error"] <= self.settings.goal:
            return
        x = np.asarray(best["x"], float)
        deep = [polish(self.problem, x, FINAL_POLISH, self.deadline(), m) for m in _both_methods(self.problem)]
        cands = np.array([x, *deep])
        err, cost = self.problem.measure(cands)
        if self.settings.pareto:
            self.keep(cands, err)
        j = best_index(err, cost)
        self.done[k] = {**best, "x": cands[j], "cost": float(cost[j]), "max_error": float(err[j]), "deep": True}
        if self.settings.checkpoint:
            self.save()

    def save(self, solver: dict[str, Any] | None = None, designs: int = 0, out_of_time: bool = False) -> None:
        """Write the checkpoint: the finished restarts, the search under way (``solver``) and its polish."""
        polish = None
        if solver is not None and self.polished is not None:
            polish = {"out_of_time": out_of_time, "count": len(self.polished)}
        header: dict[str, Any] = {
            "restart": self.restart,
            "generation": self.generation,
            "evaluations": self.evaluations + designs,
            "elapsed": self.clock(),
            "stopped_by": self.finished,
            "polish": polish,
            "kept": None if self.kept is None else self.kept[0],
        }
        arrays = {f"polish_{i}": x for i, x in enumerate(self.polished or [])} if polish else {}
        if self.kept is not None:
            arrays["kept_x"] = self.kept[1]
        _save(self.settings, self.problem, header, solver, self.done, arrays)

    def outcome(self) -> Outcome:
        """The best design (by the printed measure) and the run's account."""
        best = self.done[self.best()]
        return Outcome(
            np.asarray(best["x"], float),
            float(best["cost"]),
            len(self.done),
            sum(d["generations"] for d in self.done),
            self.evaluations,
            self.clock(),
            self.stopped_by,
            [(float(d["cost"]), float(d["max_error"])) for d in self.done],
            list(self.front),
        )

    # -- lanes: several restarts at once
    def in_lanes(self, ev: Evaluator, lanes: int) -> None:
        """Restarts from ``self.restart`` on, ``lanes`` at a time, until the goal, the last one or the clock.

        Each restart runs whole on a worker process (:func:`_restart_on_worker`: its generations
        and its polish there, its progress sent back by the :class:`~.distribute.Channel`). Once
        restart ``g`` meets the goal, the restarts after it are dropped (and stopped), those
        before it finish: the restarts one worker would have kept.
        """
        from concurrent.futures import FIRST_COMPLETED, wait
        from concurrent.futures.process import BrokenProcessPool

        line = ev.channel
        assert line is not None
        line.limit.value, line.stop.value = self.settings.restarts, 0
        lanes_ = _Lanes(self.settings.restarts)
        running: dict[Any, int] = {}
        try:
            while True:
                while len(running) < lanes and self._takes(lanes_):
                    running[ev.submit(_restart_on_worker, self._child(self.restart))] = self.restart
                    self.restart += 1
                if not running:
                    break
                finished, _ = wait(running, timeout=0.1, return_when=FIRST_COMPLETED)
                self._relay(lanes_, line.messages())
                for f in finished:
                    r = running.pop(f)
                    try:
                        self._lane_done(lanes_, r, f.result())
                    except BrokenProcessPool:  # a worker died: its restarts again, on new processes
                        running = self._again(ev, lanes_, [r, *running.values()])
                    line.limit.value = lanes_.goal_at
        except BaseException:
            line.stop.value = 1
            raise
        self._relay(lanes_, line.messages())
        kept = sorted((r, d) for r, d in lanes_.finished.items() if r < lanes_.goal_at)
        self.done += [d for _, d in kept]
        self.restart = kept[-1][0] + 1 if kept else self.restart
        self.evaluations += sum(d["designs"] for _, d in kept)
        self.stopped_by = "goal" if lanes_.goal_at < self.settings.restarts else lanes_.stopped_by
        self.report()

    def _again(self, ev: Evaluator, lanes: _Lanes, restarts: list[int]) -> dict[Any, int]:
        """The restarts of a pool that lost a process, sent again to a new one (at most ``RETRIES`` times a run)."""
        lanes.retries += 1
        if lanes.retries > RETRIES:
            raise WorkersLost(f"the local worker processes died {RETRIES + 1} times during one run")
        ev.renew()
        return {ev.submit(_restart_on_worker, self._child(r)): r for r in sorted(set(restarts))}

    def _takes(self, lanes: _Lanes) -> bool:
        """Whether another restart is to start."""
        return self.restart < lanes.goal_at and lanes.stopped_by != "time"

    def _child(self, restart: int) -> _Run:
        """What a worker needs to run restart ``restart`` (:func:`_restart_on_worker`).

        Not the objectives: the worker has them since it started (``distribute._install``; with
        fork not even pickled, so an objective pickle cannot find again still runs on workers).
        """
        return replace(
            self,
            problem=_Placeholder(),
            objectives=(),
            restart=restart,
            done=[],
            front=[],
            generation=0,
            polished=None,
            kept=None,
            evaluations=0,
            progress=None,
        )

    def _lane_done(self, lanes: _Lanes, r: int, result: dict[str, Any]) -> None:
        """A worker's finished restart ``r`` recorded (None: dropped)."""
        d = result["done"]
        if d is None:
            return
        lanes.finished[r] = d
        self.polish_time = max(self.polish_time, result["polish_time"])
        self.generation_time = result["generation_time"]
        if self.settings.pareto:
            self.front_merge(result["front"])
        if d["max_error"] <= self.settings.goal:
            lanes.goal_at = min(lanes.goal_at, r + 1)
        elif result["stop"]:
            lanes.stopped_by = "time"
        self._relay(lanes, [])

    def _relay(self, lanes: _Lanes, messages: list[tuple[int, int, float, float, int]]) -> None:
        """The workers' progress as the run's: the best over every lane, the designs of all."""
        for r, generation, cost, err, designs in messages:
            lanes.under_way[r] = (generation, cost, designs)
            self.seen = min(self.seen, err) if err == err else self.seen
        if self.progress is None:
            return
        done = [v for k, v in lanes.finished.items() if k < lanes.goal_at]
        for k in lanes.finished:
            lanes.under_way.pop(k, None)
        errors = [v["max_error"] for v in done] + ([self.seen] if np.isfinite(self.seen) else [])
        cost = min([v["cost"] for v in done] + [c for _, c, _ in lanes.under_way.values()] + [np.inf])
        n = self.evaluations + sum(v["designs"] for v in done) + sum(d for _, _, d in lanes.under_way.values())
        r = min(lanes.under_way, default=self.restart)
        generation = lanes.under_way[r][0] if r in lanes.under_way else 0
        self.progress(Progress(r, generation, cost, min(errors) if errors else np.nan, n, self.clock()))

    def front_merge(self, front: list[tuple[np.ndarray, float, float]]) -> None:
        """Another run's --pareto designs merged into this run's front."""
        from .front import non_dominated

        both = self.front + front
        keep = non_dominated(np.array([f[1] for f in both]), np.array([f[2] for f in both]))
        self.front = [both[i] for i in keep]


@dataclass
class _Lanes:
    """Where the restarts running at once (:meth:`_Run.in_lanes`) stand."""

    goal_at: int  # restarts from this number on are dropped (one after the first that met the goal)
    finished: dict[int, dict[str, Any]] = field(default_factory=dict)  # restart -> its result
    under_way: dict[int, tuple[int, float, int]] = field(default_factory=dict)  # restart -> generation, cost, designs
    stopped_by: str = "restarts"
    retries: int = 0


class _WorkerLane:
    """A restart's view, on a worker process, of the parent's :class:`~.distribute.Channel`."""

    def __init__(self, line: Any) -> None:
        self.line = line

    def dropped(self, restart: int) -> bool:
        """Whether ``restart`` is to stop now (a restart before it met the goal, or the run ends)."""
        return bool(self.line.stop.value) or restart >= self.line.limit.value


class _Placeholder(Objective):
    """Stands for the objective in a restart sent to a worker (which has the objectives already)."""

    bounds = (np.zeros(0), np.zeros(0))

    def score(self, X: FloatArray) -> Any:
        raise AssertionError("a placeholder is never scored")

    def fingerprint(self) -> str:
        return "placeholder"


class _Dropped(Exception):
    """A lane's restart stopped: a restart before it met the goal, or the run ends."""


def _restart_on_worker(run: _Run) -> dict[str, Any]:
    """Restart ``run.restart`` whole, on a local worker process: its result, or ``done`` None if it was dropped."""
    from .distribute import channel, installed

    line = channel()
    assert line is not None
    r = run.restart
    run.objectives = installed()
    run.problem = run.objectives[0]  # the variants come first, the problem itself the first of them

    def tell(p: Progress) -> None:
        line.queue.put((r, p.generation, float(p.best_cost), float(p.best_error), int(p.evaluations)))

    run.lane, run.progress = _WorkerLane(line), tell
    try:
        with Evaluator(run.objectives, 1) as ev:
            stop = run.search_once(ev)
    except _Dropped:
        return {"done": None}
    return {
        "done": run.done[0],
        "stop": stop,
        "polish_time": run.polish_time,
        "generation_time": run.generation_time,
        "front": run.front,
    }


def _no_cost(X: np.ndarray) -> np.ndarray:
    raise AssertionError("a template search is never stepped")


# ---------------------------------------------------------------------- the two searches
#: CMA-ES's first step size, in unit-box lengths
CMA_SIGMA = 0.3
#: CMA-ES's population grows by this factor from one of its restarts to the next (IPOP), at most this often
CMA_GROWTH, CMA_DOUBLINGS = 2, 3
#: every this many searches, one is CMA-ES (the others differential evolution)
CMA_EVERY = 2
#: CMA-ES's first population, in multiples of its default 4 + 3 ln n
CMA_POPULATION = 8
#: a seeded differential evolution's first population holds this many seeds (the rest a Latin hypercube)
SEEDED = 5
#: seeds whose best misses a target by more than this (relative to the targets' diagonal) are not given to
#: differential evolution: farther seeds pulled its population into their basin (the first CMA-ES still starts there)
SEED_LIMIT = 1e-3
#: a seeded CMA-ES's first step size, in unit-box lengths
CMA_SEEDED_SIGMA = 0.1


def _search(
    turn: int,
    problem: Objective,
    settings: Settings,
    seed: Any,
    cost: Cost,
    initial: np.ndarray | None = None,
    close: bool = False,
) -> Search:
    """The search of a restart at its ``turn`` (:meth:`_Run.plan`): differential evolution and CMA-ES take turns.

    With ``initial`` designs (best first), the first CMA-ES starts at the best, with a smaller step;
    when they are ``close`` (the best within ``SEED_LIMIT``), the first differential evolution
    has the best ``SEEDED`` of them in its first population too.
    """
    rng = np.random.Generator(np.random.PCG64(seed))
    seeded = initial if initial is not None and len(initial) and turn < CMA_EVERY else None
    if turn % CMA_EVERY != CMA_EVERY - 1:
        return DESearch(problem, settings, rng, cost, seeded if close else None)
    start = None if seeded is None else seeded[0]
    return CMASearch(problem, settings, rng, cost, CMA_GROWTH ** min(turn // CMA_EVERY, CMA_DOUBLINGS), start)


class Search:
    """One restart's population search: steps of one generation, a state to save, candidates to polish."""

    best = np.inf  # the best cost found so far

    def finished(self, generation: int) -> bool:
        raise NotImplementedError

    def step(self) -> int:
        """One generation; returns the number of designs it evaluated."""
        raise NotImplementedError

    def candidates(self) -> tuple[np.ndarray, np.ndarray]:
        """Designs (k, dim) and their costs (k,), best first."""
        raise NotImplementedError

    def capture(self) -> dict[str, Any]:
        raise NotImplementedError

    def restore(self, saved: dict[str, Any]) -> None:
        raise NotImplementedError

    def shapes(self) -> dict[str, tuple[tuple[int, ...], tuple[int, ...]]]:
        """The arrays of :meth:`capture`: name -> (smallest shape, largest shape) a checkpoint may hold."""
        return {k: (v.shape, v.shape) for k, v in self.capture().items() if isinstance(v, np.ndarray)}


class DESearch(Search):
    """scipy's differential evolution (``rand1bin``, dithered mutation, deferred updating, vectorized)."""

    def __init__(
        self,
        problem: Objective,
        settings: Settings,
        rng: np.random.Generator,
        cost: Cost,
        initial: np.ndarray | None = None,
    ) -> None:
        from scipy.optimize._differentialevolution import DifferentialEvolutionSolver

        lo, hi = problem.bounds
        self.settings = settings
        init: Any = "latinhypercube" if initial is None else _seeded_population(lo, hi, settings.popsize, initial, rng)
        self.solver = DifferentialEvolutionSolver(
            lambda x: cost(np.asarray(x).T),  # scipy's vectorized call: x is (dim, S)
            list(zip(lo, hi, strict=True)),
            strategy="rand1bin",
            maxiter=settings.generations,
            popsize=settings.popsize,
            tol=0,
            mutation=(0.5, 1.0),
            recombination=0.9,
            rng=rng,
            polish=False,
            init=init,
            updating="deferred",
            vectorized=True,
        )
        self.first = True

    @property
    def best(self) -> float:  # type: ignore[override]
        return float(self.solver.population_energies[0])

    def finished(self, generation: int) -> bool:
        return generation >= self.settings.generations

    def step(self) -> int:
        next(self.solver)
        n = len(self.solver.population) * (2 if self.first else 1)  # the first adds the initial population
        self.first = False
        return n

    def candidates(self) -> tuple[np.ndarray, np.ndarray]:
        order = np.argsort(self.solver.population_energies, kind="stable")
        pop = self.solver._scale_parameters(self.solver.population)
        return pop[order], np.asarray(self.solver.population_energies)[order]

    def capture(self) -> dict[str, Any]:
        sv = self.solver
        out: dict[str, Any] = {k: np.array(getattr(sv, k)) for k in _SOLVER_STATE}
        out.update(scale=float(sv.scale), nfev=int(sv._nfev), rng=sv.random_number_generator.bit_generator.state)
        return out

    def shapes(self) -> dict[str, tuple[tuple[int, ...], tuple[int, ...]]]:
        shapes = {k: np.shape(getattr(self.solver, k)) for k in _SOLVER_STATE}
        return {k: (v, v) for k, v in shapes.items()}

    def restore(self, saved: dict[str, Any]) -> None:
        sv = self.solver
        for k in _SOLVER_STATE:
            current = getattr(sv, k)
            setattr(sv, k, np.asarray(saved[k], dtype=current.dtype).reshape(current.shape))
        sv.scale = float(saved["scale"])
        sv._nfev = int(saved["nfev"])
        sv.random_number_generator.bit_generator.state = saved["rng"]
        self.first = False


def _seeded_population(
    lo: np.ndarray, hi: np.ndarray, popsize: int, initial: np.ndarray, rng: np.random.Generator
) -> np.ndarray:
    """A first population of ``popsize * dim``: the first ``SEEDED`` of ``initial``, the rest a Latin hypercube."""
    dim = len(lo)
    size = max(popsize * dim, 5)
    seeds = np.clip(np.asarray(initial, float)[:SEEDED], lo, hi)
    rest = size - len(seeds)
    strata = np.argsort(rng.uniform(size=(rest, dim)), axis=0)  # one permutation of the strata per coordinate
    U = (strata + rng.uniform(size=(rest, dim))) / rest
    return np.concatenate([seeds, lo + U * (hi - lo)])


class CMASearch(Search):
    """CMA-ES (:mod:`linkagekit.synthesis.cmaes`) in the unit box, from a random start.

    The population is the default ``4 + 3 ln n`` times ``CMA_POPULATION`` times ``growth``; the search ends when the
    strategy converges or stalls, or after as many designs as a differential-evolution search.
    """

    def __init__(
        self,
        problem: Objective,
        settings: Settings,
        rng: np.random.Generator,
        cost: Cost,
        growth: int = 1,
        start: np.ndarray | None = None,
    ) -> None:
        from .cmaes import CMAES

        self.lo, self.hi = problem.bounds
        n = len(self.lo)
        self.cost = cost
        self.budget = settings.generations * settings.popsize * n
        mean = rng.uniform(0.0, 1.0, n)
        if start is not None:  # a seed: start there, looking nearby first
            mean = np.clip((np.asarray(start, float) - self.lo) / (self.hi - self.lo), 0.0, 1.0)
        sigma = CMA_SIGMA if start is None else CMA_SEEDED_SIGMA
        self.es = CMAES(mean, sigma, rng, (4 + int(3 * np.log(n))) * CMA_POPULATION * growth)

    def _x(self, U: FloatArray) -> FloatArray:
        X: FloatArray = self.lo + U * (self.hi - self.lo)
        return X

    @property
    def best(self) -> float:  # type: ignore[override]
        return self.es.best_f

    def finished(self, generation: int) -> bool:
        return self.es.evaluations >= self.budget or self.es.stop() is not None

    def step(self) -> int:
        U = self.es.ask()
        self.es.tell(U, self.cost(self._x(U)))
        return len(U)

    def candidates(self) -> tuple[np.ndarray, np.ndarray]:
        es = self.es
        X = np.vstack([es.best_x[None], es.last_X])
        return self._x(X), np.concatenate([[es.best_f], es.last_f])

    def capture(self) -> dict[str, Any]:
        return self.es.state()

    def restore(self, saved: dict[str, Any]) -> None:
        self.es.restore(saved)

    def shapes(self) -> dict[str, tuple[tuple[int, ...], tuple[int, ...]]]:
        es, out = self.es, super().shapes()  # the history and the last generation start empty
        out.update(history=((0,), (es.history_length,)), last_X=((0, es.n), (es.lam, es.n)), last_f=((0,), (es.lam,)))
        return out


# ---------------------------------------------------------------------- polish
def residuals(problem: Objective, X: np.ndarray) -> np.ndarray:
    """Least-squares residuals of designs ``X`` (N, dim), whose squared sum is the cost (the objective's)."""
    return problem.residuals(X)


def _both_methods(problem: Objective) -> tuple[str, str]:
    """Both least-squares methods, the one that suits ``problem`` first (see :func:`polish_method`)."""
    return problem.polish_methods


def polish_method(problem: Objective) -> str:
    """The least-squares method that refines designs of ``problem`` best (measured; docs/method.md, "Search").

    For path generation: without timing the residuals have a manifold of exact solutions (a rank-deficient
    Jacobian), on which dogbox stalls and trust-region reflective converges; with timing,
    trust-region reflective crawls where dogbox converges.
    """
    return _both_methods(problem)[0]


def polish(
    problem: Objective,
    x0: np.ndarray,
    max_nfev: int = 100,
    until: float | None = None,
    method: str | None = None,
) -> np.ndarray:
    """A local least-squares refinement of one design vector within the bounds.

    ``until``: a ``time.monotonic()`` deadline; past it the refinement stops at its best point so far.
    ``method``: ``"trf"`` or ``"dogbox"`` (default: :func:`polish_method`).
    """
    from scipy.optimize import least_squares

    lo, hi = problem.bounds
    h = 1e-7 * problem.scale

    best: list[Any] = [np.inf, np.asarray(x0, float)]

    def fun(x: FloatArray) -> FloatArray:
        if until is not None and time.monotonic() > until:
            raise _OutOfTime
        r: FloatArray = residuals(problem, x[None])[0]
        if float(r @ r) < best[0]:
            best[:] = [float(r @ r), x.copy()]
        return r

    def jac(x: FloatArray) -> FloatArray:
        steps = np.where(x + h <= hi, h, -h)
        X = np.repeat(x[None], len(x) + 1, axis=0)
        X[1:] += np.diag(steps)
        R = residuals(problem, X)
        J: FloatArray = ((R[1:] - R[0]) / steps[:, None]).T
        return J

    x0 = np.clip(x0, lo, hi)
    try:
        method = method or polish_method(problem)
        scaling = "jac" if method == "dogbox" else 1.0
        r = least_squares(fun, x0, jac=jac, bounds=(lo, hi), method=method, x_scale=scaling, max_nfev=max_nfev)
    except _OutOfTime:
        return np.asarray(best[1], float)
    return np.asarray(r.x, float)


class _OutOfTime(Exception):
    """The polish's deadline passed."""


def _picked(problem: Objective, X: np.ndarray, energies: np.ndarray) -> list[np.ndarray]:
    """The ``POLISHED`` best distinct candidates, best first."""
    picked: list[np.ndarray] = []
    for i in np.argsort(energies, kind="stable"):
        if len(picked) == POLISHED:
            break
        if all(np.max(np.abs(X[i] - p)) > 1e-9 * problem.scale for p in picked):
            picked.append(X[i])
    return picked


# ---------------------------------------------------------------------- checkpoints
#: the largest checkpoint file read, and the longest JSON header (characters)
MAX_CHECKPOINT_BYTES, MAX_HEADER_CHARS = 1 << 30, 1 << 22
#: what ends a run, as a checkpoint records it
STOPS = ("goal", "restarts", "time")


class _Refused(ValueError):
    """A checkpoint that is readable but does not hold what this run needs (the message says what)."""


def _save(
    settings: Settings,
    problem: Objective,
    header: dict[str, Any],
    solver: dict[str, Any] | None,
    done: list[dict[str, Any]],
    arrays: dict[str, np.ndarray],
) -> None:
    """Write the checkpoint atomically: ``header``'s numbers, the finished restarts, the search under way."""
    assert settings.checkpoint is not None
    path = Path(settings.checkpoint)
    header = {
        "format": f"linkagekit-checkpoint/{CHECKPOINT_VERSION}",
        "version": CHECKPOINT_VERSION,
        "problem": problem.fingerprint(),
        "settings": settings.key(),
        **header,
        "done": [{k: d[k] for k in ("cost", "max_error", "generations", "designs", "deep")} for d in done],
        "solver": None,
    }
    arrays = {**arrays, **{f"done_x_{i}": np.asarray(d["x"], float) for i, d in enumerate(done)}}
    if solver is not None:  # the search's arrays into the file's arrays, its numbers into the header
        names = [k for k, v in solver.items() if isinstance(v, np.ndarray)]
        header["solver"] = {**{k: v for k, v in solver.items() if k not in names}, "arrays": names}
        arrays.update({f"solver_{k}": solver[k] for k in names})
    write_archive(path, header, arrays)


def write_archive(path: Path, header: dict[str, Any], arrays: dict[str, np.ndarray]) -> None:
    """Write a checkpoint in one step (:func:`~linkagekit.files.write_atomic`): ``arrays`` and the JSON ``header`` in
    one ``.npz``, made in memory (a checkpoint is small), written to a fresh temporary file created beside ``path``
    (never through a link) and renamed over it once whole. A run stopped while writing (Ctrl-C, SIGTERM) leaves the
    last checkpoint as it was and no temporary file; one killed outright leaves its temporary file, which the next
    run's :func:`_load` removes."""
    import io

    buf = io.BytesIO()
    np.savez(buf, **{**arrays, "header": np.array(json.dumps(header, default=int))})  # type: ignore[arg-type]
    write_atomic(path, buf.getvalue(), error=LinkageError, label=f"checkpoint {shorten_path(str(path))}")


def _load(settings: Settings, problem: Objective, template: Callable[[int], Search]) -> dict[str, Any] | None:
    """The saved state, or None when the file does not exist yet.

    Nothing is allocated before it is known to fit: the file must be a regular file of at most
    ``MAX_CHECKPOINT_BYTES``; every array's ``.npy`` header (shape and type) is read from its zip
    member and compared with what this run's search holds (``template(restart)``) before the
    array itself is read; the header's numbers are checked against the settings.
    """
    assert settings.checkpoint is not None
    path = Path(settings.checkpoint)
    states: list[dict[str, Any]] = []

    def expected(header: dict[str, Any]) -> dict[str, Any]:
        _check_owner(path, header, settings, problem)
        states.append(_state(header, settings))
        return _expected(states[0], problem, template)

    got = read_archive(path, "linkagekit-checkpoint", CHECKPOINT_VERSION, expected)
    return None if got is None else _with_arrays(states[0], got[1])


def read_archive(
    path: Path, kind: str, version: int, expected: Callable[[dict[str, Any]], dict[str, Any]]
) -> tuple[dict[str, Any], dict[str, np.ndarray]] | None:
    """A checkpoint's JSON header and arrays, or None when the file does not exist yet.

    Nothing is allocated before it is known to fit: the file must be a regular file of at most
    ``MAX_CHECKPOINT_BYTES``, its header's format ``kind/version``; ``expected(header)`` (which
    may refuse it: another problem's, other settings) names every array with its (smallest,
    largest) shape, and each array's ``.npy`` header (shape and type) is read from its zip
    member and compared with that before the array itself is read.
    """
    import stat
    import zipfile
    import zlib

    for stray in stray_temporaries(path):  # left by a run killed while writing; the checkpoint itself is whole
        stray.unlink(missing_ok=True)
    old = path.with_name(f".{path.name}.tmp")  # the one name earlier versions wrote to
    if old.is_file() and not old.is_symlink():
        old.unlink(missing_ok=True)
    try:
        st = path.stat()
    except FileNotFoundError:
        return None
    except OSError as e:
        raise InputError(f"{path}: cannot read the checkpoint ({e.strerror or e})") from None
    if not stat.S_ISREG(st.st_mode):
        raise InputError(f"{path}: not a checkpoint (not a regular file)")
    if st.st_size > MAX_CHECKPOINT_BYTES:
        raise InputError(f"{path}: not a checkpoint ({st.st_size} bytes, more than any checkpoint)")
    try:
        with zipfile.ZipFile(path) as zf:
            header = _header(zf, kind, version)
            return header, _arrays(zf, expected(header))
    except _Refused as e:
        raise InputError(f"{path}: not a usable linkagekit checkpoint ({e})") from None
    except InputError:  # another problem's, other settings: said as it is (it is a ValueError too)
        raise
    except zipfile.BadZipFile:
        raise InputError(f"{path}: not a linkagekit checkpoint (not a .npz archive)") from None
    except (OSError, EOFError, ValueError, KeyError, TypeError, zlib.error, NotImplementedError, RecursionError) as e:
        raise InputError(f"{path}: not a readable linkagekit checkpoint ({type(e).__name__}: {e})") from None


def _header(zf: Any, kind: str, version: int) -> dict[str, Any]:
    """The checkpoint's JSON header (its format ``kind/version`` checked), read once its size is known to be
    bounded."""
    if "header.npy" not in zf.namelist():
        raise _Refused("no header")
    _, shape, dtype = _npy_header(zf, "header")
    if shape != () or dtype.kind != "U" or dtype.itemsize > 4 * MAX_HEADER_CHARS:
        raise _Refused(f"a header of type {dtype} and shape {shape}")
    with zf.open("header.npy") as f:
        header = json.loads(str(np.lib.format.read_array(f, allow_pickle=False)))
    earlier = {f"{kind}/{v}": v for v in range(1, version)}
    if isinstance(header, dict) and header.get("format") in earlier:
        v = earlier[header["format"]]
        raise _Refused(f"written by an earlier linkagekit (format {v}, another search); delete it to start anew")
    if not isinstance(header, dict) or header.get("format") != f"{kind}/{version}":
        fmt = header.get("format") if isinstance(header, dict) else None
        raise _Refused(f"format {shorten(repr(fmt))}, expected {kind}/{version}" if fmt else "no format")
    return header


def _check_owner(path: Path, header: dict[str, Any], settings: Settings, problem: Objective) -> None:
    if header.get("problem") != problem.fingerprint():
        raise InputError(f"{path}: this checkpoint belongs to another problem (other targets, topology or options)")
    if header.get("settings") != settings.key():
        raise InputError(f"{path}: this checkpoint was made with other settings: {shorten(str(header['settings']))}")


def _number(value: Any, name: str, lo: float, hi: float, kind: type = int) -> Any:
    """``value`` as a ``kind`` within ``[lo, hi]``, else refused naming ``name``."""
    ok = isinstance(value, (int, float)) and not isinstance(value, bool) and (kind is float or value == int(value))
    if not ok or not lo <= value <= hi:
        what = "a whole number" if kind is int else "a number"
        raise _Refused(f"{name} {shorten(repr(value))} is not {what} in [{lo}, {hi}]")
    return kind(value)


def _state(header: dict[str, Any], settings: Settings) -> dict[str, Any]:
    """The header's numbers, each checked against the settings (the arrays come later)."""
    restarts = settings.restarts
    done = header["done"]
    if not isinstance(done, list) or len(done) > restarts:
        raise _Refused(f"'done' is not a list of at most {restarts} searches")
    state = {
        "restart": _number(header["restart"], "restart", len(done), len(done)),
        "generation": _number(header["generation"], "generation", 0, 1e15),
        "evaluations": _number(header["evaluations"], "evaluations", 0, 1e18),
        "elapsed": _number(header["elapsed"], "elapsed", 0.0, 1e12, float),
        "done": [_done(d, i) for i, d in enumerate(done)],
        "stopped_by": header["stopped_by"],
        "solver": header["solver"],
        "polish": header["polish"],
        "kept": None if header.get("kept") is None else _number(header["kept"], "kept", 0.0, np.inf, float),
    }
    if state["stopped_by"] is not None and state["stopped_by"] not in STOPS:
        raise _Refused(f"stopped_by {shorten(repr(state['stopped_by']))}")
    solver, polish = state["solver"], state["polish"]
    if solver is not None and (state["restart"] >= restarts or not isinstance(solver, dict)):
        raise _Refused("a search under way after the last one")
    if solver is not None and not (isinstance(solver.get("arrays"), list) and len(solver["arrays"]) <= 64):
        raise _Refused("the search's arrays are not listed")
    if polish is not None and (solver is None or not isinstance(polish, dict)):
        raise _Refused("a polish without its search")
    if polish is not None:
        polish["count"] = _number(polish.get("count"), "polish count", 0, 2 * POLISHED)
        polish["out_of_time"] = bool(polish.get("out_of_time"))
    return state


def _done(d: Any, i: int) -> dict[str, Any]:
    """One finished restart of the header, checked."""
    if not isinstance(d, dict):
        raise _Refused(f"done[{i}] is not a mapping")
    return {
        "cost": _number(d["cost"], f"done[{i}].cost", 0.0, np.inf, float),
        "max_error": _number(d["max_error"], f"done[{i}].max_error", 0.0, np.inf, float),
        "generations": _number(d["generations"], f"done[{i}].generations", 0, 1e15),
        "designs": _number(d["designs"], f"done[{i}].designs", 0, 1e18),
        "deep": bool(d.get("deep")),
    }


def _expected(state: dict[str, Any], problem: Objective, template: Callable[[int], Search]) -> dict[str, Any]:
    """Every array the checkpoint must hold: name -> (smallest shape, largest shape) of numbers."""
    dim = (len(problem.bounds[0]),)
    out: dict[str, Any] = {f"done_x_{i}": (dim, dim) for i in range(len(state["done"]))}
    if state["polish"] is not None:
        out.update({f"polish_{i}": (dim, dim) for i in range(state["polish"]["count"])})
    if state["kept"] is not None:
        out["kept_x"] = (dim, dim)
    if state["solver"] is not None:
        shapes = template(state["restart"]).shapes()
        listed = state["solver"]["arrays"]
        if sorted(map(str, listed)) != sorted(shapes):
            raise _Refused(f"the search's arrays {shorten(str(listed))}, expected {sorted(shapes)}")
        out.update({f"solver_{k}": v for k, v in shapes.items()})
    return out


def _npy_header(zf: Any, name: str) -> tuple[Any, tuple[int, ...], np.dtype[Any]]:
    """The zip member of array ``name``, and its shape and type, read from its ``.npy`` header only."""
    info = zf.getinfo(f"{name}.npy")
    with zf.open(info) as f:
        version = np.lib.format.read_magic(f)
        if version == (1, 0):
            shape, _, dtype = np.lib.format.read_array_header_1_0(f)
        elif version == (2, 0):
            shape, _, dtype = np.lib.format.read_array_header_2_0(f)
        else:
            raise _Refused(f"array {name}: .npy format {version}")
    return info, tuple(shape), dtype


def _arrays(zf: Any, expected: dict[str, Any]) -> dict[str, np.ndarray]:
    """The arrays ``expected`` names, each read only once its header shows the shape and type expected."""
    members = {n.removesuffix(".npy") for n in zf.namelist()} - {"header"}
    if members != set(expected):
        raise _Refused(f"arrays {shorten(str(sorted(members - set(expected)) or sorted(set(expected) - members)))}")
    out = {}
    for name, (lo, hi) in expected.items():
        info, shape, dtype = _npy_header(zf, name)
        fits = len(shape) == len(lo) and all(a <= s <= b for a, s, b in zip(lo, shape, hi, strict=True))
        if not fits or dtype.kind not in "fiub" or dtype.itemsize > 8:
            raise _Refused(f"array {name} of type {dtype} and shape {shape}, expected numbers of shape {hi}")
        if info.file_size > int(np.prod(shape)) * dtype.itemsize + 65536:
            raise _Refused(f"array {name}: {info.file_size} bytes for shape {shape}")
        with zf.open(info) as f:
            out[name] = np.lib.format.read_array(f, allow_pickle=False)
    return out


def _with_arrays(state: dict[str, Any], arrays: dict[str, np.ndarray]) -> dict[str, Any]:
    """The state of the header with its arrays put in place."""
    for i, d in enumerate(state["done"]):
        d["x"] = np.asarray(arrays[f"done_x_{i}"], float)
    polish = state.pop("polish")
    state["kept"] = None if state["kept"] is None else (state["kept"], np.asarray(arrays["kept_x"], float))
    state["polished"] = None
    state["out_of_time"] = False
    if polish is not None:
        state["polished"] = [np.asarray(arrays[f"polish_{i}"], float) for i in range(polish["count"])]
        state["out_of_time"] = polish["out_of_time"]
    if state["solver"] is not None:
        solver = dict(state["solver"])
        solver.update({k: arrays[f"solver_{k}"] for k in solver.pop("arrays")})
        state["solver"] = solver
    return state
