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

Rates
-----
Differentiating ``Phi(z_u, z_k) = 0``: ``J_u v_u = -J_k v_k`` and ``J_u a_u = -J_k a_k -
gamma``, ``gamma = 2 |v_a - v_b|^2`` for a distance row, 0 for a linear row. The
conditioning reported with the rates is the smallest singular value of ``J_u`` with its
distance rows divided by ``2 L`` (so every row has unit scale) over its largest.
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass
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


@dataclass(frozen=True)
class GroupLink:
    """One link of a group: its joints as slots (unknowns first, then knowns), base pair first."""

    name: str
    slots: tuple[int, ...]  # slot of j0, j1, j2, ... (slots < n_unknown are unknowns)
    joints: tuple[int, ...]  # the same joints as plan indices


@dataclass(frozen=True)
class Group(Step):
    """Joints placed together by Newton-Raphson on the natural-coordinate constraints of their links."""

    joints: tuple[int, ...]  # the group's unknown joints (plan indices)
    known: tuple[int, ...]  # the known joints its links hold (plan indices)
    links: tuple[GroupLink, ...]
    keep_rotation: tuple[str, ...] = ()
    angular: tuple[bool, ...] = ()  # per driver: an angle (the walk's added samples are 1 degree apart)

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
        zu = np.stack([src.pose(j) for j in self.joints])  # (m, D, 1)
        zk = np.stack([src.pose(j) for j in self.known]) if self.known else np.zeros((0, *zu.shape[1:]), complex)
        return tuple(lengths), tuple(rhos), tuple(bases), zu, zk

    @property
    def dyad_like(self) -> bool:
        """One joint of the group is on two of its links, the others ride on one: two roots, one per sign.

        Only then does the walk restart after a gap (a class-3 group has up to three roots of one
        sign, so there a sample it cannot reach by continuation stays flagged).
        """
        on_two = sum(sum(j in gl.joints for gl in self.links) >= 2 for j in self.joints)
        return on_two == 1

    @property
    def n_eq(self) -> int:
        return 2 * len(self.joints)

    # ------------------------------------------------------------------ the system
    def residual(self, P: np.ndarray, nums: Nums) -> tuple[np.ndarray, np.ndarray]:
        """Residuals (B, n_eq) and their scales, for slot positions ``P`` (n_slots, B) complex."""
        lengths, rhos = nums[0], nums[1]
        rows, scales = [], []
        for gl, L, rho in zip(self.links, lengths, rhos, strict=True):
            L = np.ravel(L) if np.ndim(L) else L
            e = P[gl.slots[1]] - P[gl.slots[0]]
            rows.append(e.real * e.real + e.imag * e.imag - L * L)
            scales.append(L * L + 0 * e.real)
            for sk, r in zip(gl.slots[2:], rho, strict=True):
                c = P[sk] - P[gl.slots[0]] - np.ravel(r) * e
                rows += [c.real, c.imag]
                scales += [L + 0 * e.real, L + 0 * e.real]
        return np.stack(rows, axis=-1), np.stack(scales, axis=-1)

    def jacobian(self, P: np.ndarray, nums: Nums, n_slots: int) -> np.ndarray:
        """d residual / d [x, y] of every slot: (B, n_eq, 2 n_slots)."""
        rhos = nums[1]
        B = P.shape[1]
        J = np.zeros((B, self.n_eq, 2 * n_slots))
        row = 0
        for gl, rho in zip(self.links, rhos, strict=True):
            a, b = gl.slots[0], gl.slots[1]
            e = P[b] - P[a]
            J[:, row, 2 * b], J[:, row, 2 * b + 1] = 2 * e.real, 2 * e.imag
            J[:, row, 2 * a], J[:, row, 2 * a + 1] = -2 * e.real, -2 * e.imag
            row += 1
            for sk, r in zip(gl.slots[2:], rho, strict=True):
                r = np.ravel(r) * np.ones(B)
                for slot, c in ((sk, np.ones(B, complex)), (a, r - 1.0), (b, -r)):
                    J[:, row, 2 * slot] += c.real
                    J[:, row, 2 * slot + 1] -= c.imag
                    J[:, row + 1, 2 * slot] += c.imag
                    J[:, row + 1, 2 * slot + 1] += c.real
                row += 2
        return J

    def _design_nums(self, nums: Nums, d: np.ndarray) -> Nums:
        """The numbers of the designs ``d`` (a design index per batch row), flat."""
        lengths, rhos = nums[0], nums[1]

        def take(x: Any) -> Any:
            x = np.asarray(x)
            return x.reshape(-1)[d] if x.size > 1 else x.reshape(-1)[0] * np.ones(len(d), x.dtype)

        return tuple(take(L) for L in lengths), tuple(tuple(take(r) for r in rho) for rho in rhos)

    def newton(
        self, U: np.ndarray, K: np.ndarray, nums: Nums, iters: int = NEWTON_ITER
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Newton from ``U`` (m, B) with knowns ``K`` (k, B): (solution, converged, det sign)."""
        m = len(self.joints)
        U = U.copy()
        B = U.shape[1]
        conv = np.zeros(B, bool)
        sign = np.zeros(B)
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            for _ in range(iters):
                P = np.concatenate([U, K]) if len(K) else U
                res, scale = self.residual(P, nums)
                ok = np.all(np.abs(res) <= NEWTON_TOL * scale, axis=1)
                if ok.all():
                    conv = ok
                    break
                J = self.jacobian(P, nums, m + len(K))[:, :, : 2 * m]
                good = np.all(np.isfinite(J), axis=(1, 2)) & np.all(np.isfinite(res), axis=1)
                dx = np.full((B, 2 * m), np.nan)
                if good.any():
                    try:
                        dx[good] = np.linalg.solve(J[good], -res[good][..., None])[..., 0]
                    except np.linalg.LinAlgError:
                        for i in np.flatnonzero(good):  # rare: a singular matrix in the batch
                            with contextlib.suppress(np.linalg.LinAlgError):
                                dx[i] = np.linalg.solve(J[i], -res[i])
                dx[ok] = 0.0
                U = U + (dx[:, 0::2] + 1j * dx[:, 1::2]).T
            else:
                P = np.concatenate([U, K]) if len(K) else U
                res, scale = self.residual(P, nums)
                conv = np.all(np.abs(res) <= NEWTON_TOL * scale, axis=1)
            P = np.concatenate([U, K]) if len(K) else U
            J = self.jacobian(P, nums, m + len(K))[:, :, : 2 * m]
            det = np.linalg.det(np.where(np.isfinite(J), J, 0.0))
            sign = np.sign(det)
            conv &= np.isfinite(det) & (det != 0)
        return U, conv, sign

    # ------------------------------------------------------------------ positions
    def place(self, k: Kin, nums: Nums) -> None:
        z = k.z
        _, D, n = z.shape
        m = len(self.joints)
        zu0 = np.broadcast_to(nums[3][:, :, 0], (m, D))
        zk0 = np.broadcast_to(nums[4][:, :, 0], (len(self.known), D))
        dn = self._design_nums(nums, np.arange(D))
        out = np.full((m, D, n), NAN_POINT)
        K_all = z[list(self.known)] if self.known else np.zeros((0, D, n), complex)
        start, conv0, ref_sign = self.newton(zu0.copy(), zk0.copy(), dn)  # the pose (exact unless `lengths`)
        start = np.where(conv0, start, NAN_POINT)
        for half in _walks(k, D, n, self.angular):
            state = (start.copy(), zk0.copy(), np.full_like(start, NAN_POINT), np.ones(D, bool))
            if len(half) < 4 * COARSE_STRIDE_MIN:
                self._walk(half, state, K_all, out, ref_sign, conv0, nums, dn)
                continue
            # two levels: walk every stride-th sample; then the samples between two walked ones
            # together, each from the interpolation of its two neighbours' solutions
            stride = max(COARSE_STRIDE_MIN, len(half) // COARSE_SAMPLES)
            ends = np.arange(stride - 1, len(half), stride)
            if ends[-1] != len(half) - 1:
                ends = np.append(ends, len(half) - 1)
            snaps, clean = [], []
            for e in ends:
                snaps.append((state[0].copy(), state[1].copy(), state[2].copy(), state[3].copy()))
                direct = self._walk(half[e : e + 1], state, K_all, out, ref_sign, conv0, nums, dn)
                clean.append(direct)
            lo = np.concatenate([[-1], ends[:-1]])
            self._fill(half, lo, ends, snaps, clean, start, K_all, out, ref_sign, conv0, nums, dn)
        for i, j in enumerate(self.joints):
            z[j] = out[i]
        if self.keep_rotation:
            bases = dict(zip((gl.name for gl in self.links), nums[2], strict=True))
            for gl in self.links:
                if gl.name in self.keep_rotation:
                    k.rot[gl.name] = (z[gl.joints[1]] - z[gl.joints[0]]) / bases[gl.name]

    def _walk(
        self,
        samples: np.ndarray,
        state: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
        K_all: np.ndarray,
        out: np.ndarray,
        ref_sign: np.ndarray,
        conv0: np.ndarray,
        nums: Nums,
        dn: Nums,
    ) -> np.ndarray:
        """Walk ``samples`` in order from ``state`` (U, knowns, previous U, fresh), updated in place.

        Returns, per design, whether every sample was accepted by a plain continuation step
        (no restart after a gap, no failure).
        """
        U, Kc, U_prev, fresh = state  # fresh: the last sample walked was solved (sub-steps allowed)
        size = _size(dn)
        clean = np.ones(U.shape[1], bool)
        for s in samples:
            K_t = K_all[:, :, s]
            target_ok = np.all(np.isfinite(K_t), axis=0) & conv0
            guess = 2 * U - U_prev  # linear predictor along the walk
            guess = np.where(np.isfinite(guess), guess, U)
            U_new, conv, sg = self.newton(guess, K_t, dn)
            acc = conv & (sg == ref_sign) & target_ok & np.all(np.isfinite(U_new), axis=0)
            acc &= np.max(np.abs(U_new - U), axis=0) <= STEP_LIMIT * size  # small steps: the nearest root
            todo = ~acc & target_ok & fresh
            lost = ~acc & target_ok & ~fresh
            if todo.any():  # step halving: move the knowns from the last good state in 2^h steps
                idx = np.flatnonzero(todo)
                U_h = self._halving(U[:, idx], Kc[:, idx], K_t[:, idx], ref_sign[idx], nums, idx)
                done = np.all(np.isfinite(U_h), axis=0)
                U_new[:, idx[done]] = U_h[:, done]
                acc[idx[done]] = True
                lost[idx[~done]] = True
            if lost.any():
                clean[lost] = False
            if lost.any() and self.dyad_like:  # not reachable from the last good sample: the only root of the sign
                idx = np.flatnonzero(lost)
                U_r = self._restart(U[:, idx], K_t[:, idx], ref_sign[idx], nums, idx)
                found = np.all(np.isfinite(U_r), axis=0)
                U_new[:, idx[found]] = U_r[:, found]
                acc[idx[found]] = True
            fresh[:] = acc  # sub-steps only from a sample solved just before; after a gap, restarts (dyads)
            clean &= acc
            out[:, acc, s] = U_new[:, acc]
            U_prev[:, acc] = U[:, acc]
            if lost.any():  # no predictor across a gap: the next step starts from the restart's solution
                U_prev[:, lost & acc] = U_new[:, lost & acc]
            U[:, acc] = U_new[:, acc]
            Kc[:, acc] = K_t[:, acc]
        return clean

    def _fill(
        self,
        half: np.ndarray,
        lo: np.ndarray,
        hi: np.ndarray,
        snaps: list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]],
        clean: list[np.ndarray],
        start: np.ndarray,
        K_all: np.ndarray,
        out: np.ndarray,
        ref_sign: np.ndarray,
        conv0: np.ndarray,
        nums: Nums,
        dn: Nums,
    ) -> None:
        """The samples between walked ones: all at once where both ends are good, else walked.

        A sample between two walked samples ``a`` and ``b`` (both reached by plain
        continuation steps) starts Newton from the linear interpolation of their solutions;
        it is accepted when Newton converges with the pose's determinant sign within half
        the distance from ``a`` to ``b`` of that start. Everything else is walked, from the
        state the walk had at ``a``.
        """
        m, D = start.shape
        rows, cols, guess, bound, redo = [], [], [], [], []
        for i, (a, b) in enumerate(zip(lo, hi, strict=True)):
            inner = half[a + 1 : b]
            if not len(inner):
                continue
            Ua = start if a < 0 else out[:, :, half[a]]
            Ub = out[:, :, half[b]]
            both = clean[i] & np.all(np.isfinite(Ua), axis=0) & np.all(np.isfinite(Ub), axis=0)
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
            sol, conv, sg = self.newton(g, K_all[:, c, r], _take(dn, c))
            # accepted: converged, with the pose's sign, near the interpolation (not another branch)
            near = np.max(np.abs(sol - g), axis=0)
            ok = conv & (sg == ref_sign[c]) & np.all(np.isfinite(sol), axis=0) & (near <= np.concatenate(bound))
            out[:, c[ok], r[ok]] = sol[:, ok]
            bad_samples = set(r[~ok].tolist())
            for i, (a, b) in enumerate(zip(lo, hi, strict=True)):
                if i not in redo and bad_samples.intersection(half[a + 1 : b].tolist()):
                    redo.append(i)
        for i in sorted(redo):
            a, b = lo[i], hi[i]
            U, Kc, U_prev, fresh = (x.copy() for x in snaps[i])
            self._walk(half[a + 1 : b], (U, Kc, U_prev, fresh), K_all, out, ref_sign, conv0, nums, dn)

    def _halving(
        self, U: np.ndarray, K0: np.ndarray, K1: np.ndarray, ref: np.ndarray, nums: Nums, designs: np.ndarray
    ) -> np.ndarray:
        """From (U, K0) to K1 by adaptive sub-steps; NaN columns where a step below 2^-MAX_HALVINGS fails.

        Each column walks ``t`` from 0 to 1 (the knowns at ``(1 - t) K0 + t K1``): a step that
        is accepted (the tests of a continuation step) doubles the next one, a step that is
        not is halved.
        """
        dn = self._design_nums(nums, designs)
        size = _size(dn)
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
            Un, conv, sg = self.newton(Uc[:, act], K_t, _take(dn, act))
            ok = conv & (sg == ref[act]) & (np.max(np.abs(Un - Uc[:, act]), axis=0) <= STEP_LIMIT * size[act])
            good, bad = act[ok], act[~ok]
            Uc[:, good], t[good] = Un[:, ok], tt[ok]
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

    def _condition(self, Ju: np.ndarray, dn: Nums) -> np.ndarray:
        """Smallest over largest singular value of J_u with distance rows scaled by 1/(2L)."""
        lengths = dn[0]
        scale = np.ones(Ju.shape[:2])
        row = 0
        for gl, L in zip(self.links, lengths, strict=True):
            scale[:, row] = 1.0 / (2 * L)
            row += 1 + 2 * (len(gl.slots) - 2)
        s = np.linalg.svd(Ju * scale[:, :, None], compute_uv=False)
        with np.errstate(invalid="ignore", divide="ignore"):
            return s[:, -1] / s[:, 0]

    # ------------------------------------------------------------------ description
    def describe(self, names: tuple[str, ...], nums: Nums | None) -> str | None:
        placed = ", ".join(names[j] for j in self.joints)
        links = ", ".join(f"'{gl.name}'" for gl in self.links)
        held = ", ".join(names[j] for j in self.known) or "nothing"
        return (
            f"{placed} placed numerically (Newton-Raphson, continued from the pose): links {links}, "
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
