"""Closed-form positions: run a solve plan over whole arrays of input samples.

Points are complex arrays ``x + 1j*y`` with one entry per sample; every step is a few
NumPy expressions over all samples at once.  A step with no real solution (two circles
that do not meet, a circle that misses a line) gives NaN for its joint and for every
joint placed from it, so a sample that does not assemble is NaN, never a wrong number.

Tolerance
---------
Two circles of radii ``r1, r2`` whose centres are ``s`` apart are taken to meet when
``|r1 - r2| - eps (r1 + r2) <= s <= (r1 + r2)(1 + eps)`` with ``eps = ASSEMBLY_RTOL``;
inside that band a slightly negative ``h^2`` (rounding of a flat or tangent triangle) is
clamped to 0.  Likewise a circle and a line meet when the distance from the centre to
the line is at most ``r (1 + eps)``.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from .plan import Carry, CircleLine, Crank, Dyad, Ground, Pivot, Place, Plan, SliderDrive

if TYPE_CHECKING:
    from .model import Mechanism

#: relative tolerance of the assembly test (see the module docstring)
ASSEMBLY_RTOL = 1e-12
_TINY = 1e-300
#: "not a point": NaN in both coordinates (``nan + 0j`` would print a y of 0)
NAN_POINT = complex(np.nan, np.nan)


@dataclass(frozen=True)
class Positions:
    """Joint positions of a solved sweep.

    Attributes
    ----------
    z : ndarray, complex, shape (n_joints, n)
        Joint positions, NaN where the mechanism does not assemble.
    rot : dict of str to ndarray
        Rotation ``exp(i*theta)`` of each link from its shape frame (only the links that
        the solve needed it for, see :func:`link_rotations` for all).
    margin : ndarray, shape (n_signs, n)
        For each sign step, how far from its assembly limit each sample is (relative;
        negative where the step has no solution).
    assembled : ndarray of bool, shape (n,)
    """

    z: np.ndarray
    rot: dict[str, np.ndarray]
    margin: np.ndarray
    assembled: np.ndarray
    inputs: np.ndarray  # shape (n_drivers, n), radians or length units
    signs: np.ndarray  # shape (n_signs, 1 or n)
    mirrors: np.ndarray  # shape (n_mirrors, 1 or n), bool


def circle_circle(
    z1: np.ndarray, z2: np.ndarray, r1: float, r2: float, sign: np.ndarray | float, eps: float = ASSEMBLY_RTOL
) -> tuple[np.ndarray, np.ndarray]:
    """Intersection of the circles ``|z - z1| = r1`` and ``|z - z2| = r2``.

    ``sign=+1`` picks the point to the left of the directed line ``z1 -> z2``.
    Returns ``(z, margin)``; ``z`` is NaN where the circles do not meet (margin < 0).

    Examples
    --------
    >>> z, m = circle_circle(np.array([0j]), np.array([4+0j]), 5.0, 3.0, 1)
    >>> complex(z[0])
    (4+3j)
    """
    d = z2 - z1
    s2 = d.real * d.real + d.imag * d.imag
    s = np.sqrt(s2)
    total = r1 + r2
    margin = np.minimum(total * (1 + eps) - s, s - abs(r1 - r2) + eps * total)
    margin /= total
    with np.errstate(divide="ignore", invalid="ignore"):
        along = (r1 * r1 - r2 * r2 + s2) / (2 * s)
        h2 = r1 * r1 - along * along
        np.maximum(h2, 0.0, out=h2)
        h = np.sqrt(h2)
        h *= sign
        u = d / s
        z = z1 + along * u + 1j * (h * u)
    ok = margin >= 0
    ok &= s > eps * total
    if ok.all():
        return z, margin
    return np.where(ok, z, NAN_POINT), np.where(ok, margin, np.minimum(margin, -_TINY))


def _line_frame(
    step: CircleLine | SliderDrive, z: np.ndarray, rot: dict[str, np.ndarray]
) -> tuple[np.ndarray | complex, np.ndarray | complex]:
    """Map from the `on` link's frame to the world: ``p -> origin + turn * p``."""
    if step.anchor is None:
        return 0j, 1 + 0j
    turn = rot[step.on]
    return z[step.anchor] - turn * step.anchor_s, turn


def solve(
    plan: Plan,
    inputs: np.ndarray,
    signs: np.ndarray | None = None,
    mirrors: np.ndarray | None = None,
    eps: float = ASSEMBLY_RTOL,
) -> Positions:
    """Positions of every joint for every input sample.

    Parameters
    ----------
    plan : Plan
    inputs : array_like, shape (n_drivers, n)
        Driver values: angles in radians, slider displacements in length units.
    signs : array_like, shape (n_signs,) or (n_signs, n), optional
        +1/-1 per sign step; default: the reference pose's.
    mirrors : array_like of bool, shape (n_mirrors,) or (n_mirrors, n), optional
        True flips the link of three or more joints of that index; default: none.
    """
    q = np.atleast_2d(np.asarray(inputs, dtype=float))
    n = q.shape[1]
    sg = np.asarray(plan.signs if signs is None else signs, dtype=float).reshape(
        plan.n_signs, -1 if plan.n_signs else 1
    )
    mr = (
        np.zeros((plan.n_mirrors, 1), bool)
        if mirrors is None
        else np.asarray(mirrors, bool).reshape(plan.n_mirrors, -1 if plan.n_mirrors else 1)
    )
    z = np.empty((len(plan.joint_names), n), complex)  # every joint is written by exactly one step
    rot: dict[str, np.ndarray] = {"ground": np.ones(n, complex)}
    margin = np.zeros((plan.n_signs, n))
    needs_rot = plan.rotation_links
    for st in plan.steps:
        if isinstance(st, Place):
            base = z[st.k2] - z[st.k1]
            if st.link in needs_rot:
                rot[st.link] = base / st.scale
            for j, rho in zip(st.joints, st.ratios, strict=True):
                if st.mirror is None:
                    z[j] = z[st.k1] + rho * base
                else:
                    z[j] = z[st.k1] + np.where(mr[st.mirror], np.conj(rho), rho) * base
        elif isinstance(st, Dyad):
            z[st.joint], margin[st.sign] = circle_circle(z[st.k1], z[st.k2], st.r1, st.r2, sg[st.sign], eps)
        elif isinstance(st, Crank):
            zt = z[st.toward]
            zt.real = np.cos(q[st.driver])
            zt.imag = np.sin(q[st.driver])
            zt *= st.radius
            zt += z[st.pivot]
        elif isinstance(st, Ground):
            for j, zj in zip(st.joints, st.z, strict=True):
                z[j] = zj
        elif isinstance(st, Carry):
            turn = rot[st.rot_of]
            rot[st.link] = turn
            for j, off in zip(st.joints, st.offsets, strict=True):
                z[j] = z[st.anchor] + turn * off
        elif isinstance(st, CircleLine):
            origin, frame_turn = _line_frame(st, z, rot)
            a = origin + frame_turn * st.point
            e = frame_turn * st.direction
            w = (z[st.center] - a) * np.conj(e)  # centre in line coordinates: (along, offset)
            disc = st.radius**2 - w.imag**2
            m = (st.radius * (1 + eps) - np.abs(w.imag)) / st.radius
            u = w.real + sg[st.sign] * np.sqrt(np.maximum(disc, 0.0))
            z[st.joint] = np.where(m >= 0, a + u * e, NAN_POINT)
            margin[st.sign] = m
        elif isinstance(st, Pivot):
            w = z[st.joint] - z[st.center]
            along = (st.offset * np.conj(st.direction)).real
            off = (st.offset * np.conj(st.direction)).imag
            aw = np.abs(w)
            m = (aw - abs(off) * (1 - eps)) / np.maximum(np.maximum(aw, abs(off)), _TINY)
            u = -along + sg[st.sign] * np.sqrt(np.maximum(aw * aw - off * off, 0.0))
            with np.errstate(divide="ignore", invalid="ignore"):
                turn = w / (st.offset + u * st.direction)
            rot[st.on] = np.where(m >= 0, turn, NAN_POINT)
            margin[st.sign] = m
        elif isinstance(st, SliderDrive):
            origin, frame_turn = _line_frame(st, z, rot)
            rot[st.block] = np.broadcast_to(frame_turn, (n,)) * np.ones(n)
            for j, p in zip(st.joints, st.points, strict=True):
                z[j] = origin + frame_turn * (p + q[st.driver] * st.direction)
    # every failure shows in a step's margin (NaN downstream of it compares False too)
    assembled = np.all(margin >= 0, axis=0) if plan.n_signs else np.ones(n, bool)
    if not assembled.all():  # a mechanism that does not assemble has no joint positions at all
        z[:, ~assembled] = NAN_POINT
    return Positions(z, rot, margin, assembled, q, sg, mr)


# ---------------------------------------------------------------------- the pose's mode
def pose_inputs(mech: Mechanism) -> np.ndarray:
    """The driver values (radians / length) at which the reference pose stands."""
    vals: list[float] = []
    for d in mech.drivers:
        if d.kind == "angle":
            assert d.pivot is not None and d.toward is not None
            vals.append(float(np.angle(mech.joints[d.toward] - mech.joints[d.pivot])))
        else:
            vals.append(0.0)
    return np.array(vals, dtype=float).reshape(-1, 1)


def all_sign_combinations(k: int) -> np.ndarray:
    """Every +1/-1 vector of length k, shape (k, 2**k), starting with all +1."""
    if k == 0:
        return np.ones((0, 1))
    return np.array(list(itertools.product((1.0, -1.0), repeat=k)), dtype=float).T.reshape(k, -1)


def pose_signs(mech: Mechanism, plan: Plan) -> tuple[int, ...]:
    """The assembly mode nearest the reference pose (exactly the pose when lengths are read off it).

    Every sign combination is solved at the pose's own input and the one whose joints lie
    nearest their pose positions wins (ties, as at a flat triangle, go to +1).
    """
    from .errors import MechanismFileError

    k = plan.n_signs
    pose = np.array([mech.joints[j] for j in plan.joint_names])[:, None]
    q0 = pose_inputs(mech)
    if k <= 14:
        combos = all_sign_combinations(k)
        sol = solve(plan, np.repeat(q0, combos.shape[1], axis=1), combos)
        err = np.sum(np.abs(sol.z - pose) ** 2, axis=0)
        err = np.where(np.isfinite(err), err, np.inf)
        best = float(np.min(err)) if err.size else 0.0
        if not np.isfinite(best):
            raise MechanismFileError(
                f"{mech.source}: the mechanism does not assemble at its reference pose's input "
                f"(given lengths that do not close, or a degenerate pose where two joints "
                f"a joint is found from coincide)"
            )
        tol = 1e-18 * mech.length_scale**2 + best * 1e-9
        choice = int(np.flatnonzero(err <= best + tol)[0])
        return tuple(int(v) for v in combos[:, choice])
    signs = np.ones(k)
    for i in range(k):  # greedy, for very large mechanisms
        errs = []
        for v in (1.0, -1.0):
            signs[i] = v
            sol = solve(plan, q0, signs)
            d = np.abs(sol.z - pose) ** 2
            errs.append(float(np.nansum(d)) if np.isfinite(d).any() else np.inf)
        signs[i] = 1.0 if errs[0] <= errs[1] else -1.0
    return tuple(int(v) for v in signs)
