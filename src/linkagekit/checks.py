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
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .api import analyze, prepare
from .errors import InputError
from .group import Group
from .groupmodes import continuation_intervals, enumerate_modes
from .model import CrankType, Mechanism
from .params import Params, all_sign_combinations
from .positions import solve
from .rates import SINGULAR_TOL, solve_rates
from .steps import CircleLine, CylinderDyad, CylinderLine, Dyad

N_COARSE = 7200
#: dead points the text of check lists per driver (the JSON has them all)
MAX_TEXT_DEAD_POINTS = 24
#: modes lists at most 2^MAX_MODE_SLOTS sign (and mirror) combinations
MAX_MODE_SLOTS = 12
N_BISECT = 60
#: a sign step's |determinant| at a sample below which a local minimum is refined as a possible change point
TOUCH = 0.05


def _inputs(params: Params, driver: int, values: np.ndarray) -> np.ndarray:
    """Driver values (n_drivers, 1, n): ``values`` for one driver, the pose's for the others."""
    q = np.repeat(params.pose_inputs[:, :, None], len(values), axis=2)
    q[driver, 0] = values
    return q


def _assembled(params: Params, driver: int, values: np.ndarray) -> np.ndarray:
    return solve(params, _inputs(params, driver, values)).assembled[0]


def _span(mech: Mechanism, driver: int) -> tuple[float, float]:
    """Where a driver's input is searched: a turn [0, 2 pi), +-2 x the sum of the link sizes for a slider;
    for a cylinder's length its stroke and 1 % of it either side, or (0, 2 x that sum] without a stroke."""
    span = 2 * sum(max(ln.length(a, b) for a in ln.joints for b in ln.joints) for ln in mech.links)
    return mech.drivers[driver].type.search_span(span)


def input_range(mech: Mechanism, driver: int = 0, params: Params | None = None) -> list[list[float]]:
    """Intervals of one driver's input (file units) where the mechanism assembles.

    The other drivers stay at their reference-pose values.  An angle's intervals lie in
    [0, 360) degrees (or [0, 2 pi)), except that an interval running through 0 starts at
    a negative value; a full turn is ``[[0, 360]]``.  Boundaries are exact to ~1e-12 rad.
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
    """Grashof class of a four-bar: (one of the spec's five names, a finer description).

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
    cond = np.where(ok, np.abs(rt.condition[:, 0]), np.nan)
    singular = np.any(cond < SINGULAR_TOL, axis=0) if len(cond) else np.zeros(len(ok), bool)
    v = rt.v[:, 0]
    return _State(ok, pos.z[:, 0], np.where(singular, np.nan, v), v, cond, pos.margin[:, 0])


class _Quantities:
    """The scalar functions of the input the checks look at, as rows of one matrix per state.

    Rows: for each loop its rocker's angular velocity per unit input speed (``w``), its
    transmission angle in degrees (``mu``), ``-mu``, and ``dmu`` = rocker's minus coupler's
    angular velocity (``d mu / d input`` up to its sign); then ``|cond|`` of each sign step,
    and for each circle-circle step ``ds``: the rate of change of the distance ``s`` between
    the two known joints it is found from (zero where ``s`` touches ``r1 + r2`` or ``|r1 - r2|``).
    """

    def __init__(
        self, loops: list[FourBar], n_signs: int, out_links: list[tuple[int, int]], known: list[tuple[int, int]]
    ) -> None:
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

    def rows(self, st: _State) -> np.ndarray:
        d = st.z[self.k2] - st.z[self.k1]
        with np.errstate(invalid="ignore", divide="ignore"):
            ds = (np.conj(d) * (st.vraw[self.k2] - st.vraw[self.k1])).real / np.abs(d)
        ds = np.where(self.dyad[:, None], ds, np.nan)
        if not self.n:
            return np.concatenate([st.cond, ds])
        z, v = st.z, st.v
        b, a, o4 = z[self.joint], z[self.tip], z[self.piv]
        arm, bar = b - o4, b - a
        with np.errstate(invalid="ignore", divide="ignore"):
            w = (np.conj(arm) * v[self.joint]).imag / (np.abs(arm) ** 2)
            wc = (np.conj(bar) * (v[self.joint] - v[self.tip])).imag / (np.abs(bar) ** 2)
            mu = np.degrees(np.abs(np.angle((o4 - b) / (a - b))))
        mu = np.where(np.isfinite(b), mu, np.nan)
        return np.concatenate([w, mu, -mu, w - wc, st.cond, ds])

    def out_angle(self, st: _State) -> np.ndarray:
        """Angle (rad) of each loop's rocker link: the direction of its first joint -> its second."""
        return np.angle(st.z[self.out1] - st.z[self.out0])


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


def _refine(
    params: Params,
    driver: int,
    q: _Quantities,
    roots: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    mins: tuple[np.ndarray, np.ndarray, np.ndarray],
) -> tuple[np.ndarray, np.ndarray]:
    """Vectorized bisection (sign changes) and golden-section search (minima), all in one solve per step.

    ``roots`` = (a, b, row, sign at a): a root of quantity ``row`` in [a, b];
    ``mins`` = (a, b, row): a minimum of quantity ``row`` in [a, b].  Returns the refined
    abscissae (roots, minima); each bracket shrinks to ~1e-16 of its width's scale.
    """
    ra, rb, rrow, rsign = (np.array(v, float) for v in roots)
    ma, mb, mrow = (np.array(v, float) for v in mins)
    rrow_i, mrow_i = rrow.astype(int), mrow.astype(int)
    nr, nm = len(ra), len(ma)
    if nr + nm == 0:
        return ra, ma
    g = (math.sqrt(5) - 1) / 2
    cols = np.arange(nr + 2 * nm)
    for _ in range(N_BISECT):
        mid = 0.5 * (ra + rb)
        c, d = mb - g * (mb - ma), ma + g * (mb - ma)
        vals = q.rows(_state(params, driver, np.concatenate([mid, c, d])))
        f = vals[np.concatenate([rrow_i, mrow_i, mrow_i]), cols]
        same = np.sign(f[:nr]) == rsign
        ra, rb = np.where(same, mid, ra), np.where(same, rb, mid)
        fc, fd = f[nr : nr + nm], f[nr + nm :]
        left = (fc < fd) | (np.isnan(fd) & ~np.isnan(fc))
        ma, mb = np.where(left, ma, c), np.where(left, d, mb)
    return 0.5 * (ra + rb), 0.5 * (ma + mb)


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
        out["detail"] = f"{step.links[0]} and {step.links[1]} in line at {names[step.joint]} ({how})"
    elif isinstance(step, CircleLine):
        out["links"] = [step.link, step.block]
        out["detail"] = f"{step.link} square to the line of slider {step.slider} at {names[step.joint]}"
    elif isinstance(step, CylinderDyad | CylinderLine):
        cyl = params.plan.drivers[step.driver]
        s = float(abs(st.z[step.joint, col] - st.z[step.k2 if isinstance(step, CylinderDyad) else step.center, col]))
        lo, hi = float(nums[-2][0, 0]), float(nums[-1][0, 0])
        other = step.link if isinstance(step, CylinderDyad) else step.block
        out["links"] = [other]
        out["cylinder"] = cyl
        if math.isfinite(s) and min(abs(s - lo), abs(s - hi)) <= 1e-6 * s:
            end = "shortest" if abs(s - lo) <= abs(s - hi) else "longest"
            out["detail"] = f"cylinder '{cyl}' at the end of its stroke ({end})"
        elif isinstance(step, CylinderDyad):
            out["detail"] = f"cylinder '{cyl}' in line with {other} at {names[step.joint]}"
        else:
            out["detail"] = f"cylinder '{cyl}' square to the line of slider {step.slider} at {names[step.joint]}"
    else:  # a guide turned about a pivot (Pivot)
        out["links"] = [getattr(step, "on", "")]
        out["detail"] = f"guide '{getattr(step, 'on', '')}' at the end of its turn ({names[step.joint]})"
    return out


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


def _driver_checks(
    mech: Mechanism, params: Params, driver: int, intervals: list[list[float]], loops: list[tuple[int, FourBar]]
) -> tuple[list[dict[str, Any]], dict[int, dict[str, Any]]]:
    """Dead points of one driver's input, and the transmission angle and limit positions of its loops.

    ``intervals`` where it assembles, in radians or length units (:func:`_assembly_intervals`);
    ``loops`` the (index, loop) pairs this driver sweeps.  Returns (dead points, {loop index:
    facts}), every value in file units.
    """
    d = mech.drivers[driver]
    factor = d.input_scale(mech)
    if not intervals:
        return [], {}
    lo, hi = _span(mech, driver)
    total = hi - lo
    cyclic = d.type.cyclic and len(intervals) == 1 and intervals[0][1] - intervals[0][0] >= total * (1 - 1e-12)
    sw = _sweep(intervals, cyclic, total)
    x = sw.x
    plan = params.plan
    names = plan.joint_names
    lps = [lp for _, lp in loops]
    out_links = []
    for lp in lps:
        j = mech.link(lp.links[2]).joints
        out_links.append((names.index(j[0]), names.index(j[1])))
    known = [(s.k1, s.k2) if isinstance(s, Dyad) else (-1, -1) for s in plan.sign_steps]
    q = _Quantities(lps, plan.n_signs, out_links, known)
    st = _state(params, driver, x)
    rows = q.rows(st)

    # -- limit positions: sign changes of each rocker's angular velocity between neighbours
    ia = np.flatnonzero(sw.has_next)
    root_a: list[Any] = []
    root_b: list[Any] = []
    root_row: list[Any] = []
    root_sign: list[Any] = []
    root_i: list[Any] = []
    for li in range(q.n):
        w = rows[q.w(li)]
        wa, wb = w[ia], w[sw.next[ia]]
        hit = np.isfinite(wa) & np.isfinite(wb) & (wa != 0) & (np.sign(wb) != np.sign(wa))
        k = ia[hit]
        root_a.append(x[k])
        root_b.append(sw.nx[k])
        root_row.append(np.full(len(k), q.w(li)))
        root_sign.append(np.sign(w[k]))
        root_i.append(k)
    # -- minima: transmission angle min and max per loop, and |cond| touching 0 inside the range
    min_a: list[Any] = []
    min_b: list[Any] = []
    min_row: list[Any] = []
    min_i: list[Any] = []
    # the transmission angle's extremes: a root of d mu / d input when it changes sign around the
    # best sample (a smooth extreme), else a golden-section search (an end of the range, or mu at 0 or 180)
    ta_tasks: list[tuple[int, int, str, int, int]] = []  # (loop, +1 min / -1 max, kind, task, sample)
    n_roots = sum(len(r) for r in root_a)
    for li in range(q.n):
        dm = rows[q.dmu(li)]
        for sgn in (1, -1):
            f = rows[q.mu(li, sgn)]
            if not np.isfinite(f).any():
                continue
            i = int(np.nanargmin(f))
            sa, sb = np.sign(dm[sw.prev[i]]), np.sign(dm[sw.next[i]])
            if sw.has_prev[i] and sw.has_next[i] and sa * sb < 0:
                root_a.append([sw.px[i]])
                root_b.append([sw.nx[i]])
                root_row.append([q.dmu(li)])
                root_sign.append([sa])
                root_i.append([i])
                ta_tasks.append((li, sgn, "root", n_roots, i))
                n_roots += 1
            else:
                ta_tasks.append((li, sgn, "min", sum(len(m) for m in min_a), i))
                min_a.append([sw.px[i]])
                min_b.append([sw.nx[i]])
                min_row.append([q.mu(li, sgn)])
                min_i.append([i])
    # change points: a sign step's |determinant| touching 0 inside the range.  For a circle-circle
    # step that is where the distance s between its known joints has an extremum at r1 + r2 or
    # |r1 - r2|: a simple root of ds (bisection); otherwise a golden-section search on |cond|
    cp_tasks: list[tuple[int, str, int]] = []  # (sign step, kind, task)
    interior = sw.has_prev & sw.has_next
    for k in range(plan.n_signs):
        c, ds = rows[q.cond(k)], rows[q.ds(k)]
        with np.errstate(invalid="ignore"):
            cand = interior & (c <= c[sw.prev]) & (c <= c[sw.next]) & (c < TOUCH)
        for ic in np.flatnonzero(cand):
            i = int(ic)
            sa, sb = np.sign(ds[sw.prev[i]]), np.sign(ds[sw.next[i]])
            if sa * sb < 0:
                root_a.append([sw.px[i]])
                root_b.append([sw.nx[i]])
                root_row.append([q.ds(k)])
                root_sign.append([sa])
                root_i.append([i])
                cp_tasks.append((k, "root", n_roots))
                n_roots += 1
            else:
                cp_tasks.append((k, "min", sum(len(m) for m in min_a)))
                min_a.append([sw.px[i]])
                min_b.append([sw.nx[i]])
                min_row.append([q.cond(k)])
                min_i.append([i])

    def cat(parts: list[Any]) -> np.ndarray:
        return np.concatenate([np.asarray(p, float) for p in parts]) if parts else np.zeros(0)

    ri = cat(root_i).astype(int)
    rrow = cat(root_row).astype(int)
    rsign = cat(root_sign)
    mrow = cat(min_row).astype(int)
    roots, mins = _refine(params, driver, q, (cat(root_a), cat(root_b), rrow, rsign), (cat(min_a), cat(min_b), mrow))
    # the range ends (not the artificial ends of a slider's search span) are dead points
    ends = [] if cyclic else [v for s, e in intervals for v in (s, e) if lo < v < hi or d.type.cyclic]
    ends_arr = np.array(ends, float)
    fin = _state(params, driver, np.concatenate([roots, mins, ends_arr]))
    fvals = q.rows(fin)
    nr, nm = len(roots), len(mins)
    cols = np.arange(nr + nm)
    fval = fvals[np.concatenate([rrow, mrow]), cols] if nr + nm else np.zeros(0)
    tol_x = 1e-9 * (1.0 if d.type.cyclic else total)

    def file_value(v: float) -> float:
        if cyclic:
            v = lo + float(np.mod(v - lo, total))
            if min(abs(v - lo), abs(lo + total - v)) < 1e-13 * total:  # 0 to round-off
                v = lo
        return float(v / factor)

    # dead points
    dead: list[tuple[float, dict[str, Any]]] = []
    for m, v in enumerate(ends):
        col = nr + nm + m
        margins = fin.margin[:, col]
        k = int(np.nanargmin(margins)) if np.isfinite(margins).any() else 0
        info = {"input": float(v / factor), "kind": "end of range"}
        if plan.numerical and not (np.isfinite(margins).any() and np.nanmin(margins) <= 1e-6):
            info.update(_group_end(params))
        elif plan.n_signs:
            info.update(_step_links(params, k, fin, col))
        dead.append((v, info))
    # change points, each once: candidates sorted by input, a candidate within tol_x of the
    # one kept before it (or of a range end) is the same point found by another step
    cands = []
    for k, kind, task in cp_tasks:
        col = task if kind == "root" else nr + task
        v = roots[task] if kind == "root" else mins[task]
        if fin.assembled[col] and fvals[q.cond(k), col] < SINGULAR_TOL:
            cands.append((float(v), k, col))
    cands.sort()
    if cands and ends:
        near_end = np.abs(np.array([c[0] for c in cands])[:, None] - ends_arr[None, :]).min(axis=1) <= tol_x
        cands = [c for c, bad in zip(cands, near_end, strict=True) if not bad]
    kept: list[tuple[float, int, int]] = []
    for c in cands:
        if kept and abs(_cyc(c[0] - kept[-1][0], cyclic, total)) <= tol_x:
            continue
        kept.append(c)
    if cyclic and len(kept) > 1 and abs(_cyc(kept[-1][0] - kept[0][0], cyclic, total)) <= tol_x:
        kept.pop()  # the same point, once either side of the turn's start
    for v, k, col in kept:
        info = {"input": file_value(v), "kind": "change point"}
        info.update(_step_links(params, k, fin, col))
        dead.append((v, info))
    dead.sort(key=lambda t: t[1]["input"])

    # transmission angle, limit positions, swing and time ratio of each loop
    facts: dict[int, dict[str, Any]] = {}
    phi_dense = q.out_angle(st)
    phi_fin = q.out_angle(fin)
    unit = mech.angle_to_rad
    for li, (index, lp) in enumerate(loops):
        out: dict[str, Any] = {}
        ta: dict[str, Any] = {}
        for lj, sgn, kind, task, i in ta_tasks:
            if lj != li:
                continue
            key = "min" if sgn > 0 else "max"
            row = q.mu(li, sgn)
            col = task if kind == "root" else nr + task
            refined_x = roots[task] if kind == "root" else mins[task]
            best_x, best = x[i], rows[row, i]
            if np.isfinite(fvals[row, col]) and fvals[row, col] <= best + 1e-12:
                best_x, best = refined_x, fvals[row, col]
            ta[key] = float(sgn * best)
            ta[f"{key}_at"] = file_value(float(best_x))
        if "min" in ta and "max" in ta:
            ta["joint"] = names[lp.rocker_tip]
            out["transmission_angle"] = ta
        # limit positions: refined roots of the rocker's angular velocity, kept when the root is a true zero
        w_dense = rows[q.w(li)]
        scale = float(np.nanmax(np.abs(w_dense))) if np.isfinite(w_dense).any() else 1.0
        limits: list[tuple[float, float, str, int]] = []
        for r in np.flatnonzero(rrow == q.w(li)):
            if not (abs(fval[r]) <= 1e-6 * scale):
                continue
            v = roots[r]
            if any(abs(_cyc(v - u, cyclic, total)) <= tol_x for u, *_ in limits):
                continue
            limits.append((v, float(phi_fin[li, r]), "max" if rsign[r] > 0 else "min", int(ri[r])))
        limits.sort(key=lambda t: file_value(t[0]))
        out["limit_positions"] = [
            {"input": file_value(v), "angle": float(_wrap(a) / unit), "extreme": kind} for v, a, kind, _ in limits
        ]
        # swing of the rocker over the range (one interval): unwrapped along the samples
        if len(intervals) == 1:
            phi = phi_dense[li]
            if np.isfinite(phi).all():
                u = np.unwrap(phi)
                turns = cyclic and abs(u[-1] - u[0] + _wrap(phi[0] - phi[-1])) > math.pi
                out["rocker_turns_fully"] = bool(turns)
                if not turns:
                    cand = [u[i] + _wrap(a - phi[i]) for _, a, _, i in limits]
                    if not cyclic:
                        e_cols = [nr + nm + m for m in range(len(ends))]
                        cand += [u[0] + _wrap(phi_fin[li, c] - phi[0]) for c in e_cols[:1]]
                        cand += [u[-1] + _wrap(phi_fin[li, c] - phi[-1]) for c in e_cols[1:2]]
                    if not cand:
                        cand = [float(np.min(u)), float(np.max(u))]
                    out["swing"] = float((max(cand) - min(cand)) / unit)
        if cyclic and len(limits) == 2 and {t[2] for t in limits} == {"min", "max"}:
            vmin = next(t[0] for t in limits if t[2] == "min")
            vmax = next(t[0] for t in limits if t[2] == "max")
            rising = float(np.mod(vmax - vmin, total))
            falling = total - rising
            out["strokes"] = {"rising": rising / factor, "falling": falling / factor}
            out["time_ratio"] = max(rising, falling) / min(rising, falling) if min(rising, falling) > 0 else None
        facts[index] = out
    return [info for _, info in dead], facts


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
    _, facts = _driver_checks(mech, params, driver, intervals, [(0, fb)])
    ta = facts.get(0, {}).get("transmission_angle", {})
    return {"min": ta["min"], "max": ta["max"]} if ta else {}


# ---------------------------------------------------------------------- kinetostatics
#: the most samples of a file's sweep that ``check`` analyses for its peak loads
MAX_DYNAMICS_SAMPLES = 100_000


def peak_loads(mech: Mechanism) -> dict[str, Any]:
    """Peak driver torque (force for a slider driver) and peak bearing load over the file's sweep.

    Solved by :func:`linkagekit.analyze` on the file's default sweep at the file's input
    speeds and accelerations.  Every peak is the sample of largest magnitude, with the
    input values there (file units); a bearing load is the magnitude of a joint reaction
    (for a slider, the normal force of the guide on the block), in N.
    """
    n = mech.drivers[0].sweep.count()
    out: dict[str, Any] = {
        "samples": n,
        "speeds": {d.name: float(d.speed) for d in mech.drivers},
        "accelerations": {d.name: float(d.acceleration) for d in mech.drivers},
    }
    if n > MAX_DYNAMICS_SAMPLES:
        out["skipped"] = f"the file's sweep has {n} samples, more than check analyses ({MAX_DYNAMICS_SAMPLES})"
        return out
    res = analyze(mech)
    f = res.forces
    if f is None:  # pragma: no cover - has_dynamics guarantees forces
        return out
    inputs = {k: np.broadcast_to(np.asarray(v, float), (res.n_samples,)) for k, v in res.inputs.items()}

    def at(i: int) -> dict[str, float]:
        return {k: float(v[i]) for k, v in inputs.items()}

    for key, efforts in (("peak_driver_torque", f.driver_torque), ("peak_driver_force", f.driver_force)):
        peaks = {}
        for name, arr in efforts.items():
            a = np.asarray(arr, float)
            if np.isfinite(a).any():
                i = int(np.nanargmax(np.abs(a)))
                peaks[name] = {"value": float(a[i]), "at": at(i)}
        if peaks:
            out[key] = peaks
    if f.reactions:
        mags = np.array([np.asarray(r.magnitude, float) for r in f.reactions])
        if np.isfinite(mags).any():
            flat = int(np.nanargmax(mags))
            k, i = divmod(flat, mags.shape[1])
            r = f.reactions[k]
            out["peak_bearing_load"] = {
                "value": float(mags[k, i]),
                "joint": r.joint,
                "on": r.on,
                "by": r.by,
                "kind": "slider" if r.moment is not None else "pin",
                "at": at(i),
            }
    out["assembled"] = int(np.sum(res.assembled))
    return out


# ---------------------------------------------------------------------- the report
@dataclass(frozen=True)
class CheckReport:
    """What ``linkagekit check`` reports (file units; transmission angles in degrees).

    ``input_range`` is the first driver's entry of ``input_ranges`` (each a list of
    ``[start, stop]`` intervals where the mechanism assembles, the other drivers held at
    their pose values, ``held_at``).  ``grashof``, ``fourbar`` and ``transmission_angle``
    describe the first four-bar loop (None without one); ``fourbars`` lists every loop.
    ``dead_points`` maps each driver to the input values where the mechanism locks;
    ``dynamics`` holds the peak loads of a file with masses, gravity or loads.
    ``numerical_joints`` are the joints placed by numerical groups (Newton continued from
    the pose), ``closed_form_joints`` the others; with numerical groups ``input_ranges`` is
    where the pose's mode goes on (by continuation) and ``solvable`` is ``"numerical"``.
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
    dynamics: dict[str, Any] | None = None
    closed_form_joints: tuple[str, ...] = ()
    numerical_joints: tuple[str, ...] = ()

    @property
    def input_range(self) -> list[list[float]]:
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
        return _finite(out)

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
    ranges = {
        d.name: [[float(s / factors[i]), float(e / factors[i])] for s, e in internal[i]]
        for i, d in enumerate(mech.drivers)
    }
    pose_values = {d.name: float(params.pose_inputs[i, 0] / factors[i]) for i, d in enumerate(mech.drivers)}
    held_at = {d.name: {k: v for k, v in pose_values.items() if k != d.name} for d in mech.drivers}
    loops = fourbar_loops(mech, params)
    dead: dict[str, list[dict[str, Any]]] = {}
    facts: dict[int, dict[str, Any]] = {}
    for i, d in enumerate(mech.drivers):
        mine = [(k, lp) for k, lp in enumerate(loops) if lp.driver == i]
        dead[d.name], f = _driver_checks(mech, params, i, internal[i], mine)
        facts.update(f)
    entries = []
    for k, lp in enumerate(loops):
        kind, detail = grashof(lp)
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
        entry.update(facts.get(k, {}))
        entries.append(entry)
    extra: dict[str, Any] = {}
    if entries:
        first = entries[0]
        extra["grashof"], extra["grashof_detail"] = first["grashof"], first["grashof_detail"]
        extra["fourbar"] = {"joints": first["joints"], "lengths": first["lengths"]}
        ta = first.get("transmission_angle")
        if ta:
            extra["transmission_angle"] = {"min": ta["min"], "max": ta["max"]}
    return CheckReport(
        name=mech.name,
        dof=plan.dof,
        drivers=tuple(d.name for d in mech.drivers),
        plan=tuple(plan.describe(params.steps).splitlines()),
        signs={
            j: {"sign": int(params.signs[i, 0]), "rule": plan.sign_labels[i]} for i, j in enumerate(plan.sign_joints)
        },
        mirror_links=plan.mirror_links,
        input_ranges=ranges,
        units={"length": mech.length_unit, "angle": mech.angle_unit},
        fourbars=tuple(entries),
        dead_points=dead,
        held_at=held_at,
        input_units={d.name: d.input_unit(mech) for d in mech.drivers},
        dynamics=peak_loads(mech) if mech.has_dynamics else None,
        closed_form_joints=tuple(j for i, j in enumerate(names) if i not in plan.numerical),
        numerical_joints=tuple(names[i] for i in plan.numerical),
        **extra,
    )


# ---------------------------------------------------------------------- text
def _num(v: Any, fmt: str = ".6g") -> str:
    return "—" if v is None else format(float(v), fmt)


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
    units = dict(rep.get("input_units") or {}) | dict(units or {})
    name = name if name is not None else str(rep.get("name") or "")
    angle_unit = (rep.get("units") or {}).get("angle", "")
    length_unit = (rep.get("units") or {}).get("length", "")
    drivers = list(rep.get("drivers", []))

    def inp(driver: str, v: Any) -> str:
        unit = units.get(driver, "")
        return f"{driver} = {_num(v, '.6f')}" + (f" {unit}" if unit else "")

    def where(at: Mapping[str, Any]) -> str:
        return ", ".join(inp(k, v) for k, v in at.items())

    numerical = list(rep.get("numerical_joints") or [])
    if numerical:
        closed = list(rep.get("closed_form_joints") or [])
        how = (
            f"solved numerically for {', '.join(numerical)} (Newton-Raphson, continued from the pose), "
            f"in closed form for {', '.join(closed) or 'no other joint'}."
        )
    else:
        how = f"solved {'in closed form' if rep.get('solvable') == 'closed-form' else rep.get('solvable', '')}."
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
    if rep.get("mirror_links"):
        lines.append("Links that can be mirrored: " + ", ".join(rep["mirror_links"]))
    held = rep.get("held_at") or {}
    dead_points = rep.get("dead_points") or {}
    for driver, rng in (rep.get("input_ranges") or {}).items():
        text = ", ".join(f"[{a:.6f}, {b:.6f}]" for a, b in rng) if rng else "nowhere"
        unit = units.get(driver, "")
        line = f"Assembles for {driver} in {text}" + (f" {unit}" if rng and unit else "")
        if held.get(driver):
            line += " (" + ", ".join(f"{inp(k, v)}" for k, v in held[driver].items()) + " held at the pose)"
        lines.append(line)
        if numerical:
            lines.append(
                "  in the pose's mode, by continuation from the pose (ends refined by bisection through the solver); "
                "other modes: linkagekit modes"
            )
        if driver in dead_points:
            dps = dead_points[driver]
            lines.append(f"Dead points of {driver} (where the mechanism locks): " + ("none" if not dps else ""))
            lines[-1] = lines[-1].rstrip()
            for dp in dps[:MAX_TEXT_DEAD_POINTS]:
                detail = f"; {dp['detail']}" if dp.get("detail") else ""
                lines.append(f"  {inp(driver, dp['input'])}: {dp['kind']}{detail}")
            if len(dps) > MAX_TEXT_DEAD_POINTS:
                lines.append(f"  ... and {len(dps) - MAX_TEXT_DEAD_POINTS} more (check --format json lists them all)")
    loops: list[Any] | None = rep.get("fourbars")
    if loops is None and "grashof" in rep:  # a report without the list: the first loop only
        loops = [dict(rep.get("fourbar") or {}, grashof=rep["grashof"], grashof_detail=rep.get("grashof_detail"))]
        if "transmission_angle" in rep:
            loops[0]["transmission_angle"] = rep["transmission_angle"]
    loops = loops or []
    for k, lp in enumerate(loops):
        tag = f" {k + 1} of {len(loops)}" if len(loops) > 1 else ""
        lines.append(f"Four-bar loop{tag} {'-'.join(lp.get('joints', []))}: {lp.get('grashof_detail', lp['grashof'])}")
        ln, lens = lp.get("links") or {}, lp.get("lengths") or {}
        if lens:
            lu = f" {length_unit}" if length_unit else ""
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
                    f" (at {ta.get('joint', '')}; min at {inp(driver, ta['min_at'])}, "
                    f"max at {inp(driver, ta['max_at'])})"
                )
            lines.append(text)
        rocker = ln.get("rocker", "rocker")
        if "limit_positions" in lp and driver:
            lims = lp["limit_positions"]
            if lp.get("rocker_turns_fully"):
                lines.append(f"  {rocker} turns fully: no limit positions")
            elif not lims:
                lines.append(f"  Limit positions of {rocker}: none")
            else:
                lines.append(f"  Limit positions of {rocker} (its angular velocity is zero):")
                for lim in lims:
                    lines.append(
                        f"    {inp(driver, lim['input'])}: {rocker} at {_num(lim['angle'], '.6f')} {angle_unit} "
                        f"({lim['extreme']})"
                    )
        if lp.get("swing") is not None:
            lines.append(f"  {rocker} swings {_num(lp['swing'], '.6f')} {angle_unit}")
        if lp.get("time_ratio") is not None:
            s = lp["strokes"]
            unit = units.get(driver or "", "")
            lines.append(
                f"  Time ratio {lp['time_ratio']:.6f} at constant input speed ({driver} travels "
                f"{_num(s['rising'], '.6f')} {unit} while {rocker} rises, "
                f"{_num(s['falling'], '.6f')} {unit} while it falls)"
            )
    dyn = rep.get("dynamics")
    if dyn:
        speeds = ", ".join(
            f"{k} at {_num(v)} {'rad/s' if units.get(k) in ('deg', 'rad') else units.get(k, '') + '/s'}"
            for k, v in (dyn.get("speeds") or {}).items()
        )
        lines.append(f"Peak loads over the file's sweep ({dyn.get('samples')} samples; {speeds}):")
        if dyn.get("skipped"):
            lines.append(f"  not computed: {dyn['skipped']}")
        for key, what, unit in (("peak_driver_torque", "torque", "N*m"), ("peak_driver_force", "force", "N")):
            for drv, pk in (dyn.get(key) or {}).items():
                lines.append(f"  Peak driver {what} of {drv}: {_num(pk['value'])} {unit} at {where(pk['at'])}")
        bl = dyn.get("peak_bearing_load")
        if bl:
            lines.append(
                f"  Peak bearing load: {_num(bl['value'])} N at joint {bl['joint']} ({bl['by']} on {bl['on']}) "
                f"at {where(bl['at'])}"
            )
        if not dyn.get("skipped") and not bl and not dyn.get("peak_driver_torque") and not dyn.get("peak_driver_force"):
            lines.append("  none: the mechanism does not assemble (or is singular) at every sample")
    return "\n".join(lines) + "\n"


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
    """Every assembly mode at one input (``linkagekit modes``); ``input`` in file units."""

    input: dict[str, float]
    modes: tuple[Mode, ...]
    distinct: int
    notes: tuple[str, ...] = ()

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "format": "linkagekit-modes/1",
            "input": self.input,
            "distinct": self.distinct,
            "modes": [m.to_dict() for m in self.modes],
        }
        if self.notes:
            out["notes"] = list(self.notes)
        return out


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
    q0 = params.pose_inputs[:, 0].copy()
    factors = [d.input_scale(mech) for d in mech.drivers]
    given: dict[str, Any] = {}
    if at is not None:
        if isinstance(at, dict):
            given = dict(at)
        elif len(mech.drivers) == 1:
            given = {mech.drivers[0].name: at}
        else:
            raise InputError(f"at: give a value per driver ({', '.join(d.name for d in mech.drivers)})")
    inp = {}
    for i, d in enumerate(mech.drivers):
        if d.name in given:
            try:
                value = float(given.pop(d.name))
            except (TypeError, ValueError, OverflowError):
                raise InputError(f"at: '{d.name}' needs one number") from None
            if not math.isfinite(value) or abs(value) > 1e12:
                raise InputError(f"at: '{d.name}' must be a finite number of at most 1e12 in magnitude")
            q0[i] = value * factors[i]
            inp[d.name] = value  # as given, not through radians and back
        else:
            inp[d.name] = float(q0[i] / factors[i])
    if given:
        raise InputError(f"at: no driver named '{next(iter(given))}' (drivers: {', '.join(plan.drivers)})")
    k, mm = plan.n_signs, plan.n_mirrors if mirrors else 0
    if k + mm > MAX_MODE_SLOTS:
        what = "sign steps and mirror links" if mm else "sign steps"
        raise InputError(
            f"modes: {k + mm} {what} give 2^{k + mm} combinations, more than modes lists "
            f"(2^{MAX_MODE_SLOTS}); fix some with analyze(..., signs={{joint: +1 or -1}})"
        )
    combos = all_sign_combinations(k + mm)
    signs, mirror_flags = combos[:k], combos[k:] < 0
    n = combos.shape[1]
    tol = 1e-9 * mech.length_scale
    groups: list[tuple[str, np.ndarray, np.ndarray]] = []  # label, mode index and count per row
    notes: tuple[str, ...] = ()
    if plan.numerical:  # every mode of each numerical group, for each combination (groupmodes.py)
        table = enumerate_modes(mech, params, q0, signs, mirror_flags if mm else None)
        z, assembled, col, notes = table.z, table.assembled, table.column, table.notes
        for g, gi in enumerate(table.groups):
            label = ",".join(names[j] for j in plan.steps[gi].joints)  # type: ignore[attr-defined]
            groups.append((label, table.group_mode[g], table.group_count[g]))
    else:
        q = np.repeat(q0[:, None, None], n, axis=2)
        sol = solve(params, q, signs[:, None, :], mirror_flags[:, None, :] if mm else None)
        z, assembled, col = sol.z[:, 0], sol.assembled[0], np.arange(n)
    reference = np.all(signs[:, col] == params.signs[:, :1], axis=0)
    if mm:
        reference &= ~mirror_flags[:, col].any(axis=0)
    if plan.numerical:  # and each group in the mode the solver continues from the pose to this input
        cont = solve(params, q0[:, None, None]).z[list(plan.numerical), 0, 0]
        reference &= np.all(np.abs(z[list(plan.numerical)] - cont[:, None]) <= tol, axis=0)
    out: list[Mode] = []
    # distinct configurations: bucket by positions rounded to 1e-6 of the size, then confirm
    # within the bucket to `tol` (two configurations within tol round alike but for a 1e-3 chance
    # at a rounding boundary, which only splits a duplicate, never merges two modes)
    keys = np.round(np.concatenate([z.real, z.imag]) / (1e3 * tol)).T
    buckets: dict[bytes, list[int]] = {}
    firsts: list[int] = []  # the first combination of each distinct assembled configuration
    for r in range(len(col)):
        zc, c = z[:, r], col[r]
        same = None
        if assembled[r]:
            bucket = buckets.setdefault(keys[r].tobytes(), [])
            same = next((f for f in bucket if np.all(np.abs(z[:, f] - zc) <= tol)), None)
            if same is None:
                bucket.append(r)
                firsts.append(r)
        out.append(
            Mode(
                signs={j: int(signs[i, c]) for i, j in enumerate(plan.sign_joints)},
                mirrors={ln: int(combos[k + i, c]) for i, ln in enumerate(plan.mirror_links)} if mm else None,
                assembled=bool(assembled[r]),
                reference=bool(reference[r]),
                joints={
                    j: ((float(zc[i].real), float(zc[i].imag)) if np.isfinite(zc[i]) else None)
                    for i, j in enumerate(names)
                },
                same_as=same,
                groups={lab: {"index": int(ix[r]), "of": int(cnt[r])} for lab, ix, cnt in groups} if groups else None,
            )
        )
    return Modes(inp, tuple(out), len(firsts), notes)
