r"""Phase-normalised elliptic Fourier descriptors of curves (Kuhl & Giardina), batched over curves.

A curve is a polygon ``z_0, ..., z_{n-1}`` (complex, the last axis of an array); a closed one
returns from ``z_{n-1}`` to ``z_0``, an open one is traced forth and back (``z_0 .. z_{n-1} ..
z_0``), which closes it without adding anything to its shape. Parametrised by arc length
``t`` over its perimeter ``T``, the polygon has the Fourier series ``z(t) = sum_k Z_k
exp(2 pi i k t / T)``; harmonic ``k`` of Kuhl & Giardina's elliptic series (``a_k, b_k, c_k,
d_k``) is the ellipse ``Z_k e^{i w} + Z_{-k} e^{-i w}``, with ``a_k + i c_k = Z_k + Z_{-k}`` and
``b_k + i d_k = i (Z_k - Z_{-k})``. The coefficients of the polygon are exact (no resampling):
on segment ``j`` the derivative ``z'_j = dz_j / dt_j`` is constant, and integrating by parts
twice,

.. math:: Z_k = \frac{T}{4 \pi^2 k^2} \sum_j z'_j \left(e^{-i\omega_k t_{j+1}} - e^{-i\omega_k t_j}\right),
          \qquad \omega_k = 2 \pi k / T,

and ``Z_0`` is the centroid of the curve (of its arc length).

Normalisation (docs/method.md, "An atlas of four-bar curves")
    moving the curve by ``b`` changes ``Z_0`` only; turning and scaling it by ``s`` (complex)
    multiplies every ``Z_k`` by ``s``; starting it later by ``tau`` multiplies ``Z_k`` by
    ``exp(i k phi)``, ``phi = 2 pi tau / T``; tracing it backwards swaps ``Z_k`` and ``Z_{-k}``.
    So: drop ``Z_0``; trace it so that ``|Z_1| >= |Z_{-1}|``; divide by the RMS radius
    ``rho = sqrt(sum_{k != 0} |Z_k|^2)``; choose the turn ``psi`` and the start ``phi`` that make
    ``Z_1`` and ``Z_{-1}`` real and positive: ``psi + phi = -arg Z_1``, ``psi - phi = -arg Z_{-1}``.
    That fixes ``(psi, phi)`` up to adding ``(pi, pi)`` together, which multiplies ``Z_k`` by
    ``(-1)^(k+1)`` (the 180-degree ambiguity of the first harmonic's ellipse): of the two, the
    one whose even harmonics' real parts sum to at least zero is kept (:func:`flipped` gives
    the other; a search looks up both).

The descriptor is ``Re Z_1, Re Z_{-1}`` and the real and imaginary parts of ``Z_{+-k}``,
``k = 2..H``; by Parseval, the squared distance of two descriptors is the mean squared
distance of the two normalised curves (up to ``H`` harmonics) at equal arc-length fractions.
What was removed is the similarity ``z = c + s w``: ``c = Z_0``, ``s = rho exp(-i psi)``, ``w``
the normalised curve.

Examples
--------
>>> import numpy as np
>>> t = np.linspace(0, 2 * np.pi, 50, endpoint=False)
>>> z = np.exp(1j * t) + 0.3 * np.exp(-1j * t) + 0.1 * np.exp(2j * t)
>>> d = describe(z)
>>> moved = describe(3 - 2j + (0.5 + 1.5j) * np.roll(z, 7))
>>> bool(np.allclose(d.vector, moved.vector, atol=1e-12))
True
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: harmonics kept by default (``k = +-1 .. +-HARMONICS``)
HARMONICS = 6


@dataclass(frozen=True)
class Descriptor:
    """Normalised descriptors of curves and the similarity each had removed.

    Attributes
    ----------
    vector : ndarray, shape (..., 4 H - 2)
        The descriptor (see the module's description).
    center : ndarray, complex, shape (...)
        ``c``: the curve's centroid ``Z_0``.
    scale : ndarray, complex, shape (...)
        ``s``: the curve is ``c + s w`` for its normalised curve ``w``.
    """

    vector: np.ndarray
    center: np.ndarray
    scale: np.ndarray

    def place(self, w: np.ndarray) -> np.ndarray:
        """Points ``w`` of the normalised frame (``(..., k)`` complex) put back: ``c + s w``."""
        out: np.ndarray = self.center[..., None] + self.scale[..., None] * w
        return out


def coefficients(z: np.ndarray, closed: bool = True, harmonics: int = HARMONICS) -> tuple[np.ndarray, np.ndarray]:
    """``(Z_0, Z)`` of polygons ``z`` (..., n): ``Z[..., k - 1]`` is ``Z_k`` and ``Z[..., H + k - 1]`` is ``Z_{-k}``.

    Exact for the polygon (module description); an open one is traced forth and back.
    Segments of zero length add nothing.
    """
    z = np.asarray(z, complex)
    if not closed:
        z = np.concatenate([z, z[..., -2:0:-1]], axis=-1)
    dz = np.roll(z, -1, axis=-1) - z
    dt = np.abs(dz)
    T = dt.sum(axis=-1)
    t = np.concatenate([np.zeros((*z.shape[:-1], 1)), np.cumsum(dt, axis=-1)], axis=-1)  # (..., n + 1)
    with np.errstate(invalid="ignore", divide="ignore"):
        slope = np.where(dt > 0, dz / np.where(dt > 0, dt, 1.0), 0.0)
        Z0 = np.sum(dt * (z + np.roll(z, -1, axis=-1)), axis=-1) / (2 * T)
        step = np.exp(-2j * np.pi * t / T[..., None])  # e^{-i w_1 t_j}
    power = np.ones_like(step)
    Z = np.empty((*z.shape[:-1], 2 * harmonics), complex)
    for k in range(1, harmonics + 1):  # e^{-i w_k t} = (e^{-i w_1 t})^k: one product per harmonic, no exp
        power *= step
        diff = np.diff(power, axis=-1)
        factor = T / (4 * np.pi**2 * k * k)
        Z[..., k - 1] = factor * np.sum(slope * diff, axis=-1)
        Z[..., harmonics + k - 1] = factor * np.sum(slope * np.conj(diff), axis=-1)
    return Z0, Z


def normalise(Z0: np.ndarray, Z: np.ndarray) -> tuple[np.ndarray, Descriptor]:
    """Normalised coefficients (same layout as ``Z``) and the :class:`Descriptor` of ``(Z0, Z)`` (``coefficients``)."""
    H = Z.shape[-1] // 2
    k = np.arange(1, H + 1)
    back = np.abs(Z[..., H]) > np.abs(Z[..., 0])  # traced clockwise: trace it the other way
    Z = np.where(back[..., None], np.concatenate([Z[..., H:], Z[..., :H]], axis=-1), Z)
    rho = np.sqrt(np.sum(np.abs(Z) ** 2, axis=-1))
    rho = np.where(rho > 0, rho, 1.0)
    a1, am1 = np.angle(Z[..., 0]), np.angle(Z[..., H])
    psi = -(a1 + am1) / 2
    phi = (am1 - a1) / 2
    ks = np.concatenate([k, -k])
    W = Z * np.exp(1j * (psi[..., None] + ks * phi[..., None])) / rho[..., None]
    even = np.sum(W[..., 1:H:2].real + W[..., H + 1 :: 2].real, axis=-1)
    flip = even < 0
    W = np.where(flip[..., None], W * _sign(H), W)
    psi = np.where(flip, psi + np.pi, psi)
    scale = rho * np.exp(-1j * psi)
    return W, Descriptor(vector(W), np.asarray(Z0), scale)


def _sign(H: int) -> np.ndarray:
    """``(-1)^(k+1)`` over the layout ``k = 1..H, -1..-H``."""
    s = np.where(np.arange(1, H + 1) % 2 == 1, 1.0, -1.0)
    return np.concatenate([s, s])


def vector(W: np.ndarray) -> np.ndarray:
    """The real descriptor of normalised coefficients ``W`` (..., 2 H): ``Re W_1, Re W_-1``, then ``W_+-k``, k >= 2."""
    H = W.shape[-1] // 2
    rest = np.concatenate([W[..., 1:H], W[..., H + 1 :]], axis=-1)
    parts = [W[..., :1].real, W[..., H : H + 1].real, rest.real, rest.imag]
    return np.concatenate(parts, axis=-1)


def flipped(v: np.ndarray) -> np.ndarray:
    """The other descriptor of the same curve (``psi`` and ``phi`` both moved by pi): even harmonics negated."""
    v = np.array(v, copy=True)
    H = (v.shape[-1] + 2) // 4
    rest = np.concatenate([np.arange(2, H + 1), np.arange(2, H + 1)])
    even = np.concatenate([rest % 2 == 0] * 2)
    v[..., 2:][..., even] *= -1
    return v


def describe(z: np.ndarray, closed: bool = True, harmonics: int = HARMONICS) -> Descriptor:
    """The :class:`Descriptor` of polygons ``z`` (..., n), closed or open."""
    return normalise(*coefficients(z, closed, harmonics))[1]


def size(harmonics: int = HARMONICS) -> int:
    """Length of a descriptor vector.

    >>> size(6)
    22
    """
    return 4 * harmonics - 2
