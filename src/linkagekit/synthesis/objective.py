r"""The synthesis objective, over (designs x samples) at once.

A :class:`Problem` holds the targets, the design space and the constraints; :func:`evaluate`
scores a batch of design vectors through the design axis (one :func:`~linkagekit.params.compile`
and a few :func:`~linkagekit.positions.solve` calls per chunk of designs; no loop per design).

Error of a design (lengths in the targets' unit, ``L`` the targets' bounding-box diagonal)
---------------------------------------------------------------------------------------
*Without timing*, ``e_i`` is the distance from target ``T_i`` to the tracer's curve
``P(theta)`` over a full crank turn. The curve is sampled at ``n`` inputs from the pose's
input; the nearest sample ``theta_k`` seeds Newton's method on

.. math:: g(\theta) = \tfrac12 \frac{d}{d\theta}|P(\theta) - T|^2 = \operatorname{Re}\big(\overline{(P - T)}\,P'\big),
          \qquad g' = |P'|^2 + \operatorname{Re}\big(\overline{(P - T)}\,P''\big),

with ``P'`` and ``P''`` by central differences of step ``h`` (all targets of all designs in
one solve of ``3m`` samples per design); a step is clipped to one sample spacing and kept
only where it brings the point nearer. So ``e_i`` is the distance to an actual point of
the curve (never an underestimate), and at a stationary point its gradient in the design
is that of the true distance (the envelope theorem), which the local polish needs.

*With timing* (an input angle ``phi_i`` per target), ``e_i = |P(phi_i + delta) - T_i|`` with
one common offset ``delta = theta_pose - phi_0``: the pose is the mechanism at the first
target's input (its tracer is searched near the first target), so the offset is not a
search variable and the design vector is the same as without timing.

*Order*: when asked, the targets are met in their order along the curve, in one direction,
within one turn: each target's sample is chosen by the monotone assignment of least total
squared distance (:func:`_ordered`, dynamic programming), then refined as above.

*Shape only* (``Problem.shape_only``): the curve is first placed on the targets by the
similarity ``z -> a z + b`` that fits it best (:func:`similarity`, then :func:`plane_fit`
alternated with the nearest samples from 4 starting turns, :func:`_icp`), and every Newton
step refits it; ``e_i`` is the distance to the placed curve ``a P + b``.

*Partial* (``Problem.partial``): the curve is the part the crank traces over its sweep
``[start, start + span]`` (:meth:`Problem.sweep`; both ends sampled), and the nearest points
stay within it.

Feasibility (penalised by how far from feasible, never by a cliff)
----------------------------------------------------------------
* the crank turns fully (partial: assembles over its sweep): the mean over the sweep of each
  dyad step's negative margin (``positions.solve``: how far the circles are from meeting, relative);
* every transmission angle ``mu`` of the space stays within ``[MIN, 180 - MIN]``: the largest
  ``|cos mu| - cos MIN`` over the sweep;
* link lengths within bounds, when given: the largest relative excess (of the placed mechanism);
* the curve's RMS radius at least ``MIN_CURVE_SIZE`` of the joints' (:func:`_too_small`; in the
  dense check always, in the search with ``shape_only`` or ``partial``);
* no link degenerate: two joints of one link (the ground's pivots too; the tracer aside) at
  least ``MIN_LINK`` of the joints' RMS spread apart (:func:`degenerate`).

The score is ``mean_i (e_i / L)^2 + PENALTY * violation``: an exact penalty (linear in the
violation), so a feasible optimum stays feasible.

Examples
--------
>>> import numpy as np
>>> from linkagekit.synthesis.space import builtin_space
>>> sp = builtin_space("fourbar", (0.0, 0.0), 4.0)
>>> mech_x = np.array([0, 0, 4, 1, 2, 0, 0.82055, 4.85890, 5.61821, 3.45088])  # seed 000's pose
>>> curve = evaluate(Problem(sp, np.array([5.61821 + 3.45088j, 0, 1j])), mech_x[None], refine=0)
>>> float(curve.errors[0, 0]) < 1e-9, bool(curve.violation[0] == 0)
(True, True)
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import cached_property
from typing import TYPE_CHECKING, Any

import numpy as np

from ..checks import MIN_TRANSMISSION
from ..errors import InputError
from ..geometry import ComplexArray, FloatArray, abs2, solve_each
from ..params import Params
from ..params import compile as compile_params
from ..positions import solve
from .base import Objective, Score
from .space import DesignSpace

if TYPE_CHECKING:
    from ..model import Mechanism

#: weight of the violation against the mean squared relative error (large: a design that gains accuracy
#: by violating a constraint a little is still worse than a feasible one)
PENALTY = 100.0
#: design-samples per chunk: bounds memory (~16 bytes x this x a few arrays) and keeps a chunk's arrays
#: in cache (benchmarks/bench_synthesis.py: 2^16 is about 1.6x faster per design-sample than 2^19 here)
CHUNK = 1 << 16
#: degrees added to the smallest transmission angle while searching, so that the design found keeps
#: the limit between the samples too (the result is checked densely against the limit itself)
MARGIN = 0.25
#: central-difference step of the refinement (radians)
H_THETA = 1e-4
#: a rule of path synthesis (docs/commands.md): the traced curve's RMS radius is at least this fraction of the RMS
#: distance of the joints (at the pose) from their centroid, for every written mechanism
MIN_CURVE_SIZE = 0.07
#: the shortest distance between two joints of one link (the tracer aside), as a fraction of the RMS distance of
#: the joints from their centroid: two ground pivots 1e-6 apart made a "four-bar" of a rigid triangle, and at 1e-3
#: the default search on the shipped letter C wrote pivots 0.1 mm apart, the tracer 84 coupler lengths out (a 1 um
#: error of one pivot raised the max error from 0.32 to 0.49 mm); the published designs of the benchmark problems
#: are at least 0.06
MIN_LINK = 1e-2
#: a rule of path synthesis (docs/commands.md): a partial sweep turns the crank through at least this angle (radians)
MIN_SPAN = np.pi / 2
#: ``--shape-only``: the similarity's starting rotations (evenly spaced), nearest-point/fit rounds from each,
#: and every how many samples of the curve they look at (the Newton steps after them see the curve itself);
#: measured on 8 random four-bars' curves, moved, turned and scaled: the exact placement from 7 of them
ROTATIONS, ICP_STEPS, ICP_STRIDE = 4, 5, 1
#: the most samples the starts look at: the dense check's curve is thinned to them, so that its placement
#: starts from the search's samples and ends in the basin the search chose
ICP_SAMPLES = 180
#: the highest transmission bound of --pareto's searches (degrees)
RAISED_MAX = 80.0


@dataclass(frozen=True, eq=False)
class Problem(Objective):
    """Path generation: targets, a design space, constraints (the engine's first :class:`~.base.Objective`).

    Its error measure is the largest distance of a target to the curve over the targets'
    diagonal; its cost and check are :func:`evaluate` and :func:`check`.

    Attributes
    ----------
    space : DesignSpace
    targets : ndarray, complex, shape (m,)
        Target points ``x + iy`` in the template's length unit.
    inputs : ndarray, shape (m,), optional
        Prescribed input angles (radians): timing, up to one common offset (the pose is at
        the first target's input).
    ordered : bool
        Without timing: the targets must be met in their order along the curve.
    min_transmission : float
        Degrees; every angle of ``space.transmission`` stays within ``[MIN, 180 - MIN]``.
    lengths : (float, float), optional
        Bounds on every link length (between any two joints of a link).
    samples : int
        Samples of the crank turn (or of the partial sweep).
    shape_only : bool
        The curve is matched up to translation, rotation and uniform scale: each design's
        curve is placed on the targets by the similarity ``z -> a z + b`` that fits it best
        (:func:`similarity`, alternated with the nearest-point search); errors are distances
        to the placed curve.
    partial : bool
        Only the part of the curve traced while the crank sweeps ``[start, start + span]``
        counts, ``span >= MIN_SPAN``, and the mechanism need only assemble over it. Without
        timing the design vector's last two entries are ``f`` in [0, 1] and ``span`` (radians),
        ``start = theta_pose - f span``: the pose, whose assembly mode is the branch, lies within
        the sweep; with timing the sweep is the one the inputs span (widened about its middle to
        ``MIN_SPAN``).
    """

    space: DesignSpace
    targets: np.ndarray
    inputs: np.ndarray | None = None
    ordered: bool = False
    min_transmission: float = MIN_TRANSMISSION
    lengths: tuple[float, float] | None = None
    samples: int = 180
    shape_only: bool = False
    partial: bool = False

    def __post_init__(self) -> None:
        t = np.asarray(self.targets)
        if t.ndim != 1 or len(t) < 3 or not np.all(np.isfinite(t)):
            raise InputError("targets: at least 3 finite points are needed")
        if not 0.0 <= self.min_transmission < 90.0:
            raise InputError(f"--min-transmission: {self.min_transmission:g} is not within [0, 90) degrees")
        if self.samples < 8:
            raise InputError("samples: at least 8 samples of the crank turn are needed")
        if self.lengths is not None:
            bounds = np.asarray(self.lengths, float).ravel()
            if len(bounds) != 2 or not (0 <= bounds[0] < bounds[1] < np.inf):  # NaN fails too
                raise InputError(f"lengths: expected (low, high) with 0 <= low < high, got {self.lengths!r}")

    @cached_property
    def scale(self) -> float:
        """The targets' bounding-box diagonal ``L``."""
        t = self.targets
        return float(np.hypot(np.ptp(t.real), np.ptp(t.imag))) or 1.0

    @property
    def timed(self) -> bool:
        return self.inputs is not None

    @property
    def swept(self) -> bool:
        """The sweep's start and span are design variables (partial, untimed)."""
        return self.partial and not self.timed

    @property
    def dim(self) -> int:
        return self.space.dim + 2 * self.swept

    @property
    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper bounds of the design vector (partial, untimed: then the sweep's ``f`` and span)."""
        if not self.swept:
            return self.space.lower, self.space.upper
        return np.append(self.space.lower, [0.0, MIN_SPAN]), np.append(self.space.upper, [1.0, 2 * np.pi])

    def sweep(self, X: FloatArray, q0: FloatArray) -> tuple[FloatArray, FloatArray]:
        """``(start, span)`` (N,) of the crank's sweep (radians, in the design's frame), ``q0`` the pose's inputs."""
        if not self.partial:
            return q0, np.full_like(q0, 2 * np.pi)
        if self.swept:  # the pose within the sweep: a fraction X[:, -2] of it before the pose
            return q0 - X[:, -2] * X[:, -1], X[:, -1]
        assert self.inputs is not None
        th = q0[:, None] + (self.inputs - self.inputs[0])[None, :]
        lo, hi = th.min(axis=1), th.max(axis=1)
        widen = np.maximum(MIN_SPAN - (hi - lo), 0.0)
        return lo - widen / 2, hi - lo + widen

    def offset(self, X: np.ndarray) -> np.ndarray:
        """With timing: the input offset ``delta`` (radians) of each design, ``theta_pose - phi_0``.

        With ``shape_only`` the placement turns the crank too: its rotation ``arg a`` is added.
        """
        assert self.inputs is not None
        X = np.atleast_2d(X)
        params = compile_params(self.space.template, self.space.poses(X), self.space.plan)
        turn = np.angle(evaluate(self, X, refine=0).a) if self.shape_only else 0.0
        return np.asarray(params.pose_inputs[0] + turn - self.inputs[0])

    def fingerprint(self) -> str:
        """A digest of everything that defines the problem (to match a checkpoint to its run)."""
        import hashlib

        h = hashlib.sha256()
        for a in (self.targets, self.space.lower, self.space.upper, self.inputs if self.timed else np.zeros(0)):
            h.update(np.ascontiguousarray(a).tobytes())
        h.update(repr((self.space.topology, self.space.free, self.space.tracer, self.space.transmission)).encode())
        h.update(repr((self.ordered, self.min_transmission, self.lengths, self.samples)).encode())
        h.update(repr((self.shape_only, self.partial)).encode() if self.shape_only or self.partial else b"")
        h.update(repr(self.space.template.to_dict()).encode())
        return h.hexdigest()[:16]

    # -- the engine's interface (base.Objective)
    @property
    def polish_methods(self) -> tuple[str, str]:
        """Trust-region reflective first without timing, dogbox first with it (see ``optimize.polish_method``)."""
        return ("dogbox", "trf") if self.timed else ("trf", "dogbox")

    def score(self, X: FloatArray) -> Score:
        """The search's score (:func:`evaluate`): error = max distance / ``L``."""
        return _score(self, evaluate(self, X))

    def cost(self, X: FloatArray) -> FloatArray:
        return evaluate(self, X).cost

    def check(self, X: FloatArray) -> Score:
        """The dense check (:func:`check`)."""
        return _score(self, check(self, X))

    def measure(self, X: FloatArray) -> tuple[FloatArray, FloatArray]:
        return measure(self, X)

    def residuals(self, X: FloatArray) -> FloatArray:
        """``e_i / (L sqrt(m))`` and ``sqrt(PENALTY * violation)``, (N, m + 1), nearest points refined 3 times."""
        e = evaluate(self, X, refine=3)
        m = len(self.targets)
        rel = np.where(np.isfinite(e.errors), e.errors / self.scale, 1.0) / np.sqrt(m)
        out: FloatArray = np.concatenate([rel, np.sqrt(PENALTY * e.violation)[:, None]], axis=1)
        return out

    def variants(self) -> tuple[Objective, ...]:
        """With the order asked for, also the problem without it (cheaper; a fit found without it may be in order)."""
        return (self, replace(self, ordered=False)) if self.ordered else (self,)

    def mechanism(self, x: FloatArray, name: str | None = None) -> Mechanism:
        """The design as a mechanism: placed on the targets (``shape_only``), its driver sweeping its range."""
        x = np.asarray(x, float)
        if not (self.shape_only or self.partial):
            return self.space.mechanism(x, name)
        e = check(self, x[None])
        a, b = complex(e.a[0]), complex(e.b[0])
        sweep = None
        if self.partial:
            start, span = float(e.sweep[0, 0] + np.angle(a)), float(e.sweep[0, 1])
            steps = int(np.ceil(np.degrees(span) - 1e-9))  # about one degree a step, the last one on the stop
            sweep = (start, start + span, span / steps)
        return self.space.mechanism(x, name, (a, b), sweep)

    def transmission(self, X: FloatArray) -> FloatArray:
        """The smallest transmission angle (degrees) over the turn, by :func:`check`."""
        return check(self, np.atleast_2d(X)).transmission

    def raised(self, degrees: float) -> Objective | None:
        """The problem with ``min_transmission`` ``degrees`` higher, at most ``RAISED_MAX`` (None: no higher)."""
        bound = min(self.min_transmission + degrees, RAISED_MAX)
        return replace(self, min_transmission=bound) if bound > self.min_transmission else None


@dataclass(frozen=True)
class Evaluation:
    """Scores of N designs.

    Attributes
    ----------
    cost : ndarray (N,)
        ``mean (e / L)^2 + PENALTY * violation``.
    errors : ndarray (N, m)
        Distance of each target to the curve (or to its timed point), in length units; NaN
        where the design has no such point.
    theta : ndarray (N, m)
        The input (radians) of the point each target is measured to.
    violation : ndarray (N,)
        0 for a feasible design.
    transmission : ndarray (N,)
        The smallest transmission angle over the sampled turn (degrees; NaN if none assembles).
    a, b : ndarray complex (N,)
        The placement ``z -> a z + b`` of each design's curve on the targets (1 and 0 unless ``shape_only``).
    sweep : ndarray (N, 2)
        The start and span (radians) of each design's crank sweep, in the design's own frame.
    """

    cost: np.ndarray
    errors: np.ndarray
    theta: np.ndarray
    violation: np.ndarray
    transmission: np.ndarray
    a: np.ndarray
    b: np.ndarray
    sweep: np.ndarray


def evaluate(
    problem: Problem,
    X: np.ndarray,
    refine: int = 1,
    samples: int | None = None,
    margin: float = MARGIN,
    strict: bool = False,
) -> Evaluation:
    """Score the design vectors ``X`` (N, dim) of ``problem`` (see the module's description).

    ``refine``: Newton iterations on each target's nearest input (untimed problems);
    ``samples``: samples of the crank turn (default ``problem.samples``); ``margin``: degrees
    added to the transmission-angle limit; ``strict``: the curve's size rule (:func:`_too_small`)
    counts even where the search leaves it out (absolute placement, full turn: there a curve
    on the targets cannot be small against joints held near them, and leaving it out keeps
    the searches of those problems as they were).
    """
    X = np.atleast_2d(np.asarray(X, float))
    n = int(samples or problem.samples)
    m = len(problem.targets)
    per_design = (n + m * (3 * refine + 1)) * (1 + (ROTATIONS - 1) * problem.shape_only)
    step = max(1, CHUNK // per_design)
    sized = strict or problem.shape_only or problem.partial
    parts = [_evaluate(problem, X[s : s + step], refine, n, margin, sized) for s in range(0, len(X), step)]
    return Evaluation(*(np.concatenate([getattr(p, f) for p in parts]) for f in Evaluation.__dataclass_fields__))


#: samples of the crank turn and Newton steps of the check that measures a result (every 0.1 degree)
CHECK_SAMPLES, CHECK_REFINE = 3600, 4
#: more Newton steps of the check with ``shape_only`` (placement and inputs together converge more slowly
#: where the curve bends sharply: on a Watt II curve 1e-5 of the diagonal after 4 steps, 1e-7 after 16)
SHAPE_REFINE = 12


def check(problem: Problem, X: np.ndarray) -> Evaluation:
    """The evaluation a result is reported by: ``CHECK_SAMPLES`` samples, nearest points refined, no margin."""
    refine = CHECK_REFINE + SHAPE_REFINE * problem.shape_only
    return evaluate(problem, X, refine=refine, samples=CHECK_SAMPLES, margin=0.0, strict=True)


def measure(problem: Problem, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(max error / L, cost)`` of designs ``X`` (N, dim) by :func:`check`: the measure a result is printed by.

    The max error is ``inf`` for a design that breaks a constraint or misses a target.
    """
    e = check(problem, X)
    ok = np.all(np.isfinite(e.errors), axis=1) & (e.violation == 0)
    err = np.max(np.where(np.isfinite(e.errors), e.errors, 0.0), axis=1) / problem.scale
    return np.where(ok, err, np.inf), e.cost


def _score(problem: Problem, e: Evaluation) -> Score:
    """An :class:`Evaluation` as the engine's :class:`~.base.Score` (error: max distance / L, NaN -> inf)."""
    miss = ~np.all(np.isfinite(e.errors), axis=1)
    err = np.max(np.where(np.isfinite(e.errors), e.errors, 0.0), axis=1) / problem.scale
    return Score(e.cost, np.where(miss, np.inf, err), e.violation)


def best_index(max_error: np.ndarray, cost: np.ndarray) -> int:
    """The best design: the smallest max error among the feasible, then the lowest cost (none feasible: cost).

    >>> best_index(np.array([0.03, 0.02, np.inf]), np.array([1e-4, 2e-4, 1e-5]))
    1
    """
    return int(np.lexsort((np.asarray(cost, float), np.asarray(max_error, float)))[0])


def _evaluate(problem: Problem, X: np.ndarray, refine: int, n: int, margin: float, sized: bool) -> Evaluation:
    sp = problem.space
    params = compile_params(sp.template, sp.poses(X), sp.plan)
    q0 = params.pose_inputs[0]  # (N,) the crank's input at each pose
    start, span = problem.sweep(X, q0)
    theta = start[:, None] + span[:, None] * (np.arange(n) / (n - problem.partial))  # a partial sweep: both ends
    sol = solve(params, theta[None])
    P = sol.z[sp.joint(sp.tracer)]
    with np.errstate(invalid="ignore"):
        violation, mu_min = _feasibility(problem, params, sol.z, sol.margin, margin)
        if sized:
            violation = violation + _too_small(P, params.pose, margin)
        violation = violation + degenerate(sp, params.pose)
        if problem.timed:
            th, err, a, b = _timed(problem, params, q0)
        else:
            within = (start, start + span) if problem.partial else (-np.inf, np.inf)
            th, err, a, b = _nearest(problem, params, P, theta, within, refine)
        if problem.lengths is not None:
            violation = violation + _length_excess(sp, params.pose * np.abs(a)[None, :], *problem.lengths)
        rel = np.where(np.isfinite(err), err / problem.scale, 1.0)
        cost = np.mean(rel * rel, axis=1) + PENALTY * violation
    return Evaluation(cost, err, th, violation, mu_min, a, b, np.stack([start, span], axis=1))


def _feasibility(
    problem: Problem, params: Params, z: ComplexArray, margins: FloatArray, margin: float
) -> tuple[FloatArray, FloatArray]:
    """``(violation, smallest transmission angle)`` (N,) of the sweep: assembly everywhere, transmission angles."""
    sp = problem.space
    short = np.nan_to_num(np.maximum(-margins, 0.0), nan=0.0)
    violation = short.sum(axis=0).mean(axis=-1) if short.size else np.zeros(z.shape[1])
    # a sample no step's margin flags but where a joint is not placed (a numerical group reports no margin): its
    # share of the sweep (a template's triad was written over a sweep where it assembled at 64 of 361 inputs)
    flagged = np.any(short > 0, axis=0) if short.size else np.zeros(z.shape[1:], bool)
    unplaced = np.mean(~np.all(np.isfinite(z), axis=0) & ~flagged, axis=-1)
    violation = violation + np.where(params.valid, unplaced, 0.0)  # (an invalid design counts 1 below)
    violation = np.where(params.valid, violation, violation + 1.0)
    cos_lim = np.cos(np.radians(transmission_limit(problem.min_transmission, margin)))
    worst_cos = np.zeros(z.shape[1])
    mu_min = np.full(z.shape[1], np.nan)
    for j, a, b in sp.transmission:
        zj = z[sp.joint(j)]
        u, v = z[sp.joint(a)] - zj, z[sp.joint(b)] - zj
        c = (np.conj(u) * v).real / (np.abs(u) * np.abs(v))
        worst = np.nanmax(np.where(np.isfinite(c), np.abs(c), -np.inf), axis=-1)
        worst_cos = np.maximum(worst_cos, worst)
        mu = np.degrees(np.arccos(np.clip(worst, -1.0, 1.0)))
        mu_min = np.where(np.isfinite(worst), np.fmin(mu_min, mu), mu_min)
    return violation + np.maximum(worst_cos - cos_lim, 0.0), mu_min


def transmission_limit(min_transmission: float, margin: float) -> float:
    """The smallest transmission angle a search holds (degrees): the bound raised by its ``margin``, the raise
    stopping at 89 deg, the bound itself never (89.99 was checked as 89, and a design below it written, exit 0).

    >>> transmission_limit(20.0, 0.25), transmission_limit(88.9, 0.25), transmission_limit(89.99, 0.25)
    (20.25, 89.0, 89.99)
    """
    return min(min_transmission + margin, max(min_transmission, 89.0))


def _too_small(P: ComplexArray, pose: ComplexArray, margin: float) -> FloatArray:
    r"""How far (N,) the curve breaks the rule of its size: ``max(0, MIN_CURVE_SIZE - R_curve / R_joints)``.

    ``R_curve``: the RMS distance of the tracer's samples ``P`` (N, n) from their mean (the
    assembled ones); ``R_joints``: that of the joints of the ``pose`` (n_joints, N). Both move
    with a similarity alike, so the rule holds for a placed curve as for the design's own.
    While searching (``margin > 0``) the limit is 2 % higher, for the dense check's sake.
    """
    ok = np.isfinite(P)
    count = np.maximum(ok.sum(axis=1), 1)
    Pz = np.where(ok, P, 0.0)
    centre = Pz.sum(axis=1) / count
    r_curve = np.sqrt(np.where(ok, abs2(Pz - centre[:, None]), 0.0).sum(axis=1) / count)
    r_joints = np.sqrt(np.mean(abs2(pose - pose.mean(axis=0)), axis=0))
    limit = MIN_CURVE_SIZE * (1.02 if margin > 0 else 1.0)
    ratio = r_curve / np.where(r_joints > 0, r_joints, 1.0)
    return np.asarray(np.maximum(limit - ratio, 0.0))


def similarity(p: ComplexArray, t: ComplexArray) -> tuple[ComplexArray, ComplexArray]:
    r"""The similarity ``z -> a z + b`` (complex ``a``, ``b``: no reflection) that maps points ``p`` onto ``t`` best.

    ``p`` (N, m) per design, ``t`` (m,) or (N, m); a non-finite ``p_i`` weighs nothing
    (``w_i = 0``, else 1). Minimising ``F = sum w_i |a p_i + b - t_i|^2``: ``dF/d conj(b) = 0``
    gives ``b = t_bar - a p_bar`` (weighted means); with ``u = p - p_bar`` and ``v = t - t_bar``,
    ``F = |a|^2 sum w|u|^2 - 2 Re(a sum w u conj(v)) + sum w|v|^2``, and ``dF/d conj(a) = 0`` gives

    .. math:: a = \frac{\sum_i w_i\,\overline{u_i}\,v_i}{\sum_i w_i\,|u_i|^2}

    (weighted Procrustes / Umeyama in complex numbers). Fewer than two distinct finite points:
    ``a = 1, b = 0``.

    >>> p = np.array([[0, 1, 1j]])
    >>> a, b = similarity(p, 2j * p[0] + (3 - 1j))
    >>> bool(abs(a[0] - 2j) < 1e-12 and abs(b[0] - (3 - 1j)) < 1e-12)
    True
    """
    w = np.isfinite(p)
    t = np.broadcast_to(t, p.shape)
    count = np.maximum(w.sum(axis=-1), 1)
    pm = np.where(w, p, 0.0).sum(axis=-1) / count
    tm = np.where(w, t, 0.0).sum(axis=-1) / count
    u = np.where(w, p - pm[:, None], 0.0)
    v = np.where(w, t - tm[:, None], 0.0)
    den = abs2(u).sum(axis=-1)
    ok = den > 1e-300
    a = np.where(ok, (np.conj(u) * v).sum(axis=-1) / np.where(ok, den, 1.0), 1.0)
    b = np.where(ok, tm - a * pm, 0.0)
    return a, b


#: ``plane_fit``'s weight of the point-to-point distances beside the distances along the normals
POINT_WEIGHT = 1e-6


def plane_fit(p: ComplexArray, nu: ComplexArray, t: ComplexArray) -> tuple[ComplexArray, ComplexArray]:
    r"""The similarity ``a, b`` (N,) that brings the points ``p`` (N, m) onto the curve's tangent lines through ``t``.

    ``nu`` (N, m): the unit normals of the placed curve at ``p``. Minimises
    ``sum_i Re(conj(nu_i) (a p_i + b - t_i))^2 + POINT_WEIGHT |a p_i + b - t_i|^2``: the first
    term is the distance of ``t_i`` from the tangent line at the placed point (Gauss-Newton's
    model of the distance to the curve), the second keeps the fit determined where the normals
    alone leave a direction free (a circle's rotation). Both are linear in the four real
    numbers ``(Re a, Im a, Re b, Im b)``: a 4 x 4 normal-equation solve per design. At the
    nearest points (``a p_i + b - t_i`` along ``nu_i``) its minimum is :func:`similarity`'s.

    >>> p = np.array([[1, 1j, -1, -1j]])
    >>> a, b = plane_fit(p, -p / abs(p), 3 * p[0] + 1j)
    >>> bool(abs(a[0] - 3) < 1e-12 and abs(b[0] - 1j) < 1e-12)
    True
    """
    ok = np.isfinite(p) & np.isfinite(nu)
    pz, nz = np.where(ok, p, 0.0), np.where(ok, nu, 0.0)
    t = np.where(ok, np.broadcast_to(t, p.shape), 0.0)
    basis = np.stack([pz, 1j * pz, ok.astype(float), 1j * ok], axis=-1)  # d(a p + b)/d(Re a, Im a, Re b, Im b)
    Jn = (np.conj(nz)[..., None] * basis).real
    M = np.einsum("nmk,nml->nkl", Jn, Jn)
    M += POINT_WEIGHT * (
        np.einsum("nmk,nml->nkl", basis.real, basis.real) + np.einsum("nmk,nml->nkl", basis.imag, basis.imag)
    )
    r = np.einsum("nmk,nm->nk", Jn, (np.conj(nz) * t).real)
    r += POINT_WEIGHT * (np.einsum("nmk,nm->nk", basis.real, t.real) + np.einsum("nmk,nm->nk", basis.imag, t.imag))
    few = ok.sum(axis=-1) < 2
    M[few], r[few] = np.eye(4), [1.0, 0.0, 0.0, 0.0]
    M += (1e-15 * np.trace(M, axis1=1, axis2=2) + 1e-300)[:, None, None] * np.eye(4)  # coincident points
    # a design whose curve runs off to ~1e160 overflows its sums: no placement (its cost is infinite); neither it nor
    # a singular system is a LinAlgError for the whole batch ('Singular matrix' ended a shape-only partial search)
    x = solve_each(M, r)
    return x[:, 0] + 1j * x[:, 1], x[:, 2] + 1j * x[:, 3]


def _tangents(P: ComplexArray, closed: bool) -> ComplexArray:
    """Tangents (N, n) of sampled curves ``P`` (N, n) by central differences (one-sided at an open curve's ends)."""
    if closed:
        return np.roll(P, -1, axis=-1) - np.roll(P, 1, axis=-1)
    return np.gradient(P, axis=-1)


def _normals(tangent: ComplexArray) -> ComplexArray:
    """Unit normals ``i tangent / |tangent|`` (NaN where the tangent is 0 or not finite)."""
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(np.abs(tangent) > 0, 1j * tangent / np.abs(tangent), np.nan)


def _timed(
    problem: Problem, params: Params, q0: FloatArray
) -> tuple[FloatArray, FloatArray, ComplexArray, ComplexArray]:
    """``(inputs, errors, a, b)`` with timing: each target against the tracer at its input (placed if shape-only)."""
    assert problem.inputs is not None
    T = problem.targets
    th = q0[:, None] + (problem.inputs - problem.inputs[0])[None, :]
    Z = _tracer(params, problem.space, th)
    a, b = similarity(Z, T) if problem.shape_only else (np.ones(len(th), complex), np.zeros(len(th), complex))
    return th, np.abs(a[:, None] * Z + b[:, None] - T[None, :]), a, b


def _tracer(params: Params, sp: DesignSpace, th: FloatArray) -> ComplexArray:
    """The tracer point at inputs ``th`` (N, k), NaN where a design does not assemble."""
    z: ComplexArray = solve(params, th[None]).z[sp.joint(sp.tracer)]
    return z


def _nearest(
    problem: Problem,
    params: Params,
    P: ComplexArray,
    theta: FloatArray,
    within: tuple[Any, Any],
    refine: int,
) -> tuple[FloatArray, FloatArray, ComplexArray, ComplexArray]:
    """``(inputs, distances, a, b)``: the nearest point of the (placed) curve to every target, (N, m) each.

    ``P`` (N, n): the curve's samples at ``theta``; ``within``: the inputs the points stay in
    (a partial sweep's ends). With ``shape_only`` the placement ``a, b`` (N,) is fitted from
    the nearest samples (:func:`_icp`) and again before every Newton step.
    """
    T = problem.targets
    N, n = P.shape
    closed = not problem.partial
    if problem.shape_only:
        a, b = _icp(P, T, problem.ordered, closed)
    else:
        a, b = np.ones(N, complex), np.zeros(N, complex)
    k = _assign(_distances2(a[:, None] * P + b[:, None], T), problem.ordered, closed)
    th = np.take_along_axis(theta, k, axis=-1)  # (N, m)
    pts = np.take_along_axis(P, k, axis=-1)
    spacing = (theta[:, 1] - theta[:, 0])[:, None]
    if problem.shape_only:  # the placement moves each step: the inputs may have to follow it further
        spacing = np.maximum(spacing, (theta[:, -1] - theta[:, 0])[:, None] / ICP_SAMPLES)
    lo, hi = (np.asarray(w)[..., None] if np.ndim(w) else w for w in within)
    for _ in range(refine):
        th, pts, a, b = _newton(problem, params, th, (a, b), spacing, (lo, hi))
    if problem.shape_only and refine:  # the placement moved under the points: the nearest samples again, then
        th, pts = _nearer_samples(problem, (P, theta), (th, pts), (a, b))  # Newton on the inputs alone
        fixed = replace(problem, shape_only=False)
        for _ in range(refine):
            th, pts, _, _ = _newton(fixed, params, th, (a, b), spacing, (lo, hi))
    d = np.abs(a[:, None] * pts + b[:, None] - T[None, :])
    return th, np.where(np.isfinite(d), d, np.nan), a, b


def _nearer_samples(
    problem: Problem,
    samples: tuple[ComplexArray, FloatArray],
    found: tuple[FloatArray, ComplexArray],
    place: tuple[ComplexArray, ComplexArray],
) -> tuple[FloatArray, ComplexArray]:
    """``(inputs, points)`` (N, m): each target's point ``found`` by the placement's Newton steps, or its nearest
    sample (in order, ``ordered``) of the curve under the final placement where that is nearer (for ``ordered``,
    a design's whole assignment, by the sum of the squares).

    The Newton steps move each point at most a sample's spacing while the placement moves under it: a point they
    left on a farther part of the curve was reported as the target's error (0.533 cm where the curve came within
    0.427 cm, review 18a)."""
    P, theta = samples
    th, pts = found
    a, b = (x[:, None] for x in place)
    T = problem.targets[None, :]
    k = _assign(_distances2(a * P + b, problem.targets), problem.ordered, not problem.partial)
    th2, pts2 = np.take_along_axis(theta, k, axis=-1), np.take_along_axis(P, k, axis=-1)
    old, new = abs2(a * pts + b - T), abs2(a * pts2 + b - T)
    old = np.where(np.isfinite(old), old, np.inf)
    if problem.ordered:
        nearer = np.broadcast_to((np.sum(new, axis=1) < np.sum(old, axis=1))[:, None], old.shape)
    else:
        nearer = new < old
    return np.where(nearer, th2, th), np.where(nearer, pts2, pts)


def _newton(
    problem: Problem,
    params: Params,
    th: FloatArray,
    place: tuple[ComplexArray, ComplexArray],
    spacing: FloatArray,
    within: tuple[Any, Any],
) -> tuple[FloatArray, ComplexArray, ComplexArray, ComplexArray]:
    """One Gauss-Newton step on each target's input ``th`` and (``shape_only``) on the placement ``a, b``.

    The curve's points, tangents and second derivatives at ``th`` (central differences);
    with ``shape_only`` the placement is refitted first by :func:`plane_fit` on them (the
    joint Gauss-Newton step of inputs and placement, the inputs eliminated); then a Newton
    step on each input towards the nearest point of the placed curve, clipped to one sample
    ``spacing`` and to ``within``, kept only where it brings the point nearer. Returns the
    inputs, their (unplaced) points and the placement.
    """
    a, b = place
    T = problem.targets
    h = H_THETA
    m = len(T)
    Z = _tracer(params, problem.space, np.concatenate([th - h, th, th + h], axis=1))
    Pm, P0, Pp = Z[:, :m], Z[:, m : 2 * m], Z[:, 2 * m :]
    d1, dd = (Pp - Pm) / (2 * h), (Pp - 2 * P0 + Pm) / (h * h)
    if problem.shape_only:
        a, b = plane_fit(P0, _normals(a[:, None] * d1), T)
    A, B = a[:, None], b[:, None]
    r = A * P0 + B - T[None, :]
    g = (np.conj(r) * A * d1).real
    gp = abs2(A * d1) + (np.conj(r) * A * dd).real
    gp = np.where(gp > 0, gp, abs2(A * d1))  # not convex here: a gradient step of Gauss-Newton's size
    step = np.clip(-g / gp, -spacing, spacing)
    cand = np.clip(th + np.where(np.isfinite(step), step, 0.0), *within)
    Pc = _tracer(params, problem.space, cand)
    dc = abs2(A * Pc + B - T[None, :])
    better = np.isfinite(dc) & ~(dc >= abs2(r))  # nearer, or the old point had none
    return np.where(better, cand, th), np.where(better, Pc, P0), a, b


def _icp(P: ComplexArray, T: ComplexArray, ordered: bool, closed: bool) -> tuple[ComplexArray, ComplexArray]:
    """The placement ``a, b`` (N,) of each curve ``P`` (N, n) on the targets: nearest samples and fits in turn.

    From ``ROTATIONS`` starts (the curve's samples' centroid and RMS radius on the targets',
    turned by ``2 pi k / ROTATIONS``), ``ICP_STEPS`` rounds each of: the nearest samples of
    the placed curve (in order, if asked), then a fit of those samples onto the targets
    (:func:`similarity` first, then :func:`plane_fit`, which converges in a few rounds where
    point-to-point fits crawl); the start whose fit leaves the least squared distance wins.
    """
    P = P[:, :: max(ICP_STRIDE, P.shape[1] // ICP_SAMPLES)]  # the check's denser curve: the search's samples
    N, n = P.shape
    ok = np.isfinite(P)
    count = np.maximum(ok.sum(axis=1), 1)
    Pz = np.where(ok, P, 0.0)
    cP = Pz.sum(axis=1) / count
    rP = np.sqrt(np.where(ok, abs2(Pz - cP[:, None]), 0.0).sum(axis=1) / count)
    cT = T.mean()
    rT = np.sqrt(np.mean(abs2(T - cT)))
    turns = np.exp(2j * np.pi * np.arange(ROTATIONS) / ROTATIONS)
    a = (turns[:, None] * (rT / np.where(rP > 0, rP, 1.0))[None, :]).ravel()  # (ROTATIONS * N,)
    b = cT - a * np.tile(cP, ROTATIONS)
    PP = np.tile(P, (ROTATIONS, 1))
    tangents = _tangents(PP, closed)
    for step in range(ICP_STEPS + 1):
        k = _assign(_distances2(a[:, None] * PP + b[:, None], T), ordered, closed)
        pts = np.take_along_axis(PP, k, axis=-1)
        if step == ICP_STEPS:  # the fits are judged by the samples nearest to their own placement
            break
        if step == 0:
            a, b = similarity(pts, T)
        else:
            a, b = plane_fit(pts, _normals(a[:, None] * np.take_along_axis(tangents, k, axis=-1)), T)
    sse = abs2(a[:, None] * pts + b[:, None] - T[None, :]).sum(axis=1)
    best = np.argmin(np.where(np.isfinite(sse), sse, np.inf).reshape(ROTATIONS, N), axis=0) * N + np.arange(N)
    return a[best], b[best]


def _assign(d2: FloatArray, ordered: bool, closed: bool) -> np.ndarray:
    """Each target's sample (N, m) from squared distances ``d2`` (N, m, n): the nearest, or in order."""
    if ordered:
        return _ordered(d2, closed)
    k: np.ndarray = np.argmin(d2.transpose(1, 0, 2), axis=-1).T  # over d2's memory order
    return k


def _distances2(P: np.ndarray, T: np.ndarray) -> np.ndarray:
    """Squared distances (N, m, n) from the targets ``T`` (m,) to the curve samples ``P`` (N, n), inf where NaN.

    ``|P - T|^2 = |P|^2 - 2 (T . P) + |T|^2`` about the targets' centre, the middle term one
    matrix product over all designs and samples (no (N, m, n) temporaries of the differences).
    Rounding is about ``eps |P - c|^2``: enough to pick the nearest sample, which is all it
    is used for (the distances kept are computed directly).
    """
    c = T.mean()
    far = ~np.isfinite(P)
    Pc = np.where(far, 0.0, P - c)
    Tc = T - c
    N, n = P.shape
    xy = np.empty((2, N, n))
    xy[0], xy[1] = Pc.real, Pc.imag
    d2 = np.stack([Tc.real, Tc.imag], axis=1) @ xy.reshape(2, N * n)  # (m, N n): T . P
    d2 *= -2.0
    d2 += abs2(Tc)[:, None]
    d2 = d2.reshape(len(T), N, n)
    d2 += np.where(far, np.inf, abs2(Pc))[None]  # an unassembled sample is infinitely far
    return d2.transpose(1, 0, 2)


def _ordered(d2: np.ndarray, closed: bool = True) -> np.ndarray:
    """Sample indices (N, m) of the targets met in order: the monotone assignment of least total ``d2``.

    ``d2`` (N, m, n): squared distance of each target to each sample of the curve. A closed
    curve is unrolled from the sample nearest the first target, once forwards and once
    backwards (an open one, a partial sweep's, is taken as it is, forwards and backwards);
    along it the targets' samples must not decrease (dynamic programming with a running
    minimum: ``acc_i(j) = d2_i(j) + min_{j' <= j} acc_{i-1}(j')``), and the cheaper
    direction wins. The total is a minimum of sums of continuous functions of the design,
    so it is continuous too.
    """
    N, m, n = d2.shape
    k0 = np.argmin(d2[:, 0, :], axis=-1)
    rows = np.arange(N)[:, None, None]
    best_total = np.full(N, np.inf)
    best_k = np.zeros((N, m), np.intp)
    for direction in (1, -1):
        first = k0 if closed else np.full(N, 0 if direction == 1 else n - 1)
        idx = np.mod(first[:, None] + direction * np.arange(n)[None, :], n)  # (N, n) unrolled -> sample
        D = d2[rows, np.arange(m)[None, :, None], idx[:, None, :]]  # (N, m, n)
        acc = np.empty_like(D)
        acc[:, 0] = D[:, 0]
        for i in range(1, m):
            acc[:, i] = D[:, i] + np.minimum.accumulate(acc[:, i - 1], axis=-1)
        j = np.argmin(acc[:, -1], axis=-1)
        total = acc[np.arange(N), -1, j]
        path = np.empty((N, m), np.intp)
        path[:, -1] = j
        for i in range(m - 2, -1, -1):  # back-track: the best earlier sample not after the next target's
            masked = np.where(np.arange(n)[None, :] <= path[:, i + 1 : i + 2], acc[:, i], np.inf)
            path[:, i] = np.argmin(masked, axis=-1)
        k = np.take_along_axis(idx, path, axis=-1)
        better = total < best_total
        best_total = np.where(better, total, best_total)
        best_k = np.where(better[:, None], k, best_k)
    return best_k


def degenerate(sp: DesignSpace, pose: np.ndarray) -> FloatArray:
    """How far (N,) the ``pose`` (n_joints, N) breaks the rule that no link is degenerate: ``max(0, MIN_LINK - d /
    R)``, ``d`` the shortest distance between two joints of one link (the tracer aside: it may sit on a joint),
    ``R`` the joints' RMS distance from their centroid.

    >>> from linkagekit.synthesis.space import builtin_space
    >>> sp = builtin_space("fourbar", (0.0, 0.0), 4.0)
    >>> xy = sp.poses(np.array([[0, 0, 1e-9, 0, 2, 0, 0.8, 4.9, 5.6, 3.5]]))  # A, B, C, D, P: A and B 1e-9 apart
    >>> pose = (xy[..., 0] + 1j * xy[..., 1]).T
    >>> bool(degenerate(sp, pose)[0] > 0.9 * MIN_LINK)
    True
    """
    spread = np.sqrt(np.mean(abs2(pose - pose.mean(axis=0)), axis=0))
    shortest = np.full(pose.shape[1], np.inf)
    for a, b in _link_pairs(sp, tracer=False):
        shortest = np.fmin(shortest, np.abs(pose[a] - pose[b]))
    return np.asarray(np.maximum(MIN_LINK - shortest / np.where(spread > 0, spread, 1.0), 0.0))


def _link_pairs(sp: DesignSpace, tracer: bool = True) -> list[tuple[int, int]]:
    """Every pair of joints of one link (indices of ``sp``'s joints), the ground's too; the tracer's if ``tracer``."""
    pairs = []
    for ln in sp.template.links:
        ids = [sp.joint(j) for j in ln.joints if tracer or j != sp.tracer]
        pairs += [(a, b) for i, a in enumerate(ids) for b in ids[i + 1 :]]
    return pairs


def _length_excess(sp: DesignSpace, pose: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """Largest relative excess of a link length (between two joints of one link, the ground's pivots too: two pivots
    a nanometre apart made a 'feasible' four-bar of a rigid triangle) outside ``[lo, hi]``."""
    out = np.zeros(pose.shape[1])
    for a, b in _link_pairs(sp):
        d = np.abs(pose[a] - pose[b])
        out = np.maximum(out, np.maximum(lo - d, d - hi) / hi)
    return np.maximum(out, 0.0)
