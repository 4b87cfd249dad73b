"""Differential evolution and CMA-ES over whole generations, a least-squares polish, restarts, checkpoints.

One restart
    Either :class:`scipy.optimize.differential_evolution`'s solver (``rand1bin``, dithered
    mutation, ``updating="deferred"``, ``vectorized=True``) or CMA-ES
    (:mod:`linkagekit.synthesis.cmaes`); they take turns from restart to restart. Every
    generation's designs go to :class:`~linkagekit.synthesis.distribute.Evaluator` as one
    array. Stepping a search one generation at a time is what lets the run save its state
    after every generation and stop on the clock.
Polish
    The ``POLISHED`` best distinct members are refined by
    :func:`scipy.optimize.least_squares` on the residuals ``e_i / (L sqrt(m))`` and
    ``sqrt(PENALTY * violation)``, each by both of its bounded methods (trust-region
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
from typing import Any

import numpy as np

from ..errors import InputError, LinkageError
from ..geometry import FloatArray
from .distribute import Evaluator
from .objective import PENALTY, Problem, evaluate

#: designs polished per restart
POLISHED = 5
#: residual evaluations of each of them
POLISH_NFEV = 100
#: residual evaluations of the last polish of the best design
FINAL_POLISH = 2000
#: the solver's fields that change from generation to generation (all else follows from its arguments)
_SOLVER_STATE = ("population", "population_energies", "_random_population_index", "feasible", "constraint_violation")
CHECKPOINT_VERSION = 3  # 3: CMA-ES population and polish changed, so earlier checkpoints cannot continue
#: the search a restart runs, as a function of its cost: (designs, dim) -> (designs,)
Cost = Callable[[np.ndarray], np.ndarray]


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
    scheduler : str, optional
    checkpoint : str, optional
    """

    seed: int = 0
    seconds: float = 60.0
    restarts: int = 32
    generations: int = 500
    popsize: int = 15
    goal: float = 1e-5
    workers: int = 1
    scheduler: str | None = None
    checkpoint: str | None = None

    def key(self) -> dict[str, Any]:
        """What a checkpoint must agree on to be continued."""
        return {"seed": self.seed, "restarts": self.restarts, "generations": self.generations, "popsize": self.popsize}


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
    """

    x: np.ndarray
    cost: float
    restarts: int
    generations: int
    evaluations: int
    seconds: float
    stopped_by: str  # "goal", "restarts" or "time"
    history: list[tuple[float, float]] = field(default_factory=list)  # (cost, max error / L) per restart


def optimize(
    problem: Problem,
    settings: Settings,
    progress: Callable[[Progress], None] | None = None,
) -> Outcome:
    """Search ``problem`` as ``settings`` say; returns the best design found."""
    run = _Run.begin(problem, settings, progress)
    # With the order asked for, every other search scores without it (cheaper, and a fit found without the
    # order may well be in order); the polish and the choice of the best always use the problem itself.
    variants = (problem, replace(problem, ordered=False)) if problem.ordered else (problem,)
    with Evaluator(variants, settings.workers, settings.scheduler) as ev:
        while run.restart < settings.restarts:
            if run.search_once(ev, variants):
                break
    return run.outcome()


@dataclass
class _Run:
    """One :func:`optimize` run: its restarts so far, the one under way, the clock (continued from a checkpoint)."""

    problem: Problem
    settings: Settings
    progress: Callable[[Progress], None] | None
    start: float
    seeds: list[np.random.SeedSequence]
    state: dict[str, Any] | None = None  # a checkpoint's, until its unfinished search is restored
    done: list[dict[str, Any]] = field(default_factory=list)  # the finished restarts
    restart: int = 0
    generation: int = 0
    evaluations: int = 0
    elapsed0: float = 0.0  # the checkpointed runs' time
    stopped_by: str = "restarts"
    reserve: float = 0.0  # seconds kept for the polish after a search's last generation

    @classmethod
    def begin(cls, problem: Problem, settings: Settings, progress: Callable[[Progress], None] | None) -> _Run:
        """A new run, or the checkpoint's when there is one."""
        start = time.monotonic()
        run = cls(problem, settings, progress, start, np.random.SeedSequence(settings.seed).spawn(settings.restarts))
        state = _load(settings, problem) if settings.checkpoint else None
        if state is not None:
            run.state, run.done, run.restart = state, state["done"], state["restart"]
            run.generation, run.evaluations, run.elapsed0 = state["generation"], state["evaluations"], state["elapsed"]
        if any(d["max_error"] <= settings.goal for d in run.done):
            run.stopped_by, run.restart = "goal", settings.restarts
        return run

    def clock(self) -> float:
        """Seconds of the run, the checkpointed ones included."""
        return self.elapsed0 + time.monotonic() - self.start

    def best_so_far(self) -> tuple[float, float]:
        """Cost and max error / L of the best finished restart (inf, NaN before the first)."""
        if not self.done:
            return np.inf, np.nan
        d = min(self.done, key=lambda d: d["cost"])
        return d["cost"], d["max_error"]

    def search_once(self, ev: Evaluator, variants: tuple[Problem, ...]) -> bool:
        """Restart ``self.restart``: its search, then its polish; True when the run is to stop."""
        which = self.restart % len(variants)

        def cost(X: np.ndarray, which: int = which) -> np.ndarray:  # X is (designs, dim)
            return ev.cost(X, which)

        search = _search(self.restart, len(variants), self.problem, self.settings, self.seeds[self.restart], cost)
        designs, out_of_time = self._generations(search, self._resume(search))
        t0 = self.clock()
        x, c, err = _polish(self.problem, *search.candidates())
        self.reserve = max(self.reserve, 2.0 * (self.clock() - t0))  # this polish and the last, longer one
        self.done.append({"x": x, "cost": c, "max_error": err, "generations": self.generation, "designs": designs})
        self.evaluations += designs
        self.restart += 1
        self.generation = 0
        if self.settings.checkpoint:
            _save(self.settings, self.problem, self.restart, 0, self.evaluations, self.clock(), None, self.done)
        if self.progress is not None:
            self.progress(Progress(self.restart, 0, *self.best_so_far(), self.evaluations, self.clock()))
        if err <= self.settings.goal:
            self.stopped_by = "goal"
        elif out_of_time or self.clock() + self.reserve > self.settings.seconds:
            self.stopped_by = "time"
        else:
            return False
        return True

    def _resume(self, search: Search) -> int:
        """The designs ``search`` has scored already: a checkpoint's unfinished search's, else none."""
        designs = 0
        if self.state is not None and self.state.get("solver") is not None:
            search.restore(self.state["solver"])
            self.evaluations = sum(d["designs"] for d in self.done)  # the finished searches'; the rest is this one's
            designs = self.state["evaluations"] - self.evaluations
        self.state = None
        return designs

    def _generations(self, search: Search, designs: int) -> tuple[int, bool]:
        """Generations until ``search`` is finished or the time is up: (designs scored, out of time)."""
        settings = self.settings
        while not search.finished(self.generation):
            designs += search.step()
            self.generation += 1
            best_cost, best_err = self.best_so_far()
            n_eval = self.evaluations + designs
            if self.progress is not None:
                best = min(best_cost, search.best)
                self.progress(Progress(self.restart, self.generation, best, best_err, n_eval, self.clock()))
            if settings.checkpoint:
                state = search.capture()
                _save(settings, self.problem, self.restart, self.generation, n_eval, self.clock(), state, self.done)
            if self.clock() + self.reserve > settings.seconds:  # leave time to polish within the budget
                return designs, True
        return designs, False

    def outcome(self) -> Outcome:
        """The best design, polished once more when it misses the goal, and the run's account."""
        best = min(self.done, key=lambda d: d["cost"])
        x = np.asarray(best["x"], float)
        if best["max_error"] > self.settings.goal:  # a last, longer polish of the best design, by both methods
            until = self.start + max(self.settings.seconds - self.elapsed0, 0.0)
            deep = [polish(self.problem, x, FINAL_POLISH, until, m) for m in _both_methods(self.problem)]
            e = evaluate(self.problem, np.array([x, *deep]), refine=3)
            k = int(np.argmin(e.cost))
            if k > 0:
                best = {**best, "x": deep[k - 1], "cost": float(e.cost[k])}
        return Outcome(
            np.asarray(best["x"], float),
            float(best["cost"]),
            len(self.done),
            sum(d["generations"] for d in self.done),
            self.evaluations,
            self.clock(),
            self.stopped_by,
            [(float(d["cost"]), float(d["max_error"])) for d in self.done],
        )


# ---------------------------------------------------------------------- the two searches
#: CMA-ES's first step size, in unit-box lengths
CMA_SIGMA = 0.3
#: CMA-ES's population grows by this factor from one of its restarts to the next (IPOP), at most this often
CMA_GROWTH, CMA_DOUBLINGS = 2, 3
#: every this many searches, one is CMA-ES (the others differential evolution)
CMA_EVERY = 2
#: CMA-ES's first population, in multiples of its default 4 + 3 ln n
CMA_POPULATION = 8


def _search(restart: int, n_variants: int, problem: Problem, settings: Settings, seed: Any, cost: Cost) -> Search:
    """The search of restart ``restart``: differential evolution and CMA-ES take turns (after the variants)."""
    rng = np.random.Generator(np.random.PCG64(seed))
    turn = restart // n_variants
    if turn % CMA_EVERY != CMA_EVERY - 1:
        return DESearch(problem, settings, rng, cost)
    return CMASearch(problem, settings, rng, cost, CMA_GROWTH ** min(turn // CMA_EVERY, CMA_DOUBLINGS))


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


class DESearch(Search):
    """scipy's differential evolution (``rand1bin``, dithered mutation, deferred updating, vectorized)."""

    def __init__(self, problem: Problem, settings: Settings, rng: np.random.Generator, cost: Cost) -> None:
        from scipy.optimize._differentialevolution import DifferentialEvolutionSolver

        lo, hi = problem.bounds
        self.settings = settings
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
            init="latinhypercube",
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

    def restore(self, saved: dict[str, Any]) -> None:
        sv = self.solver
        for k in _SOLVER_STATE:
            current = getattr(sv, k)
            setattr(sv, k, np.asarray(saved[k], dtype=current.dtype).reshape(current.shape))
        sv.scale = float(saved["scale"])
        sv._nfev = int(saved["nfev"])
        sv.random_number_generator.bit_generator.state = saved["rng"]
        self.first = False


class CMASearch(Search):
    """CMA-ES (:mod:`linkagekit.synthesis.cmaes`) in the unit box, from a random start.

    The population is the default ``4 + 3 ln n`` times ``CMA_POPULATION`` times ``growth``; the search ends when the
    strategy converges or stalls, or after as many designs as a differential-evolution search.
    """

    def __init__(
        self, problem: Problem, settings: Settings, rng: np.random.Generator, cost: Cost, growth: int = 1
    ) -> None:
        from .cmaes import CMAES

        self.lo, self.hi = problem.bounds
        n = len(self.lo)
        self.cost = cost
        self.budget = settings.generations * settings.popsize * n
        self.es = CMAES(rng.uniform(0.0, 1.0, n), CMA_SIGMA, rng, (4 + int(3 * np.log(n))) * CMA_POPULATION * growth)

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


# ---------------------------------------------------------------------- polish
def residuals(problem: Problem, X: np.ndarray) -> np.ndarray:
    """Least-squares residuals of designs ``X`` (N, dim): (N, m + 1), whose squared sum is the cost."""
    e = evaluate(problem, X, refine=3)
    m = len(problem.targets)
    rel = np.where(np.isfinite(e.errors), e.errors / problem.scale, 1.0) / np.sqrt(m)
    return np.concatenate([rel, np.sqrt(PENALTY * e.violation)[:, None]], axis=1)


def _both_methods(problem: Problem) -> tuple[str, str]:
    """Both least-squares methods, the one that suits ``problem`` first (see :func:`polish_method`)."""
    return ("dogbox", "trf") if problem.timed else ("trf", "dogbox")


def polish_method(problem: Problem) -> str:
    """The least-squares method that refines designs of ``problem`` best (measured; docs/method.md, "Search").

    Without timing the residuals have a manifold of exact solutions (a rank-deficient
    Jacobian), on which dogbox stalls and trust-region reflective converges; with timing,
    trust-region reflective crawls where dogbox converges.
    """
    return _both_methods(problem)[0]


def polish(
    problem: Problem, x0: np.ndarray, max_nfev: int = 100, until: float | None = None, method: str | None = None
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


def _polish(problem: Problem, X: np.ndarray, energies: np.ndarray) -> tuple[np.ndarray, float, float]:
    """The best of the ``POLISHED`` best distinct candidates, each polished both ways: (x, cost, max error / L)."""
    picked: list[np.ndarray] = []
    for i in np.argsort(energies, kind="stable"):
        if len(picked) == POLISHED:
            break
        if all(np.max(np.abs(X[i] - p)) > 1e-9 * problem.scale for p in picked):
            picked.append(X[i])
    methods = _both_methods(problem)
    cands = np.array([polish(problem, p, POLISH_NFEV, method=m) for p in picked for m in methods] + picked)
    e = evaluate(problem, cands, refine=3)
    k = int(np.argmin(e.cost))
    err = np.nanmax(e.errors[k]) / problem.scale if np.all(np.isfinite(e.errors[k])) else np.inf
    return cands[k], float(e.cost[k]), float(err if e.violation[k] == 0 else np.inf)


# ---------------------------------------------------------------------- checkpoints
def _save(
    settings: Settings,
    problem: Problem,
    restart: int,
    generation: int,
    evaluations: int,
    elapsed: float,
    solver: dict[str, Any] | None,
    done: list[dict[str, Any]],
) -> None:
    assert settings.checkpoint is not None
    path = Path(settings.checkpoint)
    header: dict[str, Any] = {
        "format": f"linkagekit-checkpoint/{CHECKPOINT_VERSION}",
        "version": CHECKPOINT_VERSION,
        "problem": problem.fingerprint(),
        "settings": settings.key(),
        "restart": restart,
        "generation": generation,
        "evaluations": evaluations,
        "elapsed": elapsed,
        "done": [
            {"cost": d["cost"], "max_error": d["max_error"], "generations": d["generations"], "designs": d["designs"]}
            for d in done
        ],
        "solver": None,
    }
    arrays: dict[str, np.ndarray] = {f"done_x_{i}": np.asarray(d["x"], float) for i, d in enumerate(done)}
    if solver is not None:  # the search's arrays into the file's arrays, its numbers into the header
        names = [k for k, v in solver.items() if isinstance(v, np.ndarray)]
        header["solver"] = {**{k: v for k, v in solver.items() if k not in names}, "arrays": names}
        arrays.update({f"solver_{k}": solver[k] for k in names})
    arrays["header"] = np.array(json.dumps(header, default=int))
    tmp = _temporary(path)
    try:
        with open(tmp, "wb") as f:
            np.savez(f, **arrays)  # type: ignore[arg-type]
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except OSError as e:
        tmp.unlink(missing_ok=True)
        raise LinkageError(f"{path}: cannot write the checkpoint ({e.strerror or e})") from None


def _temporary(path: Path) -> Path:
    """Where a checkpoint is written before it is renamed over ``path`` (one name: a killed run's is reused)."""
    return path.with_name(f".{path.name}.tmp")


def _load(settings: Settings, problem: Problem) -> dict[str, Any] | None:
    """The saved state, or None when the file does not exist yet."""
    import zipfile

    assert settings.checkpoint is not None
    path = Path(settings.checkpoint)
    _temporary(path).unlink(missing_ok=True)  # left by a run killed while writing; the checkpoint itself is whole
    if not path.exists():
        return None
    try:
        with np.load(path, allow_pickle=False) as z:
            header = json.loads(str(z["header"]))
            arrays = {k: z[k] for k in z.files if k != "header"}
        earlier = {f"linkagekit-checkpoint/{v}": v for v in range(1, CHECKPOINT_VERSION)}
        if isinstance(header, dict) and header.get("format") in earlier:
            v = earlier[header["format"]]
            raise ValueError(f"written by an earlier linkagekit (format {v}, another search); delete it to start anew")
        if not isinstance(header, dict) or header.get("format") != f"linkagekit-checkpoint/{CHECKPOINT_VERSION}":
            raise ValueError("not a linkagekit checkpoint")
        done = [
            {**d, "x": arrays[f"done_x_{i}"], "cost": float(d["cost"]), "max_error": float(d["max_error"])}
            for i, d in enumerate(header["done"])
        ]
        solver = None
        if header["solver"] is not None:
            solver = dict(header["solver"])
            solver.update({k: arrays[f"solver_{k}"] for k in solver.pop("arrays")})
        fingerprint, key = header["problem"], header["settings"]
        state = {
            "restart": int(header["restart"]),
            "generation": int(header["generation"]),
            "evaluations": int(header["evaluations"]),
            "elapsed": float(header["elapsed"]),
            "done": done,
            "solver": solver,
        }
    except (OSError, EOFError, ValueError, KeyError, TypeError, AttributeError, zipfile.BadZipFile) as e:
        raise InputError(f"{path}: not a readable linkagekit checkpoint ({type(e).__name__}: {e})") from None
    if fingerprint != problem.fingerprint():
        raise InputError(f"{path}: this checkpoint belongs to another problem (other targets, topology or options)")
    if key != settings.key():
        raise InputError(f"{path}: this checkpoint was made with other settings: {key}")
    return state
