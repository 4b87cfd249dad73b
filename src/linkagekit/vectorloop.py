"""The vector-loop method: a second, independent kinematics for four-bars and Stephenson six-bars.

The main solver (:mod:`linkagekit.positions`, :mod:`linkagekit.rates`) works on joint
coordinates.  This module follows the seed papers instead: every link is a vector
``L e^{i theta}``, the unknowns are link *angles*, and each closed loop gives one complex
equation ``sum_k s_k L_k e^{i theta_k} = 0``.

* Four-bar (seed 003): the loop ``r2 + r3 = r1 + r4`` is solved by the fixed-point
  iteration of its eqs. (4)-(5), written with ``atan2`` so that every quadrant is
  reachable, and polished by Newton-Raphson; velocities by its eqs. (8), (13), (14), (9),
  (15) and accelerations by its eqs. (16), (21)-(23), (17), (24).
* Stephenson six-bar in the layout of seed 001 (ternary input link and ternary output
  link both pivoted on the ground, joined directly by one binary link and through a dyad
  of two binaries): Newton-Raphson on the six equations of its corrected eq. (18) (two
  complex loops and the two rigid angles ``theta6 = theta2 - alpha``, ``theta8 =
  theta5 + beta``), started from seed 003's fixed-point iteration on each loop; rates
  from the corrected 6x6 systems (19) and (20) (see ``docs/seed-errata.md``).

Everything is vectorized over samples (Newton-Raphson on stacked 6x6 matrices with
:func:`numpy.linalg.solve`).  The assembly mode is chosen explicitly by a branch per loop,
``+1`` when the loop's free joint lies left of the line from its first to its second known
joint, which is the same convention as the signs of the main solver; seed 003's iteration
converges to the branch on the side of its starting guess, so the guess is put there.

:func:`linkagekit.analyze` uses this module with ``method="vector-loop"``.

Examples
--------
>>> import numpy as np
>>> from linkagekit.vectorloop import FourBar
>>> fb = FourBar(ground=-0.35 + 0j, crank=0.7, coupler=0.3, rocker=0.5, branch=1)  # seed 003, ex. 2.1 (m)
>>> sol = fb.solve(np.radians([120.0]), omega2=5.0, alpha2=0.0)
>>> print(np.round(sol.omega["coupler"], 6), np.round(sol.omega["rocker"], 6))
[10.097332] [2.994888]
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from .errors import MethodNotApplicableError
from .geometry import NAN_POINT, cross
from .model import CrankType
from .rates import REPORTED_TOL

if TYPE_CHECKING:
    from .model import Link, Mechanism

#: where a loop's sine ``sin(theta_a - theta_b)`` is below this, its rates are not reported (the natural-coordinate
#: solver's threshold, :data:`linkagekit.rates.REPORTED_TOL`: rounding grows there as it does in that solver)
SINGULAR_TOL = REPORTED_TOL
#: relative tolerance of the triangle-inequality assembly test
ASSEMBLY_RTOL = 1e-12


def cis(theta: np.ndarray) -> np.ndarray:
    """``e^{i theta}``, the unit vector at angle ``theta``."""
    out: np.ndarray = np.cos(theta) + 1j * np.sin(theta)
    return out


def fixed_point_loop(
    p: np.ndarray, q: np.ndarray, la: float, lb: float, branch: float, *, tol: float = 1e-13, max_iter: int = 500
) -> tuple[np.ndarray, np.ndarray]:
    """Close ``p + la e^{i ta} = q + lb e^{i tb}`` by seed 003's fixed-point iteration (its eqs. 4-5).

    ``tb = atan2(p + la e^{i ta} - q)`` then ``ta = atan2(q + lb e^{i tb} - p)``, repeated.
    Each half-step projects onto one circle, so the iteration converges linearly (slowly
    near a limit position) to the solution on the side of the line ``p -> q`` where it
    starts: it starts at ``ta = arg(q - p) + branch * 90 deg``.  Samples that do not close
    come back NaN.
    """
    p, q = np.broadcast_arrays(np.asarray(p, complex), np.asarray(q, complex))
    s = np.abs(q - p)
    closes = (s <= (la + lb) * (1 + ASSEMBLY_RTOL)) & (s >= abs(la - lb) * (1 - ASSEMBLY_RTOL))
    ta = np.angle(q - p) + branch * np.pi / 2
    tb = np.angle(p + la * cis(ta) - q)
    for _ in range(max_iter):
        ta_new = np.angle(q + lb * cis(tb) - p)
        tb = np.angle(p + la * cis(ta_new) - q)
        step = np.abs(np.angle(cis(ta_new - ta)))
        ta = ta_new
        if not np.any(closes & (step > tol)):
            break
    nan = np.where(closes, 0.0, np.nan)
    return ta + nan, tb + nan


def newton_loop(
    p: np.ndarray, q: np.ndarray, la: float, lb: float, ta: np.ndarray, tb: np.ndarray, iterations: int = 60
) -> tuple[np.ndarray, np.ndarray]:
    """Newton-Raphson on ``phi = p + la e^{i ta} - q - lb e^{i tb} = 0``, 2x2 by Cramer's rule.

    Quadratic convergence from the fixed-point answer; only at a double root (a limit or
    change point) is it linear, which is why it may take up to ``iterations`` steps.
    """
    for _ in range(iterations):
        ca, cb = 1j * la * cis(ta), -1j * lb * cis(tb)  # d phi / d ta, d phi / d tb
        phi = p + la * cis(ta) - q - lb * cis(tb)
        with np.errstate(divide="ignore", invalid="ignore"):
            det = cross(ca, cb)
            dta, dtb = cross(-phi, cb) / det, cross(ca, -phi) / det
        ok = np.isfinite(dta) & np.isfinite(dtb)
        ta, tb = np.where(ok, ta + dta, ta), np.where(ok, tb + dtb, tb)
        if not np.any(ok & (np.abs(dta) + np.abs(dtb) > 1e-15)):
            break
    return ta, tb


@dataclass(frozen=True)
class LoopSolution:
    """Angles, joint positions and their rates from the vector-loop method.

    ``theta``, ``omega``, ``alpha``: per link (rad, rad/s, rad/s^2); ``z``, ``v``, ``a``:
    complex per joint; ``assembled`` and ``singular`` per sample; ``condition`` is the
    smallest ``|sin(theta_a - theta_b)|`` over the loops (1 well conditioned, 0 singular).
    Rates are NaN where the sample is singular or does not assemble.
    """

    theta: dict[str, np.ndarray]
    omega: dict[str, np.ndarray]
    alpha: dict[str, np.ndarray]
    z: dict[str, np.ndarray]
    v: dict[str, np.ndarray]
    a: dict[str, np.ndarray]
    assembled: np.ndarray
    singular: np.ndarray
    condition: np.ndarray


def _point(
    z0: np.ndarray, v0: np.ndarray, a0: np.ndarray, r: np.ndarray, w: np.ndarray, al: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Point ``z0 + r`` of a link turning at ``w``, ``al``: seed 003's eqs. (15), (24) as complex numbers."""
    return z0 + r, v0 + 1j * w * r, a0 + (1j * al - w * w) * r


Arrays = dict[str, np.ndarray]


def _carry_points(
    points: tuple[tuple[str, str, complex], ...],
    base: dict[str, str],
    origin: np.ndarray,
    theta: Arrays,
    omega: Arrays,
    alpha: Arrays,
    z: Arrays,
    v: Arrays,
    a: Arrays,
) -> None:
    """Joints off the loops, each ``Z1 e^{i beta}`` from its link's base joint (seed 003's P), in place."""
    zero = np.zeros_like(origin)
    for joint, link, off in points:
        if link == "ground":
            z[joint], v[joint], a[joint] = origin + off, zero, zero
            continue
        b = base[link]
        z[joint], v[joint], a[joint] = _point(z[b], v[b], a[b], off * cis(theta[link]), omega[link], alpha[link])


def _finish(
    theta: Arrays,
    omega: Arrays,
    alpha: Arrays,
    z: Arrays,
    v: Arrays,
    a: Arrays,
    assembled: np.ndarray,
    condition: np.ndarray,
) -> LoopSolution:
    """The solution, NaN where undefined: rates where singular or not assembled, positions where not assembled."""
    singular = assembled & (np.abs(condition) < SINGULAR_TOL)
    bad = singular | ~assembled
    for d in (omega, alpha):
        for k in d:
            d[k] = np.where(bad, np.nan, d[k])
    for d in (v, a):
        for k in d:
            d[k] = np.where(bad, NAN_POINT, d[k])
    for k in z:
        z[k] = np.where(assembled, z[k], NAN_POINT)
    return LoopSolution(theta, omega, alpha, z, v, a, assembled, singular, condition)


@dataclass(frozen=True)
class FourBar:
    """Seed 003's four-bar: crank ``O1 A`` (length L2), coupler ``A B`` (L3), rocker ``O2 B`` (L4).

    ``ground`` is ``O2 - O1`` as a complex number, ``origin`` is ``O1``; coupler points are
    ``(Z1, beta)`` pairs from ``A`` (seed 003's ``r_AP``), given as complex ``Z1 e^{i beta}``
    in ``points``.  ``branch`` is +1 when ``B`` lies left of the line ``A -> O2``.
    """

    ground: complex
    crank: float
    coupler: float
    rocker: float
    branch: float = 1.0
    origin: complex = 0j
    points: tuple[tuple[str, str, complex], ...] = ()  # (joint, link, Z1 e^{i beta} from the link's base)
    names: tuple[str, str, str, str, str, str, str] = ("O1", "O2", "A", "B", "crank", "coupler", "rocker")

    def solve(
        self, theta2: np.ndarray, omega2: np.ndarray | float = 0.0, alpha2: np.ndarray | float = 0.0
    ) -> LoopSolution:
        """Positions and rates at crank angles ``theta2`` (rad, from the x axis)."""
        o1, o2, jA, jB, crank, coupler, rocker = self.names
        th2 = np.asarray(theta2, float)
        w2 = np.broadcast_to(np.asarray(omega2, float), th2.shape)
        al2 = np.broadcast_to(np.asarray(alpha2, float), th2.shape)
        L2, L3, L4, O2 = self.crank, self.coupler, self.rocker, np.asarray(self.ground)
        r2 = L2 * cis(th2)
        th3, th4 = fixed_point_loop(r2, O2, L3, L4, self.branch)
        th3, th4 = newton_loop(r2, O2, L3, L4, th3, th4)
        assembled = np.isfinite(th3)
        r3, r4 = L3 * cis(th3), L4 * cis(th4)
        # (8) and (16): the crank end
        vA = 1j * w2 * r2
        aA = (1j * al2 - w2 * w2) * r2
        with np.errstate(divide="ignore", invalid="ignore"):
            s34 = np.sin(th3 - th4)
            w3 = (vA.real * np.cos(th4) + vA.imag * np.sin(th4)) / (L3 * s34)  # (13)
            w4 = (vA.real * np.cos(th3) + vA.imag * np.sin(th3)) / (L4 * s34)  # (14)
            vB = 1j * w4 * r4  # (9)
            a1 = aA.real - w3 * (vB.imag - vA.imag) + w4 * vB.imag  # (21)
            a2 = aA.imag + w3 * (vB.real - vA.real) - w4 * vB.real
            al3 = (a1 * np.cos(th4) + a2 * np.sin(th4)) / (L3 * s34)  # (22)
            al4 = (a1 * np.cos(th3) + a2 * np.sin(th3)) / (L4 * s34)  # (23)
        aB = (1j * al4 - w4 * w4) * r4  # (17)
        zero = np.zeros_like(th2)
        origin = self.origin + zero
        z = {o1: origin, o2: origin + O2, jA: origin + r2, jB: origin + r2 + r3}
        v = {o1: zero + 0j, o2: zero + 0j, jA: vA, jB: vB}
        a = {o1: zero + 0j, o2: zero + 0j, jA: aA, jB: aB}
        theta = {crank: th2, coupler: th3, rocker: th4}
        omega = {crank: w2 + zero, coupler: w3, rocker: w4}
        alpha = {crank: al2 + zero, coupler: al3, rocker: al4}
        _carry_points(self.points, {crank: o1, coupler: jA, rocker: o2}, origin, theta, omega, alpha, z, v, a)
        return _finish(theta, omega, alpha, z, v, a, assembled, s34)


@dataclass(frozen=True)
class Stephenson:
    """Seed 001's Stephenson six-bar, with its letters.

    Ground ``O_A -> O_B = a e^{i theta1}``.  Input ternary link (angle ``theta2``): ``b`` to
    ``Q`` and ``f`` to ``S`` at ``theta6 = theta2 - alpha``.  Output ternary link pivoted at
    ``O_B``: ``e`` to ``Y`` (``theta5``) and ``h`` to ``W`` (``theta8 = theta5 + beta``).
    Binary ``g`` joins ``S`` and ``W`` (``theta7``); the dyad ``c`` (``Q X``, ``theta3``)
    and ``d`` (``Y X``, ``theta4``) closes the first loop::

        loop 1:  b e2 + c e3 - d e4 - e e5 - a e1 = 0
        loop 2:  f e6 + g e7 - h e8 - a e1 = 0

    ``branches`` = (s1, s2): s1 = +1 when ``W`` is left of ``S -> O_B``; s2 = +1 when ``X``
    is left of ``Q -> Y``.
    """

    a: float
    theta1: float
    b: float
    c: float
    d: float
    e: float
    f: float
    g: float
    h: float
    alpha_: float
    beta: float
    branches: tuple[float, float] = (1.0, 1.0)
    origin: complex = 0j
    points: tuple[tuple[str, str, complex], ...] = ()
    # joint names O_A, O_B, Q, S, W, Y, X; link names input, c, g, output, d
    names: tuple[str, ...] = ("OA", "OB", "Q", "S", "W", "Y", "X", "input", "link3", "link4", "output", "link6")

    def residual(self, th2: np.ndarray, q: np.ndarray) -> np.ndarray:
        """Phi(q) of the corrected eq. (18), shape (6, n); q = [theta3 .. theta8]."""
        t3, t4, t5, t6, t7, t8 = q
        ground = self.a * cis(np.asarray(self.theta1))
        l1 = self.b * cis(th2) + self.c * cis(t3) - self.d * cis(t4) - self.e * cis(t5) - ground
        l2 = self.f * cis(t6) + self.g * cis(t7) - self.h * cis(t8) - ground
        return np.array([l1.real, l2.real, l1.imag, l2.imag, t6 - th2 + self.alpha_, t5 - t8 + self.beta])

    def jacobian(self, q: np.ndarray) -> np.ndarray:
        """d Phi / d q, shape (n, 6, 6): the matrix of the corrected eqs. (18)-(20)."""
        t3, t4, t5, t6, t7, t8 = q
        n = q.shape[1]
        J = np.zeros((n, 6, 6))
        cols1 = {0: 1j * self.c * cis(t3), 1: -1j * self.d * cis(t4), 2: -1j * self.e * cis(t5)}
        cols2 = {3: 1j * self.f * cis(t6), 4: 1j * self.g * cis(t7), 5: -1j * self.h * cis(t8)}
        for k, col in cols1.items():
            J[:, 0, k], J[:, 2, k] = col.real, col.imag
        for k, col in cols2.items():
            J[:, 1, k], J[:, 3, k] = col.real, col.imag
        J[:, 4, 3] = 1.0
        J[:, 5, 2], J[:, 5, 5] = 1.0, -1.0
        return J

    def positions(self, th2: np.ndarray, newton_iterations: int = 60) -> tuple[np.ndarray, np.ndarray]:
        """``q`` = [theta3 .. theta8] (6, n) by Newton-Raphson on eq. (18), NaN where it does not assemble.

        Started from seed 003's fixed-point iteration on each loop, loosely converged; all
        samples at once on stacked 6x6 matrices.  Also returns ``assembled`` (n,).
        """
        s1, s2 = self.branches
        ground = self.a * cis(np.asarray(self.theta1)) + 0 * th2
        t6 = th2 - self.alpha_
        t7, t8 = fixed_point_loop(self.f * cis(t6), ground, self.g, self.h, s1, tol=1e-4)
        t5 = t8 - self.beta
        t3, t4 = fixed_point_loop(self.b * cis(th2), ground + self.e * cis(t5), self.c, self.d, s2, tol=1e-4)
        q = np.array([t3, t4, t5, t6, t7, t8])
        assembled = np.all(np.isfinite(q), axis=0)
        q = np.where(assembled, q, 0.0)
        for _ in range(newton_iterations):  # J dq = -Phi, all samples at once
            phi = self.residual(th2, q)
            J = self.jacobian(q)
            stuck = ~assembled | ~(np.abs(np.linalg.det(J)) > 1e-300)  # exactly singular: no step
            J[stuck] = np.eye(6)
            dq = np.linalg.solve(J, -phi.T[..., None])[..., 0].T
            dq[:, stuck] = 0.0
            q = q + dq
            if np.max(np.abs(dq), initial=0.0) < 1e-15:
                break
        return np.where(assembled, q, np.nan), assembled

    def rates(
        self, th2: np.ndarray, w2: np.ndarray, al2: np.ndarray, q: np.ndarray, assembled: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``dq/dt`` (corrected eq. 19), ``d2q/dt2`` (corrected eq. 20), both (6, n), and the condition (n,).

        One matrix ``J`` for both; the identity where the sample is singular or does not assemble.
        """
        n = th2.size
        t3, t4, t5, t6, t7, t8 = q
        J = self.jacobian(np.where(assembled, q, 0.0))
        cond = np.minimum(np.abs(np.sin(t3 - t4)), np.abs(np.sin(t7 - t8)))
        good = assembled & (cond >= SINGULAR_TOL)
        J[~good] = np.eye(6)
        e2 = cis(th2)
        rhs_v = np.zeros((n, 6))
        dphi_dt2 = 1j * self.b * e2  # the input's column, moved to the right-hand side
        rhs_v[:, 0], rhs_v[:, 2], rhs_v[:, 4] = -dphi_dt2.real * w2, -dphi_dt2.imag * w2, w2
        qd = np.linalg.solve(J, rhs_v[..., None])[..., 0].T
        d3, d4, d5, d6, d7, d8 = qd
        # second derivative of loop k: sum s L (i th'' - th'^2) e^{i th} = 0
        cent1 = self.b * w2**2 * e2 + self.c * d3**2 * cis(t3) - self.d * d4**2 * cis(t4) - self.e * d5**2 * cis(t5)
        cent2 = self.f * d6**2 * cis(t6) + self.g * d7**2 * cis(t7) - self.h * d8**2 * cis(t8)
        r1 = cent1 - 1j * self.b * al2 * e2
        rhs_a = np.zeros((n, 6))
        rhs_a[:, 0], rhs_a[:, 1], rhs_a[:, 2], rhs_a[:, 3], rhs_a[:, 4] = r1.real, cent2.real, r1.imag, cent2.imag, al2
        qdd = np.linalg.solve(J, rhs_a[..., None])[..., 0].T
        return qd, qdd, cond

    def solve(
        self,
        theta2: np.ndarray,
        omega2: np.ndarray | float = 0.0,
        alpha2: np.ndarray | float = 0.0,
        newton_iterations: int = 60,
    ) -> LoopSolution:
        """Positions (Newton-Raphson) and rates (the 6x6 linear systems) at input angles ``theta2``."""
        th2 = np.asarray(theta2, float).ravel()
        w2 = np.broadcast_to(np.asarray(omega2, float), th2.shape)
        al2 = np.broadcast_to(np.asarray(alpha2, float), th2.shape)
        q, assembled = self.positions(th2, newton_iterations)
        qd, qdd, cond = self.rates(th2, w2, al2, q, assembled)
        # angles, speeds and accelerations of input, c, g, output, d (links named as in `names`)
        inp, l3, l4, out, l6 = self.names[7:]
        zero = np.zeros(th2.size)
        theta = {inp: th2, l3: q[0], l4: q[4], out: q[2], l6: q[1]}
        omega = {inp: w2 + zero, l3: qd[0], l4: qd[4], out: qd[2], l6: qd[1]}
        alpha = {inp: al2 + zero, l3: qdd[0], l4: qdd[4], out: qdd[2], l6: qdd[1]}
        arms = {inp: self.b, l3: self.c, out: self.e, l4: self.g}
        z, v, a = self._joints(q[3], qd[3], qdd[3], theta, omega, alpha, arms)
        oa, ob, jq, js = self.names[:4]
        bases = {inp: oa, l3: jq, l4: js, out: ob, l6: self.names[5]}
        _carry_points(self.points, bases, z[oa], theta, omega, alpha, z, v, a)
        return _finish(theta, omega, alpha, z, v, a, assembled, cond)

    def _joints(
        self,
        t6: np.ndarray,
        d6: np.ndarray,
        dd6: np.ndarray,
        theta: dict[str, np.ndarray],
        omega: dict[str, np.ndarray],
        alpha: dict[str, np.ndarray],
        arms: dict[str, float],
    ) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray], dict[str, np.ndarray]]:
        """Joint positions, velocities and accelerations from the link angles, arm by arm (seed 003's eq. 15, 24).

        ``t6``, ``d6``, ``dd6``: the input link's second arm ``f`` (to ``S``); ``arms``: the
        lengths of the arms from each link's base (input ``b``, c, output ``e``, g).
        """
        oa, ob, jq, js, jw, jy, jx, inp, l3, l4, out, _l6 = self.names
        zero = np.zeros(t6.size)
        org = self.origin + zero
        ground = self.a * cis(np.asarray(self.theta1)) + zero

        def arm(length: float, th: np.ndarray, w: np.ndarray, al: np.ndarray) -> tuple[np.ndarray, ...]:
            r = length * cis(th)
            return r, 1j * w * r, (1j * al - w * w) * r

        zq, vq, aq = arm(arms[inp], theta[inp], omega[inp], alpha[inp])
        zs, vs, as_ = arm(self.f, t6, d6, dd6)
        zy, vy, ay = arm(arms[out], theta[out], omega[out], alpha[out])
        zg, vg, ag = arm(arms[l4], theta[l4], omega[l4], alpha[l4])
        zc, vc, ac = arm(arms[l3], theta[l3], omega[l3], alpha[l3])
        z = {oa: org, ob: org + ground, jq: org + zq, js: org + zs, jw: org + zs + zg, jy: org + ground + zy}
        z[jx] = org + zq + zc
        v = {oa: zero + 0j, ob: zero + 0j, jq: vq, js: vs, jw: vs + vg, jy: vy, jx: vq + vc}
        a = {oa: zero + 0j, ob: zero + 0j, jq: aq, js: as_, jw: as_ + ag, jy: ay, jx: aq + ac}
        return z, v, a


# --------------------------------------------------------------------------- from a mechanism file
def _side(k1: complex, k2: complex, j: complex) -> float:
    return 1.0 if cross(np.asarray(k2 - k1), np.asarray(j - k1)) >= 0 else -1.0


def _unsupported(why: str) -> MethodNotApplicableError:
    """The refusal, its reason first (a long name first used up the message's length before the reason)."""
    return MethodNotApplicableError(
        f"{why}: the vector-loop method handles only four-bars and Stephenson six-bars "
        "(a ternary input link and a ternary output link pivoted on the ground)"
    )


@dataclass(frozen=True)
class _Topology:
    """What both layouts read off a mechanism with one crank driver: links, hinges, the two ground pivots.

    ``hinges[link]`` are the link's joints shared with another link; ``oa`` is the crank's
    pivot, ``ob`` the other ground pivot; ``theta_in`` the crank's input direction in its shape.
    """

    mech: Mechanism
    links: dict[str, Link]
    hinges: dict[str, list[str]]
    crank: Link
    oa: str
    ob: str
    theta_in: float

    def other_link(self, joint: str, not_this: str) -> str:
        """The link at a two-link ``joint`` other than ``not_this``."""
        return next(k for k in self.mech.links_of(joint) if k != not_this)

    def points(self, refs: dict[str, tuple[str, str]], loop: tuple[str, ...]) -> tuple[tuple[str, str, complex], ...]:
        """The joints off the loop: ``(joint, link, Z1 e^{i beta})`` from the link's base ``refs[link][0]``.

        ``beta`` is measured from the line base -> ``refs[link][1]``; ground points are offsets from ``oa``.
        """
        sg = self.links["ground"].shape
        out = []
        for ln, (base, ref) in refs.items():
            s = self.links[ln].shape
            for j in self.links[ln].joints:
                if j in loop:
                    continue
                if ln == "ground":
                    out.append((j, ln, complex(sg[j] - sg[self.oa])))
                else:
                    out.append((j, ln, complex((s[j] - s[base]) / (s[ref] - s[base]) * abs(s[ref] - s[base]))))
        return tuple(out)


def _topology(mech: Mechanism) -> _Topology:
    """Check the common conditions (one crank on a ground pivot, two ground pivots, two links per joint)."""
    drive = mech.drivers[0].type if len(mech.drivers) == 1 else None
    if mech.sliders or not isinstance(drive, CrankType):
        raise _unsupported("it has sliders or not exactly one crank driver")
    links = {ln.name: ln for ln in mech.links}
    hinges = {ln.name: [j for j in ln.joints if len(mech.links_of(j)) >= 2] for ln in mech.links}
    if any(len(mech.links_of(j)) > 2 for j in mech.joint_names):
        raise _unsupported("a joint joins three or more links")
    crank = links[mech.drivers[0].link]
    oa, toward = drive.pivot, drive.toward
    if oa not in links["ground"].joints:
        raise _unsupported("the driver's pivot is not on the ground")
    others = [j for j in hinges["ground"] if j != oa]
    if len(others) != 1:
        raise _unsupported("the ground must have exactly two pivots")
    theta_in = float(np.angle(crank.shape[toward] - crank.shape[oa]))
    return _Topology(mech, links, hinges, crank, oa, others[0], theta_in)


def _four_bar(t: _Topology) -> tuple[FourBar, float]:
    """Seed 003's four-bar: the loop crank, coupler, rocker from the driver's pivot."""
    crank, oa, ob, pose, sg = t.crank, t.oa, t.ob, t.mech.joints, t.links["ground"].shape
    ja = next(j for j in t.hinges[crank.name] if j != oa)
    coupler = t.other_link(ja, crank.name)
    jb = next(j for j in t.hinges[coupler] if j != ja)
    rocker = t.other_link(jb, coupler)
    if ob not in t.links[rocker].joints:
        raise _unsupported("its four links do not form one loop")
    refs = {"ground": (oa, ob), crank.name: (oa, ja), coupler: (ja, jb), rocker: (ob, jb)}
    fb = FourBar(
        complex(sg[ob] - sg[oa]),
        crank.length(oa, ja),
        t.links[coupler].length(ja, jb),
        t.links[rocker].length(ob, jb),
        _side(pose[ja], pose[ob], pose[jb]),
        complex(sg[oa]),
        t.points(refs, (oa, ob, ja, jb)),
        (oa, ob, ja, jb, crank.name, coupler, rocker),
    )
    return fb, float(np.angle(crank.shape[ja] - crank.shape[oa]) - t.theta_in)


def _stephenson(t: _Topology) -> tuple[Stephenson, float]:
    """Seed 001's Stephenson six-bar: input and output ternaries on the ground, one binary and one dyad between."""
    crank, oa, ob, links = t.crank, t.oa, t.ob, t.links
    rocker = t.other_link(ob, "ground")
    if len(t.hinges[rocker]) != 3:
        raise _unsupported("the link pivoted at the second ground pivot is not ternary")
    c_free = [j for j in t.hinges[crank.name] if j != oa]
    r_free = [j for j in t.hinges[rocker] if j != ob]
    links_of = t.mech.links_of
    direct = [(s, w) for s in c_free for w in r_free if set(links_of(s)) & set(links_of(w)) - {crank.name, rocker}]
    if len(direct) != 1:
        raise _unsupported("no single binary link joins the input and output links")
    js, jw = direct[0]
    jq = next(j for j in c_free if j != js)
    jy = next(j for j in r_free if j != jw)
    glink, clink, dlink = t.other_link(js, crank.name), t.other_link(jq, crank.name), t.other_link(jy, rocker)
    jx = next((j for j in t.hinges[clink] if j != jq), None)
    if jx is None or jx not in links[dlink].joints:
        raise _unsupported("the remaining two links do not form a dyad")
    sc, sr, sg, pose = crank.shape, links[rocker].shape, links["ground"].shape, t.mech.joints
    gvec = complex(sg[ob] - sg[oa])
    refs = {"ground": (oa, ob), crank.name: (oa, jq), clink: (jq, jx), glink: (js, jw), rocker: (ob, jy)}
    refs[dlink] = (jy, jx)
    st = Stephenson(
        a=abs(gvec),
        theta1=float(np.angle(gvec)),
        b=crank.length(oa, jq),
        c=links[clink].length(jq, jx),
        d=links[dlink].length(jy, jx),
        e=links[rocker].length(ob, jy),
        f=crank.length(oa, js),
        g=links[glink].length(js, jw),
        h=links[rocker].length(ob, jw),
        alpha_=float(np.angle((sc[jq] - sc[oa]) / (sc[js] - sc[oa]))),
        beta=float(np.angle((sr[jw] - sr[ob]) / (sr[jy] - sr[ob]))),
        branches=(_side(pose[js], pose[ob], pose[jw]), _side(pose[jq], pose[jy], pose[jx])),
        origin=complex(sg[oa]),
        points=t.points(refs, (oa, ob, jq, js, jw, jy, jx)),
        names=(oa, ob, jq, js, jw, jy, jx, crank.name, clink, glink, rocker, dlink),
    )
    return st, float(np.angle(sc[jq] - sc[oa]) - t.theta_in)


def from_mechanism(mech: Mechanism) -> tuple[FourBar | Stephenson, float]:
    """The vector-loop model of a mechanism, and the offset from its driver input to ``theta2`` (rad).

    Lengths and angles come from the links' shapes; the branches from the reference pose.
    Joints that are not loop joints (coupler points) are carried as ``Z1 e^{i beta}`` from
    their link's base joint, as seed 003 does for ``P``.
    """
    t = _topology(mech)
    if len(mech.links) == 4 and all(len(h) == 2 for h in t.hinges.values()):
        return _four_bar(t)
    if len(mech.links) == 6 and len(t.hinges[t.crank.name]) == 3:
        return _stephenson(t)
    raise _unsupported(f"{len(mech.links)} links, the input link with {len(t.hinges[t.crank.name])} joints")
