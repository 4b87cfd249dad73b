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

Feasibility (penalised by how far from feasible, never by a cliff)
----------------------------------------------------------------
* the crank turns fully: the mean over the sweep of each dyad step's negative margin
  (``positions.solve``: how far the circles are from meeting, relative);
* every transmission angle ``mu`` of the space stays within ``[MIN, 180 - MIN]``: the largest
  ``|cos mu| - cos MIN`` over the sweep;
* link lengths within bounds, when given: the largest relative excess.

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
from typing import TYPE_CHECKING

import numpy as np

from ..checks import MIN_TRANSMISSION
from ..errors import InputError
from ..geometry import ComplexArray, FloatArray, abs2
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
        Samples of the crank turn.
    """

    space: DesignSpace
    targets: np.ndarray
    inputs: np.ndarray | None = None
    ordered: bool = False
    min_transmission: float = MIN_TRANSMISSION
    lengths: tuple[float, float] | None = None
    samples: int = 180

    def __post_init__(self) -> None:
        t = np.asarray(self.targets)
        if t.ndim != 1 or len(t) < 3 or not np.all(np.isfinite(t)):
            raise InputError("targets: at least 3 finite points are needed")
        if not 0.0 <= self.min_transmission < 90.0:
            raise InputError(f"--min-transmission: {self.min_transmission:g} is not within [0, 90) degrees")
        if self.samples < 8:
            raise InputError("samples: at least 8 samples of the crank turn are needed")

    @cached_property
    def scale(self) -> float:
        """The targets' bounding-box diagonal ``L``."""
        t = self.targets
        return float(np.hypot(np.ptp(t.real), np.ptp(t.imag))) or 1.0

    @property
    def timed(self) -> bool:
        return self.inputs is not None

    @property
    def dim(self) -> int:
        return self.space.dim

    @property
    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper bounds of the design vector."""
        return self.space.lower, self.space.upper

    def offset(self, X: np.ndarray) -> np.ndarray:
        """With timing: the input offset ``delta`` (radians) of each design, ``theta_pose - phi_0``."""
        assert self.inputs is not None
        params = compile_params(self.space.template, self.space.poses(np.atleast_2d(X)), self.space.plan)
        return np.asarray(params.pose_inputs[0] - self.inputs[0])

    def fingerprint(self) -> str:
        """A digest of everything that defines the problem (to match a checkpoint to its run)."""
        import hashlib

        h = hashlib.sha256()
        for a in (self.targets, self.space.lower, self.space.upper, self.inputs if self.timed else np.zeros(0)):
            h.update(np.ascontiguousarray(a).tobytes())
        h.update(repr((self.space.topology, self.space.free, self.space.tracer, self.space.transmission)).encode())
        h.update(repr((self.ordered, self.min_transmission, self.lengths, self.samples)).encode())
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

    def mechanism(self, x: FloatArray) -> Mechanism:
        return self.space.mechanism(np.asarray(x, float))

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
    """

    cost: np.ndarray
    errors: np.ndarray
    theta: np.ndarray
    violation: np.ndarray
    transmission: np.ndarray


def evaluate(
    problem: Problem, X: np.ndarray, refine: int = 1, samples: int | None = None, margin: float = MARGIN
) -> Evaluation:
    """Score the design vectors ``X`` (N, dim) of ``problem`` (see the module's description).

    ``refine``: Newton iterations on each target's nearest input (untimed problems);
    ``samples``: samples of the crank turn (default ``problem.samples``); ``margin``: degrees
    added to the transmission-angle limit.
    """
    X = np.atleast_2d(np.asarray(X, float))
    n = int(samples or problem.samples)
    m = len(problem.targets)
    per_design = n + m * (3 * refine + 1)
    step = max(1, CHUNK // per_design)
    parts = [_evaluate(problem, X[s : s + step], refine, n, margin) for s in range(0, len(X), step)]
    return Evaluation(*(np.concatenate([getattr(p, f) for p in parts]) for f in Evaluation.__dataclass_fields__))


#: samples of the crank turn and Newton steps of the check that measures a result (every 0.1 degree)
CHECK_SAMPLES, CHECK_REFINE = 3600, 4


def check(problem: Problem, X: np.ndarray) -> Evaluation:
    """The evaluation a result is reported by: ``CHECK_SAMPLES`` samples, nearest points refined, no margin."""
    return evaluate(problem, X, refine=CHECK_REFINE, samples=CHECK_SAMPLES, margin=0.0)


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


def _evaluate(problem: Problem, X: np.ndarray, refine: int, n: int, margin: float) -> Evaluation:
    sp = problem.space
    N = len(X)
    L = problem.scale
    params = compile_params(sp.template, sp.poses(X), sp.plan)
    q0 = params.pose_inputs[0]  # (N,) the crank's input at each pose
    theta = q0[:, None] + (2 * np.pi / n) * np.arange(n)
    sol = solve(params, theta[None])
    z = sol.z
    with np.errstate(invalid="ignore"):
        # -- feasibility: assembly over the whole turn, transmission angles, lengths
        short = np.nan_to_num(np.maximum(-sol.margin, 0.0), nan=0.0)
        violation = short.sum(axis=0).mean(axis=-1) if short.size else np.zeros(N)
        violation = np.where(params.valid, violation, violation + 1.0)
        cos_lim = np.cos(np.radians(min(problem.min_transmission + margin, 89.0)))
        worst_cos = np.zeros(N)
        mu_min = np.full(N, np.nan)
        for j, a, b in sp.transmission:
            zj = z[sp.joint(j)]
            u, v = z[sp.joint(a)] - zj, z[sp.joint(b)] - zj
            c = (np.conj(u) * v).real / (np.abs(u) * np.abs(v))
            worst = np.nanmax(np.where(np.isfinite(c), np.abs(c), -np.inf), axis=-1)
            worst_cos = np.maximum(worst_cos, worst)
            mu = np.degrees(np.arccos(np.clip(worst, -1.0, 1.0)))
            mu_min = np.where(np.isfinite(worst), np.fmin(mu_min, mu), mu_min)
        violation = violation + np.maximum(worst_cos - cos_lim, 0.0)
        if problem.lengths is not None:
            violation = violation + _length_excess(sp, params.pose, *problem.lengths)
        # -- errors
        T = problem.targets
        if problem.timed:
            assert problem.inputs is not None
            th = q0[:, None] + (problem.inputs - problem.inputs[0])[None, :]
            err = np.abs(_tracer(params, sp, th) - T[None, :])
        else:
            th, err = _nearest(params, sp, z[sp.joint(sp.tracer)], theta, T, refine, n, problem.ordered)
        rel = np.where(np.isfinite(err), err / L, 1.0)
        cost = np.mean(rel * rel, axis=1) + PENALTY * violation
    return Evaluation(cost, err, th, violation, mu_min)


def _tracer(params: Params, sp: DesignSpace, th: FloatArray) -> ComplexArray:
    """The tracer point at inputs ``th`` (N, k), NaN where a design does not assemble."""
    z: ComplexArray = solve(params, th[None]).z[sp.joint(sp.tracer)]
    return z


def _nearest(
    params: Params,
    sp: DesignSpace,
    P: np.ndarray,
    theta: np.ndarray,
    T: np.ndarray,
    refine: int,
    n: int,
    ordered: bool = False,
) -> tuple[np.ndarray, np.ndarray]:
    """(inputs, distances) of the nearest curve point to every target, (N, m) each."""
    d2 = _distances2(P, T)  # (N, m, n)
    k = _ordered(d2) if ordered else np.argmin(d2.transpose(1, 0, 2), axis=-1).T  # over d2's memory order
    th = np.take_along_axis(theta, k, axis=-1)  # (N, m)
    best = np.abs(np.take_along_axis(P, k, axis=-1) - T[None, :]) ** 2  # exactly, not by the expansion
    best = np.where(np.isfinite(best), best, np.inf)
    spacing = 2 * np.pi / n
    h = H_THETA
    m = len(T)
    for _ in range(refine):
        Z = _tracer(params, sp, np.concatenate([th - h, th, th + h], axis=1))
        Pm, P0, Pp = Z[:, :m], Z[:, m : 2 * m], Z[:, 2 * m :]
        r = P0 - T[None, :]
        d1 = (Pp - Pm) / (2 * h)
        dd = (Pp - 2 * P0 + Pm) / (h * h)
        g = (np.conj(r) * d1).real
        gp = np.abs(d1) ** 2 + (np.conj(r) * dd).real
        gp = np.where(gp > 0, gp, np.abs(d1) ** 2)  # not convex here: a gradient step of Gauss-Newton's size
        step = np.clip(-g / gp, -spacing, spacing)
        cand = th + np.where(np.isfinite(step), step, 0.0)
        dc = np.abs(_tracer(params, sp, cand) - T[None, :]) ** 2
        better = np.isfinite(dc) & (dc < best)
        th = np.where(better, cand, th)
        best = np.where(better, dc, best)
    return th, np.where(np.isfinite(best), np.sqrt(best), np.nan)


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


def _ordered(d2: np.ndarray) -> np.ndarray:
    """Sample indices (N, m) of the targets met in order: the monotone assignment of least total ``d2``.

    ``d2`` (N, m, n): squared distance of each target to each sample of the closed curve.
    The curve is unrolled from the sample nearest the first target, once forwards and once
    backwards; along it the targets' samples must not decrease (dynamic programming with a
    running minimum: ``acc_i(j) = d2_i(j) + min_{j' <= j} acc_{i-1}(j')``), and the cheaper
    direction wins. The total is a minimum of sums of continuous functions of the design,
    so it is continuous too.
    """
    N, m, n = d2.shape
    k0 = np.argmin(d2[:, 0, :], axis=-1)
    rows = np.arange(N)[:, None, None]
    best_total = np.full(N, np.inf)
    best_k = np.zeros((N, m), np.intp)
    for direction in (1, -1):
        idx = np.mod(k0[:, None] + direction * np.arange(n)[None, :], n)  # (N, n) unrolled -> sample
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


def _length_excess(sp: DesignSpace, pose: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """Largest relative excess of a link length (between two joints of one link) outside ``[lo, hi]``."""
    out = np.zeros(pose.shape[1])
    for ln in sp.template.links:
        if ln.name == "ground":
            continue
        ids = [sp.joint(j) for j in ln.joints]
        for i, a in enumerate(ids):
            for b in ids[i + 1 :]:
                d = np.abs(pose[a] - pose[b])
                out = np.maximum(out, np.maximum(lo - d, d - hi) / hi)
    return np.maximum(out, 0.0)
