"""The numerical group step: joints no closed-form step can place, by Newton-Raphson.

A mechanism with no triangulation order (an Assur group of class 3 or more: a ternary
link held by three binary links, the double butterfly, many eight-bar legs) still has
groups of joints whose positions are fixed, together, by the joints already placed. The
plan finds the smallest such group (:func:`linkagekit.plan.make_plan`); this step places it.

Constraints (natural coordinates)
---------------------------------
The unknowns are the group's joints ``z_u`` (``2 m`` reals). Every link of the group,
with joints ``j0, j1, j2, ...`` (``j0``/``j1`` its first two), gives ``2 n - 3`` equations:

* ``|z_j1 - z_j0|^2 - L^2 = 0``, ``L = |s_j1 - s_j0|`` from the link's shape;
* ``z_jk - z_j0 - rho_k (z_j1 - z_j0) = 0`` (complex, two real equations), ``rho_k =
  (s_jk - s_j0) / (s_j1 - s_j0)``, for every further joint: linear, the link stays rigid
  and keeps its handedness (no mirror image, unlike a closed-form ``Place``).

The plan accepts a group only when these count ``2 m`` equations. The Jacobian is
analytic: a distance row has ``2 (z_a - z_b)`` (as ``[x, y]``) on ``a`` and its negative on
``b``; a linear row has the real form of the complex coefficient (``1`` on ``jk``,
``rho_k - 1`` on ``j0``, ``-rho_k`` on ``j1``; ``c`` acting on ``[x, y]`` is ``[[Re c,
-Im c], [Im c, Re c]]``).

Sliders
-------
A slider whose two sides are the ground, links of the group or placed links adds rows after
the links' (:class:`GroupSlider`). Its *carrier* (the ground, or a side with two joints
``c0``, ``c1``) carries the line; the other side's first joint ``k`` stays on the line
through its reference position along the slider's direction ``d`` in the carrier's frame.
With ``e = z_c1 - z_c0`` and ``A = z_c0`` (the ground: ``e = 1``, ``A = 0``), ``rho = (p_k -
s_c0) / (s_c1 - s_c0)``, ``dhat = d / (s_c1 - s_c0)`` (the ground: ``rho = p_k``, ``dhat =
d``), ``w = z_k - A - rho e`` and ``u = dhat e`` (the line's unit direction):

* line row ``Im(w conj(u)) = 0``;
* lock row ``Im(e_o conj(c e)) = 0`` when the other side has two joints ``o0``, ``o1`` too
  (``e_o = z_o1 - z_o0``, ``c = (s_o1 - s_o0) / (s_c1 - s_c0)``, the ground: ``c = s_o1 -
  s_o0``): its rotation is the carrier's (the two distance rows fix the lengths, so one row
  fixes the angle).

Gradients, written as a complex ``G`` with ``d row = Re G dx + Im G dy`` (``Im(a dz)`` has
``G = i conj(a)``, ``Im(g conj(dz))`` has ``G = -i g``): the line row has ``i u`` on ``k``,
``i conj(rho - 1) u + i w conj(dhat)`` on ``c0``, ``-i conj(rho) u - i w conj(dhat)`` on
``c1``; the lock row ``i c e`` on ``o1`` (negated on ``o0``) and ``-i e_o conj(c)`` on ``c1``
(negated on ``c0``); the ground has no columns. Both rows are bilinear, so their acceleration
terms are ``gamma = 2 Im(w' conj(u'))`` and ``2 Im(e_o' conj(c e'))`` (``w' = v_k - v_A - rho
e'``, ``u' = dhat e'``, ``e' = v_c1 - v_c0``; zero on the ground). Scales: the group's mean
link length on a line row, ``|s_o1 - s_o0|^2`` on a lock row.

Continuation
------------
Newton converges to the root nearest its start, which may belong to another assembly
mode. So the sweep is solved in order from the reference pose outwards: the samples are
sorted by the input that moves, split at the pose's input, and each half is walked away
from the pose, every sample started from the last one solved (with a linear predictor
from the two before it). A step is accepted only when Newton converges (residual below
``NEWTON_TOL`` relative), the Jacobian's determinant keeps its sign (a sign change is a
passage through a singular position: a change of mode, never silent) and no joint moves
more than ``STEP_LIMIT`` times the group's mean link length (a class-3 group has up to
three roots of one sign; over a small step Newton's root is the branch's). A step that
fails is retried, from a sample solved just before, in adaptive sub-steps (halved on
failure, doubled on success, down to ``2^-MAX_HALVINGS`` of the step), moving the known joints linearly
from the last solved sample to the target (a homotopy in the group's boundary: each
known joint moves alone, so the path is well defined). A sample still not reached is
flagged (NaN, not assembled) and the walk goes on from the last good sample. Where the
walk cannot reach a sample from the last good one (after a gap where the group does not
assemble), Newton is restarted from ``RESTARTS`` points scattered about the last good
configuration and about the held joints, for a group with one root per sign (a dyad,
with joints riding rigidly on its links: exactly the closed form's rule, one solution per
sign); the walk resumes there. A class-3 group can have three roots of one sign, so after
a gap it does not guess: its samples stay flagged until the walk reaches them by
continuation (from the pose's other side, or never; ``modes`` lists every mode there). So
the sweep never changes mode silently. Results do not depend on the order of the inputs.

Cost, at the same results
-------------------------
Three things make a walk cheaper without changing a single accepted sample or a bit of
its position (each Newton column is computed by the same operations whatever else is in
its batch, so batching is exact):

* Newton iterates only the columns still iterating (a converged column is frozen, as
  before; a column gone NaN stays NaN), with the residual and Jacobian built from index
  arrays and the Jacobian's constant linear rows built once.
* *Chains.* Along any chain of link edges between two held joints (two joints of one
  link, ``|w_p - w_q| L`` apart with ``w`` = 0, 1, ``rho_k``), the held joints are at most
  the sum of the edges apart and at least twice the longest minus the sum. A configuration
  Newton accepts keeps every edge to about ``1e-12`` of its link, so where the held joints
  break a chain's bounds by more than ``CHAIN_MARGIN`` (``1e-8``) of its lengths no Newton
  can converge: the sample is failed at once (no Newton, sub-steps or restarts), as it
  would have been after all of them. This is the gap of a dyad (two circles that do not
  meet).
* *Look-ahead.* After a failure, a design's next steps all start from the same state (its
  last good solution and the predictor before it) until one is accepted, so they do not
  depend on each other: they are solved in one batch over a window of the next samples
  (8, doubling to 256) and read from there (:class:`_Ahead`). The segments a two-level
  walk walks again start, in a gap, from one same state: their steps come from one batch.

Rates
-----
Differentiating ``Phi(z_u, z_k) = 0``: ``J_u v_u = -J_k v_k`` and ``J_u a_u = -J_k a_k -
gamma``, ``gamma = 2 |v_a - v_b|^2`` for a distance row, 0 for a linear row (and the
sliders' above). The conditioning reported with the rates is the smallest singular value of
``J_u`` with its distance rows divided by ``2 L`` and its lock rows by ``|s_o1 - s_o0|`` (so
every row has unit scale) over its largest.
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np

from .geometry import NAN_POINT, FloatArray, link_rates
from .steps import Kin, Nums, Rate, Source, Step

#: Newton stops when every residual is below this, relative (distance rows / L^2, linear rows / L)
NEWTON_TOL = 1e-12
#: Newton iterations per attempt
NEWTON_ITER = 16
#: a failed continuation step is retried in sub-steps down to 2^-MAX_HALVINGS of it
MAX_HALVINGS = 10
#: an accepted continuation step moves no joint more than this times the group's mean link length
#: (larger steps are halved: over small steps Newton's root is the branch's, not another of one sign)
STEP_LIMIT = 0.25
#: Newton starts when the walk comes back after a gap
RESTARTS = 16
#: long walks go in two levels: about this many samples walked one by one, the rest filled in at once
COARSE_SAMPLES = 256
#: ... with at least this stride
COARSE_STRIDE_MIN = 4
#: the walk goes at most this many turns of an angle driver from the pose's input (3600 sub-steps of
#: 1 degree, a few CPU-seconds): a sample farther away is not reached (NaN, not assembled)
WALK_TURNS = 10
#: ... in radians
WALK_REACH = 2 * np.pi * WALK_TURNS
#: a chain of link edges rules a sample out only beyond this margin (relative to its lengths): far
#: above what Newton's tolerance and rounding allow a converged configuration
CHAIN_MARGIN = 1e-8
#: at most this many chains between held joints are checked (and this many search steps to find them)
MAX_CHAINS, MAX_CHAIN_SEARCH = 64, 4096
#: a lost design's steps are solved ahead over this many samples at first, doubling up to the most ...
AHEAD_FIRST, AHEAD_MOST = 8, 256
#: ... and this many (design, sample) columns in one batch
AHEAD_COLUMNS = 2048


@dataclass(frozen=True)
class GroupLink:
    """One link of a group: its joints as slots (unknowns first, then knowns), base pair first."""

    name: str
    slots: tuple[int, ...]  # slot of j0, j1, j2, ... (slots < n_unknown are unknowns)
    joints: tuple[int, ...]  # the same joints as plan indices


@dataclass(frozen=True)
class GroupSlider:
    """A slider of a group: a point on a line carried by a link (or the ground), and a rotation lock.

    The *carrier* is the side of the slider that carries the line: the ground (a fixed line),
    or a link whose first two joints ``frame`` are slots of the group. The *point* is a joint
    of the other side; it stays on the line through its reference position, parallel to the
    slider's direction in the carrier's frame. When the other side is a link with two joints
    too (``lock``: its first two joints), its rotation is the carrier's (a block translates).
    """

    slider: int  # index in the file's `sliders`
    carrier: str  # the link carrying the line ("ground": a fixed line)
    frame: tuple[int, int] | None  # the carrier's first two joints as slots (None: the ground)
    frame_joints: tuple[int, int] | None  # ... as plan indices
    point: int  # the other side's joint on the line, as a slot
    point_joint: int  # ... as a plan index
    other: str  # the other side's link
    lock: tuple[int, int] | None = None  # the other side's first two joints as slots (None: no lock)
    lock_joints: tuple[int, int] | None = None  # ... as plan indices

    @property
    def n_rows(self) -> int:
        """Its equations: the line, and the lock when it has one."""
        return 1 + (self.lock is not None)


@dataclass(frozen=True)
class _SRows:
    """Where a group's slider equations sit (after the links' rows), per slider; ``-1``: none (the ground)."""

    c0: np.ndarray  # (n_sl,) the carrier's first frame slot (-1: the ground)
    c1: np.ndarray  # (n_sl,) its second
    k: np.ndarray  # (n_sl,) the point's slot
    line: np.ndarray  # (n_sl,) the row of its line equation
    locked: np.ndarray  # (n_lock,) the sliders with a lock
    o0: np.ndarray  # (n_lock,) the locked side's first slot
    o1: np.ndarray  # (n_lock,) ... second
    lock: np.ndarray  # (n_lock,) the row of the lock equation


@dataclass(frozen=True)
class _Rows:
    """Where a group's equations sit: per link a distance row, then two rows per further joint."""

    a: np.ndarray  # (n_links,) the slot of each link's j0
    b: np.ndarray  # (n_links,) ... of its j1
    dist: np.ndarray  # (n_links,) the row of its distance equation
    link: np.ndarray  # (n_lin,) the link of each further joint (in row order)
    k: np.ndarray  # (n_lin,) the further joint's slot
    lin: np.ndarray  # (n_lin,) the row of its real part (the imaginary part is the next row)


@dataclass(frozen=True)
class _Chain:
    """A chain of link edges from one held joint to another through the group's joints."""

    ends: tuple[int, int]  # the two held joints (indices into ``known``)
    edges: tuple[tuple[int, int, int], ...]  # (link, p, q): its joints at positions p and q of ``slots``


@dataclass(frozen=True)
class _Arrays:
    """A group's numbers per column as arrays: lengths (n_links, B), rhos (n_lin, B), Newton's tolerance
    per row (n_eq, B) and the (constant) linear rows of the Jacobian (B, n_eq, 2m)."""

    L: FloatArray
    R: np.ndarray
    tol: FloatArray
    J_lin: FloatArray

    def take(self, cols: np.ndarray) -> _Arrays:
        return _Arrays(self.L[:, cols], self.R[:, cols], self.tol[:, cols], self.J_lin[cols])


@dataclass
class _Walk:
    """What every step of a walk reads: the knowns at every sample and the pose's numbers, and ``out``."""

    K: np.ndarray  # (k, D, n) the known joints
    ok: np.ndarray  # (D, n) the knowns are finite, the pose solved, and no chain rules the sample out
    out: np.ndarray  # (m, D, n) the group's joints, written as they are accepted
    ref: np.ndarray  # (D,) the pose's determinant sign
    nums: Nums
    size: FloatArray  # (D,) the group's mean link length
    arrays: _Arrays  # the numbers per design as Newton reads them
    reach: tuple[FloatArray, FloatArray, FloatArray]  # (n_chains, D) each chain's (low, high, margin)


@dataclass(frozen=True)
class Group(Step):
    """Joints placed together by Newton-Raphson on the natural-coordinate constraints of their links."""

    joints: tuple[int, ...]  # the group's unknown joints (plan indices)
    known: tuple[int, ...]  # the known joints its links hold (plan indices)
    links: tuple[GroupLink, ...]
    keep_rotation: tuple[str, ...] = ()
    angular: tuple[bool, ...] = ()  # per driver: an angle (the walk's added samples are 1 degree apart)
    sliders: tuple[GroupSlider, ...] = ()

    # ------------------------------------------------------------------ numbers
    def numbers(self, src: Source) -> Nums:
        lengths, rhos, bases = [], [], []
        for gl in self.links:
            s = [src.shape(gl.name, j) for j in gl.joints]
            base = s[1] - s[0]
            bases.append(base)
            lengths.append(np.abs(base))
            with np.errstate(divide="ignore", invalid="ignore"):
                rhos.append(tuple((sk - s[0]) / base for sk in s[2:]))
        rhos.extend(self._slider_numbers(src))
        zu = np.stack([src.pose(j) for j in self.joints])  # (m, D, 1)
        zk = np.stack([src.pose(j) for j in self.known]) if self.known else np.zeros((0, *zu.shape[1:]), complex)
        return tuple(lengths), tuple(rhos), tuple(bases), zu, zk

    def _slider_numbers(self, src: Source) -> list[tuple[np.ndarray, ...]]:
        """Per slider ``(rho, dhat, c, ell)``: its line ``A + rho e`` along ``dhat e`` (``A``, ``e``: the carrier's
        first joint and base, or 0 and 1 for the ground), its lock ``e_o = c e`` and the locked side's length."""
        out: list[tuple[np.ndarray, ...]] = []
        for gs in self.sliders:
            d = src.direction(gs.slider)
            s0: Any = 0j
            base: Any = 1.0 + 0j
            if gs.frame_joints is not None:
                s0 = src.shape(gs.carrier, gs.frame_joints[0])
                base = src.shape(gs.carrier, gs.frame_joints[1]) - s0
            with np.errstate(divide="ignore", invalid="ignore"):
                rho, dhat = (src.pose(gs.point_joint) - s0) / base, d / base
                c, ell = 0 * d, 1 + 0 * d
                if gs.lock_joints is not None:
                    lo = src.shape(gs.other, gs.lock_joints[1]) - src.shape(gs.other, gs.lock_joints[0])
                    c, ell = lo / base, np.abs(lo) + 0j
            out.append((rho, dhat, c, ell))
        return out

    @property
    def dyad_like(self) -> bool:
        """One joint of the group is on two of its links, the others ride on one: two roots, one per sign.

        Only then does the walk restart after a gap (a class-3 group has up to three roots of one
        sign, so there a sample it cannot reach by continuation stays flagged).
        """
        on_two = sum(
            sum(j in gl.joints for gl in self.links) + sum(j == gs.point_joint for gs in self.sliders) >= 2
            for j in self.joints
        )
        return on_two == 1

    @property
    def n_eq(self) -> int:
        return 2 * len(self.joints)

    # ------------------------------------------------------------------ the system
    @cached_property
    def _rows(self) -> _Rows:
        a, b, dist, link, k, lin = [], [], [], [], [], []
        row = 0
        for i, gl in enumerate(self.links):
            a.append(gl.slots[0])
            b.append(gl.slots[1])
            dist.append(row)
            row += 1
            for sk in gl.slots[2:]:
                link.append(i)
                k.append(sk)
                lin.append(row)
                row += 2
        return _Rows(*(np.array(x, dtype=np.intp) for x in (a, b, dist, link, k, lin)))

    @cached_property
    def _srows(self) -> _SRows:
        row = sum(1 + 2 * (len(gl.slots) - 2) for gl in self.links)
        c0, c1, k, line, locked, o0, o1, lock = [], [], [], [], [], [], [], []
        for i, gs in enumerate(self.sliders):
            c0.append(gs.frame[0] if gs.frame else -1)
            c1.append(gs.frame[1] if gs.frame else -1)
            k.append(gs.point)
            if gs.lock is not None:
                locked.append(i)
                o0.append(gs.lock[0])
                o1.append(gs.lock[1])
                lock.append(row)
                row += 1
            line.append(row)
            row += 1
        return _SRows(*(np.array(x, dtype=np.intp) for x in (c0, c1, k, line, locked, o0, o1, lock)))

    def _frames(self, P: np.ndarray, rates: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """Each slider's carrier frame ``(A, e)`` (n_sl, B) at ``P``: its first joint and base (``0, 1`` on the
        ground); with ``rates`` (``P`` velocities or accelerations) their derivatives (``0, 0`` on the ground)."""
        sr = self._srows
        ground = (sr.c0 < 0)[:, None]
        A = np.where(ground, 0.0, P[np.maximum(sr.c0, 0)])
        e = np.where(ground, 0.0 if rates else 1.0, P[np.maximum(sr.c1, 0)] - A)
        return A, e

    def _snums(self, R: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The sliders' numbers ``(rho, dhat, c, ell)``, each (n_sl, B), from ``R`` (after the links' rhos)."""
        n = len(self._rows.k)
        return R[n::4], R[n + 1 :: 4], R[n + 2 :: 4], R[n + 3 :: 4]

    def _slider_res(self, P: np.ndarray, R: np.ndarray, res: FloatArray) -> None:
        """The sliders' residuals into ``res``: ``Im(w conj(u))`` (line) and ``Im(e_o conj(c e))`` (lock)."""
        sr = self._srows
        rho, dhat, c, _ = self._snums(R)
        A, e = self._frames(P)
        res[sr.line] = ((P[sr.k] - A - rho * e) * np.conj(dhat * e)).imag
        if len(sr.locked):
            lk = sr.locked
            res[sr.lock] = ((P[sr.o1] - P[sr.o0]) * np.conj(c[lk] * e[lk])).imag

    def _slider_jac(self, P: np.ndarray, R: np.ndarray, J: FloatArray) -> None:
        """The sliders' Jacobian rows into ``J`` (B, n_eq, 2 n_cols); a gradient ``G`` (complex) means
        ``d res = Re G dx + Im G dy``: ``Im(a dz)`` has ``G = i conj(a)``, ``Im(g conj(dz))`` has ``G = -i g``."""
        sr = self._srows
        rho, dhat, c, _ = self._snums(R)
        A, e = self._frames(P)
        u, w = dhat * e, P[sr.k] - A - rho * e
        wd = w * np.conj(dhat)
        n_cols = J.shape[2] // 2
        _add(J, sr.line, sr.k, 1j * u, n_cols)
        _add(J, sr.line, sr.c0, 1j * np.conj(rho - 1) * u + 1j * wd, n_cols)
        _add(J, sr.line, sr.c1, -1j * np.conj(rho) * u - 1j * wd, n_cols)
        if len(sr.locked):
            lk = sr.locked
            ce, eoc = c[lk] * e[lk], (P[sr.o1] - P[sr.o0]) * np.conj(c[lk])
            _add(J, sr.lock, sr.o1, 1j * ce, n_cols)
            _add(J, sr.lock, sr.o0, -1j * ce, n_cols)
            _add(J, sr.lock, sr.c1[lk], -1j * eoc, n_cols)
            _add(J, sr.lock, sr.c0[lk], 1j * eoc, n_cols)

    def _slider_gamma(self, P: np.ndarray, V: np.ndarray, R: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The sliders' acceleration terms at positions ``P`` and velocities ``V`` (n_slots, B): line rows
        ``2 Im(w' conj(u'))``, lock rows ``2 Im(e_o' conj(c e'))`` (each (rows, B)), in :attr:`_srows` order."""
        sr = self._srows
        rho, dhat, c, _ = self._snums(R)
        vA, ve = self._frames(V, rates=True)
        line = 2 * ((V[sr.k] - vA - rho * ve) * np.conj(dhat * ve)).imag
        lk = sr.locked
        lock = 2 * ((V[sr.o1] - V[sr.o0]) * np.conj(c[lk] * ve[lk])).imag
        return line, lock

    def _stack(self, nums: Nums, B: int) -> tuple[FloatArray, np.ndarray]:
        """Design numbers as arrays: lengths (n_links, B) and the further joints' rhos (n_lin, B), in row order."""
        L = np.array([np.broadcast_to(np.ravel(x), (B,)) for x in nums[0]], float).reshape(len(self.links), B)
        rhos = [np.broadcast_to(np.ravel(r), (B,)) for rho in nums[1] for r in rho]
        R = np.array(rhos, complex) if rhos else np.zeros((0, B), complex)
        return L, R

    def _res(self, P: np.ndarray, L: FloatArray, R: np.ndarray) -> FloatArray:
        """Residuals (n_eq, B) of slot positions ``P`` (n_slots, B) with lengths ``L`` and rhos ``R``."""
        rw = self._rows
        e = P[rw.b] - P[rw.a]
        res = np.empty((self.n_eq, P.shape[1]))
        res[rw.dist] = e.real * e.real + e.imag * e.imag - L * L
        if len(rw.k):
            c = P[rw.k] - P[rw.a[rw.link]] - R[: len(rw.k)] * e[rw.link]
            res[rw.lin], res[rw.lin + 1] = c.real, c.imag
        if self.sliders:
            self._slider_res(P, R, res)
        return res

    def _scale(self, L: FloatArray, R: np.ndarray) -> FloatArray:
        """The scale of every residual (n_eq, B): ``L^2`` on a distance row, ``L`` on a linear row, the
        group's mean link length on a slider's line row and the locked side's length squared on its lock row."""
        rw = self._rows
        scale = np.empty((self.n_eq, L.shape[1]))
        scale[rw.dist] = L * L
        scale[rw.lin] = scale[rw.lin + 1] = L[rw.link]
        if self.sliders:
            sr = self._srows
            scale[sr.line] = np.mean(L, axis=0)
            scale[sr.lock] = self._snums(R)[3][sr.locked].real ** 2
        return scale

    def _lin_jacobian(self, R: np.ndarray, n_cols: int) -> FloatArray:
        """The linear rows of the Jacobian (constant) on the slots below ``n_cols``: (B, n_eq, 2 n_cols)."""
        rw = self._rows
        B = R.shape[1]
        J = np.zeros((B, self.n_eq, 2 * n_cols))
        for i, row in enumerate(rw.lin):
            r = R[i] * np.ones(B)
            a, b = rw.a[rw.link[i]], rw.b[rw.link[i]]
            for slot, c in ((rw.k[i], np.ones(B, complex)), (a, r - 1.0), (b, -r)):
                if slot < n_cols:
                    J[:, row, 2 * slot] += c.real
                    J[:, row, 2 * slot + 1] -= c.imag
                    J[:, row + 1, 2 * slot] += c.imag
                    J[:, row + 1, 2 * slot + 1] += c.real
        return J

    def _jac(self, P: np.ndarray, J_lin: FloatArray, R: np.ndarray) -> FloatArray:
        """The Jacobian at ``P`` on the slots of ``J_lin`` (its linear rows): the distance and slider rows added."""
        rw = self._rows
        n_cols = J_lin.shape[2] // 2
        J = J_lin.copy()
        e = P[rw.b] - P[rw.a]
        for s, f in ((rw.b, 2), (rw.a, -2)):
            on = s < n_cols
            rows, cols = rw.dist[on], 2 * s[on]
            J[:, rows, cols] = (f * e.real[on]).T
            J[:, rows, cols + 1] = (f * e.imag[on]).T
        if self.sliders:
            self._slider_jac(P, R, J)
        return J

    def residual(self, P: np.ndarray, nums: Nums) -> tuple[np.ndarray, np.ndarray]:
        """Residuals (B, n_eq) and their scales, for slot positions ``P`` (n_slots, B) complex."""
        L, R = self._stack(nums, P.shape[1])
        rw = self._rows
        zero = 0 * (P[rw.b] - P[rw.a]).real  # NaN scales where a link is not finite
        scale = self._scale(L, R)
        scale[rw.dist] += zero
        scale[rw.lin] += zero[rw.link]
        scale[rw.lin + 1] += zero[rw.link]
        return self._res(P, L, R).T, scale.T

    def jacobian(self, P: np.ndarray, nums: Nums, n_slots: int) -> np.ndarray:
        """d residual / d [x, y] of every slot: (B, n_eq, 2 n_slots)."""
        _, R = self._stack(nums, P.shape[1])
        return self._jac(P, self._lin_jacobian(R, n_slots), R)

    def _design_nums(self, nums: Nums, d: np.ndarray) -> Nums:
        """The numbers of the designs ``d`` (a design index per batch row), flat."""
        lengths, rhos = nums[0], nums[1]

        def take(x: Any) -> Any:
            x = np.asarray(x)
            return x.reshape(-1)[d] if x.size > 1 else x.reshape(-1)[0] * np.ones(len(d), x.dtype)

        return tuple(take(L) for L in lengths), tuple(tuple(take(r) for r in rho) for rho in rhos)

    def _arrays(self, nums: Nums, B: int) -> _Arrays:
        """The numbers ``nums`` of ``B`` columns as Newton reads them."""
        L, R = self._stack(nums, B)
        return _Arrays(L, R, NEWTON_TOL * self._scale(L, R), self._lin_jacobian(R, len(self.joints)))

    def newton(
        self, U: np.ndarray, K: np.ndarray, nums: Nums, iters: int = NEWTON_ITER
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Newton from ``U`` (m, B) with knowns ``K`` (k, B): (solution, converged, det sign).

        Each column is iterated until its residual passes (then it is left as it is), for at
        most ``iters`` steps; only the columns still iterating are computed (a column whose
        step is not finite is NaN from the next step on: it is dropped, NaN).
        """
        return self._newton(U, K, self._arrays(nums, U.shape[1]), iters)

    def _newton(
        self, U: np.ndarray, K: np.ndarray, ar: _Arrays, iters: int = NEWTON_ITER
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`newton` with the numbers as arrays."""
        U = U.copy()
        conv = np.zeros(U.shape[1], bool)
        act = np.arange(U.shape[1])
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            for it in range(iters + 1):
                P = np.concatenate([U[:, act], K[:, act]]) if len(K) else U[:, act]
                res = self._res(P, ar.L[:, act], ar.R[:, act])
                ok = np.all(np.abs(res) <= ar.tol[:, act], axis=0)
                conv[act[ok]] = True
                act = act[~ok]
                if it == iters or not len(act):
                    break
                dx = _newton_step(self._jac(P[:, ~ok], ar.J_lin[act], ar.R[:, act]), res[:, ~ok])
                U[:, act] = U[:, act] + (dx[:, 0::2] + 1j * dx[:, 1::2]).T
                live = np.all(np.isfinite(U[:, act]), axis=0)
                if not live.all():  # the next step makes the column NaN, and it stays NaN
                    if it + 1 < iters:
                        U[:, act[~live]] = NAN_POINT
                    act = act[live]
            P = np.concatenate([U, K]) if len(K) else U
            J = self._jac(P, ar.J_lin, ar.R)
            det = np.linalg.det(np.where(np.isfinite(J), J, 0.0))
            conv &= np.isfinite(det) & (det != 0)
        return U, conv, np.sign(det)

    # ------------------------------------------------------------------ chains between held joints
    @cached_property
    def _chains(self) -> tuple[_Chain, ...]:
        """Chains of link edges between two held joints through the group's joints (simple paths, a few)."""
        m = len(self.joints)
        adj: dict[int, list[tuple[int, tuple[int, int, int]]]] = {}
        for i, gl in enumerate(self.links):
            for p, sp in enumerate(gl.slots):
                adj.setdefault(sp, []).extend((sq, (i, p, q)) for q, sq in enumerate(gl.slots) if q != p)
        chains: list[_Chain] = []
        budget = [MAX_CHAIN_SEARCH]

        def extend(node: int, start: int, edges: tuple[tuple[int, int, int], ...], seen: frozenset[int]) -> None:
            for nxt, edge in adj.get(node, []):
                budget[0] -= 1
                if len(chains) >= MAX_CHAINS or budget[0] < 0:
                    return
                if nxt >= m and nxt > start:
                    chains.append(_Chain((start - m, nxt - m), (*edges, edge)))
                elif nxt < m and nxt not in seen:
                    extend(nxt, start, (*edges, edge), seen | {nxt})

        for start in range(m, m + len(self.known)):
            extend(start, start, (), frozenset())
        return tuple(chains)

    def _reach(self, dn: Nums, B: int) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Per chain and design, the distances its two held joints can be apart: (low, high, margin), (n_chains, B).

        Along a chain of edges of lengths ``l_i`` (two joints of one link, ``|w_p - w_q| L`` with
        ``w`` = 0, 1, rho_k for j0, j1, jk), the ends are between ``2 max l - sum l`` and ``sum l``
        apart. A configuration Newton accepts keeps every edge to about 1e-12 of the link, so
        beyond ``CHAIN_MARGIN`` of the chain's lengths there is none.
        """
        L, _ = self._stack(dn, B)
        one = np.ones(B, complex)
        w = [[0 * one, one, *(np.broadcast_to(np.ravel(r), (B,)) for r in rho)] for rho in dn[1]]
        out = np.zeros((3, len(self._chains), B))
        with np.errstate(invalid="ignore", over="ignore"):
            for c, ch in enumerate(self._chains):
                lens = np.array([np.abs(w[i][p] - w[i][q]) * L[i] for i, p, q in ch.edges])
                total = np.sum(lens, axis=0)
                out[:, c] = (
                    2 * np.max(lens, axis=0) - total,
                    total,
                    CHAIN_MARGIN * (total + np.sum(L[[e[0] for e in ch.edges]], axis=0)),
                )
        return out[0], out[1], out[2]

    def _possible(self, K: np.ndarray, reach: tuple[FloatArray, FloatArray, FloatArray]) -> np.ndarray:
        """False where a chain proves Newton cannot converge: its held joints ``K`` (k, ...) too far apart or too near.

        ``reach`` broadcasts against ``K``'s trailing axes.
        """
        if not self._chains:
            return np.ones(K.shape[1:], bool)
        ends = np.array([ch.ends for ch in self._chains])
        d = np.abs(K[ends[:, 1]] - K[ends[:, 0]])
        lo, hi, mg = reach
        with np.errstate(invalid="ignore"):
            out: np.ndarray = ~np.any((d > hi + mg) | (d < lo - mg), axis=0)
        return out

    # ------------------------------------------------------------------ positions
    def place(self, k: Kin, nums: Nums) -> None:
        z = k.z
        _, D, n = z.shape
        m = len(self.joints)
        zu0 = np.broadcast_to(nums[3][:, :, 0], (m, D))
        zk0 = np.broadcast_to(nums[4][:, :, 0], (len(self.known), D))
        dn = self._design_nums(nums, np.arange(D))
        K_all = z[list(self.known)] if self.known else np.zeros((0, D, n), complex)
        start, conv0, ref_sign = self.newton(zu0.copy(), zk0.copy(), dn)  # the pose (exact unless `lengths`)
        start = np.where(conv0, start, NAN_POINT)
        lo, hi, mg = self._reach(dn, D)
        ok = np.all(np.isfinite(K_all), axis=0) & conv0[:, None]
        ok &= self._possible(K_all, (lo[..., None], hi[..., None], mg[..., None]))
        w = _Walk(
            K_all, ok, np.full((m, D, n), NAN_POINT), ref_sign, nums, _size(dn), self._arrays(dn, D), (lo, hi, mg)
        )
        for half in _walks(k, D, n, self.angular):
            state = (start.copy(), zk0.copy(), np.full_like(start, NAN_POINT), np.ones(D, bool))
            if len(half) < 4 * COARSE_STRIDE_MIN:
                self._walk(half, state, w)
                continue
            # two levels: walk every stride-th sample; then the samples between two walked ones
            # together, each from the interpolation of its two neighbours' solutions
            stride = max(COARSE_STRIDE_MIN, len(half) // COARSE_SAMPLES)
            ends = np.arange(stride - 1, len(half), stride)
            if ends[-1] != len(half) - 1:
                ends = np.append(ends, len(half) - 1)
            snaps: list[tuple[np.ndarray, ...]] = []
            clean = self._walk(half[ends], state, w, snaps)
            lo_end = np.concatenate([[-1], ends[:-1]])
            self._fill(half, lo_end, ends, snaps, clean, start, w)
        for i, j in enumerate(self.joints):
            z[j] = w.out[i]
        if self.keep_rotation:
            bases = dict(zip((gl.name for gl in self.links), nums[2], strict=True))
            for gl in self.links:
                if gl.name in self.keep_rotation:
                    k.rot[gl.name] = (z[gl.joints[1]] - z[gl.joints[0]]) / bases[gl.name]

    def _walk(
        self,
        samples: np.ndarray,
        state: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
        w: _Walk,
        snaps: list[tuple[np.ndarray, ...]] | None = None,
        ahead: _Ahead | None = None,
    ) -> np.ndarray:
        """Walk ``samples`` in order from ``state`` (U, knowns, previous U, fresh), updated in place.

        Returns, per design and sample, whether the sample was accepted by a plain continuation
        step (no restart after a gap, no failure), (D, len(samples)). With ``snaps``, the state
        before each sample is appended to it. A design whose last sample failed (not fresh)
        takes its next steps from the look-ahead (:class:`_Ahead`): the same steps, solved at once.
        """
        U, Kc, U_prev, fresh = state  # fresh: the last sample walked was solved (sub-steps allowed)
        D = U.shape[1]
        clean = np.zeros((D, len(samples)), bool)
        ahead = _Ahead(D) if ahead is None else ahead
        for i, s in enumerate(samples):
            if snaps is not None:
                snaps.append(tuple(x.copy() for x in state))
            K_t = w.K[:, :, s]
            U_new, acc, lost = np.full_like(U, NAN_POINT), np.zeros(D, bool), np.zeros(D, bool)
            now = np.flatnonzero(w.ok[:, s] & fresh)
            if len(now):
                U_new[:, now], acc[now], lost[now] = self._fresh_step(U[:, now], U_prev[:, now], Kc[:, now], now, s, w)
            later = np.flatnonzero(w.ok[:, s] & ~fresh)
            if len(later):
                U_new[:, later], acc[later], lost[later] = ahead.get(self, i, later, samples, U, U_prev, w)
            clean[:, i] = acc & ~lost
            fresh[:] = acc  # sub-steps only from a sample solved just before; after a gap, restarts (dyads)
            ahead.forget(acc)
            w.out[:, acc, s] = U_new[:, acc]
            # no predictor across a gap: the next step starts from the restart's solution
            U_prev[:, acc] = np.where(lost, U_new, U)[:, acc]
            U[:, acc] = U_new[:, acc]
            Kc[:, acc] = K_t[:, acc]
        return clean

    def _plain(
        self, U: np.ndarray, U_prev: np.ndarray, K: np.ndarray, designs: np.ndarray, w: _Walk
    ) -> tuple[np.ndarray, np.ndarray]:
        """A continuation step to knowns ``K`` from ``U`` (with the linear predictor from ``U_prev``): (U, accepted)."""
        guess = 2 * U - U_prev  # linear predictor along the walk
        guess = np.where(np.isfinite(guess), guess, U)
        U_new, conv, sg = self._newton(guess, K, w.arrays.take(designs))
        acc = conv & (sg == w.ref[designs]) & np.all(np.isfinite(U_new), axis=0)
        acc &= np.max(np.abs(U_new - U), axis=0) <= STEP_LIMIT * w.size[designs]  # small steps: the nearest root
        return U_new, acc

    def _fresh_step(
        self, U: np.ndarray, U_prev: np.ndarray, Kc: np.ndarray, designs: np.ndarray, s: int, w: _Walk
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Sample ``s`` from a sample solved just before: a step, else sub-steps, else (dyads) restarts.

        Returns (U, accepted, lost): lost when neither the step nor the sub-steps got there.
        """
        K = w.K[:, designs, s]
        U_new, acc = self._plain(U, U_prev, K, designs, w)
        todo = np.flatnonzero(~acc)
        if len(todo):  # step halving: move the knowns from the last good state in 2^h steps
            U_h = self._halving(U[:, todo], Kc[:, todo], K[:, todo], w, designs[todo])
            done = np.all(np.isfinite(U_h), axis=0)
            U_new[:, todo[done]] = U_h[:, done]
            acc[todo[done]] = True
        lost = ~acc
        self._restart_lost(U, K, designs, w, U_new, acc, lost)
        return U_new, acc, lost

    def _lost_step(
        self, U: np.ndarray, U_prev: np.ndarray, K: np.ndarray, designs: np.ndarray, w: _Walk
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """A sample after one that failed: a step, else (dyads) restarts. Returns (U, accepted, lost)."""
        U_new, acc = self._plain(U, U_prev, K, designs, w)
        lost = ~acc
        self._restart_lost(U, K, designs, w, U_new, acc, lost)
        return U_new, acc, lost

    def _restart_lost(
        self,
        U: np.ndarray,
        K: np.ndarray,
        designs: np.ndarray,
        w: _Walk,
        U_new: np.ndarray,
        acc: np.ndarray,
        lost: np.ndarray,
    ) -> None:
        """For a dyad-like group: the ``lost`` columns restarted (:meth:`_restart`), ``U_new`` and ``acc`` updated."""
        if not (lost.any() and self.dyad_like):  # not reachable from the last good sample: the only root of the sign
            return
        idx = np.flatnonzero(lost)
        U_r = self._restart(U[:, idx], K[:, idx], w.ref[designs[idx]], w.nums, designs[idx])
        found = np.all(np.isfinite(U_r), axis=0)
        U_new[:, idx[found]] = U_r[:, found]
        acc[idx[found]] = True

    def _fill(
        self,
        half: np.ndarray,
        lo: np.ndarray,
        hi: np.ndarray,
        snaps: list[tuple[np.ndarray, ...]],
        clean: np.ndarray,
        start: np.ndarray,
        w: _Walk,
    ) -> None:
        """The samples between walked ones: all at once where both ends are good, else walked.

        A sample between two walked samples ``a`` and ``b`` (both reached by plain
        continuation steps) starts Newton from the linear interpolation of their solutions;
        it is accepted when Newton converges with the pose's determinant sign within half
        the distance from ``a`` to ``b`` of that start. Everything else is walked, from the
        state the walk had at ``a``.
        """
        m, D = start.shape
        out = w.out
        rows, cols, guess, bound, redo = [], [], [], [], []
        for i, (a, b) in enumerate(zip(lo, hi, strict=True)):
            inner = half[a + 1 : b]
            if not len(inner):
                continue
            Ua = start if a < 0 else out[:, :, half[a]]
            Ub = out[:, :, half[b]]
            both = clean[:, i] & np.all(np.isfinite(Ua), axis=0) & np.all(np.isfinite(Ub), axis=0)
            if not both.all():
                redo.append(i)
                continue
            t = (np.arange(1, b - a) / (b - a))[:, None, None]  # (len, 1, 1)
            g = (1 - t) * Ua[None] + t * Ub[None]  # (len, m, D)
            rows.append(np.repeat(inner, D))
            cols.append(np.tile(np.arange(D), len(inner)))
            guess.append(g.transpose(1, 0, 2).reshape(m, -1))
            reach = 0.5 * np.max(np.abs(Ub - Ua), axis=0) + 1e-9 * np.max(np.abs(Ua), axis=0)  # (D,)
            bound.append(np.tile(reach, len(inner)))
        if rows:
            r, c, g = np.concatenate(rows), np.concatenate(cols), np.concatenate(guess, axis=1)
            ok = self._fill_batch(r, c, g, np.concatenate(bound), w)
            bad_samples = set(r[~ok].tolist())
            for i, (a, b) in enumerate(zip(lo, hi, strict=True)):
                if i not in redo and bad_samples.intersection(half[a + 1 : b].tolist()):
                    redo.append(i)
        segments = [(half[lo[i] + 1 : hi[i]], tuple(x.copy() for x in snaps[i])) for i in sorted(redo)]
        while segments:  # in batches of at most about AHEAD_COLUMNS lost (design, sample) columns
            sizes = np.cumsum([np.sum(~state[3]) * len(samples) for samples, state in segments])
            k = max(1, int(np.searchsorted(sizes, AHEAD_COLUMNS, side="right")))
            batch, segments = segments[:k], segments[k:]
            for (samples, state), ahead in zip(batch, self._ahead_of(batch, w), strict=True):
                self._walk(samples, state, w, ahead=ahead)  # type: ignore[arg-type]

    def _ahead_of(self, segments: list[tuple[np.ndarray, tuple[np.ndarray, ...]]], w: _Walk) -> list[_Ahead]:
        """Look-aheads for walks of ``segments`` (samples, starting state): their lost designs' steps, at once.

        A design lost at the start of a segment (in a gap, every segment starts so, from one same
        state) gets its steps over the whole segment from one batch of :meth:`_lost_step`.
        """
        m, D = w.out.shape[:2]
        cols = []
        for samples, (U, _, U_prev, fresh) in segments:
            need = np.flatnonzero(~fresh)
            d, s = np.repeat(need, len(samples)), np.tile(samples, len(need))
            cols.append((need, d, s, U[:, d], U_prev[:, d]))
        d, s = np.concatenate([c[1] for c in cols]), np.concatenate([c[2] for c in cols])
        U0, U1 = np.concatenate([c[3] for c in cols], axis=1), np.concatenate([c[4] for c in cols], axis=1)
        Uw, acc, lost = np.full((m, len(d)), NAN_POINT), np.zeros(len(d), bool), np.zeros(len(d), bool)
        run = np.flatnonzero(w.ok[d, s])  # the other samples are not read
        if len(run):
            Uw[:, run], acc[run], lost[run] = self._lost_step(U0[:, run], U1[:, run], w.K[:, d[run], s[run]], d[run], w)
        out, start = [], 0
        for (samples, _), (need, *_) in zip(segments, cols, strict=True):
            ahead, n = _Ahead(D), len(need) * len(samples)
            if len(need):
                sl = slice(start, start + n)
                ahead.add(0, need, Uw[:, sl], acc[sl], lost[sl], len(samples))
            out.append(ahead)
            start += n
        return out

    def _fill_batch(self, r: np.ndarray, c: np.ndarray, g: np.ndarray, bound: np.ndarray, w: _Walk) -> np.ndarray:
        """Samples ``r`` of designs ``c`` from guesses ``g`` at once: accepted (written to ``out``) or not."""
        ok = np.zeros(len(r), bool)
        can = np.flatnonzero(w.ok[c, r])  # the others cannot converge
        if len(can):
            r, c, g, bound = r[can], c[can], g[:, can], bound[can]
            sol, conv, sg = self._newton(g, w.K[:, c, r], w.arrays.take(c))
            # accepted: converged, with the pose's sign, near the interpolation (not another branch)
            near = np.max(np.abs(sol - g), axis=0)
            good = conv & (sg == w.ref[c]) & np.all(np.isfinite(sol), axis=0) & (near <= bound)
            w.out[:, c[good], r[good]] = sol[:, good]
            ok[can] = good
        return ok

    def _halving(self, U: np.ndarray, K0: np.ndarray, K1: np.ndarray, w: _Walk, designs: np.ndarray) -> np.ndarray:
        """From (U, K0) to K1 by adaptive sub-steps; NaN columns where a step below 2^-MAX_HALVINGS fails.

        Each column walks ``t`` from 0 to 1 (the knowns at ``(1 - t) K0 + t K1``): a step that
        is accepted (the tests of a continuation step) doubles the next one, a step that is
        not is halved. A step to knowns a chain rules out fails without Newton.
        """
        ref, size, ar = w.ref[designs], w.size[designs], w.arrays.take(designs)
        reach = tuple(x[:, designs] for x in w.reach)  # the walk's numbers, of these designs
        B = U.shape[1]
        Uc, t, dt = U.copy(), np.zeros(B), np.full(B, 0.5)
        alive = np.ones(B, bool)
        smallest = 0.5**MAX_HALVINGS
        while True:
            act = np.flatnonzero(alive & (t < 1.0))
            if not len(act):
                break
            tt = np.minimum(t[act] + dt[act], 1.0)
            K_t = (1 - tt) * K0[:, act] + tt * K1[:, act]
            ok = np.zeros(len(act), bool)
            can = np.flatnonzero(self._possible(K_t, tuple(x[:, act] for x in reach)))  # type: ignore[arg-type]
            if len(can):
                a = act[can]
                Un, conv, sg = self._newton(Uc[:, a], K_t[:, can], ar.take(a))
                ok[can] = conv & (sg == ref[a]) & (np.max(np.abs(Un - Uc[:, a]), axis=0) <= STEP_LIMIT * size[a])
                good_can = can[ok[can]]
                Uc[:, act[good_can]] = Un[:, ok[can]]
            good, bad = act[ok], act[~ok]
            t[good] = tt[ok]
            dt[good] = np.minimum(2 * dt[good], 1.0)
            dt[bad] /= 2
            alive[bad[dt[bad] < smallest]] = False
        return np.where(alive & (t >= 1.0), Uc, NAN_POINT)

    def _restart(self, U: np.ndarray, K: np.ndarray, ref: np.ndarray, nums: Nums, designs: np.ndarray) -> np.ndarray:
        """After a gap: the solution at ``K`` with the pose's determinant sign, when it is the only one.

        Newton from ``RESTARTS`` starts scattered about the last good configuration (a fixed
        seed: results are reproducible); the converged solutions of the pose's sign are
        deduplicated. One: that is the branch coming back. None, or several (a class-3 group
        has up to three of one sign): NaN, so the sample is flagged instead of guessed.
        """
        m, B = U.shape
        dn = self._design_nums(nums, designs)
        lengths = np.array([np.broadcast_to(L, (B,)) for L in dn[0]])  # (links, B)
        size = np.mean(lengths, axis=0)
        rng = np.random.default_rng(12345)
        noise = rng.standard_normal((RESTARTS, m, 1)) + 1j * rng.standard_normal((RESTARTS, m, 1))
        # half the starts about the last good configuration, half about the held joints
        centre = np.where(np.arange(RESTARTS)[:, None, None] % 2 == 0, U[None], np.mean(K, axis=0)[None, None, :])
        starts = centre + 2 * np.max(lengths, axis=0)[None, None, :] * noise  # (R, m, B)
        Ub = np.concatenate([U[None], starts]).transpose(1, 0, 2).reshape(m, -1)
        Kb = np.repeat(K[:, None, :], RESTARTS + 1, axis=1).reshape(K.shape[0], -1)
        rows = np.tile(np.arange(B), RESTARTS + 1)
        sol, conv, sg = self.newton(Ub, Kb, _take(dn, rows), iters=4 * NEWTON_ITER)
        sol = sol.reshape(m, RESTARTS + 1, B)
        good = (conv & (sg == np.tile(ref, RESTARTS + 1))).reshape(RESTARTS + 1, B)
        out = np.full((m, B), NAN_POINT)
        for b in np.flatnonzero(good.any(axis=0)):  # per design: a handful of candidates to compare
            cand = sol[:, good[:, b], b]
            tol = 1e-4 * size[b]  # one root found from many starts (round-off near a limit: far above 1e-12)
            first = cand[:, 0]
            if np.all(np.max(np.abs(cand - first[:, None]), axis=0) <= tol):
                out[:, b] = first
        return out

    # ------------------------------------------------------------------ rates
    def rates(self, r: Rate, nums: Nums) -> None:
        m, nk = len(self.joints), len(self.known)
        _, D, n = r.z.shape
        slots = list(self.joints) + list(self.known)
        P = r.z[slots].reshape(m + nk, D * n)
        V = r.v[list(self.known)].reshape(nk, D * n) if nk else np.zeros((0, D * n), complex)
        A = r.a[list(self.known)].reshape(nk, D * n) if nk else np.zeros((0, D * n), complex)
        d = np.repeat(np.arange(D), n)
        dn = self._design_nums(nums, d)
        J = self.jacobian(P, dn, m + nk)
        Ju, Jk = J[:, :, : 2 * m], J[:, :, 2 * m :]
        ok = np.all(np.isfinite(Ju), axis=(1, 2))
        Ju_safe = np.where(ok[:, None, None], Ju, np.eye(2 * m))
        vk = np.stack([V.real, V.imag], axis=-1).reshape(nk, D * n, 2).transpose(1, 0, 2).reshape(D * n, 2 * nk)
        ak = np.stack([A.real, A.imag], axis=-1).reshape(nk, D * n, 2).transpose(1, 0, 2).reshape(D * n, 2 * nk)
        rhs_v = -np.einsum("bij,bj->bi", Jk, vk) if nk else np.zeros((D * n, 2 * m))
        cond = self._condition(Ju_safe, dn)
        sing = ~ok | ~(cond > 0)
        Ju_solve = np.where(sing[:, None, None], np.eye(2 * m), Ju_safe)
        vu = np.linalg.solve(Ju_solve, rhs_v[..., None])[..., 0]
        vu[sing] = np.nan
        # gamma: 2 |v_a - v_b|^2 on each distance row
        Vall = np.concatenate([(vu[:, 0::2] + 1j * vu[:, 1::2]).T, V]) if nk else (vu[:, 0::2] + 1j * vu[:, 1::2]).T
        gamma = np.zeros((D * n, self.n_eq))
        row = 0
        for gl in self.links:
            dv = Vall[gl.slots[1]] - Vall[gl.slots[0]]
            gamma[:, row] = 2 * (dv.real**2 + dv.imag**2)
            row += 1 + 2 * (len(gl.slots) - 2)
        if self.sliders:  # 2 Im(w' conj(u')) on a line row, 2 Im(e_o' conj(c e')) on a lock row
            line, lock = self._slider_gamma(P, Vall, self._stack(dn, D * n)[1])
            gamma[:, self._srows.line], gamma[:, self._srows.lock] = line.T, lock.T
        rhs_a = -gamma - (np.einsum("bij,bj->bi", Jk, ak) if nk else 0.0)
        au = np.linalg.solve(Ju_solve, rhs_a[..., None])[..., 0]
        au[sing] = np.nan
        for i, j in enumerate(self.joints):
            r.v[j] = (vu[:, 2 * i] + 1j * vu[:, 2 * i + 1]).reshape(D, n)
            r.a[j] = (au[:, 2 * i] + 1j * au[:, 2 * i + 1]).reshape(D, n)
        r.extra_cond.append(np.where(ok, cond, 0.0).reshape(D, n))
        for gl in self.links:
            if gl.name not in r.om:
                j0, j1 = gl.joints[0], gl.joints[1]
                r.om[gl.name], r.al[gl.name] = link_rates(r.z[j1] - r.z[j0], r.v[j1] - r.v[j0], r.a[j1] - r.a[j0])

    def row_scale(self, dn: Nums, B: int) -> FloatArray:
        """Per row (B, n_eq), what makes its gradient of unit scale: ``1 / (2 L)`` on a distance row, ``1 / ell``
        on a slider's lock row (``ell`` the locked side's length), 1 elsewhere."""
        scale = np.ones((B, self.n_eq))
        row = 0
        for gl, L in zip(self.links, dn[0], strict=True):
            scale[:, row] = 1.0 / (2 * L)
            row += 1 + 2 * (len(gl.slots) - 2)
        if self.sliders:
            sr = self._srows
            scale[:, sr.lock] = 1.0 / self._snums(self._stack(dn, B)[1])[3][sr.locked].real.T
        return scale

    def _condition(self, Ju: np.ndarray, dn: Nums) -> np.ndarray:
        """Smallest over largest singular value of J_u with its rows scaled by :meth:`row_scale`."""
        scale = self.row_scale(dn, Ju.shape[0])
        s = np.linalg.svd(Ju * scale[:, :, None], compute_uv=False)
        with np.errstate(invalid="ignore", divide="ignore"):
            return s[:, -1] / s[:, 0]

    # ------------------------------------------------------------------ description
    def describe(self, names: tuple[str, ...], nums: Nums | None) -> str | None:
        placed = ", ".join(names[j] for j in self.joints)
        links = ", ".join(f"'{gl.name}'" for gl in self.links)
        held = ", ".join(names[j] for j in self.known) or "nothing"
        sliding = "".join(f", slider {gs.slider} ('{gs.other}' on '{gs.carrier}')" for gs in self.sliders)
        return (
            f"{placed} placed numerically (Newton-Raphson, continued from the pose): links {links}{sliding}, "
            f"held by {held}; the mode is the pose's"
        )


def _size(dn: Nums) -> FloatArray:
    """The mean link length of each design (a batch row) of design numbers."""
    size: FloatArray = np.mean(np.array([np.broadcast_to(L, np.shape(dn[0][0])) for L in dn[0]]), axis=0)
    return size


def _take(dn: Nums, cols: np.ndarray) -> Nums:
    lengths, rhos = dn
    return tuple(L[cols] for L in lengths), tuple(tuple(r[cols] for r in rho) for rho in rhos)


def _walks(k: Kin, D: int, n: int, angular: tuple[bool, ...] = ()) -> list[np.ndarray]:
    """The sample indices in walking order: from the pose's input up, then from it down.

    The samples are sorted by the driver input that varies most (the first design's inputs),
    measured from the pose's input as given (not modulo a turn: a class-3 group may come back
    in another mode after a full turn of its crank, and the walk follows the motion); inputs
    equal to the pose's go up. When that driver is an angle (``angular``), samples more than
    ``WALK_REACH`` from the pose's input are left out: never walked to, they stay NaN (not
    reached), so the walk's length is bounded whatever the inputs. Over a
    design axis every design walks in this one order from its own pose (the first
    sub-step reaches the nearest sample by homotopy), so the walk stays continuous per design.

    >>> import numpy as np
    >>> from linkagekit.steps import Kin
    >>> q = np.radians([[[10.0, -20.0, 5.0, 7200.0, -7200.0]]])
    >>> k = Kin(np.zeros((0, 1, 5), complex), {}, np.zeros((0, 1, 5)), q, None, None, 0.0, np.zeros((1, 1)))
    >>> [w.tolist() for w in _walks(k, 1, 5, (True,))]
    [[2, 0], [1]]
    """
    if k.q.shape[0] == 0 or n == 0:
        return [np.arange(n)]
    q = np.broadcast_to(k.q, (k.q.shape[0], max(k.q.shape[1], 1), n))[:, 0, :]
    q0 = k.q0[:, 0] if k.q0 is not None else q[:, 0]
    d = int(np.argmax(np.ptp(q, axis=1)))
    key = q[d] - q0[d]
    order = np.argsort(key, kind="stable")
    if d < len(angular) and angular[d]:
        order = order[np.abs(key[order]) <= WALK_REACH]
    up = order[key[order] >= 0]
    down = order[key[order] < 0][::-1]
    return [w for w in (up, down) if len(w)]


def _add(J: FloatArray, rows: np.ndarray, slots: np.ndarray, G: np.ndarray, n_cols: int) -> None:
    """Add the gradients ``G`` (rows, B; complex: ``[Re, Im]`` on ``[x, y]``) at ``rows``, ``slots`` of ``J``
    (B, n_eq, 2 n_cols), on the slots below ``n_cols`` (a slot ``-1``, the ground's, has none)."""
    on = (slots >= 0) & (slots < n_cols)
    if on.any():
        r, s, g = rows[on], slots[on], G[on]
        J[:, r, 2 * s] += g.real.T
        J[:, r, 2 * s + 1] += g.imag.T


def _newton_step(J: FloatArray, res: FloatArray) -> FloatArray:
    """Newton's steps ``dx`` (B, 2m): ``J dx = -res`` (``res`` (n_eq, B)); NaN where not finite or singular."""
    r = res.T
    good = np.all(np.isfinite(J), axis=(1, 2)) & np.all(np.isfinite(r), axis=1)
    dx = np.full((len(r), J.shape[2]), np.nan)
    if good.any():
        try:
            dx[good] = np.linalg.solve(J[good], -r[good][..., None])[..., 0]
        except np.linalg.LinAlgError:
            for i in np.flatnonzero(good):  # rare: a singular matrix in the batch
                with contextlib.suppress(np.linalg.LinAlgError):
                    dx[i] = np.linalg.solve(J[i], -r[i])
    return dx


@dataclass
class _Ahead:
    """The steps of the designs a walk has lost, solved ahead.

    A design whose last sample failed starts every next sample from the same state (its last
    good solution, with the predictor from the one before), so its next steps do not depend
    on each other until one is accepted: they are solved together over a window of the next
    samples (:data:`AHEAD_FIRST` long, doubling while the design stays lost, up to
    :data:`AHEAD_MOST`), exactly as one by one, and read from there. An accepted design is
    forgotten (its state has moved on).
    """

    D: int
    windows: list[tuple[int, np.ndarray, np.ndarray, np.ndarray]] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.until = np.zeros(self.D, np.intp)  # the first sample position past the design's window
        self.which = np.zeros(self.D, np.intp)  # its window (first position, U (m, k, c), accepted, lost)
        self.col = np.zeros(self.D, np.intp)  # its column there
        self.streak = np.zeros(self.D, np.intp)  # windows since the design was lost

    def get(
        self, group: Group, i: int, cols: np.ndarray, samples: np.ndarray, U: np.ndarray, U_prev: np.ndarray, w: _Walk
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The step of the lost designs ``cols`` at the walk's ``i``-th sample: (U, accepted, lost)."""
        need = cols[self.until[cols] <= i]
        if len(need):
            self._solve(group, i, need, samples, U, U_prev, w)
        U_new = np.empty((U.shape[0], len(cols)), complex)
        acc, lost = np.zeros(len(cols), bool), np.zeros(len(cols), bool)
        for wid in np.unique(self.which[cols]):
            sel = np.flatnonzero(self.which[cols] == wid)
            first, Uw, aw, lw = self.windows[wid]
            cc = self.col[cols[sel]]
            U_new[:, sel], acc[sel], lost[sel] = Uw[:, cc, i - first], aw[cc, i - first], lw[cc, i - first]
        return U_new, acc, lost

    def _solve(
        self, group: Group, i: int, need: np.ndarray, samples: np.ndarray, U: np.ndarray, U_prev: np.ndarray, w: _Walk
    ) -> None:
        """A window for the designs ``need``, from the walk's ``i``-th sample."""
        c = AHEAD_FIRST << int(np.max(self.streak[need]))
        c = int(min(len(samples) - i, c, AHEAD_MOST, max(1, AHEAD_COLUMNS // len(need))))
        d = np.repeat(need, c)
        s = samples[i + np.tile(np.arange(c), len(need))]
        m = U.shape[0]
        Uw = np.full((m, len(d)), NAN_POINT)
        acc, lost = np.zeros(len(d), bool), np.zeros(len(d), bool)
        run = np.flatnonzero(w.ok[d, s])  # the other samples are not read
        if len(run):
            dr = d[run]
            Uw[:, run], acc[run], lost[run] = group._lost_step(U[:, dr], U_prev[:, dr], w.K[:, dr, s[run]], dr, w)
        self.add(i, need, Uw, acc, lost, c)

    def add(self, i: int, need: np.ndarray, Uw: np.ndarray, acc: np.ndarray, lost: np.ndarray, c: int) -> None:
        """The steps of designs ``need`` over ``c`` samples from the ``i``-th (flat, design-major)."""
        k = len(need)
        self.windows.append((i, Uw.reshape(-1, k, c), acc.reshape(k, c), lost.reshape(k, c)))
        self.which[need], self.col[need], self.until[need] = len(self.windows) - 1, np.arange(k), i + c
        self.streak[need] += 1

    def forget(self, acc: np.ndarray) -> None:
        """The designs ``acc`` were accepted: their windows are out of date."""
        self.until[acc] = 0
        self.streak[acc] = 0
