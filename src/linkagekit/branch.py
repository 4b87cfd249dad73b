"""Following a branch through change points: the sign of every sign step, sample by sample, along a path.

By default every sign step keeps the sign read off the reference pose.  At a *change point*
two assembly modes meet (a parallelogram's flat position: the dyad's two circles touch, or
their centres pass through each other) and the fixed sign switches from one mode to the
other there: the joint's position is continuous but its velocity jumps (or, when the
centres pass through each other, the position jumps).  Following the branch continuously
means flipping the sign there, so that the motion goes on smoothly.

:func:`follow` decides it along a path given in order (a simulation calls it with its time
steps); :func:`along_sweep` builds the path of a sweep (from the pose's input up to the
largest input and down to the smallest, through every requested input and a fixed grid)
and calls it; :func:`limits` gives a sample exactly on a change point the branch's limit.
The work is vectorized over samples and designs and sequential only over the sign steps
(a step's candidates depend on the signs chosen before it).  Derivation:
``docs/method.md``, "Following a branch through change points".

Examples
--------
>>> import numpy as np, linkagekit as lk
>>> from linkagekit.api import prepare
>>> mech = lk.load("examples/seed003_ex22.yaml")  # a parallelogram, pose at 30 deg
>>> br = along_sweep(prepare(mech), np.radians([[[0.0, 90.0, 270.0, 400.0]]]), (True,))
>>> br.signs[0, 0].tolist()  # the pose's +1 until the flat position at 180 deg, then -1, +1 again after 360
[1.0, 1.0, -1.0, 1.0]
>>> [round(float(np.degrees(x)), 6) for x in br.points[2]]
[180.0, 360.0]
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from .errors import InputError
from .params import Params
from .positions import WALK_STEP, Positions, solve, take_samples
from .rates import Rates, solve_rates
from .steps import Pivot, Step, is_sign_step

#: at a meeting, a flip is taken only where the flipped sign's defect (:func:`_defect`) is below
#: this share of the kept one's
RHO = 0.125
#: the step's relative assembly margin must come within this of zero between the two samples (a real meeting);
#: a meeting is resolved to about the square root of rounding (1e-8), and worse after an earlier one
#: (a double rhombus's second dyad, placed from a joint found from coincident circles, gets to 1e-8)
CHANGE_TOL = 1e-6
#: golden-section iterations locating the meeting (the interval shrinks by 0.618 each: 1 degree to 1e-12 rad)
GOLDEN_ITERATIONS = 48
#: consecutive good samples further apart than this many grid steps are never bridged (a gap in the range)
MAX_GAP_STEPS = 3.0

#: the longest path one call follows (samples per design: about 550 turns at 1 degree)
MAX_PATH = 200_000
#: design-samples of path solved at once (bounds the working memory of a batch)
BLOCK = 1 << 18

#: the half-step ``e`` (radians of the path driver; for a length, this share of a radian's worth of its grid step) of
#: the symmetric combination that gives a branch's limit at a sample on a change point (:func:`limits`)
LIMIT_STEP = 1e-3
#: a sample takes the limit only where the one-sided extrapolations from either side agree to this (relative)
LIMIT_AGREE = 1e-3

__all__ = ["Branch", "PathTooLongError", "along_sweep", "follow", "limits"]


class PathTooLongError(InputError):
    """The inputs span more than :data:`MAX_PATH` steps of the path :func:`along_sweep` would follow."""


@dataclass(frozen=True)
class Branch:
    """Signs along a path, and the change points crossed.

    Attributes
    ----------
    signs : ndarray, shape (n_signs, D, n)
        +1/-1 per sign step, design and sample.
    points : list of (step, design, input) arrays
        The change points crossed: the index of the sign step (in ``plan.sign_joints``),
        the design, and the path driver's input there (solver units), sorted by input.
    driver : int
        The driver the path follows (the one that moves most).
    step : float
        The path's grid step in that driver's input (solver units; 0 when nothing moves).
    """

    signs: np.ndarray
    points: tuple[np.ndarray, np.ndarray, np.ndarray]
    driver: int = 0
    step: float = 0.0


def _state(step: Step, pos: object, rt: object, i: int) -> tuple[np.ndarray, np.ndarray]:
    """What sign step ``step`` places, (m, D, n) complex, and its rate: its joint, or (a pivot) its guide's rotation."""
    if isinstance(step, Pivot):
        rot = pos.rot[step.on]  # type: ignore[attr-defined]
        om = rt.omega[step.on]  # type: ignore[attr-defined]
        return rot[None], (1j * om * rot)[None]
    j = list(step.writes())
    return pos.z[j], rt.v[j]  # type: ignore[attr-defined]


def _previous_good(good: np.ndarray) -> np.ndarray:
    """For each sample, the index of the last good sample before it (-1: none), (D, n)."""
    n = good.shape[-1]
    idx = np.where(good, np.arange(n), -1)
    last = np.maximum.accumulate(idx, axis=-1)
    return np.concatenate([np.full((good.shape[0], 1), -1), last[:, :-1]], axis=-1)


def _defect(Xa: np.ndarray, Va: np.ndarray, Xb: np.ndarray, Vb: np.ndarray, dt: np.ndarray) -> np.ndarray:
    """How far the motion from ``a`` to ``b`` is from smooth: ``max |X_b - X_a - V_a dt| + max |V_b - V_a| |dt|``.

    ``O(dt^2)`` (times the acceleration) on a smooth motion; at least ``|jump of V| |dt|``
    across a kink anywhere between (and the jump itself where the position jumps).
    """
    d: np.ndarray = np.max(np.abs(Xb - Xa - Va * dt), axis=0) + np.max(np.abs(Vb - Va), axis=0) * np.abs(dt)
    return d


Candidate = tuple[np.ndarray, np.ndarray, np.ndarray]


def _candidates(
    params: Params, q: np.ndarray, S: np.ndarray, i: int, w_in: np.ndarray, continuous: bool
) -> list[Candidate]:
    """Step ``i``'s state with sign +1 and -1 at every sample (earlier steps as decided): [(X, V, margin)] * 2."""
    out = []
    for sigma in (1.0, -1.0):
        Si = S.copy()
        Si[i] = sigma
        pos = solve(params, q, Si, continuous=continuous)
        rt = solve_rates(params, pos, w_in, np.zeros_like(w_in))
        X, V = _state(params.plan.steps[-1], pos, rt, i)
        out.append((X, V, pos.margin[i]))
    return out


def _upto(params: Params, i: int) -> Params:
    """``params`` with the plan cut after sign step ``i``: what it places does not depend on the later steps.

    (A later step that does not assemble, or is singular, would make the whole sample NaN.)
    """
    k = [n for n, st in enumerate(params.plan.steps) if is_sign_step(st)][i]
    plan = replace(params.plan, steps=params.plan.steps[: k + 1])
    return replace(params, plan=plan, steps=params.steps[: k + 1])


def _smooth_flips(cands: list[Candidate], t: np.ndarray, max_gap: float) -> tuple[np.ndarray, np.ndarray]:
    """Where flipping the sign is the smooth continuation from the last good sample: (flip (D, n), prev (D, n)).

    Both ways must agree (from +1 the smooth next is -1, and from -1 it is +1, as where two
    branches cross), and the kept sign must have a real defect (not rounding).
    """
    (Xp, Vp, mg), (Xm, Vm, _) = cands
    good = (mg >= 0) & np.all(np.isfinite(Vp) & np.isfinite(Vm) & np.isfinite(Xp) & np.isfinite(Xm), axis=0)
    prev = _previous_good(good)
    a = np.maximum(prev, 0)

    def at(x: np.ndarray) -> np.ndarray:
        return np.take_along_axis(x, np.broadcast_to(a, x.shape), axis=-1)

    dt = t - np.take_along_axis(np.broadcast_to(t, a.shape), a, axis=-1)
    keep_p = _defect(at(Xp), at(Vp), Xp, Vp, dt)
    keep_m = _defect(at(Xm), at(Vm), Xm, Vm, dt)
    flip_p = _defect(at(Xp), at(Vp), Xm, Vm, dt)
    flip_m = _defect(at(Xm), at(Vm), Xp, Vp, dt)
    scale = np.max(np.abs(at(Vp)) + np.abs(Vp), axis=0) * np.abs(dt)
    real = np.minimum(keep_p, keep_m) > 1e-9 * scale
    flip = good & (prev >= 0) & (np.abs(dt) <= max_gap) & real
    flip &= (flip_p < keep_p) & (flip_m < keep_m)  # a candidate: the meeting itself decides (_meetings)
    return flip, prev


def _signs_between(
    S: np.ndarray, E: np.ndarray, d: np.ndarray, a: np.ndarray, b: np.ndarray, tt: np.ndarray
) -> np.ndarray:
    """The signs at path parameter ``tt`` between samples ``a`` and ``b`` of designs ``d``: (n_signs, C).

    A step whose last crossing (``E``, forward-filled) lies at or before ``tt`` has the sign of ``b``, else of ``a``.
    """
    return np.where(tt >= E[:, d, b], S[:, d, b], S[:, d, a])


@dataclass(frozen=True)
class _Between:
    """Step ``i`` between samples ``a`` and ``b`` of designs ``d`` (one column per candidate): solved anywhere there."""

    params: Params  # one design per candidate
    q: np.ndarray  # (n_drivers, D, n)
    S: np.ndarray  # (n_signs, D, n) the signs so far
    E: np.ndarray  # (n_signs, D, n) where each step's last flip was (path parameter, forward-filled)
    i: int
    d: np.ndarray
    a: np.ndarray
    b: np.ndarray
    ta: np.ndarray
    tb: np.ndarray
    continuous: bool

    def _solve(self, tt: np.ndarray, own: np.ndarray | None = None) -> tuple[Positions, np.ndarray]:
        """Positions at path parameter ``tt`` (step ``i`` with sign ``own``, default as at ``a``), and dq/dt."""
        span = np.where(self.tb > self.ta, self.tb - self.ta, 1.0)
        f = np.where(self.tb > self.ta, (tt - self.ta) / span, 0.0)
        qa, qb = self.q[:, self.d, self.a], self.q[:, self.d, self.b]
        sg = np.where(tt >= self.E[:, self.d, self.b], self.S[:, self.d, self.b], self.S[:, self.d, self.a])
        if own is not None:
            sg[self.i] = own
        pos = solve(self.params, ((1 - f) * qa + f * qb)[:, :, None], sg[:, :, None], continuous=self.continuous)
        return pos, ((qb - qa) / span)[:, :, None]

    def margin(self, tt: np.ndarray) -> np.ndarray:
        """Step ``i``'s relative assembly margin at ``tt`` (inf where an earlier step fails)."""
        m = self._solve(tt)[0].margin[self.i, :, 0]
        return np.where(np.isfinite(m), m, np.inf)

    def state(self, tt: np.ndarray, own: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Step ``i``'s points and their rates d/dt at ``tt``, (m, C) each."""
        pos, w = self._solve(tt, own)
        rt = solve_rates(self.params, pos, w, np.zeros_like(w))
        X, V = _state(self.params.plan.steps[-1], pos, rt, self.i)
        return X[..., 0], V[..., 0]


def _golden(f: Callable[[np.ndarray], np.ndarray], lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The minimum of ``f`` on ``[lo, hi]`` (each column its own interval) by golden section: (where, value)."""
    g = (np.sqrt(5.0) - 1) / 2
    lo, hi = lo.copy(), hi.copy()
    x1, x2 = hi - g * (hi - lo), lo + g * (hi - lo)
    f1, f2 = f(x1), f(x2)
    for _ in range(GOLDEN_ITERATIONS):
        left = f1 <= f2
        hi = np.where(left, x2, hi)
        lo = np.where(left, lo, x1)
        x2n = np.where(left, x1, lo + g * (hi - lo))
        x1n = np.where(left, hi - g * (hi - lo), x2)
        fnew = f(np.where(left, x1n, x2n))
        f1, f2 = np.where(left, fnew, f2), np.where(left, f1, fnew)
        x1, x2 = x1n, x2n
    return np.where(f1 <= f2, x1, x2), np.minimum(f1, f2)


def _meetings(btw: _Between, probe: float) -> tuple[np.ndarray, np.ndarray]:
    """Whether step ``i``'s sign flips between each candidate's samples, and where (path parameter).

    The step's assembly margin is minimised over ``[t_a, t_b]`` (golden section, then a
    parabola's vertex); the two modes meet where it comes within ``CHANGE_TOL`` of zero (a
    gap deeper than that, or a near miss, is no meeting).  At a meeting the sign flips when,
    ``probe`` before and after it, the flipped sign continues the motion smoothly and the kept
    one does not (the test of :func:`_defect`, now at the meeting itself, so
    that it does not depend on where the samples fall; ``probe`` may reach past the samples:
    the other steps keep their signs there, the step's own is given).
    """
    best, low = _golden(btw.margin, btw.ta, btw.tb)
    where = _vertex(btw.margin, best, low, 1e-3 * (btw.tb - btw.ta))
    h = np.full_like(where, probe)  # not cut to the samples: a sample 1e-4 deg from the meeting left h = 9e-7 rad,
    one = np.ones_like(where)  # where the rates have lost the digits that tell the two ways apart (the answer changed)
    before = [btw.state(where - h, sigma * one) for sigma in (1.0, -1.0)]
    after = [btw.state(where + h, sigma * one) for sigma in (1.0, -1.0)]
    smooth = np.ones(len(where), bool)
    for k in (0, 1):  # from either sign (the sign at a may already have flipped earlier along the path)
        keep = _defect(*before[k], *after[k], 2 * h)
        flip = _defect(*before[k], *after[1 - k], 2 * h)
        smooth &= np.isfinite(flip) & (flip < RHO * np.where(np.isfinite(keep), keep, np.inf))
    return (np.abs(low) <= CHANGE_TOL) & smooth, where


def _vertex(f: Callable[[np.ndarray], np.ndarray], x: np.ndarray, fx: np.ndarray, h: np.ndarray) -> np.ndarray:
    """The minimum of ``f`` near ``x`` refined by the parabola through ``x - h, x, x + h``.

    The margin is quadratic about a meeting, so its minimiser is found by golden section to
    only about the square root of rounding; the parabola's vertex from points ``h`` away,
    where the margin is well above rounding, is good to about ``h`` times its relative rounding.
    """
    lo, hi = f(x - h), f(x + h)
    curv = lo - 2 * fx + hi
    with np.errstate(divide="ignore", invalid="ignore"):
        shift = h * (lo - hi) / (2 * curv)
    ok = (curv > 0) & (np.abs(shift) <= np.abs(h))
    return np.where(ok, x + np.where(ok, shift, 0.0), x)


def follow(
    params: Params,
    q: np.ndarray,
    t: np.ndarray,
    start: np.ndarray | None = None,
    max_gap: float = np.inf,
    continuous: bool = True,
    probe: float = 1e-5,
) -> Branch:
    """The signs along a path given in order, each sign flipped where its step crosses a change point.

    Parameters
    ----------
    params : Params
    q : ndarray, shape (n_drivers, D or 1, n)
        The inputs along the path, in the order the mechanism goes through them (solver units).
    t : ndarray, shape (D or 1, n)
        The path parameter, non-decreasing (e.g. the input of the driver that moves, or time).
    start : ndarray, shape (n_signs, D), optional
        The signs at the first sample; default: each design's pose's.
    max_gap : float
        Two good samples further apart in ``t`` are not bridged (the motion cannot pass a gap).
    continuous : bool
        Numerical groups, too, follow their branch (:mod:`linkagekit.group`).
    probe : float
        How far before and after a meeting (in ``t``) the motion is compared on both signs.

    Returns
    -------
    Branch
        ``signs`` (n_signs, D, n); ``points`` the change points crossed, as path parameters.
    """
    plan = params.plan
    D, n = params.n_designs, q.shape[-1]
    S = np.empty((plan.n_signs, D, n))
    S[...] = (params.signs if start is None else np.asarray(start, float))[:, :, None]
    E = np.full(S.shape, -np.inf)
    t = np.broadcast_to(np.asarray(t, float), (D, n))
    q_all = np.broadcast_to(q, (q.shape[0], D, n))
    w_in = _path_rates(q, t)
    found: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
    for i in range(plan.n_signs):
        sub = _upto(params, i)
        cands = _candidates(sub, q, S, i, w_in, continuous)
        flip, prev = _smooth_flips(cands, t, max_gap)
        if flip.any():
            d, b = np.nonzero(flip)
            a = prev[d, b]
            btw = _Between(sub.take(d), q_all, S, E, i, d, a, b, t[d, a], t[d, b], continuous)
            real, where = _meetings(btw, probe)
            flip[d[~real], b[~real]] = False
            E[i, d[real], b[real]] = where[real]
            E[i] = np.maximum.accumulate(E[i], axis=-1)
            found.append((np.full(int(real.sum()), i), d[real], where[real]))
        S[i] = S[i, :, :1] * np.cumprod(np.where(flip, -1.0, 1.0), axis=-1)
    return Branch(S, _joined(found))


def _path_rates(q: np.ndarray, t: np.ndarray) -> np.ndarray:
    """dq/dt at each sample of a path (``q`` (n_drivers, D or 1, n), ``t`` (D, n)): the slope of the interval before
    it, or, where that interval has no length (the pose's input repeated where the path has not left it yet), of
    the nearest one before with a length, else after (0 on a path that does not move).

    A sample at the pose's input repeated took the rate 0, so from a pose 0.5 deg before a parallelogram's flat
    position the motion to the next sample looked like a jump on either mode and the branch folded into a kite."""
    dq = np.diff(np.broadcast_to(q, (q.shape[0], *t.shape)), axis=-1)
    dt = np.diff(t, axis=-1)
    moves = np.broadcast_to(np.concatenate([dt[:, :1] != 0, dt != 0], axis=-1), dq.shape[:1] + t.shape)
    with np.errstate(divide="ignore", invalid="ignore"):
        slope = np.where(dt != 0, dq / np.where(dt != 0, dt, 1.0), 0.0)
    slope = np.concatenate([slope[..., :1], slope], axis=-1)  # from the interval before (the first: its own)
    n = slope.shape[-1]
    before = np.maximum.accumulate(np.where(moves, np.arange(n), -1), axis=-1)
    after = np.minimum.accumulate(np.where(moves, np.arange(n), n)[..., ::-1], axis=-1)[..., ::-1]
    pick = np.where(before >= 0, before, np.minimum(after, n - 1))
    rates: np.ndarray = np.take_along_axis(slope, pick, axis=-1)
    return np.where((before >= 0) | (after < n), rates, 0.0)


def _joined(found: list[tuple[np.ndarray, np.ndarray, np.ndarray]]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Lists of (steps, designs, inputs) arrays joined into three arrays."""
    if not found:
        return np.zeros(0, int), np.zeros(0, int), np.zeros(0)
    s, d, x = (np.concatenate(z) for z in zip(*found, strict=True))
    return s, d, x


def along_sweep(
    params: Params,
    q: np.ndarray,
    angular: tuple[bool, ...],
    continuous: bool = True,
    driver: int | None = None,
    step: float | None = None,
) -> Branch:
    """The signs at requested inputs ``q`` (n_drivers, D or 1, n), following the branch from each design's pose.

    The path runs along the driver that moves most, from the pose's input (its value as read
    off the pose, unwrapped: an angle of 400 deg is a turn and 40 deg further than 0) up to
    the largest requested input and down to the smallest, through every requested input and
    the multiples of ``WALK_STEP`` (of 1/360 of the span for a length) in between, so the
    signs at an input do not depend on which other inputs are asked.  The other drivers
    move along it as they do between the requested samples.  ``points`` are in the path
    driver's input.  ``driver`` and ``step`` fix the path's driver and grid step (as an
    earlier call's ``Branch.driver``, ``Branch.step``: then the signs agree with that call's
    at any input).  Designs go through in blocks of about ``BLOCK`` design-samples of path;
    a path longer than ``MAX_PATH`` samples is refused.
    """
    D, n = params.n_designs, q.shape[-1]
    x0 = params.pose_inputs  # (n_drivers, D)
    span = np.ptp(np.concatenate([q.reshape(q.shape[0], -1), x0], axis=1), axis=1)
    d = int(np.argmax(span)) if driver is None else driver
    if step is None:
        step = WALK_STEP if d < len(angular) and angular[d] else float(span[d]) / 360.0
    if span[d] == 0 or params.plan.n_signs == 0 or step == 0:
        return Branch(np.repeat(params.signs[:, :, None], n, axis=2), _joined([]), d, step)
    x = q[d, 0]
    lo, hi = min(x.min(), x0[d].min()), max(x.max(), x0[d].max())
    if (hi - lo) / step > MAX_PATH:
        raise PathTooLongError(
            f"branch 'continuous': the inputs and the pose's input span {(hi - lo) / step:.0f} steps of the path "
            f"it follows, more than linkagekit.branch.MAX_PATH ({MAX_PATH}); ask for a smaller span"
        )
    grid = np.arange(np.floor(lo / step), np.ceil(hi / step) + 1) * step
    u = np.unique(np.concatenate([x, grid[(grid > lo) & (grid < hi)]]))
    per = max(1, BLOCK // (2 * len(u) + 2))
    parts = []
    for start in range(0, D, per):  # blocks of designs: the path is longer than the samples asked
        sl = slice(start, min(start + per, D))
        parts.append(_along(params.take(sl), q[:, sl] if q.shape[1] > 1 else q, d, u, step, continuous))
    signs = np.concatenate([p.signs for p in parts], axis=1)
    found = [(p.points[0], p.points[1] + k * per, p.points[2]) for k, p in enumerate(parts)]
    return Branch(signs, _joined(found), d, step)


def _along(params: Params, q: np.ndarray, d: int, u: np.ndarray, step: float, continuous: bool) -> Branch:
    """:func:`along_sweep` for one block of designs, the path's values ``u`` (ascending) given."""
    D, n = params.n_designs, q.shape[-1]
    x0 = params.pose_inputs
    x = q[d, 0]
    srt = np.argsort(x, kind="stable")
    signs = np.empty((params.plan.n_signs, D, n))
    points: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
    for way in (1.0, -1.0):
        uu = u if way > 0 else u[::-1]
        tpath = np.concatenate([x0[d][:, None], np.where(way * uu >= way * x0[d][:, None], uu, x0[d][:, None])], axis=1)
        qp = np.empty((q.shape[0], D, len(uu) + 1))
        for k in range(q.shape[0]):  # the other drivers: held, or moved as between the requested samples
            held = np.ptp(q[k], axis=-1).max() == 0
            qp[k] = q[k][:, :1] if held else np.interp(tpath, x[srt], q[k, 0][srt])
            qp[k][:, 0] = x0[k]
        qp[d] = tpath
        br = follow(params, qp, way * tpath, max_gap=MAX_GAP_STEPS * step, continuous=continuous, probe=1e-3 * step)
        pos = 1 + np.searchsorted(u, x) if way > 0 else len(u) - np.searchsorted(u, x)
        mine = (way * x[None, :] >= way * x0[d][:, None]) if way > 0 else (x[None, :] < x0[d][:, None])
        signs[...] = np.where(mine[None], br.signs[:, :, pos], signs)
        s, dd, where = br.points
        points.append((s, dd, way * where))
    s, dd, where = _joined(points)
    order = np.lexsort((s, where, dd))
    return Branch(signs, (s[order], dd[order], where[order]), d)


def _columns(a: np.ndarray, cols: np.ndarray) -> np.ndarray:
    """An array over (..., samples) taken at ``cols``, each four times (the sides of :func:`limits`); as is when it
    has one column."""
    if np.shape(a)[-1] == 1:
        return a
    return np.repeat(np.asarray(a)[..., cols], 4, axis=-1)


def _sides(f: np.ndarray) -> tuple[np.ndarray, ...]:
    """The values at ``u - 2e, u - e, u + e, u + 2e`` of an array over (..., D, 4K): four arrays (..., D, K)."""
    g = f.reshape(*f.shape[:-1], -1, 4)
    return tuple(g[..., k] for k in range(4))


def _limit(f: np.ndarray) -> np.ndarray:
    """The symmetric fourth-order combination ``A1 + (A1 - A2) / 3`` (``A_k`` the mean of ``f(u +- k e)``): ``f(u)``.

    With ``f(u +- e)`` the branch's own values (signs followed on each side), the odd terms
    cancel and ``A_k = f + (k e)^2 f''/2 + (k e)^4 f''''/24 + ...``, so the combination is
    ``f(u) - e^4 f''''(u)/6 + O(e^6)``; a constant comes back exactly.
    """
    f0, f1, f2, f3 = _sides(f)
    a1: np.ndarray = (f1 + f2) / 2
    a2: np.ndarray = (f0 + f3) / 2
    out: np.ndarray = a1 + (a1 - a2) / 3
    return out


def _one_sided_gap(f: np.ndarray) -> np.ndarray:
    """``|(2 f(u - e) - f(u - 2e)) - (2 f(u + e) - f(u + 2e))|``, largest over the first axis: the left and right
    linear extrapolations to ``u`` differ by ``O(e^2)`` on a smooth branch, by the jump across a kink or a jump."""
    f0, f1, f2, f3 = _sides(f)
    gap: np.ndarray = np.max(np.abs((2 * f1 - f0) - (2 * f2 - f3)), axis=0)
    return gap


def _patched(value: Any, side: Any, take: np.ndarray, cols: np.ndarray, shape: tuple[int, int]) -> Any:
    """``value`` (a scalar or an array over (D, n)) with its limit from ``side`` (over (D, 4K)) where ``take``.

    A ``side`` that is one value for every sample (the ground's 0, a driver link's own speed, over (D or 1, 1)) is its
    own limit: left as the value was, a driver's omega was null at a lone sample on a change point and 5.0 when another
    sample was asked beside it (a review)."""
    if side is None:  # the sides do not have it
        return value
    side = np.asarray(side)
    if side.ndim and side.shape[-1] not in (1, 4 * len(cols)):
        return value
    full = np.array(np.broadcast_to(value, shape), dtype=np.result_type(value, side))
    lim = np.broadcast_to(side if side.ndim == 0 or side.shape[-1] == 1 else _limit(side), (shape[0], len(cols)))
    d, k = np.nonzero(take)
    full[d, cols[k]] = lim[d, k]
    return full


def _side_solves(
    params: Params,
    q: np.ndarray,
    qs: np.ndarray,
    mirrors: np.ndarray | None,
    br: Branch,
    angular: tuple[bool, ...],
    cols: np.ndarray,
) -> Positions:
    """Positions at the side inputs ``qs`` (the signs followed on ``br``'s path), solved together with the samples
    ``q`` themselves: a numerical group then walks the same grid as for the samples (its walk is fixed by the
    inputs it is given), so the sides lie on the branch the samples do."""
    n = q.shape[-1]
    qb = np.broadcast_to(q, (q.shape[0], qs.shape[1], n))
    both = np.concatenate([qb, qs], axis=-1)
    signs = np.concatenate([br.signs, along_sweep(params, qs, angular, driver=br.driver, step=br.step).signs], axis=-1)
    mr = None if mirrors is None else _columns(mirrors, cols)
    if mirrors is not None and np.shape(mirrors)[-1] > 1:
        mr = np.concatenate([mirrors, _columns(mirrors, cols)], axis=-1)
    full = solve(params, both, signs, mr, continuous=True)
    side = take_samples(full, np.arange(n, both.shape[-1]))
    if params.plan.numerical:  # Newton near a change point may land on either root: the walk alone must agree
        alone = solve(params, qs, signs[..., n:], None if mirrors is None else _columns(mirrors, cols), continuous=True)
        size = np.max(np.abs(side.z - np.mean(side.z, axis=0)), axis=0)
        with np.errstate(invalid="ignore"):
            same = np.max(np.abs(alone.z - side.z), axis=0) <= LIMIT_AGREE * size
        side = replace(side, assembled=side.assembled & same)
    return side


def _candidates_at(pos: Positions, singular: np.ndarray) -> np.ndarray:
    """The samples that may lie on a change point, (D, n): singular ones, and those that do not assemble where no
    sign step fails by more than ``CHANGE_TOL`` (coincident circles: a rhombus's crank over its ground pivot).

    A gap (a step's margin well below zero) and a numerical group's sample out of its range are left alone (they
    are not change points, and a group's sample out of range is costly)."""
    flat: np.ndarray = singular & pos.assembled
    if pos.margin.shape[0] == 0:
        return flat
    with np.errstate(invalid="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN samples: every step after a failed one
        worst = np.nanmin(pos.margin, axis=0)
    out: np.ndarray = flat | (~pos.assembled & ~(worst < -CHANGE_TOL))
    return out


def limits(
    params: Params,
    q: np.ndarray,
    rates: tuple[np.ndarray, np.ndarray],
    mirrors: np.ndarray | None,
    br: Branch,
    angular: tuple[bool, ...],
    pos: Positions,
    rt: Rates | None,
) -> tuple[Positions, Rates | None]:
    """Samples exactly at a change point given the followed branch's limit there: positions and rates.

    Where a sample along the continuous branch is singular or does not assemble (the dyad's
    circles touch, or coincide as over a rhombus's ground pivot), the branch itself goes on
    smoothly through it; its value there is taken as ``A1 + (A1 - A2) / 3`` of solves at
    ``u +- e`` and ``u +- 2e`` (``A_k`` the mean of the pair ``k``; ``e = LIMIT_STEP``, the signs
    followed on each side by :func:`along_sweep` on ``br``'s path), whose error is
    ``e^4 |f''''| / 6`` plus the solves' rounding ``~ eps / e``: both about 1e-13 of the size at
    ``e = 1e-3`` (``docs/method.md``).  It is taken only where all four solves assemble and
    are regular, and the left and right linear extrapolations agree to ``LIMIT_AGREE`` (of the
    size for positions, of the largest speed for velocities at unit input speed): the branch
    is smooth there (a lock, a gap or a kink keep the sample as solved).  Such a sample is
    ``singular`` (one that did not assemble, as over a rhombus's ground pivot, becomes so); ``Rates.limit`` marks the
    samples whose rates are such limits.  Every other sample
    is untouched.  ``rates`` are the drivers' speeds and accelerations (n_drivers, 1, n or 1).
    """
    w_in, a_in = rates
    sing = rt.singular if rt is not None else solve_rates(params, pos, w_in, a_in).singular
    cand = _candidates_at(pos, sing)
    if not cand.any() or br.step == 0:
        return pos, rt
    cols = np.flatnonzero(cand.any(axis=0))
    e = LIMIT_STEP * br.step / WALK_STEP
    qs = np.repeat(q[..., cols], 4, axis=-1)
    qs[br.driver] += np.tile(np.array([-2.0, -1.0, 1.0, 2.0]) * e, len(cols))
    ps = _side_solves(params, q, qs, mirrors, br, angular, cols)
    unit = np.zeros((q.shape[0], 1, 1))
    unit[br.driver] = 1.0
    smooth = solve_rates(params, ps, unit, np.zeros_like(unit))  # dz/du: the test of smoothness
    good = np.logical_and.reduce(_sides(ps.assembled & ~smooth.singular))
    size = np.max(np.abs(ps.z - np.mean(ps.z, axis=0)), axis=0)
    speed = np.max(np.abs(smooth.v), axis=0)
    with np.errstate(invalid="ignore"):
        ok = good & (_one_sided_gap(ps.z) <= LIMIT_AGREE * _sides(size)[1])
        ok &= _one_sided_gap(smooth.v) <= LIMIT_AGREE * _sides(speed)[1]
    take = cand[:, cols] & ok
    if not take.any():
        return pos, rt
    return _take_limits(pos, rt, ps, params, rates, take, cols)


def _take_limits(
    pos: Positions,
    rt: Rates | None,
    ps: Positions,
    params: Params,
    rates: tuple[np.ndarray, np.ndarray],
    take: np.ndarray,
    cols: np.ndarray,
) -> tuple[Positions, Rates | None]:
    """``pos`` and ``rt`` with the limits of the side solves ``ps`` at the samples ``take`` (D, K) of ``cols``."""
    d, k = np.nonzero(take)
    shape = pos.assembled.shape
    pos.z[:, d, cols[k]] = _limit(ps.z)[:, d, k]
    assembled = pos.assembled.copy()
    assembled[d, cols[k]] = True
    rot = {name: _patched(v, ps.rot.get(name), take, cols, shape) for name, v in pos.rot.items()}
    new_pos = replace(pos, assembled=assembled, rot=rot)
    if rt is None:
        return new_pos, None
    side = solve_rates(params, ps, _columns(rates[0], cols), _columns(rates[1], cols))
    rt.v[:, d, cols[k]] = _limit(side.v)[:, d, k]
    rt.a[:, d, cols[k]] = _limit(side.a)[:, d, k]
    omega = {name: _patched(v, side.omega.get(name), take, cols, shape) for name, v in rt.omega.items()}
    alpha = {name: _patched(v, side.alpha.get(name), take, cols, shape) for name, v in rt.alpha.items()}
    limit = np.zeros(shape, bool)
    limit[d, cols[k]] = True
    singular = rt.singular | limit  # (one that did not assemble, coincident circles, is singular there too)
    return new_pos, replace(rt, omega=omega, alpha=alpha, limit=limit, singular=singular)
