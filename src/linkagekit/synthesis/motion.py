r"""Approximate motion generation: a four-bar whose coupler passes near any number of poses.

A pose ``i`` is a point ``d_i`` of the moving body and the direction ``theta_i`` of a line of
the body (``u_i = e^{i theta_i}``). A point of the body with coordinates ``c`` in the body's
frame (origin at the pose point, first axis along the line) is at ``W_i(c) = d_i + u_i c``.

Error measure
-------------
All lengths are divided by the poses' bounding-box diagonal ``L``. A four-bar driven to the
crank angle ``t_i`` puts its body frame at ``(O(t_i), u(t_i))``; the pose's errors are the
position error ``p_i = |O(t_i) - d_i| / L`` and the orientation error
``a_i = |arg(u(t_i) / u_i)|`` (radians). The figure minimised is

.. math:: E = \max_i \max(p_i,\ w\, a_i)

with the *angle weight* ``w`` (default :data:`ANGLE_WEIGHT`: one radian of orientation weighs
as much as ``w`` diagonals of position); the errors are reported separately, in lengths and
degrees.

Route (docs/method.md, "Motion generation")
-------------------------------------------
1. **Dyads by circle fits.** A dyad is a ground pivot ``g``, a body point ``c`` and a radius
   ``r``; it is exact when every ``W_i(c)`` is on the circle ``|W - g| = r``. For a grid of body
   points the best circle is a linear least-squares problem (Kasa's fit: ``2 g . W + k =
   |W|^2``, ``k = r^2 - |g|^2``), solved for every grid point at once; the best grid points are
   refined by Levenberg-Marquardt on the geometric residuals ``|W_i(c) - g| - r`` over
   ``(c, g, r)``, all at once (5 unknowns per dyad). With timing (an input angle per pose)
   the crank dyad also fits ``arg(W_i - g) - arg(W_0 - g)`` to the inputs' differences.
   The engine's global search over :class:`MotionObjective` (the same circle fits as one
   8-dimensional objective of both dyads) adds its best pair.
2. **Four-bars.** Every ordered pair of distinct dyads (crank, rocker) is a four-bar whose
   assembly mode is the one its dyads have at the first pose; driven to the crank's fitted
   angles it is scored by ``E`` (vectorized over pairs). Fitted to measured (scattered)
   poses, the angles of close poses may come a little out of order; they are replaced by
   the nearest in-order angles (:func:`in_order`), at which ``E`` is then measured.
3. **Minimax polish** of the best four-bars: SLSQP on the epigraph form ``min tau`` subject
   to ``p_i^2 <= tau^2``, ``-tau <= w (phi_i - theta_i) <= tau`` over the ten link
   parameters and the crank angles (one common offset with timing), the crank angles kept
   in order within a turn.
4. **Dense check** of one branch: the crank turns one way from the first pose's angle to the
   last one's (a full turn for closed motions) through every pose in order (never back;
   two poses may share an angle), and the four-bar assembles all along (constant assembly
   mode, so no jump), checked exactly (:func:`~linkagekit.geometry.fourbar_sweep`: the crank
   tip's distance from the rocker's pivot is a sinusoid in the crank angle); the smallest
   transmission angle is reported and kept above ``min_transmission``.
5. **Other weights.** At a weight other than :data:`ANGLE_WEIGHT`, steps 2-4 run at every
   weight of :func:`weight_ladder`, each trying the four-bars found before at their own angles.

Steps 3 and 4 respect the run's deadline (``approximate(..., deadline=)``): past it, no
further four-bar is polished and a polish under way stops at its last iterate (kept only
when the dense check finds it better than its start), so the best found so far is returned.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import partial
from typing import TYPE_CHECKING

import numpy as np

from ..errors import InputError
from ..geometry import ComplexArray, FloatArray, cis, fourbar_sweep
from .base import Objective, Score, digest

if TYPE_CHECKING:
    from ..model import Mechanism

#: one radian of orientation error weighs as much as this many diagonals of position error
ANGLE_WEIGHT = 0.05
#: body-point grid of the dyad search (per axis), its half-width in diagonals, the dyads kept
GRID, GRID_REACH, DYADS = 48, 1.5, 14
#: pivots and radii beyond this many diagonals are left out (a nearly straight path: a slider's job)
FAR_PIVOT = 12.0
#: Levenberg-Marquardt iterations of the dyad refinement
LM_STEPS = 60
#: four-bars polished by the minimax step; one whose error is this many times the best polished one's is not
POLISHED, HOPELESS = 6, 20.0
#: a four-bar this near (E) needs no polish
EXACT = 1e-10
#: two poses nearer than this (diagonals and radians) are one pose
SAME_POSE = 1e-9
#: joint names of the written four-bar
JOINTS = ("A0", "A1", "B1", "B0", "P", "Q")


@dataclass(frozen=True)
class MotionPoses:
    """Poses normalised: ``d`` (m,) complex about the centre over the diagonal, ``theta`` (m,) radians.

    ``inputs`` (m,) radians or None (timing); ``closed``: the motion returns to its first pose.
    """

    d: ComplexArray
    theta: FloatArray
    center: complex
    scale: float
    inputs: FloatArray | None = None
    closed: bool = False

    @property
    def m(self) -> int:
        return len(self.d)

    @property
    def u(self) -> ComplexArray:
        return cis(self.theta)

    def at(self, c: ComplexArray) -> ComplexArray:
        """``W_i(c)``: body points ``c`` (..., 1) placed at every pose, (..., m)."""
        return self.d + self.u * c


def _check_timing(th: FloatArray, source: str) -> None:
    """The crank meets the poses in their order within one turn: ``th`` (radians) strictly monotone, spanning < 2 pi."""
    steps = np.diff(th)
    if not (np.all(steps > 0) or np.all(steps < 0)):
        k = int(np.argmax(steps * np.sign(np.sum(steps)) <= 0)) + 2
        raise InputError(f"{source}: pose {k}: the inputs must increase (or decrease) along the poses")
    if abs(th[-1] - th[0]) >= 2 * np.pi:
        span = abs(float(np.degrees(th[-1] - th[0])))
        raise InputError(f"{source}: the inputs span {span:g} deg; the crank meets the poses within one turn")


#: the most poses a motion task takes: without timing the minimax polish (:func:`minimax_polish`) has a crank
#: angle per pose and constraints at each, so its Jacobian has (poses)^2 entries times a few (10000 poses ran 36 s
#: past a 3 s budget and took 4 GB, 30000 ran out of memory)
MAX_POSES = 1000


def first_repeat(d: ComplexArray, angle: FloatArray) -> tuple[int, int] | None:
    """The first pair ``i < j`` (by ``i``, then ``j``) of poses within :data:`SAME_POSE`, or None.

    Two poses are the same when ``|d_i - d_j| + |angle_i - angle_j|`` (the angle's difference on
    the turn) is at most :data:`SAME_POSE`.  Then their points ``(d, cos angle, sin angle)`` are
    as near (the chord is shorter than the arc), so a k-d tree's pairs that near are the only
    candidates: memory linear in the poses (every pair, n x n, took 13 GiB for 30000 poses).

    >>> first_repeat(np.array([0, 1, 1, 1 + 1e-12]), np.radians([0, 10, 20, 10]))
    (1, 3)
    >>> first_repeat(np.array([0j, 0j]), np.array([0.0, 2 * np.pi])), first_repeat(np.array([0j, 1]), np.zeros(2))
    ((0, 1), None)
    """
    from scipy.spatial import cKDTree

    pts = np.column_stack([d.real, d.imag, np.cos(angle), np.sin(angle)])
    ij = cKDTree(pts).query_pairs(2 * SAME_POSE, output_type="ndarray")  # twice: rounding of cos, sin
    i, j = np.sort(ij, axis=1).T if len(ij) else (np.zeros(0, int), np.zeros(0, int))
    gap = np.abs(d[i] - d[j]) + np.abs(np.angle(cis(angle[i] - angle[j])))
    same = np.flatnonzero(gap <= SAME_POSE)
    if not len(same):
        return None
    k = same[np.lexsort((j[same], i[same]))[0]]
    return int(i[k]), int(j[k])


def motion_poses(
    x: FloatArray,
    y: FloatArray,
    angle: FloatArray,
    inputs: FloatArray | None = None,
    closed: bool = False,
    source: str = "poses",
) -> MotionPoses:
    """Checked, normalised poses (3 to :data:`MAX_POSES`) from coordinates and angles (radians); ``inputs`` in radians.

    >>> p = motion_poses(np.array([0.0, 3, 4]), np.array([0.0, 0, 0]), np.radians([0, 10, 20]))
    >>> p.scale, round(p.center.real, 3)
    (4.0, 2.0)
    """
    x, y, angle = (np.asarray(v, float).reshape(-1) for v in (x, y, angle))
    if not len(x) == len(y) == len(angle):
        raise InputError(f"{source}: x, y and angle need one value per pose")
    if len(x) < 3:
        raise InputError(f"{source}: {len(x)} poses; at least 3 are needed")
    if len(x) > MAX_POSES:
        raise InputError(
            f"{source}: {len(x)} poses; at most {MAX_POSES} (the polish's constraints grow with the square of "
            "the poses): give every k-th pose"
        )
    if not np.all(np.isfinite(np.concatenate([x, y, angle]))):
        raise InputError(f"{source}: every x, y and angle must be a finite number")
    z = x + 1j * y
    lo, hi = complex(x.min(), y.min()), complex(x.max(), y.max())
    scale = float(abs(hi - lo))
    if scale <= 0:
        raise InputError(f"{source}: the pose points span no distance")
    center = (lo + hi) / 2
    d = (z - center) / scale
    rep = first_repeat(d, angle)
    if rep is not None:
        raise InputError(f"{source}: pose {rep[1] + 1} repeats pose {rep[0] + 1}")
    th = None
    if inputs is not None:
        th = np.asarray(inputs, float).reshape(-1)
        if th.shape != x.shape or not np.all(np.isfinite(th)):
            raise InputError(f"{source}: one finite input angle per pose is needed")
        _check_timing(th, source)
    return MotionPoses(d, angle, center, scale, th, closed)


@dataclass(frozen=True)
class PoseFile:
    """Poses read from a CSV file: ``poses`` (m, 3) ``x, y, angle`` (degrees), ``inputs`` (degrees) or None."""

    poses: FloatArray
    inputs: FloatArray | None
    closed: bool
    source: str


#: the largest |angle| (degrees) a pose file may give
MAX_ANGLE = 360.0


def read_poses(path: str) -> PoseFile:
    """Poses from a CSV file with the header ``x,y,angle`` or ``x,y,angle,input`` (docs/commands.md).

    The motion is closed when the last pose repeats the first (the repeat is dropped). Bad
    input (fewer than 3 poses, a value not a finite number, an angle beyond 360 degrees, two
    equal poses) raises :class:`~linkagekit.errors.InputError` with one line naming the file.
    """
    from .targets import check_scale, read_table

    cols, table = read_table(path, [("x", "y", "angle"), ("x", "y", "angle", "input")], "pose")
    P = table[:, [cols.index(c) for c in ("x", "y", "angle")]]
    ins = table[:, cols.index("input")] if "input" in cols else None
    if len(P) < 3:  # before the size below, which a header with no rows would break
        raise InputError(f"{path}: {len(P)} poses; at least 3 are needed")
    bad = np.flatnonzero(np.abs(P[:, 2]) > MAX_ANGLE)
    if len(bad):
        raise InputError(f"{path}: pose {bad[0] + 1}: angle {P[bad[0], 2]:g} is out of range [-360, 360] degrees")
    check_scale(P[:, :2], path, "length units")  # 1e300 named no file: '<motion synthesis>: joints.A0[0]: too large'
    size = float(np.hypot(np.ptp(P[:, 0]), np.ptp(P[:, 1])))
    turn = abs(np.angle(np.exp(1j * np.radians(P[-1, 2] - P[0, 2]))))
    closed = len(P) > 3 and bool(np.hypot(*(P[-1, :2] - P[0, :2])) <= SAME_POSE * size and turn <= SAME_POSE)
    if closed:
        P, ins = P[:-1], None if ins is None else ins[:-1]
    rad = None if ins is None else np.radians(ins)
    motion_poses(P[:, 0], P[:, 1], np.radians(P[:, 2]), rad, closed, source=path)  # checked here, naming the file
    return PoseFile(P, ins, closed, path)


# ---------------------------------------------------------------------- dyads
@dataclass(frozen=True)
class Dyads:
    """K dyads (normalised): body points ``c``, ground pivots ``g``, radii ``r``, RMS residual ``rms``."""

    c: ComplexArray
    g: ComplexArray
    r: FloatArray
    rms: FloatArray


def kasa(W: ComplexArray) -> tuple[ComplexArray, FloatArray]:
    """Least-squares circles ``2 g . W + k = |W|^2`` through the rows of ``W`` (K, m): centres and radii.

    >>> g, r = kasa(np.array([[1, 1j, -1, -1j]]) * 2 + 3)
    >>> complex(np.round(g[0], 12)), float(np.round(r[0], 12))
    ((3+0j), 2.0)
    """
    M = np.stack([2 * W.real, 2 * W.imag, np.ones(W.shape)], axis=-1)  # (K, m, 3)
    rhs = np.abs(W) ** 2
    A = np.einsum("kmi,kmj->kij", M, M) + 1e-14 * np.eye(3)
    b = np.einsum("kmi,km->ki", M, rhs)
    s = np.linalg.solve(A, b[..., None])[..., 0]
    g = s[:, 0] + 1j * s[:, 1]
    r = np.sqrt(np.maximum(s[:, 2] + np.abs(g) ** 2, 0.0))
    return g, r


def _dyad_residuals(p: MotionPoses, V: FloatArray, timed: bool) -> FloatArray:
    """Residuals (K, m or 2m) of dyads ``V`` (K, 5) = ``[cx, cy, gx, gy, r]``: ``|W_i - g| - r`` (+ timing)."""
    c, g, r = V[:, 0] + 1j * V[:, 1], V[:, 2] + 1j * V[:, 3], V[:, 4]
    R = p.at(c[:, None]) - g[:, None]
    out = np.abs(R) - r[:, None]
    if timed and p.inputs is not None:
        turn = np.angle(R * np.conj(R[:, :1]) * cis(-(p.inputs - p.inputs[0])))
        out = np.concatenate([out, turn * r[:, None]], axis=1)
    return out


def _solve_damped(D: FloatArray, b: FloatArray) -> FloatArray:
    """``D x = b`` for every dyad (K, 5, 5), (K, 5); a matrix singular to rounding gets a ridge of 1e-12 of its scale.

    Levenberg-Marquardt's damping shrinks on every success: on a dyad whose residuals do not
    depend on one direction (100 poses on a circular arc) ``D`` became singular to the last bit and
    the whole search died with ``LinAlgError: Singular matrix``.
    """
    try:
        x = np.linalg.solve(D, b[..., None])
    except np.linalg.LinAlgError:
        scale = np.trace(D, axis1=1, axis2=2)[:, None, None] / 5 + 1e-300
        x = np.linalg.solve(D + 1e-12 * scale * np.eye(5), b[..., None])
    out: FloatArray = np.asarray(x[..., 0], float)
    return out


def refine_dyads(p: MotionPoses, V: FloatArray, timed: bool = False, steps: int = LM_STEPS) -> FloatArray:
    """Levenberg-Marquardt on :func:`_dyad_residuals` for every dyad at once (central-difference Jacobian)."""
    lam = np.full(len(V), 1e-3)
    h = 1e-7
    for _ in range(steps):
        r0 = _dyad_residuals(p, V, timed)
        f0 = np.sum(r0 * r0, axis=1)
        E = np.eye(5) * h
        J = np.stack([(_dyad_residuals(p, V + e, timed) - _dyad_residuals(p, V - e, timed)) / (2 * h) for e in E], -1)
        JtJ = np.einsum("kmi,kmj->kij", J, J)
        g = np.einsum("kmi,km->ki", J, r0)
        D = JtJ + lam[:, None, None] * (np.eye(5) * np.diagonal(JtJ, axis1=1, axis2=2)[:, None, :] + 1e-12 * np.eye(5))
        step = _solve_damped(D, -g)
        Vn = V + step
        rn = _dyad_residuals(p, Vn, timed)
        fn = np.sum(rn * rn, axis=1)
        better = np.isfinite(fn) & (fn < f0)
        V = np.where(better[:, None], Vn, V)
        lam = np.where(better, lam * 0.3, lam * 10.0)
    return V


def search_dyads(p: MotionPoses, timed: bool = False) -> Dyads:
    """The ``DYADS`` best distinct dyads: grids of body points, Kasa's circles, the best of each grid refined.

    The body points' first-pose positions are a square about the poses' centre and rings out
    to the far ones; each grid sends its own best to the refinement, so that the many nearly
    straight-moving far points cannot crowd out a near one.
    """
    s = np.linspace(-GRID_REACH, GRID_REACH, GRID)
    rho = np.geomspace(GRID_REACH, FAR_PIVOT / 2, GRID // 2)
    square = s[:, None] + 1j * s[None, :]
    rings = rho[:, None] * cis(np.linspace(0, 2 * np.pi, 2 * GRID)[None, :-1])
    starts = [
        _best_starts(p, square, 5 * DYADS, timed, ("nearest", "nearest")),
        _best_starts(p, rings, 3 * DYADS, timed, ("nearest", "wrap")),
    ]
    V = refine_dyads(p, np.concatenate(starts), timed)
    return _distinct(V, _rms(p, V, timed))


def _best_starts(p: MotionPoses, W0: ComplexArray, k: int, timed: bool, modes: tuple[str, str]) -> FloatArray:
    """Dyads (k, 5) of the body points at first-pose positions ``W0`` (a 2-d grid) whose Kasa circles fit best.

    The grid's local minima of the residual come first (best first), then the best of the rest:
    each valley of the residual gets a start, however shallow.
    """
    from scipy.ndimage import minimum_filter

    c = ((W0 - p.d[0]) / p.u[0]).reshape(-1)
    V, rms = _grid_fits(p, c, timed)
    grid = np.where(np.isfinite(rms), rms, np.inf).reshape(W0.shape)
    local = (grid <= minimum_filter(grid, size=3, mode=modes)).reshape(-1) & np.isfinite(rms)
    order = np.lexsort((rms, ~local))
    best: FloatArray = V[order[:k]]
    return best


#: the most (body point, pose) values :func:`_grid_fits` holds at once (its arrays per block: about 16 MB each)
GRID_BLOCK = 1 << 21


def _grid_fits(p: MotionPoses, c: ComplexArray, timed: bool) -> tuple[FloatArray, FloatArray]:
    """Kasa's circle of each body point ``c`` (K,) over the poses: dyads (K, 5) and their RMS residuals (K,).

    In blocks of body points, so that memory stays :data:`GRID_BLOCK` values whatever the poses' count
    (the whole grid at once took 2304 x 30000 values per array, GBs in all, for 30000 poses).
    """
    per = max(1, GRID_BLOCK // p.m)
    V, rms = np.empty((len(c), 5)), np.empty(len(c))
    for start in range(0, len(c), per):  # blocks of the grid (a few for any count of poses that fits one block)
        sl = slice(start, start + per)
        g, r = kasa(p.at(c[sl, None]))
        V[sl] = np.stack([c[sl].real, c[sl].imag, g.real, g.imag, r], axis=1)
        rms[sl] = _rms(p, V[sl], timed)
    return V, rms


def _rms(p: MotionPoses, V: FloatArray, timed: bool) -> FloatArray:
    """RMS residual of dyads; inf for a far pivot or radius (``FAR_PIVOT``) or a radius below 1e-3."""
    res = _dyad_residuals(p, V, timed)
    rms = np.sqrt(np.mean(res * res, axis=1))
    far = (np.hypot(V[:, 2], V[:, 3]) > FAR_PIVOT) | (V[:, 4] > FAR_PIVOT) | (V[:, 4] < 1e-3)
    return np.where(far | ~np.isfinite(rms), np.inf, rms)


def _distinct(V: FloatArray, rms: FloatArray) -> Dyads:
    """The ``DYADS`` lowest-residual dyads, no two within ``1e-3`` (diagonals) in (c, g)."""
    order = np.argsort(rms)
    kept: list[int] = []
    for i in order:
        if not np.isfinite(rms[i]) or len(kept) == DYADS:
            break
        if all(np.max(np.abs(V[i, :4] - V[k, :4])) > 1e-3 for k in kept):
            kept.append(int(i))
    K = V[kept]
    return Dyads(K[:, 0] + 1j * K[:, 1], K[:, 2] + 1j * K[:, 3], K[:, 4], rms[kept])


# ---------------------------------------------------------------------- four-bars
#: a four-bar's parameters in a vector: crank pivot, crank body point, crank length, the same of the rocker
FB_DIM = 10


def fourbar_vector(d: Dyads, i: np.ndarray, j: np.ndarray) -> FloatArray:
    """Four-bar vectors (K, 10) ``[ga, a, ra, gb, b, rb]`` (complex as two reals), crank dyads ``i``, rockers ``j``."""
    return np.stack(
        [d.g[i].real, d.g[i].imag, d.c[i].real, d.c[i].imag, d.r[i], d.g[j].real, d.g[j].imag, d.c[j].real,
         d.c[j].imag, d.r[j]], axis=1,
    )  # fmt: skip


def frames(
    F: FloatArray, t: FloatArray, s: FloatArray, clip: bool = False
) -> tuple[ComplexArray, ComplexArray, FloatArray, FloatArray]:
    """The body frame ``(O, u)`` of four-bars ``F`` (K, 10) at crank angles ``t`` (K, n), mode ``s`` (K,).

    Also ``cos alpha`` (the coupler's angle at the crank tip; ``|.| > 1``: no assembly) and
    ``cos mu`` (the transmission angle at the rocker's tip). NaN where it does not assemble,
    unless ``clip`` (then ``alpha`` is clipped to ``[0, pi]``: a continuation the polish uses).
    """
    ga, a, ra = (F[:, 0] + 1j * F[:, 1])[:, None], (F[:, 2] + 1j * F[:, 3])[:, None], F[:, 4:5]
    gb, b, rb = (F[:, 5] + 1j * F[:, 6])[:, None], (F[:, 7] + 1j * F[:, 8])[:, None], F[:, 9:10]
    A = ga + ra * cis(t)
    e = gb - A
    dist = np.abs(e)
    ell = np.abs(b - a)
    cos_a = (ell**2 + dist**2 - rb**2) / (2 * ell * dist)
    cos_mu = (ell**2 + rb**2 - dist**2) / (2 * ell * rb)
    with np.errstate(invalid="ignore", divide="ignore"):
        alpha = np.arccos(np.clip(cos_a, -1.0, 1.0) if clip else cos_a)
        B = A + ell * (e / dist) * cis(s[:, None] * alpha)
        u = (B - A) / (b - a)
        u = u / np.abs(u)
    return A - u * a, u, cos_a, cos_mu


def pose_errors(
    p: MotionPoses, F: FloatArray, t: FloatArray, s: FloatArray, clip: bool = False
) -> tuple[FloatArray, FloatArray]:
    """Position errors (over the diagonal) and signed orientation errors (radians), (K, m) each."""
    org, u, _, _ = frames(F, t, s, clip)
    return np.abs(org - p.d), np.angle(u * np.conj(p.u))


def first_mode(p: MotionPoses, F: FloatArray) -> FloatArray:
    """The assembly mode (+1/-1) each four-bar's dyads give at the first pose."""
    a, b = F[:, 2] + 1j * F[:, 3], F[:, 7] + 1j * F[:, 8]
    A0, B0 = p.at(a[:, None])[:, 0], p.at(b[:, None])[:, 0]
    gb = F[:, 5] + 1j * F[:, 6]
    return np.where(np.imag(np.conj(gb - A0) * (B0 - A0)) >= 0, 1.0, -1.0)


def crank_angles(p: MotionPoses, F: FloatArray) -> FloatArray:
    """The crank's angle at every pose by its dyad (K, m), in order (:func:`in_order`); with timing by the first
    one and the inputs."""
    ga, a = F[:, 0] + 1j * F[:, 1], F[:, 2] + 1j * F[:, 3]
    t = np.angle(p.at(a[:, None]) - ga[:, None])
    if p.inputs is not None:
        timed: FloatArray = t[:, :1] + (p.inputs - p.inputs[0])
        return timed
    return in_order(t, p.closed)


def in_order(t: FloatArray, closed: bool) -> FloatArray:
    """Crank angles (K, m) met in order: ``t`` where they are (:func:`unwrap_turn`), else the nearest that are.

    Measured poses scatter: the best crank angles of two close poses may come a little out of
    order, and one step back makes the crank turn a whole turn more. Such a row's steps are
    taken as their least turns, the crank turns the way of their sum, and the angles become
    their L-infinity isotonic regression along it, ``(max_{j<=i} t_j + min_{j>=i} t_j) / 2``
    (no angle moves by more than half the largest drop ``max_{j<i} t_j - t_i``; poses met
    out of order share one angle); a closed motion's stay within the turn from the first
    pose (a hair short of it, so that the cycle back to the first is not read as a turn more).

    >>> np.degrees(in_order(np.radians([[10.0, 20, 19, 40]]), False)).round(6).tolist()
    [[10.0, 19.5, 19.5, 40.0]]
    """
    ordered = unwrap_turn(t, closed)[2]
    steps = np.angle(cis(np.diff(t, axis=1)))
    way = np.where(np.sum(steps, axis=1, keepdims=True) >= 0, 1.0, -1.0)
    v = way * (t[:, :1] + np.concatenate([np.zeros((len(t), 1)), np.cumsum(steps, axis=1)], axis=1))
    iso = (np.maximum.accumulate(v, axis=1) + np.minimum.accumulate(v[:, ::-1], axis=1)[:, ::-1]) / 2
    if closed:
        iso = np.clip(iso, v[:, :1], v[:, :1] + 2 * np.pi * (1 - 1e-12))
        iso[:, 0] = v[:, 0]
    out: FloatArray = np.where(ordered[:, None], t, way * iso)
    return out


def unwrap_turn(t: FloatArray, closed: bool) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``(direction, unwrapped t, ordered)``: the way the crank turns through ``t`` (K, m) in order, least turn.

    Open: in order within less than a turn; closed: the cycle back to the first is exactly one turn.
    """
    steps = np.diff(np.concatenate([t, t[:, :1]], axis=1) if closed else t, axis=1)
    ccw, cw = np.mod(steps, 2 * np.pi), np.mod(-steps, 2 * np.pi)
    sign = np.where(ccw.sum(axis=1) <= cw.sum(axis=1), 1.0, -1.0)
    inc = np.where(sign[:, None] > 0, ccw, cw)
    total = inc.sum(axis=1)
    ordered = np.abs(total - 2 * np.pi) < 1e-6 if closed else total < 2 * np.pi
    un = t[:, :1] + sign[:, None] * np.concatenate([np.zeros((len(t), 1)), np.cumsum(inc, axis=1)], axis=1)
    return sign, un[:, : t.shape[1]], ordered


@dataclass(frozen=True)
class Sweep:
    """The one-branch check of K four-bars: does each assemble all along its sweep; its smallest transmission angle."""

    assembled: np.ndarray
    min_transmission: FloatArray


def sweep_check(F: FloatArray, t: FloatArray, s: FloatArray, closed: bool) -> Sweep:
    """From the first pose's crank angle to the last's (a whole turn when closed), exactly: no sampling.

    The crank's sweep, met in order (:func:`unwrap_turn`), judged by :func:`~linkagekit.geometry.fourbar_sweep`:
    assembled all along iff the crank tip's least and greatest distance from the rocker's pivot over it are within
    the coupler-rocker triangle's limits, and the smallest transmission angle at one of them. In one assembly mode
    ``s`` there is no jump. Samples every 1/4 degree stepped over a gap of 0.06 degrees between two poses, and a
    four-bar that does not assemble there was written.

    >>> F = np.array([[0.0, 0, 0, 0, 1, 3, 0, 1, 0, 2.5]])  # crank 1, ground 3, coupler 1, rocker 2.5
    >>> sw = sweep_check(F, np.radians([[0.0, 60, 110]]), np.array([1.0]), False)  # d^2 = 10 - 6 cos t <= 3.5^2
    >>> bool(sw.assembled[0]), round(float(sw.min_transmission[0]), 6)
    (True, 16.173181)
    >>> bool(sweep_check(F, np.radians([[0.0, 60, 115]]), np.array([1.0]), False).assembled[0])  # past 112.02 deg
    False
    """
    _, un, ordered = unwrap_turn(t, closed)
    t0 = un[:, 0]
    t1 = t0 + np.where(un[:, -1] >= t0, 1, -1) * 2 * np.pi if closed else un[:, -1]
    ga, a, gb, b = (F[:, k] + 1j * F[:, k + 1] for k in (0, 2, 5, 7))
    ok, mu = fourbar_sweep(ga, F[:, 4], gb, np.abs(b - a), F[:, 9], t0, t1)  # a radius < 0 from the polish: |r|
    ok = np.logical_and(ok, ordered)
    return Sweep(ok, np.where(ok, mu, np.nan))


def combined(pos: FloatArray, ang: FloatArray, weight: float) -> FloatArray:
    """``E = max_i max(p_i, w |a_i|)`` per row (NaN -> inf)."""
    e = np.max(np.maximum(pos, weight * np.abs(ang)), axis=1)
    return np.where(np.isfinite(e), e, np.inf)


# ---------------------------------------------------------------------- minimax polish
def minimax_polish(
    p: MotionPoses,
    F: FloatArray,
    t: FloatArray,
    s: float,
    weight: float,
    iterations: int = 100,
    min_transmission: float = 0.0,
    deadline: float = math.inf,
    careful: bool = False,
) -> tuple[FloatArray, FloatArray]:
    """SLSQP on ``min tau`` s.t. ``p_i <= tau``, ``w |a_i| <= tau``: ``(F, t)`` polished.

    Also constrained at the poses' crank angles and half-way between them (``careful``: at points
    between them every :data:`BETWEEN_STEP` at most, :func:`between`): the four-bar assembles
    (``careful``: with a margin, ``cos^2 alpha <= 1 -`` :data:`ASSEMBLY_MARGIN`) and, when asked,
    ``cos^2 mu <= cos^2 min_transmission``.
    Without timing the crank angles stay in the order of the start ``t`` (unwrapped, in
    order): each step the way the crank turns, the whole within a turn; a step back within
    SLSQP's tolerance is undone (:func:`in_order`). Past ``deadline`` (``time.monotonic()``)
    it stops at its last iterate (the start if none).
    """
    m = p.m
    timed = p.inputs is not None
    k = 1 if timed else m
    sv = np.array([s])
    way = 1.0 if t[-1] >= t[0] else -1.0
    inner = between(t, BETWEEN_STEP if careful else np.inf)
    margin = ASSEMBLY_MARGIN if careful else 0.0

    def unpack(Z: FloatArray) -> tuple[FloatArray, FloatArray]:
        T = Z[:, FB_DIM : FB_DIM + k]
        if timed:
            assert p.inputs is not None
            T = T + (p.inputs - p.inputs[0])[None]
        return Z[:, :FB_DIM], T

    def cons(Z: FloatArray) -> FloatArray:
        Fz, T = unpack(Z)
        tau = Z[:, -1:]
        ss = np.broadcast_to(sv, (len(Z),))
        pos, ang = pose_errors(p, Fz, T, ss, clip=True)
        _, _, cos_a, cos_mu = frames(Fz, np.concatenate([T, T @ inner], axis=1), ss)
        parts = [tau**2 - pos**2, tau - weight * ang, tau + weight * ang, 1 - margin - cos_a**2]
        if not timed:  # the poses in order, within a turn
            parts += [way * np.diff(T, axis=1), 2 * np.pi - way * (T[:, -1:] - T[:, :1])]
        if min_transmission > 0:
            parts.append(np.cos(np.radians(min_transmission)) ** 2 - cos_mu**2)
        out = np.concatenate(parts, axis=1)
        return np.where(np.isfinite(out), out, -1.0)

    z0 = np.concatenate([F, t[:k], [_start_tau(p, F, t, sv, weight)]])
    jac = partial(_forward_jacobian, cons)
    Fz, T = unpack(_slsqp_epigraph(z0, lambda z: cons(z[None])[0], jac, iterations, deadline)[None])
    return Fz[0], T[0] if timed else in_order(T, p.closed)[0]  # a step back within SLSQP's tolerance undone


def _forward_jacobian(cons: Callable[[FloatArray], FloatArray], z: FloatArray) -> FloatArray:
    """The Jacobian of the batched constraints ``cons`` at ``z`` by forward differences, in one batch."""
    h = 1e-8
    Z = np.repeat(z[None], len(z) + 1, axis=0)
    Z[1:] += np.eye(len(z)) * h
    C = cons(Z)
    out: FloatArray = ((C[1:] - C[0]) / h).T
    return out


#: ``1 - cos^2 alpha`` the minimax polish keeps at least (``alpha`` off 0 and pi by about 0.06 deg): a polish
#: that ends on the constraint ends within SLSQP's tolerance of it, on either side; a pose 1.8e-8 past a dead
#: point failed the dense check, and a design 35 times worse was written in its place
ASSEMBLY_MARGIN = 1e-6
#: the crank's largest step (radians) between the points the polish constrains
BETWEEN_STEP = np.radians(5.0)


def between(t: FloatArray, step: float) -> FloatArray:
    """The matrix M (m, (m - 1) k) of ``k`` points evenly inside each step of crank angles ``T`` (.., m):
    ``T @ M``, with ``k`` such that none of the steps of ``t`` (m,) is cut coarser than ``step`` (one point,
    the midpoint, at least; at most 16). Between poses 30 deg apart the midpoints alone let the polish through
    a gap of 9 deg where the four-bar does not assemble (``--angle-weight 5`` on Hsieh's 9 poses).

    >>> (np.array([0.0, 12.0, 15.0]) @ between(np.radians([0.0, 12.0, 15.0]), np.radians(5.0))).round(9).tolist()
    [4.0, 8.0, 13.0, 14.0]
    """
    steps = np.abs(np.diff(t))
    k = int(np.clip(np.ceil(np.max(steps, initial=0.0) / step) - 1, 1, 16))
    f = np.arange(1, k + 1) / (k + 1)
    eye = np.eye(len(t))
    return np.kron(eye[:, :-1], 1 - f[None]) + np.kron(eye[:, 1:], f[None])


def _slsqp_epigraph(
    z0: FloatArray,
    cons: Callable[[FloatArray], FloatArray],
    jac: Callable[[FloatArray], FloatArray],
    iterations: int,
    deadline: float,
) -> FloatArray:
    """SLSQP on ``min z[-1]`` s.t. ``cons(z) >= 0`` from ``z0``; past ``deadline``, its last iterate (``z0`` if none).

    The clock is read before each step's constraint Jacobian, its costliest part.
    """
    from scipy.optimize import minimize

    def timed_jac(z: FloatArray) -> FloatArray:
        if time.monotonic() > deadline:
            raise _Late
        return jac(z)

    last = [z0]
    try:
        res = minimize(
            lambda z: z[-1],
            z0,
            jac=lambda z: np.eye(len(z))[-1],
            method="SLSQP",
            constraints=[{"type": "ineq", "fun": cons, "jac": timed_jac}],
            options={"maxiter": iterations, "ftol": 1e-12},
            callback=lambda z: last.append(np.array(z, float)),
        )
        last.append(np.asarray(res.x, float))
    except _Late:
        pass
    return last[-1]


class _Late(Exception):
    """The minimax polish's deadline has passed (raised inside SLSQP, caught by :func:`minimax_polish`)."""


def _start_tau(p: MotionPoses, F: FloatArray, t: FloatArray, sv: FloatArray, weight: float) -> float:
    """The minimax polish's start of ``tau``: just above the design's largest weighted error."""
    pos0, ang0 = pose_errors(p, F[None], t[None], sv, clip=True)
    return float(max(np.max(pos0), weight * np.max(np.abs(ang0)))) * 1.001


# ---------------------------------------------------------------------- the engine's objective
@dataclass(frozen=True, eq=False)
class MotionObjective(Objective):
    """Motion generation for the synthesis engine: both dyads' circle fits as one objective.

    Design vector (8): crank pivot ``g_a``, crank body point ``a``, rocker pivot ``g_b``,
    rocker body point ``b`` (normalised coordinates); each radius is the mean distance of its
    body point's positions from its pivot. The cost is the mean squared circle residual of
    both dyads (and the crank's timing residual); the check builds the four-bar and measures
    the true pose errors ``E`` on one branch (:func:`sweep_check`).
    """

    poses: MotionPoses
    weight: float = ANGLE_WEIGHT
    min_transmission: float = 0.0
    reach: float = 2.0
    _fp: str = field(default="", repr=False)

    @property
    def bounds(self) -> tuple[FloatArray, FloatArray]:
        r = self.reach
        return np.full(8, -r), np.full(8, r)

    def _dyads(self, X: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Dyad vectors (N, 5) of the crank and of the rocker, radii by the mean distance."""
        out = []
        for k in (0, 4):
            g, c = X[:, k] + 1j * X[:, k + 1], X[:, k + 2] + 1j * X[:, k + 3]
            r = np.mean(np.abs(self.poses.at(c[:, None]) - g[:, None]), axis=1)
            out.append(np.stack([c.real, c.imag, g.real, g.imag, r], axis=1))
        return out[0], out[1]

    def residuals(self, X: FloatArray) -> FloatArray:
        X = np.atleast_2d(X)
        Va, Vb = self._dyads(X)
        p = self.poses
        R = np.concatenate([_dyad_residuals(p, Va, True), _dyad_residuals(p, Vb, False)], axis=1)
        out: FloatArray = np.where(np.isfinite(R), R, 1.0) / np.sqrt(2 * p.m)
        return out

    def score(self, X: FloatArray) -> Score:
        R = self.residuals(X)
        cost = np.sum(R * R, axis=1)
        return Score(cost, np.max(np.abs(R), axis=1) * np.sqrt(2 * self.poses.m), np.zeros(len(R)))

    def fourbars(self, X: FloatArray) -> FloatArray:
        """Four-bar vectors (N, 10) of designs ``X``."""
        Va, Vb = self._dyads(np.atleast_2d(X))
        d = Dyads(
            np.concatenate([Va[:, 0] + 1j * Va[:, 1], Vb[:, 0] + 1j * Vb[:, 1]]),
            np.concatenate([Va[:, 2] + 1j * Va[:, 3], Vb[:, 2] + 1j * Vb[:, 3]]),
            np.concatenate([Va[:, 4], Vb[:, 4]]),
            np.zeros(2 * len(Va)),
        )
        n = len(Va)
        return fourbar_vector(d, np.arange(n), np.arange(n, 2 * n))

    def check(self, X: FloatArray) -> Score:
        """The four-bar of each design judged with either dyad as the crank (the better one counts)."""
        F = self.fourbars(X)
        swapped = np.concatenate([F[:, 5:], F[:, :5]], axis=1)
        a, b = (
            judge(self.poses, G, crank_angles(self.poses, G), first_mode(self.poses, G), self) for G in (F, swapped)
        )
        pick = (b.violation < a.violation) | ((b.violation == a.violation) & (b.error < a.error))
        return Score(*(np.where(pick, getattr(b, f), getattr(a, f)) for f in ("cost", "error", "violation")))

    def fingerprint(self) -> str:
        p = self.poses
        ins = p.inputs if p.inputs is not None else np.zeros(0)
        return digest(p.d, p.theta, ins, p.closed, self.weight, self.min_transmission, self.reach, "motion/1")


def judge(p: MotionPoses, F: FloatArray, t: FloatArray, s: FloatArray, o: MotionObjective) -> Score:
    """Four-bars ``F`` at crank angles ``t``, modes ``s``: ``E``, and the dense check's violation."""
    pos, ang = pose_errors(p, F, t, s)
    e = combined(pos, ang, o.weight)
    sw = sweep_check(F, t, s, p.closed)
    bad = ~sw.assembled | ~np.isfinite(e) | (np.nan_to_num(sw.min_transmission, nan=0.0) < o.min_transmission)
    return Score(e * e, e, bad.astype(float))


# ---------------------------------------------------------------------- the whole route
@dataclass(frozen=True)
class MotionDesign:
    """One four-bar found for the poses (lengths and angles in the poses' units, radians).

    Attributes
    ----------
    vector : ndarray (10,)
        ``[ga, a, ra, gb, b, rb]`` in the poses' unit (pivots in the plane, body points in the
        body frame).
    inputs : ndarray (m,)
        The crank angle at each pose (radians), unwrapped in the turning direction.
    mode : float
        The assembly mode (+1 or -1: the side of the crank-tip-to-rocker-pivot line the rocker's tip is on).
    position_errors : ndarray (m,)
        ``|P - (x, y)|`` at each pose (poses' unit).
    angle_errors : ndarray (m,)
        Orientation error at each pose (radians, signed).
    one_branch : bool
        The poses are met in order on one branch (:func:`sweep_check`).
    min_transmission : float
        Smallest transmission angle over the sweep (degrees).
    """

    vector: FloatArray
    inputs: FloatArray
    mode: float
    position_errors: FloatArray
    angle_errors: FloatArray
    one_branch: bool
    min_transmission: float


def design(p: MotionPoses, F: FloatArray, t: FloatArray, s: float) -> MotionDesign:
    """A four-bar (normalised ``F``, angles ``t``) as a :class:`MotionDesign` in the poses' units."""
    pos, ang = pose_errors(p, F[None], t[None], np.array([s]))
    sw = sweep_check(F[None], t[None], np.array([s]), p.closed)
    _, un, _ = unwrap_turn(t[None], p.closed)
    v = F.copy()
    v[[0, 1, 5, 6]] = v[[0, 1, 5, 6]] * p.scale + np.array([p.center.real, p.center.imag] * 2)
    v[[2, 3, 4, 7, 8, 9]] *= p.scale
    return MotionDesign(v, un[0], s, pos[0] * p.scale, ang[0], bool(sw.assembled[0]), float(sw.min_transmission[0]))


#: the approximate route at a weight other than :data:`ANGLE_WEIGHT` also runs at the weights this many times
#: apart from it on the way to the weight asked (and one beyond), each passing its best four-bars on
#: (:func:`weight_ladder`): the minimax polish ends at a local optimum, and on Hsieh's 9 poses the answer at
#: ``--angle-weight 5`` (E = 0.0597) was nine times worse than the weight-2 answer judged at weight 5 (0.0068)
WEIGHT_STEP = 4.0
#: four-bars polished at each weight of the ladder before the last (every four-bar found is a candidate after it)
CARRIED = 2


def weight_ladder(weight: float) -> list[float]:
    """The weights the approximate route runs at, the asked ``weight`` last: ``ANGLE_WEIGHT * WEIGHT_STEP^k`` from
    :data:`ANGLE_WEIGHT` (``k = 0``) the way to ``weight``, up to the first one beyond it. Every weight's ladder
    runs over the same weights, so that two weights' answers come from the same four-bars found on the way.

    >>> [round(w, 4) for w in weight_ladder(5.0)], [round(w, 4) for w in weight_ladder(2.0)]
    ([0.05, 0.2, 0.8, 3.2, 12.8, 5.0], [0.05, 0.2, 0.8, 3.2, 2.0])
    >>> weight_ladder(ANGLE_WEIGHT), [round(w, 4) for w in weight_ladder(0.01)]
    ([0.05], [0.05, 0.0125, 0.0031, 0.01])
    """
    if weight == ANGLE_WEIGHT:
        return [weight]
    way = 1 if weight > ANGLE_WEIGHT else -1
    beyond = math.floor(way * math.log(weight / ANGLE_WEIGHT) / math.log(WEIGHT_STEP) + 1e-9) + 1
    return [ANGLE_WEIGHT * WEIGHT_STEP ** (way * k) for k in range(beyond + 1)] + [weight]


def approximate(
    p: MotionPoses,
    weight: float = ANGLE_WEIGHT,
    min_transmission: float = 0.0,
    seeds: FloatArray | None = None,
    deadline: float = math.inf,
) -> list[MotionDesign]:
    """Four-bars for the poses by the route of the module's description, best first (one branch each).

    ``seeds``: four-bar vectors (k, 10), normalised (e.g. the engine's best), tried as well.
    At a weight other than :data:`ANGLE_WEIGHT` the route runs at every weight of :func:`weight_ladder`, each
    trying the four-bars found at the weights before at their own crank angles: the answer is never worse, at
    ``weight``, than one found on the way. ``deadline`` (``time.monotonic()``): shared evenly by the weights left;
    past it, a polish under way stops at its last iterate and no more four-bars are polished once one is found
    (until then, the starts are judged as they are).
    """
    F = _circle_fit_fourbars(p)
    if seeds is not None:
        F = np.concatenate([F, seeds])
    t, s = crank_angles(p, F), first_mode(p, F)
    pool: list[tuple[float, FloatArray, FloatArray, float]] = []  # the four-bars found on the way
    ladder = weight_ladder(weight)
    for k, w in enumerate(ladder):
        left = deadline - time.monotonic()
        share = deadline if not math.isfinite(left) else time.monotonic() + max(left, 0.0) / (len(ladder) - k)
        Fc = np.concatenate([F, *(f[1][None] for f in pool)])
        tc = np.concatenate([t, *(f[2][None] for f in pool)])
        sc = np.concatenate([s, [f[3] for f in pool]])
        full = k in (0, len(ladder) - 1)  # the default weight's route, and the asked one's
        found = _route(p, MotionObjective(p, w, min_transmission), Fc, tc, sc, share, POLISHED if full else CARRIED)
        pool += [f for f in found if np.isfinite(f[0])]
    return [design(p, Fk, tk, sk) for _, Fk, tk, sk in found]


def _circle_fit_fourbars(p: MotionPoses) -> FloatArray:
    """Every ordered pair of distinct dyads of the circle fits (:func:`search_dyads`) as four-bar vectors (K, 10)."""
    crank = search_dyads(p, timed=p.inputs is not None)
    rocker = search_dyads(p) if p.inputs is not None else crank
    both = Dyads(*(np.concatenate([getattr(crank, f), getattr(rocker, f)]) for f in ("c", "g", "r", "rms")))
    nc = len(crank.c)
    i, j = np.meshgrid(np.arange(nc), np.arange(nc, len(both.c)), indexing="ij")
    keep = (i.ravel() != j.ravel() - nc) | (p.inputs is not None)
    return fourbar_vector(both, i.ravel()[keep], j.ravel()[keep])


def _route(
    p: MotionPoses,
    o: MotionObjective,
    F: FloatArray,
    t: FloatArray,
    s: FloatArray,
    deadline: float,
    polished: int = POLISHED,
) -> list[tuple[float, FloatArray, FloatArray, float]]:
    """``[(E, F, t, s)]`` best first at ``o``'s weight: the candidates ``F`` at crank angles ``t``, modes ``s``,
    judged, the best ``polished`` polished (steps 2-4 of the route)."""
    score = judge(p, F, t, s, o)
    pos, ang = pose_errors(p, F, t, s, clip=True)
    start = combined(pos, ang, o.weight)
    order = np.lexsort((start, score.violation > 0))  # in order on one branch first
    found: list[tuple[float, FloatArray, FloatArray, float]] = []
    for k in order[: 2 * polished]:
        best = min((f[0] for f in found), default=np.inf)
        if best <= EXACT or len(found) >= polished or (found and time.monotonic() > deadline):
            break
        if start[k] <= HOPELESS * best:  # one far worse than a polished one is seldom worth its time
            valid = score.error[k] if score.violation[k] == 0 else None
            found += _polished(p, o, F[k], t[k], float(s[k]), valid, deadline)
    found.sort(key=lambda f: f[0])
    return found


def _polished(
    p: MotionPoses,
    o: MotionObjective,
    F: FloatArray,
    t: FloatArray,
    s: float,
    error: float | None,
    deadline: float = math.inf,
) -> list[tuple[float, FloatArray, FloatArray, float]]:
    """``[(E, F, t, s)]`` of a four-bar after the minimax polish, or as it was (``error``: its E if valid), or none.

    A polish that fails the dense check is done again with a margin from the dead points and points between the
    poses every :data:`BETWEEN_STEP` at most (:func:`minimax_polish`'s ``careful``): SLSQP ends on an active
    constraint within its tolerance, on either side of it. Only then: the margin costs accuracy where the first
    polish passed (Hsieh's 9 poses with ``--angle-weight 2``: 0.0122 with it, 0.0025 without).
    """
    _, un, _ = unwrap_turn(t[None], p.closed)
    start = (F, un[0])
    if error is not None and error <= EXACT:
        return [(error, *start, s)]
    for careful in (False, True):
        Fk, tk = minimax_polish(
            p, F, un[0], s, o.weight, min_transmission=o.min_transmission, deadline=deadline, careful=careful
        )
        polished = judge(p, Fk[None], tk[None], np.array([s]), o)
        if polished.violation[0] == 0 and (error is None or polished.error[0] <= error):
            return [(float(polished.error[0]), Fk, tk, s)]
        if time.monotonic() > deadline:
            break
    return [] if error is None else [(error, *start, s)]


def mechanism(p: MotionPoses, d: MotionDesign, unit: str = "m", name: str = "motion four-bar") -> Mechanism:
    """The four-bar at the first pose as a mechanism: joints ``A0, A1, B1, B0, P, Q``, driver ``crank``.

    ``P`` is the body frame's origin (the pose point), ``Q`` a tenth of the poses' diagonal
    along the body's line; the crank sweeps from the first pose's angle to the last one's.
    """
    v = d.vector
    ga, a, ra, gb, b, rb = v[0] + 1j * v[1], v[2] + 1j * v[3], v[4], v[5] + 1j * v[6], v[7] + 1j * v[8], v[9]
    F = np.array([[ga.real, ga.imag, a.real, a.imag, ra, gb.real, gb.imag, b.real, b.imag, rb]])
    t0 = d.inputs[:1][None]
    org, u, _, _ = frames(F, t0, np.array([d.mode]), clip=True)  # flat to rounding in the poses' units: as analyze
    O0, u0 = complex(org[0, 0]), complex(u[0, 0])
    z = [ga, ga + ra * cis(float(t0[0, 0])), O0 + u0 * b, gb, O0, O0 + u0 * 0.1 * p.scale]
    start = float(np.degrees(d.inputs[0]))
    stop = start + (360.0 if p.closed else float(np.degrees(d.inputs[-1])) - start) * (
        1 if not p.closed or d.inputs[-1] >= d.inputs[0] else -1
    )
    return guided_fourbar(z, start, stop, unit, name, "<motion synthesis>")


def guided_fourbar(z: Sequence[complex], start: float, stop: float, unit: str, name: str, source: str) -> Mechanism:
    """The four-bar a motion synthesis writes: joints ``A0, A1, B1, B0, P, Q`` (``z``, complex), its coupler
    carrying ``P`` and ``Q`` (docs/commands.md), the crank sweeping from ``start`` to ``stop`` (degrees, steps of
    at most 1 degree)."""
    from ..model import Mechanism as _Mechanism

    steps = max(1, math.ceil(abs(stop - start) - 1e-9))
    step = (stop - start) / steps if stop != start else 1.0
    doc = {
        "format": "linkagekit/1",
        "name": name,
        "units": {"length": unit, "angle": "deg"},
        "joints": {j: [float(w.real), float(w.imag)] for j, w in zip(JOINTS, z, strict=True)},
        "links": {
            "ground": ["A0", "B0"],
            "crank": ["A0", "A1"],
            "coupler": ["A1", "B1", "P", "Q"],
            "rocker": ["B0", "B1"],
        },
        "drivers": [
            {"link": "crank", "pivot": "A0", "toward": "A1", "angles": {"start": start, "stop": stop, "step": step}}
        ],
    }
    return _Mechanism.from_dict(doc, source)
