"""Forward dynamics: Lagrange's equations in the driver coordinates, integrated in time.

Every point and link velocity is linear in the driver speeds ``w = q'`` (SI: rad/s, or m/s
for a slider or cylinder): ``v_P = J_P(q) w``, ``omega_b = j_b(q) w``.  The rates solver
gives the velocity coefficients (unit input speeds) and, with zero input accelerations, the
velocity-product terms ``a0_P = J_P' w``.  Lagrange's equations are then (derivation in
``docs/method.md``, "Forward dynamics")::

    M(q) q'' + h(q, w) = Q(q, w) + tau(w)
    M = sum_b m_b J_Gb^T J_Gb + I_b j_b^T j_b          h = sum_b m_b J_Gb^T a0_Gb + I_b j_b^T alpha0_b
    Q = gravity + loads + springs (virtual power) - dampers

For one driver (:class:`Reduced`) ``h = 1/2 M'(q) w^2``; ``M``, ``M'``, the position-dependent
force ``Q_s(q)`` and the damping coefficient ``C(q)`` are tabulated once on a fine grid with
their exact derivatives (from the acceleration coefficients), so cubic Hermite interpolation
is ``O(h^4)`` and the right-hand side costs microseconds.  Several drivers evaluate ``M``,
``h`` and ``Q`` directly at every step.  :func:`simulate` integrates with SciPy's DOP853
(:data:`RTOL`, :data:`ATOL`) and analyses the motion at the requested times in one vectorised
call (so every catalogue column comes with it).  Where the table's ``M`` vanishes (the crank
and coupler massless, the output at a limit position: :func:`inertia_zeros`) one driver's
motion is integrated in the time ``s``, ``dt = sqrt(M) ds``, regular there.

Examples
--------
>>> import numpy as np, linkagekit as lk
>>> mech = lk.load("examples/slider_crank.yaml")
>>> red = reduced(mech)
>>> red.period == 2 * np.pi, bool(red.mass(red.q0) > 0)
(True, True)
>>> res = simulate(mech, np.linspace(0.0, 0.05, 6), torque=2.0)
>>> res.time.tolist()
[0.0, 0.01, 0.02, 0.03, 0.04, 0.05]
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from functools import partial
from typing import Any

import numpy as np

from .api import analyze, prepare
from .branch import along_sweep
from .checks import beyond_a_turn, input_range
from .errors import InputError, shorten
from .forces import Kinematics, point_motion
from .model import CylinderType, Driver, Mechanism, SliderType
from .params import Params
from .positions import solve
from .rates import link_motion, solve_rates
from .result import Result, frozen
from .threads import one_blas_thread_with_scipy
from .units import UnitKind

#: relative and absolute tolerances of the integration (SI state: rad or m, rad/s or m/s)
RTOL = 1e-12
ATOL = 1e-12
#: grid points of the one-driver table (over a turn, or over the assembly range)
POINTS = 16384
#: the periodic table starts this share of a grid step before the pose's input (the golden ratio's part: a grid
#: point never lands exactly on a change point at a rational fraction of a turn from the pose)
SHIFT = (math.sqrt(5.0) - 1.0) / 2.0
#: grid steps (of :data:`POINTS` a turn) around a change point where the table is bridged by a fit (:func:`_bridge`)
BRIDGE = 200
#: the degree of that fit
DEGREE = 11
#: the table's cubic Hermite interpolant must meet the model at every cell's middle to this (relative)
TABLE_TOL = 1e-8
#: the reduced inertia ``M`` vanishes where its interpolant falls below this share of its median over the table (nothing
#: with inertia moves there: a rocker at its limit position, the crank and coupler massless)
NO_INERTIA = 1e-9
#: several drivers: the motion stops where the steps' smallest dimensionless determinant falls below this
STOP_CONDITION = 1e-3
#: the most output times one simulation gives
MAX_TIMES = 1_000_000
#: the most integration steps of a one-driver simulation (about 10 a turn: a motion of 20 000 turns, some
#: seconds of work); a faster or longer motion is refused with a line instead of running for hours
MAX_STEPS = 200_000
#: right-hand-side evaluations of one DOP853 step
_EVALS_PER_STEP = 12

__all__ = ["ATOL", "NO_INERTIA", "POINTS", "RTOL", "Reduced", "TorqueLaw", "inertia_zeros", "reduced", "simulate"]

ArrayLike = Any


# ---------------------------------------------------------------------- torque laws
@dataclass(frozen=True)
class TorqueLaw:
    """A driver's torque (force) law, SI: ``T0`` constant, or the linear motor curve ``T0 (1 - w / W0)``."""

    T0: float = 0.0
    W0: float | None = None

    def __call__(self, w: ArrayLike) -> Any:
        if self.W0 is None:
            return self.T0 + 0.0 * np.asarray(w)
        return self.T0 * (1.0 - np.asarray(w) / self.W0)


# ---------------------------------------------------------------------- the model's parts
@dataclass(frozen=True)
class _Model:
    """What the coefficients read, once per mechanism: solver numbers, scales and the force elements (SI)."""

    mech: Mechanism
    params: Params
    scale: np.ndarray  # (n_d,) SI per solver unit of each driver (1 for an angle, m per length unit)
    bodies: tuple[tuple[str, float, float, complex | None], ...]  # link, mass, inertia (+ flywheels), cg ratio
    loads: tuple[tuple[str, complex, float, complex | None], ...]  # link, force, torque, point ratio
    springs: tuple[tuple[int, int, float, float], ...]  # joint a, joint b, stiffness, free length (m)
    dampers: tuple[tuple[int, int, float], ...]  # joint a, joint b, damping


def _model(mech: Mechanism, flywheel: float = 0.0) -> _Model:
    """The mechanism's dynamic parts in SI, ``flywheel`` (kg*m^2) added to the first driver's link."""
    params = prepare(mech)
    si = mech.length_to_si
    extra: dict[str, float] = {}  # the file's flywheels are in params.bodies' inertia already
    if flywheel:
        extra[mech.drivers[0].link] = float(flywheel)
    bodies = [
        (b.link, float(b.mass[0, 0]), float(b.inertia[0, 0]) + extra.pop(b.link, 0.0), _one(b.cg))
        for b in params.bodies
    ]
    loads = tuple((ld.link, complex(ld.force[0, 0]), float(ld.torque[0, 0]), _one(ld.at)) for ld in params.loads)
    idx = {j: i for i, j in enumerate(mech.joint_names)}
    springs = tuple(
        (idx[s.between[0]], idx[s.between[1]], float(s.stiffness), float(s.free_length) * si) for s in mech.springs
    )
    dampers = tuple((idx[d.between[0]], idx[d.between[1]], float(d.damping)) for d in mech.dampers)
    scale = np.array([d.type.rate_to_si(si) for d in mech.drivers])
    return _Model(mech, params, scale, tuple(bodies), loads, springs, dampers)


def _one(a: np.ndarray | None) -> complex | None:
    return None if a is None else complex(a[0, 0])


@dataclass(frozen=True)
class _Motion:
    """Positions (m), velocities and velocity-product accelerations of what the forces act on, per sample (n,)."""

    good: np.ndarray
    z: np.ndarray  # joints (n_joints, n), m
    v: np.ndarray
    a: np.ndarray
    gz: list[tuple[np.ndarray, np.ndarray, np.ndarray]]  # per body: z_G, v_G, a_G (m)
    lz: list[tuple[np.ndarray, np.ndarray, np.ndarray]]  # per load: its point's z, v, a (m)
    body_w: list[tuple[np.ndarray, np.ndarray]]  # per body: omega, alpha
    load_w: list[tuple[np.ndarray, np.ndarray]]  # per load: omega, alpha
    cond: np.ndarray  # the smallest dimensionless determinant of the steps (1: well conditioned, 0: singular)


def _motion(md: _Model, q: np.ndarray, signs: np.ndarray, w: np.ndarray) -> _Motion:
    """The motion at solver inputs ``q`` (n_d, n) with signs (n_signs, n), SI speeds ``w`` (n_d, n), no acceleration."""
    mech, params = md.mech, md.params
    pos = solve(params, q[:, None, :], signs[:, None, :])
    speed = (w / md.scale[:, None])[:, None, :]  # solver units per second
    rt = solve_rates(params, pos, speed, np.zeros_like(speed))
    lm = link_motion(params, pos, rt, mech.links)
    n = q.shape[1]
    motion = {k: tuple(np.broadcast_to(x, (1, n))[0] for x in m) for k, m in lm.items()}
    good = pos.assembled[0] & ~rt.singular[0]
    km = Kinematics(pos.z[:, 0], rt.v[:, 0], rt.a[:, 0], motion, good, np.zeros((0, n)), (), ())
    si = mech.length_to_si

    def at(link: str, local: complex | None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        if local is None:
            i = mech.joint_names.index(mech.link(link).joints[0])
            return km.z[i] * si, km.v[i] * si, km.a[i] * si
        zz, vv, aa = point_motion(mech, link, np.asarray(local), km)
        return zz * si, vv * si, aa * si

    gz = [at(b[0], b[3]) for b in md.bodies]
    lz = [at(ld[0], ld[3]) for ld in md.loads]
    body_w = [(motion[b[0]][1], motion[b[0]][2]) for b in md.bodies]
    load_w = [(motion[ld[0]][1], motion[ld[0]][2]) for ld in md.loads]
    cond = np.min(np.abs(rt.condition[:, 0]), axis=0, initial=1.0)
    return _Motion(good, km.z * si, km.v * si, km.a * si, gz, lz, body_w, load_w, cond)


def _stretch(m: _Motion, a: int, b: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A force element's length ``L`` (m), its rate ``L'`` and the velocity-product part of ``L''`` (per sample)."""
    d, dv, da = m.z[b] - m.z[a], m.v[b] - m.v[a], m.a[b] - m.a[a]
    L = np.abs(d)
    u = d / L
    Lv = np.real(np.conj(u) * dv)
    La = np.real(np.conj(u) * da) + (np.abs(dv) ** 2 - Lv**2) / L
    return L, Lv, La


# ---------------------------------------------------------------------- one driver: the table
def _table_rows(md: _Model, m: _Motion) -> tuple[np.ndarray, np.ndarray]:
    """``[M, Q_s, C]`` and their derivatives along q at unit speed (velocities J, accelerations J'), each (3, n)."""
    g = md.mech.gravity if md.mech.gravity is not None else 0j
    n = m.good.shape[0]
    M, dM, Qs, dQs, C, dC = (np.zeros(n) for _ in range(6))
    for (_, mass, inertia, _), (_zg, J, dJ), (jw, djw) in zip(md.bodies, m.gz, m.body_w, strict=True):
        M += mass * np.abs(J) ** 2 + inertia * jw**2
        dM += 2.0 * (mass * np.real(np.conj(J) * dJ) + inertia * jw * djw)
        Qs += mass * np.real(np.conj(g) * J)
        dQs += mass * np.real(np.conj(g) * dJ)
    for (_, force, torque, _), (_zp, J, dJ), (jw, djw) in zip(md.loads, m.lz, m.load_w, strict=True):
        Qs += np.real(np.conj(force) * J) + torque * jw
        dQs += np.real(np.conj(force) * dJ) + torque * djw
    for a, b, k, free in md.springs:
        L, Lv, La = _stretch(m, a, b)
        Qs -= k * (L - free) * Lv
        dQs -= k * (Lv**2 + (L - free) * La)
    for a, b, c in md.dampers:
        _, Lv, La = _stretch(m, a, b)
        C += c * Lv**2
        dC += 2.0 * c * Lv * La
    return np.array([M, Qs, C]), np.array([dM, dQs, dC])


def _hermite(x0: float, h: float, Y: np.ndarray, dY: np.ndarray, x: Any) -> np.ndarray:
    """Cubic Hermite interpolation on the uniform grid ``x0 + k h`` of values ``Y`` and slopes ``dY`` (n, k)."""
    s = (np.asarray(x, float) - x0) / h
    i = np.clip(np.floor(s).astype(int), 0, len(Y) - 2)
    t = (s - i)[..., None]
    t1 = 1.0 - t
    return (  # type: ignore[no-any-return]
        (1.0 + 2.0 * t) * t1 * t1 * Y[i]
        + t * t1 * t1 * h * dY[i]
        + t * t * (3.0 - 2.0 * t) * Y[i + 1]
        - t * t * t1 * h * dY[i + 1]
    )


@dataclass(frozen=True)
class Reduced:
    """One driver's reduced model, SI: ``M(q) q'' + 1/2 M'(q) w^2 = force(q, w) + torque(w)``.

    ``q`` in rad (m for a slider or cylinder driver), ``w = dq/dt``; ``mass`` in kg*m^2 (kg),
    forces in N*m (N).  Build it with :func:`reduced`.

    Attributes
    ----------
    driver : str
        The driver's name.
    q0 : float
        The pose's input, where a simulation starts.
    q_range : (float, float)
        Where the table holds (periodic: ``(q0, q0 + period)``; otherwise the assembly range
        around the pose, just inside its ends).
    period : float or None
        ``2 pi`` when the mechanism comes back to itself after a turn of the driver, else None.
    points : ndarray
        The change points of the branch inside the table (where a sign flips), SI.
    steps : ndarray of int
        The sign step (index in ``plan.sign_joints``) that flips at each of ``points``.
    """

    driver: str
    q0: float
    q_range: tuple[float, float]
    period: float | None
    points: np.ndarray
    steps: np.ndarray
    _Y: np.ndarray
    _dY: np.ndarray

    @property
    def _h(self) -> float:
        return (self.q_range[1] - self.q_range[0]) / (len(self._Y) - 1)

    def _wrap(self, q: ArrayLike) -> Any:
        q = np.asarray(q, float)
        if self.period is None:
            return q
        return self.q_range[0] + np.mod(q - self.q_range[0], self.period)

    def _outside(self, q: Any) -> Any:
        """Where ``q`` (wrapped) lies outside a table that does not cover a turn: there is no model there."""
        lo, hi = self.q_range
        tol = 1e-12 * (hi - lo)
        return (np.asarray(q) < lo - tol) | (np.asarray(q) > hi + tol) if self.period is None else False

    def _rows(self, q: ArrayLike) -> np.ndarray:
        """M, Q_s and C at ``q`` (..., 3): NaN outside the table (its end cells' cubics went on: review 19d)."""
        q = self._wrap(q)
        rows = _hermite(self.q_range[0], self._h, self._Y, self._dY, q)
        return np.where(np.asarray(self._outside(q))[..., None], np.nan, rows)

    def mass(self, q: ArrayLike) -> np.ndarray:
        """``M(q)``, never negative (a sum of squares: the interpolant's rounding next to a zero of ``M`` is cut)."""
        return np.maximum(self._rows(q)[..., 0], 0.0)  # type: ignore[no-any-return]

    def dmass(self, q: ArrayLike) -> np.ndarray:
        """``dM/dq`` (the interpolant's slope; the table holds it exactly at the grid points; NaN outside it)."""
        q = self._wrap(q)
        s = (np.asarray(q) - self.q_range[0]) / self._h
        i = np.clip(np.floor(s).astype(int), 0, len(self._Y) - 2)
        t = s - i
        Y, dY, h = self._Y[:, 0], self._dY[:, 0], self._h
        slope = (
            (6 * t * t - 6 * t) / h * Y[i]
            + (3 * t * t - 4 * t + 1) * dY[i]
            + (6 * t - 6 * t * t) / h * Y[i + 1]
            + (3 * t * t - 2 * t) * dY[i + 1]
        )
        return np.where(self._outside(q), np.nan, slope)

    def force(self, q: ArrayLike, w: ArrayLike) -> np.ndarray:
        """The generalised force of gravity, loads, springs and dampers ``Q_s(q) - C(q) w`` (not the torque law)."""
        r = self._rows(q)
        return r[..., 1] - r[..., 2] * np.asarray(w)  # type: ignore[no-any-return]

    def accel(self, q: ArrayLike, w: ArrayLike, torque: ArrayLike = 0.0) -> np.ndarray:
        """``q''`` for speed ``w`` under the driver torque ``torque``."""
        w = np.asarray(w, float)
        r = self._rows(q)
        return (r[..., 1] - r[..., 2] * w + torque - 0.5 * self.dmass(q) * w * w) / r[..., 0]  # type: ignore[no-any-return]

    def signs(self, params: Params, q: ArrayLike) -> np.ndarray:
        """The branch's signs (n_signs, n) at inputs ``q`` (SI): the pose's, flipped at every change point passed."""
        qq = np.atleast_1d(self._wrap(q))
        lo, hi = np.minimum(qq, self.q0), np.maximum(qq, self.q0)
        out = np.repeat(params.signs[:, :1], len(qq), axis=1)
        for step, p in zip(self.steps, self.points, strict=True):
            out[step] *= np.where((p > lo) & (p <= hi), -1.0, 1.0)
        return out


def _grid(md: _Model, points: int, turns: int = 1) -> tuple[np.ndarray, float | None]:
    """The table's grid (SI) over ``turns`` turns (periodic), or inside the assembly interval that holds the pose."""
    mech, d = md.mech, md.mech.drivers[0]
    x0 = float(md.params.pose_inputs[0, 0]) * md.scale[0]
    to_si = d.input_scale(mech) * md.scale[0]  # SI per file unit
    ranges = input_range(mech, 0)
    _one_configuration_a_direction(mech, ranges)
    full = d.type.cyclic and any(hi - lo >= 2 * math.pi / to_si * (1 - 1e-12) for lo, hi in ranges)
    if full:
        n = turns * points
        h = 2 * math.pi * turns / n  # shifted by an irrational part of a step: no grid point on a change point
        return x0 - SHIFT * h + h * np.arange(n + 1), 2 * math.pi * turns
    for lo, hi in ranges:
        span = (hi - lo) * to_si
        shift = 0.0
        if d.type.cyclic:  # the pose's angle, within a turn of the interval
            shift = 2 * math.pi * math.floor((x0 - lo * to_si) / (2 * math.pi))
        a, b = lo * to_si + shift, hi * to_si + shift
        if a <= x0 <= b:  # just inside a toggle (singular there), on a stroke's end, never leaving the pose out
            margin = span * 1e-4
            low, high = (_stroke_end(d, v, hi - lo) for v in (lo, hi))  # a stroke's end bounds no angle: no shift
            a = a + margin if low is None else low * to_si
            b = b - margin if high is None else high * to_si
            return np.linspace(min(a, x0), max(b, x0), points + 1), None
    raise InputError(f"{mech.source}: the mechanism does not assemble at its pose's input")


def _one_configuration_a_direction(mech: Mechanism, ranges: list[list[float]]) -> None:
    """Refuses, in one line, a crank whose mode runs longer than a turn and does not close (a numerical group's: it
    ends at a fold each way, reaching some directions twice in two configurations). The table is solved at
    directions, so it would jump between the two (``check`` says where), and a motion through the jump would be
    no motion at all."""
    d = mech.drivers[0]
    turn = 2 * math.pi / d.input_scale(mech)
    for lo, hi in ranges:
        if d.type.cyclic and beyond_a_turn([lo, hi], turn):
            raise InputError(
                f"{mech.source}: the pose's mode of {d.name} runs {hi - lo:.6g} {d.input_unit(mech)} from fold to "
                "fold, longer than a turn, and does not come back to itself: simulate does not follow such a mode "
                "(check tells which directions it reaches twice)"
            )


def _stroke_end(d: Driver, value: float, span: float) -> float | None:
    """The end of driver ``d``'s stroke that an end of its range ``value`` is (file units, to 1e-9 of the range's
    ``span``: the range's ends are found by bisection), or None: a toggle, where the model is singular."""
    for end in d.stroke or ():
        if abs(value - end) <= 1e-9 * span:
            return float(end)
    return None


def _rows_at(md: _Model, x: np.ndarray, signs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The table's rows at grid inputs ``x`` (SI); a sample on a singular position is the mean of its two sides."""
    q = (x / md.scale[0])[None]
    Y, dY = _table_rows(md, _motion(md, q, signs, np.ones_like(q)))  # unit SI speed: J and J' = dJ/dq
    bad = ~np.all(np.isfinite(Y) & np.isfinite(dY), axis=0)
    if bad.any():
        delta = 0.25 * (x[1] - x[0])  # well off the singular position (the rates solver is NaN within 1e-6 of it)
        one = np.ones((1, int(bad.sum())))
        sides = [_table_rows(md, _motion(md, q[:, bad] + s * delta / md.scale[0], signs[:, bad], one)) for s in (-1, 1)]
        Y[:, bad] = 0.5 * (sides[0][0] + sides[1][0])
        dY[:, bad] = 0.5 * (sides[0][1] + sides[1][1])
    return Y.T, dY.T


def _bridge(x: np.ndarray, Y: np.ndarray, dY: np.ndarray, points: np.ndarray, period: float | None) -> np.ndarray:
    """Rows within :data:`BRIDGE` steps of a change point replaced by a polynomial fit from both sides, in place.

    Near a change point the closed-form solver loses digits (two circles nearly touch: position
    errors of about ``eps / theta``, the velocity and acceleration coefficients worse), while
    ``M``, ``Q`` and ``C`` go on smoothly along the branch; a least-squares polynomial of degree
    :data:`DEGREE` over the samples from ``BRIDGE`` to ``4 BRIDGE`` steps away on both sides
    bridges them (the interpolant's slope divides value errors by the step: they must be tiny).
    A full-turn table (``period``) starts at the pose, so a change point near its start has one
    side at the table's other end: the samples are taken from the table repeated a turn either
    way (a pose 2 deg from a parallelogram's flat position fitted from one side only: ``M`` off
    by 7e-4).
    """
    h = x[1] - x[0]
    if len(points) == 0:
        return np.zeros(len(x), bool)
    unique = np.unique(np.round(points / h, 3)) * h  # two sign steps may meet at one change point
    images = (0.0,) if period is None else (-period, 0.0, period)
    xs, Ys = _repeated(x, Y, period)
    near_any, free = np.zeros(len(x), bool), np.ones(len(xs), bool)
    for c in unique:
        for k in images:
            near_any |= np.abs(x - (c + k)) < BRIDGE * h
            free &= np.abs(xs - (c + k)) >= BRIDGE * h
    scale = 4 * BRIDGE * h
    for c in unique:
        ring = (np.abs(xs - c) <= scale) & free
        if ring.sum() < 4 * DEGREE:
            continue
        V = np.polynomial.chebyshev.chebvander((xs[ring] - c) / scale, DEGREE)  # well conditioned on [-1, 1]
        coef = np.linalg.solve(V.T @ V, V.T @ Ys[ring])  # least squares by the (small, tame) normal equations
        for k in images:
            near = np.abs(x - (c + k)) < BRIDGE * h
            u = (x[near] - (c + k)) / scale
            Y[near] = np.polynomial.chebyshev.chebvander(u, DEGREE) @ coef
            dY[near] = np.polynomial.chebyshev.chebvander(u, DEGREE - 1) @ np.polynomial.chebyshev.chebder(coef) / scale
    return near_any


def _repeated(x: np.ndarray, Y: np.ndarray, period: float | None) -> tuple[np.ndarray, np.ndarray]:
    """The table's grid and rows, repeated a turn before and after it when periodic (its last row is its first)."""
    if period is None:
        return x, Y
    return np.concatenate([x[:-1] - period, x[:-1], x + period]), np.concatenate([Y[:-1], Y[:-1], Y])


#: the most grid intervals a reduced model's table takes (each a row of every joint's rates: memory grows with it),
#: and the fewest (a coarser table misses its tolerance, and the pose was said to be next to a toggle: the
#: slider-crank's table failed with 256)
MIN_TABLE_POINTS, MAX_TABLE_POINTS = 1024, 100_000


@one_blas_thread_with_scipy
def reduced(mech: Mechanism, *, flywheel: float = 0.0, points: int = POINTS) -> Reduced:
    """The reduced one-coordinate model of a one-driver mechanism, tabulated along its branch from the pose.

    Parameters
    ----------
    mech : Mechanism
        With exactly one driver.
    flywheel : float
        Extra inertia (kg*m^2) on the driver's link.
    points : int
        Grid intervals of the table.

    Returns
    -------
    Reduced
    """
    if not isinstance(mech, Mechanism):
        raise InputError(f"expected a linkagekit Mechanism (lk.load(...)), got {type(mech).__name__}")
    if len(mech.drivers) != 1:
        raise InputError(
            f"{mech.source}: the reduced model needs exactly one driver, this mechanism has {len(mech.drivers)}"
        )
    if not (isinstance(flywheel, int | float) and math.isfinite(flywheel) and flywheel >= 0):
        raise InputError(f"flywheel: expected a finite inertia >= 0 (kg*m^2), got {shorten(repr(flywheel))}")
    whole = isinstance(points, int | np.integer) and not isinstance(points, bool)
    if not (whole and MIN_TABLE_POINTS <= points <= MAX_TABLE_POINTS):
        raise InputError(
            f"points: expected a whole number of grid intervals, {MIN_TABLE_POINTS} to {MAX_TABLE_POINTS}, "
            f"got {shorten(repr(points))}"
        )
    md = _model(mech, float(flywheel))
    for turns in (1, 2):  # a branch whose signs come back after two turns only (an odd number of flips in one)
        x, period = _grid(md, int(points), turns)
        br = along_sweep(md.params, (x / md.scale[0])[None, None, :], (mech.drivers[0].type.cyclic,))
        steps, _, where = br.points
        if period is None or np.all(np.bincount(steps, minlength=md.params.plan.n_signs) % 2 == 0):
            break
    signs = br.signs[:, 0]
    Y, dY = _rows_at(md, x, signs)
    q0 = float(md.params.pose_inputs[0, 0] * md.scale[0])
    change = np.asarray(where) * md.scale[0]
    bridged = _bridge(x, Y, dY, change, period)
    good = _verified(md, x, Y, dY, signs, bridged)
    turn = period
    x, Y, dY, period = _reachable(mech, q0, x, Y, dY, good, period)
    steps = np.asarray(steps)
    if turn is not None and period is None:  # a turn's table cut: its change points a turn either way too
        change, steps = np.concatenate([change - turn, change, change + turn]), np.tile(steps, 3)
        keep = (change >= x[0]) & (change <= x[-1])
        change, steps = change[keep], steps[keep]
    rng = (float(x[0]), float(x[-1]))
    return Reduced(mech.drivers[0].name, q0, rng, period, change, steps, Y, dY)


def _verified(
    md: _Model, x: np.ndarray, Y: np.ndarray, dY: np.ndarray, signs: np.ndarray, bridged: np.ndarray
) -> np.ndarray:
    """Which cells the interpolant holds to :data:`TABLE_TOL`: checked against the model at every cell's middle.

    ``M`` relative to the larger of itself and its median over the table (its typical size),
    ``Q_s`` and ``C`` relative to their largest magnitude over the table. A cell fails near a
    toggle (``M`` grows without bound) or where the model is not smooth; a bridged cell (near
    a change point, where the direct values are the inaccurate ones) and a middle on a singular
    position (no direct value) pass. Where ``M`` falls to zero (nothing with inertia moves: a
    rocker at its limit position, the crank and coupler massless) the cells hold to the median:
    relative to ``M`` itself no interpolant would, and the motion passes there
    (:func:`_integrate_reduced`).
    """
    mid = 0.5 * (x[:-1] + x[1:])
    q = (mid / md.scale[0])[None]
    direct = _table_rows(md, _motion(md, q, signs[:, :-1], np.ones_like(q)))[0].T
    h = x[1] - x[0]
    interp = 0.5 * (Y[:-1] + Y[1:]) + h * (dY[:-1] - dY[1:]) / 8.0  # the cubic Hermite at t = 1/2
    with np.errstate(invalid="ignore"):
        typical = np.nanmedian(np.abs(Y[:, 0])) if np.isfinite(Y[:, 0]).any() else 0.0
        floor = np.nanmax(np.abs(Y), axis=0, initial=0.0) * [0.0, 1.0, 1.0] + [typical, 0.0, 0.0]
        err = np.abs(interp - direct) <= TABLE_TOL * np.maximum(np.abs(direct), floor) + 1e-300
    rows = np.all(np.isfinite(Y) & np.isfinite(dY), axis=1) & (Y[:, 0] > 0)
    ok: np.ndarray = (np.all(err | ~np.isfinite(direct), axis=1) | bridged[:-1] | bridged[1:]) & rows[:-1] & rows[1:]
    return ok


def _singular_pose(mech: Mechanism) -> InputError:
    """The refusal of a pose the motion cannot leave along its branch (the table's, and the model's own)."""
    return InputError(f"{mech.source}: the mechanism cannot move from its pose along its branch (a singular pose)")


class _OffTable(InputError):
    """The pose lies in a cell the table does not hold to its tolerance, though the model is finite there: next to
    a toggle, where ``M`` grows without bound (:func:`_integrate_reduced` then integrates the model itself)."""


def _reachable(
    mech: Mechanism,
    q0: float,
    x: np.ndarray,
    Y: np.ndarray,
    dY: np.ndarray,
    good: np.ndarray,
    period: float | None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float | None]:
    """The table cut to the run of good cells around the pose (then not periodic): its ends stop a motion."""
    if good.all():
        return x, Y, dY, period
    c0 = int(np.clip(np.searchsorted(x, q0) - 1, 0, len(good) - 1))  # the pose's cell
    if not good[c0]:
        if np.all(np.nan_to_num(Y[:, 0]) <= 0):
            raise InputError(f"{mech.source}: no inertia along the driver's motion: give the links masses or inertias")
        if np.all(np.isfinite(Y[c0 : c0 + 2]) & np.isfinite(dY[c0 : c0 + 2])) and np.all(Y[c0 : c0 + 2, 0] > 0):
            raise _OffTable(f"{mech.source}: the pose is where no table holds (next to a toggle)")
        raise _singular_pose(mech)
    bad = np.flatnonzero(~good)
    n = len(good)
    if period is None:
        lo = int(bad[bad < c0].max(initial=-1)) + 1
        hi = int(bad[bad > c0].min(initial=n))
        return x[lo : hi + 1], Y[lo : hi + 1], dY[lo : hi + 1], None
    # a turn's table is a circle of cells: the run around the pose may go on past either end of it (the grid
    # starts just below the pose, and a run cut at the first cell stopped every motion that first went down)
    lo = int(bad[bad < c0].max(initial=int(bad.max()) - n)) + 1
    hi = int(bad[bad > c0].min(initial=int(bad.min()) + n))
    k = np.arange(lo, hi + 1)  # the run's nodes, numbered along the circle
    return x[k % n] + period * (k // n), Y[k % n], dY[k % n], None


def _cells(red: Reduced) -> list[float]:
    """Per grid cell, the cubic coefficients in ``t`` in [0, 1] of ``M``, ``Q_s``, ``C`` (plain floats: a fast RHS)."""
    h, Y, dY = red._h, red._Y, red._dY
    y0, y1, d0, d1 = Y[:-1], Y[1:], dY[:-1] * h, dY[1:] * h
    c2 = 3 * (y1 - y0) - 2 * d0 - d1
    c3 = 2 * (y0 - y1) + d0 + d1
    out: list[float] = np.stack([y0, d0, c2, c3], axis=1).ravel().tolist()  # 12 per cell: M, Q_s, C by power
    return out


# ---------------------------------------------------------------------- integration
@dataclass(frozen=True)
class _Run:
    """A motion at the output times (SI): ``q``, ``w``, ``qdd`` (n_d, n); ``stopped``: why it ended early."""

    t: np.ndarray
    q: np.ndarray
    w: np.ndarray
    qdd: np.ndarray
    signs: np.ndarray | None
    stopped: str | None


def _cell_at(
    cells: list[float], q: float, x0: float, h: float, n: int, period: float | None
) -> tuple[float, list[float]]:
    """The table's cell at input ``q`` (reduced to the period from ``x0``): where in it (0..1), and its 12 cubic
    coefficients of ``M``, ``Q_s``, ``C`` by power (:func:`_cells`)."""
    if not math.isfinite(q):  # a trial step of a torque law far beyond the machine's scale
        raise InputError("simulate: the integration failed: the motion's state is no longer a finite number")
    if period is not None:
        q = x0 + (q - x0) % period
    s = (q - x0) / h
    i = min(max(int(s), 0), n)
    return s - i, cells[12 * i : 12 * i + 12]


def _rhs_reduced(red: Reduced, law: TorqueLaw) -> Callable[[float, Any], list[float]]:
    """The state derivative ``(w, q'')`` of the tabulated model, in plain floats (microseconds a call)."""
    cells, x0, h, n = _cells(red), red.q_range[0], red._h, len(red._Y) - 2
    period = red.period
    T0, W0 = law.T0, law.W0

    def rhs(_t: float, y: Any) -> list[float]:
        q, w = float(y[0]), float(y[1])
        t, (m0, q0, c0, m1, q1, c1, m2, q2, c2, m3, q3, c3) = _cell_at(cells, q, x0, h, n, period)
        M = ((m3 * t + m2) * t + m1) * t + m0
        dM = ((3 * m3 * t + 2 * m2) * t + m1) / h
        Qs = ((q3 * t + q2) * t + q1) * t + q0
        C = ((c3 * t + c2) * t + c1) * t + c0
        tau = T0 if W0 is None else T0 * (1.0 - w / W0)
        return [w, (Qs - C * w + tau - 0.5 * dM * w * w) / M]

    return rhs


def _integrate_reduced(md: _Model, times: np.ndarray, law: TorqueLaw, w0: float) -> _Run:
    """One driver: the tabulated model integrated by DOP853; a motion that leaves the table's range stops (a toggle).

    A pose next to a toggle, where no table holds (:class:`_OffTable`), is integrated on the model itself, as several
    drivers are (:func:`_integrate_direct`: slower, and it stops where the conditioning falls below
    :data:`STOP_CONDITION`); it stopped at once, or was refused as "a singular pose" 0.3 deg from the toggle.
    """
    try:
        red = reduced(md.mech)
    except _OffTable as off:
        q0 = md.params.pose_inputs[:, :1] * md.scale[:, None]
        if not _direct_accel(md, q0, np.array([[w0]]), np.array([[law(w0)]]))[1][0] >= STOP_CONDITION:
            # already past the stop: the singular event can never fall through zero (pushed in, it ran on for ever)
            raise _singular_pose(md.mech) from off
        return _integrate_direct(md, times, (law,), np.array([w0], float))
    zeros = inertia_zeros(red)
    if len(zeros):
        return _integrate_passing(md, red, times, law, w0, zeros)
    rhs = _rhs_reduced(red, law)
    y0 = [red.q0, w0]
    if red.period is None:
        t, y, stop = _with_events_stiff_too(red, rhs, times, y0, partial(_speed_text, md))
    else:
        t, y, stop = times, _dop853(rhs, times, y0, partial(_speed_text, md)), None
    stopped = None if stop is None else _toggle_message(md, 0, *stop)
    q, w = y
    qdd = red.accel(q, w, law(w))
    signs = red.signs(md.params, q) if md.params.plan.n_signs else None
    return _Run(t, q[None], w[None], np.atleast_1d(qdd)[None], signs, stopped)


def inertia_zeros(red: Reduced) -> np.ndarray:
    """Where the table's ``M`` vanishes (SI inputs): below :data:`NO_INERTIA` of its median, by the interpolant.

    ``M`` is a sum of squares of velocity coefficients, so a zero is a double one (every moving
    mass stops there); the grid points miss it by up to a step, so each cell next to a small local
    minimum of the grid's values is searched on 64 points of its cubic.

    Parameters
    ----------
    red : Reduced
        A one-driver table (:func:`reduced`).

    Returns
    -------
    ndarray
        The inputs (SI) of the zeros, at the vertex of the parabola through the samples around each.

    Examples
    --------
    >>> import linkagekit as lk
    >>> inertia_zeros(reduced(lk.load("examples/slider_crank.yaml"))).size  # crank and rod have mass: M > 0
    0
    """
    M = red._Y[:, 0]
    typical = float(np.median(M))
    k = np.flatnonzero((M[1:-1] <= M[:-2]) & (M[1:-1] <= M[2:]) & (M[1:-1] < 1e-4 * typical)) + 1
    if not len(k):
        return np.zeros(0)
    u = np.linspace(-1.0, 1.0, 129)
    q = red.q_range[0] + (k[:, None] + u[None, :]) * red._h
    m = red._rows(q)[..., 0]
    rows = np.arange(len(k))
    i = np.clip(np.argmin(m, axis=1), 1, len(u) - 2)
    a, b, c = m[rows, i - 1], m[rows, i], m[rows, i + 1]
    curv = a - 2 * b + c
    with np.errstate(divide="ignore", invalid="ignore"):  # M is a parabola next to its zero: its vertex
        shift = np.where(curv > 0, 0.5 * (a - c) / curv, 0.0)
    where = q[rows, i] + shift * (q[rows, 1] - q[rows, 0])
    low = np.min(m, axis=1) < NO_INERTIA * typical
    return np.asarray(where[low], float)


def _integrate_passing(
    md: _Model, red: Reduced, times: np.ndarray, law: TorqueLaw, w0: float, zeros: np.ndarray
) -> _Run:
    """One driver whose ``M`` vanishes at ``zeros``: the motion in the time ``s``, ``dt = sqrt(M) ds`` (method.md).

    With ``u = sqrt(M) w`` (``u^2 / 2`` the kinetic energy) the reduced equation is
    ``dq/ds = u``, ``du/ds = Q_s + T0 - (C + T0 / W0) w``, ``dt/ds = sqrt(M)``: regular where ``M`` is
    0 if no force there acts on the speed (the crank passes in no time, the energy carrying
    through). A motor curve or a damper acting there is refused in one line: the crank's speed
    spikes as it passes, and what the speed-dependent force takes of the energy there depends on
    the crank's own inertia (a crank of 1e-8 and one of 1e-10 kg*m^2 on the review's rocker-only
    crank-rocker under a motor curve were 1.6 deg apart after 2 s, converging as its 0.4th power).
    """
    _refuse_speed_forces(md, red, law, zeros)
    if red.period is None and not red.q_range[0] <= red.q0 <= red.q_range[1]:
        raise _singular_pose(md.mech)
    r0 = math.sqrt(max(float(red.mass(red.q0)), 0.0))
    sol, stop = _passing_solution(md, red, law, [red.q0, r0 * w0, float(times[0])], float(times[-1]))
    t = times[times <= (stop[0] if stop else times[-1])]
    q, u = _passing_states(red, sol, t)
    r = np.sqrt(red.mass(q))
    with np.errstate(divide="ignore", invalid="ignore"):
        w = np.where(r > 0, u / r, np.copysign(np.inf, u))
    w[0] = w0
    stopped = None if stop is None else _toggle_message(md, 0, *stop)
    qdd = red.accel(q, w, law(w))
    signs = red.signs(md.params, q) if md.params.plan.n_signs else None
    return _Run(t, q[None], w[None], np.atleast_1d(qdd)[None], signs, stopped)


def _refuse_speed_forces(md: _Model, red: Reduced, law: TorqueLaw, zeros: np.ndarray) -> None:
    """The line that refuses a motor curve or a damper acting on the speed where ``M`` vanishes (at ``zeros``)."""
    c = red._rows(zeros)[..., 2]
    c_max = float(np.max(np.abs(red._Y[:, 2]), initial=0.0))
    motor = law.W0 is not None and law.T0 != 0.0
    damped = c > 1e-6 * c_max
    if not motor and not damped.any():
        return
    d = md.mech.drivers[0]
    where = float((zeros[damped] if damped.any() and not motor else zeros)[0])
    at = f"{where / (md.scale[0] * d.input_scale(md.mech)):.6g} {d.input_unit(md.mech)}"
    what = "the motor curve acts" if motor else "a damper acts"
    raise InputError(
        f"simulate: {md.mech.source}: at {d.name} = {at} nothing with inertia moves with {d.name} and {what} on its"
        f" speed: the motion there depends on the inertia left out; give {d.link} or the coupler an inertia, or"
        " apply a constant torque"
    )


def _passing_solution(
    md: _Model, red: Reduced, law: TorqueLaw, y0: list[float], t_end: float
) -> tuple[Any, tuple[float, float] | None]:
    """``(q, u, t)`` over ``s`` by DOP853 (dense), until ``t_end``: the solution, and (time, q) of a stop at the table's
    end (a toggle: a table that is not periodic), or None."""
    from scipy.integrate import solve_ivp

    lo, hi = red.q_range
    rhs = _rhs_passing(red, law, partial(_speed_text, md))

    def done(_s: float, y: Any) -> float:
        return t_end - float(y[2])

    def below(_s: float, y: Any) -> float:
        return float(y[0]) - lo

    def above(_s: float, y: Any) -> float:
        return hi - float(y[0])

    events: list[Any] = [done] if red.period is not None else [done, below, above]
    for e in events:
        e.terminal, e.direction = True, -1.0
    floor = math.sqrt(NO_INERTIA * float(np.median(red._Y[:, 0])))
    span = (0.0, (t_end - y0[2]) / floor)  # dt/ds = sqrt(M) is below that floor only next to a zero, passed at once
    sol = solve_ivp(rhs, span, y0, method="DOP853", rtol=RTOL, atol=ATOL, events=events, dense_output=True)
    if sol.status < 0:
        raise InputError(f"simulate: the integration failed: {sol.message}")
    if sol.status == 0 or len(sol.t_events[0]):
        if sol.status == 0:  # s ran out with t short of the end: stuck where dt/ds = sqrt(M) is 0 (at rest there)
            at = _inputs_text(md, sol.y[:1, -1])
            raise InputError(
                f"simulate: by t = {sol.y[2, -1]:.6g} s the motion has come to rest where nothing with inertia moves"
                f" ({at}): the model does not say how it goes on"
            )
        return sol, None
    k = 1 if len(sol.t_events[1]) else 2
    return sol, (float(sol.y_events[k][0][2]), float(sol.y_events[k][0][0]))


def _rhs_passing(red: Reduced, law: TorqueLaw, speed: Callable[[float], str]) -> Callable[[float, Any], list[float]]:
    """``d(q, u, t)/ds`` of :func:`_integrate_passing` on the table, in plain floats (at most :data:`MAX_STEPS`)."""
    cells, x0, h, n = _cells(red), red.q_range[0], red._h, len(red._Y) - 2
    period, T0 = red.period, law.T0
    calls = [0]

    def rhs(_s: float, y: Any) -> list[float]:
        calls[0] += 1
        q, u = float(y[0]), float(y[1])
        if calls[0] > _EVALS_PER_STEP * MAX_STEPS:
            raise InputError(_too_many_steps(float(y[2]), speed(u / math.sqrt(max(float(red.mass(q)), 1e-300))), 1.0))
        t, (m0, q0, c0, m1, q1, c1, m2, q2, c2, m3, q3, c3) = _cell_at(cells, q, x0, h, n, period)
        r = math.sqrt(max(((m3 * t + m2) * t + m1) * t + m0, 0.0))
        Qs = ((q3 * t + q2) * t + q1) * t + q0
        C = ((c3 * t + c2) * t + c1) * t + c0
        return [u, Qs + T0 - (C * u / r if C else 0.0), r]

    return rhs


def _passing_states(red: Reduced, sol: Any, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``q`` and ``u`` at the output ``times``: ``t(s)`` inverted on the dense solution, by Newton's steps
    (``dt/ds = sqrt(M)``) kept inside each time's integration step, bisection where one would leave it."""
    ts, ss = sol.y[2], sol.t
    j = np.clip(np.searchsorted(ts, times, side="right") - 1, 0, len(ss) - 2)
    a, b = ss[j], ss[j + 1]
    gap = ts[j + 1] - ts[j]
    s = a + (b - a) * np.clip((times - ts[j]) / np.where(gap > 0, gap, 1.0), 0.0, 1.0)
    for _ in range(100):
        y = sol.sol(s)
        f = y[2] - times
        if np.all(np.abs(f) <= 4 * np.finfo(float).eps * np.maximum(np.abs(times), 1.0)):
            break
        a, b = np.where(f < 0, s, a), np.where(f < 0, b, s)
        slope = np.sqrt(red.mass(y[0]))
        with np.errstate(divide="ignore", invalid="ignore"):
            newton = s - f / slope
        s = np.where((newton > a) & (newton < b), newton, 0.5 * (a + b))
    y = sol.sol(s)
    return y[0], y[1]


def _speed_text(md: _Model, w_si: float) -> str:
    """A one-driver state's speed (rad/s or m/s) as ``--speed`` takes it: rad/s, or the file's length unit a second."""
    d = md.mech.drivers[0]
    unit = "rad/s" if d.type.input_kind is UnitKind.ANGLE else f"{md.mech.length_unit}/s"
    return f"{w_si / md.scale[0]:.3g} {unit}"


def _dop853(
    rhs: Callable[[float, Any], list[float]], times: np.ndarray, y0: list[float], speed: Callable[[float], str]
) -> np.ndarray:
    """The state at every output time by the compiled DOP853 (SciPy's ``ode``): microseconds a step.

    At most :data:`MAX_STEPS` steps (counted by the right-hand side's evaluations). A motion whose steps
    each moved the driver less than :data:`SLOW_STEP` spent them on DOP853's stability (a stiff spring,
    nearly at rest): it goes on from the last output time reached with LSODA, which turns to a stiff
    method (BDF) and takes long steps there, under the same budget; ``speed`` formats the state's speed
    for the line that refuses more.
    """
    y = np.empty((2, len(times)))
    y[:, 0] = y0
    short = _ode(rhs, "dop853", times, y)
    if short is None:
        return y
    i, t, state = short
    travel = float(np.sum(np.abs(np.diff(y[0, :i]))) + abs(state[0] - y[0, i - 1]))
    if travel / MAX_STEPS >= SLOW_STEP or _ode(rhs, "lsoda", times[i - 1 :], y[:, i - 1 :]) is not None:
        raise InputError(_too_many_steps(t, speed(state[1]), travel / MAX_STEPS))
    return y


def _ode(
    rhs: Callable[[float, Any], list[float]], method: str, times: np.ndarray, y: np.ndarray
) -> tuple[int, float, np.ndarray] | None:
    """``y[:, 1:]`` (2, n) filled by SciPy's ``ode`` ``method`` from ``y[:, 0]`` at ``times[0]``, in place: None, or
    past the budget of :data:`MAX_STEPS` steps the first output index not reached, the time and state reached. By
    DOP853, a motion whose last :data:`STIFF_PROBE` of the budget (looked at after each such share) moved the driver
    less than :data:`SLOW_STEP` a step along its path stops there too, at the last output time reached (a stiff spring
    or damper at rest: the pendulum of the tests took the whole budget, 16 s, before LSODA took over)."""
    import warnings

    from scipy.integrate import ode

    # read once, as the budget; at least PROBE_STEPS (a motion from rest takes small steps at first)
    every = _EVALS_PER_STEP * max(int(STIFF_PROBE * MAX_STEPS), PROBE_STEPS) if method == "dop853" else 0
    counted = _Counted(rhs, float(y[0, 0]), every)
    accepted = [0]

    def step_taken(_t: float, _y: Any) -> int:  # DOP853's accepted steps (and its start): the integrator's own
        accepted[0] += 1
        return 0

    solver = ode(counted)

    def start(first_step: float = 0.0) -> None:  # 0: the integrator's own guess
        solver.set_integrator(method, rtol=RTOL, atol=ATOL, nsteps=MAX_STEPS, first_step=first_step)
        if method == "dop853":
            solver.set_solout(step_taken)

    start()
    solver.set_initial_value(y[:, 0], times[0])
    for i in range(1, len(times)):
        if i > 1 and method == "dop853":  # each call starts afresh: from the last interval's mean step, not a guess
            start(abs(times[i - 1] - times[i - 2]) / max(accepted[0] - 1, 1))
        accepted[0] = 0
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # scipy's "larger nsteps is needed": said by the caller
            y[:, i] = solver.integrate(times[i])
        if counted.refused:
            raise counted.refused[0]
        if counted.stiff:
            return i, float(times[i - 1]), y[:, i - 1].copy()
        if counted.calls > _EVALS_PER_STEP * MAX_STEPS or solver.get_return_code() in _EXCESS_WORK[method]:
            return i, float(solver.t), np.array(solver.y, float)
        if not solver.successful():
            raise InputError(f"simulate: the integration failed at t = {solver.t:.6g} s")
    return None


class _Counted:
    """:func:`_ode`'s right-hand side: its evaluations counted; an :class:`InputError` it raises kept in ``refused``
    (raised through the compiled integrator it would come back as another error); after every ``every`` evaluations
    (0: never) ``stiff`` when the driver's path along the states evaluated since the last look was under
    :data:`SLOW_STEP` a step (a pendulum that swings back moves; one at rest not). Once stiff, or refused, it gives
    the integrator NaN: it gives up on this output time, and the caller goes on from the last one."""

    def __init__(self, rhs: Callable[[float, Any], list[float]], q0: float, every: int) -> None:
        self.rhs, self.every = rhs, every
        self.calls, self.stiff = 0, False
        self.refused: list[InputError] = []
        self.length, self.at, self.looked = 0.0, q0, 0.0

    def __call__(self, t: float, state: Any) -> list[float]:
        self.calls += 1
        self.length += abs(float(state[0]) - self.at)
        self.at = float(state[0])
        if self.every and self.calls % self.every == 0:
            self.stiff = (self.length - self.looked) / (self.every / _EVALS_PER_STEP) < SLOW_STEP
            self.looked = self.length
        if self.stiff:
            return [math.nan] * len(state)
        try:
            return self.rhs(t, state)
        except InputError as exc:
            self.refused.append(exc)
            return [math.nan] * len(state)


#: SciPy ``ode``'s return codes for "more steps are needed" (DOP853's -2; LSODA's -1, excess work)
_EXCESS_WORK = {"dop853": (-2,), "lsoda": (-1,)}


#: a one-driver motion whose steps each moved the driver less than this (rad, as far as the output times show) spent
#: them on the explicit integrator's stability, not on the motion: a fast vibration (a stiff spring on a light link)
#: bounds DOP853's step even at rest
SLOW_STEP = 1e-3


def _too_many_steps(t: float, speed: str, travel_per_step: float, steps: int = 0) -> str:
    """The line that refuses a motion past ``steps`` (default :data:`MAX_STEPS`) steps at time ``t`` (s): too fast
    for its time span, or (its steps moving the driver less than :data:`SLOW_STEP` each) too long for the
    integrator's stable step."""
    head = f"simulate: more than {steps or MAX_STEPS} integration steps by t = {t:.6g} s"
    if travel_per_step >= SLOW_STEP:
        return f"{head} (the driver moves at {speed}): shorten the time span or lower the speed"
    return (
        f"{head} with the driver hardly moving (now {speed}): the explicit integrator keeps its step"
        f" ({t / (steps or MAX_STEPS):.2g} s) under the period of the fastest vibration (a stiff spring, damper or"
        " motor curve), even at rest: shorten the time span"
    )


def _budgeted(
    rhs: Callable[[float, Any], list[float]], speed: Callable[[float], str], probe: bool = True
) -> Callable[[float, Any], list[float]]:
    """``rhs`` that refuses, in one line, a motion past :data:`MAX_STEPS` steps (counted by its evaluations, as
    :func:`_ode` counts them): ``solve_ivp`` has no budget of its own, and a stiff damper ran for ever. After
    :data:`STIFF_PROBE` of the budget, a motion whose steps moved the driver less than :data:`SLOW_STEP` each is
    refused at once (for a stiff method to take over: the damper's 16 s of DOP853 came down to 2 s), unless not
    ``probe`` (the stiff method's own run)."""
    calls, first = [0], [math.nan]
    budget, at = MAX_STEPS, int(STIFF_PROBE * MAX_STEPS) if probe else 0  # read once: a test lowers MAX_STEPS

    def counted(t: float, y: Any) -> list[float]:
        calls[0] += 1
        if calls[0] == 1:
            first[0] = float(y[0])
        steps = calls[0] / _EVALS_PER_STEP
        if steps > budget or steps == at:  # the net travel: a stiff step's trial states jump back and forth
            per_step = abs(float(y[0]) - first[0]) / steps
            if steps > budget or per_step < SLOW_STEP:
                raise _OverBudget(_too_many_steps(t, speed(float(y[1])), per_step, int(steps)), per_step)
        return rhs(t, y)

    return counted


#: the share of :data:`MAX_STEPS` after which a motion of ``solve_ivp`` is judged stiff or not (:func:`_budgeted`),
#: and after each of which one of SciPy's DOP853 is (:func:`_ode`, over at least PROBE_STEPS steps)
STIFF_PROBE = 0.05
PROBE_STEPS = 1000


class _OverBudget(InputError):
    """A motion past :data:`MAX_STEPS` steps (its message the line that refuses it), ``travel_per_step`` of the
    driver each."""

    def __init__(self, message: str, travel_per_step: float) -> None:
        super().__init__(message)
        self.travel_per_step = travel_per_step


def _with_events_stiff_too(
    red: Reduced,
    rhs: Callable[[float, Any], list[float]],
    times: np.ndarray,
    y0: list[float],
    speed: Callable[[float], str],
) -> tuple[np.ndarray, np.ndarray, tuple[float, float] | None]:
    """:func:`_with_events` by DOP853 under the step budget; a motion that spent it with the driver hardly moving
    (steps under :data:`SLOW_STEP`: a stiff damper, spring or motor curve) again by LSODA, which turns to a stiff
    method, under the same budget (as :func:`_dop853` does for a crank that turns fully)."""
    try:
        return _with_events(red, _budgeted(rhs, speed), times, y0)
    except _OverBudget as over:
        if over.travel_per_step >= SLOW_STEP:
            raise
    return _with_events(red, _budgeted(rhs, speed, probe=False), times, y0, method="LSODA")


def _with_events(
    red: Reduced, rhs: Callable[[float, Any], list[float]], times: np.ndarray, y0: list[float], method: str = "DOP853"
) -> tuple[np.ndarray, np.ndarray, tuple[float, float] | None]:
    """``solve_ivp``'s ``method`` with the table's ends as terminal events: (times, states, (time, q) of a stop)."""
    from scipy.integrate import solve_ivp

    lo, hi = red.q_range
    pushed = _pushed_out(rhs, times[0], y0, lo, hi)
    if pushed is not None:  # on an end and driven out of the table: stopped at the start (the event found t ~ 1e-9)
        return times[:1], np.array([[y0[0]], [y0[1]]], float), (float(times[0]), pushed)

    def below(_t: float, y: Any) -> float:
        return float(y[0]) - lo

    def above(_t: float, y: Any) -> float:
        return hi - float(y[0])

    # only a motion leaving the table stops: a pose on its end moving inwards crosses the event's zero the other way
    below.terminal = above.terminal = True  # type: ignore[attr-defined]
    below.direction = above.direction = -1.0  # type: ignore[attr-defined]
    span = (times[0], times[-1])
    sol = solve_ivp(rhs, span, y0, method=method, t_eval=times, rtol=RTOL, atol=ATOL, events=[below, above])
    if sol.status < 0:
        raise InputError(f"simulate: the integration failed: {sol.message}")
    if sol.status == 1:
        k = 0 if len(sol.t_events[0]) else 1
        return sol.t, sol.y, (float(sol.t_events[k][0]), float(sol.y_events[k][0][0]))
    return sol.t, sol.y, None


def _pushed_out(
    rhs: Callable[[float, Any], list[float]], t0: float, y0: list[float], lo: float, hi: float
) -> float | None:
    """The end of the table ``[lo, hi]`` a start ``y0 = (q, w)`` lies on (to rounding) while its speed, or at rest its
    acceleration, drives it out; else None."""
    q, w = float(y0[0]), float(y0[1])
    tol = 1e-12 * max(hi - lo, abs(lo), abs(hi))
    out = w if w != 0 else rhs(t0, [q, w])[1]
    if abs(q - lo) <= tol and out < 0:
        return lo
    if abs(q - hi) <= tol and out > 0:
        return hi
    return None


def _toggle_message(md: _Model, k: int, t: float, q_si: float) -> str:
    """The one line that says where the motion stopped: time and the driver's input (file units)."""
    d = md.mech.drivers[k]
    value = q_si / (md.scale[k] * d.input_scale(md.mech))
    unit = d.input_unit(md.mech)
    head = f"simulate: stopped at t = {t:.6g} s, {d.name} = {value:.6g} {unit}: "
    end = None if d.stroke is None else _stroke_end(d, value, d.stroke[1] - d.stroke[0])
    if d.stroke is not None and end is not None:  # the table reaches the stroke's end itself: the event stops there
        return head + _stroke_end_text(md.mech, k, int(end == d.stroke[1]))
    if _turns_fully(md.mech, k):  # a range's 0 and 360 deg are no ends: never a toggle where `check` finds none
        return head + f"the model does not hold to its tolerance there, though {d.name} turns fully (no toggle)"
    return head + f"the end of its range{_range_end(md.mech, k, value)} (a toggle) that the motion cannot pass"


def _turns_fully(mech: Mechanism, k: int) -> bool:
    """Whether driver ``k`` (a crank) assembles over a whole turn (``check``: no dead point, no range's end)."""
    d = mech.drivers[k]
    turn = 2 * math.pi / d.input_scale(mech)
    return d.type.cyclic and any(hi - lo >= turn * (1 - 1e-12) for lo, hi in input_range(mech, k))


def _range_end(mech: Mechanism, k: int, value: float) -> str:
    """Where ``check`` puts the range's end nearest ``value`` (file units), as words; "" when there is none.

    The motion stops where its table stops holding to its tolerance, a little before the end
    itself (the inertia the driver sees grows without bound there), so the line says both.
    """
    d = mech.drivers[k]
    ends = np.array([e for iv in input_range(mech, k) for e in iv], float)
    if not len(ends):
        return ""
    gap = ends - value
    if d.type.cyclic:
        turn = 2 * math.pi / d.input_scale(mech)
        gap = (gap + turn / 2) % turn - turn / 2
    i = int(np.argmin(np.abs(gap)))
    if abs(gap[i]) <= 1e-9 * (np.ptp(ends) or 1.0):  # the end itself, to the rounding of the range's ends
        return f", at {value + gap[i]:.6g} {d.input_unit(mech)},"
    return f" is {abs(gap[i]):.3g} {d.input_unit(mech)} on, at {value + gap[i]:.6g} {d.input_unit(mech)}"


def _inputs_text(md: _Model, q_si: np.ndarray) -> str:
    """Every driver's input at SI inputs ``q_si`` (n_d,), in file units: ``"a = 1.2 m, b = 30 deg"``."""
    mech = md.mech
    return ", ".join(
        f"{d.name} = {q_si[k] / (md.scale[k] * d.input_scale(mech)):.6g} {d.input_unit(mech)}"
        for k, d in enumerate(mech.drivers)
    )


def _singular_message(md: _Model, t: float, q_si: np.ndarray) -> str:
    """Several drivers: the one line that says where the motion stopped, time and every driver's input (file units)."""
    return (
        f"simulate: stopped at t = {t:.6g} s ({_inputs_text(md, q_si)}): the mechanism reached a singular position"
        " it cannot pass"
    )


def _stroke_message(md: _Model, k: int, side: int, t: float, q_si: np.ndarray) -> str:
    """Several drivers: the line of a motion stopped by driver ``k`` at its stroke's lower (0) or upper (1) end."""
    return f"simulate: stopped at t = {t:.6g} s ({_inputs_text(md, q_si)}): {_stroke_end_text(md.mech, k, side)}"


def _stroke_end_text(mech: Mechanism, k: int, side: int) -> str:
    """Driver ``k`` at its stroke's lower (0) or upper (1) end, as the stop line says it."""
    d = mech.drivers[k]
    stroke = d.stroke
    assert stroke is not None  # only a driver with a stroke stops at its end
    return (
        f"{d.name} reached the {('lower', 'upper')[side]} end of its stroke, {stroke[side]:.6g} {d.input_unit(mech)},"
        " that the motion cannot pass"
    )


def _direct_accel(md: _Model, q: np.ndarray, w: np.ndarray, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Several drivers: ``q''`` (n_d, n) from ``M``, ``h``, ``Q`` at states (q, w) (n_d, n), SI, the pose's signs.

    One solve of ``n (n_d + 1)`` samples: each state with the unit speed of each driver (the
    columns of ``J``), then with its own speed and no acceleration (``a0``).  Also returns the
    conditioning of each state (NaN accelerations where it is singular).
    """
    nd, n = q.shape
    qs = np.tile(q / md.scale[:, None], (1, nd + 1))
    unit = np.repeat(np.eye(nd), n, axis=1)
    m = _motion(md, qs, np.repeat(md.params.signs, n * (nd + 1), axis=1), np.concatenate([unit, w], axis=1))

    def split(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(J (n_d, n), the velocity-product part (n,)) of a per-sample array."""
        r = x.reshape(nd + 1, n)
        return r[:nd], r[nd]

    g = md.mech.gravity if md.mech.gravity is not None else 0j
    M, rhs = np.zeros((n, nd, nd)), np.array(tau, float)
    for (_, mass, inertia, _), (_, v, acc), (om, al) in zip(md.bodies, m.gz, m.body_w, strict=True):
        (J, _), (_, a0), (jw, _), (_, al0) = split(v), split(acc), split(om), split(al)
        M += mass * np.einsum("in,jn->nij", np.conj(J), J).real + inertia * np.einsum("in,jn->nij", jw, jw)
        rhs += mass * np.real(np.conj(J) * (g - a0)) - inertia * jw * al0
    for (_, force, torque, _), (_, v, _), (om, _) in zip(md.loads, m.lz, m.load_w, strict=True):
        rhs += np.real(np.conj(force) * split(v)[0]) + torque * split(om)[0]
    for a, b, k, free in md.springs:
        L, Lv, _ = _stretch(m, a, b)
        rhs -= k * (split(L)[1] - free) * split(Lv)[0]
    for a, b, c in md.dampers:
        Lq, Lw = split(_stretch(m, a, b)[1])
        rhs -= c * Lq * Lw
    good = np.all(m.good.reshape(nd + 1, n), axis=0) & np.all(np.isfinite(M), axis=(1, 2))
    _check_inertia(md, M[good])
    M[~good] = np.eye(nd)
    qdd = np.linalg.solve(M, np.nan_to_num(rhs).T[..., None])[..., 0].T
    qdd[:, ~good] = np.nan
    return qdd, np.min(m.cond.reshape(nd + 1, n), axis=0)


def _check_inertia(md: _Model, M: np.ndarray) -> None:
    """Several drivers: each must move something with inertia (``M`` (n, n_d, n_d) at assembled states), else its
    acceleration is undetermined: an error naming those drivers (a massless five-bar raised LinAlgError)."""
    if not len(M):
        return
    none = np.all(np.diagonal(M, axis1=1, axis2=2) <= 0, axis=0)
    if none.any():
        names = ", ".join(repr(d.name) for d, z in zip(md.mech.drivers, none, strict=True) if z)
        they = "it moves" if none.sum() == 1 else "they move"
        raise InputError(f"{md.mech.source}: no inertia along the motion of {names}: give the links {they} masses")


def _unbounded(mech: Mechanism) -> Mechanism:
    """``mech`` with its drivers' strokes lifted: the same dynamics, defined past a stroke's end too."""
    drivers = tuple(
        replace(d, type=replace(d.type, stroke=None)) if isinstance(d.type, SliderType | CylinderType) else d
        for d in mech.drivers
    )
    return replace(mech, drivers=drivers)


def _past_end(k: int, end: float, sign: float, _t: float, y: np.ndarray) -> float:
    """How far input ``k`` (SI) is inside a stroke's end ``end``: ``sign`` 1 at the lower end, -1 at the upper."""
    return sign * (float(y[k]) - end)


def _stroke_events(md: _Model) -> list[tuple[int, int, Callable[[float, np.ndarray], float]]]:
    """Each end of each driver's stroke as ``(driver, 0 lower or 1 upper, a terminal event)``.

    The event falls through zero when the input leaves its stroke there (not when it moves in,
    so a motion that starts at an end and moves away goes on).
    """
    out: list[tuple[int, int, Callable[[float, np.ndarray], float]]] = []
    for k, d in enumerate(md.mech.drivers):
        for side, end in enumerate(d.stroke or ()):
            event = partial(_past_end, k, end * d.input_scale(md.mech) * md.scale[k], (1.0, -1.0)[side])
            event.terminal, event.direction = True, -1.0  # type: ignore[attr-defined]
            out.append((k, side, event))
    return out


def _integrate_direct(md: _Model, times: np.ndarray, laws: tuple[TorqueLaw, ...], w0: np.ndarray) -> _Run:
    """Several drivers: ``M``, ``h``, ``Q`` evaluated at every step (slower).

    The motion stops at a driver's stroke's end or where the conditioning falls below
    :data:`STOP_CONDITION` (a singular position): terminal events the integrator locates, so
    the stop does not depend on the output times.  The right-hand side reads the mechanism
    with its strokes lifted (:func:`_unbounded`): a trial step past a stroke's end is still
    the motion, and the event stops it at the end.
    """
    from scipy.integrate import solve_ivp

    nd = len(laws)
    free = replace(md, params=prepare(_unbounded(md.mech)))

    def tau(w: np.ndarray) -> np.ndarray:
        return np.array([law(x) for law, x in zip(laws, w, strict=True)], float).reshape(w.shape)

    def accel(y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return _direct_accel(free, y[:nd], y[nd:], tau(y[nd:]))

    def rhs(_t: float, y: np.ndarray) -> np.ndarray:
        return np.concatenate([y[nd:], accel(y[:, None])[0][:, 0]])

    def singular(_t: float, y: np.ndarray) -> float:
        return float(accel(y[:, None])[1][0]) - STOP_CONDITION

    singular.terminal = True  # type: ignore[attr-defined]
    ends = _stroke_events(md)
    y0 = np.concatenate([md.params.pose_inputs[:, 0] * md.scale, w0])
    span = (times[0], times[-1])
    events = [singular, *(e for _, _, e in ends)]
    sol = solve_ivp(rhs, span, y0, method="DOP853", t_eval=times, rtol=RTOL, atol=ATOL, events=events)
    ok = np.all(np.isfinite(sol.y), axis=0)
    t, y = sol.t[ok], sol.y[:, ok]
    last = (float(t[-1]), y[:nd, -1]) if len(t) else (float(times[0]), y0[:nd])
    stopped = _direct_stop(md, sol, ends, *last)
    qdd = accel(y)[0] if len(t) else np.zeros((nd, 0))
    return _Run(t, y[:nd], y[nd:], qdd, None, stopped)


def _direct_stop(
    md: _Model, sol: Any, ends: list[tuple[int, int, Any]], t_last: float, q_last: np.ndarray
) -> str | None:
    """Why a several-driver motion ended early (None: it did not): the event that ended it, when and where.

    An integration that failed without an event (the accelerations turned non-finite) is said
    at the last output time it reached, ``t_last`` with the inputs ``q_last`` (SI).
    """
    if sol.status == 0 and np.all(np.isfinite(sol.y)):
        return None
    if sol.status == 1:
        i = next(i for i, te in enumerate(sol.t_events) if len(te))
        te, qe = float(sol.t_events[i][0]), sol.y_events[i][0][: len(md.mech.drivers)]
        return _singular_message(md, te, qe) if i == 0 else _stroke_message(md, *ends[i - 1][:2], te, qe)
    return _singular_message(md, t_last, q_last)


# ---------------------------------------------------------------------- arguments
def _times(times: ArrayLike) -> np.ndarray:
    """The output times: finite, strictly increasing, at least two."""
    try:
        t = np.asarray(times, float)
    except (TypeError, ValueError, OverflowError):
        raise InputError("times: expected an array of numbers (s)") from None
    if t.ndim != 1 or len(t) < 2:
        raise InputError(f"times: expected at least two times (s) in a 1-D array, got shape {t.shape}")
    if len(t) > MAX_TIMES:
        raise InputError(f"times: {len(t)} times, more than linkagekit.dynamics.MAX_TIMES ({MAX_TIMES})")
    if not np.all(np.isfinite(t)):
        raise InputError("times: every time must be a finite number")
    if not np.all(np.diff(t) > 0):
        raise InputError("times: the times must increase strictly")
    return t


def _number(value: Any, what: str) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError, OverflowError):
        raise InputError(f"{what}: expected a number, got {shorten(repr(value))}") from None
    if not math.isfinite(x):
        raise InputError(f"{what}: expected a finite number, got {shorten(repr(value))}")
    return x


def _by_driver(mech: Mechanism, value: Any, what: str) -> dict[str, Any]:
    """A value per driver from one value (one driver) or a mapping by name."""
    names = [d.name for d in mech.drivers]
    if value is None:
        return {}
    if not names:
        raise InputError(f"{what}: {mech.source} has no driver to apply it to")
    if isinstance(value, Mapping):
        for k in value:
            if k not in names:
                raise InputError(f"{what}: no driver named {k!r} (drivers: {', '.join(names)})")
        return dict(value)
    if len(names) != 1:
        raise InputError(f"{what}: this mechanism has drivers {', '.join(names)}: give one value per driver by name")
    return {names[0]: value}


def torque_laws(mech: Mechanism, torque: Any = None, motor: Any = None) -> tuple[TorqueLaw, ...]:
    """Each driver's torque law in SI from ``simulate``'s ``torque``/``motor`` (the checks of :func:`simulate`)."""
    return _laws(_model(mech), torque, motor)


def _laws(md: _Model, torque: Any, motor: Any) -> tuple[TorqueLaw, ...]:
    """Each driver's law in SI (none given: no torque)."""
    mech = md.mech
    tq, mt = _by_driver(mech, torque, "torque"), _by_driver(mech, motor, "motor")
    out = []
    for k, d in enumerate(mech.drivers):
        if d.name in tq and d.name in mt:
            raise InputError(f"driver '{d.name}': give a torque or a motor curve, not both")
        if d.name in mt:
            try:
                t0, w0 = mt[d.name]
            except (TypeError, ValueError):
                raise InputError(f"motor[{d.name}]: expected (T0, W0), got {mt[d.name]!r}") from None
            T0, W0 = _number(t0, f"motor[{d.name}] T0"), _number(w0, f"motor[{d.name}] W0")
            if W0 == 0:
                raise InputError(f"motor[{d.name}]: the no-load speed W0 must not be zero")
            if T0 * W0 < 0:  # T0 (1 - w / W0) would grow with the speed: a motor that feeds itself runs away
                raise InputError(
                    f"motor[{d.name}]: T0 = {T0:g} and W0 = {W0:g} have opposite signs (the torque would grow with "
                    "the speed); a motor turning the other way has both negative"
                )
            out.append(TorqueLaw(T0, W0 * md.scale[k]))
        else:
            out.append(TorqueLaw(_number(tq.get(d.name, 0.0), f"torque[{d.name}]")))
    return tuple(out)


def _start_speeds(md: _Model, speed: Any) -> np.ndarray:
    sp = _by_driver(md.mech, speed, "speed")
    out: np.ndarray = np.array([_number(sp.get(d.name, 0.0), f"speed[{d.name}]") for d in md.mech.drivers]) * md.scale
    return out


# ---------------------------------------------------------------------- simulate
@one_blas_thread_with_scipy
def simulate(
    mech: Mechanism,
    times: ArrayLike,
    *,
    torque: float | Mapping[str, float] | None = None,
    motor: tuple[float, float] | Mapping[str, tuple[float, float]] | None = None,
    speed: float | Mapping[str, float] | None = None,
) -> Result:
    """The motion under a torque law, from the pose at rest (or at ``speed``): docs/commands.md, `simulate`.

    Parameters
    ----------
    mech : Mechanism
        With masses or inertias; gravity, loads, springs, dampers and flywheels as the file gives them.
    times : array_like
        Output times (s), strictly increasing; the motion starts at the first.
    torque : float or mapping of driver name to float, optional
        A constant driver torque (N*m; N for a slider or cylinder driver).
    motor : (T0, W0) or mapping of driver name to (T0, W0), optional
        The linear motor curve ``T0 (1 - w / W0)``, ``W0`` in rad/s (length unit/s for a slider or cylinder).
    speed : float or mapping, optional
        The starting speed (rad/s, or length unit/s); default 0.

    Returns
    -------
    Result
        One sample per output time, ``time`` the times; ``stopped`` a one-line message when
        the motion met a toggle it cannot pass (the rows then end there), else None.
    """
    if not isinstance(mech, Mechanism):
        raise InputError(f"expected a linkagekit Mechanism (lk.load(...)), got {type(mech).__name__}")
    t = _times(times)
    if not mech.drivers:
        raise InputError(f"{mech.source}: the mechanism has no driver: nothing to simulate")
    md = _model(mech)
    laws, w0 = _laws(md, torque, motor), _start_speeds(md, speed)
    if len(mech.drivers) == 1:
        run = _integrate_reduced(md, t, laws[0], float(w0[0]))
    else:
        run = _integrate_direct(md, t, laws, w0)
    return _result(md, run)


def _result(md: _Model, run: _Run) -> Result:
    """The motion analysed at its samples in one call: every catalogue column, with the time axis."""
    mech = md.mech
    if len(run.t) == 0:
        raise InputError(run.stopped or "simulate: no output time reached")
    factor = {d.name: md.scale[k] * d.input_scale(mech) for k, d in enumerate(mech.drivers)}
    inputs = {d.name: run.q[k] / factor[d.name] for k, d in enumerate(mech.drivers)}
    speed = {d.name: run.w[k] / md.scale[k] for k, d in enumerate(mech.drivers)}
    accel = {d.name: run.qdd[k] / md.scale[k] for k, d in enumerate(mech.drivers)}
    res = analyze(mech, inputs, speed=speed, acceleration=accel, signs=run.signs)
    return replace(res, time=frozen(run.t), stopped=run.stopped)
