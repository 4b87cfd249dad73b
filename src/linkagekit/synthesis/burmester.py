r"""Exact motion generation by Burmester theory: four-bars whose coupler meets 3, 4 or 5 poses.

A pose ``j`` of the moving body is a point ``d_j = x_j + i y_j`` of the body and the direction
``theta_j`` (radians) of a line of the body.  A point of the body with coordinates ``w`` in the
body's frame (origin at the pose point, first axis along the line) is in the plane at
``W_j = d_j + e^{i theta_j} w``.  A dyad is a ground pivot ``c`` (the *center point*) and a
body point ``w`` (the *circle point*) whose positions ``W_j`` lie on one circle about ``c``.
Two dyads make a four-bar whose coupler (the body) meets every pose.  The derivation is in
``docs/method.md`` ("Motion generation: Burmester theory"):

* 3 poses: every body point is a circle point (its center point is the circumcentre of its
  three positions), and every ground point a center point: :func:`dyad_from_circle_point`,
  :func:`dyad_from_center`.
* 4 poses: the center points lie on a cubic, the *center-point curve* ``f_{0123}(c) = 0``, and
  their circle points on the circle-point curve: :func:`center_point_curve` samples both.
* 5 poses: the center points common to the curves of poses ``abcd`` and ``abce`` (usually
  0123 and 0124), without the poles ``Pab, Pac, Pbc`` that both curves pass through: up to
  four real *Burmester points*
  (:func:`burmester_points`), so up to six four-bars.

:func:`exact_motion` returns four-bars for 3, 4 or 5 poses, each checked by
:func:`linkagekit.analyze` (an independent computation): its Grashof type, whether it meets
the poses in order on one branch, and its residual.

Examples
--------
>>> import numpy as np
>>> x, y = [0.0, 1.0, 2.0, 2.6, 3.0], [0.0, 0.6, 0.8, 0.5, 0.0]
>>> angle = np.radians([0.0, -15.0, -35.0, -60.0, -80.0])
>>> fbs = exact_motion((x, y, angle))  # every real Burmester pair, best first
>>> len(fbs) >= 1, max(fb.position_error for fb in fbs) < 1e-9
(True, True)
>>> fbs[0].mechanism(unit="mm").joint_names
('A0', 'A1', 'B1', 'B0', 'P', 'Q')
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from itertools import combinations, permutations

import numpy as np
from numpy.polynomial import polynomial as npoly

from ..api import analyze, prepare
from ..checks import FourBar, grashof
from ..errors import InputError, MethodNotApplicableError
from ..geometry import ArrayLike, BoolArray, ComplexArray, FloatArray, IntArray, cis, cross, fourbar_sweep
from ..model import Mechanism
from .motion import JOINTS as motion_joints
from .motion import guided_fourbar

#: two poses closer than this (relative to the poses' size, and in radians) are one pose
SAME_POSE = 1e-9
#: Burmester dyads with a pivot farther than this many pose sizes from the poses are left out:
#: such a dyad is a slider for any practical purpose, and its four-bar's joints are too far out
#: for its residual at the poses to stay within 1e-9 of their size (2e-9 at 10^3 sizes, 1e-7 at 10^4)
FAR = 1e2
#: a dyad is kept when its circle point's positions are on one circle to this much of its size
MISFIT = 1e-10
#: joint names of the written four-bar, in the order of :meth:`BurmesterFourBar.pose_array`
JOINTS = motion_joints  # the written four-bar's joints (motion.JOINTS)


# ---------------------------------------------------------------------- poses
@dataclass(frozen=True)
class Poses:
    """Checked poses of a moving body.

    Attributes
    ----------
    d : ndarray, complex, shape (n,)
        The body's point at each pose.
    theta : ndarray, shape (n,)
        The direction of the body's line at each pose (radians).
    size : float
        The largest distance between two pose points (1 when they all coincide): the scale
        of the tolerances.
    """

    d: ComplexArray
    theta: FloatArray
    size: float

    @property
    def n(self) -> int:
        """The number of poses."""
        return int(self.d.shape[0])

    @property
    def rot(self) -> ComplexArray:
        """``e^{i theta_j}``: the body's frame at each pose."""
        return cis(self.theta)

    def place(self, w: ArrayLike) -> ComplexArray:
        """Positions ``(..., n)`` of body points ``w`` (body frame, shape ``(...)``) at every pose."""
        out: ComplexArray = self.d + self.rot * np.asarray(w, complex)[..., None]
        return out

    def body(self, p: ArrayLike, j: int = 0) -> ComplexArray:
        """Body-frame coordinates of the points ``p`` (plane) at pose ``j``."""
        out: ComplexArray = (np.asarray(p, complex) - self.d[j]) / self.rot[j]
        return out

    def seen_from_body(self, c: ArrayLike) -> ComplexArray:
        """``z_j = e^{-i theta_j}(c - d_j)``: where the fixed points ``c`` are in the body's frame, ``(..., n)``."""
        return (np.asarray(c, complex)[..., None] - self.d) / self.rot


def motion_poses(x: ArrayLike, y: ArrayLike, angle: ArrayLike) -> Poses:
    """Check poses given as arrays ``x``, ``y``, ``angle`` (radians) and make :class:`Poses`.

    Raises
    ------
    InputError
        Arrays of different lengths or not 1-D, fewer than 3 poses, a value that is not a
        finite number, two poses at one spot with one angle, or all pose points at one spot
        (a pure rotation about it, where every point is a center point).
    """
    arrs = []
    for name, v in (("x", x), ("y", y), ("angle", angle)):
        try:
            a = np.asarray(v, dtype=float)
        except (TypeError, ValueError):
            raise InputError(f"poses: {name} must be numbers") from None
        if a.ndim != 1:
            raise InputError(f"poses: {name} must be a 1-D array, got shape {a.shape}")
        if not np.all(np.isfinite(a)):
            raise InputError(f"poses: {name}[{int(np.argmin(np.isfinite(a)))}] is not a finite number")
        arrs.append(a)
    if len({a.shape[0] for a in arrs}) != 1:
        raise InputError(f"poses: x, y and angle have different lengths {[a.shape[0] for a in arrs]}")
    if arrs[0].shape[0] < 3:
        raise InputError(f"poses: motion generation needs at least 3 poses, got {arrs[0].shape[0]}")
    d = arrs[0] + 1j * arrs[1]
    spread = float(np.max(np.abs(d[:, None] - d[None, :])))
    size = spread if spread > 0 else 1.0
    _check_distinct(d, arrs[2], size)
    if spread <= SAME_POSE * max(1.0, float(np.max(np.abs(d)))):
        raise InputError("poses: every pose has its point at one spot: a rotation about it, no four-bar to find")
    return Poses(d, arrs[2], size)


def _check_distinct(d: ComplexArray, theta: FloatArray, size: float) -> None:
    """Raise on the first two poses with one point and one angle."""
    near = np.abs(d[:, None] - d[None, :]) <= SAME_POSE * size
    turn = np.abs(np.angle(cis(theta[:, None] - theta[None, :]))) <= SAME_POSE
    same = np.triu(near & turn, 1)
    if same.any():
        a, b = (int(i) for i in np.argwhere(same)[0])
        raise InputError(f"poses: poses {a + 1} and {b + 1} coincide (the same point and angle)")


def _as_poses(poses: Poses | Sequence[ArrayLike]) -> Poses:
    return poses if isinstance(poses, Poses) else motion_poses(*poses)


def _exact(poses: Poses, counts: tuple[int, ...], what: str) -> None:
    if poses.n not in counts:
        want = (
            " or ".join([", ".join(str(c) for c in counts[:-1]), str(counts[-1])])
            if len(counts) > 1
            else str(counts[0])
        )
        raise InputError(f"poses: {what} takes {want} poses, got {poses.n}")


# ---------------------------------------------------------------------- dyads
@dataclass(frozen=True)
class Dyad:
    """A ground pivot and the moving pivot that turns about it.

    Attributes
    ----------
    ground : complex
        The ground pivot (center point).
    moving : complex
        The moving pivot (circle point) where it is at the first pose.
    """

    ground: complex
    moving: complex

    @property
    def length(self) -> float:
        """The link's length ``|moving - ground|``."""
        return float(abs(self.moving - self.ground))


def _circle_fit(points: ComplexArray) -> tuple[ComplexArray, FloatArray]:
    """Centres ``(...)`` of the circles through points ``(..., n)`` (least squares) and the largest radial misfit.

    ``|p - c|^2 = r^2`` is linear in ``(c, k = r^2 - |c|^2)``: ``2 p.c + k = |p|^2``.  The points
    are taken relative to their mean first (conditioning).
    """
    mean = points.mean(axis=-1, keepdims=True)
    p = points - mean
    a = np.stack([2 * p.real, 2 * p.imag, np.ones(p.shape)], axis=-1)
    b = (np.abs(p) ** 2)[..., None]
    sol = np.linalg.pinv(a) @ b
    centre = sol[..., 0, 0] + 1j * sol[..., 1, 0]
    radius = np.sqrt(np.maximum(sol[..., 2, 0] + np.abs(centre) ** 2, 0.0))
    misfit = np.max(np.abs(np.abs(p - centre[..., None]) - radius[..., None]), axis=-1)
    return centre + mean[..., 0], misfit


def dyad_from_center(poses: Poses | Sequence[ArrayLike], center: complex) -> Dyad:
    """The dyad of ground pivot ``center``: its circle point is the centre of the circle through ``z_j``.

    Exact for 3 poses (any ``center``); for 4 or 5 poses ``center`` must be a center point
    (on the center-point curve, or a Burmester point), and the circle is the least-squares one.

    >>> p = motion_poses([0.0, 1.0, 2.0], [0.0, 1.0, 1.0], [0.0, 0.5, 1.0])
    >>> dy = dyad_from_center(p, 0.5 - 1.0j)
    >>> r = np.abs(p.place(p.body(dy.moving)) - dy.ground)
    >>> float(np.ptp(r)) < 1e-12
    True
    """
    p = _as_poses(poses)
    w, _ = _circle_fit(p.seen_from_body(center))
    return Dyad(complex(center), complex(p.place(w)[0]))


def dyad_from_circle_point(poses: Poses | Sequence[ArrayLike], circle_point: complex) -> Dyad:
    """The dyad whose moving pivot is ``circle_point`` (plane, first pose): 3 poses, its center is the circumcentre."""
    p = _as_poses(poses)
    _exact(p, (3,), "a dyad from its circle point")
    c, _ = _circle_fit(p.place(p.body(circle_point)))
    return Dyad(complex(c), complex(circle_point))


# ---------------------------------------------------------------------- the center-point cubic
def _affine(c0: complex, cx: complex) -> tuple[FloatArray, FloatArray]:
    """Real and imaginary parts of ``c0 + cx * (x + i y)`` as bivariate coefficient arrays ``[i, j]`` of ``x^i y^j``."""
    re = np.array([[c0.real, -cx.imag], [cx.real, 0.0]])
    im = np.array([[c0.imag, cx.real], [cx.imag, 0.0]])
    return re, im


def _mul(a: FloatArray, b: FloatArray) -> FloatArray:
    """Product of two bivariate polynomials (coefficient arrays ``[i, j]`` of ``x^i y^j``)."""
    out = np.zeros((a.shape[0] + b.shape[0] - 1, a.shape[1] + b.shape[1] - 1))
    for (i, j), v in np.ndenumerate(a):
        out[i : i + b.shape[0], j : j + b.shape[1]] += v * b
    return out


def center_cubic(d: ComplexArray, theta: FloatArray, k: Sequence[int]) -> FloatArray:
    r"""Coefficients ``F[i, j]`` of ``x^i y^j`` of the center-point cubic of the four poses ``k``.

    ``f(c) = det [ 2 Re(z_j - z_0), 2 Im(z_j - z_0), |c - d_j|^2 - |c - d_0|^2 ]_{j = k1, k2, k3}``
    with ``z_j = e^{-i theta_j}(c - d_j)`` (``k0`` in place of 0): zero exactly where the
    four ``z_j`` lie on one circle (or on a line), i.e. where ``c`` is a center point.
    """
    e = np.exp(-1j * theta[list(k)])
    dk = d[list(k)]
    rows = []
    for j in (1, 2, 3):
        re, im = _affine(2 * (e[0] * dk[0] - e[j] * dk[j]), 2 * (e[j] - e[0]))
        dd = dk[j] - dk[0]
        quad = np.array([[abs(dk[j]) ** 2 - abs(dk[0]) ** 2, -2 * dd.imag], [-2 * dd.real, 0.0]])
        rows.append((re, im, quad))
    out = np.zeros((4, 4))
    for perm in permutations(range(3)):
        sign = np.linalg.det(np.eye(3)[list(perm)])
        term = _mul(_mul(rows[0][perm[0]], rows[1][perm[1]]), rows[2][perm[2]])
        out[: term.shape[0], : term.shape[1]] += sign * term
    return out


def _eval(f: FloatArray, c: ArrayLike) -> FloatArray:
    c = np.asarray(c, complex)
    return np.asarray(npoly.polyval2d(c.real, c.imag, f), float)


@dataclass(frozen=True)
class _Frame:
    """A similarity frame ``c = origin + scale * c~`` in which the poses are of size about 1.

    The frame is also turned by ``TURN`` so that no two intersection points of a resultant
    in ``x`` share their ``x`` for any reason of the poses' own symmetry.
    """

    origin: complex
    scale: complex

    TURN = 0.6180339887

    @classmethod
    def of(cls, p: Poses) -> _Frame:
        return cls(complex(p.d.mean()), p.size * complex(cis(cls.TURN)))

    def poses(self, p: Poses) -> tuple[ComplexArray, FloatArray]:
        """The pose points and angles in this frame."""
        return (p.d - self.origin) / self.scale, p.theta - float(np.angle(self.scale))

    def to_plane(self, c: ArrayLike) -> ComplexArray:
        return self.origin + self.scale * np.asarray(c, complex)

    def from_plane(self, c: ArrayLike) -> ComplexArray:
        return (np.asarray(c, complex) - self.origin) / self.scale

    def cubic(self, p: Poses, k: Sequence[int]) -> FloatArray:
        """The center-point cubic of poses ``k`` in this frame, scaled to a largest coefficient of 1."""
        f = center_cubic(*self.poses(p), k)
        top = float(np.max(np.abs(f)))
        if not top > 0:
            raise MethodNotApplicableError(
                f"poses {[i + 1 for i in k]}: every point is a center point (degenerate poses)"
            )
        return f / top


def poles(poses: Poses | Sequence[ArrayLike], pairs: Sequence[tuple[int, int]]) -> ComplexArray:
    """The displacement poles ``P_ab``: the plane point the body occupies at poses ``a`` and ``b`` (inf: a translation).

    >>> p = motion_poses([1.0, 0.0, -1.0], [0.0, 1.0, 0.0], np.radians([0.0, 90.0, 180.0]))
    >>> bool(abs(poles(p, [(0, 1)])[0]) < 1e-12)  # turning 90 degrees about the origin
    True
    """
    p = _as_poses(poses)
    a, b = np.array(pairs).T
    ea, eb = 1 / p.rot[a], 1 / p.rot[b]
    with np.errstate(divide="ignore", invalid="ignore"):
        out = (ea * p.d[a] - eb * p.d[b]) / (ea - eb)
    return np.where(np.abs(ea - eb) > SAME_POSE, out, complex(np.inf))


# ---------------------------------------------------------------------- 4 poses: the curves
@dataclass(frozen=True)
class CenterPointCurve:
    """Samples of the center-point and circle-point curves of 4 poses.

    Every line through a pole (``P01``, or the first pole at a finite place; every pole is on
    the cubic) meets the curve in at most two more points: the roots of a quadratic.  Sample
    ``k`` is the line at angle ``slope[k]``.

    Attributes
    ----------
    center : ndarray, complex, shape (2, samples)
        Center points (ground pivots), NaN where the line meets the curve in no real point.
    circle : ndarray, complex, shape (2, samples)
        The matching circle points (moving pivots at the first pose), NaN likewise.
    slope : ndarray, shape (samples,)
        The direction of each line through the pole, in ``[0, pi)``.
    pole : complex
        The pole the lines pass through (on the curve; not a sample itself).
    """

    center: ComplexArray
    circle: ComplexArray
    slope: FloatArray
    pole: complex

    def dyads(self) -> list[Dyad]:
        """Every real sample as a :class:`Dyad`."""
        ok = np.isfinite(self.center) & np.isfinite(self.circle)
        return [Dyad(complex(c), complex(w)) for c, w in zip(self.center[ok], self.circle[ok], strict=True)]


def center_point_curve(poses: Poses | Sequence[ArrayLike], samples: int = 360) -> CenterPointCurve:
    """Sample the center-point curve of 4 poses and the circle point of every sample.

    >>> x, y = [0.0, 1.0, 2.0, 2.5], [0.0, 0.5, 0.6, 0.2]
    >>> cur = center_point_curve((x, y, np.radians([0.0, -20.0, -45.0, -70.0])), samples=90)
    >>> dy = cur.dyads()[10]
    >>> p = motion_poses(x, y, np.radians([0.0, -20.0, -45.0, -70.0]))
    >>> float(np.ptp(np.abs(p.place(p.body(dy.moving)) - dy.ground))) < 1e-9
    True
    """
    p = _as_poses(poses)
    _exact(p, (4,), "the center-point curve")
    fr = _Frame.of(p)
    f = fr.cubic(p, (0, 1, 2, 3))
    pole = _curve_pole(p, fr)
    t = np.pi * np.arange(samples) / samples
    s = _line_roots(f, pole, cis(t))
    center = fr.to_plane(pole + s * cis(t))
    circle = np.full(center.shape, np.nan + 0j)
    ok = np.isfinite(center) & (np.abs(s) < FAR)
    if ok.any():
        w, _ = _circle_fit(p.seen_from_body(center[ok]))
        circle[ok] = p.place(w)[:, 0]
    center[~ok] = np.nan
    return CenterPointCurve(center, circle, t, complex(fr.to_plane(pole)))


def _curve_pole(p: Poses, fr: _Frame) -> complex:
    """The pole the sampling lines of the 4-pose curve pass through (frame coordinates): ``P01`` or the first finite."""
    every = fr.from_plane(poles(p, [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)]))
    finite = every[np.isfinite(every)]  # a pole is at infinity when two poses differ by a translation
    if finite.size == 0:
        raise MethodNotApplicableError("poses: all four at one angle (translations only): no center-point curve")
    return complex(finite[0])


def nearest_dyad(poses: Poses | Sequence[ArrayLike], point: complex) -> Dyad:
    """The dyad whose ground pivot is a center point near ``point``: for picking dyads off a plot.

    3 poses: ``point`` itself.  4 poses: where the line from the curve's pole through
    ``point`` meets the center-point curve nearest to it.  5 poses: the nearest Burmester point.

    Raises
    ------
    InputError
        4 poses, when that line meets the curve at no real point; 5 poses, when there is no
        real Burmester point.
    """
    p = _as_poses(poses)
    _exact(p, (3, 4, 5), "a dyad near a point")
    if p.n == 3:
        return dyad_from_center(p, point)
    if p.n == 5:
        dyads = burmester_points(p)
        if not dyads:
            raise InputError("poses: these 5 poses have no real Burmester point")
        return min(dyads, key=lambda dy: abs(dy.ground - point))
    fr = _Frame.of(p)
    pole = _curve_pole(p, fr)
    here = complex(fr.from_plane(point))
    u = complex(cis(np.angle(here - pole))) if here != pole else 1.0 + 0j
    s = _line_roots(fr.cubic(p, (0, 1, 2, 3)), pole, np.array([u]))[:, 0]
    s = s[np.isfinite(s)]
    if s.size == 0:
        raise InputError(
            f"({point.real:g}, {point.imag:g}): the line from the pole through it misses the center-point curve"
        )
    best = s[np.argmin(np.abs(pole + s * u - here))]
    return dyad_from_center(p, complex(fr.to_plane(pole + best * u)))


def _line_roots(f: FloatArray, pole: complex, u: ComplexArray) -> ComplexArray:
    """The other two roots ``s`` (2, m) of ``f(pole + s u) = a1 s + a2 s^2 + a3 s^3`` for each ``u`` (NaN: none)."""
    v = {s: _eval(f, pole + s * u) for s in (-1.0, 1.0, 2.0)}
    a2 = (v[1.0] + v[-1.0]) / 2
    odd = (v[1.0] - v[-1.0]) / 2
    a3 = (v[2.0] - 4 * a2 - 2 * odd) / 6
    a1 = odd - a3
    disc = a2**2 - 4 * a1 * a3
    root = np.sqrt(np.where(disc >= 0, disc, np.nan))
    q = -(a2 + np.copysign(root, a2)) / 2
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.stack([q / a3, a1 / q])
    return np.where(np.isfinite(out), out, np.nan).astype(complex)


# ---------------------------------------------------------------------- 5 poses: Burmester points
def burmester_points(poses: Poses | Sequence[ArrayLike]) -> list[Dyad]:
    """Every real Burmester point pair of 5 poses: the dyads whose circle point meets all five.

    The center points common to the center-point cubics of poses ``abcd`` and ``abce``, where
    ``a, b, c`` are the three poses whose angles lie farthest apart (usually 0, 1, 2 and 3, 4
    the others): the real roots of their resultant in ``x`` (degree 7 = 9 intersections less
    the two circular points at infinity, divided by the poles ``Pab, Pac, Pbc`` that are on
    both curves) give ``x``, the cubics' roots in ``y`` give starts, and Newton's method on
    the dyads' own equations (:func:`_dyad_newton`, where a pole is no solution) ends at the
    dyads; every dyad kept has its five circle positions on one circle, and both pivots
    within :data:`FAR` sizes of the poses.

    >>> x, y = [0.0, 1.0, 2.0, 2.6, 3.0], [0.0, 0.6, 0.8, 0.5, 0.0]
    >>> dyads = burmester_points((x, y, np.radians([0.0, -15.0, -35.0, -60.0, -80.0])))
    >>> len(dyads) in (0, 2, 4)
    True
    """
    p = _as_poses(poses)
    _exact(p, (5,), "Burmester points")
    fr = _Frame.of(p)
    k0, k1, k2, r1, r2 = _shared_three(p.theta)
    f, g = fr.cubic(p, (k0, k1, k2, r1)), fr.cubic(p, (k0, k1, k2, r2))
    spurious = fr.from_plane(poles(p, [(k0, k1), (k0, k2), (k1, k2)]))
    spurious = spurious[np.isfinite(spurious)]  # a pole at infinity (a translation) is no point of the plane
    starts = _starts(f, g, spurious)
    starts = np.concatenate([starts, _polish(f, g, starts)])
    ground, moving = _dyad_newton(p, fr.to_plane(starts[np.abs(starts) < FAR]))
    out: list[Dyad] = []
    for c, w in zip(ground, moving, strict=True):
        reach = max(abs(c - fr.origin), abs(w - fr.origin), p.size)
        if reach < FAR * p.size and not any(_same(Dyad(c, w), o, 1e-6 * reach) for o in out):
            out.append(Dyad(complex(c), complex(w)))  # a farther one is a slider for any practical purpose
    return out


def _same(a: Dyad, b: Dyad, tol: float) -> bool:
    """Whether two dyads are one: their ground pivots or their moving pivots within ``tol``.

    Two Burmester dyads never share a pivot (a circle point has one center, and a center point
    one circle point), and a far dyad is fixed by the poses only to about 1e-7 of its distance.
    """
    return abs(a.ground - b.ground) <= tol or abs(a.moving - b.moving) <= tol


def _shared_three(theta: FloatArray) -> tuple[int, int, int, int, int]:
    """The three poses the two cubics share (then the other two): the angles farthest apart.

    When two shared poses have one angle (a translation), two rows of both determinants stop
    depending on ``c`` and the cubics drop to conics, which the resultant of two cubics
    cannot handle; the most distinct angles avoid that whenever any three angles differ.
    """
    triples = list(combinations(range(5), 3))
    spread = [min(abs(math.sin((theta[i] - theta[j]) / 2)) for i, j in combinations(t, 2)) for t in triples]
    best = triples[int(np.argmax(spread))]
    r1, r2 = (k for k in range(5) if k not in best)
    return (*best, r1, r2)


def _dyad_newton(p: Poses, centers: ComplexArray, steps: int = 30) -> tuple[ComplexArray, ComplexArray]:
    """Dyads of 5 poses by Newton's method on their own equations, from every start at once.

    The unknowns are the ground pivot ``c`` and the body point ``w``, and the equations
    ``|W_j - c|^2 - |W_0 - c|^2 = 0`` (``j = 1..4``): four in four.  Unlike the cubics, a
    pole is no solution of them, so a Burmester point next to a pole is found as precisely as
    any other.  ``w`` starts at the least-squares circle of ``c`` seen from the body.  A start
    stops once its residual is at rounding (so that it cannot step on to a neighbouring
    solution); the converged ones are returned, ``(ground, moving)`` in the plane (``moving``
    at the first pose), those whose five positions lie on one circle to :data:`MISFIT`.
    """
    fr = _Frame.of(p)
    d, theta = fr.poses(p)
    rot = cis(theta)
    c = fr.from_plane(centers)
    w = _circle_fit((c[:, None] - d) / rot)[0] if c.size else c
    done = np.zeros(c.shape, bool)
    with np.errstate(all="ignore"):
        for _ in range(steps):
            u = d + rot * w[:, None] - c[:, None]  # W_j - c
            e = np.abs(u[:, 1:]) ** 2 - np.abs(u[:, :1]) ** 2
            scale = np.max(np.abs(u) ** 2, axis=1)
            done |= np.max(np.abs(e), axis=1) <= 1e-15 * scale
            live = ~done & np.isfinite(e).all(axis=1)
            if not live.any():
                break
            dc = -2 * (u[live, 1:] - u[live, :1])  # gradients in c and in w, as x + iy
            dw = 2 * (np.conj(rot[1:]) * u[live, 1:] - np.conj(rot[0]) * u[live, :1])
            jac = np.stack([dc.real, dc.imag, dw.real, dw.imag], axis=-1)
            solvable = np.abs(np.linalg.det(jac)) > 0
            delta = np.zeros((int(live.sum()), 4))
            delta[solvable] = np.linalg.solve(jac[solvable], e[live][solvable][..., None])[..., 0]
            c[live] -= delta[:, 0] + 1j * delta[:, 1]
            w[live] -= delta[:, 2] + 1j * delta[:, 3]
        r = np.abs(d + rot * w[:, None] - c[:, None])
        ok = np.isfinite(r).all(axis=1) & (np.ptp(r, axis=1) <= MISFIT * np.maximum(1.0, np.max(r, axis=1)))
    return fr.to_plane(c[ok]), fr.to_plane(d[0] + rot[0] * w[ok])


def _starts(f: FloatArray, g: FloatArray, known: ComplexArray) -> ComplexArray:
    """Starts for the common real roots of two cubics: real roots of their resultant in ``x``, then roots in ``y``.

    The resultant ``R(x)`` (degree 7) is sampled on a circle ``|x| = rho`` by the determinant of
    the Sylvester matrix, divided there by ``x - Re(k)`` for every known common root ``k`` (the
    poles, within 10 of the origin), and its coefficients read off by an FFT: the quotient is
    the quartic of the Burmester points, whose roots stay simple even next to a pole.
    """
    near = known[np.isfinite(known) & (np.abs(known) <= 10)].real
    rho = max(1.0, 1.25 * float(np.max(np.abs(near), initial=0.0)))
    n = 16
    xs = rho * cis(2 * np.pi * np.arange(n) / n)
    fy = np.stack([npoly.polyval(xs, f[:, i]) for i in range(4)], axis=-1)  # coefficients of y^0..y^3
    gy = np.stack([npoly.polyval(xs, g[:, i]) for i in range(4)], axis=-1)
    syl = np.zeros((n, 6, 6), complex)
    for r in range(3):
        syl[:, r, r : r + 4] = fy[:, ::-1]
        syl[:, r + 3, r : r + 4] = gy[:, ::-1]
    vals = np.linalg.det(syl) / np.prod(xs[:, None] - near[None, :], axis=1)
    degree = 7 - near.size  # 9 intersections less the circular points at infinity and the poles
    coef = (np.fft.fft(vals) / n).real[: degree + 1] / rho ** np.arange(degree + 1)
    x = np.roots(coef[::-1]) if np.any(coef) else np.zeros(0)
    out = []
    for x0 in x[np.abs(x.imag) <= 0.1 * (1 + np.abs(x))].real:  # a close pair of real roots may come out complex
        for h in (f, g):
            coef_y = npoly.polyval(x0, h)
            ys = np.roots(coef_y[::-1]) if np.any(coef_y) else np.zeros(0, complex)
            out += [complex(x0, y.real) for y in ys if abs(y.imag) <= 0.1 * (1 + abs(y))]
    return np.array(out, complex)


def _polish(f: FloatArray, g: FloatArray, c: ComplexArray, steps: int = 50) -> ComplexArray:
    """Newton's method on ``f = g = 0`` from every start at once; the converged points."""
    fx, fy = npoly.polyder(f, axis=0), npoly.polyder(f, axis=1)
    gx, gy = npoly.polyder(g, axis=0), npoly.polyder(g, axis=1)
    x, y = c.real.copy(), c.imag.copy()
    with np.errstate(all="ignore"):
        for _ in range(steps):
            a, b = npoly.polyval2d(x, y, f), npoly.polyval2d(x, y, g)
            j11, j12 = npoly.polyval2d(x, y, fx), npoly.polyval2d(x, y, fy)
            j21, j22 = npoly.polyval2d(x, y, gx), npoly.polyval2d(x, y, gy)
            det = j11 * j22 - j12 * j21
            x, y = x - (a * j22 - b * j12) / det, y - (j11 * b - j21 * a) / det
        scale = (1 + np.hypot(x, y)) ** 3
        ok = np.isfinite(x + y)
        ok[ok] = (np.abs(npoly.polyval2d(x[ok], y[ok], f)) + np.abs(npoly.polyval2d(x[ok], y[ok], g))) <= 1e-10 * scale[
            ok
        ]
    return (x + 1j * y)[ok]


# ---------------------------------------------------------------------- four-bars of two dyads
@dataclass(frozen=True)
class BurmesterFourBar:
    """A four-bar whose coupler carries the body: two dyads, checked by :func:`linkagekit.analyze`.

    Attributes
    ----------
    crank, rocker : Dyad
        The driven dyad (link ``crank``: A0-A1) and the other one (link ``rocker``: B0-B1).
    poses : Poses
        The poses it was made for (its coupler's ``P`` is at ``d_0``, ``Q`` one length unit
        along ``theta_0`` at the first pose).
    inputs : ndarray, shape (n,)
        The crank's angle at each pose (radians, from +x), unwrapped in the turning direction
        from the first pose's.
    direction : int
        +1 when the crank turns counter-clockwise from pose to pose, -1 clockwise.
    signs : ndarray of int, shape (n,)
        The assembly mode (the sign of joint B1, as :func:`linkagekit.analyze` names it) at each pose.
    in_order : bool
        Whether it meets the poses in order on one branch: the poses' crank angles follow each
        other in ``direction`` within one turn, every pose is in the first pose's assembly mode,
        and it assembles at every crank angle in between (exactly: :func:`~linkagekit.geometry.fourbar_sweep`).
    grashof, grashof_detail : str
        Its Grashof type (:func:`linkagekit.checks.grashof`).
    position_errors, angle_errors : ndarray, shape (n,)
        ``|P - d_j|`` and ``|angle(Q - P) - theta_j|`` (radians), the four-bar analysed at each
        pose's crank angle in that pose's assembly mode.
    """

    crank: Dyad
    rocker: Dyad
    poses: Poses
    inputs: FloatArray
    direction: int
    signs: IntArray
    in_order: bool
    grashof: str
    grashof_detail: str
    position_errors: FloatArray
    angle_errors: FloatArray

    @property
    def position_error(self) -> float:
        """The largest ``|P - d_j|``."""
        return float(np.max(self.position_errors))

    @property
    def angle_error(self) -> float:
        """The largest orientation error (radians)."""
        return float(np.max(self.angle_errors))

    @property
    def lengths(self) -> dict[str, float]:
        """Link lengths: ``ground`` |A0 B0|, ``crank`` |A0 A1|, ``coupler`` |A1 B1|, ``rocker`` |B0 B1|."""
        return _lengths(self.crank, self.rocker)

    def mechanism(self, unit: str = "m", name: str = "Burmester four-bar") -> Mechanism:
        """The four-bar as a :class:`~linkagekit.Mechanism` at the first pose, driven by ``crank``.

        Joints ``A0, A1, B1, B0, P, Q`` (in the poses' length ``unit``), links ``ground``
        ``[A0, B0]``, ``crank`` ``[A0, A1]``, ``coupler`` ``[A1, B1, P, Q]``, ``rocker``
        ``[B0, B1]``; the crank's sweep runs from the first pose's angle to the last one's in
        ``direction`` (degrees).
        """
        return _mechanism(self.poses, self.crank, self.rocker, self.inputs, unit, name)


def _lengths(crank: Dyad, rocker: Dyad) -> dict[str, float]:
    return {
        "ground": float(abs(rocker.ground - crank.ground)),
        "crank": float(crank.length),
        "coupler": float(abs(rocker.moving - crank.moving)),
        "rocker": float(rocker.length),
    }


def _joints(p: Poses, crank: Dyad, rocker: Dyad) -> ComplexArray:
    """Every joint of the four-bar at every pose, ``(n, 6)`` in :data:`JOINTS` order: ``Q`` on the pose's line a
    tenth of the pose points' diagonal (their bounding box's; their size where that is 0) from ``P``."""
    a1 = p.place(p.body(crank.moving))
    b1 = p.place(p.body(rocker.moving))
    n = p.n
    diagonal = float(np.hypot(np.ptp(p.d.real), np.ptp(p.d.imag))) or p.size
    q = p.d + 0.1 * diagonal * p.rot
    return np.stack([np.full(n, crank.ground), a1, b1, np.full(n, rocker.ground), p.d, q], axis=1)


def _mechanism(p: Poses, crank: Dyad, rocker: Dyad, inputs: FloatArray, unit: str, name: str) -> Mechanism:
    start, stop = (float(np.degrees(inputs[i])) for i in (0, -1))
    return guided_fourbar(_joints(p, crank, rocker)[0], start, stop, unit, name, "<Burmester four-bar>")


def _turn(phi: FloatArray) -> tuple[int, FloatArray]:
    """The turning direction that passes ``phi`` in order with the least total turn, and ``phi`` unwrapped that way."""
    steps = np.diff(phi, axis=-1)
    ccw = np.mod(steps, 2 * np.pi)
    cw = np.mod(-steps, 2 * np.pi)
    sign = 1 if ccw.sum() <= cw.sum() else -1
    inc = ccw if sign > 0 else cw
    return sign, phi[0] + sign * np.concatenate([[0.0], np.cumsum(inc)])


def four_bar(poses: Poses | Sequence[ArrayLike], crank: Dyad, rocker: Dyad) -> BurmesterFourBar:
    """The four-bar of two dyads, checked at the poses by :func:`linkagekit.analyze` and along its sweep exactly.

    The crank angles and assembly modes at the poses are the solver's (:func:`linkagekit.api.prepare`
    of the four-bar placed at every pose); the residuals are the four-bar analysed at those
    angles in those modes; the order check sweeps the crank from the first pose to the last
    (:func:`~linkagekit.geometry.fourbar_sweep`: no sampling that a narrow gap could slip through).
    """
    p = _as_poses(poses)
    z = _joints(p, crank, rocker)
    mech = _mechanism(p, crank, rocker, np.zeros(2), "m", "check")
    prm = prepare(mech, np.stack([z.real, z.imag], axis=-1))
    direction, inputs = _turn(prm.pose_inputs[0])
    res = analyze(mech, {"crank": np.degrees(inputs)}, signs=prm.signs, rates=False, dynamics=False)
    pq = res.point("Q") - res.point("P")
    pos_err = np.abs(res.point("P") - p.d)
    ang_err = np.abs(np.angle(pq / p.rot))
    span = abs(inputs[-1] - inputs[0])
    A0, A1, B1, B0 = z[0, :4]  # the lengths the file reads off its first pose
    whole, _ = fourbar_sweep(A0, abs(A1 - A0), B0, abs(B1 - A1), abs(B1 - B0), inputs[0], inputs[-1])
    in_order = bool(span < 2 * np.pi and np.all(prm.signs == prm.signs[:, :1]) and whole)
    lengths = _lengths(crank, rocker)
    kind, detail = grashof(
        FourBar(0, 1, 2, 3, lengths["ground"], lengths["crank"], lengths["coupler"], lengths["rocker"])
    )
    return BurmesterFourBar(
        crank,
        rocker,
        p,
        inputs,
        direction,
        prm.signs[0].astype(int),
        in_order,
        kind,
        detail,
        np.where(np.isfinite(pos_err), pos_err, np.inf),
        np.where(np.isfinite(ang_err), ang_err, np.inf),
    )


# ---------------------------------------------------------------------- choosing pairs of dyads
def _screen(p: Poses, ground: ComplexArray, moving: ComplexArray, samples: int = 128) -> tuple[BoolArray, FloatArray]:
    """For every ordered pair (crank i, rocker j) of dyads at once: in order on one branch, and its worst transmission.

    The closed-form counterpart of :func:`four_bar`'s check (used to choose among many pairs):
    the crank angles at the poses, the side of the line A1-B0 that B1 is on at each pose (the
    assembly mode), and ``cos mu = (b^2 + c^2 - |B0 - A1(phi)|^2) / 2bc`` on ``samples`` crank
    angles between the first pose and the last.  Returns ``(m, m)`` arrays: whether the pair is
    in order, and ``min sin mu`` over the sweep (0 where it does not assemble).
    """
    tips = p.place(p.body(moving))  # (m, n)
    i, j = np.meshgrid(np.arange(ground.size), np.arange(ground.size), indexing="ij")
    g0, t0, g1, t1 = ground[i], tips[i], ground[j], tips[j]  # (m, m), (m, m, n), ...
    phi = np.angle(t0 - g0[..., None])
    steps = np.diff(phi, axis=-1)
    ccw, cw = np.mod(steps, 2 * np.pi).sum(-1), np.mod(-steps, 2 * np.pi).sum(-1)
    direction, span = np.where(ccw <= cw, 1.0, -1.0), np.minimum(ccw, cw)
    side = np.sign(cross(g1[..., None] - t0, t1 - t0))
    same = np.all(side == side[..., :1], axis=-1)
    sweep = phi[..., :1] + direction[..., None] * span[..., None] * np.linspace(0, 1, samples)
    a, b, c = np.abs(t0[..., 0] - g0), np.abs(t1[..., 0] - t0[..., 0]), np.abs(t1[..., 0] - g1)
    dist2 = np.abs(g1[..., None] - g0[..., None] - a[..., None] * cis(sweep)) ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        cos_mu = (b[..., None] ** 2 + c[..., None] ** 2 - dist2) / (2 * b * c)[..., None]
    assembles = np.all(np.abs(cos_mu) <= 1, axis=-1)
    quality = np.where(assembles, np.sqrt(np.clip(1 - np.max(cos_mu**2, axis=-1), 0, 1)), 0.0)
    ok = same & assembles & (span < 2 * np.pi) & (i != j)
    return ok, np.where(i != j, quality, -1.0)


def _pairs(p: Poses, dyads: Sequence[Dyad], count: int | None) -> list[tuple[Dyad, Dyad]]:
    """The best ``count`` pairs (None: every pair), each in its better crank choice, best first.

    Better: in order on one branch first, then the larger worst transmission ``min sin mu``.
    With a ``count``, a dyad is used by one chosen pair only (so that the pairs differ).
    """
    ground = np.array([d.ground for d in dyads], complex)
    moving = np.array([d.moving for d in dyads], complex)
    ok, quality = _screen(p, ground, moving)
    score = ok + quality  # in order (1) outranks any transmission (< 1)
    order = np.argsort(-score, axis=None, kind="stable")
    chosen: list[tuple[int, int]] = []
    used: set[int] = set()
    for flat in order:
        i, j = (int(v) for v in np.unravel_index(flat, score.shape))
        if i == j or (j, i) in chosen or (i, j) in chosen or _same(dyads[i], dyads[j], 1e-9 * p.size):
            continue  # one dyad twice (or a pivot shared): no four-bar
        if count is not None and (i in used or j in used):
            continue
        chosen.append((i, j))
        used |= {i, j}
        if count is not None and len(chosen) == count:
            break
    return [(dyads[i], dyads[j]) for i, j in chosen]


def _default_dyads(p: Poses, samples: int = 256, keep: int = 40) -> list[Dyad]:
    """Candidate dyads: for 3 poses circle points on rings about the first pose's point, for 4 the center-point curve.

    Only dyads with ground pivot within ``4 * size`` of the poses' centroid and length between
    ``0.05`` and ``4`` sizes are kept, ``keep`` of them spread evenly over the candidates.
    """
    if p.n == 3:
        ring = np.concatenate([r * cis(np.linspace(0, 2 * np.pi, 24, endpoint=False)) for r in (0.25, 0.5, 1.0)])
        dyads = [dyad_from_circle_point(p, complex(c)) for c in p.d[0] + p.size * ring]
    else:
        dyads = center_point_curve(p, samples).dyads()
    mid = complex(p.d.mean())
    good = [
        d
        for d in dyads
        if np.isfinite(d.ground) and abs(d.ground - mid) <= 4 * p.size and 0.05 * p.size <= d.length <= 4 * p.size
    ]
    pick = np.unique(np.linspace(0, len(good) - 1, min(keep, len(good))).round().astype(int))
    return [good[i] for i in pick]


def exact_motion(
    poses: Poses | Sequence[ArrayLike],
    *,
    count: int = 6,
    centers: Sequence[complex] | None = None,
    circle_points: Sequence[complex] | None = None,
) -> list[BurmesterFourBar]:
    """Four-bars whose coupler meets 3, 4 or 5 poses exactly, best first.

    Parameters
    ----------
    poses : Poses or (x, y, angle)
        The poses (``angle`` in radians).
    count : int
        For 3 and 4 poses, how many four-bars to return (each from two dyads no other uses).
        For 5 poses every real Burmester pair is returned (up to six).
    centers, circle_points : sequence of complex, optional
        Dyads to pair, given by their ground pivots or, for 3 poses, by their moving pivots at
        the first pose.  A ground pivot is any point for 3 poses; for 4 it is moved onto the
        center-point curve, for 5 to the nearest Burmester point (:func:`nearest_dyad`).
        Default: 3 poses, circle points on rings of radius 1/4, 1/2 and 1 size about the
        first pose's point; 4 poses, points spread over the center-point curve; 5 poses, the
        Burmester points.

    Returns
    -------
    list of BurmesterFourBar
        Ordered: in order on one branch first, then by the worst transmission angle along the
        sweep; each with the crank choice (which dyad drives) that is better by the same rule.
    """
    p = _as_poses(poses)
    _exact(p, (3, 4, 5), "exact motion generation (Burmester theory)")
    if isinstance(count, bool) or not isinstance(count, int) or count < 1:
        raise InputError(f"count: a whole number of four-bars, at least 1, got {count!r}")
    dyads = _given_dyads(p, centers, circle_points)
    if dyads is None:
        dyads = burmester_points(p) if p.n == 5 else _default_dyads(p)
    pairs = _pairs(p, dyads, None if p.n == 5 and centers is None else count)
    fbs = [four_bar(p, a, b) for a, b in pairs]
    return sorted(fbs, key=lambda fb: not fb.in_order)


def _given_dyads(
    p: Poses, centers: Sequence[complex] | None, circle_points: Sequence[complex] | None
) -> list[Dyad] | None:
    """The user's dyads: ground pivots moved onto the center points nearest (:func:`nearest_dyad`), or circle points."""
    if centers is None and circle_points is None:
        return None
    if circle_points is not None:
        _exact(p, (3,), "circle points given by the user")
        dyads = [dyad_from_circle_point(p, complex(c)) for c in circle_points]
    else:
        dyads = [nearest_dyad(p, complex(c)) for c in centers or ()]
    what = "centers" if circle_points is None else "circle_points"
    for k, dy in enumerate(dyads):
        _, misfit = _circle_fit(p.place(p.body(dy.moving)))
        if not (np.isfinite(dy.ground) and misfit <= 1e-7 * max(p.size, dy.length)):
            raise InputError(f"{what}[{k}]: no dyad of these {p.n} poses (its circle point's positions are collinear)")
        if any(_same(dy, o, 1e-9 * p.size) for o in dyads[:k]):
            raise InputError(f"{what}[{k}]: the same dyad as an earlier one (the same center point)")
    if len(dyads) < 2:
        raise InputError(f"{what}: give at least two dyads to pair")
    return dyads
