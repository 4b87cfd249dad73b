"""Velocities and accelerations: the plan's steps differentiated analytically.

Each step of :mod:`linkagekit.steps` placed its joints from joints already known; its
``rates`` method runs the same construction on the time derivatives (the formulas are
beside each step's placement, and derived in ``docs/method.md``).

Singular positions
------------------
The determinant of each sign step, made dimensionless (for a dyad ``cross(p, q) / (r1 r2)``,
the sine of the angle at the joint), measures how well the step conditions its rates.
Where it is below ``SINGULAR_TOL`` in magnitude (a flat triangle: dead point, change
point, toggle) the rates are not defined: every rate of that sample is NaN and the
sample is flagged ``singular``.  (Following a branch continuously, a sample exactly on a
change point gets the branch's limit, rates included, and stays flagged:
:func:`linkagekit.branch.limits`.)
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .geometry import NAN_POINT, link_rates
from .params import Params
from .positions import Positions
from .steps import Rate

#: |sin| of a step's angle below which its rates are undefined (see the module docstring)
SINGULAR_TOL = 1e-6
#: ... and below which :func:`linkagekit.analyze` reports none: rounding in the positions near a singular position
#: grows in the rates as about ``eps / c^2`` (velocities) and ``1.5 eps / c^3`` (accelerations, forces), ``c`` the
#: step's condition; a parallelogram 1e-3 deg from its flat position (``c = 1.7e-5``) had its rocker's angular
#: acceleration -4.8 rad/s^2 where it is 0, unflagged. Above this, accelerations hold to about 3e-4 of their scale,
#: velocities to 2e-8 (measured, docs/method.md)
REPORTED_TOL = 1e-4

__all__ = ["REPORTED_TOL", "SINGULAR_TOL", "LinkMotion", "Rates", "link_motion", "solve_rates"]


@dataclass(frozen=True)
class Rates:
    """Velocities and accelerations of every joint, complex arrays (n_joints, D, n).

    ``omega``/``alpha``: angular rates of the links the steps knew them for; ``condition``
    (n_signs + n_groups, D, n) the dimensionless conditioning of each sign step, then of each
    numerical group; ``singular`` (D, n); ``limit`` (D, n) or None: the samples whose rates are
    the followed branch's limit at a change point (:func:`linkagekit.branch.limits`), defined
    although ``singular``.
    """

    v: np.ndarray
    a: np.ndarray
    omega: dict[str, Any]
    alpha: dict[str, Any]
    condition: np.ndarray
    singular: np.ndarray
    limit: np.ndarray | None = None


def solve_rates(
    params: Params,
    pos: Positions,
    speed: np.ndarray,
    accel: np.ndarray,
    tol: float = SINGULAR_TOL,
    out: tuple[np.ndarray, np.ndarray] | None = None,
) -> Rates:
    """Velocities and accelerations for driver speeds and accelerations, arrays (n_drivers, D or 1, n or 1).

    ``out``: two complex arrays shaped like ``pos.z`` to write the velocities and accelerations into.
    """
    plan = params.plan
    z = pos.z
    shape = z.shape[1:]
    if out is None:
        v, a = np.empty_like(z), np.empty_like(z)
    else:
        v, a = out
    v.fill(NAN_POINT)  # a joint no step writes stays NaN
    a.fill(NAN_POINT)
    r = Rate(
        z,
        pos.rot,
        pos.mirrors,
        v,
        a,
        np.asarray(speed, float),
        np.asarray(accel, float),
        np.ones((plan.n_signs, *shape)),
        {"ground": 0.0},
        {"ground": 0.0},
    )
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        for st, nums in zip(plan.steps, params.steps, strict=True):
            st.rates(r, nums)
    singular = np.any(np.abs(r.cond) < tol, axis=0) & pos.assembled
    for gc in r.extra_cond:  # numerical groups
        singular |= (np.abs(gc) < tol) & pos.assembled
    bad = singular | ~pos.assembled
    if bad.any():
        r.v[:, bad] = NAN_POINT
        r.a[:, bad] = NAN_POINT
        for rates_of in (r.om, r.al):
            for link in rates_of:
                rates_of[link] = np.where(bad, np.nan, rates_of[link])
    cond = np.concatenate([r.cond, np.stack(r.extra_cond)]) if r.extra_cond else r.cond
    return Rates(r.v, r.a, r.om, r.al, cond, singular)


#: a link's motion: rotation ``e^{i theta}`` from its shape frame, angular velocity, angular acceleration
LinkMotion = tuple[Any, Any, Any]


def link_motion(params: Params, pos: Positions, rates: Rates | None, links: Any) -> dict[str, LinkMotion]:
    """Rotation from the shape frame, omega and alpha of every link, each (D, n) (or a scalar for the ground).

    A link of two or more joints turns as the line from its first joint to its second:
    ``rot = (z_b - z_a) / (s_b - s_a)``, and its rates are the ones its step computed or
    :func:`link_rates` of that line.  A one-joint block turns with the link it slides on
    (the rotation its step recorded).  ``links`` is the mechanism's links; without
    ``rates``, omega and alpha are None.
    """
    names = params.plan.joint_names
    z = pos.z
    if rates is None:
        bad = ~pos.assembled
    else:  # a branch's limit at a change point has rates although singular
        bad = (rates.singular if rates.limit is None else rates.singular & ~rates.limit) | ~pos.assembled
    out: dict[str, LinkMotion] = {}
    for ln in links:
        if ln.name == "ground":
            zero = np.where(bad, np.nan, 0.0) if rates is not None else None
            out[ln.name] = (np.where(pos.assembled, 1.0 + 0j, NAN_POINT), zero, zero)
            continue
        if len(ln.joints) >= 2:
            i, k = names.index(ln.joints[0]), names.index(ln.joints[1])
            sa, sb = params.bases[ln.name]
            base = z[k] - z[i]
            rot = base / (sb - sa)
            if rates is None:
                w = al = None
            elif ln.name in rates.omega:  # the step that placed the link knew its rates
                w, al = rates.omega[ln.name], rates.alpha[ln.name]
            else:
                w, al = link_rates(base, rates.v[k] - rates.v[i], rates.a[k] - rates.a[i])
        else:  # a block of one joint: it turns with the link it slides on
            rot = np.where(pos.assembled, np.broadcast_to(pos.rot.get(ln.name, 1.0 + 0j), z.shape[1:]), NAN_POINT)
            if rates is None:
                w = al = None
            else:
                w = np.where(bad, np.nan, rates.omega.get(ln.name, 0.0))
                al = np.where(bad, np.nan, rates.alpha.get(ln.name, 0.0))
        if w is not None and al is not None and bad.any():
            w, al = np.where(bad, np.nan, w), np.where(bad, np.nan, al)
        out[ln.name] = (rot, w, al)
    return out
