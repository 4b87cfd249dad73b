"""Design checks: where the mechanism assembles, Grashof type, transmission angle, modes.

Everything here is built on the vectorized solver: a dense sweep finds where the
assembled flag changes, and a vectorized bisection refines every boundary at once.
:func:`check` and :func:`modes` take and report values in the file's units.

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
from dataclasses import dataclass
from typing import Any

import numpy as np

from .api import prepare
from .errors import InputError
from .model import Mechanism
from .params import Params, all_sign_combinations
from .positions import solve
from .steps import Crank, Dyad, Ground

N_COARSE = 7200
#: modes lists at most 2^MAX_MODE_SLOTS sign (and mirror) combinations
MAX_MODE_SLOTS = 12
N_BISECT = 60


def _inputs(params: Params, driver: int, values: np.ndarray) -> np.ndarray:
    """Driver values (n_drivers, 1, n): ``values`` for one driver, the pose's for the others."""
    q = np.repeat(params.pose_inputs[:, :, None], len(values), axis=2)
    q[driver, 0] = values
    return q


def _assembled(params: Params, driver: int, values: np.ndarray) -> np.ndarray:
    return solve(params, _inputs(params, driver, values)).assembled[0]


def input_range(mech: Mechanism, driver: int = 0, params: Params | None = None) -> list[list[float]]:
    """Intervals of one driver's input (file units) where the mechanism assembles.

    The other drivers stay at their reference-pose values.  An angle's intervals lie in
    [0, 360) degrees (or [0, 2 pi)), except that an interval running through 0 starts at
    a negative value; a full turn is ``[[0, 360]]``.  Boundaries are exact to ~1e-12 rad.
    """
    params = prepare(mech) if params is None else params
    d = mech.drivers[driver]
    if d.kind == "angle":
        lo, hi = 0.0, 2 * math.pi
        x = np.linspace(lo, hi, N_COARSE, endpoint=False)
    else:
        span = 2 * sum(max(ln.length(a, b) for a in ln.joints for b in ln.joints) for ln in mech.links)
        lo, hi = -span, span
        x = np.linspace(lo, hi, N_COARSE + 1)
    ok = _assembled(params, driver, x)
    factor = mech.angle_to_rad if d.kind == "angle" else 1.0
    if ok.all():
        return [[lo / factor, hi / factor]]
    if not ok.any():
        return []
    # boundaries: a change between sample i and i+1 (cyclic for an angle)
    nxt = np.roll(ok, -1) if d.kind == "angle" else np.append(ok[1:], ok[-1])
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
    if d.kind == "angle":
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
    return [[float(s / factor), float(e / factor)] for s, e in intervals]


@dataclass(frozen=True)
class FourBar:
    """A four-bar loop found in the plan: ground pivot O2 -- crank -- coupler -- rocker -- ground pivot O4."""

    crank_pivot: int
    crank_tip: int
    rocker_tip: int
    rocker_pivot: int
    ground: float
    crank: float
    coupler: float
    rocker: float


def fourbar_loop(mech: Mechanism, params: Params | None = None) -> FourBar | None:
    """The first four-bar loop driven directly by a crank on the ground, if any."""
    params = prepare(mech) if params is None else params
    plan = params.plan
    steps = list(zip(plan.steps, params.steps, strict=True))
    gstep, gnums = next((st, nums) for st, nums in steps if isinstance(st, Ground))
    gz = {j: complex(gnums[0][i, 0, 0]) for i, j in enumerate(gstep.joints)}
    cranks = {st.toward: (st, nums) for st, nums in steps if isinstance(st, Crank) and st.pivot in gz}
    for st, nums in steps:
        if isinstance(st, Dyad):
            r1, r2 = float(nums[0][0, 0]), float(nums[1][0, 0])
            for tip, piv, rc, rr in ((st.k1, st.k2, r1, r2), (st.k2, st.k1, r2, r1)):
                if tip in cranks and piv in gz:
                    cr, cnums = cranks[tip]
                    g = abs(gz[piv] - gz[cr.pivot])
                    return FourBar(cr.pivot, tip, st.joint, piv, g, float(cnums[0][0, 0]), rc, rr)
    return None


def grashof(fb: FourBar, rtol: float = 1e-9) -> tuple[str, str]:
    """Grashof class of a four-bar: (one of the spec's five names, a finer description).

    ``s + l < p + q``: Grashof; the shortest link next to the ground makes a crank-rocker
    (input crank) or rocker-crank (output crank), the ground shortest a double crank, the
    coupler shortest a (Grashof) double rocker.  ``s + l = p + q``: change point.
    Otherwise non-Grashof (triple rocker).
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


def transmission_angle(
    mech: Mechanism, fb: FourBar, ranges: list[list[float]], n: int = 7201, params: Params | None = None
) -> dict[str, float]:
    """Min and max (degrees) of the angle between coupler and rocker at their joint, over the range."""
    params = prepare(mech) if params is None else params
    factor = mech.angle_to_rad
    vals = [np.linspace(s * factor, e * factor, n) for s, e in ranges]
    if not vals:
        return {}
    x = np.concatenate(vals)

    def mu(xs: np.ndarray) -> np.ndarray:
        z = solve(params, _inputs(params, 0, xs)).z[:, 0]
        a = z[fb.crank_tip] - z[fb.rocker_tip]
        b = z[fb.rocker_pivot] - z[fb.rocker_tip]
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.degrees(np.abs(np.angle(b / a)))

    m = mu(x)
    out = {}
    for key, pick, sgn in (("min", np.nanargmin, 1.0), ("max", np.nanargmax, -1.0)):
        i = int(pick(m))
        # refine by golden-section search on the bracket around the best sample
        lo, hi = x[max(i - 1, 0)], x[min(i + 1, len(x) - 1)]
        best = float(m[i])
        g = (math.sqrt(5) - 1) / 2
        a, b = lo, hi
        for _ in range(80):
            c, d = b - g * (b - a), a + g * (b - a)
            fc, fd = mu(np.array([c, d])) * sgn
            if not np.isfinite(fc) or not np.isfinite(fd):
                break
            if fc < fd:
                b = d
            else:
                a = c
        cand = float(mu(np.array([0.5 * (a + b)]))[0])
        if np.isfinite(cand) and (cand - best) * sgn < 0:
            best = cand
        out[key] = best
    return out


@dataclass(frozen=True)
class CheckReport:
    """What ``linkagekit check`` reports (file units; angles of the transmission angle in degrees).

    ``input_range`` is the first driver's entry of ``input_ranges`` (each a list of
    ``[start, stop]`` intervals where the mechanism assembles, the other drivers at the pose).
    ``grashof``, ``fourbar`` and ``transmission_angle`` are None without a four-bar loop.
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
            "solvable": "closed-form",
            "plan": list(self.plan),
            "signs": self.signs,
            "mirror_links": list(self.mirror_links),
            "input_range": self.input_range,
            "input_ranges": self.input_ranges,
            "units": self.units,
        }
        if self.grashof is not None:
            out["grashof"] = self.grashof
            out["grashof_detail"] = self.grashof_detail
            out["fourbar"] = self.fourbar
        if self.transmission_angle:
            out["transmission_angle"] = self.transmission_angle
        return out

    def __getitem__(self, key: str) -> Any:
        """Dictionary-style access to :meth:`to_dict` (``report["grashof"]``)."""
        return self.to_dict()[key]


def check(mech: Mechanism) -> CheckReport:
    """Freedom, solve plan, assembly range, Grashof type and transmission angle of a mechanism."""
    params = prepare(mech)
    plan = params.plan
    names = plan.joint_names
    ranges = {d.name: input_range(mech, i, params) for i, d in enumerate(mech.drivers)}
    extra: dict[str, Any] = {}
    fb = fourbar_loop(mech, params)
    if fb is not None:
        kind, detail = grashof(fb)
        extra["grashof"], extra["grashof_detail"] = kind, detail
        extra["fourbar"] = {
            "joints": [names[fb.crank_pivot], names[fb.crank_tip], names[fb.rocker_tip], names[fb.rocker_pivot]],
            "lengths": {"ground": fb.ground, "crank": fb.crank, "coupler": fb.coupler, "rocker": fb.rocker},
        }
        ta = transmission_angle(mech, fb, ranges[mech.drivers[0].name], params=params)
        if ta:
            extra["transmission_angle"] = ta
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
        **extra,
    )


@dataclass(frozen=True)
class Mode:
    """One assembly mode (and mirror choice) at one input."""

    signs: dict[str, int]
    mirrors: dict[str, int] | None
    assembled: bool
    reference: bool
    joints: dict[str, tuple[float, float] | None]
    same_as: int | None = None

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {"signs": self.signs}
        if self.mirrors is not None:
            out["mirrors"] = self.mirrors
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

    def to_dict(self) -> dict[str, Any]:
        return {
            "format": "linkagekit-modes/1",
            "input": self.input,
            "distinct": self.distinct,
            "modes": [m.to_dict() for m in self.modes],
        }


def modes(mech: Mechanism, at: Any = None, mirrors: bool = False) -> Modes:
    """Every assembly mode (and with ``mirrors`` every mirror image) at one input.

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
    factors = [mech.angle_to_rad if d.kind == "angle" else 1.0 for d in mech.drivers]
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
    q = np.repeat(q0[:, None, None], n, axis=2)
    sol = solve(params, q, signs[:, None, :], mirror_flags[:, None, :] if mm else None)
    z = sol.z[:, 0]
    assembled = sol.assembled[0]
    reference = np.all(signs == params.signs[:, :1], axis=0)
    if mm:
        reference &= ~mirror_flags.any(axis=0)
    out: list[Mode] = []
    tol = 1e-9 * mech.length_scale
    # distinct configurations: bucket by positions rounded to 1e-6 of the size, then confirm
    # within the bucket to `tol` (two configurations within tol round alike but for a 1e-3 chance
    # at a rounding boundary, which only splits a duplicate, never merges two modes)
    keys = np.round(np.concatenate([z.real, z.imag]) / (1e3 * tol)).T
    buckets: dict[bytes, list[int]] = {}
    firsts: list[int] = []  # the first combination of each distinct assembled configuration
    for c in range(n):
        zc = z[:, c]
        same = None
        if assembled[c]:
            bucket = buckets.setdefault(keys[c].tobytes(), [])
            same = next((f for f in bucket if np.all(np.abs(z[:, f] - zc) <= tol)), None)
            if same is None:
                bucket.append(c)
                firsts.append(c)
        out.append(
            Mode(
                signs={j: int(signs[i, c]) for i, j in enumerate(plan.sign_joints)},
                mirrors={ln: int(combos[k + i, c]) for i, ln in enumerate(plan.mirror_links)} if mm else None,
                assembled=bool(assembled[c]),
                reference=bool(reference[c]),
                joints={
                    j: ((float(zc[i].real), float(zc[i].imag)) if np.isfinite(zc[i]) else None)
                    for i, j in enumerate(names)
                },
                same_as=same,
            )
        )
    return Modes(inp, tuple(out), len(firsts))
