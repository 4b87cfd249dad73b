"""Every assembly mode of a numerical group, and assembly ranges by continuation.

A numerical group (:class:`linkagekit.group.Group`) is solved by Newton continued from
the reference pose, so the solver only ever sees the pose's mode.  This module finds all
the others at one input, and the range of inputs over which the pose's mode goes on.

Every mode of a group at one input
----------------------------------
The group is reduced to one unknown angle.  One binary link of the group is *cut* (its
distance constraint removed) and another binary link that holds a known joint is
*driven* about that joint by an angle ``theta``.  The rest is then triangulable: the
remaining links form an ordinary one-freedom mechanism whose ground is the group's known
joints, and the closed-form planner (:func:`linkagekit.plan.make_plan`) solves it for
every ``theta`` and every sign combination (its *branches*).  A configuration of the
group is a mode exactly when the cut link closes::

    f(theta) = |z_a - z_b| - L_cut = 0

on some branch.  Conversely every mode of the group gives one ``theta`` (the driven link's
angle there) and one branch (the signs read off it), so the modes are the roots of ``f``
over all branches and ``theta`` in [0, 2 pi).

The roots are found on a grid of :data:`N_THETA` angles (0.05 degree), all branches and all
known-joint configurations in one vectorized solve:

1. where a branch stops assembling between two grid angles (a circle-circle step of the
   cut mechanism goes flat), the last assembled angle is found by bisection and added to
   the branch's samples: there the branch joins the branch of the opposite sign with the
   same value of ``f``, so a root near the end of a branch is bracketed on one of them;
2. every sign change of ``f`` between neighbouring samples of a branch is refined by
   bisection (60 halvings: to ~1e-16 rad);
3. every local minimum of ``|f|`` without a sign change on either side (two roots in one
   cell, or a double root) is refined by a golden-section search over its two cells; a
   minimum that crosses zero gives two brackets refined as in 2, one that touches zero
   (``|f| <= TOUCH_TOL L_cut``) is a double root;
4. each root's configuration is checked against the group's full constraints (distance and
   rigidity residuals of :meth:`Group.residual` below :data:`VERIFY_TOL`, relative), polished
   by the group's Newton, and roots closer than :data:`DEDUPE_RTOL` of the group's size are
   one mode (a root on a flat triangle is found on both of its branches).

**Completeness.** ``f`` is continuous along each branch and across the joins of step 1, so
by the intermediate value theorem every grid cell over which ``f`` changes sign holds a
root, and step 2 finds one.  A cell holding two roots (or a double root) has no sign
change, but then ``|f|`` has an interior minimum next to a sampled local minimum, which
step 3 refines.  So every real mode is found **provided no cell of 0.05 degree of the driven
link's angle holds more than two roots of one branch**, counting multiplicity (and no
branch stops and restarts assembling inside one cell).  Modes missed would be within
0.05 degree of ``theta`` of each other, i.e. nearly coincident configurations; the tests
compare the result with an independent dense search on random triads and with a triad of
six modes known by its sextic.

**Groups with sliders.** The group's sliders come into the cut mechanism with their sides
(a block of one joint on a line becomes a circle-line step there, a block of two joints is
carried with its guide), and links that are sides of a slider are neither cut nor driven. The
argument above is unchanged: the cut mechanism's branches are continuous in ``theta`` and a
mode of the group is a root of ``f`` on one of them, so the same guarantee holds. A group
whose line is carried by a link placed before it cannot be cut so (that link would share two
joints with the cut mechanism's ground), nor can a group with no two binary links that are
no slider's sides: it is listed in its continued mode only, with a note.

The modes of the whole mechanism combine these with the closed-form sign combinations:
the steps before a group give its known joints for each combination, the group's modes
are enumerated for each distinct set of known joints, and the solve goes on downstream
with the group started at each mode (:func:`enumerate_modes`).

Assembly range by continuation
------------------------------
:func:`continuation_intervals` walks the solver itself from the pose's input both ways
on a grid (each solve restarted from the last solved state, :func:`restarted`) until the
mechanism stops assembling (or a joint jumps by more than :data:`JUMP_RTOL` of the size
in one step: another branch): the mode of a group is defined by continuation, so beyond
that end the pose's mode does not exist (another mode may; :func:`enumerate_modes` lists
them).  Each end is refined by bisection on the input between the last assembled and the
first not-assembled value, every point re-solved through the solver from the last
assembled state, to :data:`RANGE_TOL` (:func:`_refine_end`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from functools import lru_cache
from typing import Any, Literal, NamedTuple

import numpy as np

from .errors import LinkageError
from .geometry import FloatArray
from .group import Group
from .model import FORMAT, Mechanism
from .params import Params, all_sign_combinations, compile
from .plan import Plan, make_plan
from .positions import solve
from .steps import Ground, Nums

#: grid of the driven link's angle (per turn) on which the closure function is sampled
N_THETA = 7200
#: halvings of a bisection (sign changes, ends of branches): ~1e-16 rad from a grid cell
N_BISECT = 60
#: golden-section steps for a local minimum of |f|
N_GOLDEN = 60
#: a root's configuration must meet every constraint of the group to this (relative)
VERIFY_TOL = 1e-9
#: a local minimum of |f| at most this times the cut length is a double root
TOUCH_TOL = 1e-11
#: two roots closer than this times the group's size are one mode
DEDUPE_RTOL = 1e-7
#: columns per solve (bounds the working memory)
CHUNK = 1 << 16
#: a step of the walk that moves a joint by more than this times the size is a jump to another branch
#: (near an end a joint moves like the square root of the input's step: ~0.01 of the size per grid step)
JUMP_RTOL = 0.1
#: an assembly range's ends are refined until the bracket is this narrow (rad; times the span for a length)
RANGE_TOL = 1e-9
#: a walk a turn round closes the mode where it comes back within this share of the mechanism's size of where it
#: started (the same configuration: the solver's answers at one direction agree to about 1e-10 of it)
CLOSES = 1e-6
#: a mode that does not close after a turn is walked on, up to this many turns in all, to the fold where it ends
TURNS = 2


# ---------------------------------------------------------------------- restarting the solver
def restarted(params: Params, z: np.ndarray, q: np.ndarray) -> Params:
    """One design's parameters as ``D`` designs whose numerical groups start from given states.

    Parameters
    ----------
    params : Params
        The parameters of one design.
    z : ndarray, complex, shape (n_joints, D)
        An assembled state per design (positions of every joint); each group's Newton starts
        from it (:meth:`Group.place` walks from its ``zu``/``zk`` numbers).
    q : ndarray, shape (n_drivers, D)
        The driver values of each state (where the walk starts).

    Returns
    -------
    Params
        Every design with the numbers of ``params``; solving at an input next to ``q``
        continues from ``z``.  The sign steps keep the reference signs.
    """
    D = z.shape[1]
    steps = list(params.steps)
    for i, st in enumerate(params.plan.steps):
        if isinstance(st, Group):
            steps[i] = _group_start(steps[i], z[list(st.joints)], z[list(st.known)])
    return replace(
        params,
        steps=tuple(steps),
        pose_inputs=np.asarray(q, float),
        signs=np.repeat(params.signs[:, :1], D, axis=1),
        valid=np.ones(D, bool),
        pose=z,
    )


def _group_start(nums: Nums, zu: np.ndarray, zk: np.ndarray) -> Nums:
    """A group's numbers with the start of its walk replaced (``Group.numbers``: lengths, rhos, bases, zu, zk,
    strokes)."""
    return (*nums[:3], np.asarray(zu, complex)[:, :, None], np.asarray(zk, complex)[:, :, None], *nums[5:])


def _driver_inputs(params: Params, driver: int, x: np.ndarray) -> np.ndarray:
    """Driver values (n_drivers, len(x)): ``x`` for one driver, the pose's for the others."""
    q = np.repeat(params.pose_inputs[:, :1], len(x), axis=1)
    q[driver] = x
    return q


# ---------------------------------------------------------------------- assembly range by continuation
def continuation_intervals(
    params: Params, driver: int, lo: float, hi: float, cyclic: bool, n: int = N_THETA
) -> list[list[float]]:
    """Where the pose's mode of a mechanism with numerical groups goes on, for one driver.

    The solver is walked from the pose's input up and down on a grid of ``n`` steps per
    ``hi - lo``, every solve started from the last state solved, until it stops assembling
    (or a full turn, or the end of the span); each end is then refined by bisection through
    the solver (:func:`restarted`) to :data:`RANGE_TOL`.

    Parameters
    ----------
    params : Params
        One design.
    driver : int
        The driver that moves; the others stay at their pose values.
    lo, hi : float
        The span searched (radians for an angle, ``[0, 2 pi)``; length units otherwise).
    cyclic : bool
        An angle: the walk may go round (at most one turn) and intervals follow the
        convention of :func:`linkagekit.checks.input_range`.

    Returns
    -------
    list of [start, stop]
        At most one interval (the pose's), the last assembled value at each end; ``[[lo,
        hi]]`` when the mode goes on over a full turn (or the whole span). A mode longer
        than a turn that does not close is given from its start to its end as walked from
        the pose's input (read off the pose), which it holds: in that frame alone the
        directions ``analyze`` answers with each of their two configurations are told
        (:func:`linkagekit.checks.direction_jumps`).
    """
    x0 = float(params.pose_inputs[driver, 0])
    start = solve(params, _driver_inputs(params, driver, np.array([x0]))[:, None, :])
    if not start.assembled[0, 0]:
        return []
    z0 = start.z[:, 0, 0]
    step = (hi - lo) / n
    period = hi - lo
    up = _leg(params, driver, z0, x0, step, period) if cyclic else _walk(params, driver, z0, x0, step, hi)
    if up is None and cyclic:
        return [[lo, hi]]
    down = _leg(params, driver, z0, x0, -step, period) if cyclic else _walk(params, driver, z0, x0, -step, lo)
    if down is None and cyclic:
        return [[lo, hi]]
    brackets = [w for w in (up, down) if w is not None]
    ends = np.zeros(0)
    if brackets:
        tol = RANGE_TOL if cyclic else RANGE_TOL * period
        ends = _refine_end(params, driver, tol, *(np.array([w[k] for w in brackets]) for k in range(6)))
    e = float(ends[0]) if up is not None else hi
    s = float(ends[-1]) if down is not None else lo
    if cyclic and e - s <= period:  # (a mode longer than a turn is given as walked: it holds the pose's input)
        k = math.floor((s - lo) / period)
        s, e = s - k * period, e - k * period
        if e > hi:  # runs through the turn's start: [start - period, stop]
            s, e = s - period, e - period
    return [[float(s), float(e)]]


def _leg(
    params: Params, driver: int, z0: np.ndarray, x0: float, step: float, period: float
) -> tuple[np.ndarray, float, float, float, float, float] | None:
    """An angle's walk one way from the pose (:func:`_walk`): None where the mode turns fully, else the bracket of its
    end. A turn that comes back to the pose's configuration closes the mode; one that comes back elsewhere does not
    (a mode longer than a turn reaches some directions twice, in two configurations): the walk goes on, up to
    ``TURNS`` turns in all, to the fold where it ends, or not (it turns fully, closing after more turns)."""
    reached: list[np.ndarray] = []
    end = _walk(params, driver, z0, x0, step, x0 + np.sign(step) * period, reached)
    if end is not None or np.max(np.abs(reached[0] - z0)) <= CLOSES * _size(params):
        return end
    far = x0 + np.sign(step) * TURNS * period
    return _walk(params, driver, reached[0], x0 + np.sign(step) * period, step, far)


def _walk(
    params: Params,
    driver: int,
    z0: np.ndarray,
    x0: float,
    step: float,
    limit: float,
    reached: list[np.ndarray] | None = None,
) -> tuple[np.ndarray, float, float, float, float, float] | None:
    """Walk the solver from (z0, x0) in steps of ``step`` towards ``limit``.

    Returns None when it gets there (its state there appended to ``reached``), else the bracket of its end: the last
    assembled state,
    its input, the first input that does not assemble, and the sample before the last with
    the :func:`_indicator` of both (for :func:`_refine_end`).  Solves come in chunks (each a
    sweep of the solver, sample after sample, restarted from the last state); a chunk grows
    while it assembles and shrinks to one sample where the indicator (about linear in the
    input near an end) predicts the end within the next chunk, as a sample past the end
    costs the solver its failed retries.
    """
    z, x = z0, x0
    size = 4
    g = math.inf
    x_prev, g_prev = x0, math.inf
    while True:
        xs = x + step * np.arange(1, size + 1)
        past = (xs - limit) * np.sign(step) >= 0
        if past.any():
            xs = np.append(xs[~past], limit)
        p = restarted(params, z[:, None], _driver_inputs(params, driver, np.array([x])))
        sol = solve(p, _driver_inputs(params, driver, xs)[:, None, :])
        zs = sol.z[:, 0]
        moved = np.abs(zs - np.concatenate([z[:, None], zs[:, :-1]], axis=1))
        bad = np.flatnonzero(~sol.assembled[0] | (np.max(moved, axis=0, initial=0.0) > JUMP_RTOL * _size(params)))
        good = int(bad[0]) if len(bad) else len(xs)
        ind = _indicator(params, sol.margin, sol.z)[0]
        if good:
            x_prev, g_prev = (float(xs[good - 2]), float(ind[good - 2])) if good >= 2 else (x, g)
            z, x_new, g_new = sol.z[:, 0, good - 1], float(xs[good - 1]), float(ind[good - 1])
        else:
            x_new, g_new = x, g
        if len(bad):
            return z, x_new, float(xs[good]), x_prev, g_prev, g_new
        if past.any():
            if reached is not None:
                reached.append(z)
            return None
        if np.isfinite(g_new) and g_new < g_prev:  # steps to where the indicator reaches 0
            left = g_new * abs(x_new - x_prev) / (g_prev - g_new) / abs(step)
            size = int(min(64, max(1, left / 2)))
        else:
            size = min(64, 2 * size)
        x, g = x_new, g_new


def _size(params: Params) -> float:
    """The size of the mechanism's pose (its largest distance from the pose's centre)."""
    pose = params.pose[:, 0]
    return float(np.max(np.abs(pose - pose.mean()), initial=0.0)) or 1.0


def _indicator(params: Params, margin: np.ndarray, z: np.ndarray) -> np.ndarray:
    """How far from an end of assembly each solved sample is, (D, n): about linear in the input near one.

    The smallest of the sign steps' margins (relative distances from a flat triangle) and
    of each group's conditioning squared (its smallest singular value goes like the square
    root of the distance to a fold) and of its cylinders' stroke margins (relative distances of
    their lengths from the stroke's ends, as the closed-form cylinder steps' margins); NaN where
    it does not assemble.
    """
    D, n = z.shape[1:]
    vals = [np.min(margin, axis=0)] if margin.shape[0] else []
    flat = z.reshape(len(z), D * n)
    for st, nums in zip(params.plan.steps, params.steps, strict=True):
        if isinstance(st, Group):
            vals.append((group_condition(st, nums, flat) ** 2).reshape(D, n))
            vals += list(st.stroke_margins(z, nums))
    out = np.min(vals, axis=0) if vals else np.full((D, n), np.inf)
    return np.where(np.all(np.isfinite(z), axis=0), out, np.nan)


def group_condition(st: Group, nums: Nums, z: np.ndarray) -> np.ndarray:
    """Smallest over largest singular value of the group's Jacobian, per column of ``z`` (n_joints, n).

    Its distance rows are divided by ``2 L`` so that every row has unit scale (as the
    conditioning the rates report).
    """
    m = len(st.joints)
    P = np.concatenate([z[list(st.joints)], st.held(z)])
    dn = st._design_nums(nums, np.zeros(z.shape[1], int))
    J = st.jacobian(P, dn, m + st.n_held)[:, :, : 2 * m]
    scale = st.row_scale(dn, J.shape[0])
    J = np.where(np.isfinite(J), J * scale[:, :, None], 0.0)
    s = np.linalg.svd(J, compute_uv=False)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(s[:, 0] > 0, s[:, -1] / s[:, 0], 0.0)


def _refine_end(
    params: Params,
    driver: int,
    tol: float,
    z: np.ndarray,
    a: np.ndarray,
    b: np.ndarray,
    a_prev: np.ndarray,
    g_prev: np.ndarray,
    g: np.ndarray,
) -> np.ndarray:
    """The end of assembly between inputs ``a`` (assembled, states ``z`` (E, n_joints)) and ``b`` (not).

    A bisection on the input, each midpoint solved through the solver restarted from the
    last assembled state (so the walk to it is one short step of the pose's branch), kept
    as the new ``a`` when it assembles (and does not jump, :data:`JUMP_RTOL`) and as ``b``
    when not; returns the last assembled input of each bracket once ``|b - a| <= tol``.
    A sample past the end costs the solver all its retries, so
    the points tried are placed by the :func:`_indicator` ``g`` (about linear in the input
    near the end, zero there) where it can: its secant through the last two assembled
    points predicts the end, and the two points tried (one solve for all brackets) straddle
    the prediction by twice its last correction; a prediction outside the bracket falls
    back to the midpoint.  Every step keeps a bracket of the end, so it converges as the
    bisection does, and usually in a few steps.
    """
    a, b, a_prev, g_prev, g = (np.asarray(v, float).copy() for v in (a, b, a_prev, g_prev, g))
    z = np.asarray(z).T.copy()  # (n_joints, E)
    E = len(a)
    est_prev = np.full(E, np.nan)
    for _ in range(N_BISECT):
        if np.all(np.abs(b - a) <= tol):
            break
        w = b - a
        u1, u2, est, valid = _trials(a, w, a_prev, g_prev, g, est_prev, tol)
        x = np.concatenate([a + u1 * w, a + u2 * w])
        rep = np.concatenate([np.arange(E), np.arange(E)])
        p = restarted(params, z[:, rep], _driver_inputs(params, driver, a[rep]))
        sol = solve(p, _driver_inputs(params, driver, x)[:, :, None])
        jump = np.max(np.abs(sol.z[:, :, 0] - z[:, rep]), axis=0, initial=0.0) > JUMP_RTOL * _size(params)
        ok = sol.assembled[:, 0] & ~jump
        ind = _indicator(p, sol.margin, sol.z)[:, 0]
        zs = sol.z[:, :, 0]
        ok1, ok2 = ok[:E], ok[E:]
        for k, okk in ((slice(0, E), ok1), (slice(E, 2 * E), ok2 & ok1)):  # the nearer first
            xs, gs = x[k], ind[k]
            a_prev = np.where(okk, a, a_prev)
            g_prev = np.where(okk, g, g_prev)
            z = np.where(okk[None, :], zs[:, k], z)
            a, g = np.where(okk, xs, a), np.where(okk, gs, g)
        b = np.where(~ok1, x[:E], np.where(~ok2, x[E:], b))
        est_prev = np.where(valid, est, np.nan)
    return a


def _trials(
    a: np.ndarray,
    w: np.ndarray,
    a_prev: np.ndarray,
    g_prev: np.ndarray,
    g: np.ndarray,
    est_prev: np.ndarray,
    tol: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The two points to try in each bracket ``[a, a + w]``, as fractions of it: ``(u1, u2, est, valid)``.

    ``est`` is the secant prediction of the end from the indicator ``g`` at ``a`` and ``g_prev``
    at ``a_prev``; where it is ``valid`` (inside the bracket, the indicator falling to zero) the
    points straddle it by twice its last correction (``est - est_prev``), else both are the midpoint.
    """
    with np.errstate(invalid="ignore", divide="ignore"):
        est = a + g * (a - a_prev) / (g_prev - g)
        u = (est - a) / w
        spread = np.where(np.isfinite(est_prev), 2 * np.abs(est - est_prev) / np.abs(w), 0.25)
        spread = np.maximum(spread, 0.5 * tol / np.maximum(np.abs(w), 1e-300))  # (NaN where the bracket is not)
        valid = np.isfinite(u) & (u > 0) & (u < 1) & (g_prev > g) & (g > 0)
        u1 = np.where(valid, u - spread, 0.5)
        u2 = np.where(valid, u + spread, 0.5)
    u1 = np.where(u1 <= 0, 0.5 * np.where(valid, u, 1.0), u1)
    u2 = np.where(u2 >= 1, 0.5 * (1 + np.where(valid, u, 0.0)), u2)
    return u1, u2, est, valid


# ---------------------------------------------------------------------- one group cut to one freedom
@dataclass(frozen=True)
class Reduction:
    """A numerical group cut to one freedom: the closed-form mechanism that its modes are roots of.

    Attributes
    ----------
    group : Group
        The group (a step of the parent plan).
    params : Params
        The cut mechanism's parameters (one design; its ground joints are overridden per column).
    ground_slots : tuple of int
        For each joint the cut mechanism's ground step fixes, its index in ``group.known``.
    unknown : tuple of int
        For each of ``group.joints``, its index among the cut mechanism's joints.
    ends : tuple of int
        The cut link's two joints, as indices among the cut mechanism's joints.
    length : float
        The cut link's length ``L_cut``.
    combos : ndarray, shape (n_signs, C)
        Every sign combination of the cut mechanism (its branches).
    drive, cut : str
        The driven link (turned about its known joint) and the cut link.
    size : float
        The group's size (its largest link dimension), for relative tolerances.
    frame : tuple or None
        When a slider's line is carried by a link placed before the group: that link's first two
        joints (indices in ``group.known``) and their pose positions. The cut mechanism is then
        solved in that link's frame (its line on the cut mechanism's ground) and moved back.
    """

    group: Group
    params: Params
    ground_slots: tuple[int, ...]
    unknown: tuple[int, ...]
    ends: tuple[int, int]
    length: float
    combos: np.ndarray
    drive: str
    cut: str
    size: float
    frame: tuple[int, int, complex, complex] | None = None

    def _into_frame(self, known: np.ndarray) -> tuple[np.ndarray, Callable[[np.ndarray], np.ndarray]]:
        """The known joints in the carrier's pose frame (:attr:`frame`), and the map back to the world."""
        if self.frame is None:
            return known, lambda z: z
        i0, i1, p0, p1 = self.frame
        turn = (known[i1] - known[i0]) / (p1 - p0)
        turn = turn / np.abs(turn)  # the carrier's rotation from the pose
        origin = known[i0]
        return p0 + (known - origin) / turn, lambda z: origin + turn * (z - p0)

    def closure(self, known: np.ndarray, combo: np.ndarray, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``f = |z_a - z_b| - L_cut`` and the group's joints at each column (NaN where it does not assemble).

        Parameters
        ----------
        known : ndarray, complex, shape (n_known, n)
            The group's known joints (``group.known`` order) at each column.
        combo : ndarray of int, shape (n,)
            The branch (column of :attr:`combos`) at each column.
        theta : ndarray, shape (n,)
            The driven link's angle (radians) at each column.

        Returns
        -------
        f : ndarray, shape (n,)
        joints : ndarray, complex, shape (m, n)
        """
        n = len(theta)
        f = np.full(n, np.nan)
        zs = np.full((len(self.unknown), n), complex(np.nan, np.nan))
        a, b = self.ends
        for s in range(0, n, CHUNK):
            sl = slice(s, min(n, s + CHUNK))
            inside, back = self._into_frame(known[:, sl])
            p = self._at(inside)
            sol = solve(p, theta[None, sl, None], self.combos[:, combo[sl]][:, :, None])
            z = back(sol.z[:, :, 0])
            f[sl] = np.where(sol.assembled[:, 0], np.abs(z[a] - z[b]) - self.length, np.nan)
            zs[:, sl] = z[list(self.unknown)]
        return f, zs

    def _at(self, known: np.ndarray) -> Params:
        """The cut mechanism with its ground joints at ``known`` (n_known, D): one design per column."""
        p = self.params
        D = known.shape[1]
        steps = list(p.steps)
        steps[0] = (known[list(self.ground_slots)][:, :, None],)
        return replace(
            p,
            steps=tuple(steps),
            pose_inputs=np.zeros((1, D)),
            signs=np.ones((p.plan.n_signs, D)),
            valid=np.ones(D, bool),
            pose=np.broadcast_to(p.pose[:, :1], (p.pose.shape[0], D)),
        )


@lru_cache(maxsize=64)
def reduction(mech: Mechanism, plan: Plan, index: int) -> Reduction | None:
    """The group at ``plan.steps[index]`` cut to one freedom, or None when no cut makes it closed-form.

    Every pair (driven link, cut link) of binary links of the group is tried, the driven
    one holding a known joint, in the order of the group's links; the first whose cut
    mechanism has a closed-form plan is kept.  The cut mechanism is an ordinary mechanism
    built with :meth:`Mechanism.from_dict`: its ground carries the group's known joints (at
    their pose positions; each solve puts them where they are), its links are the group's
    links but the cut one (with their ``lengths`` when the file gives them, so their shapes
    are the file's), and one driver turns the driven link.
    """
    st = plan.steps[index]
    assert isinstance(st, Group)
    if st.input_drivers:  # an input inside the group: the cut mechanism would need it as a driver too (not written)
        return None
    names = plan.joint_names
    m = len(st.joints)
    unknown = [names[j] for j in st.joints]
    known = [names[j] for j in st.known]
    sliding = {name for gs in st.sliders for name in (gs.carrier, gs.other)}
    binary = [gl for gl in st.links if len(gl.slots) == 2 and gl.name not in sliding]
    frame = _frame(mech, st, names)
    if frame is False:
        return None
    drives = [gl for gl in binary if sum(s >= m for s in gl.slots) == 1]
    for dl in drives:
        for cl in binary:
            if cl.name == dl.name:
                continue
            cut = _cut_mechanism(mech, st, names, dl.name, cl.name, frame[0] if frame else None)
            if cut is None:
                continue
            try:
                sub_plan = make_plan(cut)
            except LinkageError:
                continue
            if sub_plan.numerical or sub_plan.unwritten or not isinstance(sub_plan.steps[0], Ground):
                continue
            sub_names = sub_plan.joint_names
            ground = sub_plan.steps[0]
            assert isinstance(ground, Ground)
            a, b = (sub_names.index(names[j]) for j in cl.joints)
            link = mech.link(cl.name)
            size = max(
                ln.length(p, q) for ln in (mech.link(gl.name) for gl in st.links) for p in ln.joints for q in ln.joints
            )
            return Reduction(
                group=st,
                params=compile(cut, None, sub_plan),
                ground_slots=tuple(known.index(sub_names[j]) for j in ground.joints),
                unknown=tuple(sub_names.index(u) for u in unknown),
                ends=(a, b),
                length=float(link.length(names[cl.joints[0]], names[cl.joints[1]])),
                combos=all_sign_combinations(sub_plan.n_signs),
                drive=dl.name,
                cut=cl.name,
                size=float(size),
                frame=frame[1] if frame else None,
            )
    return None


def _frame(
    mech: Mechanism, st: Group, names: tuple[str, ...]
) -> tuple[str, tuple[int, int, complex, complex]] | None | Literal[False]:
    """The placed link carrying a slider's line, with its frame (see :attr:`Reduction.frame`); None if there is
    none, False if there are several or it is a slider's block (then no cut mechanism is written)."""
    inner = {gl.name for gl in st.links}
    placed = {gs.carrier for gs in st.sliders if gs.frame_joints is not None and gs.carrier not in inner}
    if not placed:
        return None
    if len(placed) > 1 or any(mech.sliders[gs.slider].link in placed for gs in st.sliders):
        return False
    (carrier,) = placed
    j0, j1 = next(gs.frame_joints for gs in st.sliders if gs.carrier == carrier and gs.frame_joints)
    known = list(st.known)
    return carrier, (known.index(j0), known.index(j1), mech.joints[names[j0]], mech.joints[names[j1]])


def _cut_mechanism(
    mech: Mechanism, st: Group, names: tuple[str, ...], drive: str, cut: str, frame: str | None = None
) -> Mechanism | None:
    """The group without link ``cut``, its known joints on the ground, link ``drive`` driven (None if invalid).

    The group's sliders come along with their sides: a side that is not a link of the group
    (a block of one joint) is added as it is; a placed link ``frame`` carrying a line is the
    cut mechanism's ground (it is solved in that link's frame, :attr:`Reduction.frame`).
    """
    known = [names[j] for j in st.known]
    used = {names[j] for j in (*st.joints, *st.known)}
    dl = mech.link(drive)
    pivot = next(j for j in dl.joints if j in known)
    toward = next(j for j in dl.joints if j != pivot)
    links: dict[str, Any] = {"ground": known}
    for gl in st.links:
        if gl.name == cut:
            continue
        ln = mech.link(gl.name)
        links[gl.name] = {"joints": list(ln.joints), "lengths": dict(ln.lengths)} if ln.lengths else list(ln.joints)
    sliders = []
    for gs in st.sliders:
        s = mech.sliders[gs.slider]
        on = "ground" if s.on == frame else s.on
        for side in (on, s.link):
            if side not in links:
                links[side] = list(mech.link(side).joints)
        d = s.direction
        sliders.append({"link": s.link, "on": on, "through": names[gs.point_joint], "direction": [d.real, d.imag]})
    doc = {
        "format": FORMAT,
        "name": f"group {', '.join(names[j] for j in st.joints)} cut at '{cut}', '{drive}' driven",
        "units": {"length": mech.length_unit, "angle": "rad"},
        "joints": {j: [mech.joints[j].real, mech.joints[j].imag] for j in mech.joint_names if j in used},
        "links": links,
        "drivers": [{"link": drive, "pivot": pivot, "toward": toward}],
        **({"sliders": sliders} if sliders else {}),
    }
    try:
        return Mechanism.from_dict(doc, source=f"{mech.source} (group cut)")
    except LinkageError:
        return None


# ---------------------------------------------------------------------- the roots of the closure
def group_modes(red: Reduction, known: np.ndarray, nums: Nums, n: int = N_THETA) -> list[tuple[np.ndarray, np.ndarray]]:
    """Every real mode of a group for each configuration of its known joints.

    Parameters
    ----------
    red : Reduction
        The group cut to one freedom (:func:`reduction`).
    known : ndarray, complex, shape (n_known, B)
        Its known joints, ``group.known`` order, one column per configuration (finite).
    nums : tuple
        The group's numbers in the parent parameters (for its constraints and Newton).
    n : int
        Grid of the driven link's angle per turn.

    Returns
    -------
    list of (joints, theta)
        Per configuration: ``joints`` (n_modes, m) complex, the group's joints in each mode
        (``group.joints`` order), sorted by ``theta``, the driven link's angle in [0, 2 pi).
    """
    B, C = known.shape[1], red.combos.shape[1]
    th = 2 * math.pi * np.arange(n) / n

    def f_of(branch: np.ndarray, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return red.closure(known[:, branch // C], branch % C, theta)

    ring = _ring(f_of, th, B * C)  # 1. every branch's samples and the ends of its assembled stretches
    brackets, touch_b, touch_t = _brackets(f_of, ring, TOUCH_TOL * red.length)  # 2., 3.
    roots_b, roots_t, z_r = _roots(f_of, brackets, touch_b, touch_t)
    # 4. verify each root against the group's own constraints; polish; deduplicate
    cfg = roots_b // C
    U, good = _verify(red.group, nums, z_r, known[:, cfg], red.size)
    theta = np.mod(roots_t, 2 * math.pi)
    return [_distinct(U, theta, np.flatnonzero((cfg == c) & good), red.size) for c in range(B)]


#: the closure of a group's branches: (branch, theta) -> (f, joints)
Closure = Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]
#: intervals of theta where the closure changes sign: (branch, lo, hi, f(lo) >= 0)
Brackets = list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]


class _Ring(NamedTuple):
    """Every branch's samples in order of theta, with their neighbours round the turn."""

    b: np.ndarray  # the branch of each sample
    t: np.ndarray
    f: np.ndarray
    t_next: np.ndarray  # unwrapped: the last sample's next is the first one's angle + 2 pi
    t_prev: np.ndarray
    f_next: np.ndarray
    f_prev: np.ndarray


def _ring(f_of: Closure, th: np.ndarray, NB: int) -> _Ring:
    """The closure of ``NB`` branches on the grid ``th`` and at the ends of their assembled stretches."""
    n = len(th)
    br = np.repeat(np.arange(NB), n)
    F = f_of(br, np.tile(th, NB))[0].reshape(NB, n)
    cb, edge = _assembly_ends(f_of, th, np.isfinite(F))
    f_edge = f_of(cb, edge)[0]
    b_all = np.concatenate([br, cb])
    t_all = np.concatenate([np.tile(th, NB), edge])
    f_all = np.concatenate([F.ravel(), f_edge])
    order = np.lexsort((t_all, b_all))
    b_all, t_all, f_all = b_all[order], t_all[order], f_all[order]
    j = np.arange(len(b_all))
    first = np.searchsorted(b_all, b_all, "left")
    last = np.searchsorted(b_all, b_all, "right") - 1
    nxt = np.where(j < last, j + 1, first)
    prv = np.where(j > first, j - 1, last)
    t_next = t_all[nxt] + np.where(j == last, 2 * math.pi, 0.0)
    t_prev = t_all[prv] - np.where(j == first, 2 * math.pi, 0.0)
    return _Ring(b_all, t_all, f_all, t_next, t_prev, f_all[nxt], f_all[prv])


def _assembly_ends(f_of: Closure, th: np.ndarray, ok: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The ends of the assembled stretches (``ok`` (NB, n) on the grid ``th``), by bisection: (branch, theta)."""
    cell = 2 * math.pi / len(th)
    cb, ci = np.nonzero(ok != np.roll(ok, -1, axis=1))
    lo, hi = th[ci].copy(), th[ci] + cell
    inside = ok[cb, ci]
    for _ in range(N_BISECT):
        mid = 0.5 * (lo + hi)
        same = np.isfinite(f_of(cb, mid)[0]) == inside
        lo, hi = np.where(same, mid, lo), np.where(same, hi, mid)
    return cb, np.mod(np.where(inside, lo, hi), 2 * math.pi)


def _brackets(f_of: Closure, r: _Ring, touch_tol: float) -> tuple[Brackets, np.ndarray, np.ndarray]:
    """Brackets of the roots (sign changes, and both sides of a dip through zero) and the touching roots.

    Returns the brackets and the branches and angles of the local minima of ``|f|`` that touch zero
    (within ``touch_tol``) without a sign change.
    """
    fin = np.isfinite(r.f)
    pos, pos_next, pos_prev = r.f >= 0, r.f_next >= 0, r.f_prev >= 0
    # 2. sign changes between neighbours
    sc = fin & np.isfinite(r.f_next) & (pos != pos_next)
    brackets = [(r.b[sc], r.t[sc], r.t_next[sc], pos[sc])]
    # 3. local minima of |f| with no sign change either side
    vp, vn = np.isfinite(r.f_prev), np.isfinite(r.f_next)
    a_f = np.abs(r.f)
    with np.errstate(invalid="ignore"):
        cond_p = ~vp | ((a_f <= np.abs(r.f_prev)) & (pos_prev == pos))
        cond_n = ~vn | ((a_f <= np.abs(r.f_next)) & (pos_next == pos))
    cand = fin & (vp | vn) & cond_p & cond_n & (r.f != 0)
    g_b = r.b[cand]
    g_lo = np.where(vp[cand], r.t_prev[cand], r.t[cand])
    g_hi = np.where(vn[cand], r.t_next[cand], r.t[cand])
    g_s = np.where(pos[cand], 1.0, -1.0)
    t_min, g_min = _golden(f_of, g_b, g_lo, g_hi, g_s)
    touch = np.isfinite(g_min) & (g_min >= 0) & (g_min <= touch_tol)
    cross = np.isfinite(g_min) & (g_min < 0)
    brackets.append((g_b[cross], g_lo[cross], t_min[cross], g_s[cross] > 0))
    brackets.append((g_b[cross], t_min[cross], g_hi[cross], g_s[cross] < 0))
    return brackets, g_b[touch], t_min[touch]


def _roots(
    f_of: Closure, brackets: Brackets, touch_b: np.ndarray, touch_t: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The roots in ``brackets`` by bisection, and the touching ones: (branch, theta, joints (m, n_roots))."""
    rb = np.concatenate([x[0] for x in brackets])
    rlo = np.concatenate([x[1] for x in brackets])
    rhi = np.concatenate([x[2] for x in brackets])
    rpos = np.concatenate([x[3] for x in brackets])
    for _ in range(N_BISECT):
        mid = 0.5 * (rlo + rhi)
        fm = f_of(rb, mid)[0]
        same = (fm >= 0) == rpos
        rlo, rhi = np.where(same, mid, rlo), np.where(same, rhi, mid)
    roots_b = np.concatenate([rb, rb, touch_b])
    roots_t = np.concatenate([rlo, rhi, touch_t])
    f_r, z_r = f_of(roots_b, roots_t)
    # of the two ends of a bisection keep the one nearer the root
    nr = len(rb)
    if nr:
        pick = np.abs(f_r[:nr]) <= np.abs(f_r[nr : 2 * nr])
        keep = np.concatenate([pick, ~pick, np.ones(len(roots_b) - 2 * nr, bool)])
        roots_b, roots_t, z_r = roots_b[keep], roots_t[keep], z_r[:, keep]
    return roots_b, roots_t, z_r


def _distinct(U: np.ndarray, theta: np.ndarray, idx: np.ndarray, size: float) -> tuple[np.ndarray, np.ndarray]:
    """The distinct modes among the columns ``idx`` of ``U``, by ``theta``: (joints (k, m), theta (k,))."""
    idx = idx[np.argsort(theta[idx], kind="stable")]
    kept: list[int] = []
    for i in idx:
        if not any(np.max(np.abs(U[:, i] - U[:, k])) <= DEDUPE_RTOL * size for k in kept):
            kept.append(int(i))
    return U[:, kept].T.copy(), theta[kept]


def _golden(
    f_of: Closure, b: np.ndarray, lo: np.ndarray, hi: np.ndarray, s: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Golden-section search for the minimum of ``s f`` on each [lo, hi] (NaN counts as +inf): (argmin, min)."""
    g = (math.sqrt(5) - 1) / 2
    lo, hi = lo.copy(), hi.copy()
    if not len(b):
        return lo, lo.copy()
    for _ in range(N_GOLDEN):
        c, d = hi - g * (hi - lo), lo + g * (hi - lo)
        fv = f_of(np.concatenate([b, b]), np.concatenate([c, d]))[0] * np.concatenate([s, s])
        fc, fd = fv[: len(b)], fv[len(b) :]
        left = np.nan_to_num(fc, nan=np.inf) < np.nan_to_num(fd, nan=np.inf)
        lo, hi = np.where(left, lo, c), np.where(left, d, hi)
    t = 0.5 * (lo + hi)
    return t, f_of(b, t)[0] * s


def _verify(st: Group, nums: Nums, U: np.ndarray, K: np.ndarray, size: float) -> tuple[np.ndarray, np.ndarray]:
    """Each column's residual of the group's constraints (relative) below :data:`VERIFY_TOL`, then Newton-polished.

    Returns the (polished) joints (m, n) and which columns pass.
    """
    n = U.shape[1]
    if not n:
        return U, np.zeros(0, bool)
    dn = st._design_nums(nums, np.zeros(n, int))
    m = len(st.joints)

    def worst(Uc: FloatArray) -> FloatArray:
        P = np.concatenate([Uc, K]) if len(K) else Uc
        with np.errstate(invalid="ignore"):
            res, scale = st.residual(P, dn)
            largest: FloatArray = np.max(np.abs(res) / scale, axis=1)
        return largest

    err = worst(U)
    good = np.isfinite(err) & (err <= VERIFY_TOL)
    if good.any():
        Un, conv, _ = st.newton(U, K, dn)
        near = np.all(np.abs(Un - U) <= 1e-6 * size, axis=0)
        better = conv & near & (worst(Un) <= err)
        U = np.where(better[None, :], Un, U)
    assert U.shape[0] == m
    return U, good


# ---------------------------------------------------------------------- every mode of a mechanism
@dataclass(frozen=True)
class ModeTable:
    """Every combination of closed-form signs (and mirrors) and group modes at one input.

    Attributes
    ----------
    z : ndarray, complex, shape (n_joints, R)
        Positions of every joint in each row (NaN where it does not assemble).
    assembled : ndarray of bool, shape (R,)
    column : ndarray of int, shape (R,)
        The sign (and mirror) combination of each row (a column of the combinations given).
    group_mode, group_count : ndarray of int, shape (n_groups, R)
        Each group's mode in the row (0-based, sorted by the driven link's angle; -1 when
        the group has no mode there or was not enumerated) and how many modes it has there.
    groups : tuple of int
        The plan steps of the groups (rows of ``group_mode``).
    notes : tuple of str
        Groups whose modes could not be enumerated (no cut makes them closed-form): only
        the mode the solver continues from the pose is listed for them.
    """

    z: np.ndarray
    assembled: np.ndarray
    column: np.ndarray
    group_mode: np.ndarray
    group_count: np.ndarray
    groups: tuple[int, ...]
    notes: tuple[str, ...]


def enumerate_modes(
    mech: Mechanism, params: Params, q: np.ndarray, signs: np.ndarray, mirrors: np.ndarray | None
) -> ModeTable:
    """Every assembly mode at input ``q``: each sign (and mirror) combination times every mode of each group.

    Parameters
    ----------
    mech : Mechanism
    params : Params
        One design (``plan.numerical`` may be empty: then each combination is one row).
    q : ndarray, shape (n_drivers,)
        The input (radians, length units).
    signs : ndarray, shape (n_signs, n)
        The sign combinations; ``mirrors`` (n_mirrors, n) bool likewise, or None.

    Returns
    -------
    ModeTable
        Rows ordered by combination, then by each group's mode in plan order.  The groups
        are handled in plan order: the steps before a group give its known joints for each
        row, its modes are enumerated once per distinct set of known joints
        (:func:`group_modes`), and each row is repeated once per mode, the group started at
        that mode (:func:`restarted`) so the steps after it continue from there.
    """
    plan = params.plan
    gsteps = tuple(i for i, st in enumerate(plan.steps) if isinstance(st, Group))
    n = signs.shape[1]
    col = np.arange(n)
    starts: dict[int, tuple[np.ndarray, np.ndarray]] = {}  # step -> each row's mode of the group and its knowns
    gmode = np.zeros((0, n), int)
    gcount = np.zeros((0, n), int)
    notes: list[str] = []
    names = plan.joint_names
    for gi in gsteps:
        st = plan.steps[gi]
        assert isinstance(st, Group)
        red = reduction(mech, plan, gi)
        label = ", ".join(names[j] for j in st.joints)
        if red is None:
            notes.append(_not_enumerated(mech, st, label))
            gmode = np.concatenate([gmode, np.full((1, len(col)), -1)])
            gcount = np.concatenate([gcount, np.full((1, len(col)), -1)])
            continue
        sol = _solve_rows(params, q, signs[:, col], None if mirrors is None else mirrors[:, col], starts, upto=gi)
        K = sol[list(st.known)]
        rows, within, counts, zu = _rows_per_mode(red, K, params.steps[gi])
        col = col[rows]
        starts = {g: (zu_g[:, rows], zk_g[:, rows]) for g, (zu_g, zk_g) in starts.items()}
        starts[gi] = (zu, K[:, rows])
        gmode = np.concatenate([gmode[:, rows], np.where(counts[rows] > 0, within, -1)[None]])
        gcount = np.concatenate([gcount[:, rows], counts[rows][None]])
    z = _solve_rows(params, q, signs[:, col], None if mirrors is None else mirrors[:, col], starts)
    assembled = np.all(np.isfinite(z), axis=0) if z.shape[0] else np.ones(len(col), bool)
    return ModeTable(z, assembled, col, gmode, gcount, gsteps, tuple(notes))


def _not_enumerated(mech: Mechanism, st: Group, label: str) -> str:
    """The note that group ``label``'s modes are not enumerated, and why."""
    why = (
        f"it holds driver {', '.join(mech.drivers[d].name for d in st.input_drivers)}"
        if st.input_drivers
        else "no cut of one of its binary links makes it closed-form"
    )
    return f"the modes of group {label} are not enumerated ({why}): only the mode continued from the pose is listed"


def _rows_per_mode(red: Reduction, K: np.ndarray, nums: Nums) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Each row repeated once per mode of the group at its known joints ``K`` (n_known, R).

    The modes are enumerated once per distinct set of known joints (:func:`group_modes`); a row
    without a mode (or with unknown joints) stays as one row.  Returns ``(rows, within, counts,
    zu)``: the row each new row repeats, its mode's number, each old row's mode count, and the
    group's joints in each new row's mode (NaN without one).
    """
    rows_ok = np.all(np.isfinite(K), axis=0)
    found: list[tuple[np.ndarray, np.ndarray]] = []
    inverse = np.full(K.shape[1], -1)
    if rows_ok.any():
        flat = np.concatenate([K.real, K.imag])[:, rows_ok].T
        uniq, inv = np.unique(flat, axis=0, return_inverse=True)
        inverse[rows_ok] = np.ravel(inv)
        Ku = uniq[:, : K.shape[0]] + 1j * uniq[:, K.shape[0] :]
        found = group_modes(red, Ku.T, nums)
    counts = np.array([len(found[u][0]) if u >= 0 else 0 for u in inverse], int)
    rep = np.maximum(counts, 1)
    rows = np.repeat(np.arange(K.shape[1]), rep)
    within = np.arange(len(rows)) - np.repeat(np.cumsum(rep) - rep, rep)
    zu = np.full((len(red.group.joints), len(rows)), complex(np.nan, np.nan))
    for r in np.flatnonzero(counts[rows] > 0):
        zu[:, r] = found[inverse[rows[r]]][0][within[r]]
    return rows, within, counts, zu


def _solve_rows(
    params: Params,
    q: np.ndarray,
    signs: np.ndarray,
    mirrors: np.ndarray | None,
    starts: dict[int, tuple[np.ndarray, np.ndarray]],
    upto: int | None = None,
) -> np.ndarray:
    """Positions (n_joints, R) at input ``q``, one row per design: its signs, mirrors and group starts.

    ``upto``: run only the plan's steps before that one (the joints they place; NaN for the others).

    ``starts`` maps a group's step to its joints and known joints per row (a mode at ``q``,
    or NaN for none): the group begins its walk there, so it stays in that mode (a walk of
    one sample starts at its start).  A group without a start walks from the pose as usual.
    """
    R = signs.shape[1]
    steps = list(params.steps)
    for gi, (zu, zk) in starts.items():
        steps[gi] = _group_start(steps[gi], zu, zk)
    plan = params.plan if upto is None else replace(params.plan, steps=params.plan.steps[:upto])
    p = replace(
        params,
        plan=plan,
        steps=tuple(steps[: len(plan.steps)]),
        # a group started at a mode at q walks from q (its grid's origin is the driver's input there)
        pose_inputs=np.repeat(np.asarray(q, float)[:, None], R, axis=1)
        if starts
        else params.pose_inputs[:, :1].repeat(R, 1),
        signs=np.repeat(params.signs[:, :1], R, axis=1),
        valid=np.ones(R, bool),
        pose=np.repeat(params.pose[:, :1], R, axis=1),
    )
    qr = np.repeat(np.asarray(q, float)[:, None, None], R, axis=1)
    sol = solve(p, qr, signs[:, :, None], None if mirrors is None else mirrors[:, :, None])
    return np.asarray(sol.z[:, :, 0])
