r"""The tracer's best place on its link, and the curve's similarity placement, by linear least squares.

For given motions of two joints ``X_i``, ``X_j`` of the link that carries the tracer (complex
numbers, one per sample), every point of that link is ``X_i + c (X_j - X_i)`` for one
complex ``c`` (the link is rigid: ``c`` is the point in the frame the two joints span). A
similarity placement of the curve maps ``z`` to ``a + b z`` (translation ``a``, rotation and
scale ``b``). With targets ``T_k`` matched to samples ``k``, the placed tracer

.. math:: a + b X_i + e D, \qquad D = X_j - X_i, \quad e = b c,

is linear in ``u = (a, b, e)``: the best ``u`` solves the normal equations ``G u = r``,
``G_{pq} = \sum_k \overline{B_p} B_q``, ``r_p = \sum_k \overline{B_p} T_k`` over the basis
``B = (1, X_i, D)``, and the residual is ``|T|^2 - r^H G^{-1} r``; then ``c = e / b``
(:func:`fit`). Without the placement (``a = 0``, ``b = 1``) only ``c`` is free:
``c = \sum \overline{D} (T - X_i) / \sum |D|^2``.

Over cyclic shifts of the correspondence (:func:`fit_shifts`): target ``k`` at sample
``(p_k + s) mod n`` (``p_k = floor(k n / m)``: the targets spread evenly over ``w`` of the
``n`` samples, ``w = n`` for a closed curve), for every shift ``s`` at once. With the targets
scattered onto the samples (``t_p``: the target at sample ``p``, 0 elsewhere; ``w_p``: how
many), each sum is a cyclic correlation ``\sum_p f_p g_{p+s}``:
``G_{pq}(s) = corr(w, \overline{B_p} B_q)``, ``r_p(s) = corr(t, \overline{B_p})``, each one FFT
product (``corr(f, g) = ifft(fft(g) conj(fft(conj f)))``), so all ``n`` shifts cost
``O(n log n)`` per design; both directions along the curve are tried (the targets reversed).
A shift that puts a target on a sample where the design does not assemble is ruled out
(the correlation of ``w`` with the missing samples is positive there).

Examples
--------
>>> import numpy as np
>>> t = np.linspace(0, 2 * np.pi, 12, endpoint=False)
>>> Xi = np.exp(1j * t)[None]
>>> Xj = Xi + 0.5 * np.exp(-2j * t)[None]                           # a link that turns as it goes
>>> T = 2 + 3j * (Xi[0] + (0.2 + 0.4j) * (Xj[0] - Xi[0]))          # a placed point of it
>>> f = fit(Xi, Xj, T)
>>> np.round(f.c, 9), bool(f.sse[0] < 1e-8)  # exact, but for the ridge (about 1e-10)
(array([0.2+0.4j]), True)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: relative ridge on the normal equations (keeps a degenerate link's fit finite)
RIDGE = 1e-12


@dataclass(frozen=True)
class TracerFit:
    """The best tracer and placement of N designs.

    Attributes
    ----------
    c : ndarray (N,) complex
        The tracer ``X_i + c (X_j - X_i)`` on its link.
    a, b : ndarray (N,) complex
        The placement ``z -> a + b z`` (``0`` and ``1`` when not asked for).
    sse : ndarray (N,)
        Sum of squared distances from the targets to their placed samples (inf: no fit).
    shift : ndarray (N,) int
        :func:`fit_shifts`: the shift ``s`` (sample of the first target); 0 for :func:`fit`.
    direction : ndarray (N,) int
        :func:`fit_shifts`: ``+1`` targets along increasing samples, ``-1`` the other way.
    """

    c: np.ndarray
    a: np.ndarray
    b: np.ndarray
    sse: np.ndarray
    shift: np.ndarray
    direction: np.ndarray


def fit(Xi: np.ndarray, Xj: np.ndarray, T: np.ndarray, placement: bool = True) -> TracerFit:
    """The best ``c`` (and placement ``a, b``) for targets ``T`` (m,) or (N, m) matched to samples ``Xi, Xj`` (N, m).

    ``placement=False``: the curve stays where it is (``a = 0``, ``b = 1``).
    """
    Xi, Xj = np.asarray(Xi, complex), np.asarray(Xj, complex)
    T = np.broadcast_to(np.asarray(T, complex), Xi.shape)
    D = Xj - Xi
    N = len(Xi)
    zero = np.zeros(N, int)
    if not placement:
        R = T - Xi
        dd = np.sum(np.abs(D) ** 2, axis=1)
        c = np.sum(np.conj(D) * R, axis=1) / np.where(dd > 0, dd, np.inf)
        sse = np.sum(np.abs(R - c[:, None] * D) ** 2, axis=1)
        return TracerFit(c, np.zeros(N, complex), np.ones(N, complex), _finite(sse), zero, zero + 1)
    B = np.stack([np.ones_like(Xi), Xi, D], axis=1)  # (N, 3, m)
    G = np.einsum("npk,nqk->npq", np.conj(B), B)
    r = np.einsum("npk,nk->np", np.conj(B), T)
    u, sse = _Inverse3(G).solve(r, np.sum(np.abs(T) ** 2, axis=1))
    return _placed(u, sse, zero, zero + 1)


@dataclass(frozen=True)
class Spectra:
    """What :func:`fit_shifts` correlates with the targets' pattern, from samples ``Xi, Xj`` (N, n) alone: the
    spectra of the normal matrices' six products and of the three basis rows, and of the missing samples. The
    same for every width of a partial fit (:func:`spectra`)."""

    products: np.ndarray  # (6, N, n): fft of conj(B_i) B_j, i <= j, in PAIRS' order
    rows: np.ndarray  # (3, N, n): fft of conj(B_i)
    missing: np.ndarray  # (N, n): fft of the missing samples' indicator


#: the upper triangle of the 3 x 3 normal matrix, in the order of :attr:`Spectra.products`
PAIRS = ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2))


def spectra(Xi: np.ndarray, Xj: np.ndarray) -> Spectra:
    """The :class:`Spectra` of samples ``Xi, Xj`` (N, n) (NaN: the design does not assemble there)."""
    Xi, Xj = np.asarray(Xi, complex), np.asarray(Xj, complex)
    missing = ~(np.isfinite(Xi) & np.isfinite(Xj))
    Xi, D = np.where(missing, 0, Xi), np.where(missing, 0, Xj - Xi)
    B = np.stack([np.ones_like(Xi), Xi, D])
    products = np.fft.fft(np.stack([np.conj(B[i]) * B[j] for i, j in PAIRS]), axis=-1)
    return Spectra(products, np.fft.fft(np.conj(B), axis=-1), np.fft.fft(missing.astype(float), axis=-1))


def fit_shifts(
    Xi: np.ndarray,
    Xj: np.ndarray,
    T: np.ndarray,
    width: int | None = None,
    directions: tuple[int, ...] = (1, -1),
    spec: Spectra | None = None,
) -> TracerFit:
    """The best ``c``, placement and cyclic shift for targets ``T`` (m,) on samples ``Xi, Xj`` (N, n) of a turn.

    Target ``k`` goes to sample ``(floor(k width / m) + s) mod n`` (``width``: samples the
    targets span, default ``n``: a closed curve over the whole turn); NaN samples (the design
    does not assemble) are never matched. ``spec``: the samples' :func:`spectra` when already
    taken (a partial fit tries several widths). See the module's description.
    """
    T = np.asarray(T, complex)
    N, n = np.shape(Xi)
    m = len(T)
    sp = spectra(Xi, Xj) if spec is None else spec
    width = n if width is None else int(width)
    p = (np.arange(m) * width) // m
    spread = np.fft.fft(np.bincount(p, minlength=n).astype(complex))  # w
    bad = _corr(spread, sp.missing).real > 0.5  # (N, n)
    upper = _corr(spread, sp.products)  # (6, N, n)
    G = np.empty((N, n, 3, 3), complex)
    for k, (i, j) in enumerate(PAIRS):
        G[:, :, i, j] = upper[k]
        G[:, :, j, i] = np.conj(upper[k])
    best: TracerFit | None = None
    inverse = _Inverse3(G)  # the same normal matrices for both directions
    for d in directions:
        Td = T if d > 0 else T[::-1]
        t = np.fft.fft(np.bincount(p, weights=Td.real, minlength=n) + 1j * np.bincount(p, weights=Td.imag, minlength=n))
        r = np.moveaxis(_corr(t, sp.rows), 0, -1)  # (N, n, 3)
        u, sse = inverse.solve(r, float(np.sum(np.abs(T) ** 2)))
        sse = np.where(bad, np.inf, sse)
        s = np.argmin(sse, axis=1)
        rows = np.arange(N)
        f = _placed(u[rows, s], sse[rows, s], s, np.full(N, d))
        best = f if best is None else _better(best, f)
    assert best is not None
    return best


def _corr(Ff: np.ndarray, Fg: np.ndarray) -> np.ndarray:
    """``sum_p f_p g_{p+s}`` over the shifts ``s``, from ``fft(f)`` (n,) and ``fft(g)`` (N, n).

    Its DFT is ``fft(g) * conj(fft(conj f))``.
    """
    return np.fft.ifft(Fg * np.conj(_conj_fft(Ff)), axis=-1)


def _conj_fft(Ff: np.ndarray) -> np.ndarray:
    """``fft(conj f)`` from ``fft(f)``: ``conj(F[-k mod n])``."""
    out: np.ndarray = np.conj(np.roll(Ff[..., ::-1], 1, axis=-1))
    return out


def _ridge(G: np.ndarray) -> np.ndarray:
    """The ridge added to the normal matrices ``G`` (..., 3, 3): ``RIDGE`` times the trace (1 where it is 0)."""
    scale = np.einsum("...ii->...", G).real
    out: np.ndarray = RIDGE * np.where(scale > 0, scale, 1.0)
    return out


def _residual(r: np.ndarray, u: np.ndarray, tt: float | np.ndarray, lam: np.ndarray) -> np.ndarray:
    """``|B u - T|^2`` of the ridged solution ``u`` of ``(G + lam) u = r``, clipped at 0."""
    sse = tt - np.einsum("...p,...p->...", np.conj(r), u).real - lam * np.sum(np.abs(u) ** 2, axis=-1)
    out: np.ndarray = np.maximum(_finite(sse), 0.0)
    return out


class _Inverse3:
    """``G + lam`` (..., 3, 3), ``lam`` a tiny ridge (:func:`_ridge`), inverted by its adjugate once, for several
    right-hand sides: NumPy's batched LAPACK solve costs microseconds per 3 x 3 system, the adjugate's products a
    fraction of one. The residual reported is ``|B u - T|^2 = |T|^2 - Re(r^H u) - lam |u|^2`` (:func:`_residual`):
    ``|T|^2 - Re(r^H u)`` alone also counts the ridge's own term, 9 % of the residual on a basis of condition
    2.5e5."""

    def __init__(self, G: np.ndarray) -> None:
        self.lam = _ridge(G)
        g = G + self.lam[..., None, None] * np.eye(3)
        adj = np.empty_like(g)
        for i in range(3):
            for j in range(3):  # adj[i, j] = the cofactor of g[j, i]: rows p, q other than j, columns s, t other than i
                (p, q), (s, t) = [k for k in range(3) if k != j], [k for k in range(3) if k != i]
                minor = g[..., p, s] * g[..., q, t] - g[..., p, t] * g[..., q, s]
                adj[..., i, j] = -minor if (i + j) % 2 else minor
        det = np.einsum("...k,...k->...", g[..., 0, :], adj[..., :, 0])
        self.g, self.inv = g, adj / det[..., None, None]

    def solve(self, r: np.ndarray, tt: float | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``u = G^-1 r``, refined once on its own residual ``r - G u`` (the adjugate alone drifted 1e-5 of
        ``|T|^2`` from least squares on a nearly singular basis), and the residual ``|B u - T|^2``."""
        u = np.einsum("...ij,...j->...i", self.inv, r)
        u += np.einsum("...ij,...j->...i", self.inv, r - np.einsum("...ij,...j->...i", self.g, u))
        return u, _residual(r, u, tt, self.lam)


def _placed(u: np.ndarray, sse: np.ndarray, shift: np.ndarray, direction: np.ndarray) -> TracerFit:
    """``(a, b, e)`` as a fit: ``c = e / b`` (inf residual where ``b`` vanishes)."""
    a, b, e = u[..., 0], u[..., 1], u[..., 2]
    ok = np.abs(b) > 1e-12 * (np.abs(a) + np.abs(e) + 1e-300)
    c = np.where(ok, e / np.where(ok, b, 1.0), 0.0)
    return TracerFit(c, a, b, np.where(ok, sse, np.inf), np.asarray(shift), np.asarray(direction))


def _better(x: TracerFit, y: TracerFit) -> TracerFit:
    """Per design, the fit with the smaller residual."""
    take = y.sse < x.sse
    return TracerFit(*(np.where(take, getattr(y, f), getattr(x, f)) for f in TracerFit.__dataclass_fields__))


def _finite(v: np.ndarray) -> np.ndarray:
    return np.where(np.isfinite(v), v, np.inf)


def chords_to(P: np.ndarray, window: np.ndarray, T: np.ndarray, k: np.ndarray) -> np.ndarray:
    """Squared distance (N, m) from each target to the two chords of the curve at its nearest sample ``k``: the
    curve is ``P``'s samples in their order, an open polyline (``window``: the samples it is made of).

    The samples are coarse (a chord is ~1/100 of the curve): the distance to a sample alone
    would floor the error at about half a chord.
    """
    N, n = P.shape
    rows = np.arange(N)[:, None]
    best = np.full(k.shape, np.inf)
    for step in (-1, 1):
        k2 = np.clip(k + step, 0, n - 1)
        ok = window[rows, k] & window[rows, k2] & (k2 != k)
        a, b = P[rows, k], P[rows, k2]
        ab = b - a
        t = np.clip(((np.conj(ab) * (T[None, :] - a)).real) / np.maximum(np.abs(ab) ** 2, 1e-300), 0.0, 1.0)
        d = np.abs(a + t * ab - T[None, :]) ** 2
        best = np.where(ok, np.minimum(best, d), best)
    return best
