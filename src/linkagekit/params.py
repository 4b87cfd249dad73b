"""Parameters: every number a plan's steps use, for one design or a batch of designs.

:func:`compile` turns a mechanism (one design) or a mechanism plus an array of reference
poses (many designs of its topology) into :class:`Params`: per step, the step's numbers
with a leading design axis (``(D, 1)`` arrays that broadcast against ``(D, samples)``),
the driver values at which each design's pose stands, each design's reference assembly
mode (signs), and a per-design validity flag.

Where the numbers come from
---------------------------
* A mechanism: the link shapes of the model (read off the pose, or built from the
  ``lengths`` the file gives).  The reference signs are read off the pose's geometry,
  exact when every length comes from the pose (the pose is then a solution); when the
  file gives lengths, the solver layer replaces them by the mode nearest the pose
  (:func:`linkagekit.positions.reference_mode`, docs/mechanism-files.md).
* Poses ``(D, n_joints, 2)``: each design's shapes are its pose (every link's joints as
  they stand), exactly as a file without ``lengths``; its signs are read off its pose.
  Slider directions, masses and loads are the mechanism's (see :mod:`linkagekit.forces`).
  A design with two joints of one link at one spot is invalid: it never assembles.

Examples
--------
>>> import numpy as np, linkagekit as lk
>>> mech = lk.load("examples/seed003_ex21.yaml")
>>> p = compile(mech)
>>> p.n_designs, p.signs.tolist()
(1, [[1.0]])
>>> pose = mech.pose_array()
>>> poses = np.stack([pose, pose * [1, -1]])  # the pose and its mirror image about the x axis
>>> compile(mech, poses).signs.tolist()
[[1.0, -1.0]]
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from functools import lru_cache
from typing import TYPE_CHECKING, Any, assert_never

import numpy as np

from .errors import InputError
from .model import MIN_SIZE, CrankType, CylinderType, SliderType
from .plan import Plan, make_plan
from .steps import Nums, is_sign_step

if TYPE_CHECKING:
    from .model import Mechanism


@dataclass(frozen=True)
class Body:
    """Mass properties of one moving link, per design (arrays (D, 1)).

    ``inertia`` (kg*m^2) is the link's own, about its centre of gravity, plus its flywheels'
    (massless rotors: their inertia adds whatever the reference point).

    ``cg`` is where the centre of gravity sits on the link: for a link of two or more joints
    the complex ratio ``rho = (G - s_a) / (s_b - s_a)`` to its first two joints, so
    ``z_G = z_a + rho (z_b - z_a)``; for a one-joint block, the offset ``G - s_j`` turned with
    the block.  None: a massless link (its moment reference is its first joint).
    """

    link: str
    mass: np.ndarray
    inertia: np.ndarray
    cg: np.ndarray | None


@dataclass(frozen=True)
class LoadParams:
    """An external load on one link, per design (arrays (D, 1)): force (N, complex), torque (N*m),
    and its point ``at`` in the same ratio/offset form as :attr:`Body.cg` (None: at the reference point)."""

    link: str
    force: np.ndarray
    torque: np.ndarray
    at: np.ndarray | None


@dataclass(frozen=True)
class Params:
    """The numbers of a plan's steps for ``n_designs`` designs.

    Attributes
    ----------
    plan : Plan
    steps : tuple
        ``steps[i]`` is the numbers tuple of ``plan.steps[i]`` (see each step's ``numbers``).
    pose_inputs : ndarray, shape (n_drivers, D)
        Driver values at each design's pose (radians; length units for a slider's displacement
        and a cylinder's length).
    signs : ndarray, shape (n_signs, D)
        Each design's reference assembly mode (+1/-1 per sign step).
    valid : ndarray of bool, shape (D,)
        False for a degenerate design (two joints of a link at one spot).
    pose : ndarray, complex, shape (n_joints, D)
        Each design's reference pose.
    bases : dict
        Link name -> (s_a, s_b), the shape positions of its first two joints, each (D, 1).
    bodies, loads : tuple
        Mass properties of every moving link and the external loads, per design
        (:class:`Body`, :class:`LoadParams`).  For a batch of poses they are the mechanism's:
        a centre of gravity or load point keeps its ratio to its link's first two joints.
    """

    plan: Plan
    steps: tuple[Nums, ...]
    pose_inputs: np.ndarray
    signs: np.ndarray
    valid: np.ndarray
    pose: np.ndarray
    bases: dict[str, tuple[np.ndarray, np.ndarray]]
    bodies: tuple[Body, ...] = ()
    loads: tuple[LoadParams, ...] = ()
    #: each driver's stroke (min, max) in its input's units, (-inf, inf) where it has none (every design's)
    strokes: tuple[tuple[float, float], ...] = ()

    @property
    def n_designs(self) -> int:
        return int(self.valid.shape[0])

    def read_only(self) -> Params:
        """This object with every array made read-only (safe to cache and share)."""

        def lock(x: Any) -> Any:
            if isinstance(x, tuple):
                return tuple(lock(y) for y in x)
            if isinstance(x, np.ndarray):
                x.flags.writeable = False
            return x

        for field in (self.steps, self.pose_inputs, self.signs, self.valid, self.pose):
            lock(field)
        for body in self.bodies:
            lock((body.mass, body.inertia, body.cg))
        for ld in self.loads:
            lock((ld.force, ld.torque, ld.at))
        for pair in self.bases.values():
            lock(pair)
        return self

    def take(self, sl: slice | np.ndarray) -> Params:
        """The designs ``sl`` of this batch (a slice for chunked solves, or design indices, repeats allowed)."""
        if isinstance(sl, slice) and sl == slice(0, self.n_designs):
            return self

        def cut(x: Any) -> Any:
            if isinstance(x, tuple):
                return tuple(cut(y) for y in x)
            if isinstance(x, np.ndarray) and x.ndim == 2:  # (D, 1)
                return x[sl]
            if isinstance(x, np.ndarray) and x.ndim == 3:  # (m, D, 1)
                return x[:, sl]
            return x

        return Params(
            self.plan,
            tuple(cut(n) for n in self.steps),
            self.pose_inputs[:, sl],
            self.signs[:, sl],
            self.valid[sl],
            self.pose[:, sl],
            {k: (a[sl], b[sl]) for k, (a, b) in self.bases.items()},
            tuple(Body(b.link, b.mass[sl], b.inertia[sl], None if b.cg is None else b.cg[sl]) for b in self.bodies),
            tuple(
                LoadParams(ld.link, ld.force[sl], ld.torque[sl], None if ld.at is None else ld.at[sl])
                for ld in self.loads
            ),
            self.strokes,
        )


class _Shapes:
    """The :class:`~linkagekit.steps.Source` of step numbers: shapes and pose per design."""

    def __init__(self, mech: Mechanism, plan: Plan, poses: np.ndarray | None) -> None:
        self.names = plan.joint_names
        self.mech = mech
        self.z: np.ndarray  # (n_joints, D, 1) complex
        if poses is None:
            self.z = np.array([mech.joints[j] for j in self.names], complex)[:, None, None]
            self.batch = False
        else:
            self.z = (poses[..., 0] + 1j * poses[..., 1]).T[:, :, None]  # (n_joints, D, 1)
            self.batch = True
        self.D = self.z.shape[1]
        self.directions = [np.full((self.D, 1), s.direction) for s in mech.sliders]

    def shape(self, link: str, joint: int) -> np.ndarray:
        if self.batch:
            return self.pose(joint)
        return np.full((1, 1), self.mech.link(link).shape[self.names[joint]])

    def pose(self, joint: int) -> np.ndarray:
        z: np.ndarray = self.z[joint]
        return z

    def direction(self, slider: int) -> np.ndarray:
        return self.directions[slider]

    def stroke(self, driver: int) -> tuple[np.ndarray, np.ndarray]:
        lo, hi = self.mech.drivers[driver].stroke or (-np.inf, np.inf)
        return np.full((self.D, 1), lo), np.full((self.D, 1), hi)


def _pose_inputs(mech: Mechanism, plan: Plan, zpose: np.ndarray) -> np.ndarray:
    """Driver values at the pose, (n_drivers, D): angle of pivot -> toward; slider displacement 0; cylinder length."""
    idx = {n: i for i, n in enumerate(plan.joint_names)}
    rows = []
    for d in mech.drivers:
        match d.type:
            case CrankType(pivot=pivot, toward=toward):
                rows.append(np.angle(zpose[idx[toward]] - zpose[idx[pivot]]))
            case CylinderType(ends=(a, b)):
                rows.append(np.abs(zpose[idx[b]] - zpose[idx[a]]))
            case SliderType():
                rows.append(np.zeros(zpose.shape[1]))
            case _:
                assert_never(d.type)
    return np.array(rows, float).reshape(len(mech.drivers), zpose.shape[1])


def as_poses(mech: Mechanism, poses: Any) -> np.ndarray:
    """Check and convert a user's poses to a float array (D, n_joints, 2)."""
    try:
        arr = np.asarray(poses, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise InputError("poses: expected an array of numbers (n_designs, n_joints, 2)") from None
    nj = len(mech.joints)
    if arr.ndim == 2:
        arr = arr[None]
    if arr.ndim != 3 or arr.shape[1:] != (nj, 2):
        raise InputError(
            f"poses: expected shape (n_designs, {nj}, 2) (joints in the order {', '.join(mech.joints)}), "
            f"got {arr.shape}"
        )
    if arr.shape[0] == 0:
        raise InputError("poses: no design given")
    if not np.all(np.isfinite(arr)):
        raise InputError("poses: every coordinate must be a finite number")
    return arr


def compile(mech: Mechanism, poses: np.ndarray | None = None, plan: Plan | None = None) -> Params:  # noqa: A001
    """The numbers of every step for the mechanism, or for each of ``poses`` (D, n_joints, 2)."""
    plan = make_plan(mech) if plan is None else plan
    src = _Shapes(mech, plan, None if poses is None else as_poses(mech, poses))
    nums = tuple(st.numbers(src) for st in plan.steps)
    zpose = src.z
    if poses is None:
        valid = np.ones(1, bool)
    else:
        # a design is valid when no two joints of one link coincide (relative to the design's size), and it is not
        # too small to solve (a file's least size: at 1e-160 it said "assembled" with no positions)
        scale = np.max(np.abs(zpose - zpose.mean(axis=0)), axis=0)[:, 0]  # (D,)
        ia, ib = _link_pairs(mech, plan.joint_names)
        valid = np.all(np.abs(zpose[ia, :, 0] - zpose[ib, :, 0]) > 1e-9 * scale, axis=0) & (
            scale >= MIN_SIZE / 2 * (1 - 1e-9)
        )
    bases = {}
    for ln in mech.links:
        if len(ln.joints) >= 2:
            a, b = (plan.joint_names.index(j) for j in ln.joints[:2])
            bases[ln.name] = (src.shape(ln.name, a), src.shape(ln.name, b))
    q0 = _pose_inputs(mech, plan, zpose[:, :, 0])
    sign_rows = [st.pose_sign(zpose, n)[:, 0] for st, n in zip(plan.steps, nums, strict=True) if is_sign_step(st)]  # type: ignore[attr-defined]
    signs = np.array(sign_rows, float).reshape(plan.n_signs, src.D)
    bodies, loads = _dynamics(mech, src)
    strokes = tuple(d.stroke or (-np.inf, np.inf) for d in mech.drivers)
    return Params(plan, nums, q0, signs, valid, zpose[:, :, 0], bases, bodies, loads, strokes)


@lru_cache(maxsize=64)
def _link_pairs(mech: Mechanism, names: tuple[str, ...]) -> tuple[list[int], list[int]]:
    """Every pair of joints that share a link, as two lists of joint indices."""
    pairs = [(a, b) for ln in mech.links for i, a in enumerate(ln.joints) for b in ln.joints[i + 1 :]]
    return [names.index(a) for a, _ in pairs], [names.index(b) for _, b in pairs]


def _on_link(mech: Mechanism, link: str, local: complex) -> complex:
    """A shape-frame point of a link as its ratio to the first two joints (offset from the joint for a block)."""
    ln = mech.link(link)
    s0 = ln.shape[ln.joints[0]]
    if len(ln.joints) >= 2:
        return complex((local - s0) / (ln.shape[ln.joints[1]] - s0))
    return complex(local - s0)


def _dynamics(mech: Mechanism, src: _Shapes) -> tuple[tuple[Body, ...], tuple[LoadParams, ...]]:
    """The mechanism's mass properties and loads, one row per design.

    A centre of gravity or a load point given as a point keeps the mechanism's ratio to its
    link's first two joints; a load at a named joint follows that joint in every design.
    """
    D = src.D
    names = src.names

    def col(value: complex | float) -> np.ndarray:
        return np.full((D, 1), value)

    def at_joint(link: str, joint: str) -> np.ndarray:
        """A joint of a link as its ratio to the link's first two joints, per design (offset 0 on a block)."""
        js = mech.link(link).joints
        if len(js) < 2:
            return col(0j)
        a, b, j = (names.index(x) for x in (js[0], js[1], joint))
        sa = src.shape(link, a)
        return np.asarray((src.shape(link, j) - sa) / (src.shape(link, b) - sa), complex) * np.ones((D, 1))

    def load_point(ld: Any) -> np.ndarray | None:
        if ld.at_joint is not None:
            return at_joint(ld.link, ld.at_joint)
        return None if ld.at is None else col(_on_link(mech, ld.link, ld.at))

    bodies = tuple(  # a flywheel is inertia without mass on its link: its I adds to the link's
        Body(
            ln.name,
            col(ln.mass),
            col(ln.inertia + mech.flywheel_inertia(ln.name)),
            None if ln.cg is None else col(_on_link(mech, ln.name, ln.cg)),
        )
        for ln in mech.links
        if ln.name != "ground"
    )
    loads = tuple(
        LoadParams(
            ld.link,
            col(ld.force),
            col(ld.torque),
            load_point(ld),
        )
        for ld in mech.loads
        if ld.link != "ground"
    )
    return bodies, loads


def all_sign_combinations(k: int) -> np.ndarray:
    """Every +1/-1 vector of length k, shape (k, 2**k), starting with all +1."""
    if k == 0:
        return np.ones((0, 1))
    return np.array(list(itertools.product((1.0, -1.0), repeat=k)), dtype=float).T.reshape(k, -1)
