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
