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

Cylinders and slider drivers
----------------------------
A cylinder driver whose ends are joints of the group (or one a known joint) adds the row
``|z_b - z_a|^2 - s^2 = 0`` (:class:`GroupCylinder`), ``s`` its length: the driver's input.
A slider driver between two moving links (an actuator's barrel and rod) whose slider is the
group's, its guide the carrier, adds the *displacement row* ``Re(w conj(u)) - x = 0``
(:class:`GroupSliderDrive`; ``w``, ``u`` as the line row's, ``x`` the displacement). The input
is a *held value*: a slot after the known joints (its real part the input, :meth:`Group.held`),
which the walk moves exactly as it moves the known joints (linearly between states), so the
continuation is unchanged. Gradients: ``2 e`` on ``b``, ``-2 e`` on ``a``, ``-2 s`` on ``s``
(``e = z_b - z_a``); ``u`` on ``k``, ``conj(rho - 1) u - w conj(dhat)`` on ``c0``, ``-conj(rho)
u + w conj(dhat)`` on ``c1``, ``-1`` on ``x`` (``Re(a dz)`` has ``G = conj(a)``, ``Re(g
conj(dz))`` has ``G = g``). The held values' rates are the drivers' speeds and accelerations,
and ``gamma = 2 |e'|^2 - 2 s'^2`` and ``2 Re(w' conj(u'))``. Scales: ``s0^2`` (the pose's
length) and the mean link length. A sample beyond a driver's stroke is flagged as the
closed-form steps flag it (:meth:`Group._beyond_stroke`).

Continuation on a fixed grid
----------------------------
Newton converges to the root nearest its start, which may belong to another assembly
mode, so the mode is defined by continuation from the pose. The walk follows a fixed grid
of the driver that moves (:class:`linkagekit.steps.WalkGrid`, appended to the samples by
:func:`linkagekit.positions.solve`): the pose's input plus whole steps of ``GRID_STEP``
(``GRID_STEP_LENGTH`` of the group's mean link length for a length), in two legs, up and
down from the pose's input, both legs of every design in one Newton batch per grid step,
each started from a quadratic predictor; the batch also solves the next ``LOOK_AHEAD - 1``
columns of a leg, kept while each passes the step's test from the one before (one
that fails is stepped to again from the last kept). The grid does not depend on the inputs asked; they
only say how far the legs go. A step is accepted (:meth:`Group._accept`, the one place that
decides, but for the continuous branch's sign) only when Newton converges (residual below
``NEWTON_TOL`` relative), the Jacobian's determinant keeps the pose's sign (a sign change is a
passage through a singular position: a change of mode, never silent; following the branch
continuously, :func:`_sign_passes`, it follows the determinant's trend, or keeps the sign of
the state before where no zero of the determinant lies within the step; a grid step that changes
the sign, or keeps it with the zero within it, also keeps the velocity continuous,
:meth:`Group._branch_steps`) and no joint moves
more than ``STEP_LIMIT`` times the group's mean link length (a class-3 group has up to three
roots of one sign; over a small step Newton's
root is the branch's). A step that fails waits while the other designs
go on; the waiting steps are then retried together in adaptive sub-steps (halved on
failure, doubled on success, down to ``2^-MAX_HALVINGS`` of the step), moving the known
joints as the inputs between the two columns put them (the steps before the group re-run
there, :meth:`Group._knowns`; along the chord between their two places where those steps
cannot be re-run: a numerical group before this one, or signs given per sample). A sub-step that moves a joint more than
``HOP_MOVE`` of the size must also find its way back (:meth:`Group._returns`): past a fold,
where the range ends, Newton could land on a root of the pose's sign on another sheet. A
class-3 leg that still fails stops:
after a gap it does not guess (it has up to three roots of one sign; ``modes`` lists every
mode there). A dyad-like group (one root per sign) goes on past a gap, Newton restarted
from ``RESTARTS`` points scattered about the last good configuration and about the held
joints; the walk resumes on the unique root of the pose's sign (the closed form's rule).

Every sample is then solved at once: from its cell of the grid, Newton starts at the
cubic Hermite interpolation of the cell's two solutions and their motions (from the
Jacobian, :meth:`Group._grid_slopes`), accepted by the same test within half the cell's
move; the rare rejects are reached by sub-steps from the cell's end nearer the pose, all at
once. A sample outside the walked range is flagged at once (NaN, not assembled). The pose
is given back at its input (the grid's origin starts at the pose, exact). A sample's answer
depends only on its input and the grid: not on the order of the inputs, nor on which others
are asked. **A crank's input is a direction**: an angle input u is placed on the grid at its
representative in half a turn either side of the pose's input, or, where a class-3 leg
stopped before it, at the one a turn the other way (:func:`grid_places`; also where the nearest one
lies past its leg's last solved column and does not assemble there); so u and u + 360 k
answer alike. A group that comes back in another configuration after a turn keeps, for each
direction, the configuration reached by turning less than half a turn from the pose.

Cost, at the same results
-------------------------
Newton iterates only the columns still iterating (a converged column is frozen; a column
gone NaN stays NaN), with the residual and Jacobian built from index arrays and the
Jacobian's constant linear rows built once; each Newton column is computed by the same
operations whatever else is in its batch, so batching is exact. *Chains.* Along any chain of
link edges between two held joints (two joints of one link, ``|w_p - w_q| L`` apart with
``w`` = 0, 1, ``rho_k``), the held joints are at most the sum of the edges apart and at least
twice the longest minus the sum. A configuration Newton accepts keeps every edge to about
``1e-12`` of its link, so where the held joints break a chain's bounds by more than
``CHAIN_MARGIN`` (``1e-8``) of its lengths no Newton can converge: the grid step or sample is
failed at once (no Newton, sub-steps or restarts), as it would have been after all of them.
This is the gap of a dyad (two circles that do not meet).

*Small linear systems as array operations.* LAPACK costs about 1 us per small matrix (a
6x6 solve 0.3-0.5 us, its determinant 0.25 us more), whatever its size. Where many columns
are solved at once (the samples of ``VECTOR_SAMPLES`` samples x designs or more, the walk
of ``VECTOR_DESIGNS`` designs or more, the rates of as many samples) Newton's systems are
solved by :func:`_gauss`, Gaussian elimination with partial pivoting written as about
``n^2`` array operations over the columns, which gives the determinant (the product of the
pivots, with the sign of the swaps) for free: :meth:`Group._newton_vector` factors the
Jacobian at every residual it evaluates, so a column that converges has its determinant at
its solution from that factorization. Sub-steps are LAPACK's whatever the size. Which
solver a column gets depends only on the problem's size (samples x designs, designs) and on
the column's own iteration (``VECTOR_ITER``), never on the other columns of its batch: batching stays exact. The
samples' columns still iterating after ``VECTOR_ITER`` go on together, every chunk's in one
LAPACK batch (:meth:`Group._newton_samples`). *One design's numbers are broadcast*, not
copied per column (:meth:`_Arrays.take`; the rates' constant linear rows likewise, in
:meth:`Group.jacobian`): a chunk's copy of them was 0.6 MB of fresh memory, copied again by
each Jacobian. Measured (``benchmarks/bench_group.py``, best of
3, run alternately with the code before): a triad at 10^4 samples 2.28-2.33 -> 2.11-2.15 us a
sample (positions; 2.84 -> 2.16 us in a fresh process, where every chunk's copy faults),
5.67 -> 5.20-5.26 us with rates; 10^3 designs x 360 samples 2.95-3.01 us and outside the
range 2.4-2.5 us unchanged. Then the walk's look-ahead (``LOOK_AHEAD``), the conditioning as array
operations (:func:`_condition`) and one factorization for both rates solves (:class:`_RatesSystem`),
measured by CPU time (``time.process_time``, other jobs' load on the machine made wall time useless), best of
5-7, alternately with the code before: positions 2.34-2.44 -> 1.94-2.02 us a sample, with rates
5.05-5.16 -> 3.12-3.21 us, outside the range 2.71-2.76 -> 2.42-2.50 us, the batch 3.3-3.5 us
unchanged (docs/method.md says where its time goes).

Rates
-----
Differentiating ``Phi(z_u, z_k) = 0``: ``J_u v_u = -J_k v_k`` and ``J_u a_u = -J_k a_k -
gamma``, ``gamma = 2 |v_a - v_b|^2`` for a distance row, 0 for a linear row (and the
sliders' above). The conditioning reported with the rates is the smallest singular value of
``J_u`` with its distance rows divided by ``2 L`` and its lock rows by ``|s_o1 - s_o0|`` (so
every row has unit scale) over its largest: from the extreme eigenvalues of ``J_u^T J_u``,
found as array operations (:func:`_condition`). Both systems are solved with one
factorization (:class:`_RatesSystem`).
"""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from functools import cached_property, partial
from typing import Any

import numpy as np

from .geometry import NAN_POINT, FloatArray, link_rates
from .steps import Kin, Nums, Rate, Source, Step, WalkGrid, _stroke_margin

#: Newton stops when every residual is below this, relative (distance rows / L^2, linear rows / L)
NEWTON_TOL = 1e-12
#: a sample whose Jacobian's determinant is below this part of the pose's (next to a fold) takes one more Newton step
#: once converged (:meth:`Group._polish`)
POLISH_DET = 1e-2
#: ... kept where it moves no joint more than this times the group's mean link length (and the residual falls)
POLISH_MOVE = 1e-6
#: Newton iterations per attempt
NEWTON_ITER = 16
#: Newton iterations of a sub-step (it starts from a solution a small step away: a sub-step that needs
#: more is halved, so a sub-step past the end of the range costs this many, not NEWTON_ITER)
SUBSTEP_ITER = 6
#: a group's conditioning below this is computed by an SVD (above, from the eigenvalues of J^T J: within
#: 1e-16 / COND_EXACT^2 relative of it)
COND_EXACT = 1e-3
#: the extreme eigenvalues of J^T J by Newton (:func:`_extreme_root`): converged at a step below this of the
#: largest, at most COND_ITER steps (the rest by LAPACK's eigvalsh)
COND_STEP, COND_ITER = 1e-15, 12
#: above this many unknowns (columns of J) a group's conditioning is the SVD's at once: the tridiagonal form
#: (:func:`_gram_tridiagonal`) costs about n^3 / 3 array operations in Python, past LAPACK's SVD from about
#: 18 columns (10^4 samples; 361: 14), and 7.4 of 10 s of a 97-joint chain forced onto the numerical group
COND_TRIDIAGONAL_MOST = 18
#: samples solved at once in chunks of this many (their arrays stay in the cache)
FILL_CHUNK = 2048
#: from this many designs on, the walk's Newton runs as array operations over them (:func:`_gauss`), below
#: by LAPACK per matrix (cheaper for a few: ~1 us a matrix against ~n^2 array operations a step)
VECTOR_DESIGNS = 64
#: ... and the samples' Newton from this many samples x designs on
VECTOR_SAMPLES = 4096
#: ... and for this many iterations (the few columns still iterating after them cost less by LAPACK; a column's
#: numbers still depend only on its own iterations, not on the other columns)
VECTOR_ITER = 2
#: a sub-step that moves a joint more than this times the group's mean link length is accepted only where Newton
#: from its end, back at its start's knowns, returns to its start (or to a root of the other sign): another root of
#: the pose's sign lies farther (nearer, it would be a hair from a singular position of its own)
HOP_MOVE = 1e-3
#: a converged configuration whose Jacobian's determinant is at most this part of the pose's is singular (a joint
#: undetermined, as two coincident circles leave it): not an answer (Newton converges there only by rounding)
SINGULAR_DET = 1e-12
#: a failed continuation step is retried in sub-steps down to 2^-MAX_HALVINGS of it
MAX_HALVINGS = 10
#: a grid step is taken whole only where the determinant of the group's Jacobian, extrapolated linearly through the
#: leg's last two columns, stays off zero for this many steps (:func:`_zero_ahead`); else the step is taken in
#: sub-steps, each going at most ``1 / SUB_FOLD_SHARE`` of the way to where the last two sub-steps put that zero
GRID_FOLD_SHARE = 1.0
SUB_FOLD_SHARE = 1.5
#: a sub-step after a state whose determinant's trend is not known goes at most this part of its way (it gives one)
FIRST_SUBSTEP = 1 / 16
#: ... and the determinant's zero ahead shortens no sub-step below this part of its way (finer than a failed step's
#: halvings: where the determinant only nearly vanishes the branch turns sharply, and small steps follow it through)
FINEST_SUBSTEP = 0.5**30
#: Newton iterations of the last try of a sample's sub-steps that gave up next to a fold (:meth:`Group._last_step`)
FOLD_ITER = 40
#: a way back that creeps home (not converged after a sub-step's iterations) must arrive, in ``FOLD_ITER`` in all,
#: within this part of its move of where the move started (506 such ways back about folds of triads, sliders and the
#: Pyslvs six-bar arrived within 1.6e-9; a hop across a fold onto another sheet ended 4.7 moves away, not converged)
ARRIVED = 1e-3
#: an accepted continuation step moves no joint more than this times the group's mean link length
#: (larger steps are halved: over small steps Newton's root is the branch's, not another of one sign)
STEP_LIMIT = 0.25
#: following the branch continuously, a grid step that changes the determinant's sign, or keeps it with the
#: determinant's zero within it, must keep the velocity continuous: the tangent at each end (from a determinant above
#: ``TANGENT_DET`` of the pose's) predicts the other end to within this part of the step's move (:meth:`Group._smooth`)
VELOCITY_SHARE = 0.25
TANGENT_DET = 1e-4
#: Newton starts when the walk comes back after a gap
RESTARTS = 16
#: a grid step's Newton batch also solves this many columns of the leg in all (the next ones speculatively, along
#: the quadratic predictor, for at most LOOK_AHEAD_ITER iterations: one past the range's end would iterate NEWTON_ITER)
LOOK_AHEAD = 4
LOOK_AHEAD_ITER = 8
#: the grid the walk follows: a fixed step of an angle driver's input from the pose's input (radians) ... 3 deg
#: times 998/997, so that a pose at a round angle puts no column on another round angle, where change points lie (a
#: flat position at 0 or 180 deg): for k <= 240 steps, k x step is at least 2e-4 deg from any multiple of 0.1 deg
#: (with 3 deg exactly, a double parallelogram posed at 3 deg had a column on the change point of both its loops)
GRID_STEP = np.radians(3.0) * 998 / 997
#: unknown grid columns before a step that make a gap in the range (fewer: a change point left unsolved)
GAP_COLUMNS = 3
#: the knowns' motion at the grid's origin, for a group whose knowns follow an earlier one, by a central difference
#: over this share of a grid step either side (:meth:`Group._local_rate`)
LOCAL_STEP = 1e-4
#: ... and of a length driver's, times the group's mean link length
GRID_STEP_LENGTH = 1 / 32
#: a length driver's grid goes at most this many steps either way from the pose's input
GRID_MOST = 4096
#: a chain of link edges rules a sample out only beyond this margin (relative to its lengths): far
#: above what Newton's tolerance and rounding allow a converged configuration
CHAIN_MARGIN = 1e-8
#: workspaces of at most this many floats are kept for the next call in the same thread (:func:`_workspace`)
WORKSPACE_MOST = 1 << 22
#: at most this many chains between held joints are checked (and this many search steps to find them)
MAX_CHAINS, MAX_CHAIN_SEARCH = 64, 4096


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
class GroupCylinder:
    """A cylinder driver of a group: its two ends (joints of the group, or one a known joint) are the
    driver's input apart, a length that changes from sample to sample.

    The length enters the group as a *held value* after the known joints (slot ``m + len(known) +
    i``, its real part the length): the walk moves it with the known joints, linearly between
    states, which is a homotopy in the length as in the joints (see :meth:`Group.held`).
    """

    driver: int  # index in the file's `drivers`
    ends: tuple[int, int]  # its ends as slots
    end_joints: tuple[int, int]  # ... as plan indices


@dataclass(frozen=True)
class GroupSliderDrive:
    """A slider driver of a group (an actuator written as a barrel, a rod and a slider): the point of one of the
    group's sliders is the driver's input (a displacement from its reference position) along the line.

    The displacement is a held value after the cylinders' lengths, as theirs (:class:`GroupCylinder`).
    """

    driver: int  # index in the file's `drivers`
    slider: int  # the slider's position in the group's `sliders`


@dataclass(frozen=True)
class _CRows:
    """Where a group's cylinder equations sit (after the sliders' rows), per cylinder."""

    a: np.ndarray  # (n_cyl,) the slot of its first end
    b: np.ndarray  # (n_cyl,) ... of its second
    s: np.ndarray  # (n_cyl,) the slot of its length (a held value)
    row: np.ndarray  # (n_cyl,) the row of its distance equation


@dataclass(frozen=True)
class _DRows:
    """Where a group's slider drivers' equations sit (after the cylinders' rows), per slider driver."""

    slider: np.ndarray  # (n_drv,) its slider's position in the group's sliders
    s: np.ndarray  # (n_drv,) the slot of its displacement (a held value)
    row: np.ndarray  # (n_drv,) the row of its equation


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


#: what a term of an entry of :class:`_Reduced` multiplies ``2 sign`` by: 1, ``conj(1 - rho_i)``, ``conj(rho_i)``
_ONE, _ONE_MINUS_RHO, _RHO = 0, 1, 2


@dataclass(frozen=True)
class _Reduced:
    """A revolute group's Newton system with its further joints substituted (the samples' Newton, the rates).

    A further joint ``k`` of a link (``z_k = z_a + rho (z_b - z_a)``, ``a``, ``b`` the link's first two joints) that
    is unknown and on no other link's linear rows has, on its two linear rows, the identity on its own two columns.
    Ordering the rows as the distance rows then those, and the columns as the other unknowns' then the further
    joints', ``J = [[A, B], [C, I]]``, and ``J x = b`` is ``(A - B C) x_c = b_o - B b_l``, ``x_k = b_l - C x_c``;
    ``det J = det(A - B C)`` (``det [[A, B], [C, I]] = det(A - B C)``; both orderings move rows and columns in pairs
    past others, an even permutation each). This is
    the joint substituted: a distance row's gradient ``G`` on ``k`` (complex, ``Re G dx + Im G dy``) moves to ``a``
    as ``conj(1 - rho) G`` and to ``b`` as ``conj(rho) G``; the step of ``k`` is ``-c + (1 - rho) dz_a + rho dz_b``
    (``c`` its linear residual); the right-hand side of a distance row gains ``Re(G conj(c))``. Each entry of ``A - B
    C`` is ``f e`` (``f`` a constant of the design, ``e`` the row's link vector), so ``|A - B C|_F^2 = sum_r W_r
    |e_r|^2`` and a step changes it by ``sum_r W_r |de_r|^2``, ``W_r = sum_s |f_rs|^2``. A triad's system is 4 x 4,
    not 6 x 6. Only for groups whose every further joint is so (else None): the rows left are the distance rows.
    """

    cols: np.ndarray  # (n,) the unknown slots kept, in column order (slot cols[s] has columns 2s, 2s + 1)
    k: np.ndarray  # (p,) its slot
    a: np.ndarray  # (p,) its link's first joint's slot
    b: np.ndarray  # (p,) ... second's
    entries: tuple[tuple[int, int, tuple[tuple[int, int, float], ...]], ...]  # (row, column pair, ((kind, i, sign)))
    ends: tuple[tuple[int, int, float], ...]  # (row, further joint i, sign of the row's gradient on it)

    def factors(self, R: np.ndarray) -> list[np.ndarray]:
        """Each entry's ``f`` (B,) complex: the sum of its terms, ``2 sign`` times 1 (``_ONE``), ``conj(1 - rho_i)``
        (``_ONE_MINUS_RHO``) or ``conj(rho_i)`` (``_RHO``)."""
        rho = np.conj(R[: len(self.k)])  # (every further joint's: their rhos are R's, in the linear rows' order)
        out = []
        for _, _, terms in self.entries:
            f = np.zeros(R.shape[1], complex)
            for kind, i, sg in terms:
                f = f + 2 * sg * (1.0 if kind == _ONE else 1.0 - rho[i] if kind == _ONE_MINUS_RHO else rho[i])
            out.append(f)
        return out

    def weights(self, f: list[np.ndarray], n_rows: int, B: int) -> FloatArray:
        """``W_r`` (n_rows, B) of the factors ``f``."""
        W = np.zeros((n_rows, B))
        for (r, _, _), fr in zip(self.entries, f, strict=True):
            W[r] += np.abs(fr) ** 2
        return W


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
        """The columns ``cols`` (indices or a mask). Numbers of one design (one column, or broadcast from one)
        are broadcast, not copied: they are only read, and a chunk of 2048 samples' linear rows is 0.6 MB."""
        if self.J_lin.shape[0] == 1 or self.J_lin.strides[0] == 0:
            n = int(np.count_nonzero(cols)) if cols.dtype == bool else len(cols)
            L, R, tol, J = self.L[:, :1], self.R[:, :1], self.tol[:, :1], self.J_lin[:1]
            return _Arrays(
                np.broadcast_to(L, (len(L), n)),
                np.broadcast_to(R, (len(R), n)),
                np.broadcast_to(tol, (len(tol), n)),
                np.broadcast_to(J, (n, *J.shape[1:])),
            )
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
    K0: np.ndarray  # (k, D) the known joints the start was solved with
    any_sign: bool = False  # continuous branch: a step may change the determinant's sign along its trend
    vector: bool = False  # the walk's Newton as array operations over the designs (many designs), else LAPACK
    fill_vector: bool = False  # ... and the samples' (many samples and designs)
    grid_columns: int = 0  # the walk's grid columns (the last of ``K``'s samples)
    q: np.ndarray | None = None  # (n_drivers, D, n) the inputs of ``K``'s columns
    upstream: Callable[[np.ndarray], np.ndarray | None] | None = None  # the joints before the group at inputs
    det: np.ndarray | None = None  # (D, n) the Jacobian's determinant at the grid's solved columns (NaN elsewhere)
    det0: np.ndarray = field(default_factory=lambda: np.ones(0))  # (D,) its size at the pose (set with the walk):
    # a root where it is SINGULAR_DET times that is no answer
    rough: np.ndarray | None = None  # (D, n) cells (by their column nearer the grid's start) where the groups whose
    # motion the knowns follow (:attr:`Kin.follows`) took sub-steps: their motion turns there
    substepped: np.ndarray | None = None  # (D, n) ... and those where this group's walk took sub-steps
    slopes: np.ndarray | None = None  # the grid's slopes (:meth:`Group._grid_slopes`) once the walk is finished

    def rough_cells(self, d: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Whether the cells from columns ``a`` to ``b`` (designs ``d``; ``a == b``: no cell) are :attr:`rough`."""
        if self.rough is None:
            return np.zeros(np.broadcast(d, a, b).shape, bool)
        lo = np.clip(np.minimum(a, b), 0, self.rough.shape[1] - 1)
        return self.rough[d, lo] & (a != b)  # type: ignore[no-any-return]

    def sign_ok(self, sg: np.ndarray, designs: np.ndarray) -> np.ndarray:
        """A continuation step keeps the pose's determinant sign (following the branch, any sign here: the steps
        check :func:`_sign_passes` where the states before them are known)."""
        ok: np.ndarray = (np.sign(sg) == self.ref[designs]) | self.any_sign
        return ok

    def on_grid(self, col: np.ndarray) -> np.ndarray:
        """Whether columns ``col`` of ``K`` (and ``det``) are grid columns (the samples' come first)."""
        n = self.K.shape[2]
        return (col >= n - self.grid_columns) & (col < n)  # type: ignore[no-any-return]

    def grid_det(self, d: np.ndarray, col: np.ndarray) -> np.ndarray:
        """The determinant at grid columns ``col`` of designs ``d``: NaN where unknown, or not a grid column."""
        assert self.det is not None
        return np.where(self.on_grid(col), self.det[d, np.clip(col, 0, self.det.shape[1] - 1)], np.nan)

    def regular(self, det: np.ndarray, designs: np.ndarray) -> np.ndarray:
        """A root keeping the pose's sign is not singular: its determinant above :data:`SINGULAR_DET` of the pose's
        (where a joint is undetermined, as at a rhombus's flat position, Newton converges only by rounding, to any
        point of a circle; following the branch continuously, its limit there is the answer)."""
        return self.any_sign | (np.abs(det) > self.floor(designs))  # type: ignore[no-any-return]

    def floor(self, designs: np.ndarray) -> np.ndarray:
        """The determinant at and below which a root is singular (:meth:`regular`), per column of ``designs``."""
        return np.zeros(len(designs)) if self.any_sign else SINGULAR_DET * self.det0[designs]


def _any_of(masks: list[np.ndarray | None]) -> np.ndarray | None:
    """The union of the masks given (None for none)."""
    got = [m for m in masks if m is not None]
    return np.logical_or.reduce(got) if got else None


@dataclass
class Walked:
    """A numerical group's finished walk, kept for the later groups' sub-steps (:meth:`Group.place_walked`)."""

    walk: _Walk
    grid: WalkGrid
    start: np.ndarray  # (m, D) the group's pose solution


@dataclass(frozen=True)
class _Path:
    """Sub-steps' way, per column (``designs`` (B,)): from knowns ``K0`` to ``K1`` (k, B), through the inputs from
    ``q0`` to ``q1`` (n_drivers, B) where those are given, else along the chord (:meth:`Group._knowns`)."""

    K0: np.ndarray
    K1: np.ndarray
    designs: np.ndarray
    q0: np.ndarray | None = None
    q1: np.ndarray | None = None
    rates: tuple[np.ndarray, np.ndarray] | None = None  # the knowns' motion over the path at its ends (k, B) each


@dataclass(frozen=True)
class Group(Step):
    """Joints placed together by Newton-Raphson on the natural-coordinate constraints of their links."""

    joints: tuple[int, ...]  # the group's unknown joints (plan indices)
    known: tuple[int, ...]  # the known joints its links hold (plan indices)
    links: tuple[GroupLink, ...]
    keep_rotation: tuple[str, ...] = ()
    angular: tuple[bool, ...] = ()  # per driver: an angle (the walk's added samples are 1 degree apart)
    sliders: tuple[GroupSlider, ...] = ()
    cylinders: tuple[GroupCylinder, ...] = ()
    drives: tuple[GroupSliderDrive, ...] = ()

    # ------------------------------------------------------------------ numbers
    def numbers(self, src: Source) -> Nums:
        """``(lengths, rhos, bases, zu, zk, strokes)``: the links' lengths, their further joints' rhos (then the
        sliders' and the cylinders' numbers, :meth:`_slider_numbers`, the cylinders' pose lengths), the links'
        bases, the pose's group and known joints, and the stroke ``(lo, hi)`` of each driver the group reads
        (:attr:`input_drivers`)."""
        lengths, rhos, bases = [], [], []
        for gl in self.links:
            s = [src.shape(gl.name, j) for j in gl.joints]
            base = s[1] - s[0]
            bases.append(base)
            lengths.append(np.abs(base))
            with np.errstate(divide="ignore", invalid="ignore"):
                rhos.append(tuple((sk - s[0]) / base for sk in s[2:]))
        rhos.extend(self._slider_numbers(src))
        rhos.extend((np.abs(src.pose(gc.end_joints[1]) - src.pose(gc.end_joints[0])) + 0j,) for gc in self.cylinders)
        zu = np.stack([src.pose(j) for j in self.joints])  # (m, D, 1)
        zk = np.stack([src.pose(j) for j in self.known]) if self.known else np.zeros((0, *zu.shape[1:]), complex)
        strokes = tuple(src.stroke(d) for d in self.input_drivers)
        return tuple(lengths), tuple(rhos), tuple(bases), zu, zk, strokes

    @property
    def input_drivers(self) -> tuple[int, ...]:
        """The drivers whose input the group's equations read, in held order: its cylinders, then its slider
        drivers."""
        return tuple(gc.driver for gc in self.cylinders) + tuple(gd.driver for gd in self.drives)

    @property
    def n_held(self) -> int:
        """The held values the equations read after the group's joints: the known joints, then the inputs of
        :attr:`input_drivers` (a cylinder's length, a slider driver's displacement)."""
        return len(self.known) + len(self.input_drivers)

    def held(self, z: np.ndarray, q: np.ndarray | None = None) -> np.ndarray:
        """The held values (n_held, ...) at joint positions ``z`` (n_joints, ...): the known joints, then each
        input (complex, real) of :attr:`input_drivers`: ``q[driver]`` (``q`` (n_drivers, D or 1, n) broadcast to
        ``z``'s samples) or, without ``q``, a cylinder's ends' distance in ``z`` and 0 for a slider driver's
        displacement (its rows' Jacobian and acceleration terms do not read it; :meth:`inputs_at` does)."""
        known = z[list(self.known)] if self.known else np.zeros((0, *z.shape[1:]), complex)
        if not self.input_drivers:
            return known
        if q is None:
            ins = [np.abs(z[gc.end_joints[1]] - z[gc.end_joints[0]]) for gc in self.cylinders]
            ins += [np.zeros(z.shape[1:]) for _ in self.drives]
        else:
            ins = [np.broadcast_to(q[d], z.shape[1:]) for d in self.input_drivers]
        return np.concatenate([known, np.array(ins, float).astype(complex)])

    def inputs_at(self, P: np.ndarray, R: np.ndarray) -> np.ndarray:
        """The inputs of :attr:`input_drivers` (n_in, B) that slot positions ``P`` (n_slots, B; its held inputs
        not read) realise with numbers ``R``: the cylinders' ends' distances, the slider drivers' displacements
        ``Re(w conj(u))`` (see the module's docstring)."""
        cr = self._crows
        ins = [np.abs(P[cr.b] - P[cr.a])]
        if self.drives:
            dr = self._drows
            rho, dhat, _, _ = self._snums(R)
            A, e = self._frames(P)
            i = dr.slider
            ins.append(((P[self._srows.k[i]] - A[i] - rho[i] * e[i]) * np.conj(dhat[i] * e[i])).real)
        return np.concatenate(ins)

    def stroke_margins(self, z: np.ndarray, nums: Nums) -> np.ndarray:
        """How far each input of :attr:`input_drivers` is inside its stroke at positions ``z`` (n_joints, D, n):
        (n_in, D, n), negative outside; a cylinder's relative to its length (as the closed-form cylinder steps'
        margins), a slider driver's relative to the group's mean link length."""
        D, n = z.shape[1:]
        P = np.concatenate([z[list(self.joints)], self.held(z)]).reshape(-1, D * n)
        L, R = self._stack(self._design_nums(nums, np.repeat(np.arange(D), n)), D * n)
        ins = self.inputs_at(P, R).reshape(-1, D, n)
        size = np.mean(L, axis=0).reshape(D, n)
        out = []
        for i, (lo, hi) in enumerate(nums[5]):
            if i < len(self.cylinders):
                out.append(_stroke_margin(ins[i], lo, hi, 0.0))
            else:
                with np.errstate(invalid="ignore"):
                    out.append(np.minimum(ins[i] - lo, hi - ins[i]) / size)
        return np.array(out, float).reshape(len(out), D, n)

    def _pose_held(self, zu: np.ndarray, zk: np.ndarray, R: np.ndarray) -> np.ndarray:
        """The held values of a start (the group's joints ``zu`` and known joints ``zk``): its inputs are those
        the start realises (:meth:`inputs_at`)."""
        if not self.input_drivers:
            return zk
        P = np.concatenate([zu, zk, np.zeros((len(self.input_drivers), *zk.shape[1:]), complex)])
        return np.concatenate([zk, self.inputs_at(P, R) + 0j])

    def _beyond_stroke(self, q: np.ndarray, strokes: Nums, eps: float, shape: tuple[int, ...]) -> np.ndarray:
        """The samples (D, n) where an input is beyond its stroke: a cylinder's length (or not positive) as the
        closed-form cylinder steps flag it, a slider driver's displacement as :class:`~linkagekit.steps.SliderDrive`
        does (beyond ``eps`` of the stroke's larger end)."""
        out = np.zeros(shape, bool)
        n_cyl = len(self.cylinders)
        for i, (d, (lo, hi)) in enumerate(zip(self.input_drivers, strokes, strict=True)):
            u = np.broadcast_to(q[d], shape)
            if i < n_cyl:
                out |= _stroke_margin(u, lo, hi, eps) < 0
            else:
                slack = eps * np.maximum(np.abs(lo), np.abs(hi))  # no stroke: lo - slack = -inf, hi + slack = inf
                out |= (u < lo - slack) | (u > hi + slack)
        return out

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

    @cached_property  # asked at every restart of the walk: 0.6 s of a 97-joint group's sweep when recounted
    def dyad_like(self) -> bool:
        """One joint of the group is on two of its links, the others ride on one: two roots, one per sign.

        Only then does the walk restart after a gap (a class-3 group has up to three roots of one
        sign, so there a sample it cannot reach by continuation stays flagged).
        """
        on_two = sum(
            sum(j in gl.joints for gl in self.links)
            + sum(j == gs.point_joint for gs in self.sliders)
            + sum(j in gc.end_joints for gc in self.cylinders)
            >= 2
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
    def _reduced(self) -> _Reduced | None:
        """The Newton system with the further joints substituted (:class:`_Reduced`), where every further joint is
        unknown, on one link's linear rows and neither end of a link with linear rows; else None."""
        rw, m = self._rows, len(self.joints)
        ks = [int(k) for k in rw.k]
        ends = {int(x) for x in (*rw.a[rw.link], *rw.b[rw.link])}
        if not (self.revolute and ks) or any(k >= m or k in ends or ks.count(k) > 1 for k in ks):
            return None
        a, b = rw.a[rw.link], rw.b[rw.link]
        cols = np.setdiff1d(np.arange(m), ks)
        if not len(cols):  # (a further joint of two known ones: the plan places it in closed form)
            return None
        col_of, elim = {int(c): i for i, c in enumerate(cols)}, {k: i for i, k in enumerate(ks)}
        terms: dict[tuple[int, int], list[tuple[int, int, float]]] = {}
        on_k = []
        for r in range(len(self.links)):
            for slot, sg in ((int(rw.b[r]), 1.0), (int(rw.a[r]), -1.0)):
                if slot in elim:  # its gradient moves to its link's first two joints
                    i = elim[slot]
                    on_k.append((r, i, sg))
                    for end, kind in ((int(a[i]), _ONE_MINUS_RHO), (int(b[i]), _RHO)):
                        if end < m:
                            terms.setdefault((r, col_of[end]), []).append((kind, i, sg))
                elif slot < m:
                    terms.setdefault((r, col_of[slot]), []).append((_ONE, 0, sg))
        entries = tuple((r, c, tuple(t)) for (r, c), t in sorted(terms.items()))
        return _Reduced(cols, np.array(ks), a, b, entries, tuple(on_k))

    def _factor(
        self, P: np.ndarray, ar: _Arrays, res: FloatArray, done: np.ndarray, vector: bool, work: FloatArray | None
    ) -> tuple[FloatArray, FloatArray, Callable[[np.ndarray], tuple[FloatArray, FloatArray | None]]]:
        """Newton's steps ``dx`` (B, 2m) from slot positions ``P`` with residuals ``res``, the Jacobians'
        determinants (B,) (:func:`_solve_small`; ``vector`` and a :attr:`_reduced` system: that system's), and
        ``bound(cols)``: for columns ``cols``, a lower bound of each Jacobian's smallest singular value and the
        weights of its change along a step (:meth:`_kept_det`; None: the whole Jacobian's)."""
        if vector and self._reduced is not None:
            return self._reduced_step(P, ar, res, work)
        J = self._jac(P, ar.J_lin, ar.R)
        dx, det = _solve_small(J, res, done, vector, work)
        return dx, det, lambda cols: (_smallest_singular_bound(J[cols], det[cols]), None)

    def _reduced_step(
        self, P: np.ndarray, ar: _Arrays, res: FloatArray, work: FloatArray | None
    ) -> tuple[FloatArray, FloatArray, Callable[[np.ndarray], tuple[FloatArray, FloatArray | None]]]:
        """:meth:`_factor` by the reduced system (:class:`_Reduced`), by :func:`_eliminate`."""
        red = self._reduced
        assert red is not None
        n, B = 2 * len(red.cols), P.shape[1]
        work = np.empty(_gauss_size(n, B)) if work is None else work
        A = work[: n * (n + 1) * B].reshape(n, n + 1, B)
        e, f = self._reduced_matrix(P, ar.R, -res, A)
        W = red.weights(f, n, B)
        frob = np.sum(W * (e.real**2 + e.imag**2), axis=0)
        xc, det = _eliminate(A, work[n * (n + 1) * B :])
        dx = self._reduced_expand(xc, -res, ar.R)
        return dx, det, lambda cols: (_singular_bound(det[cols], frob[cols], n), W[:, cols])

    def _reduced_matrix(
        self, P: np.ndarray, R: np.ndarray, b: FloatArray, A: FloatArray
    ) -> tuple[np.ndarray, list[np.ndarray]]:
        """The reduced system (:class:`_Reduced`) of ``J x = b`` (``b`` (n_eq, B)) at slot positions ``P`` into ``A``
        (n, n + 1, B), augmented with its right-hand side (:meth:`_reduced_rhs`): (the links' vectors ``e``, the
        entries' factors)."""
        red, rw = self._reduced, self._rows
        assert red is not None
        n = A.shape[0]
        A[:, :n] = 0.0
        e = P[rw.b] - P[rw.a]
        f = red.factors(R)
        for (r, c, _), fr in zip(red.entries, f, strict=True):
            g = fr * e[r]
            A[r, 2 * c], A[r, 2 * c + 1] = g.real, g.imag
        A[:, n] = self._reduced_rhs(e, b)
        return e, f

    def _reduced_rhs(self, e: np.ndarray, b: FloatArray) -> FloatArray:
        """``b_o - B b_l`` (n, B) of ``b`` (n_eq, B): a distance row's ``b`` less ``Re(G conj(b_k))`` for a further
        joint ``k`` at its end (``G = +/- 2 e`` its gradient there, ``b_k`` the joint's linear rows' ``b``)."""
        red, rw = self._reduced, self._rows
        assert red is not None
        out = b[rw.dist].copy()
        lin = b[rw.lin] + 1j * b[rw.lin + 1]
        for r, i, sg in red.ends:
            out[r] -= 2 * sg * (e[r] * np.conj(lin[i])).real
        return out  # type: ignore[no-any-return]

    def _reduced_expand(self, xc: FloatArray, b: FloatArray, R: np.ndarray) -> FloatArray:
        """The whole solution (B, 2m) of ``J x = b`` from the reduced system's ``xc`` (B, n): a further joint's
        ``x_k = b_k + (1 - rho) x_a + rho x_b`` (0 for a known end)."""
        red, rw = self._reduced, self._rows
        assert red is not None
        m, B = len(self.joints), len(xc)
        dz = np.zeros((m + 1, B), complex)  # the unknowns' steps, and a zero for a known end last
        dz[red.cols] = (xc[:, 0::2] + 1j * xc[:, 1::2]).T
        rho = R[: len(red.k)]
        ea, eb = np.where(red.a < m, red.a, m), np.where(red.b < m, red.b, m)
        dz[red.k] = b[rw.lin] + 1j * b[rw.lin + 1] + (1 - rho) * dz[ea] + rho * dz[eb]
        dx = np.empty((B, 2 * m))
        dx[:, 0::2], dx[:, 1::2] = dz[:m].real.T, dz[:m].imag.T
        return dx

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

    @cached_property
    def _crows(self) -> _CRows:
        row = self._crows_start
        first = len(self.joints) + len(self.known)
        a = [gc.ends[0] for gc in self.cylinders]
        b = [gc.ends[1] for gc in self.cylinders]
        n = len(self.cylinders)
        out = (a, b, list(range(first, first + n)), list(range(row, row + n)))
        return _CRows(*(np.array(x, dtype=np.intp) for x in out))

    @cached_property
    def _drows(self) -> _DRows:
        first = self._crows_start + len(self.cylinders)
        slot = len(self.joints) + len(self.known) + len(self.cylinders)
        n = len(self.drives)
        sl = [gd.slider for gd in self.drives]
        return _DRows(*(np.array(x, dtype=np.intp) for x in (sl, range(slot, slot + n), range(first, first + n))))

    @property
    def _crows_start(self) -> int:
        """The first row after the links' and the sliders'."""
        return sum(1 + 2 * (len(gl.slots) - 2) for gl in self.links) + sum(gs.n_rows for gs in self.sliders)

    def _drive_res(self, P: np.ndarray, R: np.ndarray, res: FloatArray) -> None:
        """The slider drivers' residuals into ``res``: ``Re(w conj(u)) - x``, ``x`` the displacement (a held value)."""
        dr = self._drows
        res[dr.row] = self.inputs_at(P, R)[len(self.cylinders) :] - P[dr.s].real

    def _drive_jac(self, P: np.ndarray, R: np.ndarray, J: FloatArray) -> None:
        """The slider drivers' Jacobian rows into ``J``: the real part's gradients of the slider's line row (``u``
        on ``k``, ``conj(rho - 1) u - w conj(dhat)`` on ``c0``, ``-conj(rho) u + w conj(dhat)`` on ``c1``; none on
        the ground) and ``-1`` on the displacement's slot."""
        dr, sr = self._drows, self._srows
        i = dr.slider
        rho, dhat, _, _ = self._snums(R)
        A, e = self._frames(P)
        rho, dhat, A, e = rho[i], dhat[i], A[i], e[i]
        u, w = dhat * e, P[sr.k[i]] - A - rho * e
        wd = w * np.conj(dhat)
        n_cols = J.shape[2] // 2
        _add(J, dr.row, sr.k[i], u, n_cols)
        _add(J, dr.row, sr.c0[i], np.conj(rho - 1) * u - wd, n_cols)
        _add(J, dr.row, sr.c1[i], -np.conj(rho) * u + wd, n_cols)
        _add(J, dr.row, dr.s, -np.ones_like(u), n_cols)

    def _drive_gamma(self, V: np.ndarray, R: np.ndarray) -> np.ndarray:
        """The slider drivers' acceleration terms (n_drives, B) at velocities ``V``: ``2 Re(w' conj(u'))``."""
        dr, sr = self._drows, self._srows
        i = dr.slider
        rho, dhat, _, _ = self._snums(R)
        vA, ve = self._frames(V, rates=True)
        out: np.ndarray = 2 * ((V[sr.k[i]] - vA[i] - rho[i] * ve[i]) * np.conj(dhat[i] * ve[i])).real
        return out

    def _cnums(self, R: np.ndarray) -> np.ndarray:
        """The cylinders' pose lengths (n_cyl, B) from ``R`` (after the links' rhos and the sliders' numbers)."""
        n = len(self._rows.k) + 4 * len(self.sliders)
        return R[n : n + len(self.cylinders)].real

    def _cyl_res(self, P: np.ndarray, res: FloatArray) -> None:
        """The cylinders' residuals into ``res``: ``|z_b - z_a|^2 - s^2``, ``s`` the length (a held value)."""
        cr = self._crows
        e = P[cr.b] - P[cr.a]
        s = P[cr.s].real
        res[cr.row] = e.real * e.real + e.imag * e.imag - s * s

    def _cyl_jac(self, P: np.ndarray, J: FloatArray) -> None:
        """The cylinders' Jacobian rows into ``J``: ``2 e`` on ``b``, ``-2 e`` on ``a`` (``e = z_b - z_a``), and
        ``-2 s`` on the length's slot (its real part: the length)."""
        cr = self._crows
        e = P[cr.b] - P[cr.a]
        n_cols = J.shape[2] // 2
        _add(J, cr.row, cr.b, 2 * e, n_cols)
        _add(J, cr.row, cr.a, -2 * e, n_cols)
        _add(J, cr.row, cr.s, -2 * P[cr.s].real + 0j, n_cols)

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
        end = n + 4 * len(self.sliders)
        return R[n:end:4], R[n + 1 : end : 4], R[n + 2 : end : 4], R[n + 3 : end : 4]

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
        if self.cylinders:
            self._cyl_res(P, res)
        if self.drives:
            self._drive_res(P, R, res)
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
        if self.cylinders:
            scale[self._crows.row] = self._cnums(R) ** 2
        if self.drives:
            scale[self._drows.row] = np.mean(L, axis=0)
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
        if self.cylinders:
            self._cyl_jac(P, J)
        if self.drives:
            self._drive_jac(P, R, J)
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
        if R.shape[1] > 1 and np.array_equal(R, np.broadcast_to(R[:, :1], R.shape)):  # one design: built once
            J_lin = np.broadcast_to(self._lin_jacobian(R[:, :1], n_slots), (R.shape[1], self.n_eq, 2 * n_slots))
            return self._jac(P, J_lin, R)
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
        self, U: np.ndarray, K: np.ndarray, nums: Nums, iters: int = NEWTON_ITER, vector: bool = False
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Newton from ``U`` (m, B) with knowns ``K`` (k, B): (solution, converged, det sign).

        Each column is iterated until its residual passes (then it is left as it is), for at
        most ``iters`` steps; only the columns still iterating are computed (a column whose
        step is not finite is NaN from the next step on: it is dropped, NaN). ``vector``: the
        linear algebra as array operations over the columns (:func:`_gauss`), else LAPACK.
        """
        U, conv, det = self._newton(U, K, self._arrays(nums, U.shape[1]), iters, vector)
        return U, conv, np.sign(det)

    def _newton(
        self,
        U: np.ndarray,
        K: np.ndarray,
        ar: _Arrays,
        iters: int = NEWTON_ITER,
        vector: bool = False,
        work: FloatArray | None = None,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`newton` with the numbers as arrays, and the determinant itself (its value, not only its sign: the
        walk reads how it falls, :func:`_zero_ahead`); ``vector``: :meth:`_newton_vector` (``work``: its workspace)."""
        if vector:
            return self._newton_vector(U, K, ar, iters, work)
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
        return U, conv, det

    def _newton_vector(
        self,
        U: np.ndarray,
        K: np.ndarray,
        ar: _Arrays,
        iters: int = NEWTON_ITER,
        work: FloatArray | None = None,
        reuse: bool = False,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`_newton` with its linear algebra as array operations over the columns (:func:`_solve_small`).

        The Jacobian is factored at every residual evaluated: a column that converges has its
        determinant (at its solution) from that factorization, one still iterating its step.
        Only the first ``VECTOR_ITER`` iterations are vectorized (the few columns left cost less
        by LAPACK; a column's numbers depend only on its own iterations, not on the others).
        ``reuse``: a column that converges after a step too small to move its determinant's sign keeps the
        determinant factored before the step (:meth:`_kept_det`), and is not factored again.
        """
        U = U.copy()
        conv, det = np.zeros(U.shape[1], bool), np.zeros(U.shape[1])
        act, Ua, Ka, ara = np.arange(U.shape[1]), U, K, ar  # the columns still iterating and their numbers
        dU, smin = np.zeros_like(U), np.zeros(U.shape[1])  # the last step, and its start's smallest singular value
        weights: FloatArray | None = None  # ... and the weights of the Jacobian's change (:meth:`_kept_det`)
        reuse = reuse and self.revolute  # only distance and linear rows bound the Jacobian's change by the step
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            for it in range(iters + 1):
                P = np.concatenate([Ua, Ka]) if len(K) else Ua
                res = self._res(P, ara.L, ara.R)
                passed = np.all(np.abs(res) <= ara.tol, axis=0)
                if reuse and it:
                    kept = passed & self._kept_det(dU, smin, weights)
                    if kept.any():
                        conv[act[kept]], U[:, act[kept]] = True, Ua[:, kept]
                        if kept.all():
                            break
                        rest = ~kept
                        act, Ua, Ka, ara, P = act[rest], Ua[:, rest], Ka[:, rest], ara.take(rest), P[:, rest]
                        res, passed = res[:, rest], passed[rest]
                done = passed | (it == iters)
                dx, det[act], bound = self._factor(P, ara, res, done, it < VECTOR_ITER, work)
                conv[act[passed]] = True
                go = ~done & np.all(np.isfinite(dx), axis=1)  # a step not finite: the column is NaN, dropped
                U[:, act[~go]] = np.where(done, Ua, NAN_POINT)[:, ~go]
                det[act[~done & ~go]] = 0.0
                if not go.any():
                    break
                if reuse:
                    smin, weights = bound(go)
                if not go.all():
                    act, Ua, Ka, ara = act[go], Ua[:, go], Ka[:, go], ara.take(go)
                    dx = dx[go]
                dU = (dx[:, 0::2] + 1j * dx[:, 1::2]).T
                Ua = Ua + dU
            self._lapack_det_where_zero(U, K, ar, conv, det)
        conv &= np.isfinite(det) & (det != 0)
        return U, conv, det

    @cached_property
    def revolute(self) -> bool:
        """Whether every row is a distance or a linear one (no slider, cylinder or slider driver)."""
        return not (self.sliders or self.cylinders or self.drives)

    def _kept_det(self, dU: np.ndarray, smin: FloatArray, W: FloatArray | None = None) -> np.ndarray:
        """Whether the step ``dU`` (m, B) left each column's determinant's sign, and its size to within a factor
        (1 +/- 1/20)^(2m), as it was before the step, where ``smin`` (B,) bounds the smallest singular value of the
        Jacobian there from below.

        Only the distance rows change, by ``2 (de_b - de_a)`` on each unknown end, so the change ``E`` has
        ``|E|_F^2 <= 8 sum |de|^2``; with ``|E|_2 <= smin / 20`` every eigenvalue of ``J^-1 (J + E)`` lies within
        1/20 of 1, and ``det(J + E) / det(J)``, their product, is positive and in that range (a step a Newton that
        has converged takes is 1e-6 of the size or less). ``W`` (n_links, B): for the reduced system
        (:class:`_Reduced`), whose change is exactly ``|E|_F^2 = sum_r W_r |de_r|^2``, instead of 8."""
        rw = self._rows
        d = np.concatenate([dU, np.zeros((self.n_held, dU.shape[1]), dU.dtype)])
        de = d[rw.b] - d[rw.a]
        change = np.sqrt(np.sum((8.0 if W is None else W) * (de.real**2 + de.imag**2), axis=0))
        kept: np.ndarray = change <= smin / 20
        return kept

    def _lapack_det_where_zero(
        self, U: np.ndarray, K: np.ndarray, ar: _Arrays, conv: np.ndarray, det: FloatArray
    ) -> None:
        """Where a converged column's pivots give an exactly zero determinant (an exactly singular position, such
        as a parallelogram's flat one), its determinant by LAPACK as :meth:`_newton` takes it (its rounding is
        what decides there), written into ``det``."""
        zero = np.flatnonzero(conv & (det == 0))
        if len(zero):
            P = np.concatenate([U[:, zero], K[:, zero]]) if len(K) else U[:, zero]
            J = self._jac(P, ar.J_lin[zero], ar.R[:, zero])
            det[zero] = np.linalg.det(np.where(np.isfinite(J), J, 0.0))

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
        dn = self._design_nums(nums, np.arange(D))
        zk0 = self._pose_held(zu0, np.broadcast_to(nums[4][:, :, 0], (len(self.known), D)), self._stack(dn, D)[1])
        upstream, rough, follows = self._after(k)
        K_all = self.held(z, k.q)  # the known joints, then the cylinders' lengths (the drivers' inputs)
        start, conv0, ref_sign = self.newton(zu0.copy(), zk0.copy(), dn)  # the pose (exact unless `lengths`)
        start = np.where(conv0, start, NAN_POINT)
        lo, hi, mg = self._reach(dn, D)
        ok = np.all(np.isfinite(K_all), axis=0) & conv0[:, None]
        ok &= self._possible(K_all, (lo[..., None], hi[..., None], mg[..., None]))
        w = _Walk(
            K_all,
            ok,
            np.full((m, D, n), NAN_POINT),
            ref_sign,
            nums,
            _size(dn),
            self._arrays(dn, D),
            (lo, hi, mg),
            zk0,
            k.continuous,
            D >= VECTOR_DESIGNS,
            D * n >= VECTOR_SAMPLES,
            0 if k.grid is None else len(k.grid.index),
            np.broadcast_to(k.q, (k.q.shape[0], D, n)),
            upstream,
            np.full((D, n), np.nan),
        )
        w.det0 = np.abs(self._dets(start, zk0, np.arange(D), w))
        w.rough, w.substepped = rough, np.zeros((D, n), bool)
        g = k.grid
        if g is None:  # no grid (no driver moves): every sample from the pose, by sub-steps
            c, s = np.nonzero(ok)
            self._from_state(start[:, c], zk0[:, c], start[:, c], c, s, w)
        else:
            places, second, legs = self._walk_grid(g, k, start, w)
            self._solve_samples(g, places, start, w)
            places = self._other_turn(g, legs, second, start, places, w)
            if k.took is None:
                k.took = np.where(np.all(np.isfinite(w.out[:, :, : g.n_given]), axis=0), places, np.nan)
            k.walks[id(self)] = Walked(w, g, start)
            k.follows.update((j, follows | {id(self)}) for j in self.joints)
        if self.input_drivers:
            w.out[:, self._beyond_stroke(k.q, nums[5], k.eps, (D, n))] = NAN_POINT
        for i, j in enumerate(self.joints):
            z[j] = w.out[i]
        self._keep_rotations(k, nums)

    def _keep_rotations(self, k: Kin, nums: Nums) -> None:
        """The rotations of the links later steps read (:attr:`keep_rotation`), from the placed joints."""
        if self.keep_rotation:
            bases = dict(zip((gl.name for gl in self.links), nums[2], strict=True))
            for gl in self.links:
                if gl.name in self.keep_rotation:
                    k.rot[gl.name] = (k.z[gl.joints[1]] - k.z[gl.joints[0]]) / bases[gl.name]

    def _after(
        self, k: Kin
    ) -> tuple[Callable[[np.ndarray], np.ndarray | None] | None, np.ndarray | None, frozenset[int]]:
        """What the group reads of the numerical groups before it: the steps before re-run at other inputs (None:
        its knowns move on their chord), the cells where the groups its knowns follow took sub-steps
        (:attr:`_Walk.rough`, None for none), and those groups (:attr:`Kin.follows`).

        The steps before are re-run where they hold no group, or where the knowns follow one. A group that holds
        none of an earlier group's joints keeps the chord, as following the branch continuously does (signs per
        sample: which hold between two samples is not known)."""
        follows = frozenset().union(*(k.follows.get(j, frozenset()) for j in self.known))
        if k.continuous and k.walks:
            return None, None, follows
        upstream = None if k.upstream is None or (k.walks and not follows) else partial(k.upstream, stop=self)
        return upstream, _any_of([k.walks[i].walk.substepped for i in follows if i in k.walks]), follows

    def place_walked(self, k: Kin, nums: Nums, walked: Walked) -> None:
        """The group's joints at the inputs of ``k`` (n_drivers, D, r; the steps before it placed there), from its
        finished walk (``walked``): each input on its grid as it is, no turn taken off (the inputs of a later
        group's sub-steps between two of its columns, :meth:`_knowns`), solved as a sample is.

        The later group's knowns then move as this group moves them. Along the chord between two columns, or the
        cubic through them, they cut across a sharp turn of this group's motion: a triad after one that turns
        sharply left its range through a fold 0.34 deg past the pose and came back into it 0.2 deg on, and with
        one Newton per grid step walked on to 40 deg on another branch."""
        w0, g = walked.walk, walked.grid
        assert w0.q is not None  # a walk over a grid has its inputs
        G, r = len(g.index), k.q.shape[-1]
        D = w0.K.shape[1]
        K_new = self.held(k.z, k.q)
        ok = np.all(np.isfinite(K_new), axis=0) & np.all(np.isfinite(walked.start), axis=0)[:, None]
        ok &= self._possible(K_new, tuple(x[..., None] for x in w0.reach))  # type: ignore[arg-type]
        if w0.slopes is None:
            w0.slopes = self._grid_slopes(g, w0)

        def cat(new: np.ndarray, old: np.ndarray) -> np.ndarray:
            return np.concatenate([np.broadcast_to(new, (*old.shape[:-1], r)), old[..., -G:]], axis=-1)

        w = replace(
            w0,
            K=cat(K_new, w0.K),
            ok=cat(ok, w0.ok),
            out=cat(np.full((), NAN_POINT), w0.out),
            q=cat(k.q, w0.q),
            det=None if w0.det is None else cat(np.full((), np.nan), w0.det),
            rough=None if w0.rough is None else cat(np.zeros((), bool), w0.rough),
            substepped=None,
        )
        x0 = w0.q[g.driver, :, w0.q.shape[-1] - G + int(np.searchsorted(g.index, 0))]  # the origin: the pose's input
        places = (np.broadcast_to(k.q[g.driver], (D, r)) - x0[:, None]) / g.step[:, None]
        self._solve_samples(replace(g, n_given=r), places, walked.start, w)
        out = w.out[:, :, :r]
        if self.input_drivers:
            out[:, self._beyond_stroke(k.q, nums[5], k.eps, (D, r))] = NAN_POINT
        for i, j in enumerate(self.joints):
            k.z[j] = out[i]
        self._keep_rotations(k, nums)

    # ------------------------------------------------------------------ the walk over the grid
    def _walk_grid(
        self, g: WalkGrid, k: Kin, start: np.ndarray, w: _Walk
    ) -> tuple[np.ndarray, np.ndarray, tuple[_Leg, _Leg]]:
        """Walk the grid from the pose as far as the samples need: each sample's place on it, a second place to
        try where the first fails (both (D, n_given), NaN where there is none), and the legs.

        The two legs (up and down from the pose's input) step together, one Newton batch per
        grid step for every design. A class-3 leg stops where a step fails; a dyad-like leg
        goes on (restarting after a gap). A sample's place (in grid steps from the pose's
        input) is, for an angle, the representative of its direction nearest the pose's input
        when a leg reaches it, else the other one (a turn the other way) when the other leg
        does (a second walk, as far as those need); NaN where neither is reached. A nearest
        representative past the last column its leg solved (the range may end in that cell)
        has the other representative as its second place (:meth:`_other_turn`).
        """
        D = start.shape[1]
        u = np.broadcast_to(k.q[g.driver, :, : g.n_given], (D, g.n_given))
        x0 = np.broadcast_to(np.asarray(k.q0, float)[g.driver], (D,))
        near, other = grid_places(u, x0, g.step, g.cyclic)
        if k.turn is not None:  # the mechanism takes these directions a turn the other way
            near, other = np.where(k.turn, other, near), np.where(k.turn, np.nan, other)
        if k.took is not None:  # an earlier group took each direction one way round: this one takes it the same way
            near = k.took
        c0 = int(np.searchsorted(g.index, 0))
        origin = self._origin(start, g.n_given + c0, w)
        legs = (_Leg.new(origin, w, g, c0, 1), _Leg.new(origin, w, g, c0, -1))
        self._walk_legs(legs, near, w, g)
        covered = legs[0].covers(near, c0) | legs[1].covers(near, c0)
        if not g.cyclic or self.dyad_like or k.took is not None:
            return np.where(covered, near, np.nan), np.full_like(near, np.nan), legs
        edge = legs[0].past_solved(near, c0) | legs[1].past_solved(near, c0)
        second = np.where(edge, other, np.nan)
        if covered.all():
            return near, second, legs
        alt = np.where(covered, np.nan, other)
        self._walk_legs(legs, alt, w, g)
        use = ~covered & (legs[0].covers(alt, c0) | legs[1].covers(alt, c0))
        return np.where(covered, near, np.where(use, alt, np.nan)), second, legs

    def _other_turn(
        self, g: WalkGrid, legs: tuple[_Leg, _Leg], second: np.ndarray, start: np.ndarray, places: np.ndarray, w: _Walk
    ) -> np.ndarray:
        """Samples not assembled at their nearest representative, where it lay past its leg's last solved column,
        tried at the representative a turn the other way (``second``), the legs walked as far as those need.

        A class-3 range that nearly spans a turn ends inside a cell both ways: a direction past one
        end, in the cell where that leg stopped (or would have), may lie on the branch a turn the
        other way, before its other end. Returns each sample's place as finally tried (``places``, or
        ``second`` where that was tried)."""
        retry = np.isfinite(second) & w.ok[:, : g.n_given] & ~np.all(np.isfinite(w.out[:, :, : g.n_given]), axis=0)
        if not retry.any():
            return places
        alt = np.where(retry, second, np.nan)
        self._walk_legs(legs, alt, w, g)
        c0 = int(np.searchsorted(g.index, 0))
        reached = legs[0].covers(alt, c0) | legs[1].covers(alt, c0)
        self._solve_samples(g, np.where(reached, alt, np.nan), start, w)
        out: np.ndarray = np.where(reached, alt, places)
        return out

    def _origin(self, start: np.ndarray, col: int, w: _Walk) -> np.ndarray:
        """The grid's origin (the pose's input, column ``col``) solved from the group's start, written to ``out``.

        The start is the pose, solved with its own known joints: at the pose's input Newton
        returns it as it is. (A start given at another input, as :mod:`linkagekit.groupmodes`
        gives a mode, is carried there by sub-steps.)
        """
        D = start.shape[1]
        d = np.arange(D)
        U, acc = self._plain(start, start, w.K[:, :, col], d, w)
        todo = np.flatnonzero(~acc & np.all(np.isfinite(start), axis=0) & w.ok[:, col])
        if len(todo):
            U[:, todo] = self._halving(start[:, todo], _Path(w.K0[:, todo], w.K[:, todo, col], todo), w)
            acc[todo] = np.all(np.isfinite(U[:, todo]), axis=0)
        U = np.where(acc & w.ok[:, col], U, NAN_POINT)
        w.out[:, :, col] = U
        if w.det is not None:
            w.det[:, col] = self._dets(U, w.K[:, :, col], d, w)
            self._origin_trend(U, col, w)
        return U

    def _origin_trend(self, U: np.ndarray, col: int, w: _Walk) -> None:
        """The determinant's trend at the grid's origin ``col`` (solved ``U``), written to ``w.det`` at the columns
        either side until the legs solve them: ``det -/+ det'`` a grid step away, ``det'`` by a central difference
        along the tangent (``J_u V = -J_k dK``, ``dK`` the knowns' central difference over the two columns): the
        first step of each leg has a trend to read (:meth:`_clear_of_zero`), as every later one has."""
        assert w.det is not None
        first, n = w.K.shape[2] - w.grid_columns, w.K.shape[2]
        if not first < col < n - 1 or not self.n_held:
            return
        d = np.flatnonzero(np.isfinite(w.det[:, col]))
        K = w.K[:, d, col]
        dK = (w.K[:, d, col + 1] - w.K[:, d, col - 1]) / 2
        if w.rough is not None:  # the knowns follow an earlier group, which may turn sharply inside a grid step
            dK = self._local_rate(d, col, w, dK)
        V = self._tangent(U[:, d], K, dK, d, w)
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            eps = 1e-3
            ahead, back = (self._dets(U[:, d] + e * V, K + e * dK, d, w) for e in (eps, -eps))
            slope = (ahead - back) / (2 * eps)
        w.det[d, col + 1] = w.det[d, col] + slope
        w.det[d, col - 1] = w.det[d, col] - slope

    def _local_rate(self, d: np.ndarray, col: int, w: _Walk, dK: np.ndarray) -> np.ndarray:
        """The knowns' motion per grid step at column ``col`` (designs ``d``) by a central difference over
        ``LOCAL_STEP`` of a grid step, the steps before re-run there (:attr:`_Walk.upstream`); ``dK`` where they
        cannot be.

        The central difference over the columns either side averages the motion over two grid steps: where an
        earlier group turns sharply next to the pose, it says nothing of the motion there, nor so of the
        determinant's trend (a triad whose fold lay 0.007 deg above its pose stepped over it)."""
        if w.upstream is None or w.q is None:
            return dK
        q0, q1 = w.q[:, :, col], w.q[:, :, col + 1]
        q2 = np.stack([q0 - LOCAL_STEP * (q1 - q0), q0 + LOCAL_STEP * (q1 - q0)], axis=-1)
        z = w.upstream(q2)
        if z is None:
            return dK
        Kh = self.held(z, q2)
        local: np.ndarray = ((Kh[:, :, 1] - Kh[:, :, 0]) / (2 * LOCAL_STEP))[:, d]
        return np.where(np.all(np.isfinite(local), axis=0), local, dK)

    def _tangent(self, U: np.ndarray, K: np.ndarray, dK: np.ndarray, d: np.ndarray, w: _Walk) -> np.ndarray:
        """The group's motion ``V`` (m, B) at ``U`` with knowns ``K`` (columns of designs ``d``) as the knowns move by
        ``dK``: ``J_u V = -J_k dK`` (NaN where singular)."""
        m = U.shape[0]
        J = self.jacobian(np.concatenate([U, K]), self._design_nums(w.nums, d), m + self.n_held)
        rhs = np.einsum("bij,bj->bi", J[:, :, 2 * m :], _real_pairs(dK))
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            du = _newton_step(J[:, :, : 2 * m], rhs.T)
        V: np.ndarray = (du[:, 0::2] + 1j * du[:, 1::2]).T
        return V

    def _smooth(
        self,
        ends: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
        rates: tuple[np.ndarray, np.ndarray],
        d: np.ndarray,
        w: _Walk,
    ) -> np.ndarray:
        """Whether steps from ``U0`` (knowns ``K0``) to ``U1`` (``K1``), ``ends`` = ``(U0, K0, U1, K1)``, columns of
        designs ``d``, keep the velocity continuous: the tangent at each end (:meth:`_tangent`, the knowns moving
        there by ``rates`` over the step: their motion along their path, not their chord) predicts the other end to
        within ``VELOCITY_SHARE`` of the step's move (the largest over the group's joints).

        On the branch the defect ``|U1 - U0 - V|`` is of second order in the step. Across a kink at ``s`` of the
        way (the other branch taken at a change point) it is at least ``|jump of V| max(s, 1 - s)``, half the jump;
        across a hop to another root, the hop itself. A tangent is not read where its end's determinant is below
        ``TANGENT_DET`` of the pose's: next to a change point it is lost in rounding (Newton places a parallelogram's
        flat position to the square root of its tolerance, its determinant 6e-7 of the pose's), and there both
        branches pass; the determinant's trend decides the step after it (:func:`_sign_passes`). (The knowns' chord
        will not do for their motion where they move on a curve: off it by the square of the step, it is amplified
        by the Jacobian's inverse, and a parallelogram's smooth 3-deg step 6 deg before its flat position had a
        defect of half its move.)"""
        U0, K0, U1, K1 = ends
        out = np.ones(U0.shape[1], bool)
        i = np.flatnonzero(np.all(np.isfinite(np.concatenate([U0, K0, U1, K1])), axis=0))
        if not len(i) or not self.n_held:
            return out
        dU = U1[:, i] - U0[:, i]
        worst, read = np.zeros(len(i)), np.ones(len(i), bool)
        for U, K, dK in ((U0, K0, rates[0]), (U1, K1, rates[1])):
            V = self._tangent(U[:, i], K[:, i], dK[:, i], d[i], w)
            det = np.abs(self._dets(U[:, i], K[:, i], d[i], w))
            read &= np.all(np.isfinite(V), axis=0) & (det > TANGENT_DET * w.det0[d[i]])
            worst = np.maximum(worst, np.max(np.abs(dU - V), axis=0, initial=0.0))
        out[i] = ~read | (worst <= VELOCITY_SHARE * np.max(np.abs(dU), axis=0, initial=0.0))
        return out

    def _grid_rate(self, d: np.ndarray, col: np.ndarray, w: _Walk) -> np.ndarray:
        """The knowns' motion per grid step (up the grid) at grid columns ``col`` of designs ``d``: by differences
        over the grid's columns, central of fourth order where two columns lie either side (as
        :meth:`_grid_slopes`), of second order where one does, else one-sided of second order."""
        first, n = w.K.shape[2] - w.grid_columns, w.K.shape[2]

        def at(off: int) -> np.ndarray:
            return w.K[:, d, np.clip(col + off, first, n - 1)]

        lo, hi = col - first, n - 1 - col
        c4 = (at(-2) - 8 * at(-1) + 8 * at(1) - at(2)) / 12
        c2 = (at(1) - at(-1)) / 2
        one = np.where(lo == 0, -3 * at(0) + 4 * at(1) - at(2), 3 * at(0) - 4 * at(-1) + at(-2)) / 2
        out: np.ndarray = np.where((lo >= 2) & (hi >= 2), c4, np.where((lo >= 1) & (hi >= 1), c2, one))
        return out

    def _walk_legs(self, legs: tuple[_Leg, _Leg], places: np.ndarray, w: _Walk, g: WalkGrid) -> None:
        """Step both legs, all designs at once, until each covers the ``places`` (D, n) on its side or stops.

        A step that fails waits (pending) while the other designs go on; the waiting steps are
        then retried in sub-steps all at once (one batch however many grid steps they failed at).
        """
        c0 = int(np.searchsorted(g.index, 0))
        with np.errstate(invalid="ignore"):
            # to the cell's end nearer the pose: the last cell of a leg is extrapolated (no step past the end)
            far_up = np.nanmax(np.where(places >= 0, np.floor(places), 0), axis=1, initial=0)
            far_dn = np.nanmin(np.where(places < 0, np.ceil(places), 0), axis=1, initial=0)
        limits = (np.minimum(c0 + far_up, len(g.index) - 1), np.maximum(c0 + far_dn, 0))
        while True:
            steps = [leg.due(lim) for leg, lim in zip(legs, limits, strict=True)]
            waiting = not any(len(x) for x in steps)
            if waiting:
                steps = [np.flatnonzero(leg.pending) for leg in legs]
                if not any(len(x) for x in steps):
                    return
            d = np.concatenate(steps)
            s = g.n_given + np.concatenate([leg.pos[x] + leg.sign for leg, x in zip(legs, steps, strict=True)])
            U, U_prev, U_prev2, Kc, fresh = (
                np.concatenate([getattr(leg, f)[..., x] for leg, x in zip(legs, steps, strict=True)], axis=-1)
                for f in ("U", "U_prev", "U_prev2", "Kc", "fresh")
            )
            ahead: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
            if waiting:
                src = g.n_given + np.concatenate([leg.pos[x] for leg, x in zip(legs, steps, strict=True)])
                U_new, acc, lost = self._substeps(U, Kc, d, s, w, src)
                pend = np.zeros(len(d), bool)
            else:
                sign = np.concatenate([np.full(len(x), leg.sign) for leg, x in zip(legs, steps, strict=True)])
                U_new, acc, lost, pend, ahead = self._grid_step(U, np.stack([U_prev, U_prev2]), fresh, d, s, w, sign)
            w.out[:, d[acc], s[acc]] = U_new[:, acc]
            first = 0
            for leg, x in zip(legs, steps, strict=True):
                sl = slice(first, first + len(x))
                leg.pending[x] = pend[sl]
                now = ~pend[sl]
                leg.advance(
                    x[now],
                    U_new[:, sl][:, now],
                    acc[sl][now],
                    lost[sl][now],
                    w.K[:, x[now], s[sl][now]],
                    self.dyad_like,
                )
                for U_j, s_j, ok_j in ahead:  # the columns after it the same Newton batch reached
                    y = np.flatnonzero(ok_j[sl])
                    w.out[:, x[y], s_j[sl][y]] = U_j[:, sl][:, y]
                    leg.advance(
                        x[y],
                        U_j[:, sl][:, y],
                        np.ones(len(y), bool),
                        np.zeros(len(y), bool),
                        w.K[:, x[y], s_j[sl][y]],
                        self.dyad_like,
                    )
                first += len(x)

    def _grid_step(
        self,
        U: np.ndarray,
        before: np.ndarray,
        fresh: np.ndarray,
        d: np.ndarray,
        s: np.ndarray,
        w: _Walk,
        sign: np.ndarray,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, list[tuple[np.ndarray, np.ndarray, np.ndarray]]]:
        """One grid step of designs ``d`` to columns ``s`` by a continuation step: (U, accepted, lost, pending,
        ahead).

        Pending: a step from a solved one that failed, to be retried in sub-steps
        (:meth:`_substeps`). After a failure (dyad-like legs only) there are no sub-steps:
        lost, and restarted. *Ahead*: the same Newton batch also solves the next ``LOOK_AHEAD
        - 1`` columns of a leg whose last step was solved (``sign``: its direction), each
        started from the quadratic predictor carried on; ``ahead`` lists, column by column,
        ``(U, columns, accepted)``, accepted where every step up to it passes the tests of a
        continuation step from the one before (:meth:`_accept`). A column that fails there is
        simply stepped to again, as the next grid step, from the last accepted one.
        """
        N, m = len(d), U.shape[0]
        U_new, acc, lost, pend = np.full_like(U, NAN_POINT), np.zeros(N, bool), np.ones(N, bool), np.zeros(N, bool)
        first, G = w.K.shape[2] - w.grid_columns, w.K.shape[2]
        k = LOOK_AHEAD
        cols = s[None, :] + sign[None, :] * np.arange(k)[:, None]  # (k, N)
        inside = (cols >= first) & (cols < G) & fresh[None, :]
        inside[0] = True
        col = np.clip(cols, 0, G - 1)
        can = inside & w.ok[d[None, :], col]  # the others cannot converge
        can[1:] &= can[0]
        j, i = np.nonzero(can)
        if not len(i):
            return U_new, acc, lost, pend, []
        guess = _predict(U[:, i], before[0][:, i], before[1][:, i], j + 1.0)
        sol, conv, sg = self._newton_ahead(guess, w.K[:, d[i], col[j, i]], w.arrays.take(d[i]), j == 0, w)
        got = np.full((k, m, N), NAN_POINT)
        got[j, :, i] = sol.T
        good = np.zeros((k, N), bool)
        good[j, i] = conv & w.sign_ok(sg, d[i]) & w.regular(sg, d[i]) & np.all(np.isfinite(sol), axis=0)
        start = np.concatenate([U[None], got[:-1]])
        good &= np.max(np.abs(got - start), axis=1) <= STEP_LIMIT * w.size[d][None, :]
        dets = np.full((k, N), np.nan)
        dets[j, i] = sg
        if w.any_sign and w.det is not None:
            good &= self._branch_steps((start, got), dets, cols, sign, d, w)
        else:
            good &= self._clear_of_zero(dets, d, s, sign, w)
        good &= ~w.rough_cells(d[None, :], col - sign[None, :], col)  # through an earlier group's turn: sub-steps
        c0 = np.flatnonzero(can[0])
        a = good[0, c0]
        pend[c0] = ~a & fresh[c0]
        lost[c0] = ~a
        Un = got[0][:, c0]
        if w.det is not None:
            w.det[d[c0[a]], s[c0[a]]] = dets[0, c0[a]]
        self._restart_lost(U[:, c0], w.K[:, d[c0], s[c0]], d[c0], w, Un, a, ~a & ~fresh[c0])
        U_new[:, c0], acc[c0] = Un, a
        return U_new, acc, lost, pend, self._ahead(got, cols, good, fresh, dets, d, w)

    def _newton_ahead(
        self, guess: np.ndarray, K: np.ndarray, ar: _Arrays, step: np.ndarray, w: _Walk
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """A grid step's Newton batch (:meth:`_newton`): the columns ahead of the ``step`` ones, speculative, for at
        most ``LOOK_AHEAD_ITER`` iterations (one past the range's end would take all ``NEWTON_ITER``; one that fails
        is stepped to again), the step's own on to ``NEWTON_ITER`` (the same iterations as in one call)."""
        sol, conv, sg = self._newton(guess, K, ar, LOOK_AHEAD_ITER, vector=w.vector)
        rest = np.flatnonzero(~conv & step & np.all(np.isfinite(sol), axis=0))
        if len(rest):
            sol[:, rest], conv[rest], sg[rest] = self._newton(
                sol[:, rest], K[:, rest], ar.take(rest), NEWTON_ITER - LOOK_AHEAD_ITER, vector=w.vector
            )
        return sol, conv, sg

    def _ahead(
        self,
        got: np.ndarray,
        cols: np.ndarray,
        good: np.ndarray,
        fresh: np.ndarray,
        dets: np.ndarray,
        d: np.ndarray,
        w: _Walk,
    ) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
        """The columns after a grid step's first that its Newton batch reached (``got`` (k, m, N) at ``cols`` (k, N),
        ``good`` where each passed the tests from the one before): ``(U, columns, accepted)`` by column, accepted
        where every step up to it passed from a ``fresh`` leg; their determinants written to ``w.det``."""
        ahead: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
        chain = good[0] & fresh
        for q in range(1, len(good)):
            chain = chain & good[q]
            if not chain.any():
                break
            ahead.append((got[q], cols[q], chain.copy()))
            if w.det is not None:
                w.det[d[chain], cols[q][chain]] = dets[q, chain]
        return ahead

    def _clear_of_zero(self, dets: np.ndarray, d: np.ndarray, s: np.ndarray, sign: np.ndarray, w: _Walk) -> np.ndarray:
        """Which of a leg's grid steps (k, N) to columns ``s + q sign`` (determinants ``dets`` there) may be taken
        whole: the determinant, extrapolated linearly through the two columns before each, stays off zero for
        ``GRID_FOLD_SHARE`` steps (:func:`_zero_ahead`). (Following the branch continuously the steps go through the
        zeros on purpose: :meth:`_branch_steps` decides there.)

        Newton's root at a column past a fold can lie on another sheet whose own fold is near: a Pyslvs six-bar
        variant's branch folds at 366.71 deg and another branch begins at 366.87; the step from 366 to 369 deg landed
        on it, and its way back converged home. The determinant told: it fell linearly to zero at 366.79 deg."""
        out = np.ones(dets.shape, bool)
        if w.det is None:
            return out
        seq = self._dets_before(dets, d, s, sign, w)
        for q in range(dets.shape[0]):
            out[q] = _zero_ahead(seq[q], seq[q + 1]) >= GRID_FOLD_SHARE
        return out

    def _dets_before(self, dets: np.ndarray, d: np.ndarray, s: np.ndarray, sign: np.ndarray, w: _Walk) -> np.ndarray:
        """The determinants (k + 2, N) of the two grid columns before a leg's steps to columns ``s + q sign``, then
        ``dets`` (k, N), the steps' own (NaN where unknown)."""
        before = [w.grid_det(d, s - back * sign) for back in (2, 1)]
        return np.concatenate([np.stack(before), dets])

    def _after_wide_gap(self, d: np.ndarray, s: np.ndarray, sign: np.ndarray, w: _Walk) -> np.ndarray:
        """Whether a leg's first step (to column ``s``) comes after a gap in the range (N,): the :data:`GAP_COLUMNS`
        grid columns before it all unknown, or the unknown ones just before it including one a chain rules out
        (no configuration there: :meth:`_possible`); not the one or two columns a change point on the grid leaves
        unsolved (a rhombus's crank on the ground pivot: possible, but Newton does not converge there)."""
        run, ruled = np.ones(len(d), bool), np.zeros(len(d), bool)
        for back in range(1, GAP_COLUMNS + 1):
            col = s - back * sign
            at = np.clip(col, 0, w.K.shape[2] - 1)
            run &= w.on_grid(col) & np.isnan(w.grid_det(d, col))
            ruled |= run & ~w.ok[d, at] & np.all(np.isfinite(w.K[:, d, at]), axis=0)
        return run | ruled

    def _branch_steps(
        self,
        steps: tuple[np.ndarray, np.ndarray],
        dets: np.ndarray,
        cols: np.ndarray,
        sign: np.ndarray,
        d: np.ndarray,
        w: _Walk,
    ) -> np.ndarray:
        """Following the branch continuously: which of a leg's grid steps (k, N) to columns ``cols`` (``steps``: the
        states each starts from and its solution, both (k, m, N); ``dets`` the solutions' determinants) are the
        branch's. A step that keeps the sign of the column before where the determinant's zero ahead is not within it
        is; one that changes the sign, or keeps it with the zero within it, must follow the determinant's trend
        (:func:`_sign_passes`; where the trend is not known, as at the first step from a grid that ends at the pose,
        the velocity alone tells) and keep the velocity continuous (:meth:`_smooth`; a first column refused for it is
        taken once more from the tangent's predictor, :meth:`_from_tangent`). After a gap (the determinant
        of the column before unknown) a step has the pose's sign: the groups restart in the pose's mode, and a gap is
        no change point.

        The review's cases: two random triads in sequence (no change point) took, 0.05 grid steps
        before a fold, a root of another branch whose determinant followed the trend (-560.4, -124.5, then 420.1):
        62 samples off by up to 0.29 of the span; its velocity defect was the hop itself. A double parallelogram
        posed 0.5 deg past its flat position, asked one input, had no trend at its grid's first step (its grid ends
        at the pose), and its sub-steps kept the pose's sign onto the other mode; the whole step, smooth, crosses.
        A four-bar (rocker 0.95) resumed past its gap with the other sign, 105 samples in the other mode."""
        assert w.det is not None
        seq = self._dets_before(dets, d, cols[0], sign, w)
        wide = self._after_wide_gap(d, cols[0], sign, w)
        out = np.ones(dets.shape, bool)
        for j in range(dets.shape[0]):
            no_trend = np.isnan(seq[j]) & np.isfinite(seq[j + 1])  # the velocity alone tells (:func:`_needs_velocity`)
            out[j] = _sign_passes(seq[j], seq[j + 1], dets[j], 1.0) | no_trend
            gap = wide if j == 0 else np.isnan(seq[j]) & np.isnan(seq[j + 1]) & wide
            out[j] &= ~gap | (np.sign(dets[j]) == w.ref[d])
        q, i = np.nonzero(out & _needs_velocity(seq[:-2], seq[1:-1], dets, 1.0))
        if len(i):
            n = w.K.shape[2]
            prev = np.clip(cols[q, i] - sign[i], 0, n - 1)
            col = np.clip(cols[q, i], 0, n - 1)
            ends = (steps[0][q, :, i].T, w.K[:, d[i], prev], steps[1][q, :, i].T, w.K[:, d[i], col])
            rates = (self._grid_rate(d[i], prev, w) * sign[i], self._grid_rate(d[i], col, w) * sign[i])
            out[q, i] = self._smooth(ends, rates, d[i], w)
            first = np.flatnonzero(~out[q, i] & (q == 0))
            if len(first):  # refused for its velocity: once more, from the tangent's predictor
                r = i[first]
                sub = (ends[0][:, first], ends[1][:, first], ends[2][:, first], ends[3][:, first])
                rates = (rates[0][:, first], rates[1][:, first])
                out[0, r] = self._from_tangent(sub, rates, (seq[0, r], seq[1, r]), d[r], w)
                out[1:, r[out[0, r]]] = False  # the columns ahead were judged from the refused root: again, later
                steps[1][0, :, r[out[0, r]]] = sub[2][:, out[0, r]].T
                dets[0, r] = np.where(out[0, r], self._dets(sub[2], sub[3], d[r], w), dets[0, r])
        return out

    def _from_tangent(
        self,
        ends: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
        rates: tuple[np.ndarray, np.ndarray],
        before: tuple[np.ndarray, np.ndarray],
        d: np.ndarray,
        w: _Walk,
    ) -> np.ndarray:
        """Grid steps ``ends`` = ``(U0, K0, U1, K1)`` (designs ``d``; ``rates`` and the determinants ``before``, at the
        column before ``U0`` and at ``U0``, as :meth:`_branch_steps` reads them) refused for their velocity, taken again
        by Newton from the tangent's predictor ``U0 + V0``: where the new root passes the same tests it replaces ``U1``
        in ``ends[2]`` (in place); which did.

        Near a change point the two modes' roots lie close, and Newton from the walk's quadratic predictor can take the
        other mode: a parallelogram (ground 4, crank 1) posed at 177.37 deg stepped from 177.37 + 3 k deg onto the kite
        0.37 deg past its flat position (determinants 1.57, 0.73, then 0.10 on the kite, -0.10 on the parallelogram);
        refused, its sub-steps took the kite too (356 of 721 samples off the parallelogram). From the tangent's
        predictor Newton finds the parallelogram."""
        U0, K0, U1, K1 = ends
        V0 = self._tangent(U0, K0, rates[0], d, w)
        sol, conv, sg = self._newton(U0 + V0, K1, w.arrays.take(d), vector=w.vector)
        ok = self._accept(sol, conv, sg, U0, STEP_LIMIT * w.size[d], w, d)
        ok &= _sign_passes(before[0], before[1], sg, 1.0) | np.isnan(before[0])  # (before[1] is known here)
        ok &= self._smooth((U0, K0, sol, K1), rates, d, w)
        U1[:, ok] = sol[:, ok]
        return ok

    def _substeps(
        self, U: np.ndarray, Kc: np.ndarray, d: np.ndarray, s: np.ndarray, w: _Walk, src: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Grid steps from columns ``src`` to ``s`` that failed, retried by step halving from the last good state:
        (U, accepted, lost); for a dyad-like group, restarts where that fails too. The cells are marked
        (:attr:`_Walk.substepped`)."""
        if w.substepped is not None:
            w.substepped[d, np.minimum(src, s)] = True
        K = w.K[:, d, s]
        before, U_before = None, None
        if w.det is not None:
            before = (np.full(len(d), -1.0), w.grid_det(d, 2 * src - s))
            if w.any_sign:  # the secant's state before: a grid step back along the tangent (:meth:`_halving`)
                U_before = U - self._tangent(U, Kc, self._grid_rate(d, src, w) * (s - src), d, w)
        U_new = self._halving(U, self._path(Kc, K, d, (src, s), w), w, before=before, U_before=U_before)
        acc = np.all(np.isfinite(U_new), axis=0)
        if w.det is not None:
            w.det[d[acc], s[acc]] = self._dets(U_new[:, acc], K[:, acc], d[acc], w)
        lost = ~acc
        self._restart_lost(U, K, d, w, U_new, acc, lost & w.ok[d, s])
        return U_new, acc, lost

    # ------------------------------------------------------------------ the samples, at once
    def _solve_samples(self, g: WalkGrid, places: np.ndarray, start: np.ndarray, w: _Walk) -> None:
        """Every sample from its grid cell: Newton from the interpolation of the cell's solutions, at once.

        Accepted with the tests of a continuation step (:meth:`_accept`), within half the
        cell's move of the interpolation; the others are reached by sub-steps from the cell's
        end nearer the pose (or its other end), all at once; a place outside the walk is NaN.
        """
        c0 = int(np.searchsorted(g.index, 0))
        c, s = np.nonzero(np.isfinite(places) & w.ok[:, : g.n_given])
        P = places[c, s]
        lo = np.floor(P).astype(np.intp)
        t = P - lo
        a = c0 + lo
        b = np.where(t > 0, a + 1, a)
        G = len(g.index)
        Ug = w.out[:, :, g.n_given :]

        def sol(col: np.ndarray, cc: np.ndarray = c) -> np.ndarray:
            inside = (col >= 0) & (col < G)
            return np.where(inside, Ug[:, cc, np.clip(col, 0, G - 1)], NAN_POINT)

        V = self._grid_slopes(g, w) if w.slopes is None else w.slopes
        Ua, Ub = sol(a), sol(b)  # NaN off the grid (a leg that reached its last column covers the cell past it)
        guess = _hermite(Ua, V[:, c, np.clip(a, 0, G - 1)], Ub, V[:, c, np.clip(b, 0, G - 1)], t)
        bound = _cell_bounds(Ug, c, a, t)
        other = np.flatnonzero(~np.all(np.isfinite(guess), axis=0))  # without both ends and their motions
        if len(other):
            ao, bo, co = a[other], b[other], c[other]
            Umm, Um, Uao, Ubo, Up, Upp = (sol(x, co) for x in (ao - 2, ao - 1, ao, bo, bo + 1, bo + 2))
            guess[:, other], bound[other] = _cell_guess(Umm, Um, Uao, Ubo, Up, Upp, t[other])
            ends = (np.all(np.isfinite(Uao), axis=0), np.all(np.isfinite(Ubo), axis=0))
            past = self._past_zero(t[other], ao + g.n_given, co, ends, w)
            bound[other] = np.where(past, np.nan, bound[other])  # sub-steps, which the zero ahead bounds
        rough = w.rough_cells(c, g.n_given + a, g.n_given + b)  # sub-steps along an earlier group's turn
        with_guess = np.flatnonzero(np.all(np.isfinite(guess), axis=0) & np.isfinite(bound) & ~rough)
        done = np.zeros(len(c), bool)
        if len(with_guess):
            i = with_guess
            keep = self._cell_sign(c[i], a[i], b[i], g.n_given, w)
            done[i] = self._fill_batch(s[i], c[i], guess[:, i], bound[i], w, keep)
        rest = np.flatnonzero(~done)
        if len(rest):  # sub-steps from the cell's end nearer the pose, else its other end
            near = np.where(P[rest] >= 0, a[rest], b[rest])
            far = np.where(P[rest] >= 0, b[rest], a[rest])
            cr = c[rest]
            frm = np.clip(np.where(np.all(np.isfinite(sol(near, cr)), axis=0), near, far), 0, G - 1)
            U0 = Ug[:, cr, frm]
            centre = np.where(np.isfinite(U0), U0, start[:, cr])  # a dyad-like group restarts about it
            before = self._column_before(P[rest] - (frm - c0), cr, g.n_given + frm, w)
            self._from_state(U0, w.K[:, cr, g.n_given + frm], centre, cr, s[rest], w, g.n_given + frm, before)

    def _cell_sign(self, c: np.ndarray, a: np.ndarray, b: np.ndarray, first: int, w: _Walk) -> np.ndarray | None:
        """Following the branch continuously, the determinant's sign samples in cells from grid columns ``a`` to
        ``b`` (designs ``c``; grid column 0 is column ``first`` of ``w.det``) must have: the one both ends share
        (0, any, where they differ: a change point between them; or where an end is unknown). Else None."""
        if not w.any_sign or w.det is None:
            return None
        da, db = (w.grid_det(c, first + x) for x in (a, b))
        return np.where(np.isfinite(da) & (np.sign(da) == np.sign(db)), np.sign(da), 0.0)

    def _column_before(
        self, dist: np.ndarray, c: np.ndarray, col: np.ndarray, w: _Walk
    ) -> tuple[np.ndarray, np.ndarray] | None:
        """For sub-steps from grid columns ``col`` (designs ``c``) to samples ``dist`` grid steps away: the column on
        the other side of each, as ``t`` along its path (``-1 / |dist|``) and its determinant (:meth:`_halving`)."""
        if w.det is None:
            return None
        prev = col - np.sign(dist).astype(np.intp)
        inside = w.on_grid(prev) & (dist != 0)
        with np.errstate(divide="ignore"):
            t = np.where(inside, -1 / np.abs(dist), -np.inf)
        return t, np.where(inside, w.grid_det(c, prev), np.nan)

    def _past_zero(
        self, t: np.ndarray, a: np.ndarray, c: np.ndarray, ends: tuple[np.ndarray, np.ndarray], w: _Walk
    ) -> np.ndarray:
        """Which samples at ``t`` in cells from columns ``a`` to ``a + 1`` (designs ``c``) with one end solved
        (``ends``: which) lie past where the determinant's square, linear through that end and the column before it,
        vanishes (less than 1.5 times their distance from that end: :func:`_zero_ahead`). Extrapolated into such a
        cell, Newton can converge on another branch past a fold (a random triad 2 deg past its range's end, 0.56 deg
        past the cell's solved end)."""
        if w.det is None or w.any_sign:
            return np.zeros(len(t), bool)
        up = ends[0] & ~ends[1]  # solved below the sample: the branch goes up to it
        last = w.K.shape[2] - 1
        end = np.clip(np.where(up, a, a + 1), 0, last)
        prev = np.clip(np.where(up, a - 1, a + 2), 0, last)
        dist = np.where(up, t, 1 - t)
        with np.errstate(invalid="ignore"):
            zero = _zero_ahead(w.det[c, prev], w.det[c, end])
            out: np.ndarray = (ends[0] != ends[1]) & (zero < 1.5 * dist)
        return out

    def _grid_slopes(self, g: WalkGrid, w: _Walk) -> np.ndarray:
        """The group's motion per grid step at every solved grid point, (m, D, G); NaN where unknown.

        ``J_u dU = -J_k dK``, the knowns' motion per step ``dK`` from the grid's own knowns by a
        central difference of fourth order (second at the grid's ends): the solutions are
        interpolated by cubic Hermite (:func:`_hermite`), far closer than from values alone.
        """
        m, D = w.out.shape[:2]
        Ug, Kg = w.out[:, :, g.n_given :], w.K[:, :, g.n_given :]
        G = Ug.shape[2]
        dK = np.full_like(Kg, NAN_POINT)
        if G >= 3:
            dK[:, :, 1:-1] = (Kg[:, :, 2:] - Kg[:, :, :-2]) / 2
        if G >= 5:
            dK[:, :, 2:-2] = (Kg[:, :, :-4] - 8 * Kg[:, :, 1:-3] + 8 * Kg[:, :, 3:-1] - Kg[:, :, 4:]) / 12
        V = np.full((m, D, G), NAN_POINT)
        d, j = np.nonzero(np.all(np.isfinite(Ug), axis=0) & np.all(np.isfinite(dK), axis=0))
        if not len(d) or not self.n_held:
            return V
        V[:, d, j] = self._tangent(Ug[:, d, j], Kg[:, d, j], dK[:, d, j], d, w)
        return V

    def _from_state(
        self,
        U0: np.ndarray,
        K0: np.ndarray,
        centre: np.ndarray,
        c: np.ndarray,
        s: np.ndarray,
        w: _Walk,
        src: np.ndarray | None = None,
        before: tuple[np.ndarray, np.ndarray] | None = None,
    ) -> None:
        """Samples ``s`` of designs ``c`` reached by sub-steps from ``(U0, K0)`` (the knowns of columns ``src``, or
        the pose's; ``before``: the column before each, :meth:`_halving`); a dyad-like group restarts about
        ``centre`` where they fail."""
        K1 = w.K[:, c, s]
        U = np.full((U0.shape[0], len(c)), NAN_POINT)
        live = np.flatnonzero(np.all(np.isfinite(U0), axis=0) & w.ok[c, s])
        if len(live):
            cols = None if src is None else (src[live], s[live])
            path = self._path(K0[:, live], K1[:, live], c[live], cols, w)
            ahead = None if before is None else (before[0][live], before[1][live])
            U[:, live] = self._halving(U0[:, live], path, w, to_fold=True, before=ahead)
        acc = np.all(np.isfinite(U), axis=0)
        self._restart_lost(centre, K1, c, w, U, acc, ~acc & w.ok[c, s])
        if acc.any():
            U[:, acc] = self._polish(U[:, acc], K1[:, acc], c[acc], w)
        w.out[:, c[acc], s[acc]] = U[:, acc]

    def _accept(
        self,
        sol: np.ndarray,
        conv: np.ndarray,
        sign: np.ndarray,
        start: np.ndarray,
        bound: np.ndarray,
        w: _Walk,
        designs: np.ndarray,
    ) -> np.ndarray:
        """Whether Newton's ``sol`` from ``start`` (columns of ``designs``) is the branch's: converged, with the
        pose's determinant sign (a sign change is a passage through a singular position, never silent; following
        the branch continuously, any sign here: the grid steps, sub-steps and samples, which know the states before,
        check :func:`_sign_passes`), and no joint farther than ``bound`` from where
        it started (over a small step Newton's root is the branch's, not another of one sign); and not singular
        (:meth:`_Walk.regular`)."""
        near = np.max(np.abs(sol - start), axis=0) <= bound
        ok = conv & w.sign_ok(sign, designs) & w.regular(sign, designs) & np.all(np.isfinite(sol), axis=0) & near
        return ok  # type: ignore[no-any-return]

    def _plain(
        self,
        U: np.ndarray,
        U_prev: np.ndarray,
        K: np.ndarray,
        designs: np.ndarray,
        w: _Walk,
        U_prev2: np.ndarray | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """A continuation step to knowns ``K`` from ``U``: (U, accepted).

        Newton starts from the predictor along the walk: quadratic through ``U_prev2``,
        ``U_prev`` and ``U`` (equal steps), else linear through the last two, else ``U``.
        """
        guess = 2 * U - U_prev
        guess = np.where(np.isfinite(guess), guess, U)
        if U_prev2 is not None:
            quad = 3 * U - 3 * U_prev + U_prev2
            guess = np.where(np.isfinite(quad), quad, guess)
        U_new, conv, sg = self._newton(guess, K, w.arrays.take(designs), vector=w.vector)
        return U_new, self._accept(U_new, conv, sg, U, STEP_LIMIT * w.size[designs], w, designs)

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
        U_r = self._restart(U[:, idx], K[:, idx], w.ref[designs[idx]], w.nums, designs[idx], w.floor(designs[idx]))
        found = np.all(np.isfinite(U_r), axis=0)
        U_new[:, idx[found]] = U_r[:, found]
        acc[idx[found]] = True

    def _fill_batch(
        self, r: np.ndarray, c: np.ndarray, g: np.ndarray, bound: np.ndarray, w: _Walk, keep: np.ndarray | None = None
    ) -> np.ndarray:
        """Samples ``r`` of designs ``c`` from guesses ``g`` at once: accepted (written to ``out``) or not (``keep``:
        the determinant's sign each must have, 0 any, :meth:`_cell_sign`)."""
        ok = np.zeros(len(r), bool)
        i = np.flatnonzero(w.ok[c, r])  # the others cannot converge
        ri, ci, gi = r[i], c[i], g[:, i]
        sol, conv, sg = self._newton_samples(gi, w.K[:, ci, ri], ci, w)
        good = self._accept(sol, conv, sg, gi, bound[i], w, ci)
        if keep is not None:
            good &= (keep[i] == 0) | (np.sign(sg) == keep[i])
        sol[:, good] = self._polish(sol[:, good], w.K[:, ci[good], ri[good]], ci[good], w, sg[good])
        w.out[:, ci[good], ri[good]] = sol[:, good]
        ok[i] = good
        return ok

    def _polish(
        self, U: np.ndarray, K: np.ndarray, d: np.ndarray, w: _Walk, det: np.ndarray | None = None
    ) -> np.ndarray:
        """Converged columns ``U`` (designs ``d``, knowns ``K``; ``det``: their Jacobians' determinants, else
        computed) with one more Newton step where the determinant is below ``POLISH_DET`` of the pose's.

        Near a fold the Jacobian's smallest singular value ``s`` is small, and a residual ``r`` that passes
        ``NEWTON_TOL`` leaves the joints up to ``r / s`` off (1e-4 deg from a six-bar's fold, 1.5e-9 of the
        size). The step takes the residual to rounding (quadratic convergence). It is kept only where it moves no
        joint more than ``POLISH_MOVE`` of the group's size and leaves the residual no larger: at a singular root
        (a rhombus's joint on a circle of solutions) the Jacobian is nearly singular, and the step goes anywhere."""
        det = self._dets(U, K, d, w) if det is None else det
        weak = np.flatnonzero(np.abs(det) < POLISH_DET * w.det0[d])
        if not len(weak):
            return U
        ar = w.arrays.take(d[weak])
        Uw = U[:, weak]
        P = np.concatenate([Uw, K[:, weak]]) if len(K) else Uw
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            res = self._res(P, ar.L, ar.R)
            dx = _newton_step(self._jac(P, ar.J_lin, ar.R), res)
            step = (dx[:, 0::2] + 1j * dx[:, 1::2]).T
            P[: len(Uw)] = Uw + step
            after = np.max(np.abs(self._res(P, ar.L, ar.R)) / ar.tol, axis=0)
            keep = (np.max(np.abs(step), axis=0) <= POLISH_MOVE * w.size[d[weak]]) & (
                after <= np.max(np.abs(res) / ar.tol, axis=0)
            )
        out = U.copy()
        out[:, weak[keep]] = P[: len(Uw), keep]
        return out

    def _newton_samples(
        self, U: np.ndarray, K: np.ndarray, d: np.ndarray, w: _Walk
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Newton on the samples' columns (designs ``d``): vectorized (``w.fill_vector``), its first ``VECTOR_ITER``
        iterations chunk by chunk, then the few columns still iterating all together by LAPACK (each column's
        arithmetic is that of one Newton of ``NEWTON_ITER`` iterations; the tail of every chunk in one batch)."""
        if not w.fill_vector:
            return self._newton_chunks(U, K, d, w, NEWTON_ITER, False)
        sol, conv, sg = self._newton_chunks(U, K, d, w, VECTOR_ITER, True)
        tail = np.flatnonzero(~conv & np.all(np.isfinite(sol), axis=0))
        if len(tail):
            sol[:, tail], conv[tail], sg[tail] = self._newton_chunks(
                sol[:, tail], K[:, tail], d[tail], w, NEWTON_ITER - VECTOR_ITER, False
            )
        return sol, conv, sg

    def _newton_chunks(
        self, U: np.ndarray, K: np.ndarray, d: np.ndarray, w: _Walk, iters: int, vector: bool
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`_newton` on columns of designs ``d`` in chunks of ``FILL_CHUNK`` (their arrays stay in the cache;
        vectorized, they share one workspace)."""
        B = U.shape[1]
        sol, conv, sg = np.empty_like(U), np.zeros(B, bool), np.zeros(B)
        work = _workspace("newton", _gauss_size(self.n_eq, min(FILL_CHUNK, B))) if vector else None
        for first in range(0, B, FILL_CHUNK):
            i = slice(first, first + FILL_CHUNK)
            ar = w.arrays.take(d[i])
            if vector:
                sol[:, i], conv[i], sg[i] = self._newton_vector(U[:, i], K[:, i], ar, iters, work, reuse=True)
            else:
                sol[:, i], conv[i], sg[i] = self._newton(U[:, i], K[:, i], ar, iters)
        return sol, conv, sg

    def _halving(
        self,
        U: np.ndarray,
        path: _Path,
        w: _Walk,
        to_fold: bool = False,
        before: tuple[np.ndarray, np.ndarray] | None = None,
        U_before: np.ndarray | None = None,
    ) -> np.ndarray:
        """From ``U`` at the start of ``path`` to its end by adaptive sub-steps; NaN columns where a step below
        2^-MAX_HALVINGS fails.

        Each column walks ``t`` from 0 to 1 along its path (:meth:`_knowns`: the knowns where the inputs between its
        two columns put them): a step that is accepted (the tests of a continuation step) doubles the next one, a step
        that is not is halved. A step to knowns a chain rules out fails without Newton. Newton here is LAPACK's,
        whatever the problem's size (few columns sub-step, and many rounds: array operations' fixed cost would
        dominate). A sub-step that moves a joint far is checked on the way back (:meth:`_returns`). ``before``: the
        path's ``t`` (negative) of the state before its start and the determinant there; with it, no sub-step goes
        more than ``1 / SUB_FOLD_SHARE`` of the way to where the determinant, through the last two states, is zero
        (:class:`_DetTrail`), down to the smallest step. Following the branch continuously, Newton starts from the
        secant through the last two states (:meth:`_substep_newton`; ``U_before``: the state at ``before``'s ``t``),
        no zero ahead bounds the steps (a change point is crossed on purpose), failed ones halve to ``FINEST_SUBSTEP``
        (:class:`_Steps`); in either mode a column stops at a fold (:meth:`_DetTrail.folded`)."""
        designs = path.designs
        size, ar = w.size[designs], w.arrays.take(designs)
        reach = tuple(x[:, designs] for x in w.reach)  # the walk's numbers, of these designs
        B = U.shape[1]
        Uc, Kc, st = U.copy(), path.K0.copy(), _Steps.new(B, fine=w.any_sign)
        before = (np.full(B, np.nan), np.full(B, np.nan)) if before is None else before
        trail = _DetTrail.new(before, self._dets(U, path.K0, designs, w))
        bounded = None if w.any_sign else trail  # following the branch continuously, steps go through zeros on purpose
        secant = _Secant.new(U, before[0], U_before) if w.any_sign else None
        while True:
            act = st.due()
            if not len(act):
                break
            gone = trail.folded(act)  # at a fold, not at a sharp turn or a change point: the path goes no farther
            st.alive[act[gone]] = False
            act = act[~gone]
            tt = st.target(act, bounded)
            K_t = self._knowns(path, tt, act, w)
            ok = np.zeros(len(act), bool)
            can = np.flatnonzero(self._possible(K_t, tuple(x[:, act] for x in reach)))  # type: ignore[arg-type]
            if len(can):
                a = act[can]
                Un, conv, sg = self._substep_newton(Uc[:, a], K_t[:, can], ar.take(a), secant, (a, st.t[a], tt[can]))
                ok[can] = self._accept(Un, conv, sg, Uc[:, a], STEP_LIMIT * size[a], w, designs[a])
                if w.any_sign:  # a sign change only across the determinant's zero (:func:`_sign_passes`)
                    ok[can] &= trail.sign_passes(a, tt[can], sg)
                back = can[ok[can]]  # the way back must lead to where the step started: no hop to another root
                ok[back] = self._returns(Un[:, ok[can]], Kc[:, act[back]], Uc[:, act[back]], w, designs[act[back]])
                good_can = can[ok[can]]
                _Secant.push(secant, act[good_can], st.t[act[good_can]], Uc[:, act[good_can]])
                Uc[:, act[good_can]] = Un[:, ok[can]]
                trail.push(act[good_can], tt[good_can], sg[ok[can]])
            Kc[:, act[ok]] = K_t[:, ok]
            st.update(act, tt, ok)
        if to_fold:  # samples (the walk's own steps find the range's ends: they are not pushed)
            self._last_step(Uc, Kc, st.t, st.alive, path, w)
        return np.where(st.alive & (st.t >= 1.0), Uc, NAN_POINT)

    def _substep_newton(
        self, U: np.ndarray, K: np.ndarray, ar: _Arrays, secant: _Secant | None, at: tuple[np.ndarray, ...]
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """A sub-step's Newton from columns ``U`` to knowns ``K``: started from ``secant``'s predictor (columns
        ``at[0]``, from ``t = at[1]`` to ``at[2]``) where there is one, and again from ``U`` where that does not
        converge (a predictor onto a singular point: the double rhombus's sub-steps through its change points).

        Next to a change point the two modes' roots lie about as near the last state, and from it Newton took either
        (a parallelogram posed 1 deg before its flat position, forced through Newton: 358 of 721 samples kites)."""
        if secant is None:
            return self._newton(U, K, ar, SUBSTEP_ITER)
        Un, conv, sg = self._newton(secant.predict(at[0], U, at[1], at[2]), K, ar, SUBSTEP_ITER)
        redo = np.flatnonzero(~conv)
        if len(redo):
            Un[:, redo], conv[redo], sg[redo] = self._newton(U[:, redo], K[:, redo], ar.take(redo), SUBSTEP_ITER)
        return Un, conv, sg

    def _path(
        self, K0: np.ndarray, K1: np.ndarray, designs: np.ndarray, cols: tuple[np.ndarray, np.ndarray] | None, w: _Walk
    ) -> _Path:
        """Sub-steps of ``designs`` from knowns ``K0`` to ``K1``, the knowns of columns ``cols`` (from, to) of ``w.K``
        (None: the chord between them): through the inputs between the two columns where the steps before the group
        can be re-run there (an angle's input the shorter way round: a sample's input is a direction)."""
        rates = None
        if cols is not None and w.det is not None:
            first, n = w.K.shape[2] - w.grid_columns, w.K.shape[2]
            a, b = np.clip(cols[0], first, n - 1), np.clip(cols[1], first, n - 1)
            if np.all(cols[0] >= first) and np.all(cols[1] >= first) and np.all(np.abs(cols[1] - cols[0]) == 1):
                rates = (self._grid_rate(designs, a, w) * (b - a), self._grid_rate(designs, b, w) * (b - a))
        if cols is None or w.upstream is None or w.q is None:
            return _Path(K0, K1, designs, rates=rates)
        q0, q1 = w.q[:, designs, cols[0]], w.q[:, designs, cols[1]]
        angle = np.zeros(len(q0), bool)
        angle[: len(self.angular)] = self.angular[: len(q0)]
        with np.errstate(invalid="ignore"):
            step = q1 - q0
            q1 = np.where(angle[:, None], q0 + step - 2 * np.pi * np.round(step / (2 * np.pi)), q1)
        return _Path(K0, K1, designs, q0, q1, rates)

    def _knowns(self, path: _Path, t: np.ndarray, idx: np.ndarray, w: _Walk) -> np.ndarray:
        """The knowns at ``t`` (N,) of columns ``idx`` of ``path``: ``K0`` at 0, ``K1`` at 1; between, where the
        inputs ``(1 - t) q0 + t q1`` put them (the steps before the group re-run there, every design's columns side
        by side), else on the chord."""
        K: np.ndarray = (1 - t) * path.K0[:, idx] + t * path.K1[:, idx]
        if path.rates is not None:
            H = _hermite(path.K0[:, idx], path.rates[0][:, idx], path.K1[:, idx], path.rates[1][:, idx], t)
            K = np.where(np.all(np.isfinite(H), axis=0), H, K)
        K[:, t >= 1.0] = path.K1[:, idx[t >= 1.0]]
        mid = np.flatnonzero((t > 0) & (t < 1))
        if path.q0 is None or path.q1 is None or w.upstream is None or not len(mid):
            return K
        i, d = idx[mid], path.designs[idx[mid]]
        q = (1 - t[mid]) * path.q0[:, i] + t[mid] * path.q1[:, i]
        D = w.K.shape[1]
        order = np.argsort(d, kind="stable")
        first = np.concatenate([[0], np.cumsum(np.bincount(d, minlength=D))[:-1]])
        rank = np.empty(len(d), np.intp)
        rank[order] = np.arange(len(d)) - first[d[order]]
        q2 = np.full((len(q), D, int(rank.max()) + 1), np.nan)
        q2[:, d, rank] = q
        z = w.upstream(q2)
        if z is not None:
            K[:, mid] = self.held(z, q2)[:, d, rank]
        return K

    def _last_step(
        self,
        Uc: np.ndarray,
        Kc: np.ndarray,
        t: np.ndarray,
        alive: np.ndarray,
        path: _Path,
        w: _Walk,
    ) -> None:
        """Sample columns whose sub-steps gave up a hair before their end (the knowns still to move by at most
        ``HOP_MOVE`` of the group's size) tried once more, in place: Newton of ``FOLD_ITER`` iterations from where
        they stopped to the end, accepted by the tests of a sub-step, its way back (as many iterations), and a step
        toward the fold: the configuration's conditioning falls on it.

        Next to a fold Newton converges only linearly (the Jacobian is nearly singular), so a sub-step of six
        iterations fails there however small: samples 1e-5 deg inside a range's end that ``check`` finds to 3e-8
        deg were not assembled. Just past the fold there is no root of the pose's sign on the branch's sheet, and a
        root that many iterations find elsewhere is better conditioned than the fold the sub-steps stopped at, while
        each sample truly inside lands nearer the fold (its conditioning below its start's). (The case that first
        showed it, a triad's range growing from -43.4 to -94.8 deg, was in fact the branch going on through a sharp
        turn to a fold at -94.814 deg, which an arclength continuation confirms; the sub-steps now follow such turns
        in fine steps, :class:`_Steps`.)"""
        K0, K1, designs = path.K0, path.K1, path.designs
        left = (1 - t) * np.max(np.abs(K1 - K0), axis=0, initial=0.0)  # how far the knowns still move
        a = np.flatnonzero(~alive & (t > 0) & (t < 1.0) & (left <= HOP_MOVE * w.size[designs]))
        if not len(a):
            return
        Ks = Kc[:, a]  # the knowns where each column stopped
        Un, conv, sg = self._newton(Uc[:, a], K1[:, a], w.arrays.take(designs[a]), FOLD_ITER)
        ok = self._accept(Un, conv, sg, Uc[:, a], STEP_LIMIT * w.size[designs[a]], w, designs[a])
        ok[ok] = self._returns(Un[:, ok], Ks[:, ok], Uc[:, a[ok]], w, designs[a[ok]], FOLD_ITER)
        if ok.any():
            ar = w.arrays.take(designs[a[ok]])
            ok[ok] = self._sv_ratio(Un[:, ok], K1[:, a[ok]], ar) <= self._sv_ratio(Uc[:, a[ok]], Ks[:, ok], ar)
        Uc[:, a[ok]] = Un[:, ok]
        t[a[ok]], alive[a[ok]] = 1.0, True

    def _dets(self, U: np.ndarray, K: np.ndarray, designs: np.ndarray, w: _Walk) -> np.ndarray:
        """The determinant of the Jacobian at ``U`` (m, B) with knowns ``K`` (columns of ``designs``; NaN where
        either is not finite), as Newton's LAPACK path takes it."""
        out = np.full(U.shape[1], np.nan)
        i = np.flatnonzero(np.all(np.isfinite(U), axis=0) & np.all(np.isfinite(K), axis=0))
        if len(i):
            ar = w.arrays.take(designs[i])
            out[i] = np.linalg.det(self._jac(np.concatenate([U[:, i], K[:, i]]) if len(K) else U[:, i], ar.J_lin, ar.R))
        return out

    def _sv_ratio(self, U: np.ndarray, K: np.ndarray, ar: _Arrays) -> np.ndarray:
        """sigma_min / sigma_max of the Jacobian at ``U`` with knowns ``K`` (a few columns: by SVD)."""
        J = self._jac(np.concatenate([U, K]) if len(K) else U, ar.J_lin, ar.R)
        sv = np.linalg.svd(np.where(np.isfinite(J), J, 0.0), compute_uv=False)
        out: np.ndarray = sv[:, -1] / np.maximum(sv[:, 0], 1e-300)
        return out

    def _returns(
        self, U: np.ndarray, K: np.ndarray, U0: np.ndarray, w: _Walk, designs: np.ndarray, iters: int = SUBSTEP_ITER
    ) -> np.ndarray:
        """Whether a move from ``U0`` (with knowns ``K``) to ``U`` is the branch's, not a hop to another root: one
        that moves no joint more than ``HOP_MOVE`` of the group's size is; for one that moves more, Newton from ``U``
        with the knowns ``K`` must end (after ``iters`` steps, converged or not: near a fold it converges only
        linearly) within a tenth of the move of ``U0``, or converge to a root of the other determinant sign than the
        pose's (columns of ``designs``). One that ends there without converging is followed on to ``FOLD_ITER``
        steps in all and must then converge within ``ARRIVED`` of its move of ``U0``: a hop across a fold onto
        another sheet near it crept within a tenth of its move in six steps, then went away.

        Past a fold (the end of a range, where the branch meets the one of opposite sign) a
        sub-step can converge to a root of the pose's sign on another sheet, near enough to pass
        the step's tests. The way back tells: from a root of the branch Newton returns to where the
        move started, or, a hair inside the fold, to its partner of the other sign; from another
        sheet it converges on that sheet, to a root of the pose's sign, or not at all.
        """
        size = w.size[designs]
        move = np.max(np.abs(U - U0), axis=0)
        out: np.ndarray = move <= HOP_MOVE * size
        check = np.flatnonzero(~out)
        if len(check):
            d = designs[check]
            Ub, conv, sg = self._newton(U[:, check], K[:, check], w.arrays.take(d), iters)
            home = np.max(np.abs(Ub - U0[:, check]), axis=0) <= 0.1 * move[check]
            creep = np.flatnonzero(home & ~conv)  # on its way home near a fold it may still creep: followed on
            if len(creep) and iters < FOLD_ITER:
                c = check[creep]
                Uf, cf, _ = self._newton(Ub[:, creep], K[:, c], w.arrays.take(d[creep]), FOLD_ITER - iters)
                home[creep] = cf & (np.max(np.abs(Uf - U0[:, c]), axis=0) <= ARRIVED * move[c])
            out[check] = home | (conv & (np.sign(sg) == -w.ref[d]))
        return out

    def _restart(
        self, U: np.ndarray, K: np.ndarray, ref: np.ndarray, nums: Nums, designs: np.ndarray, floor: np.ndarray
    ) -> np.ndarray:
        """After a gap: the solution at ``K`` with the pose's determinant sign, when it is the only one (a root whose
        determinant is at most ``floor`` is singular, no answer: :data:`SINGULAR_DET`).

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
        centre = np.where(
            np.arange(RESTARTS)[:, None, None] % 2 == 0, U[None], np.mean(K[: len(self.known)], axis=0)[None, None, :]
        )
        starts = centre + 2 * np.max(lengths, axis=0)[None, None, :] * noise  # (R, m, B)
        Ub = np.concatenate([U[None], starts]).transpose(1, 0, 2).reshape(m, -1)
        Kb = np.repeat(K[:, None, :], RESTARTS + 1, axis=1).reshape(K.shape[0], -1)
        rows = np.tile(np.arange(B), RESTARTS + 1)
        sol, conv, det = self._newton(Ub, Kb, self._arrays(_take(dn, rows), len(rows)), 4 * NEWTON_ITER)
        sol = sol.reshape(m, RESTARTS + 1, B)
        good = conv & (np.sign(det) == np.tile(ref, RESTARTS + 1)) & (np.abs(det) > np.tile(floor, RESTARTS + 1))
        good = good.reshape(RESTARTS + 1, B)
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
        m, nk = len(self.joints), self.n_held
        _, D, n = r.z.shape
        P = np.concatenate([r.z[list(self.joints)], self.held(r.z)]).reshape(m + nk, D * n)
        # the held values' rates: the known joints', then each cylinder's length's (its driver's speed, acceleration)
        V = self.held(r.v, r.w_in).reshape(nk, D * n)
        A = self.held(r.a, r.a_in).reshape(nk, D * n)
        d = np.repeat(np.arange(D), n)
        dn = self._design_nums(nums, d)
        J = self.jacobian(P, dn, m + nk)
        Ju, Jk = J[:, :, : 2 * m], J[:, :, 2 * m :]
        ok = np.all(np.isfinite(Ju), axis=(1, 2))
        Ju_safe = Ju if ok.all() else np.where(ok[:, None, None], Ju, np.eye(2 * m))  # (copies cost page faults)
        vk, ak = _real_pairs(V), _real_pairs(A)
        rhs_v = -np.einsum("bij,bj->bi", Jk, vk) if nk else np.zeros((D * n, 2 * m))
        cond = self._condition(Ju_safe, dn)
        sing = ~ok | ~(cond > 0)
        R = self._stack(dn, D * n)[1]
        if self._reduced is not None and D * n >= VECTOR_SAMPLES:  # factored once for both solves
            system: _RatesSystem | _ReducedRates = _ReducedRates(self, P, R, rhs_v)
        else:  # (LAPACK refuses a singular matrix: the identity in its place, its answer flagged below)
            system = _RatesSystem(
                np.where(sing[:, None, None], np.eye(2 * m), Ju_safe) if sing.any() else Ju_safe, rhs_v
            )
        vu = system.first
        vu[sing] = np.nan
        Vall = np.concatenate([(vu[:, 0::2] + 1j * vu[:, 1::2]).T, V]) if nk else (vu[:, 0::2] + 1j * vu[:, 1::2]).T
        gamma = self._gamma(P, Vall, R).T
        rhs_a = -gamma - (np.einsum("bij,bj->bi", Jk, ak) if nk else 0.0)
        au = system.solve(rhs_a)
        au[sing] = np.nan
        for i, j in enumerate(self.joints):
            r.v[j] = (vu[:, 2 * i] + 1j * vu[:, 2 * i + 1]).reshape(D, n)
            r.a[j] = (au[:, 2 * i] + 1j * au[:, 2 * i + 1]).reshape(D, n)
        r.extra_cond.append(np.where(ok, cond, 0.0).reshape(D, n))
        for gl in self.links:
            if gl.name not in r.om:
                j0, j1 = gl.joints[0], gl.joints[1]
                r.om[gl.name], r.al[gl.name] = link_rates(r.z[j1] - r.z[j0], r.v[j1] - r.v[j0], r.a[j1] - r.a[j0])

    def _gamma(self, P: np.ndarray, V: np.ndarray, R: np.ndarray) -> FloatArray:
        """What the constraints' second derivative along a motion adds to ``J P''``, at positions ``P`` and
        velocities ``V`` (n_slots, B) of every slot: (n_eq, B). Each row is quadratic in the coordinates, so it is
        the row's constant Hessian on ``V`` twice: ``2 |v_b - v_a|^2`` on a distance row, 0 on a linear row,
        ``2 Im(w' conj(u'))`` on a slider's line row, ``2 Im(e_o' conj(c e'))`` on its lock row, ``2 |e'|^2 - 2
        s'^2`` on a cylinder's (``d2/dt2 (|e|^2 - s^2) = 2 e.e'' + 2 |e'|^2 - 2 s s'' - 2 s'^2``), ``2 Re(w'
        conj(u'))`` on a slider driver's."""
        gamma = np.zeros((self.n_eq, V.shape[1]))
        row = 0
        for gl in self.links:
            dv = V[gl.slots[1]] - V[gl.slots[0]]
            gamma[row] = 2 * (dv.real**2 + dv.imag**2)
            row += 1 + 2 * (len(gl.slots) - 2)
        if self.sliders:
            gamma[self._srows.line], gamma[self._srows.lock] = self._slider_gamma(P, V, R)
        if self.cylinders:
            cr = self._crows
            de = V[cr.b] - V[cr.a]
            gamma[cr.row] = 2 * (de.real**2 + de.imag**2) - 2 * V[cr.s].real ** 2
        if self.drives:
            gamma[self._drows.row] = self._drive_gamma(V, R)
        return gamma

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
        if self.cylinders:
            scale[:, self._crows.row] = 1.0 / (2 * self._cnums(self._stack(dn, B)[1])).T
        return scale

    def _condition(self, Ju: np.ndarray, dn: Nums) -> np.ndarray:
        """Smallest over largest singular value of J_u with its rows scaled by :meth:`row_scale`."""
        B, r, n = Ju.shape
        C = _workspace("condition", n * r * B).reshape(n, r, B)  # the scaled matrices column by column, in one pass
        np.multiply(Ju.transpose(2, 1, 0), self.row_scale(dn, B).T[None], out=C)
        return _condition(C.transpose(2, 1, 0))

    # ------------------------------------------------------------------ description
    def link_names(self) -> tuple[str, ...]:
        return tuple(gl.name for gl in self.links)

    def describe(self, names: tuple[str, ...], nums: Nums | None) -> str | None:
        placed = ", ".join(names[j] for j in self.joints)
        links = ", ".join(f"'{gl.name}'" for gl in self.links)
        held = ", ".join(names[j] for j in self.known) or "nothing"
        sliding = "".join(f", slider {gs.slider} ('{gs.other}' on '{gs.carrier}')" for gs in self.sliders)
        sliding += "".join(
            f", cylinder {names[gc.end_joints[0]]}-{names[gc.end_joints[1]]} (driver {gc.driver})"
            for gc in self.cylinders
        )
        sliding += "".join(
            f", slider driver {gd.driver} on slider {self.sliders[gd.slider].slider}" for gd in self.drives
        )
        return (
            f"{placed} placed numerically (Newton-Raphson, continued from the pose): links {links}{sliding}, "
            f"held by {held}; the mode is the pose's"
        )


_WORKSPACES = threading.local()


def _workspace(name: str, size: int) -> FloatArray:
    """A float workspace of ``size`` floats, the one named ``name`` the last call in this thread used when it is
    large enough (at most ``WORKSPACE_MOST`` floats are kept): a fresh large array faults every page it writes in,
    which costs as much as the arithmetic done in it. Its contents are undefined; a caller uses it before it calls
    anything that takes the same name.

    >>> a = _workspace("doc", 10); b = _workspace("doc", 5)
    >>> bool(np.shares_memory(a, b)), b.size
    (True, 5)
    """
    if size > WORKSPACE_MOST:
        return np.empty(size)
    buf: FloatArray | None = getattr(_WORKSPACES, name, None)
    if buf is None or buf.size < size:
        buf = np.empty(size)
        setattr(_WORKSPACES, name, buf)
    return buf[:size]


def _size(dn: Nums) -> FloatArray:
    """The mean link length of each design (a batch row) of design numbers."""
    size: FloatArray = np.mean(np.array([np.broadcast_to(L, np.shape(dn[0][0])) for L in dn[0]]), axis=0)
    return size


def _take(dn: Nums, cols: np.ndarray) -> Nums:
    lengths, rhos = dn
    return tuple(L[cols] for L in lengths), tuple(tuple(r[cols] for r in rho) for rho in rhos)


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


def _solve_small(
    J: FloatArray, res: FloatArray, done: np.ndarray, vector: bool, work: FloatArray | None = None
) -> tuple[FloatArray, FloatArray]:
    """Newton's steps ``dx`` (B, n) with ``J dx = -res`` (``J`` (B, n, n), ``res`` (n, B)) where not ``done``, and
    the determinants of ``J`` (B,) where ``done``: by :func:`_gauss` (``vector``; both everywhere), else by LAPACK
    per matrix (NaN steps where singular or not finite; a non-finite ``J``'s determinant is its finite part's)."""
    if vector:
        return _gauss(J, res, work)
    dx, det = np.full((J.shape[0], J.shape[2]), np.nan), np.zeros(J.shape[0])
    if not done.all():
        dx[~done] = _newton_step(J[~done], res[:, ~done])
    if done.any():
        Jd = J[done]
        det[done] = np.linalg.det(np.where(np.isfinite(Jd), Jd, 0.0))
    return dx, det


def _gauss_again(A: FloatArray, piv: np.ndarray, rhs: FloatArray) -> FloatArray:
    """``x`` (n, B) with ``J x = rhs`` (``rhs`` (n, B)) from the factors :func:`_gauss` left (``A`` (n, n + 1, B),
    its multipliers below the diagonal) and its pivots ``piv``: the operations its right-hand side column went
    through (the swaps, then ``b_i -= (A_ik / A_kk) b_k``), and the same back-substitution."""
    n, B = piv.shape
    b = np.array(rhs, float)
    cols = np.arange(B)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        for k in range(n):
            p = piv[k]
            lo, hi = p.min(), p.max()
            if lo == hi and lo > 0:  # the same swap in every column (often: the rows' structure decides)
                b[[k, k + lo]] = b[[k + lo, k]]
            elif hi > 0:
                rows = k + p
                top = b[rows, cols]
                b[rows, cols] = b[k]
                b[k] = top
            if k < n - 1:
                b[k + 1 :] -= (A[k + 1 :, k] / A[k, k]) * b[k]
        x = np.empty((n, B))
        for k in range(n - 1, -1, -1):
            x[k] = (b[k] - np.sum(A[k, k + 1 : n] * x[k + 1 :], axis=0)) / A[k, k]
    return x


class _RatesSystem:
    """``J x = rhs`` for one batch of matrices ``J`` (B, n, n) (nonsingular) and a first right-hand side ``rhs``
    (B, n), its solution :attr:`first`, then others (:meth:`solve`): from ``VECTOR_SAMPLES`` systems on, by
    :func:`_gauss` (in chunks of ``FILL_CHUNK``) whose factors then solve the others (:func:`_gauss_again`: the
    arithmetic a right-hand side goes through in the factorization), else by LAPACK."""

    def __init__(self, J: FloatArray, rhs: FloatArray) -> None:
        self.J = J
        self.factors: list[tuple[FloatArray, np.ndarray]] = []
        if len(J) < VECTOR_SAMPLES:
            self.first = self.solve(rhs)
            return
        B, n, _ = J.shape
        self.first = np.empty(rhs.shape)
        factors = _workspace("rates", n * (n + 1) * B)  # every chunk's factors, kept for the second solve
        scratch = _workspace("rates scratch", _gauss_size(n, FILL_CHUNK))
        for start in range(0, B, FILL_CHUNK):
            rows = slice(start, start + FILL_CHUNK)
            Jc = J[rows]
            b, piv = len(Jc), np.empty((n, len(Jc)), np.intp)
            self.first[rows] = _gauss(Jc, -rhs[rows].T, scratch[: _gauss_size(n, b)], piv)[0]
            A = factors[n * (n + 1) * start : n * (n + 1) * (start + b)].reshape(n, n + 1, b)
            A[...] = scratch[: n * (n + 1) * b].reshape(n, n + 1, b)
            self.factors.append((A, piv))

    def solve(self, rhs: FloatArray) -> FloatArray:
        """``x`` (B, n) for ``rhs`` (B, n)."""
        if not self.factors:
            y: np.ndarray = np.linalg.solve(self.J, rhs[..., None])[..., 0]
            return y
        x = np.empty(rhs.shape)
        for i, (A, piv) in enumerate(self.factors):
            rows = slice(i * FILL_CHUNK, i * FILL_CHUNK + piv.shape[1])
            x[rows] = _gauss_again(A, piv, rhs[rows].T).T
        return x


class _ReducedRates:
    """:class:`_RatesSystem` by a group's reduced system (:class:`_Reduced`; slot positions ``P`` (n_slots, B),
    rhos ``R``), in chunks of ``FILL_CHUNK``: each factored once (:func:`_eliminate`), its factors solving the
    second right-hand side (:func:`_gauss_again`). A singular system gives a step that is not finite, flagged by
    the caller."""

    def __init__(self, group: Group, P: np.ndarray, R: np.ndarray, rhs: FloatArray) -> None:
        assert group._reduced is not None
        self.group, self.R = group, R
        n, B = 2 * len(group._reduced.cols), P.shape[1]
        self.first = np.empty(rhs.shape)
        factors = _workspace("rates", n * (n + 1) * B)  # every chunk's factors, kept for the second solve
        scratch = _workspace("rates scratch", (n - 1) * n * FILL_CHUNK)
        self.chunks: list[tuple[slice, FloatArray, np.ndarray, np.ndarray]] = []
        for start in range(0, B, FILL_CHUNK):
            rows = slice(start, min(start + FILL_CHUNK, B))
            b = rows.stop - start
            A = factors[n * (n + 1) * start : n * (n + 1) * rows.stop].reshape(n, n + 1, b)
            e, _ = group._reduced_matrix(P[:, rows], R[:, rows], rhs[rows].T, A)
            piv = np.empty((n, b), np.intp)
            self.first[rows] = group._reduced_expand(_eliminate(A, scratch, piv)[0], rhs[rows].T, R[:, rows])
            self.chunks.append((rows, A, piv, e))

    def solve(self, rhs: FloatArray) -> FloatArray:
        """``x`` (B, 2m) for ``rhs`` (B, 2m)."""
        x = np.empty(rhs.shape)
        for rows, A, piv, e in self.chunks:
            b = rhs[rows].T
            xc = _gauss_again(A, piv, self.group._reduced_rhs(e, b)).T
            x[rows] = self.group._reduced_expand(xc, b, self.R[:, rows])
        return x


def _gauss_size(n: int, B: int) -> int:
    """The workspace :func:`_gauss` needs for ``B`` systems of ``n`` equations (floats)."""
    return (n * (n + 1) + (n - 1) * n) * B


def _gauss(
    J: FloatArray, res: FloatArray, work: FloatArray | None = None, piv: np.ndarray | None = None
) -> tuple[FloatArray, FloatArray]:
    """:func:`_solve_small` as array operations over the columns: Gaussian elimination with partial pivoting.

    Each entry of the ``n x (n + 1)`` augmented matrices is an array over the columns, so the
    cost is about ``n^2`` array operations whatever the number of columns (LAPACK costs about
    1 us per small matrix). A column's numbers are computed by the same scalar operations
    whatever else is in the batch. The determinant is the product of the pivots, negated for
    each row swap; a zero pivot (a singular matrix) gives a zero determinant and a step that is
    not finite, a non-finite ``J`` or ``res`` NaN. ``work``: a workspace of :func:`_gauss_size` floats or more
    (reused across calls, it spares the page faults of fresh large arrays). ``piv`` (n, B): where to record each
    step's pivot row (below the diagonal); with the factors left in ``work`` :func:`_gauss_again` solves for
    another right-hand side.
    """
    B, n, _ = J.shape
    work = np.empty(_gauss_size(n, B)) if work is None else work
    A = work[: n * (n + 1) * B].reshape(n, n + 1, B)
    A[:, :n] = J.transpose(1, 2, 0)
    A[:, n] = -res
    return _eliminate(A, work[n * (n + 1) * B :], piv)


def _eliminate(A: FloatArray, scratch: FloatArray, piv: np.ndarray | None = None) -> tuple[FloatArray, FloatArray]:
    """:func:`_gauss` on its augmented matrices ``A`` (n, n + 1, B) (overwritten by the factors), ``scratch`` of
    ``(n - 1) n B`` floats or more: (x (B, n), det (B,))."""
    n, B = A.shape[0], A.shape[2]
    det, zero = np.ones(B), np.zeros(B, bool)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        for k in range(n):
            p = np.argmax(np.abs(A[k:, k]), axis=0)
            if piv is not None:
                piv[k] = p
            counts = np.bincount(p, minlength=n - k)
            for i in np.flatnonzero(counts[1:]) + k + 1:  # row i's pivot is the largest: swap rows k and i
                if counts[i - k] == B:  # in every column (often: the rows' structure decides)
                    A[k, k:], A[i, k:] = A[i, k:].copy(), A[k, k:].copy()
                    det = -det
                else:
                    sw = p == i - k
                    top = np.where(sw, A[i, k:], A[k, k:])
                    A[i, k:] = np.where(sw, A[k, k:], A[i, k:])
                    A[k, k:] = top
                    det = np.where(sw, -det, det)
            zero |= (A[k, k] == 0) & np.isfinite(det)  # the rest of the elimination divides by it: NaN
            det *= A[k, k]
            if k < n - 1:  # in place: large temporaries cost page faults
                upd = scratch[: (n - k - 1) * (n - k) * B].reshape(n - k - 1, n - k, B)
                np.multiply((A[k + 1 :, k] / A[k, k])[:, None, :], A[k, None, k + 1 :, :], out=upd)
                A[k + 1 :, k + 1 :] -= upd
        x = np.empty((n, B))
        for k in range(n - 1, -1, -1):
            x[k] = (A[k, n] - np.sum(A[k, k + 1 : n] * x[k + 1 :], axis=0)) / A[k, k]
    return x.T, np.where(zero, 0.0, det)


def _smallest_singular_bound(J: FloatArray, det: FloatArray) -> FloatArray:
    """A lower bound (B,) of the smallest singular value of each ``J`` (B, n, n) of determinant ``det``: the
    product of the other ``n - 1`` is at most ``(|J|_F^2 / (n - 1))^((n - 1) / 2)`` (their squares sum to at most
    ``|J|_F^2``; the geometric mean is at most the arithmetic one); 0 where not finite.

    >>> import numpy as np
    >>> J = np.diag([3.0, 2.0, 0.5])[None]
    >>> float(_smallest_singular_bound(J, np.linalg.det(J))[0]) <= 0.5
    True
    """
    return _singular_bound(det, np.einsum("bij,bij->b", J, J), J.shape[1])


def _singular_bound(det: FloatArray, frob: FloatArray, n: int) -> FloatArray:
    """:func:`_smallest_singular_bound` from the determinants and the squared Frobenius norms ``frob`` (B,) of ``n x
    n`` matrices."""
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        out = np.abs(det) / (frob / (n - 1)) ** ((n - 1) / 2)
    bound: FloatArray = np.where(np.isfinite(out), out, 0.0)
    return bound


def _zero_ahead(det_prev: np.ndarray, det: np.ndarray) -> np.ndarray:
    """How many steps (each as long as the one from ``det_prev`` to ``det``) past ``det`` the determinant is zero,
    its square taken linear through the two; inf where it does not fall toward zero (it grows, changes sign, or
    is unknown) and where ``det_prev`` is unknown, NaN.

    Next to a fold the determinant goes as the root of the input's distance to it: its square
    puts the zero at the fold. Where it falls linearly (two branches nearly crossing) its square
    puts the zero nearer than it is, never farther: on the safe side both ways.

    >>> float(_zero_ahead(np.array(3.0), np.array(2.0))), float(_zero_ahead(np.array(2.0), np.array(3.0)))
    (0.8, inf)
    """
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        falls = (np.sign(det_prev) == np.sign(det)) & (np.abs(det) < np.abs(det_prev))
        out: np.ndarray = np.where(falls, det**2 / (det_prev**2 - det**2), np.inf)
    return np.where(np.isnan(det_prev) & np.isfinite(det), np.nan, out)


def _sign_passes(det_prev: np.ndarray, det: np.ndarray, det_new: np.ndarray, ratio: np.ndarray | float) -> np.ndarray:
    """Following the branch continuously: whether a step from a state of determinant ``det`` (``det_prev`` at the
    state before it; the step ``ratio`` times as long as the last) to one of ``det_new`` is the branch's as far as the
    determinant tells. ``det_new`` continues the determinant's trend (off the line through ``det_prev`` and ``det`` by
    at most that line's own change over the step), or keeps ``det``'s sign where the determinant's zero ahead
    (:func:`_zero_ahead`, as the default's whole grid steps read it) is not within the step. Where ``det`` is unknown it
    tells nothing.

    Along the branch the determinant is smooth: at a change point (a simple zero) it changes sign along its trend, and
    where its zero is near (a change point, or a fold, where the range ends) the branch's next state is on the trend,
    not at a root of another branch. A triad fed by a four-bar's coupler, its determinant 341 and 377 at 87 and 84
    deg, took -474 at 81 deg (0.1 of its size off the branch) and 317 again at 78 deg; another, past a fold, kept its
    sign on another branch. A parallelogram's determinant, 1.67 and 0.84 a grid step apart, is -0.0 at its flat
    position.

    >>> _sign_passes(np.array([341.0, 1.67]), np.array([377.0, 0.84]), np.array([-474.0, -0.0]), 1.0).tolist()
    [False, True]
    """
    with np.errstate(invalid="ignore", over="ignore"):
        trend = det + (det - det_prev) * ratio
        follows = np.abs(det_new - trend) <= np.abs(trend - det)
        out: np.ndarray = follows | ~_needs_velocity(det_prev, det, det_new, ratio)
    return out


def _needs_velocity(
    det_prev: np.ndarray, det: np.ndarray, det_new: np.ndarray, ratio: np.ndarray | float
) -> np.ndarray:
    """Following the branch continuously: which steps (as :func:`_sign_passes` reads them) the determinant alone does
    not vouch for, so that the velocity must be continuous across them too (:meth:`Group._smooth`): those that
    change ``det``'s sign, or keep it where the determinant's zero ahead lies within the step (both where ``det`` is
    known). A fold's partner past its zero, or another sheet's root, can follow the determinant's trend: two triads in
    sequence, determinants -560.4 and -124.5 a grid step apart near a fold, took 420.1 on another branch, 0.29 of the
    mechanism's span away.

    >>> _needs_velocity(np.array([3.0, 3.0, 3.0]), np.array([2.0, 2.0, 2.9]), np.array([-1.0, 1.0, 2.8]), 1.0).tolist()
    [True, True, False]
    """
    with np.errstate(invalid="ignore", over="ignore"):
        keeps = (np.sign(det_new) == np.sign(det)) & ~(_zero_ahead(det_prev, det) < ratio)
    out: np.ndarray = ~keeps & np.isfinite(det)
    return out


@dataclass
class _Steps:
    """Sub-steps' progress along their paths, per column: ``t`` reached, the next step ``dt``, ``alive``, and the
    step a failed one may be halved down to (``0.5**MAX_HALVINGS``; ``FINEST_SUBSTEP`` after an accepted step
    finer than that, which only the determinant's zero ahead makes: the branch turns sharply there; ``FINEST_SUBSTEP``
    always where ``fine``: following the branch continuously, no zero ahead bounds the steps, and only halving
    that far follows a sharp turn)."""

    t: np.ndarray
    dt: np.ndarray
    alive: np.ndarray
    floor: np.ndarray
    fine: bool = False

    @classmethod
    def new(cls, B: int, fine: bool = False) -> _Steps:
        floor = FINEST_SUBSTEP if fine else 0.5**MAX_HALVINGS
        return cls(np.zeros(B), np.full(B, 0.5), np.ones(B, bool), np.full(B, floor), fine)

    def due(self) -> np.ndarray:
        """The columns still on their way."""
        return np.flatnonzero(self.alive & (self.t < 1.0))

    def target(self, act: np.ndarray, trail: _DetTrail | None) -> np.ndarray:
        """Where columns ``act`` step next: ``dt`` on, not past the path's end, nor (with a ``trail``) past its
        room before the determinant's zero ahead, down to ``FINEST_SUBSTEP``."""
        step = self.dt[act]
        if trail is not None:
            step = np.minimum(step, np.maximum(trail.room(act), FINEST_SUBSTEP))
        t = self.t[act]
        out: np.ndarray = np.where(step >= 1.0 - t, 1.0, t + step)
        return out

    def update(self, act: np.ndarray, tt: np.ndarray, ok: np.ndarray) -> None:
        """Columns ``act`` stepped to ``tt``, accepted where ``ok``: an accepted step doubles, a failed one halves
        (the column gives up below its floor)."""
        step = tt - self.t[act]
        good, bad = act[ok], act[~ok]
        coarse = 0.5**MAX_HALVINGS
        self.t[good] = tt[ok]
        self.dt[good] = np.minimum(2 * step[ok], 1.0)
        self.floor[good] = np.where(step[ok] < coarse, FINEST_SUBSTEP, FINEST_SUBSTEP if self.fine else coarse)
        self.dt[bad] = step[~ok] / 2
        self.alive[bad[self.dt[bad] < self.floor[bad]]] = False


@dataclass
class _DetTrail:
    """Sub-steps' last two accepted states per column: their ``t`` along the path and the determinant there (2, B);
    and where the last two pairs put the determinant's zero (``zero``, (2, B), NaN where none)."""

    t: np.ndarray
    det: np.ndarray
    zero: np.ndarray

    @classmethod
    def new(cls, before: tuple[np.ndarray, np.ndarray], det0: np.ndarray) -> _DetTrail:
        B = len(det0)
        return cls(np.stack([before[0], np.zeros(B)]), np.stack([before[1], det0]), np.full((2, B), np.nan))

    def folded(self, i: np.ndarray) -> np.ndarray:
        """Which columns ``i`` stand within ``0.5**MAX_HALVINGS`` of a fold before their path's end: the last two
        pairs of states put the determinant's zero at the same place (to 1e-2 of the way there), as a fold does
        (the square of the determinant linear in the input); where it only nearly vanishes, or two branches nearly
        cross, the zero's place runs ahead as the states come nearer, and the fine sub-steps go on."""
        z, t = self.zero[:, i], self.t[1, i]
        with np.errstate(invalid="ignore"):
            way = z[1] - t
            out: np.ndarray = (way < 0.5**MAX_HALVINGS) & (z[1] < 1.0) & (np.abs(z[1] - z[0]) <= 1e-2 * way)
        return out

    def room(self, i: np.ndarray) -> np.ndarray:
        """How far (in ``t``) past its last state column ``i`` may go: ``1 / SUB_FOLD_SHARE`` of the way to the
        determinant's zero (:func:`_zero_ahead`), inf where none is ahead, ``FIRST_SUBSTEP`` where the trend is not
        known (no state before the last)."""
        with np.errstate(invalid="ignore"):
            out: np.ndarray = _zero_ahead(self.det[0, i], self.det[1, i]) * (self.t[1, i] - self.t[0, i])
        return np.where(np.isnan(out), FIRST_SUBSTEP, out / SUB_FOLD_SHARE)

    def sign_passes(self, i: np.ndarray, t: np.ndarray, det: np.ndarray) -> np.ndarray:
        """Whether columns ``i`` may step to ``t``, where the determinant is ``det``, following the branch
        continuously (:func:`_sign_passes`, the trend through their last two states)."""
        with np.errstate(invalid="ignore", divide="ignore"):
            ratio = (t - self.t[1, i]) / (self.t[1, i] - self.t[0, i])
        return _sign_passes(self.det[0, i], self.det[1, i], det, ratio)

    def push(self, i: np.ndarray, t: np.ndarray, det: np.ndarray) -> None:
        """Columns ``i`` accepted a state at ``t`` with determinant ``det``."""
        self.t[0, i], self.det[0, i] = self.t[1, i], self.det[1, i]
        self.t[1, i], self.det[1, i] = t, det
        with np.errstate(invalid="ignore"):
            ahead = _zero_ahead(self.det[0, i], self.det[1, i]) * (self.t[1, i] - self.t[0, i])
        self.zero[0, i], self.zero[1, i] = self.zero[1, i], np.where(np.isfinite(ahead), t + ahead, np.nan)


@dataclass
class _Secant:
    """Sub-steps' last accepted state but one, per column (``U`` (m, B) at path parameter ``t`` (B,); NaN where
    unknown): the secant predictor through it and the last state."""

    U: np.ndarray
    t: np.ndarray

    @classmethod
    def new(cls, U: np.ndarray, t: np.ndarray, U_before: np.ndarray | None) -> _Secant:
        prev = np.full_like(U, NAN_POINT) if U_before is None else U_before.copy()
        return cls(prev, np.asarray(t, float).copy())

    def predict(self, i: np.ndarray, U: np.ndarray, t: np.ndarray, t_new: np.ndarray) -> np.ndarray:
        """Columns ``i``, now at ``U`` (at ``t``), predicted at ``t_new``: on the secant, else ``U``."""
        with np.errstate(invalid="ignore", divide="ignore"):
            pred = U + (U - self.U[:, i]) * ((t_new - t) / (t - self.t[i]))
        return np.where(np.all(np.isfinite(pred), axis=0), pred, U)

    @staticmethod
    def push(secant: _Secant | None, i: np.ndarray, t: np.ndarray, U: np.ndarray) -> None:
        """Columns ``i`` leave their state ``U`` at ``t`` for a new one: it becomes the state before (no secant:
        nothing to do)."""
        if secant is not None:
            secant.U[:, i], secant.t[i] = U, t


@dataclass
class _Leg:
    """One leg of the grid walk (up or down from the pose's input), per design."""

    sign: int  # +1 up, -1 down the grid
    pos: np.ndarray  # (D,) the last grid column stepped to (solved, or where the leg stopped)
    U: np.ndarray  # (m, D) the last solution
    U_prev: np.ndarray  # (m, D) the one before (the predictor's)
    U_prev2: np.ndarray  # (m, D) and the one before that
    Kc: np.ndarray  # (k, D) the knowns of the last solution
    fresh: np.ndarray  # (D,) the last step was solved (sub-steps allowed from it)
    alive: np.ndarray  # (D,) the leg goes on (a class-3 group's leg stops where a step fails)
    pending: np.ndarray  # (D,) its next step failed and waits for sub-steps

    @classmethod
    def new(cls, start: np.ndarray, w: _Walk, g: WalkGrid, c0: int, sign: int) -> _Leg:
        D = start.shape[1]
        alive = np.all(np.isfinite(start), axis=0)
        K = w.K[:, :, g.n_given + c0].copy()
        nan = np.full_like(start, NAN_POINT)
        return cls(sign, np.full(D, c0), start.copy(), nan, nan.copy(), K, alive.copy(), alive, np.zeros(D, bool))

    def due(self, limit: np.ndarray) -> np.ndarray:
        """The designs whose next step is not past ``limit`` (a grid column per design)."""
        return np.flatnonzero(self.alive & ~self.pending & ((self.pos + self.sign - limit) * self.sign <= 0))

    def advance(
        self, x: np.ndarray, U: np.ndarray, acc: np.ndarray, lost: np.ndarray, K: np.ndarray, dyad_like: bool
    ) -> None:
        """Designs ``x`` stepped to their next column: solved ``U`` where ``acc`` (``lost``: after restarts)."""
        self.pos[x] += self.sign
        good = x[acc]
        # no predictor across a gap or a restart: the next step starts from the solution
        reset = lost[acc] | ~self.fresh[good]
        self.U_prev2[:, good] = np.where(reset, U[:, acc], self.U_prev[:, good])
        self.U_prev[:, good] = np.where(reset, U[:, acc], self.U[:, good])
        self.U[:, good], self.Kc[:, good] = U[:, acc], K[:, acc]
        self.fresh[x] = acc
        if not dyad_like:  # a class-3 group does not guess after a gap: the leg ends here
            self.alive[x[~acc]] = False

    def past_solved(self, places: np.ndarray, c0: int) -> np.ndarray:
        """Which ``places`` (D, n) this leg covers past its last solved column: in the cell where its step failed,
        or in the one past its last column (not walked)."""
        last = (self.pos - c0 - np.where(self.alive, 0, self.sign))[:, None]
        with np.errstate(invalid="ignore"):
            beyond = places > last if self.sign > 0 else places < last
        return self.covers(places, c0) & beyond

    def covers(self, places: np.ndarray, c0: int) -> np.ndarray:
        """Which ``places`` (D, n), in grid steps from the pose's input, lie on this leg's side up to where it got.

        A leg that stopped covers up to the column where its step failed; one that goes on, the
        cell past its last column too.
        """
        got = (self.pos - c0 + np.where(self.alive, self.sign, 0))[:, None]
        with np.errstate(invalid="ignore"):
            if self.sign > 0:
                return (places >= 0) & (places <= got)
            return (places < 0) & (places >= got)


def grid_places(u: np.ndarray, x0: np.ndarray, step: np.ndarray, cyclic: bool) -> tuple[np.ndarray, np.ndarray]:
    """Where inputs ``u`` (D, n) lie on the walk's grid, in steps from the pose's input ``x0`` (D,): (near, other).

    For an angle (``cyclic``) ``u`` is a direction: ``near`` is its representative nearest the
    pose's input (in half a turn below it to half a turn above), ``other`` the one a turn the
    other way; for a length ``near`` is ``u``'s place and ``other`` NaN.

    >>> import numpy as np
    >>> near, other = grid_places(np.radians([[30.0, 390.0, -300.0, 200.0]]), np.zeros(1), np.radians([3.0]), True)
    >>> np.round(near, 9).tolist(), np.round(other, 9).tolist()
    ([[10.0, 10.0, 20.0, -53.333333333]], [[-110.0, -110.0, -100.0, 66.666666667]])
    """
    P = (np.asarray(u, float) - x0[:, None]) / step[:, None]
    if not cyclic:
        return P, np.full_like(P, np.nan)
    turn = 2 * np.pi / step[:, None]
    near = P - turn * np.floor(P / turn + 0.5)
    return near, np.where(near >= 0, near - turn, near + turn)


def _predict(U: np.ndarray, U_prev: np.ndarray, U_prev2: np.ndarray, t: np.ndarray) -> np.ndarray:
    """The walk's predictor ``t`` steps on from ``U`` (columns): the quadratic through ``U_prev2``, ``U_prev``, ``U``
    (at -2, -1, 0) where all three are known, else the line through the last two, else ``U``."""
    quad = (t + 1) * (t + 2) / 2 * U - t * (t + 2) * U_prev + t * (t + 1) / 2 * U_prev2
    lin = (t + 1) * U - t * U_prev
    out: np.ndarray = np.where(np.isfinite(quad), quad, np.where(np.isfinite(lin), lin, U))
    return out


def _real_pairs(z: np.ndarray) -> FloatArray:
    """Complex (k, B) as real rows (B, 2k): ``[Re z_0, Im z_0, Re z_1, ...]``."""
    out: FloatArray = np.stack([z.real, z.imag], axis=-1).transpose(1, 0, 2).reshape(z.shape[1], 2 * z.shape[0])
    return out  # (the width written out: with no design, B = 0, -1 cannot be inferred)


def _hermite(Ua: np.ndarray, Va: np.ndarray, Ub: np.ndarray, Vb: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Cubic Hermite at ``t`` in [0, 1] between ``Ua`` and ``Ub`` with motions per cell ``Va``, ``Vb``."""
    t2, t3 = t * t, t * t * t
    out: np.ndarray = (2 * t3 - 3 * t2 + 1) * Ua + (t3 - 2 * t2 + t) * Va + (3 * t2 - 2 * t3) * Ub + (t3 - t2) * Vb
    return out


def _cell_bounds(Ug: np.ndarray, c: np.ndarray, a: np.ndarray, t: np.ndarray) -> np.ndarray:
    """How far Newton may move samples at ``t`` in [0, 1) of cells from grid columns ``a`` (designs ``c``) of the
    grid's solutions ``Ug`` (m, D, G): half the cell's largest joint move plus 1e-9 of the largest coordinate at
    ``a`` (``t = 0``: the column itself, no move); NaN where either end is off the grid or unsolved. Each cell's
    value once, then taken by the samples.

    >>> import numpy as np
    >>> Ug = np.array([[[0.0, 1.0, 3.0]]]) + 0j
    >>> _cell_bounds(Ug, np.zeros(4, int), np.array([0, 1, 1, 2]), np.array([0.5, 0.5, 0.0, 0.5])).tolist()
    [0.5, 1.000000001, 1e-09, nan]
    """
    D, G = Ug.shape[1:]
    move = np.full((D, G), np.nan)
    move[:, :-1] = np.max(np.abs(Ug[:, :, 1:] - Ug[:, :, :-1]), axis=0)
    size = np.max(np.abs(Ug), axis=0)
    inside = (a >= 0) & (a < G)
    ac = np.clip(a, 0, G - 1)
    with np.errstate(invalid="ignore"):
        out: np.ndarray = 0.5 * np.where(t > 0, move[c, ac], 0.0) + 1e-9 * size[c, ac]
    return np.where(inside, out, np.nan)


def _cell_guess(
    Umm: np.ndarray, Um: np.ndarray, Ua: np.ndarray, Ub: np.ndarray, Up: np.ndarray, Upp: np.ndarray, t: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """A sample's start at ``t`` in [0, 1) of its cell ``a``-``b`` from the grid's solutions, and how far from it
    Newton may go (half the cell's move): (guess (m, N), bound (N,)); NaN where there is none.

    Both ends solved: cubic through them and their outer neighbours (``Um``, ``Up``) where all
    four are, else linear. One end only (the cell where a leg stopped): quadratic extrapolation
    from that end and the two solutions before it.
    """
    cubic = -t * (t - 1) * (t - 2) / 6 * Um + (t + 1) * (t - 1) * (t - 2) / 2 * Ua
    cubic += -(t + 1) * t * (t - 2) / 2 * Ub + (t + 1) * t * (t - 1) / 6 * Up
    inside = np.where(np.all(np.isfinite(cubic), axis=0), cubic, (1 - t) * Ua + t * Ub)
    r = 1 - t  # from b towards a

    def beyond(U0: np.ndarray, U1: np.ndarray, U2: np.ndarray, x: np.ndarray) -> np.ndarray:
        """Quadratic through U2, U1, U0 at -2, -1, 0, at x."""
        out: np.ndarray = (x + 1) * (x + 2) / 2 * U0 - x * (x + 2) * U1 + x * (x + 1) / 2 * U2
        return out

    up, down = beyond(Ua, Um, Umm, t), beyond(Ub, Up, Upp, r)
    fin = [np.all(np.isfinite(U), axis=0) for U in (Ua, Ub)]
    guess = np.where(fin[0] & fin[1], inside, np.where(fin[0], up, down))
    move = np.where(fin[0] & fin[1], Ub - Ua, np.where(fin[0], Ua - Um, Ub - Up))
    with np.errstate(invalid="ignore"):
        bound = 0.5 * np.max(np.abs(move), axis=0) + 1e-9 * np.max(np.abs(np.where(fin[0], Ua, Ub)), axis=0)
    return guess, bound


def _condition(Js: FloatArray) -> FloatArray:
    """Smallest over largest singular value of each matrix of ``Js`` (B, r, n), as ``sqrt(lo / hi)``, ``lo`` and
    ``hi`` the extreme eigenvalues of ``Js^T Js``.

    The Gram matrices are brought to tridiagonal form (:func:`_gram_tridiagonal`) and their extreme eigenvalues
    found by Newton on the characteristic polynomial from outside (:func:`_extreme_root`), all as array operations
    over the batch (LAPACK's ``eigvalsh`` costs about 1.5 us a matrix). Their rounding is about 1e-16 of the
    largest, as ``eigvalsh``'s: a matrix where Newton has not converged after ``COND_ITER`` steps goes to
    ``eigvalsh``, one whose ratio is below ``COND_EXACT`` to the SVD; above ``COND_TRIDIAGONAL_MOST`` columns,
    every matrix goes to the SVD.

    >>> import numpy as np
    >>> A = np.random.default_rng(0).normal(size=(3, 6, 6))
    >>> s = np.linalg.svd(A, compute_uv=False)
    >>> bool(np.allclose(_condition(A), s[:, -1] / s[:, 0], rtol=1e-12, atol=0))
    True
    """
    B, _, n = Js.shape
    cond = np.full(B, np.nan)
    finite = np.all(np.isfinite(Js), axis=(1, 2))  # else NaN, flagged singular (a zero-length link's row scale)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        if 2 <= n <= COND_TRIDIAGONAL_MOST:  # beyond, LAPACK's SVD of every matrix is the faster (and exact)
            d, e2 = _gram_tridiagonal(Js)
            e = np.sqrt(e2)
            pad = np.zeros((1, B))
            high = np.max(d + np.concatenate([pad, e]) + np.concatenate([e, pad]), axis=0)  # Gershgorin: >= hi
            hi, ok_hi = _extreme_root(d, e2, high, high)
            lo, ok_lo = _extreme_root(d, e2, np.zeros(B), high)
            cond = np.sqrt(np.maximum(lo, 0.0) / hi)
            cond[~(ok_hi & ok_lo)] = np.nan
            slow = np.flatnonzero(~np.isfinite(cond) & finite)
            if len(slow):
                ev = np.linalg.eigvalsh(Js[slow].transpose(0, 2, 1) @ Js[slow])
                cond[slow] = np.sqrt(np.maximum(ev[:, 0], 0.0) / ev[:, -1])
        low = np.flatnonzero(~(cond >= COND_EXACT) & finite)
        if len(low):
            sv = np.linalg.svd(Js[low], compute_uv=False)
            cond[low] = sv[:, -1] / sv[:, 0]
    return cond


def _gram_tridiagonal(Js: FloatArray) -> tuple[FloatArray, FloatArray]:
    """The symmetric tridiagonal form of ``Js^T Js`` (``Js`` (B, r, n)) by Householder reflections: its diagonal
    (n, B) and its off-diagonal squared (n - 1, B), with the same eigenvalues.

    Each entry is an array over the batch (about ``n^3`` array operations whatever ``B``). Step ``k`` reflects
    column ``k`` below the diagonal, ``x``, onto ``alpha e_1`` (``alpha = -sign(x_0) |x|``): with ``v = x - alpha
    e_1``, ``beta = 2 / |v|^2``, ``p = beta S v``, ``w = p - (beta v.p / 2) v``, the trailing block ``S`` becomes
    ``S - v w^T - w v^T``.
    """
    B, _, n = Js.shape
    C = np.ascontiguousarray(Js.transpose(2, 1, 0))  # (n, r, B): column i of every matrix (a view when it is one)
    S: list[list[Any]] = [[None] * n for _ in range(n)]
    for i in range(n):
        for j in range(i, n):
            S[i][j] = S[j][i] = np.einsum("kb,kb->b", C[i], C[j])
    d, e2 = np.empty((n, B)), np.empty((n - 1, B))
    for k in range(n - 2):
        idx = range(k + 1, n)
        x = [S[i][k] for i in idx]
        s2 = sum(xi * xi for xi in x)
        alpha = -np.copysign(np.sqrt(s2), x[0])
        v = [x[0] - alpha, *x[1:]]
        vv = 2 * (s2 - alpha * x[0])  # |v|^2
        beta = np.where(vv > 0, 2 / vv, 0.0)  # nothing to reflect: no reflection
        p = [beta * sum(S[i][j] * vj for j, vj in zip(idx, v, strict=True)) for i in idx]
        half = 0.5 * beta * sum(vi * pi for vi, pi in zip(v, p, strict=True))
        w = [pi - half * vi for pi, vi in zip(p, v, strict=True)]
        for a, i in enumerate(idx):
            for b in range(a, len(v)):
                j = k + 1 + b
                S[i][j] = S[j][i] = S[i][j] - v[a] * w[b] - w[a] * v[b]
        d[k], e2[k] = S[k][k], s2
    d[n - 2], d[n - 1], e2[n - 2] = S[n - 2][n - 2], S[n - 1][n - 1], S[n - 1][n - 2] ** 2
    return d, e2


def _extreme_root(
    d: FloatArray, e2: FloatArray, x: FloatArray, scale: FloatArray, iters: int = 0
) -> tuple[FloatArray, np.ndarray]:
    """The eigenvalue of the tridiagonal (``d``, ``e2`` as :func:`_gram_tridiagonal`'s) nearest ``x`` from
    outside (``x`` above the largest, or below the smallest): (eigenvalue, converged), (B,) each.

    Newton on ``p(x) = det(T - x I) = prod q_i``, the pivots ``q_0 = d_0 - x``, ``q_i = d_i - x - e_{i-1}^2 /
    q_{i-1}``, ``p'/p = sum q_i'/q_i`` with ``q_i' = -1 + e_{i-1}^2 q_{i-1}' / q_{i-1}^2``. Every root of ``p`` is
    real, so from outside Newton moves monotonically to the extreme root (it cannot pass it). Converged: a step
    below ``COND_STEP`` of ``|x| + scale``; at most ``COND_ITER`` steps (``iters``, when given).
    """
    n = len(d)
    conv = np.zeros(x.shape, bool)
    for _ in range(iters or COND_ITER):
        q, dq = d[0] - x, -np.ones_like(x)
        s = dq / q
        for i in range(1, n):
            r = e2[i - 1] / q
            dq = -1 + r * dq / q
            q = d[i] - x - r
            s += dq / q
        step = np.where(conv, 0.0, 1 / s)
        x = x - step
        conv |= np.abs(step) <= COND_STEP * (np.abs(x) + scale)
        if conv.all():
            break
    return x, conv & np.isfinite(x)
