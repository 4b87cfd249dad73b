"""Planar geometry on complex numbers: the kernels every solve step is built from.

A point or a vector of the plane is a complex number ``x + iy``; a rotation by ``theta`` is
the product with ``cis(theta) = e^{i theta}``; with ``conj(a) b = a . b + i cross(a, b)`` one
complex product gives both the dot and the cross product.  Every function here works
elementwise on arrays of any shape (samples, designs x samples, ...).

Examples
--------
>>> import numpy as np
>>> float(cross(1 + 0j, 1j)), float(dot(3 + 4j, 3 + 4j))
(1.0, 25.0)
>>> z, m = circle_circle(np.array([0j]), np.array([4 + 0j]), 5.0, 3.0, 1.0)
>>> complex(z[0])
(4+3j)
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

#: relative tolerance of the assembly tests (see docs/method.md, "Tolerances")
ASSEMBLY_RTOL = 1e-12
#: "not a point": NaN in both coordinates (``nan + 0j`` would print a y of 0)
NAN_POINT = complex(np.nan, np.nan)
_TINY = 1e-300

#: anything NumPy reads as an array (scalars, sequences, arrays); left open for the arithmetic
ArrayLike = Any
#: arrays by element type: real values, planar points (complex numbers), flags, indices
FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]
BoolArray = NDArray[np.bool_]
IntArray = NDArray[np.intp]


def abs2(a: ComplexArray) -> FloatArray:
    """Squared magnitude of planar vectors written as complex numbers."""
    return a.real * a.real + a.imag * a.imag


def dot(a: ArrayLike, b: ArrayLike) -> FloatArray:
    """Dot product of planar vectors written as complex numbers."""
    x: ComplexArray = np.asarray(a)
    y: ComplexArray = np.asarray(b)
    return x.real * y.real + x.imag * y.imag


def cross(a: ArrayLike, b: ArrayLike) -> FloatArray:
    """z-component of the cross product of planar vectors written as complex numbers."""
    x: ComplexArray = np.asarray(a)
    y: ComplexArray = np.asarray(b)
    return x.real * y.imag - x.imag * y.real


def cis(theta: ArrayLike) -> ComplexArray:
    """``e^{i theta}``, the unit vector at angle ``theta`` (radians)."""
    theta = np.asarray(theta, float)
    out = np.empty(theta.shape, complex)
    out.real = np.cos(theta)
    out.imag = np.sin(theta)
    return out


def side(k1: ArrayLike, k2: ArrayLike, j: ArrayLike) -> FloatArray:
    """+1 where ``j`` lies left of (or on) the directed line ``k1 -> k2``, else -1."""
    return np.where(cross(np.asarray(k2) - k1, np.asarray(j) - k1) >= 0, 1.0, -1.0)


def circle_circle(
    z1: ComplexArray,
    z2: ComplexArray,
    r1: ArrayLike,
    r2: ArrayLike,
    sign: ArrayLike,
    eps: float = ASSEMBLY_RTOL,
    out: ComplexArray | None = None,
    margin: FloatArray | None = None,
) -> tuple[ComplexArray, FloatArray]:
    """Intersection of the circles ``|z - z1| = r1`` and ``|z - z2| = r2`` (seed 000, eqs. 11-15).

    With ``d = z2 - z1``, ``s = |d|``: ``along = (r1^2 - r2^2 + s^2) / (2 s)``,
    ``h = sign sqrt(r1^2 - along^2)``, ``z = z1 + (along + i h) d / s``; ``sign=+1`` picks the
    point to the left of the directed line ``z1 -> z2``.  The radii broadcast against the
    centres (one radius per design, one centre per design and sample).  Returns
    ``(z, margin)``: ``margin`` is the relative distance from the nearest assembly limit,
    negative where the circles do not meet, and there ``z`` is NaN.  ``out`` (complex) and
    ``margin`` (float) are written in place when given.

    Computed as ``z = z1 + w d`` with ``w = a + i b``, ``a = along / s = 1/2 + (r1^2 - r2^2) / (2 s^2)``
    and ``b = h / s = sign sqrt(r1^2 / s^2 - a^2)``: one complex product places the point
    (NumPy runs complex products as fast as real ones), and every operation writes in place
    into four work arrays taken in two allocations: on large batches a fresh temporary per
    operation (new memory, handed over zeroed page by page) cost more than the arithmetic.
    """
    shape = np.broadcast_shapes(*(np.shape(a) for a in (z1, z2, r1, r2, sign)))
    if out is None:
        out = np.empty(shape, complex)
    if margin is None:
        margin = np.empty(shape)
    d, w = np.empty((2, *shape), complex)  # d = z2 - z1 and w = a + i b
    s2, t = np.empty((2, *shape))
    np.subtract(z2, z1, out=d)
    dx, dy = d.real, d.imag
    np.multiply(dx, dx, out=s2)
    np.multiply(dy, dy, out=t)
    s2 += t
    np.sqrt(s2, out=t)  # t = s
    total = r1 + r2
    _assembly_margin(margin, t, r1, r2, eps, total)
    a, b = w.real, w.imag
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):  # s -> 0 is flagged below
        r1sq = r1 * r1
        np.divide(1.0, s2, out=s2)  # s2 = 1 / s^2
        np.multiply(s2, 0.5 * (r1sq - r2 * r2), out=t)
        np.add(t, 0.5, out=a)
        np.multiply(s2, r1sq, out=s2)  # b = sign sqrt(max(r1^2 / s^2 - a^2, 0))
        np.multiply(a, a, out=t)
        s2 -= t
        np.maximum(s2, 0.0, out=s2)
        np.sqrt(s2, out=s2)
        np.multiply(s2, sign, out=b)
        np.multiply(w, d, out=out)
        out += z1
    _flag_unassembled(out, margin, d, r1, r2, eps, total)
    return out, margin


def _assembly_margin(
    margin: FloatArray, s: FloatArray, r1: ArrayLike, r2: ArrayLike, eps: float, total: ArrayLike
) -> None:
    """``margin = min(total (1 + eps) - s, s - |r1 - r2| + eps total) / total`` in place (``s`` is overwritten)."""
    np.subtract(total * (1 + eps), s, out=margin)
    np.subtract(s, np.abs(r1 - r2) - eps * total, out=s)
    np.minimum(margin, s, out=margin)
    margin *= 1.0 / total


def _flag_unassembled(
    out: ComplexArray, margin: FloatArray, d: ComplexArray, r1: ArrayLike, r2: ArrayLike, eps: float, total: ArrayLike
) -> None:
    """NaN points and negative margins, in place, where the circles do not meet or the centres coincide.

    Coincident centres (``s <= eps total``) are flagged too; with ``margin >= 0`` they need ``r1``
    and ``r2`` within ``2 eps total`` of each other, so the batch is checked sample by sample only then.
    """
    if margin.min(initial=0.0) >= 0 and not np.any(np.abs(r1 - r2) <= 2 * eps * total):
        return
    ok = margin >= 0
    ok &= np.hypot(d.real, d.imag) > eps * total
    out[~ok] = NAN_POINT
    np.copyto(margin, np.minimum(margin, -_TINY), where=~ok)


def link_rates(base: ComplexArray, vbase: ComplexArray, abase: ComplexArray) -> tuple[FloatArray, FloatArray]:
    """Angular velocity and acceleration of the line ``base`` from its first two derivatives.

    ``base = |b| e^{i theta}`` with constant length, so ``vbase = i w base`` and
    ``abase = (i alpha - w^2) base``: ``w = cross(base, vbase) / |base|^2``, likewise alpha.
    """
    n2 = abs2(base)
    with np.errstate(divide="ignore", invalid="ignore"):
        return cross(base, vbase) / n2, cross(base, abase) / n2


def solve_each(A: FloatArray, b: FloatArray) -> FloatArray:
    """``x`` with ``A x = b`` for each small system (``A`` (..., k, k), ``b`` (..., k)): NaN where a system is not
    finite, and the minimum-norm least squares (``pinv``) for all when one is singular (LAPACK's solve then raises
    for the whole batch; the others keep their exact answer).

    >>> A = np.array([[[1.0, 1.0], [1.0, 1.0]], [[2.0, 0.0], [0.0, 4.0]], [[np.inf, 0.0], [0.0, 1.0]]])
    >>> np.round(solve_each(A, np.array([[2.0, 2.0], [2.0, 4.0], [1.0, 1.0]])), 12).tolist()
    [[1.0, 1.0], [1.0, 1.0], [nan, nan]]
    """
    A, b = np.asarray(A, float), np.asarray(b, float)
    bad = ~(np.all(np.isfinite(A), axis=(-2, -1)) & np.all(np.isfinite(b), axis=-1))
    A = np.where(bad[..., None, None], np.eye(A.shape[-1]), A)
    b = np.where(bad[..., None], 0.0, b)
    try:
        x = np.linalg.solve(A, b[..., None])[..., 0]
    except np.linalg.LinAlgError:  # exactly singular to LAPACK (rounding made a pivot 0)
        x = (np.linalg.pinv(A) @ b[..., None])[..., 0]
    out: FloatArray = np.where(bad[..., None], np.nan, x)
    return out


def crank_reach(
    ga: ArrayLike, ra: ArrayLike, g: ArrayLike, t0: ArrayLike, t1: ArrayLike
) -> tuple[FloatArray, FloatArray]:
    """The least and the greatest ``|A(t) - g|^2`` of a crank tip ``A(t) = ga + ra cis(t)`` for ``t`` between
    ``t0`` and ``t1`` (either way round; elementwise).

    With ``c = ga - g = |c| cis(phi)``: ``|A(t) - g|^2 = |c|^2 + ra^2 + 2 ra |c| cos(t - phi)``, a sinusoid in
    ``t``; over the interval its extremes are at the ends or at ``t = phi`` (the greatest) and ``t = phi + pi``
    (the least) plus whole turns, where one falls inside. Exact: no sampling of ``t``.

    >>> lo, hi = crank_reach(0j, 1.0, 3 + 0j, 0.0, np.pi / 2)  # from (1, 0) to (0, 1): distances 2 and sqrt(10)
    >>> float(lo), float(np.round(hi, 12))
    (4.0, 10.0)
    >>> lo, hi = crank_reach(0j, 1.0, 3 + 0j, -1.0, 4.0)  # through t = pi: the far end of the crank
    >>> float(lo), float(np.round(hi, 12))
    (4.0, 16.0)
    """
    c = np.asarray(ga) - np.asarray(g)
    ra = np.asarray(ra, float)
    lo_t, hi_t = np.minimum(t0, t1), np.maximum(t0, t1)
    mean, amp, phi = abs2(c) + ra * ra, 2 * ra * np.abs(c), np.angle(c)  # amp < 0 for a negative ra
    ends = mean + amp * np.cos(np.stack([lo_t, hi_t]) - phi)
    top, bottom = np.stack([mean + amp, mean - amp]), np.stack([phi, phi + np.pi])  # the sinusoid's extremes
    inside = np.mod(bottom - lo_t, 2 * np.pi) <= hi_t - lo_t  # at a t + 2 pi k within [lo_t, hi_t]
    least = np.minimum(np.min(ends, axis=0), np.min(np.where(inside, top, np.inf), axis=0))
    greatest = np.maximum(np.max(ends, axis=0), np.max(np.where(inside, top, -np.inf), axis=0))
    return least, greatest


def fourbar_sweep(
    ga: ArrayLike, ra: ArrayLike, gb: ArrayLike, coupler: ArrayLike, rocker: ArrayLike, t0: ArrayLike, t1: ArrayLike
) -> tuple[BoolArray, FloatArray]:
    """Does a four-bar assemble at every crank angle between ``t0`` and ``t1``, and its smallest transmission angle
    there (degrees, folded to [0, 90]; NaN where it does not assemble), exactly (elementwise, no sampling).

    Crank pivot ``ga``, crank ``ra`` (its tip ``A(t) = ga + ra cis(t)``), rocker pivot ``gb``, coupler ``l`` and
    rocker ``r_b``: it assembles at ``t`` iff ``d(t) = |A(t) - gb|`` lies in ``[|l - r_b|, l + r_b]`` (within
    :data:`ASSEMBLY_RTOL`, as :func:`circle_circle`), so all along the sweep iff the least and the greatest
    ``d^2`` (:func:`crank_reach`) do. ``cos mu = (l^2 + r_b^2 - d^2) / (2 l r_b)`` is monotone in ``d^2``: the
    smallest folded angle is at one of those extremes.

    >>> ok, mu = fourbar_sweep(0j, 1.0, 3 + 0j, 1.0, 2.5, 0.0, np.radians([110.0, 115.0]))  # d^2 = 10 - 6 cos t
    >>> ok.tolist(), np.round(mu, 6).tolist()  # past 112.02 deg, d > l + r_b = 3.5
    ([True, False], [16.173181, nan])
    """
    ell, rb = np.abs(np.asarray(coupler, float)), np.abs(np.asarray(rocker, float))
    least, greatest = crank_reach(ga, ra, gb, t0, t1)
    near = np.maximum(np.abs(ell - rb) - ASSEMBLY_RTOL * (ell + rb), 0.0)
    ok = (least >= near**2) & (greatest <= ((ell + rb) * (1 + ASSEMBLY_RTOL)) ** 2)
    with np.errstate(invalid="ignore", divide="ignore"):
        cos_mu = (ell**2 + rb**2 - np.stack([least, greatest])) / (2 * ell * rb)
        mu = np.degrees(np.arccos(np.clip(np.max(np.abs(cos_mu), axis=0), 0.0, 1.0)))
    return np.asarray(ok), np.where(ok, mu, np.nan)
