"""Periodic steady state of a one-driver machine under a torque law, and flywheel sizing.

The reduced equation of a one-driver mechanism (``docs/method.md``, "Forward dynamics") is
``M(q) q'' + 1/2 M'(q) w^2 = F(q, w) + T(w)`` with ``w = q'``.  With the kinetic energy
``E = 1/2 M w^2`` and ``q`` as the independent variable (``w`` keeps one sign),

    dE/dq = (dE/dt) / w = M q'' + 1/2 M' w^2 = F(q, w) + T(w),    w = sqrt(2 E / M),

so one turn is a first-order ODE in ``q`` and a periodic motion is a fixed point of the
period map ``E(q0) -> E(q0 + period)``.  With a motor curve or a damper the map contracts
(its derivative ``exp(int (dF/dw + T'(w)) / (M |w|) dq)`` is below one), so the fixed point
is unique.  It is found by Fourier collocation of ``ln E`` over the period (Newton, each
step by GMRES with FFTs); if that fails, by shooting (the period map integrated by SciPy,
Newton on its fixed point with the variational equation, safeguarded by a bracket), which
also tells a stall within a turn.  A flywheel of inertia ``I`` on the driver's crank adds ``I`` to
``M``; the smallest ``I`` with a coefficient of speed fluctuation
``Cs = (w_max - w_min) / ((w_max + w_min) / 2)`` at most the one asked is found by bracketing
and Brent's method on ``log Cs(I)`` (``Cs`` falls with ``I``).

>>> import numpy as np
>>> from linkagekit.dynamics import TorqueLaw
>>> class Toy:  # M = 1 + 0.5 cos 2q, no loads: a motor alone
...     period = 2 * np.pi
...     q_range = (0.0, 2 * np.pi)
...     def mass(self, q): return 1 + 0.5 * np.cos(2 * q)
...     def dmass(self, q): return -np.sin(2 * q)
...     def force(self, q, w): return 0 * q * w
>>> motor = TorqueLaw(2.0, 10.0)
>>> st = steady_state(Toy(), motor)
>>> round(float(np.mean(st.w[:-1])), 6)   # no loads: the motor's mean torque over a turn is 0
10.0
>>> round(st.cs, 4), round(size_flywheel_reduced(Toy(), motor, 0.02).inertia, 4)  # about (M_max - M_min) / (2 Cs) - M
(0.5359, 24.0025)
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from . import dynamics
from .dynamics import reduced, torque_laws
from .errors import InputError, LinkageError, shorten
from .model import CrankType, Mechanism
from .threads import one_blas_thread_with_scipy

Array = NDArray[Any]

#: solve_ivp's tolerances on the kinetic energy over one period (relative; absolute is RTOL * E0)
RTOL = 1e-10
#: the fixed point is accepted when one turn changes the energy by less than this (relative)
FIXED_POINT_TOL = 1e-10
#: the flywheel inertia is found to this relative tolerance
INERTIA_RTOL = 1e-6
#: Fourier collocation points per period to start with, and the most (doubled until the
#: harmonics of ln E above a quarter of the grid have amplitudes below TAIL: E to ~1e-10 relative)
COLLOCATION_POINTS = 512
MAX_COLLOCATION_POINTS = 8192
TAIL = 1e-10
#: Newton's steps on the collocation equations, and the step in ln E at which it has converged
#: (or below NEWTON_FLOOR, when the steps stop shrinking: rounding)
NEWTON_STEPS = 40
NEWTON_TOL = 1e-12
NEWTON_FLOOR = 1e-10
#: GMRES on each Newton step: relative residual and restart length
GMRES_RTOL = 1e-12
GMRES_RESTART = 60
#: grid of q for the mean torque balance that guesses the mean speed
BALANCE_SAMPLES = 256
#: the energy below which (relative to the period's start) the machine counts as stopped: its speed
#: fell to 1e-3 of the start's (the energy equation in q is singular at w = 0)
STALL_FRACTION = 1e-6


#: the least reduced inertia the energy equation divides by (kg*m^2): where nothing with inertia moves, ``M = 0``
_NO_MASS = 1e-300


class StallError(LinkageError):
    """No periodic motion: under the torque law the machine stops, or never settles.

    Exit status 1: the file and options are valid; the answer to the question asked is
    that this machine has no periodic steady state (like a simulation meeting a toggle).
    """

    exit_code = 1


class NoBalanceError(StallError):
    """No constant speed balances the torque law and the loads over a turn: no flywheel can help."""


class Reduced(Protocol):
    """The one-driver reduced model (``dynamics.reduced``), vectorised over ``q``."""

    @property
    def period(self) -> float | None: ...

    def mass(self, q: Array) -> Array: ...

    def force(self, q: Array, w: Array) -> Array: ...


Drive = Callable[[Array], Array]


@dataclass(frozen=True)
class SteadyState:
    """The periodic motion: speed ``w`` at the input values ``q`` over one period (``q[-1] = q[0] + period``).

    Attributes
    ----------
    q, w : ndarray
        Input value (rad) and speed (rad/s) over one period, closed (``w[-1] = w[0]``), on a
        grid 16 times finer than the collocation's.
    energy : float
        Kinetic energy ``1/2 M w^2`` at ``q[0]`` (J).
    w_min, w_max : float
        The extremes of ``|w|`` over the period.
    contraction : float
        The derivative of the period map at the fixed point (below 1: the motion attracts).
    extra_inertia : float
        The flywheel inertia added to the model (kg*m^2).
    nodes, log_energy : ndarray
        The collocation points (``q``, rad) and ``ln E`` there: the solution itself.
    """

    q: Array
    w: Array
    energy: float
    w_min: float
    w_max: float
    contraction: float
    extra_inertia: float
    nodes: Array
    log_energy: Array

    @property
    def mean_speed(self) -> float:
        """``(w_max + w_min) / 2``, the mean speed of the coefficient's definition."""
        return 0.5 * (self.w_max + self.w_min)

    @property
    def cs(self) -> float:
        """The coefficient of speed fluctuation ``(w_max - w_min) / ((w_max + w_min) / 2)``."""
        return (self.w_max - self.w_min) / self.mean_speed


@dataclass(frozen=True)
class FlywheelSize:
    """The answer of :func:`size_flywheel`: the smallest extra inertia and the steady state with it.

    ``float(size)`` is the inertia (kg*m^2).

    Attributes
    ----------
    inertia : float
        The extra inertia on the driver's crank (kg*m^2); 0 when none is needed.
    cs : float
        The coefficient of speed fluctuation of the steady state with it.
    cs_without : float
        The same without the extra inertia.
    steady : SteadyState
        The periodic motion with it.
    """

    inertia: float
    cs: float
    cs_without: float
    steady: SteadyState

    def __float__(self) -> float:
        return self.inertia


@dataclass(frozen=True)
class _Turn:
    """One run of the period map from the energy ``e0``."""

    e0: float
    e_end: float
    slope: float  # dE_end / dE0
    stalled: bool
    sol: Any


class _Problem:
    """The energy ODE over one period, with the extra inertia, in the driving direction."""

    def __init__(self, red: Reduced, drive: Drive, extra: float, q0: float, sign: float) -> None:
        if red.period is None:
            raise InputError(
                "flywheel sizing (--flywheel): the driver does not turn fully "
                "(no periodic motion to size a flywheel for)"
            )
        self.red, self.drive, self.extra = red, drive, float(extra)
        self.q0, self.sign, self.period = float(q0), float(sign), float(red.period)

    def mass(self, q: Array) -> Array:
        """``M(q)`` with the flywheel, never 0 (the energy equation divides by it; ``M`` of a massless crank and coupler
        vanishes where the output stops, and the sizing's trial flywheels start above 0)."""
        return np.maximum(np.asarray(self.red.mass(q), dtype=float) + self.extra, _NO_MASS)

    def speed(self, q: Array, e: Array) -> Array:
        """``w`` from the energy: ``sign * sqrt(2 E / M)`` (``E`` clipped at 0)."""
        return self.sign * np.sqrt(2.0 * np.maximum(e, 0.0) / self.mass(q))

    def rhs(self, u: float, y: Array) -> Array:
        """``d(E, ln dE/dE0)/du`` at ``q = q0 + sign * u``: the energy equation and its variational equation."""
        q = self.q0 + self.sign * u
        m = float(self.mass(np.array([q]))[0])
        speed = math.sqrt(2.0 * max(float(y[0]), 0.0) / m)
        h = 1e-6 * max(speed, 1e-3)
        ws = self.sign * np.array([speed, speed + h, speed - h])
        g = np.asarray(self.red.force(np.full(3, q), ws), dtype=float) + np.asarray(self.drive(ws), dtype=float)
        dg_dw = self.sign * (g[1] - g[2]) / (2.0 * h)
        return np.array([self.sign * g[0], dg_dw / (m * max(speed, 1e-300))])

    def turn(self, e0: float) -> _Turn:
        """Integrate one period from ``E(q0) = e0``; stop early if the energy falls to ~0 (a stall)."""
        from scipy.integrate import solve_ivp

        floor = STALL_FRACTION * e0

        def stop(u: float, y: Array) -> float:
            return float(y[0] - floor)

        stop.terminal = True  # type: ignore[attr-defined]
        stop.direction = -1  # type: ignore[attr-defined]
        sol = solve_ivp(
            self.rhs,
            (0.0, self.period),
            [e0, 0.0],
            method="DOP853",
            rtol=RTOL,
            atol=[RTOL * e0, RTOL],
            events=stop,
            dense_output=True,
        )
        stalled = sol.status == 1 or not sol.success
        return _Turn(e0, float(sol.y[0, -1]), math.exp(float(sol.y[1, -1])), stalled, sol)


def _mean_balance_speed(p: _Problem) -> float:
    """The constant speed at which the torque law's mean over a period balances the loads'.

    A first guess of the steady state's speed; raises :class:`StallError` when no speed
    balances (the mean torque cannot overcome the loads, or the speed grows without bound).
    """
    from scipy.optimize import brentq

    q = p.q0 + p.sign * np.linspace(0.0, p.period, BALANCE_SAMPLES, endpoint=False)

    def mean_power(speed: float) -> float:
        w = np.full_like(q, p.sign * speed)
        return float(p.sign * np.mean(np.asarray(p.red.force(q, w)) + np.asarray(p.drive(w))))

    zero = np.zeros_like(q)
    at_rest = np.asarray(p.red.force(q, zero))
    load = -p.sign * float(np.mean(at_rest))  # what the loads take at rest, on average
    load = 0.0 if abs(load) <= 1e-9 * float(np.max(np.abs(at_rest), initial=0.0)) else load  # rounding: conservative
    low = 1e-9
    if mean_power(low) <= 0.0:
        given = abs(float(np.asarray(p.drive(zero[:1]))[0]))
        if load <= 0.0:  # --torque 0 on conservative loads: "the loads take -0 N*m, more than ... 0 N*m"
            raise NoBalanceError(
                f"no periodic steady state: nothing drives the crank on average over a turn (the loads take "
                f"{load:.6g} N*m, the torque law gives {given:.6g} N*m at rest)"
            )
        raise NoBalanceError(
            f"the mechanism stalls: the loads take {load:.6g} N*m on average over a turn, more than the "
            f"torque law gives at any speed ({given:.6g} N*m at rest)"
        )
    high = 1.0
    for _ in range(80):
        if mean_power(high) < 0.0:
            return float(brentq(mean_power, low, high, xtol=1e-12, rtol=1e-12))
        low, high = high, 2.0 * high
    raise NoBalanceError(
        f"no periodic steady state: the speed grows without bound (the torque law exceeds the loads' mean "
        f"{load:.6g} N*m at every speed; a motor curve or a damper would balance it)"
    )


def _energy_at(p: _Problem, speed: float) -> float:
    return float(0.5 * p.mass(np.array([p.q0]))[0] * speed**2)


def _fixed_point(p: _Problem, e0: float) -> _Turn:
    """Safeguarded Newton iteration on ``g(E0) = E(end) - E0``.

    ``g`` falls with ``E0`` (the map's slope is below one), so a bracket ``[lo, hi]`` with
    ``g > 0`` or a stall at ``lo`` and ``g < 0`` at ``hi`` holds the fixed point; a Newton
    step leaving it is replaced by bisection (or by growing ``E0`` while no ``hi`` is known).
    A bracket that shrinks onto a stall without a fixed point means there is none.
    """
    lo, hi, lo_stalled = 0.0, math.inf, True
    for _ in range(200):
        t = p.turn(e0)
        g = t.e_end - e0
        if not t.stalled and abs(g) <= FIXED_POINT_TOL * e0:
            return t
        if t.stalled or g > 0.0:
            lo, lo_stalled = e0, t.stalled
        else:
            hi = e0
        if lo_stalled and hi - lo <= STALL_FRACTION * hi:
            break
        step = e0 - g / (t.slope - 1.0) if not t.stalled and t.slope < 1.0 else math.nan
        e0 = step if lo < step < hi else (0.5 * (lo + hi) if math.isfinite(hi) else 4.0 * e0)
    if lo_stalled:
        raise StallError("the mechanism stalls: under this torque law the speed falls to zero within a turn")
    raise StallError("no periodic steady state: the period map did not converge")


class _Collocation:
    """``dz/du = sign (F + T) e^-z`` (``z = ln E``) at ``n`` Fourier points of one period, solved by Newton.

    Matrix-free: ``d/du`` by FFT, each Newton step by GMRES preconditioned with the
    constant-coefficient operator (no dense solve, which a busy multi-threaded BLAS makes slow).
    """

    def __init__(self, p: _Problem, n: int) -> None:
        self.p, self.n = p, n
        self.u = np.arange(n) * (p.period / n)
        self.q = p.q0 + p.sign * self.u
        self.m = p.mass(self.q)
        self.ik = 1j * np.fft.rfftfreq(n, 1.0 / n) * (2.0 * np.pi / p.period)
        self.ik[-1] = 0.0  # the Nyquist mode's derivative (as the Fourier differentiation matrix has it)

    def deriv(self, x: Array) -> Array:
        """``dx/du`` of the trigonometric interpolant, at the points."""
        return np.asarray(np.fft.irfft(self.ik * np.fft.rfft(x), self.n), dtype=float)

    def parts(self, z: Array) -> tuple[Array, Array, Array]:
        """The residual, the diagonal of ``d(rate)/dz`` and ``dF/dw + T'`` at ``z``."""
        p = self.p
        e = np.exp(z)
        w = p.sign * np.sqrt(2.0 * e / self.m)
        h = 1e-6 * np.maximum(np.abs(w), 1e-3)
        ws = np.concatenate([w, w + h, w - h])
        gs = np.asarray(p.red.force(np.tile(self.q, 3), ws), dtype=float) + np.asarray(p.drive(ws), dtype=float)
        g, g_w = gs[: self.n], (gs[self.n : 2 * self.n] - gs[2 * self.n :]) / (2.0 * h)
        rate = p.sign * g / e
        return self.deriv(z) - rate, p.sign * (g_w * w / 2.0 - g) / e, g_w

    def newton_step(self, r: Array, a: Array) -> Array | None:
        """``(d/du - diag(a))^-1 (-r)`` by GMRES, preconditioned by ``d/du - mean(a)`` (diagonal in Fourier space)."""
        from scipy.sparse.linalg import LinearOperator, gmres

        shift = float(np.mean(a))
        if not shift < 0.0:
            return None  # no contraction on average: the periodic solution is not isolated
        inverse = 1.0 / (self.ik - shift)
        n = self.n
        jac = LinearOperator((n, n), matvec=lambda x: self.deriv(x) - a * x, dtype=float)
        pre = LinearOperator((n, n), matvec=lambda x: np.fft.irfft(inverse * np.fft.rfft(x), n), dtype=float)
        step, info = gmres(jac, -r, M=pre, rtol=GMRES_RTOL, atol=0.0, restart=GMRES_RESTART, maxiter=20)
        return None if info != 0 else np.asarray(step, dtype=float)

    def solve(self, z: Array) -> Array | None:
        """Damped Newton from ``z``; None when it does not converge to ``NEWTON_TOL``."""
        r, a, _ = self.parts(z)
        last = math.inf
        for _ in range(NEWTON_STEPS):
            step = self.newton_step(r, a)
            if step is None:
                return None
            size = float(np.max(np.abs(step)))
            if size <= NEWTON_TOL or (size <= NEWTON_FLOOR and size > last / 2.0):
                return z  # converged, or stalled at the rounding of the FFT derivative on a fine grid
            last = size
            lam, norm = 1.0, float(np.max(np.abs(r)))
            while True:
                z_try = z + lam * step
                r_try, a_try, _ = self.parts(z_try)
                if np.max(np.abs(r_try)) < (1.0 - lam / 4.0) * norm or lam < 1e-3:
                    break
                lam /= 2.0
            z, r, a = z_try, r_try, a_try
            if not np.all(np.isfinite(z)):
                return None
        return None

    def resolved(self, z: Array) -> bool:
        """Whether the harmonics of ``ln E`` above a quarter of the grid have amplitudes below ``TAIL``."""
        amplitude = 2.0 * np.abs(np.fft.rfft(z)) / self.n
        return bool(np.max(amplitude[self.n // 4 :]) <= TAIL)

    def upsample(self, z: Array, factor: int) -> Array:
        """The trigonometric interpolant of ``z`` on ``factor`` times as many points."""
        c = np.fft.rfft(z)
        c[-1] *= 0.5  # the Nyquist mode split evenly (a real interpolant)
        return np.asarray(np.fft.irfft(c, factor * self.n) * factor, dtype=float)


def _periodic_energy(p: _Problem, z: Array | None) -> tuple[_Collocation, Array]:
    """``ln E`` at the collocation points: Fourier collocation, refined until resolved; shooting if it fails."""
    n = COLLOCATION_POINTS if z is None else len(z)
    if z is None:
        z = np.full(n, math.log(_energy_at(p, _mean_balance_speed(p))))
    while True:
        col = _Collocation(p, n)
        sol = col.solve(z)
        if sol is None:
            break
        if col.resolved(sol) or 2 * n > MAX_COLLOCATION_POINTS:
            return col, sol
        n, z = 2 * n, col.upsample(sol, 2)
    # Newton on the collocation failed: shoot (slower, and tells a stall from a slow start)
    col = _Collocation(p, COLLOCATION_POINTS)
    t = _fixed_point(p, _energy_at(p, _mean_balance_speed(p)))
    return col, np.log(np.maximum(t.sol.sol(col.u)[0], 1e-300))


def _speed_extremes(p: _Problem, col: _Collocation, z: Array) -> tuple[Array, Array, float, float]:
    """``q`` and ``w`` on a 16-fold finer grid (closed over the period), and ``min |w|``, ``max |w|``."""
    fine = col.upsample(z, 16)
    n = len(fine)
    u = np.arange(n + 1) * (p.period / n)
    q = p.q0 + p.sign * u
    w = p.speed(q, np.exp(np.append(fine, fine[0])))
    a = np.abs(w[:-1])
    return q, w, _vertex(a, int(np.argmin(a))), _vertex(a, int(np.argmax(a)))


def _vertex(v: Array, k: int) -> float:
    """The extreme of a periodic sampled function at sample ``k``, by the parabola through its neighbours."""
    a, b, c = v[k - 1], v[k], v[(k + 1) % len(v)]
    curv = a - 2.0 * b + c
    return float(b) if curv == 0.0 else float(b - (c - a) ** 2 / (8.0 * curv))


def steady_state(
    red: Reduced, drive: Drive, extra_inertia: float = 0.0, *, start: SteadyState | None = None
) -> SteadyState:
    """The periodic motion of a one-driver mechanism under the torque law ``drive(w)``.

    Parameters
    ----------
    red : Reduced
        The reduced model; ``red.period`` must be set (the crank turns fully).
    drive : callable
        The driver torque as a function of the speed (e.g. :class:`~linkagekit.dynamics.TorqueLaw`).
    extra_inertia : float
        A flywheel on the crank, added to ``M(q)`` (kg*m^2).
    start : SteadyState, optional
        A steady state (another flywheel) whose speeds start the Newton iteration; default:
        the constant speed of mean torque balance.

    Raises
    ------
    StallError
        When no periodic motion exists (the machine stops, or never settles).
    InputError
        Without ``extra_inertia``, when ``M`` vanishes somewhere (:func:`~linkagekit.dynamics.inertia_zeros`).
    """
    q0 = float(getattr(red, "q0", getattr(red, "q_range", (0.0,))[0]))
    if extra_inertia == 0.0 and isinstance(red, dynamics.Reduced) and len(zeros := dynamics.inertia_zeros(red)):
        raise InputError(
            f"no steady state without a flywheel: nothing with inertia moves with the driver at {zeros[0]:.6g} rad"
            " (its speed is unbounded there, or depends on the inertia left out); add a flywheel or an inertia"
        )
    sign = 1.0 if float(np.asarray(drive(np.zeros(1)))[0]) >= 0.0 else -1.0
    p = _Problem(red, drive, extra_inertia, q0, sign)
    z = (
        None
        if start is None
        else start.log_energy + np.log(p.mass(start.nodes) / (p.mass(start.nodes) - p.extra + start.extra_inertia))
    )
    col, z = _periodic_energy(p, z)
    q, w, w_min, w_max = _speed_extremes(p, col, z)
    _, _, g_w = col.parts(z)
    contraction = math.exp(float(np.mean(g_w / (col.m * np.abs(p.speed(col.q, np.exp(z)))))) * p.period)
    return SteadyState(q, w, float(np.exp(z[0])), w_min, w_max, contraction, float(extra_inertia), col.q, z)


#: the smallest coefficient of speed fluctuation sized for: the kinetic energy over a period is integrated to
#: :data:`RTOL` relative (the speeds to half that), and a flywheel for 1e-15 left a fluctuation that rounded to 0 (a
#: math domain error; review 16a)
MIN_CS = 1e-9


def size_flywheel_reduced(red: Reduced, drive: Drive, cs: float, *, rtol: float = INERTIA_RTOL) -> FlywheelSize:
    """The smallest extra inertia on the crank for which the steady state's ``Cs`` is at most ``cs``.

    ``Cs(I)`` falls with ``I``, roughly as ``1 / (M_mean + I)``: that model's prediction
    (enlarged by 5 %) is tried until one meets ``cs``, which brackets the answer; Brent's
    method on ``log(Cs(I) / cs)`` then finds it to ``rtol`` relative.  The inertia returned
    is the bracket's upper end, so its ``Cs`` is at most ``cs`` (to the integration's tolerance).
    A machine that stalls within a turn with too small a flywheel counts as ``Cs = 2`` there
    (the limit as ``w_min -> 0``): the flywheel that carries it through is part of the answer.
    """
    from scipy.optimize import brentq

    if not 0.0 < cs < 2.0:
        raise InputError(f"cs (--flywheel CS): the coefficient of speed fluctuation must be in (0, 2), got {cs}")
    if cs < MIN_CS:  # a flywheel for less swings the speed below the steady state's tolerance: Cs came out 0
        raise InputError(f"cs (--flywheel CS): at least {MIN_CS:g}, what the steady state resolves; got {cs:g}")
    search = _Search(red, drive)
    cs_without = search.cs(0.0)
    if cs_without <= cs:
        return FlywheelSize(0.0, cs_without, cs_without, search.found[0.0])
    m_mean = search.mean_mass()

    def excess(inertia: float) -> float:
        return math.log(search.cs(inertia) / cs)

    lo, hi = 0.0, 0.0
    while excess(hi) > 0.0:
        lo, hi = hi, max((m_mean + hi) * search.cs(hi) / cs * 1.05 - m_mean, 2.0 * hi)
    root = brentq(excess, lo, hi, xtol=1e-12 * hi, rtol=rtol / 4.0)  # |root - crossing| <= rtol / 4 * root
    top = root * (1.0 + rtol / 2.0)
    if top < hi and excess(top) <= 0.0:
        hi = top
    st = search.found[hi]
    return FlywheelSize(hi, st.cs, cs_without, st)


class _Search:
    """``Cs`` of the steady state for each flywheel tried, each started from the nearest one solved."""

    def __init__(self, red: Reduced, drive: Drive) -> None:
        self.red, self.drive = red, drive
        self.found: dict[float, SteadyState] = {}
        self.stalled: set[float] = set()
        self.vanishes = isinstance(red, dynamics.Reduced) and len(dynamics.inertia_zeros(red)) > 0

    def cs(self, inertia: float) -> float:
        """``Cs`` with ``inertia`` on the crank; 2 where the machine stalls within a turn, or where nothing with inertia
        turns with the crank at some input and no flywheel is added (:func:`steady_state` refuses that model)."""
        if inertia in self.stalled or (inertia == 0.0 and self.vanishes):
            return 2.0
        if inertia not in self.found:
            near = min(self.found, key=lambda i: abs(i - inertia)) if self.found else None
            try:
                st = steady_state(self.red, self.drive, inertia, start=None if near is None else self.found[near])
            except NoBalanceError:
                raise
            except StallError:
                self.stalled.add(inertia)
                return 2.0
            self.found[inertia] = st
        return self.found[inertia].cs

    def mean_mass(self) -> float:
        """``M`` averaged over a period (kg*m^2)."""
        period = float(self.red.period or 2.0 * math.pi)
        q0 = float(getattr(self.red, "q0", 0.0))
        return float(np.mean(self.red.mass(q0 + np.linspace(0.0, period, 256, endpoint=False))))


@one_blas_thread_with_scipy
def size_flywheel(
    mech: Mechanism,
    cs: float,
    *,
    torque: float | Mapping[str, float] | None = None,
    motor: tuple[float, float] | Mapping[str, tuple[float, float]] | None = None,
) -> FlywheelSize:
    """The smallest extra inertia on the driver's crank that keeps the steady state's ``Cs`` at most ``cs``.

    The mechanism has one crank driver that turns fully; the torque law is ``torque`` (a
    constant, N*m) or ``motor`` ``(T0, W0)``: ``T = T0 (1 - w / W0)``, as :func:`simulate`
    takes them.  The file's own flywheels stay; the inertia found is added to theirs.

    Parameters
    ----------
    mech : Mechanism
    cs : float
        The coefficient of speed fluctuation ``(w_max - w_min) / ((w_max + w_min) / 2)`` asked.
    torque, motor
        The torque law (one of them).

    Returns
    -------
    FlywheelSize
        ``inertia`` (kg*m^2; ``float(size)``), the ``cs`` reached, ``cs_without`` the extra
        inertia, and ``steady`` the periodic motion with it.

    Raises
    ------
    InputError
        Not one crank driver that turns fully, no torque law, or ``cs`` not a positive number (exit 2).
    StallError
        No periodic motion under this torque law: the machine stalls, or runs away (exit 1).

    Examples
    --------
    >>> import linkagekit as lk
    >>> mech = lk.load("examples/motor_fourbar.yaml")
    >>> size = lk.size_flywheel(mech, 0.02, motor=(6500.0, 6.5))
    >>> round(size.cs, 6), size.cs_without > 0.02, round(size.steady.mean_speed, 2)
    (0.02, True, 6.2)
    """
    if not isinstance(mech, Mechanism):
        raise InputError(f"expected a linkagekit Mechanism (lk.load(...)), got {type(mech).__name__}")
    if len(mech.drivers) != 1 or not isinstance(mech.drivers[0].type, CrankType):
        kinds = ", ".join(f"'{d.name}' ({d.kind})" for d in mech.drivers) or "none"
        raise InputError(
            f"flywheel sizing (--flywheel): {mech.source}: needs exactly one crank driver (the flywheel's link); "
            f"drivers: {kinds}"
        )
    if torque is None and motor is None:
        raise InputError(
            "flywheel sizing (--flywheel): give the torque law: torque= or motor= (--torque T or --motor T0,W0)"
        )
    try:
        target = float(cs)
    except (TypeError, ValueError):
        raise InputError(f"cs (--flywheel CS): expected a number, got {shorten(repr(cs))}") from None
    (law,) = torque_laws(mech, torque, motor)
    return size_flywheel_reduced(reduced(mech), law, target)
