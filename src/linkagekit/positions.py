"""Closed-form positions: run a plan's steps over (designs, samples) at once.

Points are complex arrays ``x + iy`` of shape ``(n_joints, designs, samples)``; every step
is a few NumPy expressions over all designs and samples (see :mod:`linkagekit.steps`).  A
step with no real solution (two circles that do not meet, a circle that misses a line)
gives NaN for its joint and for every joint placed from it, and a negative margin, so a
sample that does not assemble is NaN, never a wrong number.

Tolerance
---------
Two circles of radii ``r1, r2`` whose centres are ``s`` apart are taken to meet when
``|r1 - r2| - eps (r1 + r2) <= s <= (r1 + r2)(1 + eps)`` with ``eps = ASSEMBLY_RTOL``;
inside that band a slightly negative ``h^2`` (rounding of a flat or tangent triangle) is
clamped to 0.  Likewise a circle and a line meet when the distance from the centre to
the line is at most ``r (1 + eps)``.

Examples
--------
>>> import numpy as np, linkagekit as lk
>>> from linkagekit.params import compile
>>> p = compile(lk.load("examples/seed000_fourbar.yaml"))
>>> sol = solve(p, np.radians([[[0.0, 90.0]]]))
>>> sol.z.shape, sol.assembled.tolist()
((5, 1, 2), [[True, True]])
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import partial
from typing import TYPE_CHECKING, Any

import numpy as np

from .errors import MechanismFileError, shorten
from .geometry import ASSEMBLY_RTOL, NAN_POINT
from .group import GRID_MOST, GRID_STEP, GRID_STEP_LENGTH, Group, grid_places
from .params import Params, all_sign_combinations
from .steps import Kin, WalkGrid, is_sign_step

if TYPE_CHECKING:
    from .model import Mechanism
    from .plan import Plan

#: above this many sign steps the pose's mode (given lengths) is searched greedily, one sign at a time
EXHAUSTIVE_SIGNS = 14

__all__ = ["ASSEMBLY_RTOL", "NAN_POINT", "Positions", "all_sign_combinations", "reference_mode", "solve"]


@dataclass(frozen=True)
class Positions:
    """Joint positions over (designs, samples).

    Attributes
    ----------
    z : ndarray, complex, shape (n_joints, D, n)
        Joint positions, NaN where the mechanism does not assemble.
    rot : dict of str to ndarray
        Rotation ``exp(i*theta)`` from the shape frame of the links later steps needed.
    margin : ndarray, shape (n_signs, D, n)
        For each sign step, how far from its assembly limit each sample is (relative;
        negative where the step has no solution).
    assembled : ndarray of bool, shape (D, n)
    signs : ndarray, shape (n_signs, D or 1, n or 1)
    mirrors : ndarray of bool, shape (n_mirrors, D or 1, n or 1)
    """

    z: np.ndarray
    rot: dict[str, Any]
    margin: np.ndarray
    assembled: np.ndarray
    signs: np.ndarray
    mirrors: np.ndarray


def solve(
    params: Params,
    q: np.ndarray,
    signs: np.ndarray | None = None,
    mirrors: np.ndarray | None = None,
    eps: float = ASSEMBLY_RTOL,
    out: np.ndarray | None = None,
    grid: WalkGrid | None = None,
    continuous: bool = False,
    turn: np.ndarray | None = None,
) -> Positions:
    """Positions of every joint for every design and input sample.

    Parameters
    ----------
    params : Params
        The plan and the numbers of ``D`` designs.
    q : array_like, shape (n_drivers, D or 1, n)
        Driver values: angles in radians, slider displacements in length units.
    signs : array_like, shape (n_signs, D or 1, n or 1), optional
        +1/-1 per sign step; default: each design's reference mode.
    mirrors : array_like of bool, shape (n_mirrors, D or 1, n or 1), optional
        True flips the link of three or more joints of that index; default: none.
    out : ndarray, complex, shape (n_joints, D, n), optional
        Where to write the positions.
    grid : WalkGrid, optional
        Set by this function itself: ``q``'s last columns are the grid a numerical group walks.
    continuous : bool
        Numerical groups follow their branch through change points (a sign change of their
        Jacobian's determinant is accepted where the motion is smooth); the sign steps take
        ``signs`` as given (:mod:`linkagekit.branch` chooses them).
    turn : ndarray of bool, shape (D, n), optional
        Set by this function itself: directions taken a turn the other way (:func:`_other_turn`).
    """
    plan = params.plan
    q = np.asarray(q, dtype=float)
    got = _solve_on_grid(params, q, signs, mirrors, eps, out, continuous) if plan.numerical and grid is None else None
    if got is not None:
        return got
    sg = params.signs[:, :, None] if signs is None else np.asarray(signs, float)
    mr = np.zeros((plan.n_mirrors, 1, 1), bool) if mirrors is None else np.asarray(mirrors, bool)
    D = params.n_designs
    n = int(np.broadcast_shapes(q.shape[-1:], sg.shape[-1:] if plan.n_signs else (1,), mr.shape[-1:])[0])
    z = np.empty((len(plan.joint_names), D, n), complex) if out is None else out
    if plan.unwritten:  # a joint no step writes is NaN, never uninitialised memory
        z[list(plan.unwritten)] = NAN_POINT
    k = Kin(z, {"ground": 1.0 + 0j}, np.zeros((plan.n_signs, D, n)), q, sg, mr, eps, params.pose_inputs, continuous)
    k.grid, k.upstream, k.turn = grid, None if grid is None else partial(_upstream, params, sg, mr, eps, k.walks), turn
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):  # failures are NaN and margins
        for st, nums in zip(plan.steps, params.steps, strict=True):
            _place(k, st, nums)
    # every failure shows in a step's margin (NaN downstream of it compares False too)
    assembled = np.all(k.margin >= 0, axis=0) if plan.n_signs else np.ones((D, n), bool)
    if plan.nan_flagged:  # a numerical group (or a block beyond its stroke) flags by NaN, not by a margin
        assembled &= np.all(np.isfinite(z[list(plan.nan_flagged)]), axis=0)
    if not params.valid.all():
        assembled &= params.valid[:, None]
    if not assembled.all():  # a mechanism that does not assemble has no joint positions at all
        z[:, ~assembled] = NAN_POINT
    return Positions(z, k.rot, k.margin, assembled, sg, mr)


def _place(k: Kin, st: Any, nums: Any) -> None:
    """Step ``st`` places its joints (a closed-form step's follow every group before it, :attr:`Kin.follows`)."""
    st.place(k, nums)
    if not isinstance(st, Group):
        k.placed(st)


def reference_mode(mech: Mechanism, params: Params) -> Params:
    """``params`` with the assembly mode of the mechanism's pose, found by solving (one design).

    When every length is read off the pose, the pose is an exact solution and its signs,
    read off its geometry by :func:`linkagekit.params.compile`, are already right.  When
    the file gives ``lengths``, every sign combination is solved at the pose's own input and
    the one whose joints lie nearest their pose positions wins (ties, as at a flat triangle,
    go to +1); above ``EXHAUSTIVE_SIGNS`` signs, greedily one sign at a time.
    """
    if not mech.has_given_lengths:
        return params

    plan = params.plan
    k = plan.n_signs
    pose = params.pose[:, 0][:, None, None]
    q0 = params.pose_inputs[:, :, None]
    if k == 0:  # a numerical group alone takes its mode from the pose: it must assemble there
        if plan.numerical and unplaced_step(params, q0) is not None:
            raise MechanismFileError(f"{mech.source}: {unassembled_text(params, q0)}")
        return params
    if k <= EXHAUSTIVE_SIGNS:
        combos = all_sign_combinations(k)
        sol = solve(params, np.broadcast_to(q0, (len(mech.drivers), 1, combos.shape[1])), combos[:, None, :])
        err = np.sum(np.abs(sol.z - pose) ** 2, axis=0)[0]
        err = np.where(np.isfinite(err), err, np.inf)
        best = float(np.min(err))
        if not np.isfinite(best):
            raise MechanismFileError(f"{mech.source}: {unassembled_text(params, q0)}")
        tol = 1e-18 * mech.length_scale**2 + best * 1e-9
        choice = int(np.flatnonzero(err <= best + tol)[0])
        return replace(params, signs=combos[:, choice : choice + 1].copy())
    signs = np.ones((k, 1))
    for i in range(k):  # greedy, for very large mechanisms
        errs = []
        for v in (1.0, -1.0):
            signs[i] = v
            sol = solve(params, q0, signs[:, :, None])
            d = np.abs(sol.z[:, 0, 0] - pose[:, 0, 0]) ** 2
            errs.append(float(np.nansum(d)) if np.isfinite(d).any() else np.inf)
        signs[i] = 1.0 if errs[0] <= errs[1] else -1.0
    return replace(params, signs=signs)


def unplaced_step(params: Params, q: np.ndarray) -> int | None:
    """The index (in ``params.plan.steps``) of the first step that cannot place its joints at the inputs ``q``
    (n_drivers, 1, 1) in the first design's own mode, or None when every step places them.

    The steps run as :func:`solve` runs them (with the grid a numerical group walks), and stop
    at the first whose joints are not finite or whose sign step has no solution there.

    Examples
    --------
    >>> import numpy as np, linkagekit as lk
    >>> from linkagekit.params import compile
    >>> p = compile(lk.load("examples/seed000_fourbar.yaml"))
    >>> unplaced_step(p, np.radians([[[0.0]]])) is None
    True
    """
    plan = params.plan
    q = np.asarray(q, dtype=float)
    walk = _walk_grid(params, q) if plan.numerical else None
    qg, grid = walk if walk is not None else (q, None)
    sg, mr = params.signs[:, :1, None], np.zeros((plan.n_mirrors, 1, 1), bool)
    z = np.full((len(plan.joint_names), 1, qg.shape[-1]), NAN_POINT)
    k = Kin(z, {"ground": 1.0 + 0j}, np.zeros((plan.n_signs, 1, qg.shape[-1])), qg, sg, mr, ASSEMBLY_RTOL)
    k.q0, k.grid = params.pose_inputs[:, :1], grid
    k.upstream = None if grid is None else partial(_upstream, params, sg, mr, ASSEMBLY_RTOL, k.walks)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        for i, (st, nums) in enumerate(zip(plan.steps, params.steps, strict=True)):
            _place(k, st, nums)
            sign = getattr(st, "sign", None) if is_sign_step(st) else None
            if not np.isfinite(z[list(st.writes()), 0, 0]).all() or (sign is not None and k.margin[sign, 0, 0] < 0):
                return i
    return None


def unassembled_text(params: Params, q: np.ndarray) -> str:
    """One line saying that the mechanism does not assemble at the inputs ``q`` of its reference pose, naming the
    joints, links and plan step (as ``linkagekit check`` numbers them) that first fail (:func:`unplaced_step`)."""
    plan = params.plan
    i = unplaced_step(params, q)
    if i is None:
        return (
            "the mechanism does not assemble at its reference pose's input (given lengths that do not close, "
            "or a degenerate pose: two joints that locate another joint coincide)"
        )
    st, names = plan.steps[i], plan.joint_names
    number = sum(s.describe(names, None) is not None for s in plan.steps[: i + 1])
    said = shorten((st.describe(names, params.steps[i]) or "").split("; ")[0].split(" (")[0], 60)  # its first clause
    joints, links = [names[j] for j in st.writes()], [f"'{name}'" for name in st.link_names()]
    which = " of ".join(
        f"{what}{'s' * (len(items) > 1)} {', '.join(items)}"
        for what, items in (("joint", joints), ("link", links))
        if items
    )
    return (
        f"does not assemble at its reference pose's input: {which or 'a step'} cannot be placed (step {number} of "
        f"the plan: {said}: no solution with the given lengths)"
    )


#: paths that follow the inputs (:mod:`linkagekit.branch`) pass through inputs at most this far apart
#: (radians): a sub-step between two samples moves the known joints along a chord, which must not skip a
#: turning point of the motion
WALK_STEP = np.radians(1.0)


def _solve_on_grid(
    params: Params,
    q: np.ndarray,
    signs: np.ndarray | None,
    mirrors: np.ndarray | None,
    eps: float,
    out: np.ndarray | None,
    continuous: bool = False,
) -> Positions | None:
    """:func:`solve` with the grid the numerical group walks appended to the samples (:func:`_walk_grid`), and
    the samples taken back; None without a grid (no driver, or no sample)."""
    walk = _walk_grid(params, q)
    if walk is None:
        return None
    qg, grid = walk
    n, m = q.shape[-1], qg.shape[-1]
    sg, mr = _dense_choice(signs, n, m), _dense_choice(mirrors, n, m)
    full = solve(params, qg, sg, mr, eps, grid=grid, continuous=continuous)
    got = take_samples(full, np.arange(n))
    if grid.cyclic and _after_a_group(params.plan):
        got = _other_turn(params, qg, grid, (sg, mr), eps, got, continuous)
    if out is not None:
        out[...] = got.z
        got = Positions(out, got.rot, got.margin, got.assembled, got.signs, got.mirrors)
    return got


def _after_a_group(plan: Plan) -> bool:
    """Whether a step comes after the plan's first numerical group (which may need it a turn the other way)."""
    first = next((i for i, st in enumerate(plan.steps) if isinstance(st, Group)), None)
    return first is not None and first < len(plan.steps) - 1


def _other_turn(
    params: Params,
    qg: np.ndarray,
    grid: WalkGrid,
    choices: tuple[np.ndarray | None, np.ndarray | None],
    eps: float,
    got: Positions,
    continuous: bool = False,
) -> Positions:
    """Samples that did not assemble with their directions taken nearest the pose's input, solved again with every
    numerical group a turn the other way (``turn``); taken where they assemble so.

    Each group goes the other way round by itself where its own branch ends first
    (:meth:`linkagekit.group.Group._other_turn`), but a later step needs the joints of the
    earlier ones on the same way round: the first of two triads in sequence turns fully (not
    back to the same configuration after a turn), the second ends 0.05 deg above the pose, and a
    direction whose nearest representative lies above the pose assembles only the other way round,
    for both groups. The samples of a chain (a step after a numerical group) that did not assemble
    are solved once more with all its groups that way round."""
    n = grid.n_given
    miss = ~got.assembled
    cols = np.flatnonzero(miss.any(axis=0))
    if not len(cols):
        return got
    keep = np.concatenate([cols, np.arange(n, qg.shape[-1])])

    def sub(a: np.ndarray | None) -> np.ndarray | None:
        return a[..., keep] if a is not None and np.ndim(a) and np.shape(a)[-1] > 1 else a

    signs, mirrors = choices
    grid = replace(grid, n_given=len(cols))
    again = solve(
        params, qg[..., keep], sub(signs), sub(mirrors), eps, grid=grid, continuous=continuous, turn=miss[:, cols]
    )
    use = miss[:, cols] & again.assembled[:, : len(cols)]
    if not use.any():
        return got
    z, margin, assembled = got.z.copy(), got.margin.copy(), got.assembled.copy()
    z[:, :, cols] = np.where(use, again.z[:, :, : len(cols)], z[:, :, cols])
    margin[:, :, cols] = np.where(use, again.margin[:, :, : len(cols)], margin[:, :, cols])
    assembled[:, cols] |= use
    rot = dict(got.rot)
    for name, v in got.rot.items():
        if np.ndim(v) and np.shape(v)[-1] == n:
            w = np.array(v, copy=True)
            w[..., cols] = np.where(use, again.rot[name][..., : len(cols)], w[..., cols])
            rot[name] = w
    return Positions(z, rot, margin, assembled, got.signs, got.mirrors)


def _held(choices: np.ndarray, used: list[int]) -> np.ndarray | None:
    """Per-sample ``choices`` (n, D, samples) as one column, where the rows ``used`` are the same at every sample
    (the others do not matter); None where they differ."""
    if choices.shape[-1] == 1:
        return choices
    rows = choices[used]
    return choices[..., :1] if np.all(rows == rows[..., :1]) else None


def _upstream(
    params: Params,
    signs: np.ndarray,
    mirrors: np.ndarray,
    eps: float,
    walks: dict[int, Any],
    q: np.ndarray,
    stop: Any,
) -> np.ndarray | None:
    """The joints the steps before ``stop`` place at inputs ``q`` (n_drivers, D, n), every design; None when the
    signs or mirrors of those steps differ between samples (following a branch continuously: which ones hold
    between two samples is not known). A numerical group before ``stop`` is solved there from its finished walk
    (``walks``, :meth:`linkagekit.group.Group.place_walked`): at the inputs as given, no turn added or taken off.

    A numerical group's sub-steps between two of its samples follow the inputs between them
    through this: the knowns it holds move as the mechanism moves them, not along the chord
    between their two positions (:mod:`linkagekit.group`). (The signs once had to be one column: a group after
    a crank, with no sign at all, had its sub-steps on the chord, where across a parallelogram's flat position
    the two modes only come close and the smooth continuation is the other one.)"""
    plan = params.plan
    before = plan.steps[: next(i for i, st in enumerate(plan.steps) if st is stop)]
    if any(isinstance(st, Group) and id(st) not in walks for st in before):
        return None
    sg = _held(signs, [i for i in (getattr(st, "sign", None) for st in before if is_sign_step(st)) if i is not None])
    mr = _held(mirrors, [m for m in (getattr(st, "mirror", None) for st in before) if m is not None])
    if sg is None or mr is None:
        return None
    D, n = params.n_designs, q.shape[-1]
    z = np.full((len(plan.joint_names), D, n), NAN_POINT)
    k = Kin(z, {"ground": 1.0 + 0j}, np.zeros((plan.n_signs, D, n)), q, sg, mr, eps, params.pose_inputs)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        for st, nums in zip(before, params.steps, strict=False):
            if isinstance(st, Group):
                st.place_walked(k, nums, walks[id(st)])
            else:
                st.place(k, nums)
    return z


def _nearest_turn(params: Params, key: np.ndarray) -> np.ndarray:
    """Inputs ``key`` (n_drivers, n; the pose's first) with every angle's taken at its direction's representative
    nearest the pose's, as :func:`linkagekit.group.grid_places` takes it (an angle is a direction: the walk's path
    through the samples, and so an answer, is the same for u + 360 k)."""
    angular = np.zeros(len(key), bool)
    got = next((st.angular for st in params.plan.steps if isinstance(st, Group)), ())
    angular[: len(got)] = np.asarray(got, bool)[: len(key)]
    step = key - key[:, :1]
    near = key[:, :1] + step - 2 * np.pi * np.floor(step / (2 * np.pi) + 0.5)
    out: np.ndarray = np.where(angular[:, None], near, key)
    return out


def _walk_driver(params: Params, key: np.ndarray) -> tuple[int, bool]:
    """The driver the walk follows (the one that moves most over ``key`` (n_drivers, n), the pose's input
    first) and whether it is an angle (its input is a direction)."""
    d = int(np.argmax(np.ptp(key, axis=1)))
    angular = next((st.angular for st in params.plan.steps if isinstance(st, Group)), ())
    return d, d < len(angular) and bool(angular[d])


def _grid_step(params: Params, cyclic: bool) -> np.ndarray:
    """The walk's grid step per design: ``GRID_STEP`` for an angle, ``GRID_STEP_LENGTH`` of the first group's
    mean link length for a length."""
    D = params.n_designs
    if cyclic:
        return np.full(D, GRID_STEP)
    st, nums = next((s, n) for s, n in zip(params.plan.steps, params.steps, strict=True) if isinstance(s, Group))
    lengths = np.array(st._design_nums(nums, np.arange(D))[0], float).reshape(-1, D)
    step: np.ndarray = GRID_STEP_LENGTH * np.mean(lengths, axis=0)
    return step


def _walk_grid(params: Params, q: np.ndarray) -> tuple[np.ndarray, WalkGrid] | None:
    """The inputs with the grid the numerical walk follows appended: (inputs (n_drivers, D, n + G), grid).

    The grid is fixed: the pose's input plus whole steps of the driver that moves most
    (:func:`_grid_step`), as far as the samples may need (for an angle, the representatives
    of their directions either way round, :func:`linkagekit.group.grid_places`; at most
    ``GRID_MOST`` steps either way for a length); the other drivers are interpolated along
    it (between the pose's values and the samples', every angle at its representative
    nearest the pose's, :func:`_nearest_turn`). None without a driver or a sample.
    """
    n = q.shape[-1]
    if q.ndim != 3 or n == 0 or q.shape[0] == 0:
        return None
    D = params.n_designs
    q0 = params.pose_inputs
    qb = np.broadcast_to(q, (q.shape[0], D, n))
    key = _nearest_turn(params, np.concatenate([q0[:, :1], qb[:, 0, :]], axis=1))  # the pose's input first
    d, cyclic = _walk_driver(params, key)
    step = _grid_step(params, cyclic)
    near, other = grid_places(qb[d], q0[d], step, cyclic)
    with np.errstate(invalid="ignore"):
        ends = np.nan_to_num(np.array([np.nanmin([near, other]), np.nanmax([near, other])]), posinf=0, neginf=0)
    if not cyclic and d < len(params.strokes):  # past the stroke every sample is flagged: the walk stops a cell out
        with np.errstate(invalid="ignore"):
            bounds = (np.array(params.strokes[d])[:, None] - q0[d][None]) / step[None]  # (2, D) places
        ends = np.clip(ends, np.min(bounds[0]) - 1, np.max(bounds[1]) + 1)
    lo, hi = (int(np.clip(f(e), -GRID_MOST, GRID_MOST)) for f, e in zip((np.floor, np.ceil), ends, strict=True))
    index = np.arange(min(lo, 0), max(hi, 0) + 1)
    x = q0[d][:, None] + index * step[:, None]  # (D, G)
    srt = np.argsort(key[d], kind="stable")
    rows = [x if i == d else np.interp(x, key[d][srt], key[i][srt]) for i in range(q.shape[0])]
    qg = np.concatenate([qb, np.array(rows)], axis=2)
    return qg, WalkGrid(n, index, step, d, cyclic)


def _dense_choice(arr: np.ndarray | None, n: int, n_total: int) -> np.ndarray | None:
    """Signs or mirrors given per sample, extended to the added samples (with the first sample's)."""
    if arr is None:
        return None
    a = np.asarray(arr)
    if a.ndim == 0 or a.shape[-1] != n or n == 1:
        return a
    return np.concatenate([a, np.repeat(a[..., :1], n_total - n, axis=-1)], axis=-1)


def take_samples(full: Positions, keep: np.ndarray) -> Positions:
    """The given samples of a dense solve."""
    rot = {k: (v[..., keep] if np.ndim(v) and np.shape(v)[-1] > 1 else v) for k, v in full.rot.items()}
    sg = full.signs[..., keep] if full.signs.shape[-1] > 1 else full.signs
    mr = full.mirrors[..., keep] if full.mirrors.shape[-1] > 1 else full.mirrors
    return Positions(full.z[..., keep], rot, full.margin[..., keep], full.assembled[..., keep], sg, mr)
