"""Design checks: where the mechanism assembles, Grashof type, transmission angle, modes.

Everything here is built on the vectorized solver: a dense sweep finds where the
assembled flag changes, and a vectorized bisection refines every boundary at once.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .model import Mechanism
from .plan import Crank, Dyad, Ground
from .positions import all_sign_combinations, pose_inputs, solve

N_COARSE = 7200
N_BISECT = 60


def _assembled(mech: Mechanism, driver: int, values: np.ndarray) -> np.ndarray:
    q = np.repeat(pose_inputs(mech), len(values), axis=1)
    q[driver] = values
    return solve(mech.plan, q).assembled


def input_range(mech: Mechanism, driver: int = 0) -> list[list[float]]:
    """Intervals of one driver's input (file units) where the mechanism assembles.

    The other drivers stay at their reference-pose values.  An angle's intervals lie in
    [0, 360) degrees (or [0, 2 pi)), except that an interval running through 0 starts at
    a negative value; a full turn is ``[[0, 360]]``.  Boundaries are exact to ~1e-12 rad.
    """
    d = mech.drivers[driver]
    if d.kind == "angle":
        lo, hi = 0.0, 2 * math.pi
        x = np.linspace(lo, hi, N_COARSE, endpoint=False)
    else:
        span = 2 * sum(max(ln.length(a, b) for a in ln.joints for b in ln.joints) for ln in mech.links)
        lo, hi = -span, span
        x = np.linspace(lo, hi, N_COARSE + 1)
    ok = _assembled(mech, driver, x)
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
        m_ok = _assembled(mech, driver, mid)
        same = m_ok == inside_a
        a = np.where(same, mid, a)
        b = np.where(same, b, mid)
    edge = np.where(inside_a, a, b)  # the last assembled value on each side
    starts = sorted(edge[~inside_a])
    ends = sorted(edge[inside_a])
    intervals: list[list[float]] = []
    if d.kind == "angle":
        for s in starts:
            e = next((e for e in ends if e >= s), None)
            if e is None:  # runs through 0
                e = ends[0] + 2 * math.pi
                s -= 2 * math.pi
                intervals.insert(0, [s, e])
            else:
                intervals.append([s, e])
    else:
        if ok[0]:
            starts.insert(0, lo)
        if ok[-1]:
            ends.append(hi)
        intervals = [[s, e] for s, e in zip(starts, ends, strict=False)]
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


def fourbar_loop(mech: Mechanism) -> FourBar | None:
    """The first four-bar loop driven directly by a crank on the ground, if any."""
    plan = mech.plan
    ground = next(st for st in plan.steps if isinstance(st, Ground))
    cranks = {st.toward: st for st in plan.steps if isinstance(st, Crank) and st.pivot in ground.joints}
    for st in plan.steps:
        if isinstance(st, Dyad):
            for tip, piv, rc, rr in ((st.k1, st.k2, st.r1, st.r2), (st.k2, st.k1, st.r2, st.r1)):
                if tip in cranks and piv in ground.joints:
                    cr = cranks[tip]
                    g = abs(ground.z[ground.joints.index(piv)] - ground.z[ground.joints.index(cr.pivot)])
                    return FourBar(cr.pivot, tip, st.joint, piv, g, cr.radius, rc, rr)
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


def transmission_angle(mech: Mechanism, fb: FourBar, ranges: list[list[float]], n: int = 7201) -> dict[str, float]:
    """Min and max (degrees) of the angle between coupler and rocker at their joint, over the range."""
    factor = mech.angle_to_rad
    vals = [np.linspace(s * factor, e * factor, n) for s, e in ranges]
    if not vals:
        return {}
    x = np.concatenate(vals)

    def mu(xs: np.ndarray) -> np.ndarray:
        q = np.repeat(pose_inputs(mech), len(xs), axis=1)
        q[0] = xs
        z = solve(mech.plan, q).z
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


def check(mech: Mechanism) -> dict[str, Any]:
    """The report of ``linkagekit check``: freedom, plan, assembly range, Grashof, transmission angle."""
    plan = mech.plan
    names = plan.joint_names
    ranges = {d.name: input_range(mech, i) for i, d in enumerate(mech.drivers)}
    out: dict[str, Any] = {
        "format": "linkagekit-check/1",
        "name": mech.name,
        "dof": plan.dof,
        "drivers": [d.name for d in mech.drivers],
        "solvable": "closed-form",
        "plan": plan.describe().splitlines(),
        "signs": {
            names[st.joint] if hasattr(st, "joint") else str(i): {
                "sign": int(plan.signs[i]),
                "rule": plan.sign_labels[i],
            }
            for i, st in enumerate(plan.sign_steps())
        },
        "mirror_links": list(plan.mirror_links),
        "input_range": ranges[mech.drivers[0].name],
        "input_ranges": ranges,
        "units": {"length": mech.length_unit, "angle": mech.angle_unit},
    }
    fb = fourbar_loop(mech)
    if fb is not None:
        kind, detail = grashof(fb)
        out["grashof"] = kind
        out["grashof_detail"] = detail
        out["fourbar"] = {
            "joints": [names[fb.crank_pivot], names[fb.crank_tip], names[fb.rocker_tip], names[fb.rocker_pivot]],
            "lengths": {"ground": fb.ground, "crank": fb.crank, "coupler": fb.coupler, "rocker": fb.rocker},
        }
        ta = transmission_angle(mech, fb, ranges[mech.drivers[0].name])
        if ta:
            out["transmission_angle"] = ta
    return out


def modes(mech: Mechanism, at: np.ndarray, mirrors: bool = False) -> dict[str, Any]:
    """Every assembly mode (and with ``mirrors`` every mirror image) at one input."""
    plan = mech.plan
    names = plan.joint_names
    k, mm = plan.n_signs, plan.n_mirrors if mirrors else 0
    combos = all_sign_combinations(k + mm)
    signs, mirror_flags = combos[:k], combos[k:] < 0
    n = combos.shape[1]
    q = np.repeat(np.asarray(at, float).reshape(-1, 1), n, axis=1)
    sol = solve(plan, q, signs, mirror_flags if mm else None)
    sign_joints = [names[st.joint] for st in plan.sign_steps()]
    out = []
    seen: list[tuple[int, np.ndarray]] = []
    scale = mech.length_scale
    for c in range(n):
        entry: dict[str, Any] = {"signs": {j: int(signs[i, c]) for i, j in enumerate(sign_joints)}}
        if mm:
            entry["mirrors"] = {ln: int(combos[k + i, c]) for i, ln in enumerate(plan.mirror_links)}
        entry["assembled"] = bool(sol.assembled[c])
        zc = sol.z[:, c]
        entry["joints"] = {
            j: ([float(zc[i].real), float(zc[i].imag)] if np.isfinite(zc[i]) else None) for i, j in enumerate(names)
        }
        entry["reference"] = bool(all(signs[:, c] == np.asarray(plan.signs)) and not (mm and mirror_flags[:, c].any()))
        if sol.assembled[c]:
            dup = next((i for i, zs in seen if np.all(np.abs(zs - zc) <= 1e-9 * scale)), None)
            if dup is not None:
                entry["same_as"] = dup
            else:
                seen.append((c, zc))
        out.append(entry)
    distinct = sum(1 for e in out if e["assembled"] and "same_as" not in e)
    return {"modes": out, "distinct": distinct}
