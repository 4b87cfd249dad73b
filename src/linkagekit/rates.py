"""Velocities and accelerations, by differentiating every step of the plan analytically.

Each step of :mod:`linkagekit.plan` placed its joints from joints already known; here
the same steps run again on time derivatives.  With ``a . b = Re(conj(a) b)`` the dot
product of two points as complex numbers:

* ``Crank``: ``v_t = v_p + i w e``, ``a_t = a_p + (i alpha - w^2) e`` with ``e = z_t - z_p``.
* ``Place``: ``z_j = z_k1 + rho (z_k2 - z_k1)`` is linear, so ``v`` and ``a`` obey it too.
* ``Dyad``: the two distance constraints ``p . (v_j - v_k1) = 0`` and ``q . (v_j - v_k2) = 0``
  with ``p = z_j - z_k1``, ``q = z_j - z_k2`` form a 2x2 system with determinant
  ``cross(p, q)``; its solution is ``v_j = i (c2 p - c1 q) / cross(p, q)`` with
  ``c1 = p . v_k1``, ``c2 = q . v_k2``.  For accelerations the right-hand sides become
  ``c1 = p . a_k1 - |v_j - v_k1|^2`` (and likewise ``c2``).
* ``CircleLine``, ``Pivot``, ``SliderDrive``, ``Carry``: see the comments at each branch.

Singular positions
------------------
The determinant of each step, made dimensionless (for a dyad ``cross(p, q) / (r1 r2)``,
the sine of the angle at the joint), measures how well the step conditions its rates.
Where it is below ``SINGULAR_TOL`` in magnitude (a flat triangle: dead point, change
point, toggle) the rates are not defined: every rate of that sample is NaN and the
sample is flagged ``singular``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .plan import Carry, CircleLine, Crank, Dyad, Ground, Pivot, Place, Plan, SliderDrive
from .positions import NAN_POINT, Positions

#: |sin| of a step's angle below which its rates are undefined (see the module docstring)
SINGULAR_TOL = 1e-6


@dataclass(frozen=True)
class Rates:
    """Velocities and accelerations of every joint, complex arrays (n_joints, n)."""

    v: np.ndarray
    a: np.ndarray
    omega: dict[str, np.ndarray]  # links whose rates the steps needed
    alpha: dict[str, np.ndarray]
    condition: np.ndarray  # (n_signs, n): dimensionless conditioning of each sign step
    singular: np.ndarray  # (n,) bool


def abs2(a: np.ndarray) -> np.ndarray:
    """Squared magnitude of planar vectors written as complex numbers."""
    return a.real * a.real + a.imag * a.imag


def dot(a: np.ndarray | complex, b: np.ndarray | complex) -> np.ndarray:
    """Dot product of planar vectors written as complex numbers."""
    a, b = np.asarray(a), np.asarray(b)
    return a.real * b.real + a.imag * b.imag


def cross(a: np.ndarray | complex, b: np.ndarray | complex) -> np.ndarray:
    """z-component of the cross product of planar vectors written as complex numbers."""
    a, b = np.asarray(a), np.asarray(b)
    return a.real * b.imag - a.imag * b.real


def link_rates(base: np.ndarray, vbase: np.ndarray, abase: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Angular velocity and acceleration of the line ``base`` from its first two derivatives.

    ``base = |b| e^{i theta}`` with constant length, so ``vbase = i w base`` and
    ``abase = (i alpha - w^2) base``.
    """
    n2 = abs2(base)
    with np.errstate(divide="ignore", invalid="ignore"):
        return cross(base, vbase) / n2, cross(base, abase) / n2


def solve_rates(
    plan: Plan,
    pos: Positions,
    speed: np.ndarray,
    accel: np.ndarray,
    rate_links: frozenset[str] = frozenset(),
    tol: float = SINGULAR_TOL,
) -> Rates:
    """Velocities and accelerations for driver speeds and accelerations (arrays (n_drivers, n))."""
    z = pos.z
    n = z.shape[1]
    w_in = np.broadcast_to(np.asarray(speed, float).reshape(len(plan.drivers), -1), (len(plan.drivers), n))
    a_in = np.broadcast_to(np.asarray(accel, float).reshape(len(plan.drivers), -1), (len(plan.drivers), n))
    v = np.full_like(z, NAN_POINT)  # every row is written by one step; NaN shows one that is not
    a = np.full_like(z, NAN_POINT)
    om: dict[str, np.ndarray] = {"ground": np.zeros(n)}
    al: dict[str, np.ndarray] = {"ground": np.zeros(n)}
    cond = np.ones((plan.n_signs, n))
    with np.errstate(divide="ignore", invalid="ignore"):
        for st in plan.steps:
            if isinstance(st, Place):
                for j, ratio in zip(st.joints, st.ratios, strict=True):
                    rho: complex | np.ndarray = ratio
                    if st.mirror is not None:
                        rho = np.where(pos.mirrors[st.mirror], np.conj(ratio), ratio)
                    v[j] = v[st.k1] + rho * (v[st.k2] - v[st.k1])
                    a[j] = a[st.k1] + rho * (a[st.k2] - a[st.k1])
                if st.link in rate_links and st.link not in om:
                    om[st.link], al[st.link] = link_rates(z[st.k2] - z[st.k1], v[st.k2] - v[st.k1], a[st.k2] - a[st.k1])
            elif isinstance(st, Dyad):
                # conj(p) x = dot(p, x) + i cross(p, x): one complex product gives both
                p = z[st.joint] - z[st.k1]
                q = z[st.joint] - z[st.k2]
                pc, qc = np.conj(p), np.conj(q)
                det = (pc * q).imag
                inv = 1.0 / det
                cond[st.sign] = det * (1.0 / (st.r1 * st.r2))
                c1 = (pc * v[st.k1]).real
                c2 = (qc * v[st.k2]).real
                vj = (c2 * p - c1 * q) * (1j * inv)
                # the two links turn at w1 = cross(p, vj - v_k1) / r1^2, w2 likewise; and
                # |vj - v_k1|^2 = (w1 r1)^2, the centripetal term of the acceleration
                w1 = (pc * (vj - v[st.k1])).imag * (1.0 / st.r1**2)
                w2 = (qc * (vj - v[st.k2])).imag * (1.0 / st.r2**2)
                c1 = (pc * a[st.k1]).real - (w1 * st.r1) ** 2
                c2 = (qc * a[st.k2]).real - (w2 * st.r2) ** 2
                aj = (c2 * p - c1 * q) * (1j * inv)
                v[st.joint], a[st.joint] = vj, aj
                for link, w, r, k, rc in ((st.links[0], w1, st.r1, st.k1, pc), (st.links[1], w2, st.r2, st.k2, qc)):
                    if link not in om:
                        om[link], al[link] = w, (rc * (aj - a[k])).imag * (1.0 / r**2)
            elif isinstance(st, Crank):
                e = z[st.toward] - z[st.pivot]
                w, al_in = w_in[st.driver], a_in[st.driver]
                v[st.toward] = v[st.pivot] + 1j * w * e
                a[st.toward] = a[st.pivot] + (1j * al_in - w * w) * e
                om[st.link], al[st.link] = w, al_in
            elif isinstance(st, Ground):
                v[list(st.joints)] = 0.0
                a[list(st.joints)] = 0.0
            elif isinstance(st, Carry):
                # rigid motion with the rotation of another link: v = v_0 + i w (z - z_0)
                w, alpha = om[st.rot_of], al[st.rot_of]
                om[st.link], al[st.link] = w, alpha
                for j in st.joints:
                    r = z[j] - z[st.anchor]
                    v[j] = v[st.anchor] + 1j * w * r
                    a[j] = a[st.anchor] + (1j * alpha - w * w) * r
            elif isinstance(st, CircleLine):
                # z_j = A + u E with A, E carried by `on`; the circle gives p . (v_j - v_c) = 0.
                w, alpha, va, aa, za = _frame_rates(st.on, st.anchor, z, v, a, om, al, n)
                turn = pos.rot[st.on] if st.anchor is not None else 1.0
                zA = (z[st.anchor] - turn * st.anchor_s if st.anchor is not None else 0.0) + turn * st.point
                E = turn * st.direction
                u = dot(E, z[st.joint] - zA)
                vA = va + 1j * w * (zA - za)
                aA = aa + (1j * alpha - w * w) * (zA - za)
                vE, aE = 1j * w * E, (1j * alpha - w * w) * E
                p = z[st.joint] - z[st.center]
                pe = dot(p, E)
                cond[st.sign] = pe / st.radius
                du = dot(p, v[st.center] - vA - u * vE) / pe
                v[st.joint] = vA + u * vE + du * E
                dv = v[st.joint] - v[st.center]
                ddu = (dot(p, a[st.center] - aA - u * aE - 2 * du * vE) - np.abs(dv) ** 2) / pe
                a[st.joint] = aA + u * aE + 2 * du * vE + ddu * E
            elif isinstance(st, Pivot):
                # z_j - z_c = g = rot (offset + u d):  v_j - v_c = i w g + du E  with E = rot d
                g = z[st.joint] - z[st.center]
                E = pos.rot[st.on] * st.direction
                wg = np.conj(E) * g
                cond[st.sign] = np.real(wg) / np.abs(g)
                dv = np.conj(E) * (v[st.joint] - v[st.center])
                w = np.imag(dv) / np.real(wg)
                du = np.real(dv) + w * np.imag(wg)
                da = np.conj(E) * (a[st.joint] - a[st.center] + w * w * g - 2j * w * du * E)
                alpha = np.imag(da) / np.real(wg)
                om[st.on], al[st.on] = w, alpha
            elif isinstance(st, SliderDrive):
                w, alpha, va, aa, za = _frame_rates(st.on, st.anchor, z, v, a, om, al, n)
                turn = pos.rot[st.on] if st.anchor is not None else 1.0
                E = turn * st.direction
                du, ddu = w_in[st.driver], a_in[st.driver]
                om[st.block], al[st.block] = w, alpha
                for j in st.joints:
                    r = z[j] - za
                    v[j] = va + 1j * w * r + du * E
                    a[j] = aa + (1j * alpha - w * w) * r + 2j * w * du * E + ddu * E
    singular = np.any(np.abs(cond) < tol, axis=0) & pos.assembled
    bad = singular | ~pos.assembled
    if bad.any():
        v[:, bad] = NAN_POINT
        a[:, bad] = NAN_POINT
        for rates_of in (om, al):
            for link in rates_of:
                rates_of[link] = np.where(bad, np.nan, rates_of[link])
    return Rates(v, a, om, al, cond, singular)


def _frame_rates(
    on: str,
    anchor: int | None,
    z: np.ndarray,
    v: np.ndarray,
    a: np.ndarray,
    om: dict[str, np.ndarray],
    al: dict[str, np.ndarray],
    n: int,
):  # type: ignore[no-untyped-def]
    """Angular rates of link `on` and the motion of its anchor joint (all zero for the ground)."""
    if anchor is None:
        zero = np.zeros(n)
        return zero, zero, 0.0, 0.0, 0.0
    return om[on], al[on], v[anchor], a[anchor], z[anchor]
