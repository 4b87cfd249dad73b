"""Design checks: assembly range, dead points, four-bar loops, limit positions, peak loads, modes.

Everything here is built on the vectorized solver: a dense sweep of one driver finds where
the assembled flag changes, where a sign step's triangle goes flat (dead points), where a
rocker's angular velocity changes sign (limit positions) and where the transmission angle
is extreme; then one vectorized bisection / golden-section loop refines every such value
at once (one solve per step for all of them).  :func:`check` and :func:`modes` take and
report values in the file's units; the derivations are in ``docs/method.md`` ("Checks").

Examples
--------
>>> import linkagekit as lk
>>> rep = lk.check(lk.load("examples/seed003_ex21.yaml"))
>>> rep.grashof, [[round(a, 6), round(b, 6)] for a, b in rep.input_range]
('non-grashof', [[86.78273, 273.21727]])
>>> m = lk.modes(lk.load("examples/seed000_fourbar.yaml"), at=30.0)
>>> m.distinct, [mode.signs for mode in m.modes]
(2, [{'D': 1}, {'D': -1}])
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np

from .api import analyze, prepare, sweep_inputs
from .branch import MAX_PATH, PathTooLongError, along_sweep
from .errors import InputError
from .group import Group
from .groupmodes import continuation_intervals, enumerate_modes
from .model import CrankType, Mechanism
from .params import Params, all_sign_combinations
from .positions import Positions, solve
from .rates import SINGULAR_TOL, solve_rates
from .steps import ActuatorDyad, CircleLine, CylinderDyad, CylinderLine, Dyad, SliderDrive
from .threads import one_blas_thread

N_COARSE = 7200
#: dead points the text of check lists per driver (the JSON has them all)
MAX_TEXT_DEAD_POINTS = 24
#: modes lists at most 2^MAX_MODE_SLOTS sign (and mirror) combinations
MAX_MODE_SLOTS = 12
N_BISECT = 60
#: a sign step's |determinant| at a sample below which a local minimum is refined as a possible change point
TOUCH = 0.05
#: a rocker whose angular velocity stays within this share of its largest is at rest (the rest is rounding)
REST = 1e-9
#: a slider whose position moves less than this share of its stroke over two or more sample steps in a row rests there
#: (a dwell: its velocity is rounding, whose sign says nothing)
DWELL = 1e-10
#: check warns when a four-bar's transmission angle goes below this (degrees; synthesize's --min-transmission default)
MIN_TRANSMISSION = 20.0
#: check warns when a driver's peak effort is within this angle (degrees) of a toggle (a sign step's triangle flat)
TOGGLE_ANGLE = 10.0
#: the kind of the warning that the pose sits at a change point (check prints it under the pose's assembly mode)
POSE_WARNING = "pose-at-change-point"
#: a sign step whose dimensionless determinant at the pose's own coordinates is below this is flat there, to the
#: rounding of a pose typed in decimals: the pose sits at a change point (or a toggle) and picks none of its two modes
POSE_FLAT = 1e-9


def _inputs(params: Params, driver: int, values: np.ndarray) -> np.ndarray:
    """Driver values (n_drivers, 1, n): ``values`` for one driver, the pose's for the others."""
    q = np.repeat(params.pose_inputs[:, :, None], len(values), axis=2)
    q[driver, 0] = values
    return q


def _assembled(params: Params, driver: int, values: np.ndarray) -> np.ndarray:
    ok: np.ndarray = solve(params, _inputs(params, driver, values)).assembled[0]
    return ok


def _span(mech: Mechanism, driver: int) -> tuple[float, float]:
    """Where a driver's input is searched: a turn [0, 2 pi), +-2 x the sum of the link sizes for a slider;
    for a cylinder's length its stroke and 1 % of it either side, or (0, 2 x that sum] without a stroke."""
    span = 2 * sum(max(ln.length(a, b) for a in ln.joints for b in ln.joints) for ln in mech.links)
    return mech.drivers[driver].type.search_span(span)


def input_range(mech: Mechanism, driver: int = 0, params: Params | None = None) -> list[list[float]]:
    """Intervals of one driver's input (file units) where the mechanism assembles.

    The other drivers stay at their reference-pose values.  An angle's intervals lie in
    [0, 360) degrees (or [0, 2 pi)), except that an interval running through 0 starts at
    a negative value; a full turn is ``[[0, 360]]``; a numerical group's mode longer than a
    turn that does not close runs from fold to fold, longer than 360.  Boundaries are exact to ~1e-12 rad.
    With numerical groups it is the interval over which the pose's mode goes on, found by
    continuation, its ends to 1e-9 rad (:func:`linkagekit.groupmodes.continuation_intervals`).
    """
    params = prepare(mech) if params is None else params
    factor = mech.drivers[driver].input_scale(mech)
    return [[float(s / factor), float(e / factor)] for s, e in _assembly_intervals(mech, driver, params)]


def _assembly_intervals(mech: Mechanism, driver: int, params: Params) -> list[list[float]]:
    """:func:`input_range` in radians (or length units): every boundary is the last assembled value.

    With numerical groups, the interval over which the pose's mode goes on, by continuation
    (:func:`linkagekit.groupmodes.continuation_intervals`).
    """
    cyclic = mech.drivers[driver].type.cyclic
    lo, hi = _span(mech, driver)
    if params.plan.numerical:
        return continuation_intervals(params, driver, lo, hi, cyclic, N_COARSE)
    x = np.linspace(lo, hi, N_COARSE, endpoint=False) if cyclic else np.linspace(lo, hi, N_COARSE + 1)
    ok = _assembled(params, driver, x)
    if ok.all():
        return [[lo, hi]]
    if not ok.any():
        return []
    # boundaries: a change between sample i and i+1 (cyclic for an angle)
    nxt = np.roll(ok, -1) if cyclic else np.append(ok[1:], ok[-1])
    idx = np.flatnonzero(ok != nxt)
    a = x[idx]
    step = x[1] - x[0]
    b = a + step
    inside_a = ok[idx]  # True: the boundary is an end (assembled at a), else a start
    for _ in range(N_BISECT):
        mid = 0.5 * (a + b)
        m_ok = _assembled(params, driver, mid)
        same = m_ok == inside_a
        a = np.where(same, mid, a)
        b = np.where(same, b, mid)
    edge = np.where(inside_a, a, b)  # the last assembled value on each side
    starts = np.sort(edge[~inside_a])
    ends = np.sort(edge[inside_a])
    intervals: list[list[float]] = []
    if cyclic:
        # on the circle every start is followed by the next end; an interval whose end
        # comes only after 0 runs through 0 and is reported as [start - 2 pi, end]
        for s in starts:
            later = ends[ends >= s]
            if later.size:
                intervals.append([float(s), float(later[0])])
            else:
                intervals.insert(0, [float(s) - 2 * math.pi, float(ends[0])])
    else:
        st, en = list(starts), list(ends)
        if ok[0]:
            st.insert(0, lo)
        if ok[-1]:
            en.append(hi)
        intervals = [[float(s), float(e)] for s, e in zip(st, en, strict=False)]
    return intervals


@dataclass(frozen=True)
class FourBar:
    """A four-bar loop of the mechanism: ground pivot O2 -- crank -- coupler -- rocker -- ground pivot O4.

    ``crank`` is the loop's input side (the link pinned to the ground at O2 that the
    mechanism moves first) and ``rocker`` its output side, whatever they do: a "crank"
    may only rock when the loop is moved by an earlier part of the mechanism.

    Attributes
    ----------
    crank_pivot, crank_tip, rocker_tip, rocker_pivot : int
        Joint indices of O2, A (crank--coupler), B (coupler--rocker) and O4.
    ground, crank, coupler, rocker : float
        Link lengths |O2 O4|, |O2 A|, |A B|, |O4 B| (file length unit).
    links : tuple of str
        Names of the crank, coupler and rocker links.
    driver : int or None
        The driver whose input sweeps the loop (None when several drivers move it).
    moved_by : str
        What moves the loop's input link, for people (``"driver 'crank'"``, ``"loop 1 (its rocker 'r')"``).
    """

    crank_pivot: int
    crank_tip: int
    rocker_tip: int
    rocker_pivot: int
    ground: float
    crank: float
    coupler: float
    rocker: float
    links: tuple[str, str, str] = ("", "", "")
    driver: int | None = None
    moved_by: str = ""


def fourbar_loops(mech: Mechanism, params: Params | None = None) -> list[FourBar]:
    """Every four-bar loop of the mechanism, in the order the solve plan closes them.

    A loop is the ground (two distinct ground pivots O2, O4), a link pinned to the ground at
    O2 only, a coupler and a link pinned to the ground at O4 only, the coupler joined to both
    by revolute joints A and B.  In a mechanism the closed-form plan can solve, each such
    loop is closed by the circle-circle step that places B from A (on the coupler) and O4
    (on the rocker), so its input side is the link through A that the plan placed before.
    """
    params = prepare(mech) if params is None else params
    plan = params.plan
    names = plan.joint_names
    ground = set(mech.link("ground").joints)
    blocks = {s.link for s in mech.sliders}
    driven = {d.link: i for i, d in enumerate(mech.drivers) if isinstance(d.type, CrankType)}
    line_of = _plan_lines(plan)
    loops: list[FourBar] = []
    for st in plan.steps:
        if not isinstance(st, Dyad):
            continue
        for tip, piv, coupler, rocker in ((st.k1, st.k2, *st.links), (st.k2, st.k1, st.links[1], st.links[0])):
            o4, a = names[piv], names[tip]
            if o4 not in ground or a in ground or coupler in blocks or rocker in blocks:
                continue
            for ln in mech.links:
                if ln.name in ("ground", coupler, rocker) or ln.name in blocks or a not in ln.joints:
                    continue
                pivots = [j for j in ln.joints if j in ground]
                if len(pivots) != 1 or pivots[0] == o4:
                    continue
                o2 = pivots[0]
                if ln.name in driven:
                    driver: int | None = driven[ln.name]
                    moved_by = f"driver '{mech.drivers[driven[ln.name]].name}'"
                else:
                    driver = 0 if len(mech.drivers) == 1 else None
                    earlier = next((k for k, lp in enumerate(loops) if lp.links[2] == ln.name), None)
                    if earlier is not None:
                        moved_by = f"loop {earlier + 1} (its rocker '{ln.name}')"
                    else:
                        placed = next(k for k, s in enumerate(plan.steps) if tip in s.writes())
                        moved_by = f"the mechanism (step {line_of.get(placed, placed + 1)} of the solve plan)"
                loops.append(
                    FourBar(
                        names.index(o2),
                        tip,
                        st.joint,
                        piv,
                        mech.link("ground").length(o2, o4),
                        ln.length(o2, a),
                        mech.link(coupler).length(a, names[st.joint]),
                        mech.link(rocker).length(o4, names[st.joint]),
                        (ln.name, coupler, rocker),
                        driver,
                        moved_by,
                    )
                )
    return loops


def _plan_lines(plan: Any) -> dict[int, int]:
    """Step index -> its line number in :meth:`Plan.describe` (steps that print nothing have none)."""
    out, line = {}, 0
    names = plan.joint_names
    for i, st in enumerate(plan.steps):
        if st.describe(names, None) is not None:
            line += 1
            out[i] = line
    return out


def fourbar_loop(mech: Mechanism, params: Params | None = None) -> FourBar | None:
    """The first four-bar loop of :func:`fourbar_loops`, if any."""
    loops = fourbar_loops(mech, params)
    return loops[0] if loops else None


def grashof(fb: FourBar, rtol: float = 1e-9) -> tuple[str, str]:
    """Grashof class of a four-bar: (one of five names, a finer description).

    ``s + l < p + q``: Grashof; the shortest link next to the ground makes a crank-rocker
    (input crank) or rocker-crank (output crank), the ground shortest a double crank, the
    coupler shortest a (Grashof) double rocker.  ``s + l = p + q`` (to ``rtol`` of ``l``):
    change point.  Otherwise non-Grashof (triple rocker).
    """
    lengths = {"ground": fb.ground, "crank": fb.crank, "coupler": fb.coupler, "rocker": fb.rocker}
    vals = sorted(lengths.values())
    s, p, q, ell = vals
    diff = (s + ell) - (p + q)
    if abs(diff) <= rtol * ell:
        return "change-point", "change-point (s + l = p + q)"
    if diff > 0:
        return "non-grashof", "non-Grashof triple rocker"
    shortest = min(lengths, key=lambda k: lengths[k])
    return {
        "crank": ("crank-rocker", "crank-rocker (the input turns fully)"),
        "rocker": ("crank-rocker", "rocker-crank (the output turns fully, the input rocks)"),
        "ground": ("double-crank", "double crank (drag link)"),
        "coupler": ("double-rocker", "Grashof double rocker"),
    }[shortest]


# ---------------------------------------------------------------------- one driver's sweep
@dataclass(frozen=True)
class _State:
    """The mechanism at input values ``x`` of one driver (the others at the pose), unit input speed.

    ``z``, ``v`` (n_joints, n) positions and velocities per unit input speed (NaN where not
    assembled or singular, as the solver flags it); ``vraw`` the velocities not masked at
    singular samples (finite upstream of a singular step); ``cond`` (n_signs, n) the
    magnitude of each sign step's dimensionless determinant (NaN where not assembled);
    ``margin`` (n_signs, n).
    """

    assembled: np.ndarray
    z: np.ndarray
    v: np.ndarray
    vraw: np.ndarray
    cond: np.ndarray
    margin: np.ndarray


def _state(params: Params, driver: int, x: np.ndarray) -> _State:
    if not len(x):  # nothing to solve (a numerical group walks from one sample to the next: it needs one)
        nj, ns = len(params.plan.joint_names), params.plan.n_signs
        none = np.zeros((nj, 0), complex)
        return _State(np.zeros(0, bool), none, none, none, np.zeros((ns, 0)), np.zeros((ns, 0)))
    pos = solve(params, _inputs(params, driver, x))
    nd = params.pose_inputs.shape[0]
    speed = np.zeros((nd, 1, 1))
    speed[driver] = 1.0
    rt = solve_rates(params, pos, speed, np.zeros((nd, 1, 1)), tol=0.0)
    ok = pos.assembled[0]
    every = np.where(ok, np.abs(rt.condition[:, 0]), np.nan)  # the sign steps', then each numerical group's
    singular = np.any(every < SINGULAR_TOL, axis=0) if len(every) else np.zeros(len(ok), bool)
    v = rt.v[:, 0]
    cond = every[: params.plan.n_signs]  # the rows :class:`_Quantities` reads: a group's shifted the slider rows
    return _State(ok, pos.z[:, 0], np.where(singular, np.nan, v), v, cond, pos.margin[:, 0])


@dataclass(frozen=True)
class SliderLine:
    """A slider whose guide is the frame, as :func:`check` looks at it (its block's joint and the rod pushing it).

    Attributes
    ----------
    index : int
        The slider's index in the file's ``sliders``.
    link : str
        The block.
    joint : int
        Joint index of ``through``, the block's joint that moves along the line.
    direction : complex
        Unit vector of the line (the file's ``direction``).
    rod : str
        The two-joint link pinned to the block at ``joint`` (the coupler pushing it), or ``""``.
    rod_joint : int
        The rod's other joint, or -1 without a rod.
    """

    index: int
    link: str
    joint: int
    direction: complex
    rod: str = ""
    rod_joint: int = -1


def slider_lines(mech: Mechanism) -> list[SliderLine]:
    """The sliders on the frame whose position is not itself an input (not a slider driver's).

    The rod is the one link of two joints, other than the block, pinned at the block's joint:
    the force it carries is along it (without masses or loads on it), which makes the
    pressure angle the angle between the rod and the line of the slide.

    >>> import linkagekit as lk
    >>> [(s.link, s.rod) for s in slider_lines(lk.load("examples/whitworth_quick_return.yaml"))]
    [('ram', 'rod')]
    """
    names = mech.joint_names
    driven = {d.slider for d in mech.drivers if d.slider is not None}
    out = []
    for i, sl in enumerate(mech.sliders):
        if sl.on != "ground" or i in driven:
            continue
        rods = [ln for ln in mech.links if ln.name not in ("ground", sl.link) and sl.through in ln.joints]
        rods = [ln for ln in rods if len(ln.joints) == 2]
        rod = rods[0] if len(rods) == 1 else None
        other = next((j for j in rod.joints if j != sl.through), None) if rod else None
        out.append(
            SliderLine(
                i,
                sl.link,
                names.index(sl.through),
                sl.direction,
                rod.name if rod else "",
                names.index(other) if other else -1,
            )
        )
    return out


def transmission_deg(tip: np.ndarray, joint: np.ndarray, pivot: np.ndarray) -> np.ndarray:
    """A four-bar loop's transmission angle (degrees, in [0, 180]) at the rocker's ``joint`` with the coupler: between
    the coupler (to the crank's ``tip``) and the rocker (to its ground ``pivot``); NaN where a position is.

    >>> float(transmission_deg(np.array(1j), np.array(0j), np.array(1 + 0j)))
    90.0
    """
    with np.errstate(invalid="ignore", divide="ignore"):
        out: np.ndarray = np.degrees(np.abs(np.angle((pivot - joint) / (tip - joint))))
    return out


class _Quantities:
    """The scalar functions of the input the checks look at, as rows of one matrix per state.

    Rows: for each loop its rocker's angular velocity per unit input speed (``w``), its
    transmission angle in degrees (``mu``), ``-mu``, and ``dmu`` = rocker's minus coupler's
    angular velocity (``d mu / d input`` up to its sign); then ``|cond|`` of each sign step,
    and for each circle-circle step ``ds``: the rate of change of the distance ``s`` between
    the two known joints it is found from (zero where ``s`` touches ``r1 + r2`` or ``|r1 - r2|``).
    """

    def __init__(
        self,
        loops: list[FourBar],
        n_signs: int,
        out_links: list[tuple[int, int]],
        known: list[tuple[int, int]],
        sliders: list[SliderLine] | None = None,
    ) -> None:
        self.sliders = list(sliders or [])
        self.sj = np.array([sl.joint for sl in self.sliders], int)
        self.srod = np.array([sl.rod_joint for sl in self.sliders], int)
        self.sdir = np.array([sl.direction for sl in self.sliders], complex)
        self.n = len(loops)
        self.tip = np.array([lp.crank_tip for lp in loops], int)
        self.joint = np.array([lp.rocker_tip for lp in loops], int)
        self.piv = np.array([lp.rocker_pivot for lp in loops], int)
        self.out0 = np.array([o[0] for o in out_links], int)
        self.out1 = np.array([o[1] for o in out_links], int)
        self.n_signs = n_signs
        self.k1 = np.array([k[0] for k in known], int)
        self.k2 = np.array([k[1] for k in known], int)
        self.dyad = self.k1 >= 0

    def w(self, i: int) -> int:
        return i

    def mu(self, i: int, sign: int = 1) -> int:
        return self.n + i if sign > 0 else 2 * self.n + i

    def dmu(self, i: int) -> int:
        return 3 * self.n + i

    def cond(self, k: int) -> int:
        return 4 * self.n + k

    def ds(self, k: int) -> int:
        return 4 * self.n + self.n_signs + k

    def sv(self, i: int) -> int:
        """Slider ``i``'s velocity along its line per unit input speed."""
        return 4 * self.n + 2 * self.n_signs + i

    def pa(self, i: int, sign: int = 1) -> int:
        """Slider ``i``'s pressure angle (degrees; ``sign`` -1: its negative)."""
        return 4 * self.n + 2 * self.n_signs + (1 if sign > 0 else 2) * len(self.sliders) + i

    def position(self, st: _State) -> np.ndarray:
        """(n_sliders, n) each slider's joint along its line, from the origin (file length unit)."""
        pos: np.ndarray = (st.z[self.sj] * np.conj(self.sdir)[:, None]).real
        return pos

    def _slider_rows(self, st: _State) -> list[np.ndarray]:
        if not self.sliders:
            return []
        dirs = np.conj(self.sdir)[:, None]
        along = (st.v[self.sj] * dirs).real
        rod = st.z[self.sj] - st.z[np.maximum(self.srod, 0)]
        with np.errstate(invalid="ignore", divide="ignore"):
            pa = np.degrees(np.arccos(np.minimum(np.abs((rod * dirs).real) / np.abs(rod), 1.0)))
        pa = np.where(self.srod[:, None] >= 0, pa, np.nan)
        return [along, pa, -pa]

    def rows(self, st: _State) -> np.ndarray:
        d = st.z[self.k2] - st.z[self.k1]
        with np.errstate(invalid="ignore", divide="ignore"):
            ds = (np.conj(d) * (st.vraw[self.k2] - st.vraw[self.k1])).real / np.abs(d)
        ds = np.where(self.dyad[:, None], ds, np.nan)
        if not self.n:
            return np.concatenate([st.cond, ds, *self._slider_rows(st)])
        z, v = st.z, st.v
        b, a, o4 = z[self.joint], z[self.tip], z[self.piv]
        arm, bar = b - o4, b - a
        with np.errstate(invalid="ignore", divide="ignore"):
            w = (np.conj(arm) * v[self.joint]).imag / (np.abs(arm) ** 2)
            wc = (np.conj(bar) * (v[self.joint] - v[self.tip])).imag / (np.abs(bar) ** 2)
        mu = np.where(np.isfinite(b), transmission_deg(a, b, o4), np.nan)
        return np.concatenate([w, mu, -mu, w - wc, st.cond, ds, *self._slider_rows(st)])

    def out_angle(self, st: _State) -> np.ndarray:
        """Angle (rad) of each loop's rocker link: the direction of its first joint -> its second."""
        angle: np.ndarray = np.angle(st.z[self.out1] - st.z[self.out0])
        return angle


@dataclass
class _Sweep:
    """Dense samples of one driver over its assembly range, with their neighbours.

    ``x`` (n,) input values (radians or length units), ``seg`` the interval of each;
    ``prev``/``next`` the neighbour indices and ``px``/``nx`` their values (for a full turn
    the neighbours wrap around, shifted by the period); ``has_prev``/``has_next``.
    """

    x: np.ndarray
    seg: np.ndarray
    cyclic: bool
    period: float
    prev: np.ndarray
    next: np.ndarray
    px: np.ndarray
    nx: np.ndarray
    has_prev: np.ndarray
    has_next: np.ndarray


def _sweep(intervals: list[list[float]], cyclic: bool, total: float) -> _Sweep:
    if cyclic:
        ((lo, _),) = intervals
        x = np.linspace(lo, lo + total, N_COARSE, endpoint=False)
        seg = np.zeros(len(x), int)
    else:
        parts = [np.linspace(s, e, max(32, math.ceil(N_COARSE * (e - s) / total)) + 1) for s, e in intervals]
        x = np.concatenate(parts)
        seg = np.repeat(np.arange(len(parts)), [len(p) for p in parts])
    n = len(x)
    i = np.arange(n)
    prev, nxt = np.maximum(i - 1, 0), np.minimum(i + 1, n - 1)
    has_prev = (i > 0) & (seg[prev] == seg)
    has_next = (i < n - 1) & (seg[nxt] == seg)
    prev, nxt = np.where(has_prev, prev, i), np.where(has_next, nxt, i)
    px, nx = x[prev].copy(), x[nxt].copy()
    if cyclic:
        prev[0], px[0], has_prev[0] = n - 1, x[-1] - total, True
        nxt[-1], nx[-1], has_next[-1] = 0, x[0] + total, True
    return _Sweep(x, seg, cyclic, total, prev, nxt, px, nx, has_prev, has_next)


@dataclass
class _Bracket:
    """One search over an input interval [a, b] of one driver, refined by :func:`_refine`.

    A root of quantity ``row`` of :class:`_Quantities` (its sign at ``a`` is ``sign``;
    bisection) or, with ``sign`` None, a minimum of it (golden section); found around the
    dense sample ``sample``.  :func:`_refine` sets ``x``, the refined input value, and
    :func:`_finish` ``col``, its column in the state at every refined value.
    """

    a: float
    b: float
    row: int
    sample: int
    sign: float | None = None
    x: float = math.nan
    col: int = -1
    value_row: int = -1  # a root of a quantity's slope: the quantity (:func:`_singular_slopes`)


def _refine(params: Params, driver: int, q: _Quantities, roots: list[_Bracket], mins: list[_Bracket]) -> None:
    """Vectorized bisection (sign changes) and golden-section search (minima), all in one solve per step.

    Sets each bracket's ``x``: its interval shrinks to ~1e-16 of its width's scale.  The
    roots come first in the solve's columns, then the minima, each in the order given.
    """
    ra, rb = np.array([b.a for b in roots], float), np.array([b.b for b in roots], float)
    ma, mb = np.array([b.a for b in mins], float), np.array([b.b for b in mins], float)
    rrow, mrow = np.array([b.row for b in roots], int), np.array([b.row for b in mins], int)
    rsign = np.array([b.sign for b in roots], float)
    nr, nm = len(ra), len(ma)
    g = (math.sqrt(5) - 1) / 2
    cols = np.arange(nr + 2 * nm)
    for _ in range(N_BISECT if nr + nm else 0):
        mid = 0.5 * (ra + rb)
        c, d = mb - g * (mb - ma), ma + g * (mb - ma)
        vals = q.rows(_state(params, driver, np.concatenate([mid, c, d])))
        f = vals[np.concatenate([rrow, mrow, mrow]), cols]
        same = np.sign(f[:nr]) == rsign
        ra, rb = np.where(same, mid, ra), np.where(same, rb, mid)
        fc, fd = f[nr : nr + nm], f[nr + nm :]
        left = (fc < fd) | (np.isnan(fd) & ~np.isnan(fc))
        ma, mb = np.where(left, ma, c), np.where(left, d, mb)
    for b, x in zip(roots + mins, np.concatenate([0.5 * (ra + rb), 0.5 * (ma + mb)]), strict=True):
        b.x = float(x)


#: the step, in radians (or that share of a slider's span), either side of a golden-section minimum that the parabola
#: refining it goes through (:func:`_vertices`): where the quantity is well above its rounding
VERTEX_STEP = 1e-5


def _vertices(run: _Run, mins: list[_Bracket]) -> None:
    """Each golden-section minimum's ``x`` refined from the quantity at ``x``, ``x +- h`` and ``x +- 2 h`` (where the
    five assemble): where the line through the two points on the left meets the line through the two on the right
    for a V (the second difference at ``x`` more than the rises' mean: a parabola's is 2/3 of it, a V's twice), else
    the vertex of the parabola through the middle three where the quantity is no higher there (``x`` itself where
    it is; an estimate more than ``h`` away is none).

    Golden section places a minimum only to about the square root of rounding, where the quantity is flat to
    rounding: a smooth extreme (Whitworth's pressure angle's largest, at 90.000002 deg), whose parabola's vertex is
    exact to its third derivative, or a V, as a change point's ``|cond|``, which goes as the distance to it (two modes
    cross there) but is 0 to rounding within about 1e-8 rad of it (an isosceles slider-crank's came out at 90.00000045
    and 269.9999995 deg), or a parallelogram's transmission angle at its flat position: the two lines meet at a V's
    point exactly, and at ``x`` itself for a parabola. Where the quantity at ``x`` is below 1/10 of its values ``h``
    away (a V down to 0) the parabola goes through its square, which is one then.
    """
    if not mins:
        return
    h = _vertex_step(run)
    x = np.array([b.x for b in mins])
    rows = np.array([b.row for b in mins])
    vals = _values(run, rows, np.concatenate([x + k * h for k in (-2, -1, 0, 1, 2)])).reshape(5, len(mins))
    with np.errstate(invalid="ignore"):
        touch = np.abs(vals[2]) <= 0.1 * np.minimum(np.abs(vals[1]), np.abs(vals[3]))  # a V down to 0
    f = np.where(touch[None], vals**2, vals)
    with np.errstate(divide="ignore", invalid="ignore"):
        curv = f[1] - 2 * f[2] + f[3]
        vertex = x + np.where(curv > 0, h * (f[1] - f[3]) / (2 * curv), np.nan)
        left, right = vals[1] - vals[0], vals[4] - vals[3]  # each line's rise over h
        apex = x + h * ((vals[3] - right) - (vals[1] + left)) / (left - right)  # the lines through x -+ h meet
        # a parabola's second difference is 2/3 of its one-sided rises h out, a V's twice them
        is_v = (vals[1] - 2 * vals[2] + vals[3]) > (2 / 3) * (np.abs(left) + np.abs(right))
    pick = np.where(is_v, apex, vertex)
    pick = np.where(np.abs(pick - x) <= h, pick, np.nan)
    value = _values(run, rows, pick)
    # a V's point (a change point) may be singular there: it stands; a vertex no worse than x (a tie: the estimate)
    better = np.isfinite(pick) & (is_v | (np.isfinite(value) & ~(value > vals[2])))
    for b, xb, good in zip(mins, pick, better, strict=True):
        if good:
            b.x = float(xb)
    _plateau_edges(run, [b for b, good in zip(mins, better, strict=True) if not good])


def _plateau_edges(run: _Run, mins: list[_Bracket]) -> None:
    """Golden-section minima on a stretch where the quantity is constant (a plateau, ``x`` on it) that a V rises
    from inside the bracket, moved to the plateau's edge: bisection between ``x`` and the bracket's end on the V's
    side, on whether the quantity is still the plateau's (within 1e-9 of its rise at that end), then the straight
    line through the V at :data:`VERTEX_STEP` and twice that from the edge so found, where the quantity is well
    above its rounding.

    A double parallelogram folded into a kite in its pose's mode keeps its second dyad flat over half a turn: the
    change point where that starts was put 0.05 deg into it, anywhere the quantity is 0, and so was the largest
    transmission angle, 180 deg all along (review 19b)."""
    if not mins:
        return
    x = np.array([b.x for b in mins])
    rows = np.array([b.row for b in mins])
    ends = np.array([[b.a, b.b] for b in mins])
    vals = _values(run, rows, np.concatenate([x, ends[:, 0], ends[:, 1]])).reshape(3, len(mins))
    level, rise = vals[0], np.abs(vals[1:] - vals[0])  # rise (2, B): at each end
    side = np.argmax(np.where(np.isfinite(rise), rise, -1.0), axis=0)  # the V's side: the end it rises most at
    top = rise[side, np.arange(len(mins))]
    go = np.isfinite(level) & (top > 0)
    if not go.any():
        return
    lo, hi, tol = x.copy(), ends[np.arange(len(mins)), side], 1e-9 * top
    for _ in range(N_BISECT):
        mid = 0.5 * (lo + hi)
        on = np.abs(_values(run, rows, mid) - level) <= tol  # NaN (not assembled): off the plateau
        lo, hi = np.where(on, mid, lo), np.where(on, hi, mid)
    edge = 0.5 * (lo + hi)  # to about the rounding of the quantity near the edge (1e-8 rad for a dyad's |cond|)
    step = _vertex_step(run) * np.sign(hi - lo)  # then the V's line, h and 2 h out
    w = np.abs(_values(run, rows, np.concatenate([edge + step, edge + 2 * step])) - np.tile(level, 2))
    w1, w2 = w[: len(mins)], w[len(mins) :]
    with np.errstate(invalid="ignore", divide="ignore"):
        line = edge + step - w1 * step / (w2 - w1)
    line_ok = (w1 > 0) & (w1 < w2) & (np.abs(line - edge) <= np.abs(step))
    for b, e, ln, moved, good in zip(mins, edge, line, go, line_ok, strict=True):
        if moved:
            b.x = float(ln if good else e)


def _vertex_step(run: _Run) -> float:
    """:data:`VERTEX_STEP` in the driver's input: radians for an angle, else that share of the span."""
    return VERTEX_STEP * (1.0 if run.turn else run.total)


def _values(run: _Run, rows: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Quantity ``rows[i % len(rows)]`` at each input ``x[i]`` (NaN where the mechanism does not assemble)."""
    st = run.state(x)
    cols = np.arange(len(x))
    return np.where(st.assembled, run.q.rows(st)[np.resize(rows, len(x)), cols], np.nan)


def _singular_slopes(run: _Run, roots: list[_Bracket]) -> None:
    """Roots of a quantity's slope (``roots``, each with its ``value_row``) where the bisection ended on a jump of the
    slope, not on a zero of it (the slope there not finite, or above 1e-6 of its largest over the samples), searched
    again as minima of the quantity itself (golden section, then :func:`_vertices`).

    At a change point the quantity may turn back with its slope not zero, and the rates next to it are flagged
    singular (NaN): the bisection on the slope's sign ended at the edge of that stretch. A four-bar folded flat at
    crank 0 had its transmission angle's minimum, 0 there, at -0.000035 deg, 0.0001 deg (review 19b); the quantity
    itself is defined there (a V down to 0). The new place is kept only where the quantity is lower there: where the
    bisection ended on the kink itself, it stays (a parallelogram's largest transmission angle at 180 deg exactly,
    put 1e-6 deg off by the search again: review 19e)."""
    if not roots:
        return
    slopes = _values(run, np.array([b.row for b in roots]), np.array([b.x for b in roots]))
    with np.errstate(invalid="ignore"):
        scale = [float(np.nanmax(np.abs(run.rows[b.row]), initial=0.0)) for b in roots]
    again = [b for b, f, k in zip(roots, slopes, scale, strict=True) if not abs(f) <= 1e-6 * k]
    if not again:
        return
    before = np.array([b.x for b in again])
    for b in again:
        b.row, b.sign, b.value_row = b.value_row, None, -1
    _refine(run.params, run.driver, run.q, [], again)
    _vertices(run, again)
    rows = np.array([b.row for b in again])
    old, new = _values(run, rows, np.concatenate([before, [b.x for b in again]])).reshape(2, len(again))
    for b, x, keep in zip(again, before, ~(new < old), strict=True):  # the bisection's, where it was on the kink
        if keep:
            b.x = float(x)


def _step_links(params: Params, k: int, st: _State, col: int) -> dict[str, Any]:
    """Which sign step locks at a dead point, and how (the k-th sign step, at sample ``col`` of ``st``)."""
    plan = params.plan
    names = plan.joint_names
    step: Any
    step, nums = next((s, n) for s, n in zip(plan.steps, params.steps, strict=True) if getattr(s, "sign", None) == k)
    out: dict[str, Any] = {"joint": names[step.joint]}
    if isinstance(step, Dyad):
        r1, r2 = float(nums[0][0, 0]), float(nums[1][0, 0])
        s = float(abs(st.z[step.k1, col] - st.z[step.k2, col]))
        how = "stretched" if abs(s - (r1 + r2)) <= abs(s - abs(r1 - r2)) else "folded"
        out["links"] = list(step.links)
        out["detail"] = f"{step.links[0]} and {step.links[1]} are in line at {names[step.joint]} ({how})"
    elif isinstance(step, CircleLine):
        out["links"] = [step.link, step.block]
        out["detail"] = f"{step.link} square to the line of slider {step.slider} at {names[step.joint]}"
    elif isinstance(step, CylinderDyad | CylinderLine | ActuatorDyad):
        cyl = params.plan.drivers[step.driver]
        s = float(abs(st.z[step.joint, col] - st.z[step.center if isinstance(step, CylinderLine) else step.k2, col]))
        lo, hi = _stroke_lengths(step, nums)
        other = step.block if isinstance(step, CylinderLine) else step.link
        out["links"] = [other]
        out["cylinder"] = cyl
        if math.isfinite(s) and min(abs(s - lo), abs(s - hi)) <= 1e-6 * s:
            # by length, not by which end of the stroke: an actuator's slide may point from rod to barrel
            end = "shortest" if abs(s - min(lo, hi)) <= abs(s - max(lo, hi)) else "longest"
            out["detail"] = f"cylinder '{cyl}' at the end of its stroke ({end})"
        elif isinstance(step, CylinderDyad | ActuatorDyad):
            out["detail"] = f"cylinder '{cyl}' in line with {other} at {names[step.joint]}"
        else:
            out["detail"] = f"cylinder '{cyl}' square to the line of slider {step.slider} at {names[step.joint]}"
    else:  # a guide turned about a pivot (Pivot)
        out["links"] = [getattr(step, "on", "")]
        out["detail"] = f"guide '{getattr(step, 'on', '')}' at the end of its turn ({names[step.joint]})"
    return out


def _stroke_lengths(step: CylinderDyad | CylinderLine | ActuatorDyad, nums: Any) -> tuple[float, float]:
    """The distances between a cylinder's ends at the ends of its stroke (a slider's: ``|rel0 + u d|``)."""
    lo, hi = float(nums[-2][0, 0]), float(nums[-1][0, 0])
    if not isinstance(step, ActuatorDyad):
        return lo, hi
    rel0, d = complex(nums[1][0, 0]), complex(nums[2][0, 0])
    lo_s, hi_s = (abs(rel0 + u * d) if math.isfinite(u) else math.inf for u in (lo, hi))
    return lo_s, hi_s


def _group_end(params: Params) -> dict[str, Any]:
    """The numerical group(s) whose mode ends at an end of range (no sign step is at its limit there)."""
    names = params.plan.joint_names
    groups = [st for st in params.plan.steps if isinstance(st, Group)]
    joints = [names[j] for st in groups for j in st.joints]
    links = [gl.name for st in groups for gl in st.links]
    what = "group " + ", ".join(joints) if len(groups) == 1 else "the numerical groups"
    return {
        "joints": joints,
        "links": links,
        "detail": f"{what} at a singular position (its Jacobian loses rank: the pose's mode turns back)",
    }


def _wrap(a: np.ndarray | float) -> Any:
    """An angle (rad) in (-pi, pi]."""
    return math.pi - np.mod(math.pi - np.asarray(a, float), 2 * math.pi)


def _cyc(dv: float, cyclic: bool, period: float) -> float:
    """A difference of two inputs, taken modulo the period on a full turn."""
    return float(dv - period * round(dv / period)) if cyclic else float(dv)


@dataclass
class _Run:
    """One driver's dense sweep over where it assembles, and the quantities the checks look at there.

    ``intervals`` where it assembles and ``lo``, ``hi`` its search span (radians or length
    units); ``factor`` the file unit in those; ``turn`` whether the input is an angle;
    ``sw.cyclic`` whether it assembles over the whole turn.  ``st`` and ``rows`` the state
    and :class:`_Quantities` rows at the dense samples ``sw.x``.
    """

    params: Params
    driver: int
    intervals: list[list[float]]
    factor: float
    lo: float
    hi: float
    turn: bool
    sw: _Sweep
    q: _Quantities
    st: _State
    rows: np.ndarray

    @property
    def cyclic(self) -> bool:
        return self.sw.cyclic

    @property
    def total(self) -> float:
        return self.hi - self.lo

    @property
    def tol_x(self) -> float:
        """Two refined inputs closer than this are the same point."""
        return 1e-9 * (1.0 if self.turn else self.total)

    def cyc(self, dv: float) -> float:
        return _cyc(dv, self.cyclic, self.total)

    def state(self, x: np.ndarray) -> _State:
        return _state(self.params, self.driver, x)

    def file_value(self, v: float) -> float:
        """An input in file units (on a full turn, brought into [lo, lo + total) with 0 to round-off at lo)."""
        if self.cyclic:
            v = self.lo + float(np.mod(v - self.lo, self.total))
            if min(abs(v - self.lo), abs(self.lo + self.total - v)) < 1e-13 * self.total:
                v = self.lo
        return float(v / self.factor)


def _run(
    mech: Mechanism,
    params: Params,
    driver: int,
    intervals: list[list[float]],
    loops: list[tuple[int, FourBar]],
    sliders: list[SliderLine] | None = None,
) -> _Run:
    """Sample one driver densely over ``intervals`` (:func:`_sweep`) and evaluate the checks' quantities there."""
    d = mech.drivers[driver]
    lo, hi = _span(mech, driver)
    total = hi - lo
    cyclic = d.type.cyclic and len(intervals) == 1 and intervals[0][1] - intervals[0][0] >= total * (1 - 1e-12)
    sw = _sweep(intervals, cyclic, total)
    plan = params.plan
    names = plan.joint_names
    out_links = []
    for _, lp in loops:
        j = mech.link(lp.links[2]).joints
        out_links.append((names.index(j[0]), names.index(j[1])))
    known = [(s.k1, s.k2) if isinstance(s, Dyad) else (-1, -1) for s in plan.sign_steps]
    q = _Quantities([lp for _, lp in loops], plan.n_signs, out_links, known, sliders)
    st = _state(params, driver, sw.x)
    return _Run(params, driver, intervals, d.input_scale(mech), lo, hi, d.type.cyclic, sw, q, st, q.rows(st))


def _limit_brackets(run: _Run, li: int) -> list[_Bracket]:
    """Limit positions of loop ``li``: where its rocker's angular velocity changes sign between neighbours.

    Not where it only flickers about zero while the rocker rests (both neighbours within ``REST`` of the largest
    speed: a rhombus folded into a kite holds its rocker still for half a turn, and the rounding of its speed
    changed sign at hundreds of samples).
    """
    sw, row = run.sw, run.q.w(li)
    w = run.rows[row]
    ia = np.flatnonzero(sw.has_next)
    wa, wb = w[ia], w[sw.next[ia]]
    hit = np.isfinite(wa) & np.isfinite(wb) & (wa != 0) & (np.sign(wb) != np.sign(wa))
    if hit.any():
        rest = REST * float(np.nanmax(np.abs(w)))
        hit &= (np.abs(wa) > rest) | (np.abs(wb) > rest)
    return [_Bracket(sw.x[k], sw.nx[k], row, int(k), float(np.sign(w[k]))) for k in ia[hit]]


def _around(run: _Run, i: int, row: int, slope: int) -> _Bracket:
    """A bracket over sample ``i``'s neighbours for a minimum of quantity ``row``.

    A root of ``slope`` (bisection) when that changes sign across them, i.e. a smooth
    extreme; else a golden-section search on ``row`` itself (an end of the range, or a
    minimum where ``row`` has a kink).
    """
    sw = run.sw
    sa, sb = np.sign(run.rows[slope, sw.prev[i]]), np.sign(run.rows[slope, sw.next[i]])
    if sw.has_prev[i] and sw.has_next[i] and sa * sb < 0:
        return _Bracket(sw.px[i], sw.nx[i], slope, i, float(sa), value_row=row)
    return _Bracket(sw.px[i], sw.nx[i], row, i)


def _extreme_brackets(run: _Run, li: int) -> dict[int, _Bracket]:
    """Loop ``li``'s transmission angle extremes, +1 the minimum and -1 the maximum (a minimum of -mu)."""
    out = {}
    for sgn in (1, -1):
        f = run.rows[run.q.mu(li, sgn)]
        if np.isfinite(f).any():
            out[sgn] = _around(run, int(np.nanargmin(f)), run.q.mu(li, sgn), run.q.dmu(li))
    return out


def _change_point_brackets(run: _Run) -> list[tuple[int, _Bracket]]:
    """Each sign step's |determinant| touching 0 inside the range: (sign step, bracket).

    For a circle-circle step that is where the distance s between its known joints has an
    extremum at r1 + r2 or |r1 - r2|: a simple root of ds; otherwise a minimum of |cond|.
    Where the step stays at a change point over a run of samples (a rhombus folded into a kite
    puts the next dyad's circles tangent for half a turn), only the run's two ends count.
    """
    sw, q = run.sw, run.q
    interior = sw.has_prev & sw.has_next
    out = []
    for k in range(q.n_signs):
        c = run.rows[q.cond(k)]
        with np.errstate(invalid="ignore"):
            cand = interior & (c <= c[sw.prev]) & (c <= c[sw.next]) & (c < TOUCH)
            flat = c < SINGULAR_TOL  # a step that stays at its change point (a kite's folded dyad): its two ends
            cand &= ~(flat & flat[sw.prev] & flat[sw.next])
        out += [(k, _around(run, int(i), q.cond(k), q.ds(k))) for i in np.flatnonzero(cand)]
    return out


@dataclass
class _Final:
    """The state at every refined input (columns ``0 .. ends - 1``) and at the range ends (from ``ends`` on)."""

    state: _State
    rows: np.ndarray
    phi: np.ndarray
    ends: int


def _finish(run: _Run, searched: list[_Bracket], ends: list[float]) -> _Final:
    """One solve at every refined input (setting each bracket's ``col``) and at the range ends."""
    for col, b in enumerate(searched):
        b.col = col
    fin = run.state(np.concatenate([np.array([b.x for b in searched], float), np.array(ends, float)]))
    return _Final(fin, run.q.rows(fin), run.q.out_angle(fin), len(searched))


def _end_dead_points(run: _Run, fin: _Final, ends: list[float]) -> list[tuple[float, dict[str, Any]]]:
    """The range ends as dead points, with the sign step (or numerical group) at its limit there."""
    params = run.params
    dead = []
    for m, v in enumerate(ends):
        col = fin.ends + m
        margins = fin.state.margin[:, col]
        k = int(np.nanargmin(margins)) if np.isfinite(margins).any() else 0
        info: dict[str, Any] = {"input": float(v / run.factor), "kind": "end of range"}
        if (stroke_end := _slide_stroke_end(run, v) or _group_stroke_end(run, v)) is not None:
            info.update(stroke_end)
        elif params.plan.numerical and not (np.isfinite(margins).any() and np.nanmin(margins) <= 1e-6):
            info.update(_group_end(params))
        elif params.plan.n_signs:
            info.update(_step_links(params, k, fin.state, col))
        dead.append((v, info))
    return dead


def _slide_stroke_end(run: _Run, v: float) -> dict[str, Any] | None:
    """A block pushed along a placed guide at an end of its driver's stroke there (None: not such an end)."""
    plan = run.params.plan
    found = [
        (st, nums)
        for st, nums in zip(plan.steps, run.params.steps, strict=True)
        if isinstance(st, SliderDrive) and st.driver == run.driver
    ]
    if not found:
        return None
    step, nums = found[0]
    lo, hi = float(nums[3][0, 0]), float(nums[4][0, 0])
    if not (math.isfinite(lo) and math.isfinite(hi)) or min(abs(v - lo), abs(v - hi)) > 1e-9 * max(-lo, hi):
        return None
    end = "min" if abs(v - lo) <= abs(v - hi) else "max"
    detail = f"slider driver '{plan.drivers[run.driver]}' at the end of its stroke ({end})"
    return {"links": [step.block], "detail": detail}


def _group_stroke_end(run: _Run, v: float) -> dict[str, Any] | None:
    """A cylinder driver of a numerical group at an end of its stroke there (None: not such an end)."""
    plan = run.params.plan
    for st, nums in zip(plan.steps, run.params.steps, strict=True):
        if not isinstance(st, Group):
            continue
        for i, (d, (lo_a, hi_a)) in enumerate(zip(st.input_drivers, nums[5], strict=True)):
            lo, hi = float(lo_a[0, 0]), float(hi_a[0, 0])
            if d != run.driver or min(abs(v - lo), abs(v - hi)) > 1e-9 * max(abs(v), abs(lo), abs(hi)):
                continue
            links = [gl.name for gl in st.links]
            if i < len(st.cylinders):
                end = "shortest" if abs(v - lo) <= abs(v - hi) else "longest"
                detail = f"cylinder '{plan.drivers[d]}' at the end of its stroke ({end})"
                return {"links": links, "cylinder": plan.drivers[d], "detail": detail}
            end = "min" if abs(v - lo) <= abs(v - hi) else "max"
            return {"links": links, "detail": f"slider driver '{plan.drivers[d]}' at the end of its stroke ({end})"}
    return None


def _undetermined(run: _Run) -> float | None:
    """The one input of a whole turn where the mechanism does not assemble (None where there is none): a change point
    where a dyad's two circles coincide (a rhombus's crank on its rocker's pivot), so the pose's signs leave its joint
    undetermined; the range runs from a hair past it to a hair before it (:func:`_assembly_intervals`)."""
    if not run.cyclic or not run.turn:
        return None
    (s, e), turn = run.intervals[0], run.total
    mid = 0.5 * (e + s + turn)
    if e - s >= turn or bool(_assembled(run.params, run.driver, np.array([mid]))[0]):
        return None
    return mid


def _undetermined_dead_point(run: _Run, fin: _Final, m: int, x: float) -> tuple[float, dict[str, Any]]:
    """The dead point of :func:`_undetermined` at ``x``, its links from the range's end a hair before it (column
    ``m`` of the ends in ``fin``)."""
    col = fin.ends + m
    info: dict[str, Any] = {"input": run.file_value(x), "kind": "change point"}
    q = run.q
    if len(q.k1) and (q.k1 >= 0).any():  # the dyad whose two known joints meet there
        apart = np.abs(fin.state.z[q.k1, col] - fin.state.z[q.k2, col])
        k = int(np.nanargmin(np.where(q.k1 >= 0, apart, np.inf)))
        info.update(_step_links(run.params, k, fin.state, col))
        info["detail"] += f"; {info['joint']} undetermined at this input (analyze flags it)"
    return x, info


def _change_dead_points(
    run: _Run, changes: list[tuple[int, _Bracket]], fin: _Final, ends: list[float]
) -> list[tuple[float, dict[str, Any]]]:
    """The change points, each once per sign step.

    Candidates sorted by input; a candidate within ``tol_x`` (round the turn) of one of the same step kept before
    it, or of a range end, is the same point again. Two steps that change at one input are both listed (IFToMM
    A02's two dyads at 180 deg: one of them was dropped as the other's, review 19g).
    """
    cands = sorted(
        (b.x, k, b.col)
        for k, b in changes
        if fin.state.assembled[b.col] and fin.rows[run.q.cond(k), b.col] < SINGULAR_TOL
    )
    if cands and ends:
        dist = np.abs(np.array([c[0] for c in cands])[:, None] - np.array(ends, float)[None, :])
        cands = [c for c, bad in zip(cands, dist.min(axis=1) <= run.tol_x, strict=True) if not bad]
    kept: list[tuple[float, int, int]] = []
    for c in cands:  # the same step's again (two steps that change at one input are two change points: review 19g)
        if not any(k == c[1] and abs(run.cyc(c[0] - v)) <= run.tol_x for v, k, _ in kept):
            kept.append(c)
    dead = []
    for v, k, col in kept:
        info = {"input": run.file_value(v), "kind": "change point"}
        info.update(_step_links(run.params, k, fin.state, col))
        dead.append((v, info))
    return dead


class _Limit(NamedTuple):
    """A limit position: the input (internal units), the rocker's angle (rad), ``"min"``/``"max"``, the dense sample.

    ``until``: for a dwell (a slider at rest at its extreme over an interval), the input where it moves again.
    """

    x: float
    angle: float
    extreme: str
    sample: int
    until: float | None = None


def _transmission(run: _Run, li: int, extremes: dict[int, _Bracket], fin: _Final) -> dict[str, Any]:
    """Min and max of loop ``li``'s transmission angle and where: the refined value when it is no worse."""
    return _min_max(run, {1: run.q.mu(li, 1), -1: run.q.mu(li, -1)}, extremes, fin)


def _min_max(run: _Run, rows: dict[int, int], extremes: dict[int, _Bracket], fin: _Final) -> dict[str, Any]:
    """``min``, ``max`` and where (``min_at``, ``max_at``) of a quantity: ``rows[1]`` it, ``rows[-1]`` its negative."""
    ta: dict[str, Any] = {}
    for sgn, b in extremes.items():
        key, row = ("min" if sgn > 0 else "max"), rows[sgn]
        best_x, best = run.sw.x[b.sample], run.rows[row, b.sample]
        if np.isfinite(fin.rows[row, b.col]) and fin.rows[row, b.col] <= best + 1e-12:
            best_x, best = b.x, fin.rows[row, b.col]
        ta[key] = float(sgn * best)
        ta[f"{key}_at"] = run.file_value(float(best_x))
    return ta


def _limits(run: _Run, li: int, brackets: list[_Bracket], fin: _Final) -> list[_Limit]:
    """Refined roots of the rocker's angular velocity, kept when the root is a true zero, sorted by input."""
    w_dense = run.rows[run.q.w(li)]
    scale = float(np.nanmax(np.abs(w_dense))) if np.isfinite(w_dense).any() else 1.0
    limits: list[_Limit] = []
    for b in brackets:
        if not (abs(fin.rows[b.row, b.col]) <= 1e-6 * scale):
            continue
        if any(abs(run.cyc(b.x - lim.x)) <= run.tol_x for lim in limits):
            continue
        extreme = "max" if b.sign is not None and b.sign > 0 else "min"
        limits.append(_Limit(b.x, float(fin.phi[li, b.col]), extreme, b.sample))
    limits.sort(key=lambda t: run.file_value(t.x))
    return limits


def _swing(run: _Run, li: int, found: tuple[list[_Limit], list[_Bracket]], fin: _Final, unit: float) -> dict[str, Any]:
    """Whether the rocker turns fully and, if not, its swing over the range (one interval), unwrapped: from its
    extremes among its limit positions (``found[0]``), the change points (``found[1]``: there it may turn back with
    its angular velocity not zero, a change-point four-bar's at its flat position), the range's ends and the
    samples."""
    phi = run.q.out_angle(run.st)[li]
    if len(run.intervals) != 1 or not np.isfinite(phi).all():
        return {}
    u = np.unwrap(phi)
    turns = run.cyclic and abs(u[-1] - u[0] + _wrap(phi[0] - phi[-1])) > math.pi
    if turns:
        return {"rocker_turns_fully": True}
    limits, changes = found
    at = [(lim.sample, lim.angle) for lim in limits]
    at += [(b.sample, fin.phi[li, b.col]) for b in changes if b.col >= 0 and np.isfinite(fin.phi[li, b.col])]
    cand = [u[k] + _wrap(angle - phi[k]) for k, angle in at] + [float(np.min(u)), float(np.max(u))]
    if not run.cyclic:
        e_cols = list(range(fin.ends, fin.phi.shape[1]))
        cand += [u[0] + _wrap(fin.phi[li, c] - phi[0]) for c in e_cols[:1]]
        cand += [u[-1] + _wrap(fin.phi[li, c] - phi[-1]) for c in e_cols[1:2]]
    return {"rocker_turns_fully": False, "swing": float((max(cand) - min(cand)) / unit)}


def _moves_on(t: _Limit) -> float:
    """Where the output leaves a limit position: the end of its dwell, or the limit position itself."""
    return t.x if t.until is None else t.until


def _time_ratio(run: _Run, limits: list[_Limit]) -> dict[str, Any]:
    """Over a full turn with one limit position each way: the input's travel each way and their ratio.

    A dwell (a slider at rest at an extreme) counts in neither travel.
    """
    if not (run.cyclic and len(limits) == 2 and {t.extreme for t in limits} == {"min", "max"}):
        return {}
    vmin = next(t for t in limits if t.extreme == "min")
    vmax = next(t for t in limits if t.extreme == "max")
    rising = float(np.mod(vmax.x - _moves_on(vmin), run.total))
    falling = run.total - rising - sum(float(np.mod(_moves_on(t) - t.x, run.total)) for t in (vmin, vmax))
    rest = run.total - rising - falling
    return {
        "strokes": {"rising": rising / run.factor, "falling": falling / run.factor}
        | ({"rest": rest / run.factor} if rest else {}),
        "time_ratio": max(rising, falling) / min(rising, falling) if min(rising, falling) > 0 else None,
    }


def _driver_checks(
    mech: Mechanism,
    params: Params,
    driver: int,
    intervals: list[list[float]],
    loops: list[tuple[int, FourBar]],
    sliders: list[SliderLine] | None = None,
) -> tuple[list[dict[str, Any]], dict[int, dict[str, Any]], list[dict[str, Any]]]:
    """Dead points of one driver's input, and the facts of its loops and sliders.

    ``intervals`` where it assembles, in radians or length units (:func:`_assembly_intervals`);
    ``loops`` the (index, loop) pairs this driver sweeps, ``sliders`` the sliders on the
    frame.  Returns (dead points, {loop index: facts}, [slider facts]), every value in file
    units.  Every bracket is refined in one vectorized search (:func:`_refine`), then solved
    once more (:func:`_finish`).
    """
    if not intervals:
        return [], {}, []
    run = _run(mech, params, driver, intervals, loops, sliders)
    limits = [_limit_brackets(run, li) for li in range(run.q.n)]
    extremes = [_extreme_brackets(run, li) for li in range(run.q.n)]
    slides = [_slider_brackets(run, k) for k in range(len(run.q.sliders))]
    changes = _change_point_brackets(run)
    ordered = [
        *(b for bs in limits for b in bs),
        *(b for e in extremes for b in e.values()),
        *(b for bs, _ in slides for b in bs),
        *(b for _, e in slides for b in e.values()),
        *(b for _, b in changes),
    ]
    roots, mins = [b for b in ordered if b.sign is not None], [b for b in ordered if b.sign is None]
    _refine(params, driver, run.q, roots, mins)
    _vertices(run, mins)
    _singular_slopes(run, [b for b in roots if b.value_row >= 0])
    # the range ends (not the artificial ends of a slider's search span) are dead points
    ends = [] if run.cyclic else [v for s, e in intervals for v in (s, e) if run.lo < v < run.hi or run.turn]
    if run.cyclic and beyond_a_turn(intervals[0], run.hi - run.lo):  # a mode longer than a turn that does not
        ends = list(intervals[0])  # close ends at a fold each way
    hole = _undetermined(run)
    near_hole = [] if hole is None else list(intervals[0])  # a hair either side of it
    fin = _finish(run, roots + mins, ends + near_hole[1:])
    dead = _end_dead_points(run, fin, ends) + _change_dead_points(run, changes, fin, ends + near_hole)
    if hole is not None:
        dead.append(_undetermined_dead_point(run, fin, len(ends), hole))
    dead.sort(key=lambda t: t[1]["input"])
    crossed = [b for _, b in changes]
    facts = {
        index: _loop_facts(run, mech, li, lp, (limits[li], extremes[li], crossed), fin)
        for li, (index, lp) in enumerate(loops)
    }
    slider_facts = [_slider_facts(run, mech, k, (*slides[k], crossed), fin) for k in range(len(run.q.sliders))]
    return [info for _, info in dead], facts, slider_facts


def _loop_facts(
    run: _Run,
    mech: Mechanism,
    li: int,
    lp: FourBar,
    found: tuple[list[_Bracket], dict[int, _Bracket], list[_Bracket]],
    fin: _Final,
) -> dict[str, Any]:
    """Transmission angle, limit positions, swing and time ratio of loop ``li``, and whether its input link turns;
    ``found``: the loop's limit positions and transmission extremes, and the change points of the mechanism."""
    limits, extremes, changes = found
    out: dict[str, Any] = {}
    ta = _transmission(run, li, extremes, fin)
    if "min" in ta and "max" in ta:
        worst = min(ta["min"], 180.0 - ta["max"])
        out["transmission_angle"] = ta | {"joint": run.params.plan.joint_names[lp.rocker_tip], "worst": worst}
    lims = _limits(run, li, limits, fin)
    out["limit_positions"] = [
        {"input": run.file_value(t.x), "angle": float(_wrap(t.angle) / mech.angle_to_rad), "extreme": t.extreme}
        for t in lims
    ]
    turns = _turns_fully(run, np.angle(run.st.z[lp.crank_tip] - run.st.z[lp.crank_pivot]))
    out["input_turns_fully"] = turns
    return out | _swing(run, li, (lims, changes), fin, mech.angle_to_rad) | _time_ratio(run, lims)


def _turns_fully(run: _Run, angle: np.ndarray) -> bool:
    """Whether a link at ``angle`` (rad, at the dense samples) turns through a full turn over the driver's turn."""
    if not run.cyclic or not np.isfinite(angle).all():
        return False
    u = np.unwrap(angle)
    return bool(abs(u[-1] - u[0] + _wrap(angle[0] - angle[-1])) > math.pi)


def _slider_brackets(run: _Run, k: int) -> tuple[list[_Bracket], dict[int, _Bracket]]:
    """Slider ``k``'s limit positions (its velocity changes sign between moving samples) and its pressure angle's
    extremes.  Where it rests (:func:`_resting`) the sign of its velocity is rounding: :func:`_dwells` says those."""
    sw, row = run.sw, run.q.sv(k)
    v = run.rows[row]
    moving = ~_resting(run, run.q.position(run.st)[k])
    ia = np.flatnonzero(sw.has_next & moving & moving[sw.next])
    va, vb = v[ia], v[sw.next[ia]]
    hit = np.isfinite(va) & np.isfinite(vb) & (va != 0) & (np.sign(vb) != np.sign(va))
    limits = [_Bracket(sw.x[i], sw.nx[i], row, int(i), float(np.sign(v[i]))) for i in ia[hit]]
    extremes = {}
    for sgn in (1, -1):
        f = run.rows[run.q.pa(k, sgn)]
        if np.isfinite(f).any():
            i = int(np.nanargmin(f))
            extremes[sgn] = _Bracket(sw.px[i], sw.nx[i], run.q.pa(k, sgn), i)
    return limits, extremes


def _slider_facts(
    run: _Run,
    mech: Mechanism,
    k: int,
    found: tuple[list[_Bracket], dict[int, _Bracket], list[_Bracket]],
    fin: _Final,
) -> dict[str, Any]:
    """Slider ``k``'s stroke, limit positions, time ratio and pressure angle over the driver's range; ``found``: its
    limit positions' and pressure angle's brackets, and the mechanism's change points (a slider may turn back at one
    with its speed not zero: an offset slider-crank's stroke was short of it by 3e-8, review 19e).

    Positions are measured along the slider's line from the pose's position (file length unit).
    """
    limits, extremes, changes = found
    sl, q = run.q.sliders[k], run.q
    names = run.params.plan.joint_names
    origin = float((mech.joints[names[sl.joint]] * np.conj(sl.direction)).real)
    dense, refined = q.position(run.st)[k] - origin, q.position(fin.state)[k] - origin
    v_dense = run.rows[q.sv(k)]
    scale = float(np.nanmax(np.abs(v_dense))) if np.isfinite(v_dense).any() else 1.0
    lims: list[_Limit] = []
    for b in limits:
        if abs(fin.rows[b.row, b.col]) <= 1e-6 * scale and not any(abs(run.cyc(b.x - t.x)) <= run.tol_x for t in lims):
            lims.append(
                _Limit(b.x, float(refined[b.col]), "max" if b.sign is not None and b.sign > 0 else "min", b.sample)
            )
    lims += _dwells(run, k, origin)
    lims.sort(key=lambda t: run.file_value(t.x))
    at_changes = [(b.x, refined[b.col]) for b in changes if b.col >= 0 and np.isfinite(refined[b.col])]
    cand = np.concatenate([dense[np.isfinite(dense)], [t.angle for t in lims], [p for _, p in at_changes]])
    out: dict[str, Any] = {
        "slider": sl.index,
        "link": sl.link,
        "joint": names[sl.joint],
        "driver": mech.drivers[run.driver].name,
        "stroke": float(np.ptp(cand)) if cand.size else None,
        "limit_positions": [_slider_limit(run, t) for t in lims],
    }
    out |= _pose_stroke(run, dense, [(t.x, t.angle) for t in lims] + at_changes)
    ratio = _time_ratio(run, lims)
    if ratio:
        out["input_travel"], out["time_ratio"] = ratio["strokes"], ratio["time_ratio"]
    if sl.rod:
        pa = _min_max(run, {1: q.pa(k, 1), -1: q.pa(k, -1)}, extremes, fin)
        if "max" in pa:
            out["pressure_angle"] = pa | {"rod": sl.rod}
    return out


def _pose_stroke(run: _Run, dense: np.ndarray, refined: list[tuple[float, float]]) -> dict[str, Any]:
    """``{"pose_stroke": ...}``: with several intervals in the range, the stroke over the one that holds the pose (the
    dense positions ``dense`` and the ``(input, position)`` pairs ``refined`` inside it): the whole stroke spans the
    others too, which the pose cannot reach (a crank longer than its rod: 4.86 m, where the pose's travels 1.46;
    review 19e). Nothing with one interval."""
    if len(run.intervals) < 2:
        return {}
    x0 = float(run.params.pose_inputs[run.driver, 0])
    period = 2 * math.pi if run.turn else math.inf

    def within(v: Any, s: float, e: float) -> Any:  # (an angle a whole number of turns along)
        v = s + np.mod(np.asarray(v, float) - s, period) if math.isfinite(period) else np.asarray(v, float)
        return (s - run.tol_x <= v) & (v <= e + run.tol_x)

    k = next((i for i, (s, e) in enumerate(run.intervals) if within(x0, s, e)), None)
    if k is None:
        return {}
    s, e = run.intervals[k]
    mask = within(run.sw.x, s, e) & np.isfinite(dense)
    cand = np.concatenate([dense[mask], [p for v, p in refined if within(v, s, e)]])
    return {"pose_stroke": float(np.ptp(cand))} if cand.size else {}


def _slider_limit(run: _Run, t: _Limit) -> dict[str, Any]:
    """A slider's limit position as the JSON gives it (a dwell with ``until``, where the slider moves again)."""
    out = {"input": run.file_value(t.x), "position": t.angle, "extreme": t.extreme}
    return out if t.until is None else out | {"until": run.file_value(t.until)}


def _resting(run: _Run, p: np.ndarray) -> np.ndarray:
    """Which dense samples rest: in a run of two or more sample steps over which the position ``p`` (n,) moves
    less than :data:`DWELL` of its range (one such step alone is two samples either side of a smooth extreme)."""
    sw = run.sw
    finite = p[np.isfinite(p)]
    tol = DWELL * float(np.ptp(finite)) if finite.size else 0.0
    still = sw.has_next & (np.abs(p[sw.next] - p) <= tol)  # the step from each sample to its next
    held = still & still[sw.prev] & sw.has_prev  # the step before it too: two in a row
    rest: np.ndarray = held.copy()
    rest[sw.prev[held]] = True
    rest[sw.next[held]] = True
    return rest


def _runs(run: _Run, rest: np.ndarray) -> list[np.ndarray]:
    """The dense samples of each segment in order (a full turn: one, starting at a sample that does not rest)."""
    sw = run.sw
    if sw.cyclic:
        moving = np.flatnonzero(~rest)
        return [np.roll(np.arange(len(sw.x)), -int(moving[0]))] if moving.size else []
    return [np.flatnonzero(sw.seg == s) for s in np.unique(sw.seg)]


def _dwells(run: _Run, k: int, origin: float) -> list[_Limit]:
    """Slider ``k`` at rest at an extreme: a run of resting samples between motions in opposite directions.

    One limit position each, at the rest's position (the median there, from ``origin``), from the input where
    it arrives to the one where it leaves (``until``), each refined by bisection to where the position comes
    within :data:`DWELL` of its range of the rest's.  Rests at a range's end, or between motions in one
    direction, are no extremes.
    """
    sw, p = run.sw, run.q.position(run.st)[k]
    rest = _resting(run, p)
    v = run.rows[run.q.sv(k)]
    way = np.where(~rest & np.isfinite(v), np.sign(v), 0.0)
    found: list[tuple[int, int, float, float]] = []  # first, last dense sample, rest position, way before
    for order in _runs(run, rest):
        r = rest[order].astype(int)
        edges = np.flatnonzero(np.diff(np.concatenate([[0], r, [0]])))
        for a, b in zip(edges[::2], edges[1::2] - 1, strict=True):
            before, after = way[order[:a]], way[order[b + 1 :]]
            if sw.cyclic:  # on the turn, what comes after the run comes before it too
                before = after = np.concatenate([after, before])
            sb, sa = before[before != 0], after[after != 0]
            if sb.size and sa.size and sb[-1] * sa[0] < 0:
                found.append((int(order[a]), int(order[b]), float(np.median(p[order[a : b + 1]])), sb[-1]))
    if not found:
        return []
    first, last, at = (np.array([f[i] for f in found]) for i in range(3))
    tol = DWELL * float(np.ptp(p[np.isfinite(p)]))
    arrive = _rest_edge(run, k, sw.px[first], sw.x[first], at, tol)
    leave = _rest_edge(run, k, sw.nx[last], sw.x[last], at, tol)
    return [
        _Limit(float(arrive[i]), f[2] - origin, "max" if f[3] > 0 else "min", f[0], float(leave[i]))
        for i, f in enumerate(found)
    ]


def _rest_edge(run: _Run, k: int, moving: np.ndarray, resting: np.ndarray, at: np.ndarray, tol: float) -> np.ndarray:
    """Bisection between inputs where slider ``k`` moves and where it rests at position ``at``: the input
    nearest the moving side where its position is within ``tol`` of ``at`` (one solve a step for all)."""
    a, b = np.array(moving, float), np.array(resting, float)
    for _ in range(N_BISECT):
        mid = 0.5 * (a + b)
        near = np.abs(run.q.position(run.state(mid))[k] - at) <= tol
        a, b = np.where(near, a, mid), np.where(near, mid, b)
    return b


def transmission_angle(
    mech: Mechanism, fb: FourBar, ranges: list[list[float]], n: int = 7201, params: Params | None = None
) -> dict[str, float]:
    """Min and max (degrees) of the angle between coupler and rocker at their joint, over the range.

    ``ranges`` in file units of the loop's driver (the first driver when the loop names none).
    ``n`` is kept for compatibility: the sampling is :data:`N_COARSE` per full input range.
    """
    params = prepare(mech) if params is None else params
    driver = fb.driver if fb.driver is not None else 0
    factor = mech.drivers[driver].input_scale(mech)
    intervals = [[s * factor, e * factor] for s, e in ranges]
    _, facts, _ = _driver_checks(mech, params, driver, intervals, [(0, fb)])
    ta = facts.get(0, {}).get("transmission_angle", {})
    return {"min": ta["min"], "max": ta["max"]} if ta else {}


# ---------------------------------------------------------------------- kinetostatics
#: the most samples of a file's sweep that ``check`` evaluates (its peak loads and the change points crossed along
#: it): the picture commands' and ``analyze``'s cap on the command line; a longer sweep is reported as not computed
MAX_SWEEP_SAMPLES = 100_000
#: the cap on the peak loads' sweep (:data:`MAX_SWEEP_SAMPLES`)
MAX_DYNAMICS_SAMPLES = MAX_SWEEP_SAMPLES


def _too_many_samples(mech: Mechanism) -> str | None:
    """Why ``check`` does not evaluate the file's sweep (too many samples), or None."""
    n = mech.drivers[0].sweep.count()
    if n > MAX_SWEEP_SAMPLES:
        return f"the file's sweep has {n} samples, more than check evaluates ({MAX_SWEEP_SAMPLES})"
    return None


def peak_loads(mech: Mechanism, params: Params | None = None) -> dict[str, Any]:
    """Peak driver torque (force for a slider driver) and peak bearing load over the file's sweep.

    Solved by :func:`linkagekit.analyze` on the file's default sweep at the file's input
    speeds and accelerations.  Every peak is the sample of largest magnitude, with the
    input values there (file units); a bearing load is the magnitude of a joint reaction
    (for a slider, the normal force of the guide on the block), in N.  A driver's peak also
    carries ``toggle``: how near the mechanism is to a toggle there (:func:`toggle_at`).
    """
    n = mech.drivers[0].sweep.count()
    out: dict[str, Any] = {
        "samples": n,
        "speeds": {d.name: float(d.speed) for d in mech.drivers},
        "accelerations": {d.name: float(d.acceleration) for d in mech.drivers},
    }
    skipped = _too_many_samples(mech)
    if skipped:
        out["skipped"] = skipped
        return out
    res = analyze(mech)
    f = res.forces
    if f is None:  # pragma: no cover - has_dynamics guarantees forces
        return out
    inputs = {k: np.broadcast_to(np.asarray(v, float), (res.n_samples,)) for k, v in res.inputs.items()}

    def at(i: int) -> dict[str, float]:
        return {k: float(v[i]) for k, v in inputs.items()}

    params = prepare(mech) if params is None else params
    for key, efforts in (("peak_driver_torque", f.driver_torque), ("peak_driver_force", f.driver_force)):
        peaks = {}
        for name, arr in efforts.items():
            a = np.asarray(arr, float)
            if np.isfinite(a).any():
                i = int(np.nanargmax(np.abs(a)))
                peaks[name] = {"value": float(a[i]), "at": at(i)} | _toggle_entry(mech, params, at(i))
        if peaks:
            out[key] = peaks
    if f.reactions:
        out |= _peak_bearing(f.reactions, at)
    out["assembled"] = int(np.sum(res.assembled))
    return out


def _peak_bearing(reactions: Any, at: Any) -> dict[str, Any]:
    """The largest joint reaction over the samples (``peak_bearing_load``), if any is finite."""
    mags = np.array([np.asarray(r.magnitude, float) for r in reactions])
    if not np.isfinite(mags).any():
        return {}
    k, i = divmod(int(np.nanargmax(mags)), mags.shape[1])
    r = reactions[k]
    return {
        "peak_bearing_load": {
            "value": float(mags[k, i]),
            "joint": r.joint,
            "on": r.on,
            "by": r.by,
            "kind": "slider" if r.moment is not None else "pin",
            "at": at(i),
        }
    }


def _toggle_entry(mech: Mechanism, params: Params, at: Mapping[str, float]) -> dict[str, Any]:
    tg = toggle_at(mech, at, params)
    return {"toggle": tg} if tg else {}


def toggle_at(mech: Mechanism, at: Mapping[str, float], params: Params | None = None) -> dict[str, Any] | None:
    """How near the mechanism is to a toggle at the inputs ``at`` (file units): the worst sign step there.

    Returns ``{"angle", "joint", "links", "detail"}``: ``angle`` (degrees) is the arcsine of
    the sign step's dimensionless determinant (for two links meeting at a joint, the angle
    between them, folded to [0, 90]: 0 when they are in line, where the drivers' effort has
    no bound); the other fields name the step as a dead point does.  None without sign steps
    or where the mechanism does not assemble.
    """
    params = prepare(mech) if params is None else params
    if not params.plan.n_signs:
        return None
    q = np.array([[[float(at[d.name]) * d.input_scale(mech)]] for d in mech.drivers])
    pos = solve(params, q)
    if not bool(pos.assembled[0, 0]):
        return None
    zero = np.zeros((len(mech.drivers), 1, 1))
    rt = solve_rates(params, pos, zero, zero, tol=0.0)
    cond = np.abs(rt.condition[: params.plan.n_signs, 0])
    k = int(np.nanargmin(cond[:, 0]))
    v = pos.z[:, 0]
    st = _State(pos.assembled[0], v, v, v, cond, pos.margin[:, 0])
    angle = math.degrees(math.asin(min(float(cond[k, 0]), 1.0)))
    return {"angle": angle} | _step_links(params, k, st, 0)


# ---------------------------------------------------------------------- the report
@dataclass(frozen=True)
class CheckReport:
    """What ``linkagekit check`` reports (file units; transmission angles in degrees).

    Every input value is in the file's units of its driver (``input_units``); a report reads
    like a mapping too (``report["grashof"]``, the keys of :meth:`to_dict`).

    Attributes
    ----------
    name : str
        The mechanism's name.
    dof : int
        Its degrees of freedom (the number of drivers it needs).
    drivers : tuple of str
        The driver names, in the file's order.
    plan : tuple of str
        The solve plan, one numbered step a line (:meth:`Plan.describe`).
    signs : dict of str to dict
        For each joint placed by a sign step, the reference pose's ``{"sign": +1 or -1,
        "rule": what the sign means}``.
    mirror_links : tuple of str
        The links of three or more joints whose mirror image is a choice (``modes --mirrors``).
    input_ranges : dict of str to list of [float, float]
        For each driver the ``[start, stop]`` intervals where the mechanism assembles, the
        other drivers held at their pose values (``held_at``); with numerical groups, where
        the pose's mode goes on (by continuation).  An angle's intervals lie in [0, 360)
        degrees, one through 0 starting at a negative value (:func:`input_range`).
    units : dict of str to str
        The file's ``{"length": unit, "angle": unit}``.
    grashof, grashof_detail : str or None
        The Grashof class of the first four-bar loop (:func:`grashof`), and its finer
        description; None without a loop.
    fourbar : dict or None
        The first loop's ``{"joints": [O2, A, B, O4], "lengths": {"ground", "crank",
        "coupler", "rocker"}}``; None without a loop.
    transmission_angle : dict of str to float or None
        The first loop's transmission angle ``{"min", "max"}`` in degrees, when a driver
        sweeps it.
    fourbars : tuple of dict
        Every four-bar loop (:func:`fourbar_loops`): ``joints``, ``lengths``, ``links``,
        ``grashof``, ``grashof_detail``, ``input`` (its input link, driver and what moves
        it) and, when one driver sweeps it, ``transmission_angle`` (``min``, ``min_at``,
        ``max``, ``max_at``, ``joint``), ``limit_positions`` (each ``input``, the rocker's
        ``angle``, ``extreme``), ``rocker_turns_fully``, ``swing``, and over a full turn
        ``strokes`` and ``time_ratio``.
    dead_points : dict of str to list of dict
        For each driver the input values where the mechanism locks, sorted: each
        ``{"input", "kind": "end of range" or "change point"}`` with the step at its limit
        there (``"joint"``, ``"links"``, ``"detail"``; ``"joints"`` for a numerical group).
    held_at : dict of str to dict of str to float
        For each driver, the other drivers' pose values it was swept with.
    input_units : dict of str to str
        Each driver's input unit (``"deg"``, ``"mm"``, ...).
    pose_input : dict of str to float
        Each driver's input at the reference pose, in its input unit.
    dynamics : dict or None
        With masses, gravity or loads, the peak loads over the file's sweep
        (:func:`peak_loads`); else None.
    closed_form_joints, numerical_joints : tuple of str
        The joints placed in closed form, and those placed by numerical groups (Newton
        continued from the pose; then :meth:`to_dict`'s ``solvable`` is ``"numerical"``).
    sliders : tuple of dict
        For each slider on the frame that a driver moves (:func:`slider_lines`), per driver:
        ``slider`` (its index), ``link``, ``joint``, ``driver``, ``stroke`` (the length of
        the slide its joint travels over the driver's range), ``limit_positions`` (each
        ``input``, ``position`` along the line from the pose's, ``extreme``), over a full
        turn with two limit positions ``input_travel`` (``rising``, ``falling``: the input's
        travel while the position increases, decreases) and ``time_ratio`` (the larger over
        the smaller), and with a rod ``pressure_angle`` (``min``, ``max``, ``min_at``,
        ``max_at``, ``rod``: degrees between the rod and the line of the slide).
    assembly_gaps : dict of str to list of [float, float]
        For each angle driver the open intervals of the turn where it does not assemble
        (the complement of ``input_ranges``, each starting in [0, 1 turn)).
    reached_twice : dict of str to dict
        For an angle driver whose range is longer than a turn (a numerical group's mode that
        does not close), the directions reached twice (``from``, ``to``) and where a sweep of
        directions jumps between their two configurations (``jumps``, :func:`direction_jumps`).
    change_points : tuple of dict
        The change points the branch crosses along the file's sweep when it is followed
        continuously (``analyze --branch continuous``), from the pose's input up and down:
        each ``{"joint", "driver", "input"}`` (the sign step's joint, the driver the sweep
        follows, its input there in the file's unit, to about 1e-6 degree); None when the
        sweep has more than :data:`MAX_SWEEP_SAMPLES` samples or is too long to follow (more than
        :data:`linkagekit.branch.MAX_PATH` steps).
    change_points_skipped : str or None
        Why ``change_points`` is None (in :meth:`to_dict` only then).
    warnings : tuple of dict
        ``kind`` ``"transmission-angle"`` (a loop's ``min`` below ``limit``,
        :data:`MIN_TRANSMISSION`, or its ``max`` above 180 - ``limit``) or ``"toggle"`` (a
        driver's peak effort at a sample within ``limit`` degrees, :data:`TOGGLE_ANGLE`, of a
        toggle; with the peak's fields).
    """

    name: str
    dof: int
    drivers: tuple[str, ...]
    plan: tuple[str, ...]
    signs: dict[str, dict[str, Any]]
    mirror_links: tuple[str, ...]
    input_ranges: dict[str, list[list[float]]]
    units: dict[str, str]
    grashof: str | None = None
    grashof_detail: str | None = None
    fourbar: dict[str, Any] | None = None
    transmission_angle: dict[str, float] | None = None
    fourbars: tuple[dict[str, Any], ...] = ()
    dead_points: dict[str, list[dict[str, Any]]] = field(default_factory=dict)
    held_at: dict[str, dict[str, float]] = field(default_factory=dict)
    input_units: dict[str, str] = field(default_factory=dict)
    pose_input: dict[str, float] = field(default_factory=dict)
    dynamics: dict[str, Any] | None = None
    closed_form_joints: tuple[str, ...] = ()
    numerical_joints: tuple[str, ...] = ()
    sliders: tuple[dict[str, Any], ...] = ()
    assembly_gaps: dict[str, list[list[float]]] = field(default_factory=dict)
    reached_twice: dict[str, dict[str, Any]] = field(default_factory=dict)
    warnings: tuple[dict[str, Any], ...] = ()
    change_points: tuple[dict[str, Any], ...] | None = ()
    change_points_skipped: str | None = None

    @property
    def input_range(self) -> list[list[float]]:
        """The first driver's entry of :attr:`input_ranges`."""
        return self.input_ranges[self.drivers[0]]

    def to_dict(self) -> dict[str, Any]:
        """The JSON of ``linkagekit check --format json``."""
        out: dict[str, Any] = {
            "format": "linkagekit-check/1",
            "name": self.name,
            "dof": self.dof,
            "drivers": list(self.drivers),
            "solvable": "numerical" if self.numerical_joints else "closed-form",
            "closed_form_joints": list(self.closed_form_joints),
            "numerical_joints": list(self.numerical_joints),
            "plan": list(self.plan),
            "signs": self.signs,
            "mirror_links": list(self.mirror_links),
            "input_range": self.input_range,
            "input_ranges": self.input_ranges,
            "held_at": self.held_at,
            "input_units": self.input_units,
            "pose_input": self.pose_input,
            "units": self.units,
            "dead_points": self.dead_points,
        }
        if self.grashof is not None:
            out["grashof"] = self.grashof
            out["grashof_detail"] = self.grashof_detail
            out["fourbar"] = self.fourbar
        if self.transmission_angle:
            out["transmission_angle"] = self.transmission_angle
        out["fourbars"] = list(self.fourbars)
        if self.dynamics is not None:
            out["dynamics"] = self.dynamics
        out["sliders"] = list(self.sliders)
        out["assembly_gaps"] = self.assembly_gaps
        if self.reached_twice:
            out["reached_twice"] = self.reached_twice
        out["change_points"] = None if self.change_points is None else list(self.change_points)
        if self.change_points_skipped:
            out["change_points_skipped"] = self.change_points_skipped
        out["warnings"] = list(self.warnings)
        finite: dict[str, Any] = _finite(out)
        return finite

    def __getitem__(self, key: str) -> Any:
        """Dictionary-style access to :meth:`to_dict` (``report["grashof"]``)."""
        return self.to_dict()[key]

    def text(self) -> str:
        """The plain-text report of ``linkagekit check``."""
        return check_text(self.to_dict())


def _finite(obj: Any) -> Any:
    """``obj`` with every non-finite float replaced by None (JSON without NaN)."""
    if isinstance(obj, dict):
        return {k: _finite(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_finite(v) for v in obj]
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def _loop_entry(mech: Mechanism, names: tuple[str, ...], lp: FourBar, facts: dict[str, Any]) -> dict[str, Any]:
    """An entry of ``CheckReport.fourbars``: joints, lengths, links, Grashof type and input of a loop, and ``facts``."""
    kind, detail = grashof(lp)
    if lp.links[0] not in {d.link for d in mech.drivers} and "input_turns_fully" in facts:
        detail = _moved_loop_detail(lp, kind, detail, facts["input_turns_fully"])
    entry: dict[str, Any] = {
        "joints": [names[lp.crank_pivot], names[lp.crank_tip], names[lp.rocker_tip], names[lp.rocker_pivot]],
        "lengths": {"ground": lp.ground, "crank": lp.crank, "coupler": lp.coupler, "rocker": lp.rocker},
        "links": {"ground": "ground", "crank": lp.links[0], "coupler": lp.links[1], "rocker": lp.links[2]},
        "grashof": kind,
        "grashof_detail": detail,
        "input": {
            "link": lp.links[0],
            "driver": mech.drivers[lp.driver].name if lp.driver is not None else None,
            "moved_by": lp.moved_by,
        },
    }
    return entry | facts


def _moved_loop_detail(lp: FourBar, kind: str, detail: str, turns: bool) -> str:
    """The Grashof description of a loop whose input link is moved by the rest of the mechanism, not a driver.

    Its lengths say what its input side could do; what it does is what the mechanism makes it
    do: ``turns`` whether it turns fully over the driver's sweep.
    """
    by_lengths = {
        "crank": "crank-rocker by its lengths (the input side is the shortest link)",
        "rocker": "rocker-crank by its lengths (the output side is the shortest link)",
        "ground": "double crank by its lengths (the ground is the shortest link)",
    }
    lengths = {"ground": lp.ground, "crank": lp.crank, "coupler": lp.coupler, "rocker": lp.rocker}
    shortest = min(lengths, key=lambda k: lengths[k])
    base = by_lengths.get(shortest, detail) if kind in ("crank-rocker", "double-crank") else detail
    motion = "turns fully" if turns else "only rocks"
    return f"{base}; its input link '{lp.links[0]}' {motion} here"


def _first_loop(entries: list[dict[str, Any]]) -> dict[str, Any]:
    """The first loop's fields of :class:`CheckReport` (``grashof``, ``fourbar``, ...), none without a loop."""
    if not entries:
        return {}
    first = entries[0]
    out = {
        "grashof": first["grashof"],
        "grashof_detail": first["grashof_detail"],
        "fourbar": {"joints": first["joints"], "lengths": first["lengths"]},
    }
    ta = first.get("transmission_angle")
    if ta:
        out["transmission_angle"] = {"min": ta["min"], "max": ta["max"]}
    return out


@one_blas_thread
def check(mech: Mechanism) -> CheckReport:
    """Freedom, solve plan, assembly range, dead points, four-bar loops and peak loads of a mechanism.

    Parameters
    ----------
    mech : Mechanism

    Returns
    -------
    CheckReport
        Every input value in the file's units: for each driver (the others held at their
        pose values) the intervals where the mechanism assembles and its dead points; for
        every four-bar loop its lengths, Grashof type and, when a driver sweeps it, the
        transmission angle, the limit positions of its rocker, the rocker's swing and the
        time ratio; with masses, gravity or loads, the peak driver effort and bearing load.
    """
    params = prepare(mech)
    plan = params.plan
    names = plan.joint_names
    factors = [d.input_scale(mech) for d in mech.drivers]
    internal = [_assembly_intervals(mech, i, params) for i in range(len(mech.drivers))]
    pose_values = {d.name: float(params.pose_inputs[i, 0] / factors[i]) for i, d in enumerate(mech.drivers)}
    loops = fourbar_loops(mech, params)
    dead, facts, sliders = _sweep_drivers(mech, params, internal, loops)
    entries = [_loop_entry(mech, names, lp, facts.get(k, {})) for k, lp in enumerate(loops)]
    ranges = {
        d.name: [[float(s / factors[i]), float(e / factors[i])] for s, e in internal[i]]
        for i, d in enumerate(mech.drivers)
    }
    dynamics = peak_loads(mech, params) if mech.has_dynamics else None
    flat = pose_at_change_point(params)
    crossed = change_points_crossed(mech, params)
    return CheckReport(
        name=mech.name,
        dof=plan.dof,
        drivers=tuple(d.name for d in mech.drivers),
        plan=tuple(plan.describe(params.steps).splitlines()),
        signs={
            j: {"sign": int(params.signs[i, 0]), "rule": plan.sign_labels[i], "at_change_point": j in flat}
            for i, j in enumerate(plan.sign_joints)
        },
        mirror_links=plan.mirror_links,
        input_ranges=ranges,
        units={"length": mech.length_unit, "angle": mech.angle_unit},
        fourbars=tuple(entries),
        dead_points=dead,
        held_at={d.name: {k: v for k, v in pose_values.items() if k != d.name} for d in mech.drivers},
        input_units={d.name: d.input_unit(mech) for d in mech.drivers},
        pose_input=pose_values,
        dynamics=dynamics,
        closed_form_joints=tuple(j for i, j in enumerate(names) if i not in plan.numerical),
        numerical_joints=tuple(names[i] for i in plan.numerical),
        sliders=tuple(sliders),
        assembly_gaps={d.name: assembly_gaps(ranges[d.name], mech.angle_to_rad) for d in mech.drivers if d.type.cyclic},
        reached_twice=_reached_twice(ranges, mech, pose_values),
        warnings=_report_warnings(mech, flat, entries, dynamics, ranges),
        change_points=crossed,
        change_points_skipped=None if crossed is not None else change_points_skipped(mech),
        **_first_loop(entries),
    )


def _report_warnings(
    mech: Mechanism,
    flat: list[str],
    entries: list[dict[str, Any]],
    dynamics: Mapping[str, Any] | None,
    ranges: Mapping[str, list[list[float]]],
) -> tuple[dict[str, Any], ...]:
    """The report's warnings: a pose at a change point (its joints ``flat``), then :func:`_warnings`."""
    first = ranges[mech.drivers[0].name] if mech.drivers else []
    return tuple(([{"kind": POSE_WARNING, "joints": flat}] if flat else []) + _warnings(entries, dynamics, mech, first))


def pose_at_change_point(params: Params) -> list[str]:
    """The joints of the sign steps whose two modes meet at the pose itself (one design).

    The steps' dimensionless determinants (:func:`linkagekit.rates.solve_rates`) from the pose's own
    coordinates (not re-solved: a flat triangle solved keeps ``sqrt`` of rounding, 1e-8) below
    :data:`POSE_FLAT`. There the side a joint lies on is rounding: the pose picks none of the two modes, and
    the sign written for it (+1 where the cross product is 0) is a choice, not the pose's.

    >>> import linkagekit as lk
    >>> from linkagekit.api import prepare
    >>> pose_at_change_point(prepare(lk.load("examples/seed000_fourbar.yaml")))
    []
    """
    plan = params.plan
    q0 = params.pose_inputs[:, :1, None]
    pos = solve(params, q0)
    if not plan.n_signs or not pos.assembled.all():
        return []
    at_pose = Positions(
        np.asarray(params.pose, complex)[:, :1, None], pos.rot, pos.margin, pos.assembled, pos.signs, pos.mirrors
    )
    nd = q0.shape[0]
    rt = solve_rates(params, at_pose, np.ones((nd, 1, 1)), np.zeros((nd, 1, 1)), tol=0.0)
    cond = np.abs(rt.condition[: plan.n_signs, 0, 0])
    return [j for j, c in zip(plan.sign_joints, cond, strict=True) if c <= POSE_FLAT]


def change_points_crossed(mech: Mechanism, params: Params) -> tuple[dict[str, Any], ...] | None:
    """The change points the continuous branch crosses along the file's sweep (see :class:`CheckReport`).

    None when the sweep has more than :data:`MAX_SWEEP_SAMPLES` samples or is too long to follow
    (:func:`change_points_skipped` says which): ``check`` still reports everything else about a file that
    ``analyze`` takes.
    """
    if _too_many_samples(mech):  # the path runs through every sample: memory grows with them
        return None
    q = sweep_inputs(mech, params)
    try:
        br = along_sweep(params, q, tuple(d.type.cyclic for d in mech.drivers))
    except PathTooLongError:
        return None
    steps, _, where = br.points
    drv = mech.drivers[br.driver]
    scale = drv.input_scale(mech)
    names = params.plan.sign_joints
    return tuple(
        {"joint": names[int(i)], "driver": drv.name, "input": round(float(x) / scale, 9)}
        for i, x in zip(steps, where, strict=True)
    )


def change_points_skipped(mech: Mechanism) -> str:
    """Why :func:`change_points_crossed` gave None: the sweep's samples, or its span."""
    return (
        _too_many_samples(mech)
        or f"the sweep spans more than {MAX_PATH} degrees, which the path follows in steps of 1 degree"
    )


def _sweep_drivers(
    mech: Mechanism, params: Params, internal: list[list[list[float]]], loops: list[FourBar]
) -> tuple[dict[str, list[dict[str, Any]]], dict[int, dict[str, Any]], list[dict[str, Any]]]:
    """Each driver's sweep (:func:`_driver_checks`): dead points, loop facts, and the sliders it moves."""
    lines = slider_lines(mech)
    dead: dict[str, list[dict[str, Any]]] = {}
    facts: dict[int, dict[str, Any]] = {}
    sliders: list[dict[str, Any]] = []
    for i, d in enumerate(mech.drivers):
        mine = [(k, lp) for k, lp in enumerate(loops) if lp.driver == i]
        dead[d.name], f, sf = _driver_checks(mech, params, i, internal[i], mine, lines)
        facts.update(f)
        sliders += [x for x in sf if x["stroke"] is not None and x["stroke"] > 1e-12]
    return dead, facts, sliders


def assembly_gaps(ranges: list[list[float]], angle_to_rad: float) -> list[list[float]]:
    """Where an angle driver does not assemble: the open intervals between its ``ranges``, on the turn.

    ``ranges`` as :func:`input_range` gives them (file units); each gap starts in [0, 1 turn).

    >>> assembly_gaps([[-341.593352, 4.792542]], math.pi / 180)
    [[4.792542, 18.406648]]
    >>> assembly_gaps([[0.0, 360.0]], math.pi / 180), assembly_gaps([], math.pi / 180)
    ([], [[0.0, 360.0]])
    """
    turn = 2 * math.pi / angle_to_rad
    if not ranges:
        return [[0.0, turn]]
    spans = sorted(ranges)
    gaps = []
    for (_, end), (start, _) in zip(spans, [*spans[1:], [spans[0][0] + turn, 0.0]], strict=True):
        if start - end > 1e-9 * turn:
            a = math.fmod(end, turn) + (turn if end < 0 else 0.0)
            gaps.append([round(a, 12), round(a + start - end, 12)])
    return sorted(gaps)


#: samples of the file's sweep at which a transmission-angle warning gives the angle's extremes there too
SWEEP_TRANSMISSION_SAMPLES = 3601


def _warnings(
    entries: list[dict[str, Any]],
    dynamics: Mapping[str, Any] | None,
    mech: Mechanism | None = None,
    ranges: list[list[float]] | None = None,
) -> list[dict[str, Any]]:
    """Transmission angles outside [MIN, 180 - MIN] (:data:`MIN_TRANSMISSION`) over the input range, with their
    extremes over the file's sweep where it does not cover the range (``ranges``: ``mech``'s one driver's);
    efforts peaking near a toggle."""
    out = []
    for k, lp in enumerate(entries):
        ta = lp.get("transmission_angle") or {}
        if ta.get("min") is not None and min(ta["min"], 180.0 - ta["max"]) < MIN_TRANSMISSION:
            w = {"kind": "transmission-angle", "loop": k, "joints": lp["joints"], "min": ta["min"], "max": ta["max"]}
            out.append(w | {"limit": MIN_TRANSMISSION} | _over_sweep(mech, lp["joints"], ranges or [], ta))
    for key in ("peak_driver_torque", "peak_driver_force"):
        for name, pk in ((dynamics or {}).get(key) or {}).items():
            tg = pk.get("toggle")
            if tg and tg["angle"] < TOGGLE_ANGLE:
                out.append({"kind": "toggle", "driver": name, "effort": key, "limit": TOGGLE_ANGLE} | pk)
    return out


def _sweep_covers(mech: Mechanism, ranges: list[list[float]]) -> bool:
    """Whether the file's sweep of its one driver covers every interval of its input range ``ranges`` (file units;
    an angle's a turn along when it is one).

    >>> import linkagekit as lk
    >>> mech = lk.load("examples/nongrashof_rocker.yaml")  # its sweep: -78 to 78 deg
    >>> [_sweep_covers(mech, r) for r in ([[-78.58, 78.58]], [[-10.0, 10.0]], [[282.0, 300.0]], [[0.0, 360.0]])]
    [False, True, True, False]
    >>> bucket = lk.load("examples/excavator_bucket.yaml")  # a cylinder's stroke, 2.15 to 2.9 m, swept whole
    >>> [_sweep_covers(bucket, r) for r in ([[2.15, 2.9]], [[2.2, 2.3]], [[2.1, 2.3]], [[2.8, 2.95]])]
    [True, True, False, False]
    """
    d = mech.drivers[0]
    a, b = sorted(d.sweep.ends())
    turn = 2 * math.pi / d.input_scale(mech) if d.type.cyclic else math.inf
    tol = 1e-9 * max(abs(a), abs(b), 1.0)
    if b - a >= turn - tol:
        return True
    for s, e in ranges:
        shift = math.ceil((a - tol - s) / turn) * turn if math.isfinite(turn) else 0.0  # the copy of s at or after a
        if not (e - s < turn - tol and a - tol <= s + shift and e + shift <= b + tol):
            return False
    return True


def _over_sweep(
    mech: Mechanism | None, joints: list[str], ranges: list[list[float]], ta: Mapping[str, Any] | None = None
) -> dict[str, Any]:
    """``{"sweep": {"driver", "from", "to", "min", "max"}}``: the transmission angle of the loop of ``joints``
    (crank pivot, crank tip, rocker tip, rocker pivot) over the file's sweep of its one driver, at
    :data:`SWEEP_TRANSMISSION_SAMPLES` inputs and at the range's refined extremes that lie in the sweep (``ta``'s
    ``min_at`` and ``max_at``: a four-bar folded flat at crank 0, inside its sweep, was 0.0272 deg there by the
    samples alone, against 0); nothing with several drivers or where it never assembles. A file whose crank rocks
    through part of its range (``synthesize --partial``) is bounded there, not over the range."""
    if mech is None or len(mech.drivers) != 1 or _sweep_covers(mech, ranges):
        return {}
    d = mech.drivers[0]
    q = np.linspace(*d.sweep.ends(), SWEEP_TRANSMISSION_SAMPLES)  # from its first value to its last
    q = np.concatenate([q, _in_sweep(mech, [(ta or {}).get(k) for k in ("min_at", "max_at")])])
    res = analyze(mech, {d.name: q}, rates=False, dynamics=False)
    mu = transmission_deg(*(res.point(j) for j in joints[1:]))  # NaN where a sample does not assemble
    if not np.isfinite(mu).any():
        return {}
    ends = {"driver": d.name, "from": float(q[0]), "to": float(q[SWEEP_TRANSMISSION_SAMPLES - 1])}
    return {"sweep": ends | {"min": float(np.nanmin(mu)), "max": float(np.nanmax(mu))}}


def _in_sweep(mech: Mechanism, inputs: list[float | None]) -> list[float]:
    """The ``inputs`` (file units; None skipped) that lie in the file's sweep of its one driver, each taken a whole
    number of turns along where it is an angle.

    >>> import linkagekit as lk
    >>> _in_sweep(lk.load("examples/nongrashof_rocker.yaml"), [0.0, 360.0, 100.0, None])  # its sweep: -78 to 78
    [0.0, 0.0]
    """
    d = mech.drivers[0]
    a, b = sorted(d.sweep.ends())
    turn = 2 * math.pi / d.input_scale(mech) if d.type.cyclic else math.inf
    out = []
    for x in inputs:
        if x is None or not math.isfinite(x):
            continue
        x = a + (x - a) % turn if math.isfinite(turn) else x
        if a <= x <= b:
            out.append(float(x))
    return out


# ---------------------------------------------------------------------- text
def _num(v: Any, fmt: str = ".6g") -> str:
    """``v`` formatted, ``—`` for None, a zero that rounding left negative without its sign.

    >>> _num(-1e-12, ".6f"), _num(-1e-12), _num(None)
    ('0.000000', '-1e-12', '—')
    """
    if v is None:
        return "—"
    text = format(float(v), fmt)
    return text[1:] if text.startswith("-") and not text.strip("-0.") else text


@dataclass(frozen=True)
class _Text:
    """How :func:`check_text` writes values: each driver's input unit, the file's angle and length units."""

    units: dict[str, str]
    angle: str
    length: str

    def inp(self, driver: str, v: Any) -> str:
        """``driver = value unit``."""
        unit = self.units.get(driver, "")
        return f"{driver} = {_num(v, '.6f')}" + (f" {unit}" if unit else "")

    def where(self, at: Mapping[str, Any]) -> str:
        """Every driver's input of a sample."""
        return ", ".join(self.inp(k, v) for k, v in at.items())


def check_text(rep: Mapping[str, Any], units: Mapping[str, str] | None = None, name: str | None = None) -> str:
    """The plain-text report of ``check`` from its :meth:`CheckReport.to_dict` document.

    Parameters
    ----------
    rep : mapping
        ``CheckReport.to_dict()``.
    units : mapping of str to str, optional
        The unit of each driver's input values (default: the report's ``input_units``).
    name : str, optional
        The name printed first (default: the report's ``name``).
    """
    file_units = rep.get("units") or {}
    fmt = _Text(
        dict(rep.get("input_units") or {}) | dict(units or {}),
        file_units.get("angle", ""),
        file_units.get("length", ""),
    )
    loops = _report_loops(rep)
    lines = [
        *_head_lines(rep, name if name is not None else str(rep.get("name") or "")),
        *_range_lines(rep, fmt),
        *(line for k, lp in enumerate(loops) for line in _loop_lines(k, len(loops), lp, fmt)),
        *(line for sl in rep.get("sliders") or [] for line in _slider_lines_text(sl, fmt)),
        *_dynamics_lines(rep.get("dynamics"), fmt),
        *_change_point_lines(rep.get("change_points", []), fmt, rep.get("change_points_skipped")),
        *(_warning_line(w, fmt) for w in rep.get("warnings") or [] if w.get("kind") != POSE_WARNING),
    ]
    return "\n".join(lines) + "\n"


def _change_point_lines(cps: list[dict[str, Any]] | None, fmt: _Text, skipped: str | None = None) -> list[str]:
    """The change points the continuous branch crosses along the sweep (none: no line; None: why not followed)."""
    if cps is None:
        why = skipped or f"the sweep spans more than {MAX_PATH} degrees, which the path follows in steps of 1 degree"
        return [f"Change points: not followed ({why})"]
    if not cps:
        return []
    at = ", ".join(f"{cp['joint']} at {fmt.inp(cp['driver'], cp['input'])}" for cp in cps[:MAX_TEXT_DEAD_POINTS])
    more = f" and {len(cps) - MAX_TEXT_DEAD_POINTS} more" if len(cps) > MAX_TEXT_DEAD_POINTS else ""
    return [
        f"Change points crossed along the sweep (analyze --branch continuous goes on smoothly through them): {at}{more}"
    ]


def _head_lines(rep: Mapping[str, Any], name: str) -> list[str]:
    """The first line (freedom, drivers, how it is solved), the solve plan, the pose's signs and mirror links."""
    numerical = list(rep.get("numerical_joints") or [])
    if numerical:
        closed = list(rep.get("closed_form_joints") or [])
        how = (
            f"solved numerically for {', '.join(numerical)} (Newton-Raphson, continued from the pose), "
            f"in closed form for {', '.join(closed) or 'no other joint'}."
        )
    else:
        how = f"solved {'in closed form' if rep.get('solvable') == 'closed-form' else rep.get('solvable', '')}."
    drivers = list(rep.get("drivers", []))
    lines = [
        f"{name}: valid; {rep['dof']} degree(s) of freedom, driven by {', '.join(drivers)}; {how}".rstrip(),
        "Solve plan:",
        *("  " + line for line in rep.get("plan", [])),
    ]
    if rep.get("signs"):
        lines.append(
            "Assembly mode of the reference pose: "
            + ", ".join(f"{j} {'+1' if s['sign'] > 0 else '-1'}" for j, s in rep["signs"].items())
        )
    flat = [w for w in rep.get("warnings") or [] if w.get("kind") == POSE_WARNING]
    lines += [
        f"Warning: the reference pose sits at a change point of {', '.join(w['joints'])} (its two modes meet there,"
        " a triangle flat to rounding; at an end of the range too): the pose picks neither, the sign above is a"
        " choice; pose it off that position to pick one"
        for w in flat
    ]
    if rep.get("mirror_links"):
        lines.append("Links that can be mirrored: " + ", ".join(rep["mirror_links"]))
    return lines


def _inward(v: float, up: bool) -> str:
    """A range's end to 6 decimals, rounded into the range (``up`` for a start, else an end) so that the printed
    value assembles (seed 003's 86.78273010617 printed as 86.782730 did not: review 19b); the nearest 6-decimal
    value where it is inward already (an end computed a hair outside a round value is not snapped to it: 59.9999999998
    printed as 60 did not assemble either, review 19e).

    >>> _inward(86.78273010617251, True), _inward(273.2172698938275, False), _inward(360.0, False)
    ('86.782731', '273.217269', '360.000000')
    >>> _inward(59.9999999998, False), _inward(-60.00000000002, True)
    ('59.999999', '-60.000000')
    """
    r = round(v, 6)
    if (r >= v) if up else (r <= v):
        return _num(r, ".6f")
    return _num((math.ceil if up else math.floor)(v * 1e6) / 1e6, ".6f")


def _pose_interval_line(driver: str, rng: list[list[float]], pose: float | None, fmt: _Text) -> list[str]:
    """With several intervals, the one that holds the pose's input: moving the input from the pose reaches no other
    (a Grashof double rocker's second interval is its other circuit; review 19b; two intervals that touch meet where
    the mechanism locks, review 19e).

    >>> _pose_interval_line("crank", [[29.0, 90.0], [270.0, 331.0]], 420.0, _Text({"crank": "deg"}, "deg", "mm"))
    ['  the pose (crank = 420.000000 deg) is in [29.000000, 90.000000]: moving the input from it reaches no other \
interval (between them it does not assemble, or locks)']
    """
    if pose is None or len(rng) < 2:
        return []
    turn = {"deg": 360.0, "rad": 2 * math.pi}.get(fmt.units.get(driver, ""))
    for a, b in rng:
        x = a + (pose - a) % turn if turn else pose
        if a <= x <= b:
            return [
                f"  the pose ({fmt.inp(driver, pose)}) is in [{_inward(a, True)}, {_inward(b, False)}]: moving the "
                "input from it reaches no other interval (between them it does not assemble, or locks)"
            ]
    return []


def _range_lines(rep: Mapping[str, Any], fmt: _Text) -> list[str]:
    """Each driver's assembly range (with the inputs held at the pose) and its dead points."""
    held = rep.get("held_at") or {}
    dead_points = rep.get("dead_points") or {}
    lines = []
    gaps = rep.get("assembly_gaps") or {}
    for driver, rng in (rep.get("input_ranges") or {}).items():
        text = ", ".join(f"[{_inward(a, True)}, {_inward(b, False)}]" for a, b in rng) if rng else "nowhere"
        unit = fmt.units.get(driver, "")
        line = f"Assembles for {driver} in {text}" + (f" {unit}" if rng and unit else "")
        if gaps.get(driver) and any(a < 0 for a, _ in rng):  # a range through 0: its gap reads best
            but = ", ".join(f"({_inward(a, False)}, {_inward(b, True)})" for a, b in gaps[driver])
            line = f"Assembles for {driver} in all but {but}" + (f" {unit}" if unit else "") + f" ({text})"
        if held.get(driver):
            line += " (" + ", ".join(f"{fmt.inp(k, v)}" for k, v in held[driver].items()) + " held at the pose)"
        lines.append(line)
        lines += _pose_interval_line(driver, rng, (rep.get("pose_input") or {}).get(driver), fmt)
        if rep.get("numerical_joints"):
            lines.append(
                "  in the pose's mode, by continuation from the pose (ends refined by bisection through the solver); "
                "other modes: linkagekit modes"
            )
            lines += _twice_reached((rep.get("reached_twice") or {}).get(driver), unit)
        if driver in dead_points:
            lines += _dead_point_lines(driver, dead_points[driver], fmt)
    return lines


def beyond_a_turn(interval: Sequence[float], turn: float) -> bool:
    """Whether an angle's assembly ``interval`` is longer than a ``turn`` (a full turn is ``[0, turn]`` exactly)."""
    return interval[1] - interval[0] > turn * (1 + 1e-9)


def direction_jumps(interval: list[float], x0: float, turn: float) -> list[float]:
    """Where a sweep of directions jumps between the two configurations of a mode longer than a ``turn`` that does not
    close (``interval``: its inputs from fold to fold as walked from the pose's input ``x0``, which it holds).

    ``analyze`` answers a direction ``u`` at its representative ``r`` nearest ``x0`` (``r - x0`` in
    ``[-turn/2, turn/2)``) where the mode has it, else at the one a turn the other way. That choice
    changes, and the answer jumps, at ``x0 + turn/2`` when both representatives there lie on the mode,
    and at each fold within half a turn of ``x0``: past it only the other representative is on the mode.

    >>> direction_jumps([-360.74, 57.54], -160.0, 360.0), direction_jumps([-0.74, 417.54], 0.0, 360.0)
    ([20.0], [-0.74])
    """
    a, b = interval
    half = turn / 2
    out = [x0 + half] if a <= x0 - half and x0 + half <= b else []
    out += [e for e, near in ((a, a - x0 >= -half), (b, b - x0 < half)) if near]
    return sorted(out)


def _reached_twice(
    ranges: Mapping[str, list[list[float]]], mech: Mechanism, pose: Mapping[str, float]
) -> dict[str, Any]:
    """For each angle driver whose range is longer than a turn (a numerical group's mode that does not close: it ends
    at a fold each way), the directions it reaches twice (``from``, ``to``) and where a sweep of directions jumps
    between their two configurations (``jumps``, :func:`direction_jumps`), in the file's unit."""
    out = {}
    for d in mech.drivers:
        turn = 2 * math.pi / d.input_scale(mech)
        rng = ranges[d.name]
        if d.type.cyclic and len(rng) == 1 and beyond_a_turn(rng[0], turn):
            a, b = rng[0]
            out[d.name] = {"from": a, "to": b - turn, "jumps": direction_jumps(rng[0], pose[d.name], turn)}
    return out


def _twice_reached(twice: Mapping[str, Any] | None, unit: str) -> list[str]:
    """The text of a driver's ``reached_twice`` (:func:`_reached_twice`): nothing without it."""
    if not twice:
        return []
    at = " and ".join(f"{j:.6f}" for j in twice["jumps"])
    return [
        f"  longer than a turn, and it does not close: the directions from {twice['from']:.6f} to {twice['to']:.6f} "
        f"{unit} are reached twice, a turn apart, in two configurations; analyze answers each direction with the one "
        f"reached turning the least from the pose's input where the mode has it, so a sweep of directions jumps "
        f"from one to the other at {at} {unit} (plot draws a break there)"
    ]


def _dead_point_lines(driver: str, dps: list[dict[str, Any]], fmt: _Text) -> list[str]:
    """A driver's dead points, at most :data:`MAX_TEXT_DEAD_POINTS` of them."""
    lines = [f"Dead points of {driver} (where the mechanism locks): {'none' if not dps else ''}".rstrip()]
    for dp in dps[:MAX_TEXT_DEAD_POINTS]:
        detail = f"; {dp['detail']}" if dp.get("detail") else ""
        lines.append(f"  {fmt.inp(driver, dp['input'])}: {dp['kind']}{detail}")
    if len(dps) > MAX_TEXT_DEAD_POINTS:
        lines.append(f"  ... and {len(dps) - MAX_TEXT_DEAD_POINTS} more (check --format json lists them all)")
    return lines


def _report_loops(rep: Mapping[str, Any]) -> list[Any]:
    """The report's four-bar loops (of a report without the list, its first loop only)."""
    loops: list[Any] | None = rep.get("fourbars")
    if loops is None and "grashof" in rep:
        loops = [dict(rep.get("fourbar") or {}, grashof=rep["grashof"], grashof_detail=rep.get("grashof_detail"))]
        if "transmission_angle" in rep:
            loops[0]["transmission_angle"] = rep["transmission_angle"]
    return loops or []


def _loop_lines(k: int, n: int, lp: Mapping[str, Any], fmt: _Text) -> list[str]:
    """The ``k``-th of ``n`` four-bar loops: Grashof type, lengths, input, transmission angle, rocker's motion."""
    tag = f" {k + 1} of {n}" if n > 1 else ""
    lines = [f"Four-bar loop{tag} {'-'.join(lp.get('joints', []))}: {lp.get('grashof_detail', lp['grashof'])}"]
    ln, lens = lp.get("links") or {}, lp.get("lengths") or {}
    if lens:
        lu = f" {fmt.length}" if fmt.length else ""
        roles = (("ground", "ground"), ("crank", "input side"), ("coupler", "coupler"), ("rocker", "output side"))
        parts = [
            f"{what} {_num(lens.get(role))}{lu}" + (f" ('{ln[role]}')" if role != "ground" and role in ln else "")
            for role, what in roles
        ]
        lines.append("  lengths: " + ", ".join(parts))
    if lp.get("input"):
        lines.append(f"  input: link '{lp['input']['link']}', moved by {lp['input']['moved_by']}")
    driver = (lp.get("input") or {}).get("driver")
    ta = lp.get("transmission_angle")
    if ta:
        text = f"  Transmission angle: min {ta['min']:.4f}°, max {ta['max']:.4f}°"
        if "min_at" in ta and driver:
            text += (
                f" (at {ta.get('joint', '')}; min at {fmt.inp(driver, ta['min_at'])}, "
                f"max at {fmt.inp(driver, ta['max_at'])})"
            )
        which = "min" if ta["min"] <= 180.0 - ta["max"] else "180° - max"
        text += f"; worst {min(ta['min'], 180.0 - ta['max']):.4f}° ({which}, as synthesize counts it)"
        lines.append(text)
    return lines + _rocker_lines(lp, driver, ln.get("rocker", "rocker"), fmt)


def _rocker_lines(lp: Mapping[str, Any], driver: str | None, rocker: str, fmt: _Text) -> list[str]:
    """A loop's limit positions, swing and time ratio (what its driver's sweep found)."""
    lines = []
    if "limit_positions" in lp and driver:
        lims = lp["limit_positions"]
        if lp.get("rocker_turns_fully"):
            lines.append(f"  {rocker} turns fully: no limit positions")
        elif not lims:
            lines.append(f"  Limit positions of {rocker}: none")
        else:
            lines.append(f"  Limit positions of {rocker} (its angular velocity is zero):")
            lines += [
                f"    {fmt.inp(driver, lim['input'])}: {rocker} at {_num(lim['angle'], '.6f')} {fmt.angle} "
                f"({lim['extreme']})"
                for lim in lims
            ]
    if lp.get("swing") is not None:
        lines.append(f"  {rocker} swings {_num(lp['swing'], '.6f')} {fmt.angle}")
    if lp.get("time_ratio") is not None:
        s = lp["strokes"]
        unit = fmt.units.get(driver or "", "")
        lines.append(
            f"  Time ratio {lp['time_ratio']:.6f} at constant input speed ({driver} travels "
            f"{_num(s['rising'], '.6f')} {unit} while {rocker} rises, "
            f"{_num(s['falling'], '.6f')} {unit} while it falls)"
        )
    return lines


def _dwell_inputs(fmt: _Text, driver: str, lim: Mapping[str, Any]) -> str:
    """A limit position's input, or the inputs from where a dwell starts to where it ends."""
    if "until" not in lim:
        return fmt.inp(driver, lim["input"])
    return f"{fmt.inp(driver, lim['input'])} to {_num(lim['until'], '.6f')} {fmt.units.get(driver, '')}".rstrip()


def _slider_lines_text(sl: Mapping[str, Any], fmt: _Text) -> list[str]:
    """A slider on the frame: stroke, limit positions, time ratio, pressure angle (what its driver's sweep found)."""
    driver, link, lu = sl["driver"], sl["link"], f" {fmt.length}" if fmt.length else ""
    lines = [
        f"Slider {sl['slider']} ('{link}' on the frame, joint {sl['joint']}), moved by {driver}: "
        f"stroke {_num(sl['stroke'], '.6f')}{lu}"
        + (f" ({_num(sl['pose_stroke'], '.6f')}{lu} over the pose's interval)" if "pose_stroke" in sl else "")
    ]
    lims = sl.get("limit_positions") or []
    if lims:
        lines.append(f"  Limit positions of {link} (its velocity is zero; position along its line from the pose's):")
        lines += [
            f"    {_dwell_inputs(fmt, driver, lim)}: {link} at {_num(lim['position'], '.6f')}{lu} ({lim['extreme']}"
            f"{', at rest' if 'until' in lim else ''})"
            for lim in lims
        ]
    if sl.get("time_ratio") is not None:
        t, unit = sl["input_travel"], fmt.units.get(driver, "")
        rest = f", {_num(t['rest'], '.6f')} {unit} at rest" if "rest" in t else ""
        lines.append(
            f"  Time ratio {sl['time_ratio']:.6f} at constant input speed ({driver} travels "
            f"{_num(t['rising'], '.6f')} {unit} while {link} advances, {_num(t['falling'], '.6f')} {unit} "
            f"while it returns{rest})"
        )
    pa = sl.get("pressure_angle")
    if pa:
        lines.append(
            f"  Pressure angle (between rod '{pa['rod']}' and the slide): max {pa['max']:.4f}° at "
            f"{fmt.inp(driver, pa['max_at'])}, min {pa['min']:.4f}° at {fmt.inp(driver, pa['min_at'])}"
        )
    return lines


def _warning_line(w: Mapping[str, Any], fmt: _Text) -> str:
    """One warning of the report, for people."""
    if w["kind"] == "transmission-angle":
        return (
            f"Warning: the transmission angle of loop {'-'.join(w['joints'])} leaves [{w['limit']:g}°, "
            f"{180 - w['limit']:g}°] (min {w['min']:.4f}°, max {w['max']:.4f}°): there the coupler pushes the "
            f"output mostly into its bearing{_sweep_words(w, fmt)}"
        )
    tg = w["toggle"]
    what, unit = ("torque", "N*m") if w["effort"] == "peak_driver_torque" else ("force", "N")
    return (
        f"Warning: the driver {what} of {w['driver']} peaks at {_num(w['value'])} {unit} at {fmt.where(w['at'])}, "
        f"{tg['angle']:.4f}° (less than {w['limit']:g}°) from the toggle where {tg.get('detail', tg['joint'])}"
    )


def _sweep_words(w: Mapping[str, Any], fmt: _Text) -> str:
    """The transmission angle's extremes over the file's sweep, for a warning over the whole range; said to stay
    within the bounds there when it does."""
    sw = w.get("sweep")
    if not sw:
        return ""
    inside = min(sw["min"], 180.0 - sw["max"]) >= w["limit"]
    return (
        f"; over the file's sweep ({sw['driver']} from {_num(sw['from'])} to {_num(sw['to'])}"
        f"{' ' + fmt.units[sw['driver']] if fmt.units.get(sw['driver']) else ''}) "
        f"min {sw['min']:.4f}°, max {sw['max']:.4f}°{': within the bounds there' if inside else ''}"
    )


def _dynamics_lines(dyn: Mapping[str, Any] | None, fmt: _Text) -> list[str]:
    """The peak driver efforts and bearing load over the file's sweep (nothing without dynamics)."""
    if not dyn:
        return []
    units = fmt.units
    speeds = ", ".join(
        f"{k} at {_num(v)} {'rad/s' if units.get(k) in ('deg', 'rad') else units.get(k, '') + '/s'}"
        for k, v in (dyn.get("speeds") or {}).items()
    )
    lines = [f"Peak loads over the file's sweep ({dyn.get('samples')} samples; {speeds}):"]
    if dyn.get("skipped"):
        lines.append(f"  not computed: {dyn['skipped']}")
    for key, what, unit in (("peak_driver_torque", "torque", "N*m"), ("peak_driver_force", "force", "N")):
        for drv, pk in (dyn.get(key) or {}).items():
            lines.append(f"  Peak driver {what} of {drv}: {_num(pk['value'])} {unit} at {fmt.where(pk['at'])}")
    bl = dyn.get("peak_bearing_load")
    if bl:
        lines.append(
            f"  Peak bearing load: {_num(bl['value'])} N at joint {bl['joint']} ({bl['by']} on {bl['on']}) "
            f"at {fmt.where(bl['at'])}"
        )
    if not dyn.get("skipped") and not bl and not dyn.get("peak_driver_torque") and not dyn.get("peak_driver_force"):
        lines.append("  none: the mechanism does not assemble (or is singular) at every sample")
    return lines


@dataclass(frozen=True)
class Mode:
    """One assembly mode (and mirror choice) at one input.

    Attributes
    ----------
    signs, mirrors : dict
        The closed-form steps' signs (and the mirror flags, when asked for).
    assembled, reference : bool
        Whether it assembles; whether it is the mode the solver gives at this input (the
        pose's signs, and each numerical group as continued from the pose).
    joints : dict of str to (x, y) or None
        Every joint's position (file units).
    same_as : int or None
        The first mode with the same positions.
    groups : dict or None
        With numerical groups: for each (named by its joints, ``"J1,J2,J3"``) ``{"index":
        i, "of": n}``, its mode among the ``n`` real modes it has there (sorted by the angle
        of the link the enumeration drives; index -1 when it has none or they were not
        enumerated).  Signs alone do not tell such modes apart: choose one by its positions,
        :meth:`mechanism`.
    """

    signs: dict[str, int]
    mirrors: dict[str, int] | None
    assembled: bool
    reference: bool
    joints: dict[str, tuple[float, float] | None]
    same_as: int | None = None
    groups: dict[str, dict[str, int]] | None = None

    def mechanism(self, mech: Mechanism) -> Mechanism:
        """``mech`` in this mode: its reference pose moved to this mode's positions (:meth:`Mechanism.with_pose`).

        Every dimension is read off the new pose (exact to the mode's accuracy, ~1e-12
        relative), and the pose picks the mode, so analysing the result at this input gives
        these positions back and follows this mode from there (numerical groups continue
        from it; closed-form steps keep its signs).

        Raises
        ------
        InputError
            The mode does not assemble.
        """
        if not self.assembled:
            raise InputError("this mode does not assemble: it has no positions to make a pose of")
        return mech.with_pose({j: p for j, p in self.joints.items() if p is not None})

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {"signs": self.signs}
        if self.mirrors is not None:
            out["mirrors"] = self.mirrors
        if self.groups is not None:
            out["groups"] = self.groups
        out["assembled"] = self.assembled
        out["reference"] = self.reference
        if self.same_as is not None:
            out["same_as"] = self.same_as
        out["joints"] = {j: (list(p) if p is not None else None) for j, p in self.joints.items()}
        return out


@dataclass(frozen=True)
class Modes:
    """Every assembly mode at one input (``linkagekit modes``).

    Attributes
    ----------
    input : dict of str to float
        The input of each driver, in the file's units.
    modes : tuple of Mode
        Every sign (and mirror) combination, and with numerical groups every mode of each
        group for each, in order: assembled or not, the same positions more than once
        (:attr:`Mode.same_as`).
    distinct : int
        How many distinct assembled configurations there are among them.
    notes : tuple of str
        The numerical groups whose modes could not be enumerated (only the mode continued
        from the pose is listed for them).
    units : dict of str to str
        The file's ``length`` unit (the joints') and ``angle`` unit (the inputs of cranks).
    """

    input: dict[str, float]
    modes: tuple[Mode, ...]
    distinct: int
    notes: tuple[str, ...] = ()
    units: dict[str, str] = field(default_factory=dict)  # the file's length and angle units (the joints', inputs')

    def to_dict(self) -> dict[str, Any]:
        """The JSON of ``linkagekit modes --format json``."""
        out: dict[str, Any] = {
            "format": "linkagekit-modes/1",
            "units": self.units,
            "input": self.input,
            "distinct": self.distinct,
            "modes": [m.to_dict() for m in self.modes],
        }
        if self.notes:
            out["notes"] = list(self.notes)
        return out


def _given_inputs(mech: Mechanism, at: Any) -> dict[str, Any]:
    """``at`` of :func:`modes` as {driver name: value} (a bare value for a single driver)."""
    if at is None:
        return {}
    if isinstance(at, dict):
        return dict(at)
    if len(mech.drivers) == 1:
        return {mech.drivers[0].name: at}
    raise InputError(f"at: give a value per driver ({', '.join(d.name for d in mech.drivers)})")


def _mode_inputs(mech: Mechanism, params: Params, at: Any) -> tuple[np.ndarray, dict[str, float]]:
    """The inputs of :func:`modes`: internal units per driver (the pose's where not given) and file units by name."""
    given = _given_inputs(mech, at)
    q0 = params.pose_inputs[:, 0].copy()
    inp = {}
    for i, d in enumerate(mech.drivers):
        factor = d.input_scale(mech)
        if d.name not in given:
            inp[d.name] = float(q0[i] / factor)
            continue
        try:
            value = float(given.pop(d.name))
        except (TypeError, ValueError, OverflowError):
            raise InputError(f"at: '{d.name}' needs one number") from None
        if not math.isfinite(value) or abs(value) > 1e12:
            raise InputError(f"at: '{d.name}' must be a finite number of at most 1e12 in magnitude")
        q0[i] = value * factor
        inp[d.name] = value  # as given, not through radians and back
    if given:
        raise InputError(f"at: no driver named '{next(iter(given))}' (drivers: {', '.join(params.plan.drivers)})")
    return q0, inp


@dataclass(frozen=True)
class _ModeRows:
    """The configurations :func:`modes` found, one per row.

    Positions ``z`` (n_joints, R), whether each assembles, the sign (and mirror) combination
    of each row (``col``), and per numerical group (label, its mode, its mode count).
    """

    z: np.ndarray
    assembled: np.ndarray
    col: np.ndarray
    notes: tuple[str, ...] = ()
    groups: tuple[tuple[str, np.ndarray, np.ndarray], ...] = ()


def _group_label(params: Params, index: int) -> str:
    """A numerical group named by its joints (``"J1,J2,J3"``), the ``index``-th step of the plan."""
    step = params.plan.steps[index]
    assert isinstance(step, Group)
    return ",".join(params.plan.joint_names[j] for j in step.joints)


def _mode_rows(
    mech: Mechanism, params: Params, q0: np.ndarray, signs: np.ndarray, flags: np.ndarray | None
) -> _ModeRows:
    """Every sign (and mirror) combination solved at ``q0``.

    With numerical groups, every mode of each group for each combination
    (:func:`linkagekit.groupmodes.enumerate_modes`).
    """
    if params.plan.numerical:
        table = enumerate_modes(mech, params, q0, signs, flags)
        groups = tuple(
            (_group_label(params, gi), table.group_mode[g], table.group_count[g]) for g, gi in enumerate(table.groups)
        )
        return _ModeRows(table.z, table.assembled, table.column, table.notes, groups)
    q = np.repeat(q0[:, None, None], signs.shape[1], axis=2)
    sol = solve(params, q, signs[:, None, :], flags[:, None, :] if flags is not None else None)
    return _ModeRows(sol.z[:, 0], sol.assembled[0], np.arange(signs.shape[1]))


def _reference_rows(
    params: Params, rows: _ModeRows, signs: np.ndarray, flags: np.ndarray | None, q0: np.ndarray, tol: float
) -> np.ndarray:
    """Which rows are the solver's own mode at ``q0``.

    The pose's signs, no mirror, and each numerical group as continued from the pose.
    """
    plan, col = params.plan, rows.col
    reference: np.ndarray = np.all(signs[:, col] == params.signs[:, :1], axis=0)
    if flags is not None:
        reference &= ~flags[:, col].any(axis=0)
    if plan.numerical:
        cont = solve(params, q0[:, None, None]).z[list(plan.numerical), 0, 0]
        reference &= np.all(np.abs(rows.z[list(plan.numerical)] - cont[:, None]) <= tol, axis=0)
    return reference


def _same_as(rows: _ModeRows, tol: float) -> tuple[list[int | None], int]:
    """For each row the first row with the same positions (None for the first of each), and how many are distinct.

    Rows are bucketed by positions rounded to 1e-6 of the size, then confirmed within the
    bucket to ``tol`` (two configurations within tol round alike but for a 1e-3 chance at a
    rounding boundary, which only splits a duplicate, never merges two modes).
    """
    z = rows.z
    keys = np.round(np.concatenate([z.real, z.imag]) / (1e3 * tol)).T
    buckets: dict[bytes, list[int]] = {}
    same: list[int | None] = []
    distinct = 0
    for r in range(len(rows.col)):
        first = None
        if rows.assembled[r]:
            bucket = buckets.setdefault(keys[r].tobytes(), [])
            first = next((f for f in bucket if np.all(np.abs(z[:, f] - z[:, r]) <= tol)), None)
            if first is None:
                bucket.append(r)
                distinct += 1
        same.append(first)
    return same, distinct


@one_blas_thread
def modes(mech: Mechanism, at: Any = None, mirrors: bool = False) -> Modes:
    """Every assembly mode (and with ``mirrors`` every mirror image) at one input.

    Each combination of the closed-form steps' signs is one mode; a numerical group
    multiplies it by every real mode the group has there, found by
    :func:`linkagekit.groupmodes.enumerate_modes` (see docs/method.md, "Every mode of a
    numerical group").

    Parameters
    ----------
    at : float or mapping of driver name to float, optional
        The input, in the file's units (one value per driver); default: the pose's.
    mirrors : bool
        Also flip each link of three or more joints (the 2^k sign configurations of the
        natural-coordinate papers).
    """
    params = prepare(mech)
    if not isinstance(mirrors, bool | np.bool_):
        raise InputError(f"mirrors: expected True or False, got {type(mirrors).__name__}")
    plan = params.plan
    names = plan.joint_names
    q0, inp = _mode_inputs(mech, params, at)
    k, mm = plan.n_signs, plan.n_mirrors if mirrors else 0
    if k + mm > MAX_MODE_SLOTS:
        what = "sign steps and mirror links" if mm else "sign steps"
        raise InputError(
            f"modes: {k + mm} {what} give 2^{k + mm} combinations, more than modes lists "
            f"(2^{MAX_MODE_SLOTS}); to look at some of them, fix some signs from Python: "
            "lk.analyze(mech, ..., signs={joint: +1 or -1})"
        )
    combos = all_sign_combinations(k + mm)
    signs, flags = combos[:k], (combos[k:] < 0 if mm else None)
    tol = 1e-9 * mech.length_scale
    rows = _mode_rows(mech, params, q0, signs, flags)
    reference = _reference_rows(params, rows, signs, flags, q0, tol)
    same, distinct = _same_as(rows, tol)
    out = []
    for r, c in enumerate(rows.col):
        zc = rows.z[:, r]
        out.append(
            Mode(
                signs={j: int(signs[i, c]) for i, j in enumerate(plan.sign_joints)},
                mirrors={ln: int(combos[k + i, c]) for i, ln in enumerate(plan.mirror_links)} if mm else None,
                assembled=bool(rows.assembled[r]),
                reference=bool(reference[r]),
                joints={
                    j: ((float(zc[i].real), float(zc[i].imag)) if np.isfinite(zc[i]) else None)
                    for i, j in enumerate(names)
                },
                same_as=same[r],
                groups={lab: {"index": int(ix[r]), "of": int(cnt[r])} for lab, ix, cnt in rows.groups}
                if rows.groups
                else None,
            )
        )
    return Modes(inp, tuple(out), distinct, rows.notes, {"length": mech.length_unit, "angle": mech.angle_unit})
