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

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from .errors import MechanismFileError
from .geometry import ASSEMBLY_RTOL, NAN_POINT
from .group import WALK_REACH, Group
from .params import Params, all_sign_combinations
from .steps import Kin

if TYPE_CHECKING:
    from .model import Mechanism

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
    _dense: bool = False,
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
    """
    plan = params.plan
    q = np.asarray(q, dtype=float)
    if plan.numerical and not _dense:
        dense = _walk_inputs(params, q)
        if dense is not None:  # the numerical group walks along the inputs, not across gaps between them
            qd, keep = dense
            m = qd.shape[-1]
            sd, md = _dense_choice(signs, len(keep), m), _dense_choice(mirrors, len(keep), m)
            full = solve(params, qd, sd, md, eps, _dense=True)
            got = _take_samples(full, keep)
            if out is not None:
                out[...] = got.z
                got = Positions(out, got.rot, got.margin, got.assembled, got.signs, got.mirrors)
            return got
    sg = params.signs[:, :, None] if signs is None else np.asarray(signs, float)
    mr = np.zeros((plan.n_mirrors, 1, 1), bool) if mirrors is None else np.asarray(mirrors, bool)
    D = params.n_designs
    n = int(np.broadcast_shapes(q.shape[-1:], sg.shape[-1:] if plan.n_signs else (1,), mr.shape[-1:])[0])
    shape = (len(plan.joint_names), D, n)
    z = np.empty(shape, complex) if out is None else out
    missing = plan.unwritten
    if missing:  # a joint no step writes is NaN, never uninitialised memory
        z[list(missing)] = NAN_POINT
    k = Kin(z, {"ground": 1.0 + 0j}, np.zeros((plan.n_signs, D, n)), q, sg, mr, eps, params.pose_inputs)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):  # failures are NaN and margins
        for st, nums in zip(plan.steps, params.steps, strict=True):
            st.place(k, nums)
    # every failure shows in a step's margin (NaN downstream of it compares False too)
    assembled = np.all(k.margin >= 0, axis=0) if plan.n_signs else np.ones((D, n), bool)
    if plan.nan_flagged:  # a numerical group (or a block beyond its stroke) flags by NaN, not by a margin
        assembled &= np.all(np.isfinite(z[list(plan.nan_flagged)]), axis=0)
    if not params.valid.all():
        assembled &= params.valid[:, None]
    if not assembled.all():  # a mechanism that does not assemble has no joint positions at all
        z[:, ~assembled] = NAN_POINT
    return Positions(z, k.rot, k.margin, assembled, sg, mr)


def reference_mode(mech: Mechanism, params: Params) -> Params:
    """``params`` with the assembly mode of the mechanism's pose, found by solving (one design).

    When every length is read off the pose, the pose is an exact solution and its signs,
    read off its geometry by :func:`linkagekit.params.compile`, are already right.  When
    the file gives ``lengths``, every sign combination is solved at the pose's own input and
    the one whose joints lie nearest their pose positions wins (ties, as at a flat triangle,
    go to +1); above ``EXHAUSTIVE_SIGNS`` signs, greedily one sign at a time.
    """
    if not mech.has_given_lengths or params.plan.n_signs == 0:
        return params
    from dataclasses import replace

    plan = params.plan
    k = plan.n_signs
    pose = params.pose[:, 0][:, None, None]
    q0 = params.pose_inputs[:, :, None]
    if k <= EXHAUSTIVE_SIGNS:
        combos = all_sign_combinations(k)
        sol = solve(params, np.broadcast_to(q0, (len(mech.drivers), 1, combos.shape[1])), combos[:, None, :])
        err = np.sum(np.abs(sol.z - pose) ** 2, axis=0)[0]
        err = np.where(np.isfinite(err), err, np.inf)
        best = float(np.min(err))
        if not np.isfinite(best):
            raise MechanismFileError(
                f"{mech.source}: the mechanism does not assemble at its reference pose's input "
                f"(given lengths that do not close, or a degenerate pose where two joints "
                f"a joint is found from coincide)"
            )
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


#: the numerical group's walk passes through inputs at most this far apart (radians; lengths use
#: 1/360 of the sweep's span): a sub-step between two samples moves the known joints along a chord,
#: which must not skip a turning point of the motion
WALK_STEP = np.radians(1.0)


def _walk_driver(params: Params, key: np.ndarray) -> tuple[int, bool]:
    """The driver the walk follows (the one that moves most over ``key``, the pose's input first) and
    whether it is an angle (then the walk goes at most ``WALK_REACH`` from the pose's input)."""
    d = int(np.argmax(np.ptp(key, axis=1)))
    angular = next((st.angular for st in params.plan.steps if isinstance(st, Group)), ())
    return d, d < len(angular) and bool(angular[d])


def beyond_reach(params: Params, q: np.ndarray) -> np.ndarray:
    """Which samples of inputs ``q`` ``(n_drivers, n)`` (solver units) the numerical walk never goes to.

    All False for a plan without a numerical group, or when the walk follows a length.
    """
    if not any(isinstance(st, Group) for st in params.plan.steps):
        return np.zeros(q.shape[-1], dtype=bool)
    key = np.concatenate([params.pose_inputs[:, :1], q], axis=1)
    d, angle = _walk_driver(params, key)
    return np.abs(q[d] - key[d, 0]) > WALK_REACH if angle else np.zeros(q.shape[-1], dtype=bool)


def _walk_inputs(params: Params, q: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """The inputs with the samples the numerical walk needs added: (inputs, columns of the given ones).

    Along the driver that moves most, from the pose's input to every sample, at most ``WALK_STEP``
    apart; the other drivers are interpolated along it. An angle sample more than
    :data:`linkagekit.group.WALK_REACH` from the pose's input gets no added samples (the walk
    never goes there: it is not reached), so at most ``2 WALK_REACH / WALK_STEP`` are added.
    None when nothing needs adding, or when the inputs carry a design axis.
    """
    n = q.shape[-1]
    if q.ndim != 3 or q.shape[1] != 1 or n == 0 or q.shape[0] == 0:
        return None
    q0 = params.pose_inputs[:, 0]
    key = np.concatenate([q0[:, None], q[:, 0, :]], axis=1)  # the pose's input first
    d, angle = _walk_driver(params, key)
    if angle:
        key = key[:, np.abs(key[d] - key[d, 0]) <= WALK_REACH]  # the samples the walk goes to
        step = WALK_STEP
    else:
        step = max(float(np.ptp(key[d])) / 360.0, 1e-300)
    x = key[d]
    order = np.unique(x)
    added = [
        np.linspace(a, b, int(np.ceil((b - a) / step)) + 1)[1:-1] for a, b in zip(order[:-1], order[1:], strict=True)
    ]
    extra = np.concatenate(added) if added else np.zeros(0)
    if not len(extra):
        return None
    srt = np.argsort(x, kind="stable")
    rows = [extra if i == d else np.interp(extra, x[srt], key[i][srt]) for i in range(q.shape[0])]
    dense = np.concatenate([q[:, 0, :], np.array(rows)], axis=1)[:, None, :]
    return dense, np.arange(n)


def _dense_choice(arr: np.ndarray | None, n: int, n_total: int) -> np.ndarray | None:
    """Signs or mirrors given per sample, extended to the added samples (with the first sample's)."""
    if arr is None:
        return None
    a = np.asarray(arr)
    if a.ndim == 0 or a.shape[-1] != n or n == 1:
        return a
    return np.concatenate([a, np.repeat(a[..., :1], n_total - n, axis=-1)], axis=-1)


def _take_samples(full: Positions, keep: np.ndarray) -> Positions:
    """The given samples of a dense solve."""
    rot = {k: (v[..., keep] if np.ndim(v) and np.shape(v)[-1] > 1 else v) for k, v in full.rot.items()}
    sg = full.signs[..., keep] if full.signs.shape[-1] > 1 else full.signs
    mr = full.mirrors[..., keep] if full.mirrors.shape[-1] > 1 else full.mirrors
    return Positions(full.z[..., keep], rot, full.margin[..., keep], full.assembled[..., keep], sg, mr)
