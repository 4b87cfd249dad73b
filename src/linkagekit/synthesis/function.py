r"""Function generation: a four-bar whose output angle follows its input angle at given pairs.

The four-bar: ground pivots ``A = 0`` and ``B = d`` on the ground line (the +x axis), crank
``AC`` of length ``a`` at the input angle ``phi``, output ``BD`` of length ``c`` at the
output angle ``psi``, coupler ``CD`` of length ``b``.  Closing the loop,
``|d + c e^{i psi} - a e^{i phi}|^2 = b^2``, divided by ``2ac``, is Freudenstein's equation

.. math:: K_1 \cos\psi - K_2 \cos\phi + K_3 = \cos(\phi - \psi),\quad
          K_1 = d/a,\ K_2 = d/c,\ K_3 = (a^2 - b^2 + c^2 + d^2) / (2ac),

linear in ``K``: three pairs fix it (:func:`freudenstein_exact`), more are fitted by least
squares of its residual (:func:`freudenstein_lsq`, the textbooks' method).  The output angle
of a design at an input (:func:`output_angle`) is ``psi = theta + sigma arccos(R / r)``, where
``r e^{i theta} = B - C`` and ``R = (b^2 - c^2 - r^2) / (2c)``; ``sigma = +1`` puts ``D`` to the
left of the line from ``C`` to ``B``.  A design meets the pairs on one branch when it
assembles at every input between the first and the last pair (:func:`assembles_between`,
exact: ``|B - C|^2 = a^2 + d^2 - 2ad cos phi`` must stay within ``[(b - c)^2, (b + c)^2]``).
:func:`solve` then minimises the largest output-angle error (minimax) from least-squares starts.

Examples
--------
Three pairs are met exactly:

>>> import numpy as np
>>> from linkagekit.synthesis.function import solve
>>> fit = solve([30, 75, 135], [75, 90, 135])
>>> bool(fit.max_error < 1e-9), fit.method, fit.branch
(True, 'exact', 1)
"""

from __future__ import annotations

import itertools
import math
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from ..checks import FourBar, grashof
from ..errors import InputError, shorten
from ..geometry import BoolArray, FloatArray, solve_each
from .base import Objective, Score, digest
from .targets import _csv_cells, _read_text

if TYPE_CHECKING:
    from ..model import Mechanism

#: the error (degrees) that stands for "does not assemble there" in a search
UNASSEMBLED = 360.0
#: offsets tried per angle scale when both are free (a grid of OFFSET_GRID^2 Freudenstein fits)
OFFSET_GRID = 36
#: exact Freudenstein fits of triples of pairs tried as starts (all triples when there are no more)
TRIPLES = 400
#: least-squares starts polished by the minimax step
POLISH_STARTS = 6


def freudenstein_system(x: FloatArray, y: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Freudenstein's linear system ``M K = r`` for inputs ``x`` and outputs ``y`` (radians, ``(..., n)``).

    ``M = [cos y, -cos x, 1]`` (``(..., n, 3)``) and ``r = cos(x - y)`` (``(..., n)``).

    >>> M, r = freudenstein_system(np.radians([30.0]), np.radians([75.0]))
    >>> np.round(M, 4).tolist(), np.round(r, 4).tolist()
    ([[0.2588, -0.866, 1.0]], [0.7071])
    """
    x, y = np.asarray(x, float), np.asarray(y, float)
    M = np.stack([np.cos(y), -np.cos(x), np.ones_like(x)], axis=-1)
    return M, np.cos(x - y)


def freudenstein_exact(x: FloatArray, y: FloatArray) -> FloatArray:
    """``K`` (``(..., 3)``) of the four-bar that meets three pairs exactly (radians, ``(..., 3)``)."""
    M, r = freudenstein_system(x, y)
    return solve_each(M, r)


def freudenstein_lsq(x: FloatArray, y: FloatArray) -> FloatArray:
    """``K`` (``(..., 3)``) minimising the sum of squared Freudenstein residuals, batched over ``...``.

    The normal matrix is singular when the outputs are the inputs, or their negatives (the ``cos psi``
    and ``cos phi`` columns are then equal): a whole family of ``K`` fits, the parallelograms among
    them.  Its minimum-norm member (:func:`~linkagekit.geometry.solve_each`) is one more start, scored
    like the others; the polish and the generic starts find the rest.

    >>> x = np.radians([0.0, 30.0, 60.0])
    >>> np.round(freudenstein_lsq(x, x), 9).tolist()  # K1 = K2 is free: the smallest is 0
    [0.0, 0.0, 1.0]
    """
    M, r = freudenstein_system(x, y)
    Mt = np.swapaxes(M, -1, -2)
    return solve_each(Mt @ M, (Mt @ r[..., None])[..., 0])


def lengths_from_k(K: FloatArray, d: float = 1.0) -> FloatArray:
    """Link lengths ``(a, b, c)`` (``(..., 3)``) of ``K``; NaN where a length would be negative or imaginary.

    >>> np.round(lengths_from_k(np.array([2.0, 1.0, 1.25])), 6).tolist()
    [0.5, 1.0, 1.0]
    """
    K = np.asarray(K, float)
    with np.errstate(divide="ignore", invalid="ignore"):
        a, c = d / K[..., 0], d / K[..., 1]
        b2 = a * a + c * c + d * d - 2 * a * c * K[..., 2]
        abc = np.stack([a, np.sqrt(b2), c], axis=-1)
    bad = (a <= 0) | (c <= 0) | ~(b2 > 0)
    abc[bad] = np.nan
    return abc


def output_angle(abc: FloatArray, d: float, phi: FloatArray, sigma: float | FloatArray) -> FloatArray:
    """Output angle ``psi`` (radians) of designs ``abc`` (``(..., 3)``) at inputs ``phi`` (``(..., n)``).

    On branch ``sigma`` (+1 or -1, broadcast against ``abc[..., 0]``).

    NaN where the design does not assemble; ``abc[..., None, k]`` broadcasts against ``phi``.

    >>> np.degrees(output_angle(np.array([1.0, 1.0, 1.0]), 1.0, np.radians([90.0]), 1)).round(9).tolist()
    [90.0]
    """
    abc = np.asarray(abc, float)
    a, b, c = (abc[..., k, None] for k in range(3))
    p, q = d - a * np.cos(phi), -a * np.sin(phi)
    r2 = p * p + q * q
    with np.errstate(invalid="ignore", divide="ignore"):
        cosine = (b * b - c * c - r2) / (2 * c * np.sqrt(r2))
        out: FloatArray = np.arctan2(q, p) + np.asarray(sigma)[..., None] * np.arccos(cosine)
    return out


def wrap_deg(angle: FloatArray) -> FloatArray:
    """Angles (degrees) wrapped into ``[-180, 180)``.

    >>> wrap_deg(np.array([190.0, -190.0])).tolist()
    [-170.0, 170.0]
    """
    out: FloatArray = (np.asarray(angle, float) + 180.0) % 360.0 - 180.0
    return out


def angle_errors(
    abc: FloatArray,
    d: float,
    x: FloatArray,
    y: FloatArray,
    sigma: float | FloatArray,
    offsets: FloatArray | None = None,
) -> FloatArray:
    """Output-angle errors (degrees, ``(..., n)``) at pairs ``x, y`` (radians); NaN where not assembled.

    ``offsets`` (``(..., 2)``, radians) are added to the inputs and the outputs.
    """
    if offsets is not None:
        off = np.asarray(offsets, float)
        x, y = x + off[..., 0, None], y + off[..., 1, None]
    return wrap_deg(np.degrees(output_angle(abc, d, x, sigma) - y))


def assembly_margin(
    abc: FloatArray, d: float, x: FloatArray, offsets: FloatArray | None = None, min_transmission: float = 0.0
) -> FloatArray:
    """By how much (over ``d^2``) each design assembles at every input from the first to the last of ``x``.

    Negative where it does not somewhere: :func:`assembly_shortfall` is its negative part.
    Exact: on ``[x_1, x_n]`` (radians) the squared distance ``a^2 + d^2 - 2ad cos phi`` from
    ``C`` to ``B`` is extreme where ``cos phi`` is, at an end or at a multiple of pi inside; it
    must stay in ``[(b - c)^2, (b + c)^2]``; the margin is the smaller distance to those bounds.
    With ``min_transmission`` (degrees) the transmission angle ``mu`` must also stay within
    ``[min, 180 - min]``: ``|b^2 + c^2 - r^2| <= 2bc cos(min)``, the same test with narrower bounds.
    """
    abc = np.asarray(abc, float)
    lo, hi = np.min(x, axis=-1), np.max(x, axis=-1)
    if offsets is not None:
        off = np.asarray(offsets, float)[..., 0]
        lo, hi = lo + off, hi + off
    cmax = np.where(np.floor(hi / (2 * np.pi)) * 2 * np.pi >= lo, 1.0, np.maximum(np.cos(lo), np.cos(hi)))
    odd = np.floor((hi - np.pi) / (2 * np.pi)) * 2 * np.pi + np.pi
    cmin = np.where(odd >= lo, -1.0, np.minimum(np.cos(lo), np.cos(hi)))
    a, b, c = abc[..., 0], abc[..., 1], abc[..., 2]
    near, far = a * a + d * d - 2 * a * d * cmax, a * a + d * d - 2 * a * d * cmin
    k = 2 * b * c * math.cos(math.radians(min_transmission))
    out: FloatArray = np.minimum(near - (b * b + c * c - k), (b * b + c * c + k) - far) / (d * d)
    return out


def assembly_shortfall(
    abc: FloatArray, d: float, x: FloatArray, offsets: FloatArray | None = None, min_transmission: float = 0.0
) -> FloatArray:
    """How far (over ``d^2``) each design is from assembling from the first to the last of ``x``: 0 where it does."""
    out: FloatArray = np.maximum(-assembly_margin(abc, d, x, offsets, min_transmission), 0.0)
    return out


def assembles_between(
    abc: FloatArray, d: float, x: FloatArray, offsets: FloatArray | None = None, min_transmission: float = 0.0
) -> BoolArray:
    """Whether each design assembles at every input from the first to the last of ``x`` (radians, monotone).

    :func:`assembly_shortfall` is 0 (to 1e-12 of the squared sizes).  Returns a bool array ``(...)``.

    >>> bool(assembles_between(np.array([0.2, 1.0, 1.0]), 1.0, np.radians([0.0, 350.0])))
    True
    >>> bool(assembles_between(np.array([1.0, 0.5, 0.6]), 1.0, np.radians([-10.0, 10.0])))
    False
    """
    abc = np.asarray(abc, float)
    tol = 1e-12 * (np.sum(abc, axis=-1) + d) ** 2 / (d * d)
    ok: BoolArray = assembly_shortfall(abc, d, x, offsets, min_transmission) <= tol
    return ok


def transmission_range(abc: FloatArray, d: float, x: FloatArray) -> tuple[float, float]:
    """Smallest and largest transmission angle (degrees, in [0, 180]) over inputs ``x[0]..x[-1]`` (radians).

    The angle at ``D`` between coupler and output: ``cos mu = (b^2 + c^2 - |BC|^2) / (2bc)``,
    extreme where ``|BC|`` is, so the ends and the multiples of pi inside are enough.
    """
    a, b, c = (float(v) for v in abc)
    lo, hi = float(np.min(x)), float(np.max(x))
    inside = [k * math.pi for k in range(math.ceil(lo / math.pi), math.floor(hi / math.pi) + 1)]
    phi = np.array([lo, hi, *inside])
    bc2 = a * a + d * d - 2 * a * d * np.cos(phi)
    mu = np.degrees(np.arccos(np.clip((b * b + c * c - bc2) / (2 * b * c), -1.0, 1.0)))
    return float(mu.min()), float(mu.max())


# ---------------------------------------------------------------------- the pairs
#: the most pairs function generation takes: the Freudenstein starts and their minimax polish (SLSQP with two
#: constraints per pair) run before the search's clock is read (10000 pairs ran 12 to 24 s of a 3 s budget)
MAX_PAIRS = 1000


def check_pairs(inputs: ArrayLike, outputs: ArrayLike, source: str = "pairs") -> tuple[FloatArray, FloatArray]:
    """The pairs as radians, checked: 3 to :data:`MAX_PAIRS`, finite, within [-360, 360] deg, inputs strictly monotone.

    The crank turns through the pairs in their order, so the inputs must increase (or decrease)
    along the list and span less than a turn; the outputs must not all be equal.
    Raises :class:`~linkagekit.errors.InputError`.

    >>> check_pairs([1, 2], [3, 4], "p.csv")
    Traceback (most recent call last):
    ...
    linkagekit.errors.InputError: p.csv: function generation needs at least 3 pairs, got 2
    """
    x, y = np.asarray(inputs, float).ravel(), np.asarray(outputs, float).ravel()
    if len(x) != len(y):
        raise InputError(f"{source}: {len(x)} inputs but {len(y)} outputs")
    if len(x) < 3:
        raise InputError(f"{source}: function generation needs at least 3 pairs, got {len(x)}")
    if len(x) > MAX_PAIRS:
        raise InputError(
            f"{source}: {len(x)} pairs; function generation takes at most {MAX_PAIRS} (every polish step costs "
            "in proportion, before the clock is read): give every k-th pair"
        )
    for name, v in (("input", x), ("output", y)):
        bad = np.flatnonzero(~np.isfinite(v) | (np.abs(v) > 360.0))
        if len(bad):
            raise InputError(f"{source}: pair {bad[0] + 1}: {name} {v[bad[0]]} is not an angle in [-360, 360] deg")
    step = np.diff(x)
    if np.any(step == 0):
        raise InputError(
            f"{source}: pair {int(np.flatnonzero(step == 0)[0]) + 2}: duplicate input {x[1:][step == 0][0]}"
        )
    if not (np.all(step > 0) or np.all(step < 0)):
        row = int(np.flatnonzero(np.sign(step) != np.sign(step[0]))[0]) + 2
        raise InputError(f"{source}: pair {row}: the inputs must increase (or decrease) along the list")
    if abs(x[-1] - x[0]) >= 360.0:
        raise InputError(f"{source}: the inputs span {abs(x[-1] - x[0])} deg; a crank meets them within one turn")
    if np.all(y == y[0]):  # a four-bar's output turns whenever its crank does (or it is folded onto a pivot)
        raise InputError(f"{source}: every output is {y[0]:g} deg; a constant output needs no mechanism")
    return np.radians(x), np.radians(y)


def read_pairs(path: str | Path) -> tuple[FloatArray, FloatArray]:
    """Inputs and outputs (degrees) of a CSV file with the header ``input,output``, checked by :func:`check_pairs`.

    A message names the file as given and the line of the file (``sub/f.csv: line 6: ...``), as the
    path and motion readers' do.
    """
    name = os.fspath(path)
    rows = list(_csv_cells(_read_text(Path(path), name), name))
    header = [c.lower() for c in rows[0][1]] if rows else []
    if sorted(header) != ["input", "output"]:
        raise InputError(f"{name}: expected the header 'input,output'")
    cols = [header.index("input"), header.index("output")]
    values = []
    for number, row in rows[1:]:
        if len(row) != 2:
            raise InputError(f"{name}: line {number}: expected 2 values (input,output), got {len(row)}")
        try:
            values.append([float(row[k]) for k in cols])
        except ValueError:
            raise InputError(f"{name}: line {number}: {shorten(','.join(row), 60)!r} is not two numbers") from None
    table = np.array(values, float).reshape(-1, 2)
    check_pairs(table[:, 0], table[:, 1], name)
    return table[:, 0], table[:, 1]


# ---------------------------------------------------------------------- designs as vectors
#: a valid design's shortest link (the ground included) is at least this fraction of its longest: a crank of
#: 2e-8 ground lengths (kept at 89 deg transmission by barely moving) is no mechanism
MIN_LINK_RATIO = 1e-3


@dataclass(frozen=True)
class _Pairs:
    """Pairs (radians), the ground length, whether the offsets are free, and the branch."""

    x: FloatArray
    y: FloatArray
    d: float
    free: bool
    mu: float = 0.0

    def unpack(self, z: FloatArray) -> tuple[FloatArray, FloatArray | None]:
        """``abc`` and offsets of design vectors ``z`` = ``[ln a/d, ln b/d, ln c/d(, phi0, psi0)]``."""
        z = np.asarray(z, float)
        return self.d * np.exp(np.clip(z[..., :3], -30.0, 30.0)), (z[..., 3:5] if self.free else None)

    def pack(self, abc: FloatArray, offsets: FloatArray | None) -> FloatArray:
        """The design vectors of ``abc`` (``(..., 3)``) and offsets (``(..., 2)``)."""
        z = np.log(np.asarray(abc, float) / self.d)
        if self.free and offsets is not None:
            z = np.concatenate([z, np.broadcast_to(offsets, (*z.shape[:-1], 2))], axis=-1)
        return z

    def errors(self, z: FloatArray, sigma: float | FloatArray) -> FloatArray:
        """Output-angle errors (degrees), UNASSEMBLED where a design does not assemble."""
        abc, off = self.unpack(z)
        e = angle_errors(abc, self.d, self.x, self.y, sigma, off)
        return np.where(np.isfinite(e), e, UNASSEMBLED)

    def margin(self, z: FloatArray) -> FloatArray:
        """:func:`assembly_margin` of design vectors ``z`` (NaN lengths: -1)."""
        abc, off = self.unpack(z)
        m = assembly_margin(abc, self.d, self.x, off, self.mu)
        out: FloatArray = np.where(np.isfinite(m), m, -1.0)
        return out

    def valid(self, z: FloatArray) -> BoolArray:
        """Whether each design assembles over the whole path from the first pair to the last, and is buildable."""
        abc, off = self.unpack(z)
        ok: BoolArray = assembles_between(abc, self.d, self.x, off, self.mu) & np.all(np.isfinite(abc), axis=-1)
        return ok & self.buildable(z)

    def buildable(self, z: FloatArray) -> BoolArray:
        """Whether no link of each design (the ground included) is shorter than :data:`MIN_LINK_RATIO` of the
        longest."""
        abc = self.unpack(z)[0]
        longest = np.maximum(np.max(abc, axis=-1), self.d)
        out: BoolArray = np.minimum(np.min(abc, axis=-1), self.d) >= MIN_LINK_RATIO * longest
        return out

    def penalty(self, z: FloatArray) -> FloatArray:
        """What a design's score adds to its largest error: nothing when valid; an unbuildable one ranks last."""
        out: FloatArray = 2 * UNASSEMBLED * ((~self.valid(z)).astype(float) + (~self.buildable(z)).astype(float))
        return out


# ---------------------------------------------------------------------- starts and polish
def _offset_grid(n: int) -> FloatArray:
    """``n^2`` offset pairs (radians) on a regular grid of the torus."""
    g = np.arange(n) * (2 * np.pi / n)
    out: FloatArray = np.stack(np.meshgrid(g, g, indexing="ij"), axis=-1).reshape(-1, 2)
    return out


def _freudenstein_designs(p: _Pairs) -> tuple[FloatArray, FloatArray | None]:
    """Freudenstein fits: of all pairs, and exact fits of triples (fixed scales) or of offset grid points (free)."""
    n = len(p.x)
    if p.free:
        off = _offset_grid(OFFSET_GRID)
        K = freudenstein_lsq(p.x + off[:, :1], p.y + off[:, 1:])
        return lengths_from_k(K, p.d), off
    if math.comb(n, 3) <= TRIPLES:
        triples = np.array(list(itertools.combinations(range(n), 3)))
    else:  # a fixed sample, spread over all pairs
        triples = np.sort(np.argsort(np.random.default_rng(0).random((TRIPLES, n)), axis=1)[:, :3], axis=1)
    K = np.concatenate([freudenstein_lsq(p.x, p.y)[None], freudenstein_exact(p.x[triples], p.y[triples])])
    return lengths_from_k(K, p.d), None


def _generic(p: _Pairs) -> FloatArray:
    """27 design vectors: each of crank, coupler and output 0.5, 1 or 2 ground lengths (offsets 0)."""
    ratios = np.log(np.array(list(itertools.product([0.5, 1.0, 2.0], repeat=3))))
    out: FloatArray = np.concatenate([ratios, np.zeros((len(ratios), 2))], axis=1) if p.free else ratios
    return out


def _starts(p: _Pairs) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Every Freudenstein fit on both branches: design vectors, branches and scores (max error, invalid last)."""
    abc, off = _freudenstein_designs(p)
    keep = np.all(np.isfinite(abc), axis=-1)
    z = p.pack(abc[keep], None if off is None else off[keep])
    z = np.concatenate([z, _generic(p)])  # when no fit has positive lengths, these still start the polish
    z = np.concatenate([z, z])
    sigma = np.repeat([1.0, -1.0], len(z) // 2)
    score = np.max(np.abs(p.errors(z, sigma)), axis=-1) + p.penalty(z)
    order = np.argsort(score, kind="stable")
    return z[order], sigma[order], score[order]


def _score(p: _Pairs, z: FloatArray, sigma: float) -> float:
    """The largest absolute error of one design (degrees), penalised when not valid (:meth:`_Pairs.penalty`)."""
    return float(np.max(np.abs(p.errors(z, sigma))) + p.penalty(z))


#: scipy's finite-difference step, sqrt(eps): SLSQP's absolute one, and the relative one of its "2-point" differences
SLSQP_STEP = RELATIVE_STEP = float(np.sqrt(np.finfo(float).eps))


def forward_jacobian(f: Callable[[FloatArray], FloatArray], x: FloatArray, h: FloatArray) -> FloatArray:
    """The forward differences of ``f`` at ``x`` with steps ``h`` (m, n), its rows at ``x`` and at each ``x + h_i e_i``
    evaluated in one call (``f`` takes points as rows): scipy's "2-point" differences (the step taken as
    ``(x_i + h_i) - x_i``; a relative one where ``h_i`` is lost to rounding), one call of ``f`` instead of ``n + 1``.

    >>> f = lambda X: np.stack([X[..., 0] * X[..., 1], X[..., 0]], -1)
    >>> forward_jacobian(f, np.array([2.0, 3.0]), np.full(2, 1e-6)).round(6)
    array([[3., 2.],
           [1., 0.]])
    """
    h = np.where((x + h) - x == 0, _relative_steps(x), h)  # scipy's too: a step lost to rounding at a large x
    X = np.repeat(x[None], len(x) + 1, axis=0)
    X[1:][np.diag_indices(len(x))] += h
    F = np.asarray(f(X), float).reshape(len(x) + 1, -1)
    dx = X[1:][np.diag_indices(len(x))] - x  # the steps taken
    out: FloatArray = ((F[1:] - F[0]) / dx[:, None]).T
    return out


def _relative_steps(x: FloatArray) -> FloatArray:
    """scipy's "2-point" steps at ``x`` by default: ``sqrt(eps) max(1, |x|)``, signed as ``x`` (+ at 0)."""
    out: FloatArray = RELATIVE_STEP * np.where(x >= 0, 1.0, -1.0) * np.maximum(1.0, np.abs(x))
    return out


def _least_squares(p: _Pairs, z: FloatArray, sigma: float) -> FloatArray:
    """Least squares of the output-angle errors from ``z`` (the Jacobian by forward differences in one batch)."""
    from scipy.optimize import least_squares

    def errors(v: FloatArray) -> FloatArray:
        return p.errors(v, sigma)

    out = least_squares(
        errors, z, jac=lambda v: forward_jacobian(errors, v, _relative_steps(v)), xtol=1e-15, ftol=1e-15, gtol=1e-15,
        max_nfev=400,
    )  # fmt: skip
    x: FloatArray = out.x
    return x


def _minimax(p: _Pairs, z: FloatArray, sigma: float) -> FloatArray:
    """Minimise the largest absolute error from ``z``: ``min t`` s.t. ``-t <= e_i(z) <= t`` (SLSQP, epigraph form).

    One more constraint keeps the design assembled from the first pair to the last (its
    :func:`assembly_margin` is not negative). The constraints' Jacobians by forward differences
    (SLSQP's own steps) in one batch each.
    """
    from scipy.optimize import minimize

    last: list[Any] = [None, None]  # SLSQP asks for both bounds at each point: the errors once

    def errors(V: FloatArray) -> FloatArray:
        key = V.tobytes() + bytes(V.shape)
        if last[0] != key:
            last[:] = [key, p.errors(V[..., :-1], sigma)]
        out: FloatArray = last[1]
        return out

    def above(V: FloatArray) -> FloatArray:
        return V[..., -1:] - errors(V)

    def below(V: FloatArray) -> FloatArray:
        return V[..., -1:] + errors(V)

    def margin(V: FloatArray) -> FloatArray:
        return np.asarray(p.margin(V[..., :-1]))[..., None]

    t0 = float(np.max(np.abs(p.errors(z, sigma))))
    cons = [
        {"type": "ineq", "fun": f, "jac": lambda v, f=f: forward_jacobian(f, v, np.full(len(v), SLSQP_STEP))}
        for f in (above, below, margin)
    ]
    res = minimize(
        lambda v: v[-1], np.r_[z, t0], method="SLSQP", constraints=cons, options={"ftol": 1e-15, "maxiter": 300}
    )
    x: FloatArray = res.x[:-1]
    return x


def _polish(p: _Pairs, z: FloatArray, sigma: float, method: str) -> tuple[FloatArray, str]:
    """``z`` polished by ``method``'s steps: least squares of the angle errors, then minimax from there and from
    ``z``.

    ``least-squares`` returns its own answer (when it is valid); ``minimax`` the best of the four.  The minimax
    starts from the least squares' answer even when it is not valid: its margin constraint can bring it back, and
    from an invalid ``z`` alone SLSQP's answer hung on rounding (a bound of 80 deg on five pairs: valid with two
    BLAS threads, invalid with one).
    """
    cands: list[tuple[FloatArray, str]] = [(z, "freudenstein")]
    zl = z
    if method != "freudenstein":
        zl = _least_squares(p, z, sigma)
        if bool(p.valid(zl)):
            cands.append((zl, "least-squares"))
    if method == "least-squares":
        return cands[-1]
    if method == "minimax":
        cands += [(_minimax(p, start, sigma), "minimax") for start in (zl, z)]
    return min(cands, key=lambda c: _score(p, c[0], sigma))


# ---------------------------------------------------------------------- the answer
#: the search methods, from the textbooks' to the command's default
METHODS = ("freudenstein", "least-squares", "minimax")


@dataclass(frozen=True)
class FunctionFit:
    """A four-bar for function generation (:func:`solve`).

    Attributes
    ----------
    lengths : tuple of float
        Crank ``a``, coupler ``b``, output ``c`` and ground ``d`` (the ground length's unit).
    branch : int
        +1 when the output joint ``D`` lies left of the line from the crank joint ``C`` to
        the output pivot ``B``, -1 when right; the same at every pair.
    offsets : tuple of float
        Degrees added to every input and to every output (0, 0 unless the offsets are free), in (-180, 180].
    inputs, outputs, errors : ndarray (n,)
        The pairs (degrees, as given) and the output-angle error at each (degrees).
    method : str
        ``"exact"`` (three pairs met by Freudenstein's equation) or the step that gave the
        design: ``"freudenstein"`` (least squares of its residual), ``"least-squares"`` (of
        the angle errors) or ``"minimax"``.
    valid : bool
        It assembles at every input from the first pair to the last (one branch, no gap).
    grashof : str
        The Grashof type (:func:`linkagekit.checks.grashof`).
    transmission : tuple of float
        Smallest and largest transmission angle (degrees) from the first pair to the last.
    score : float
        What it was chosen by among the polished designs: the largest absolute error (degrees), plus a
        penalty when it is not valid (of two answers, the lower is the better).
    """

    lengths: tuple[float, float, float, float]
    branch: int
    offsets: tuple[float, float]
    inputs: FloatArray
    outputs: FloatArray
    errors: FloatArray
    method: str
    valid: bool
    grashof: str
    transmission: tuple[float, float]
    score: float = float("nan")

    @property
    def max_error(self) -> float:
        """The largest absolute output-angle error (degrees)."""
        return float(np.max(np.abs(self.errors)))

    def joints(self) -> dict[str, list[float]]:
        """The joints at the first pair: ``A`` crank pivot, ``B`` output pivot, ``C`` crank tip, ``D`` output tip."""
        a, _, c, d = self.lengths
        phi = math.radians(self.inputs[0] + self.offsets[0])
        psi = float(output_angle(np.array(self.lengths[:3]), d, np.array([phi]), self.branch)[0])
        return {
            "A": [0.0, 0.0],
            "B": [d, 0.0],
            "C": [a * math.cos(phi), a * math.sin(phi)],
            "D": [d + c * math.cos(psi), c * math.sin(psi)],
        }

    def mechanism_dict(self, unit: str = "m", samples: int = 120) -> dict[str, Any]:
        """The mechanism file (docs/mechanism-files.md) as a dictionary; the driver sweeps the pairs' inputs."""
        start, stop = (round(float(self.inputs[k] + self.offsets[0]), 9) for k in (0, -1))
        return {
            "format": "linkagekit/1",
            "name": ("" if self.valid else "INFEASIBLE ")
            + f"Function generator ({len(self.inputs)} pairs, {self.method})",
            "units": {"length": unit, "angle": "deg"},
            "joints": self.joints(),
            "links": {"ground": ["A", "B"], "crank": ["A", "C"], "coupler": ["C", "D"], "output": ["B", "D"]},
            "drivers": [
                {
                    "link": "crank",
                    "pivot": "A",
                    "toward": "C",
                    "angles": {"start": start, "stop": stop, "step": (stop - start) / samples},
                }
            ],
        }


def _direction(radians: float) -> float:
    """An offset (radians) as the angle in (-180, 180] deg it is: the search's are unwrapped (a crank written to sweep
    from 408.7 deg).

    >>> round(_direction(np.radians(408.7 - 61.1)), 9), _direction(np.radians(-180.0))
    (-12.4, 180.0)
    """
    return float(-wrap_deg(-np.degrees(radians)))  # (-180, 180]: wrap_deg's [-180, 180) turned over


def _fit(p: _Pairs, z: FloatArray, sigma: float, method: str) -> FunctionFit:
    """The :class:`FunctionFit` of design vector ``z`` on branch ``sigma``."""
    abc, off = p.unpack(z)
    offsets = (0.0, 0.0) if off is None else (_direction(off[0]), _direction(off[1]))
    a, b, c = (float(v) for v in abc)
    x = p.x + (0.0 if off is None else off[0])
    return FunctionFit(
        lengths=(a, b, c, p.d),
        branch=int(sigma),
        offsets=offsets,
        inputs=np.degrees(p.x),
        outputs=np.degrees(p.y),
        errors=angle_errors(abc, p.d, p.x, p.y, sigma, off),
        method=method,
        valid=bool(p.valid(z)),
        grashof=grashof(FourBar(0, 1, 2, 3, ground=p.d, crank=a, coupler=b, rocker=c))[0],
        transmission=transmission_range(abc, p.d, x),
        score=_score(p, z, sigma),
    )


def solve(
    inputs: ArrayLike,
    outputs: ArrayLike,
    *,
    free_offsets: bool = False,
    ground_length: float = 1.0,
    method: str = "minimax",
    source: str = "pairs",
    starts: Sequence[FloatArray] = (),
    min_transmission: float = 0.0,
    freudenstein: bool = True,
) -> FunctionFit:
    """A four-bar whose output angle meets ``outputs`` at ``inputs`` (degrees, from the ground line), on one branch.

    Three pairs with fixed scales are met exactly (Freudenstein).  Otherwise every
    Freudenstein fit (of all pairs, of each triple, or, with ``free_offsets``, of a grid of
    offsets) is tried on both branches; the best ``POLISH_STARTS`` that assemble between the
    first and the last pair are polished by ``method`` (:data:`METHODS`) and the best valid
    one is returned (an invalid one only when no start is valid).  ``starts``: more design
    vectors of :class:`FunctionObjective` (e.g. the engine's best) polished the same way.
    ``min_transmission`` (degrees): a valid design also keeps its transmission angle within
    ``[min, 180 - min]`` from the first pair to the last (default 0: it only assembles).
    ``freudenstein=False``: only ``starts`` are polished (an earlier call's answer from the Freudenstein
    starts is the same: compare the two by their ``score``).
    """
    if method not in METHODS:
        raise InputError(f"method: {method!r} is not one of {', '.join(METHODS)}")
    if not (math.isfinite(ground_length) and ground_length > 0):
        raise InputError(f"--ground-length: {ground_length} is not a positive length")
    x, y = check_pairs(inputs, outputs, source)
    if not 0 <= min_transmission < 90:
        raise InputError(f"--min-transmission: {min_transmission} is not an angle in [0, 90) deg")
    p = _Pairs(x, y, float(ground_length), bool(free_offsets), float(min_transmission))
    z, sigma, score = _starts(p)
    if len(x) == 3 and not free_offsets and score[0] < 1e-9:
        return _fit(p, z[0], sigma[0], "exact")
    todo = [(z[k], float(sigma[k])) for k in range(min(POLISH_STARTS, len(z)) if freudenstein else 0)]
    todo += [(np.asarray(v, float)[1:], 1.0 if v[0] >= 0 else -1.0) for v in starts]
    best: tuple[float, FloatArray, float, str] | None = None
    for zk, sk in todo:
        zk, label = _polish(p, zk, sk, method)
        s = _score(p, zk, sk)
        if best is None or s < best[0]:
            best = (s, zk, sk, label)
    assert best is not None
    return _fit(p, best[1], best[2], best[3])


# ---------------------------------------------------------------------- the engine's objective
#: bounds of ln(length / ground length) of the crank, the coupler and the output
LOG_RATIO = 3.0
#: the exact penalty on an assembly gap between the pairs (as path generation's)
PENALTY = 100.0


@dataclass(frozen=True)
class FunctionObjective(Objective):
    """Function generation as the synthesis engine's objective (:mod:`linkagekit.synthesis.base`).

    The design vector is ``[s, ln a/d, ln b/d, ln c/d(, phi0, psi0)]``: the branch is the sign
    of ``s``, the offsets (radians) are there only when free.  ``error`` is the largest
    absolute output-angle error in radians; ``violation`` the :func:`assembly_shortfall`
    (exact, so :meth:`check` is :meth:`score`); ``cost`` the mean squared error (radians) plus
    ``PENALTY * violation``.  The engine's answer is then polished to the minimax by :func:`solve`.

    Attributes
    ----------
    inputs, outputs : ndarray (n,)
        The pairs, radians.
    ground : float
        The ground length.
    free : bool
        Whether the two offsets are free.
    unit : str
        The length unit of the written mechanism.
    min_transmission : float
        Degrees: the transmission angle stays within ``[min, 180 - min]`` between the pairs.
    """

    inputs: FloatArray
    outputs: FloatArray
    ground: float = 1.0
    free: bool = False
    unit: str = "m"
    min_transmission: float = 0.0

    @property
    def bounds(self) -> tuple[FloatArray, FloatArray]:
        """``s`` in [-1, 1], each log ratio within ``LOG_RATIO``, each offset in [-pi, pi]."""
        hi = np.array([1.0, LOG_RATIO, LOG_RATIO, LOG_RATIO] + [np.pi, np.pi] * self.free)
        return -hi, hi

    def _pairs(self) -> _Pairs:
        x, y = np.asarray(self.inputs, float), np.asarray(self.outputs, float)
        return _Pairs(x, y, self.ground, self.free, self.min_transmission)

    def _parts(self, X: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Errors (radians, (N, n)) and violations (N,) of designs ``X``."""
        X = np.atleast_2d(np.asarray(X, float))
        p = self._pairs()
        e = np.radians(p.errors(X[:, 1:], np.where(X[:, 0] >= 0, 1.0, -1.0)))
        abc, off = p.unpack(X[:, 1:])
        v = assembly_shortfall(abc, p.d, p.x, off, p.mu)
        return e, np.where(np.isfinite(v), v, 1.0)

    def score(self, X: FloatArray) -> Score:
        """Cost, largest error (radians) and violation of designs ``X`` (N, dim)."""
        e, v = self._parts(X)
        return Score(np.mean(e * e, axis=1) + PENALTY * v, np.max(np.abs(e), axis=1), v)

    def residuals(self, X: FloatArray) -> FloatArray:
        """``e_i / sqrt(n)`` and ``sqrt(PENALTY * violation)``: the squared sum is the cost."""
        e, v = self._parts(X)
        out: FloatArray = np.concatenate([e / np.sqrt(e.shape[1]), np.sqrt(PENALTY * v)[:, None]], axis=1)
        return out

    def fingerprint(self) -> str:
        """A digest of the pairs, the ground length and the offsets' freedom."""
        x, y = np.asarray(self.inputs), np.asarray(self.outputs)
        return digest(x, y, self.ground, self.free, self.min_transmission, "function")

    def fit(self, x: FloatArray, method: str = "engine") -> FunctionFit:
        """The :class:`FunctionFit` of design vector ``x`` (dim,)."""
        x = np.asarray(x, float)
        return _fit(self._pairs(), x[1:], 1.0 if x[0] >= 0 else -1.0, method)

    def mechanism(self, x: FloatArray) -> Mechanism:
        """The four-bar of ``x`` at its first pair (links ground, crank, coupler, output)."""
        from ..model import Mechanism

        return Mechanism.from_dict(self.fit(x).mechanism_dict(self.unit))
