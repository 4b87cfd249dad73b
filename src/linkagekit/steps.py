"""The solve steps: one small class per kind, with its numbers, placement, rates and description.

A step places joints (and link rotations) from joints already placed.  The step object is
topology only (joint indices, link names, which sign or mirror slot it reads): it is
hashable and picklable, and the same for every design of a topology.  Its numbers (radii,
shape ratios, slider lines) come from :meth:`Step.numbers`, one entry per design, and are
kept by :mod:`linkagekit.params`.

Every step implements

``numbers(src)``
    the step's constants read off the link shapes and the reference pose of every
    design (arrays with a leading design axis and a trailing axis of length 1, so they
    broadcast against ``(designs, samples)``);
``place(k, nums)``
    positions, on a :class:`Kin` holding ``z`` (joints x designs x samples, complex);
``rates(r, nums)``
    velocities and accelerations of the same joints, on a :class:`Rate`;
``pose_sign(zpose, nums)`` (sign steps only)
    the sign of the reference pose, read off its geometry (exact when the lengths come
    from the pose);
``describe(names, nums)``
    one line for ``linkagekit check``.

Notation: points are complex (:mod:`linkagekit.geometry`); ``a . b = Re(conj(a) b)``,
``cross(a, b) = Im(conj(a) b)``.  The derivations are in ``docs/method.md``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

from .geometry import _TINY, NAN_POINT, circle_circle, cis, cross, dot, link_rates, side

Nums = tuple[Any, ...]


class Source(Protocol):
    """Where steps read their numbers: link shapes and the pose, one row per design."""

    def shape(self, link: str, joint: int) -> np.ndarray:
        """Shape-frame position of ``joint`` on ``link``, shape (designs, 1), complex."""
        ...

    def pose(self, joint: int) -> np.ndarray:
        """Reference-pose position of ``joint``, shape (designs, 1), complex."""
        ...

    def direction(self, slider: int) -> np.ndarray:
        """Unit direction of ``slider`` in the reference pose, shape (designs, 1), complex."""
        ...

    def stroke(self, driver: int) -> tuple[np.ndarray, np.ndarray]:
        """Bounds of ``driver``'s input (a cylinder's length, a slider's displacement), (designs, 1) each; inf: none."""
        ...


@dataclass
class Kin:
    """Working state of a positions solve over (designs, samples).

    ``z`` (n_joints, D, n) complex, NaN until a step writes a joint; ``rot`` link ->
    rotation from the shape frame; ``margin`` (n_signs, D, n); ``q`` driver values
    (n_drivers, D or 1, n) in radians or length units; ``signs`` (n_signs, D or 1, n or 1);
    ``mirrors`` (n_mirrors, D or 1, n or 1) bool; ``eps`` the assembly tolerance.
    """

    z: np.ndarray
    rot: dict[str, Any]
    margin: np.ndarray
    q: np.ndarray
    signs: np.ndarray
    mirrors: np.ndarray
    eps: float
    q0: np.ndarray | None = None  # (n_drivers, D) driver values at the pose (numerical groups walk from it)
    continuous: bool = False  # numerical groups follow their branch through change points (linkagekit.branch)
    grid: WalkGrid | None = None  # the fixed inputs numerical groups walk (columns of q after the given samples)
    #: the joints the steps before ``stop`` place at other inputs ``q2`` (n_drivers, D, n2): ``upstream(q2, stop)``
    #: (n_joints, D, n2), NaN where not placed; None where that cannot be re-run (a numerical group before it)
    upstream: Callable[..., np.ndarray | None] | None = None
    #: (D, n given) where a numerical group takes each sample's direction a turn the other way from the nearest one
    #: to the pose's input (:func:`linkagekit.positions.solve`'s second pass for chains of groups)
    turn: np.ndarray | None = None
    #: (D, n given) each sample's place on the grid (in grid steps from the pose's input) where the plan's first
    #: numerical group solved it, NaN where it did not: the later groups take the same way round (set by that group)
    took: np.ndarray | None = None
    #: each numerical group's finished walk (by ``id`` of the step), which :attr:`upstream` re-runs the group from at
    #: other inputs (:meth:`linkagekit.group.Group.place_walked`)
    walks: dict[int, Any] = field(default_factory=dict)
    #: joint -> the numerical groups (``id`` of the step) whose motion it follows: a group's own joints follow it
    #: and what its knowns follow; a closed-form step's joints, every group placed before it (a later group steps
    #: through the cells where those took sub-steps, :meth:`linkagekit.group.Group.place`)
    follows: dict[int, frozenset[int]] = field(default_factory=dict)

    def placed(self, step: Any) -> None:
        """Note that closed-form ``step`` placed its joints (:attr:`follows`)."""
        if self.walks:
            groups = frozenset(self.walks)
            self.follows.update((j, groups) for j in step.writes())


@dataclass(frozen=True)
class WalkGrid:
    """The fixed inputs a numerical group walks, appended to the given samples by the positions solve.

    Column ``n_given + g`` of ``q`` is the input ``q0[driver] + index[g] * step`` of driver
    ``driver`` (``index`` increasing, holding 0: the pose's input); ``cyclic``: that driver is
    an angle, so a sample's input is a direction (:mod:`linkagekit.group`).
    """

    n_given: int
    index: np.ndarray  # (G,) int
    step: np.ndarray  # (D,) the grid's step per design (radians or length units)
    driver: int
    cyclic: bool


@dataclass
class Rate:
    """Working state of a rates solve: positions in, velocities/accelerations out."""

    z: np.ndarray
    rot: dict[str, Any]
    mirrors: np.ndarray
    v: np.ndarray
    a: np.ndarray
    w_in: np.ndarray  # (n_drivers, D or 1, n): input speeds
    a_in: np.ndarray  # input accelerations
    cond: np.ndarray  # (n_signs, D, n): dimensionless conditioning of each sign step
    om: dict[str, Any] = field(default_factory=dict)
    al: dict[str, Any] = field(default_factory=dict)
    extra_cond: list[np.ndarray] = field(default_factory=list)  # (D, n) conditioning of each numerical group

    def frame(self, on: str, anchor: int | None) -> tuple[Any, Any, Any, Any, Any]:
        """Angular rates of link ``on`` and the motion of its anchor joint (zero for the ground)."""
        if anchor is None:
            return 0.0, 0.0, 0.0, 0.0, 0.0
        return self.om[on], self.al[on], self.v[anchor], self.a[anchor], self.z[anchor]


class Step:
    """Base of the step kinds (see the module docstring)."""

    def numbers(self, src: Source) -> Nums:
        return ()

    def place(self, k: Kin, nums: Nums) -> None:
        raise NotImplementedError

    def rates(self, r: Rate, nums: Nums) -> None:
        raise NotImplementedError

    def describe(self, names: tuple[str, ...], nums: Nums | None) -> str | None:
        raise NotImplementedError

    def rotation_needs(self) -> tuple[str, ...]:
        """Links whose rotation this step reads."""
        return ()

    def writes(self) -> tuple[int, ...]:
        """The joints this step places (its ``joints``, or its one ``joint``)."""
        joint = getattr(self, "joint", None)
        return (joint,) if joint is not None else tuple(getattr(self, "joints", ()))

    def link_names(self) -> tuple[str, ...]:
        """The links whose dimensions this step reads (its ``links``, or its one ``link``): what a message names
        when the step cannot place its joints."""
        links = getattr(self, "links", None)
        if links is not None:
            return tuple(links)
        link = getattr(self, "link", None)
        return (link,) if link else ()


def _num(value: Any) -> str:
    """A design's number for a description (the first design of a batch)."""
    return f"{float(np.ravel(value)[0]):.6g}"


@dataclass(frozen=True)
class Ground(Step):
    """The joints of the frame: fixed at their ground-shape positions."""

    joints: tuple[int, ...]

    def numbers(self, src: Source) -> Nums:
        return (np.stack([src.shape("ground", j) for j in self.joints]),)

    def place(self, k: Kin, nums: Nums) -> None:
        for j, zj in zip(self.joints, nums[0], strict=True):
            k.z[j] = zj

    def rates(self, r: Rate, nums: Nums) -> None:
        r.v[list(self.joints)] = 0.0
        r.a[list(self.joints)] = 0.0

    def describe(self, names: tuple[str, ...], nums: Nums | None) -> str | None:
        return "fixed joints " + ", ".join(names[j] for j in self.joints)


@dataclass(frozen=True)
class Crank(Step):
    """A driven link: ``z_t = z_p + r e^{i phi}``; ``v_t = v_p + i w e``, ``a_t = a_p + (i alpha - w^2) e``."""

    driver: int
    link: str
    pivot: int
    toward: int

    def writes(self) -> tuple[int, ...]:
        return (self.toward,)

    def numbers(self, src: Source) -> Nums:
        return (np.abs(src.shape(self.link, self.toward) - src.shape(self.link, self.pivot)),)

    def place(self, k: Kin, nums: Nums) -> None:
        zt = k.z[self.toward]
        e = cis(k.q[self.driver])  # e^{i phi} once per sample, not per design
        np.multiply(e, nums[0] + 0j, out=zt)  # the radius made complex once per design: one complex product
        zt += k.z[self.pivot]

    def rates(self, r: Rate, nums: Nums) -> None:
        e = r.z[self.toward] - r.z[self.pivot]
        w, al = r.w_in[self.driver], r.a_in[self.driver]
        r.v[self.toward] = r.v[self.pivot] + 1j * w * e
        r.a[self.toward] = r.a[self.pivot] + (1j * al - w * w) * e
        r.om[self.link], r.al[self.link] = w, al

    def describe(self, names: tuple[str, ...], nums: Nums | None) -> str | None:
        radius = f" (r = {_num(nums[0])})" if nums else ""
        return f"driver '{self.link}': {names[self.toward]} from {names[self.pivot]} at the input angle{radius}"


@dataclass(frozen=True)
class Place(Step):
    """A link with two known joints: ``z_j = z_k1 + rho_j (z_k2 - z_k1)`` (seed 000, eq. 18, complex).

    ``rho_j = (s_j - s_k1) / (s_k2 - s_k1)`` from the shape; the mirror image uses
    ``conj(rho_j)``.  Linear in the positions, so velocities and accelerations obey it too.
    """

    link: str
    k1: int
    k2: int
    joints: tuple[int, ...]
    mirror: int | None = None  # index into the mirror flags, for links of 3+ joints
    keep_rotation: bool = False  # a later step needs this link's rotation (and rates)

    def numbers(self, src: Source) -> Nums:
        s1 = src.shape(self.link, self.k1)
        base = src.shape(self.link, self.k2) - s1
        with np.errstate(divide="ignore", invalid="ignore"):
            ratios = tuple((src.shape(self.link, j) - s1) / base for j in self.joints)
        return base, ratios

    def _rho(self, mirrors: np.ndarray, ratio: Any) -> Any:
        if self.mirror is None:
            return ratio
        return np.where(mirrors[self.mirror], np.conj(ratio), ratio)

    def place(self, k: Kin, nums: Nums) -> None:
        scale, ratios = nums
        z1, z2 = k.z[self.k1], k.z[self.k2]
        if self.keep_rotation:
            k.rot[self.link] = (z2 - z1) / scale
        for j, ratio in zip(self.joints, ratios, strict=True):
            zj = k.z[j]  # z_k1 + rho (z_k2 - z_k1), written in place (no temporaries of the batch's size)
            np.subtract(z2, z1, out=zj)
            zj *= self._rho(k.mirrors, ratio)
            zj += z1

    def rates(self, r: Rate, nums: Nums) -> None:
        v, a = r.v, r.a
        for j, ratio in zip(self.joints, nums[1], strict=True):
            rho = self._rho(r.mirrors, ratio)
            v[j] = v[self.k1] + rho * (v[self.k2] - v[self.k1])
            a[j] = a[self.k1] + rho * (a[self.k2] - a[self.k1])
        if self.keep_rotation and self.link not in r.om:
            r.om[self.link], r.al[self.link] = link_rates(
                r.z[self.k2] - r.z[self.k1], v[self.k2] - v[self.k1], a[self.k2] - a[self.k1]
            )

    def describe(self, names: tuple[str, ...], nums: Nums | None) -> str | None:
        if not self.joints:
            return None
        m = " (mirror image selectable)" if self.mirror is not None else ""
        placed = ", ".join(names[j] for j in self.joints)
        return f"link '{self.link}': {placed} placed rigidly on {names[self.k1]}, {names[self.k2]}{m}"


@dataclass(frozen=True)
class Dyad(Step):
    """A joint of two links that each have one known joint: two circles (seed 000, eqs. 11-15).

    Rates: ``p . (v_j - v_k1) = 0`` and ``q . (v_j - v_k2) = 0`` with ``p = z_j - z_k1``,
    ``q = z_j - z_k2``, by Cramer's rule ``v_j = i (c2 p - c1 q) / cross(p, q)``; the
    accelerations solve the same system with the centripetal terms ``(w r)^2`` moved over.
    """

    joint: int
    k1: int
    k2: int
    links: tuple[str, str]
    sign: int  # index into the sign vector

    def numbers(self, src: Source) -> Nums:
        l1, l2 = self.links
        r1 = np.abs(src.shape(l1, self.joint) - src.shape(l1, self.k1))
        r2 = np.abs(src.shape(l2, self.joint) - src.shape(l2, self.k2))
        return r1, r2

    def place(self, k: Kin, nums: Nums) -> None:
        z, sign = k.z, k.signs[self.sign]
        circle_circle(z[self.k1], z[self.k2], nums[0], nums[1], sign, k.eps, z[self.joint], k.margin[self.sign])

    def pose_sign(self, zpose: np.ndarray, nums: Nums) -> np.ndarray:
        return side(zpose[self.k1], zpose[self.k2], zpose[self.joint])

    def rates(self, r: Rate, nums: Nums) -> None:
        r1, r2 = nums
        z, v, a = r.z, r.v, r.a
        p = z[self.joint] - z[self.k1]
        q = z[self.joint] - z[self.k2]
        pc, qc = np.conj(p), np.conj(q)
        det = (pc * q).imag
        inv = 1.0 / det
        r.cond[self.sign] = det / (r1 * r2)
        c1 = (pc * v[self.k1]).real
        c2 = (qc * v[self.k2]).real
        vj = (c2 * p - c1 * q) * (1j * inv)
        # the two links turn at w1 = cross(p, vj - v_k1) / r1^2 (w2 likewise), and
        # |vj - v_k1|^2 = (w1 r1)^2 is the centripetal term of the acceleration
        w1 = (pc * (vj - v[self.k1])).imag / (r1 * r1)
        w2 = (qc * (vj - v[self.k2])).imag / (r2 * r2)
        c1 = (pc * a[self.k1]).real - (w1 * r1) ** 2
        c2 = (qc * a[self.k2]).real - (w2 * r2) ** 2
        aj = (c2 * p - c1 * q) * (1j * inv)
        v[self.joint], a[self.joint] = vj, aj
        for link, w, rr, kk, rc in ((self.links[0], w1, r1, self.k1, pc), (self.links[1], w2, r2, self.k2, qc)):
            if link not in r.om:
                r.om[link], r.al[link] = w, (rc * (aj - a[kk])).imag / (rr * rr)

    def describe(self, names: tuple[str, ...], nums: Nums | None) -> str | None:
        r1, r2 = (f", {_num(x)}" for x in nums) if nums else ("", "")
        n = names
        return (
            f"{n[self.joint]} = circle({n[self.k1]}{r1}) x circle({n[self.k2]}{r2}); "
            f"sign +1: left of {n[self.k1]}->{n[self.k2]}"
        )


def _line_frame(on_anchor: int | None, k_z: np.ndarray, rot: dict[str, Any], on: str, anchor_s: Any) -> tuple[Any, Any]:
    """Map from the guide link's shape frame to the world: ``p -> origin + turn * p``."""
    if on_anchor is None:
        return 0j, 1.0 + 0j
    turn = rot[on]
    return k_z[on_anchor] - turn * anchor_s, turn


@dataclass(frozen=True)
class CircleLine(Step):
    """A joint on a slider block's line and on a link with one known joint: circle and line.

    The line is ``z = A + u E`` (``A``, ``E`` carried by the guide ``on``); with
    ``w = conj(E)(z_c - A)``, ``u = Re w + t sqrt(r^2 - (Im w)^2)``: ``t = +1`` puts the joint
    ahead of the circle's centre along the slider direction.
    """

    joint: int
    center: int
    link: str  # the link through `center` and `joint`
    slider: int
    block: str
    on: str
    anchor: int | None  # a known joint of `on` (None: `on` is the ground)
    sign: int  # index into the sign vector

    def numbers(self, src: Source) -> Nums:
        radius = np.abs(src.shape(self.link, self.joint) - src.shape(self.link, self.center))
        anchor_s = src.shape(self.on, self.anchor) if self.anchor is not None else 0j
        return radius, src.pose(self.joint), src.direction(self.slider), anchor_s

    def rotation_needs(self) -> tuple[str, ...]:
        return (self.on,)

    def place(self, k: Kin, nums: Nums) -> None:
        radius, point, direction, anchor_s = nums
        origin, turn = _line_frame(self.anchor, k.z, k.rot, self.on, anchor_s)
        a = origin + turn * point
        e = turn * direction
        w = (k.z[self.center] - a) * np.conj(e)  # the centre in line coordinates: (along, offset)
        disc = radius**2 - w.imag**2
        m = (radius * (1 + k.eps) - np.abs(w.imag)) / radius
        u = w.real + k.signs[self.sign] * np.sqrt(np.maximum(disc, 0.0))
        k.z[self.joint] = np.where(m >= 0, a + u * e, NAN_POINT)
        k.margin[self.sign] = m

    def pose_sign(self, zpose: np.ndarray, nums: Nums) -> np.ndarray:
        return np.where(dot(nums[2], zpose[self.joint] - zpose[self.center]) >= 0, 1.0, -1.0)

    def rates(self, r: Rate, nums: Nums) -> None:
        # z_j = A + u E with A, E carried by `on`; the circle gives p . (v_j - v_c) = 0:
        # du (p . E) = p . (v_c - v_A - u v_E), d2u (p . E) = p . (a_c - a_A - u a_E - 2 du v_E) - |v_j - v_c|^2
        radius, point, direction, anchor_s = nums
        z, v, a = r.z, r.v, r.a
        w, alpha, va, aa, za = r.frame(self.on, self.anchor)
        turn = r.rot[self.on] if self.anchor is not None else 1.0
        z_a = (z[self.anchor] - turn * anchor_s if self.anchor is not None else 0.0) + turn * point
        e = turn * direction
        u = dot(e, z[self.joint] - z_a)
        v_a = va + 1j * w * (z_a - za)
        a_a = aa + (1j * alpha - w * w) * (z_a - za)
        v_e, a_e = 1j * w * e, (1j * alpha - w * w) * e
        p = z[self.joint] - z[self.center]
        pe = dot(p, e)
        r.cond[self.sign] = pe / radius
        du = dot(p, v[self.center] - v_a - u * v_e) / pe
        v[self.joint] = v_a + u * v_e + du * e
        dv = v[self.joint] - v[self.center]
        ddu = (dot(p, a[self.center] - a_a - u * a_e - 2 * du * v_e) - np.abs(dv) ** 2) / pe
        a[self.joint] = a_a + u * a_e + 2 * du * v_e + ddu * e

    def describe(self, names: tuple[str, ...], nums: Nums | None) -> str | None:
        n = names
        radius = f", {_num(nums[0])}" if nums else ""
        return (
            f"{n[self.joint]} = circle({n[self.center]}{radius}) x line of slider {self.slider} "
            f"('{self.block}' on '{self.on}'); sign +1: {n[self.joint]} ahead of {n[self.center]} along the slider"
        )


@dataclass(frozen=True)
class Pivot(Step):
    """The guide a block slides on turns about its one known joint until its line passes the block's joint.

    With the line offset ``o = pose(J) - s_Q`` and direction ``d``:
    ``u = -Re(conj(d) o) + t sqrt(|J - Q|^2 - Im(conj(d) o)^2)``, rotation ``(J - Q)/(o + u d)``.
    """

    slider: int
    on: str
    center: int  # the known joint of `on` it turns about
    joint: int  # the known joint of the block
    sign: int  # index into the sign vector

    def numbers(self, src: Source) -> Nums:
        return src.pose(self.joint) - src.shape(self.on, self.center), src.direction(self.slider)

    def place(self, k: Kin, nums: Nums) -> None:
        offset, direction = nums
        w = k.z[self.joint] - k.z[self.center]
        od = offset * np.conj(direction)
        along, off = od.real, od.imag
        aw = np.abs(w)
        m = (aw - np.abs(off) * (1 - k.eps)) / np.maximum(np.maximum(aw, np.abs(off)), _TINY)
        u = -along + k.signs[self.sign] * np.sqrt(np.maximum(aw * aw - off * off, 0.0))
        with np.errstate(divide="ignore", invalid="ignore"):
            turn = w / (offset + u * direction)
        k.rot[self.on] = np.where(m >= 0, turn, NAN_POINT)
        k.margin[self.sign] = m

    def writes(self) -> tuple[int, ...]:
        return ()  # it turns a guide; its `joint` is the block joint it passes through, already placed

    def pose_sign(self, zpose: np.ndarray, nums: Nums) -> np.ndarray:
        # at the pose the rotation is 1, so u = 0 and t = sign(Re(conj(d) (J - Q)))
        return np.where(dot(nums[1], zpose[self.joint] - zpose[self.center]) >= 0, 1.0, -1.0)

    def rates(self, r: Rate, nums: Nums) -> None:
        # z_J - z_Q = g = rot (offset + u d): v_J - v_Q = i w g + du E with E = rot d
        g = r.z[self.joint] - r.z[self.center]
        e = r.rot[self.on] * nums[1]
        wg = np.conj(e) * g
        r.cond[self.sign] = np.real(wg) / np.abs(g)
        dv = np.conj(e) * (r.v[self.joint] - r.v[self.center])
        w = np.imag(dv) / np.real(wg)
        du = np.real(dv) + w * np.imag(wg)
        da = np.conj(e) * (r.a[self.joint] - r.a[self.center] + w * w * g - 2j * w * du * e)
        r.om[self.on], r.al[self.on] = w, np.imag(da) / np.real(wg)

    def describe(self, names: tuple[str, ...], nums: Nums | None) -> str | None:
        n = names
        return (
            f"link '{self.on}' turns about {n[self.center]} until slider {self.slider}'s line passes "
            f"{n[self.joint]}; sign +1: {n[self.joint]} ahead of {n[self.center]} along the slider"
        )


@dataclass(frozen=True)
class SliderDrive(Step):
    """A driven slider block, displaced by the input along its line (carried by the guide ``on``)."""

    driver: int
    slider: int
    block: str
    on: str
    anchor: int | None
    joints: tuple[int, ...]

    def numbers(self, src: Source) -> Nums:
        anchor_s = src.shape(self.on, self.anchor) if self.anchor is not None else 0j
        lo, hi = src.stroke(self.driver)
        return anchor_s, src.direction(self.slider), tuple(src.pose(j) for j in self.joints), lo, hi

    def rotation_needs(self) -> tuple[str, ...]:
        return (self.on,)

    def place(self, k: Kin, nums: Nums) -> None:
        anchor_s, direction, points, lo, hi = nums
        origin, turn = _line_frame(self.anchor, k.z, k.rot, self.on, anchor_s)
        k.rot[self.block] = np.broadcast_to(turn, k.z.shape[1:])
        u = k.q[self.driver]
        slack = k.eps * np.maximum(np.abs(lo), np.abs(hi))  # no stroke: lo - slack = -inf, hi + slack = inf
        u = np.where((u < lo - slack) | (u > hi + slack), np.nan, u)  # beyond its stroke: NaN (positions flags it)
        for j, p in zip(self.joints, points, strict=True):
            k.z[j] = origin + turn * (p + u * direction)

    def rates(self, r: Rate, nums: Nums) -> None:
        anchor_s, direction = nums[:2]
        w, alpha, va, aa, za = r.frame(self.on, self.anchor)
        turn = r.rot[self.on] if self.anchor is not None else 1.0
        e = turn * direction
        du, ddu = r.w_in[self.driver], r.a_in[self.driver]
        r.om[self.block], r.al[self.block] = w, alpha
        for j in self.joints:
            rr = r.z[j] - za
            r.v[j] = va + 1j * w * rr + du * e
            r.a[j] = aa + (1j * alpha - w * w) * rr + 2j * w * du * e + ddu * e

    def describe(self, names: tuple[str, ...], nums: Nums | None) -> str | None:
        return f"driver '{self.block}': slider {self.slider} displaced along its line"


@dataclass(frozen=True)
class Carry(Step):
    """A link with one known joint whose rotation is known (a block turns with its guide).

    Rigid motion with another link's rotation: ``v = v_0 + i w (z - z_0)``, ``a = a_0 + (i alpha - w^2)(z - z_0)``.
    """

    link: str
    rot_of: str  # the link whose rotation this link shares
    anchor: int
    joints: tuple[int, ...]

    def numbers(self, src: Source) -> Nums:
        s0 = src.shape(self.link, self.anchor)
        return (tuple(src.shape(self.link, j) - s0 for j in self.joints),)

    def rotation_needs(self) -> tuple[str, ...]:
        return (self.rot_of,)

    def place(self, k: Kin, nums: Nums) -> None:
        turn = k.rot[self.rot_of]
        k.rot[self.link] = turn
        for j, off in zip(self.joints, nums[0], strict=True):
            k.z[j] = k.z[self.anchor] + turn * off

    def rates(self, r: Rate, nums: Nums) -> None:
        w, alpha = r.om[self.rot_of], r.al[self.rot_of]
        r.om[self.link], r.al[self.link] = w, alpha
        for j in self.joints:
            rr = r.z[j] - r.z[self.anchor]
            r.v[j] = r.v[self.anchor] + 1j * w * rr
            r.a[j] = r.a[self.anchor] + (1j * alpha - w * w) * rr

    def describe(self, names: tuple[str, ...], nums: Nums | None) -> str | None:
        if not self.joints:
            return None
        moved = ", ".join(names[j] for j in self.joints)
        return f"link '{self.link}': {moved} carried with '{self.rot_of}' from {names[self.anchor]}"


def _stroke_margin(s: Any, lo: Any, hi: Any, eps: float) -> Any:
    """How far a cylinder's length ``s`` is inside its stroke ``[lo, hi]``, relative to ``s``; negative outside.

    A length that is not positive is always outside (-1).
    """
    with np.errstate(divide="ignore", invalid="ignore"):
        m = np.minimum(s - lo * (1 - eps), hi * (1 + eps) - s) / s
    return np.where(s > 0, m, -1.0)


@dataclass(frozen=True)
class CylinderDyad(Step):
    """A joint at the free end of a cylinder and on a link with one known joint: two circles, one of radius ``s(t)``.

    The cylinder runs from the known joint ``k2`` to ``joint`` and is ``s`` long (the driver's
    input); ``link`` carries ``joint`` and the known joint ``k1`` at the constant distance
    ``r1``.  Positions as :class:`Dyad` with ``r2 = s``; ``t = +1`` puts ``joint`` left of
    ``k1 -> k2``.  Rates: ``p . (v_j - v_k1) = 0`` and ``q . (v_j - v_k2) = s ds`` with
    ``p = z_j - z_k1``, ``q = z_j - z_k2``; then
    ``p . (a_j - a_k1) = -|v_j - v_k1|^2`` and ``q . (a_j - a_k2) = ds^2 + s dds - |v_j - v_k2|^2``.
    """

    joint: int
    k1: int
    k2: int
    link: str
    driver: int
    sign: int  # index into the sign vector

    def numbers(self, src: Source) -> Nums:
        r1 = np.abs(src.shape(self.link, self.joint) - src.shape(self.link, self.k1))
        lo, hi = src.stroke(self.driver)
        return r1, lo, hi

    def place(self, k: Kin, nums: Nums) -> None:
        r1, lo, hi = nums
        s = k.q[self.driver]
        with np.errstate(invalid="ignore"):
            _, m = circle_circle(k.z[self.k1], k.z[self.k2], r1, s, k.signs[self.sign], k.eps, out=k.z[self.joint])
        m = np.minimum(m, _stroke_margin(s, lo, hi, k.eps))
        k.margin[self.sign] = m
        k.z[self.joint] = np.where(m >= 0, k.z[self.joint], NAN_POINT)

    def pose_sign(self, zpose: np.ndarray, nums: Nums) -> np.ndarray:
        return side(zpose[self.k1], zpose[self.k2], zpose[self.joint])

    def rates(self, r: Rate, nums: Nums) -> None:
        r1 = nums[0]
        z, v, a = r.z, r.v, r.a
        p = z[self.joint] - z[self.k1]
        q = z[self.joint] - z[self.k2]
        s = np.abs(q)
        ds, dds = r.w_in[self.driver], r.a_in[self.driver]
        pc, qc = np.conj(p), np.conj(q)
        det = (pc * q).imag
        inv = 1.0 / det
        r.cond[self.sign] = det / (r1 * s)
        c1 = (pc * v[self.k1]).real
        c2 = (qc * v[self.k2]).real + s * ds
        vj = (c2 * p - c1 * q) * (1j * inv)
        w1 = (pc * (vj - v[self.k1])).imag / (r1 * r1)
        c1 = (pc * a[self.k1]).real - (w1 * r1) ** 2
        c2 = (qc * a[self.k2]).real - np.abs(vj - v[self.k2]) ** 2 + ds * ds + s * dds
        aj = (c2 * p - c1 * q) * (1j * inv)
        v[self.joint], a[self.joint] = vj, aj
        if self.link not in r.om:
            r.om[self.link], r.al[self.link] = w1, (pc * (aj - a[self.k1])).imag / (r1 * r1)

    def describe(self, names: tuple[str, ...], nums: Nums | None) -> str | None:
        n = names
        r1 = f", {_num(nums[0])}" if nums else ""
        return (
            f"{n[self.joint]} = circle({n[self.k1]}{r1}) x circle({n[self.k2]}, cylinder length); "
            f"sign +1: left of {n[self.k1]}->{n[self.k2]}"
        )


@dataclass(frozen=True)
class CylinderLine(Step):
    """A joint at the free end of a cylinder and on a slider block's line: a circle of radius ``s(t)`` and a line.

    As :class:`CircleLine` with the radius the cylinder's length ``s`` about its known end
    ``center``: ``z = A + u E``, ``w = conj(E)(z_c - A)``, ``u = Re w + t sqrt(s^2 - (Im w)^2)``.
    Rates: ``du (p . E) = p . (v_c - v_A - u v_E) + s ds`` and
    ``d2u (p . E) = p . (a_c - a_A - u a_E - 2 du v_E) - |v_j - v_c|^2 + ds^2 + s dds``.
    """

    joint: int
    center: int  # the cylinder's known end
    slider: int
    block: str
    on: str
    anchor: int | None  # a known joint of `on` (None: `on` is the ground)
    driver: int
    sign: int  # index into the sign vector

    def numbers(self, src: Source) -> Nums:
        anchor_s = src.shape(self.on, self.anchor) if self.anchor is not None else 0j
        lo, hi = src.stroke(self.driver)
        return src.pose(self.joint), src.direction(self.slider), anchor_s, lo, hi

    def rotation_needs(self) -> tuple[str, ...]:
        return (self.on,)

    def place(self, k: Kin, nums: Nums) -> None:
        point, direction, anchor_s, lo, hi = nums
        s = k.q[self.driver]
        origin, turn = _line_frame(self.anchor, k.z, k.rot, self.on, anchor_s)
        a = origin + turn * point
        e = turn * direction
        w = (k.z[self.center] - a) * np.conj(e)  # the centre in line coordinates: (along, offset)
        with np.errstate(divide="ignore", invalid="ignore"):
            m = (np.abs(s) * (1 + k.eps) - np.abs(w.imag)) / np.abs(s)
        m = np.minimum(m, _stroke_margin(s, lo, hi, k.eps))
        u = w.real + k.signs[self.sign] * np.sqrt(np.maximum(s * s - w.imag**2, 0.0))
        k.z[self.joint] = np.where(m >= 0, a + u * e, NAN_POINT)
        k.margin[self.sign] = m

    def pose_sign(self, zpose: np.ndarray, nums: Nums) -> np.ndarray:
        return np.where(dot(nums[1], zpose[self.joint] - zpose[self.center]) >= 0, 1.0, -1.0)

    def rates(self, r: Rate, nums: Nums) -> None:
        point, direction, anchor_s, _, _ = nums
        z, v, a = r.z, r.v, r.a
        w, alpha, va, aa, za = r.frame(self.on, self.anchor)
        turn = r.rot[self.on] if self.anchor is not None else 1.0
        z_a = (z[self.anchor] - turn * anchor_s if self.anchor is not None else 0.0) + turn * point
        e = turn * direction
        u = dot(e, z[self.joint] - z_a)
        v_a = va + 1j * w * (z_a - za)
        a_a = aa + (1j * alpha - w * w) * (z_a - za)
        v_e, a_e = 1j * w * e, (1j * alpha - w * w) * e
        p = z[self.joint] - z[self.center]
        s = np.abs(p)
        ds, dds = r.w_in[self.driver], r.a_in[self.driver]
        pe = dot(p, e)
        r.cond[self.sign] = pe / s
        du = (dot(p, v[self.center] - v_a - u * v_e) + s * ds) / pe
        v[self.joint] = v_a + u * v_e + du * e
        dv = v[self.joint] - v[self.center]
        ddu = (dot(p, a[self.center] - a_a - u * a_e - 2 * du * v_e) - np.abs(dv) ** 2 + ds * ds + s * dds) / pe
        a[self.joint] = a_a + u * a_e + 2 * du * v_e + ddu * e

    def describe(self, names: tuple[str, ...], nums: Nums | None) -> str | None:
        n = names
        return (
            f"{n[self.joint]} = circle({n[self.center]}, cylinder length) x line of slider {self.slider} "
            f"('{self.block}' on '{self.on}'); sign +1: {n[self.joint]} ahead of {n[self.center]} along the slider"
        )


def _travel_margin(u: Any, lo: Any, hi: Any, s: Any, eps: float) -> Any:
    """How far a slider's displacement ``u`` is inside its stroke ``[lo, hi]``, relative to the length ``s``."""
    with np.errstate(divide="ignore", invalid="ignore"):
        m = np.minimum(u - lo, hi - u) / s + eps
    return np.where(s > 0, m, -1.0)


@dataclass(frozen=True)
class ActuatorDyad(Step):
    """A slider driver between two moving links: a cylinder written as a barrel, a rod and a slider.

    The rod (slider ``slider``'s block) slides on the barrel (its guide ``barrel``) and keeps
    its direction; the barrel carries its pin ``P`` and the line, the rod its pin ``Q``.  In the
    barrel's frame ``Q - P = rel(u) = rel0 + u d`` (``rel0`` from the pose, ``d`` the slide's
    unit direction, ``u`` the driver's displacement), so the pins are ``s(u) = |rel(u)|`` apart:
    one pin (``k2``) is known, the other (``joint``) is on ``link`` with the known joint ``k1``,
    and it is placed as :class:`CylinderDyad`'s free end with radius ``s(u)`` (the same sign);
    the barrel then turns by ``(z_Q - z_P) / rel(u)``.  With the line through both pins,
    ``s = s0 + u``: the cylinder driver ``[P, Q]`` of length ``s0 + u``.

    Rates: as :class:`CylinderDyad` with ``s ds = (rel . d) du`` and ``ds^2 + s dds = du^2 +
    (rel . d) ddu``; the barrel's ``w = Im((D' - du E) / D)`` and ``alpha = Im((D'' - ddu E) / D
    - (D' / D)^2 + (du E / D)^2)`` with ``D = z_Q - z_P`` and ``E`` the slide direction now.
    """

    joint: int
    k1: int
    k2: int
    link: str  # the body through `joint` and `k1`
    driver: int
    slider: int
    barrel: str  # the slider's guide, carrying pin `pin_p`
    pin_p: int
    pin_q: int  # on the rod (the slider's block)
    sign: int  # index into the sign vector

    def numbers(self, src: Source) -> Nums:
        r1 = np.abs(src.shape(self.link, self.joint) - src.shape(self.link, self.k1))
        rel0 = src.pose(self.pin_q) - src.shape(self.barrel, self.pin_p)
        lo, hi = src.stroke(self.driver)
        return r1, rel0, src.direction(self.slider), lo, hi

    def place(self, k: Kin, nums: Nums) -> None:
        r1, rel0, direction, lo, hi = nums
        u = k.q[self.driver]
        rel = rel0 + u * direction
        s = np.abs(rel)
        with np.errstate(invalid="ignore"):
            _, m = circle_circle(k.z[self.k1], k.z[self.k2], r1, s, k.signs[self.sign], k.eps, out=k.z[self.joint])
        m = np.minimum(m, _travel_margin(u, lo, hi, s, k.eps))
        k.margin[self.sign] = m
        k.z[self.joint] = np.where(m >= 0, k.z[self.joint], NAN_POINT)
        k.rot[self.barrel] = (k.z[self.pin_q] - k.z[self.pin_p]) / rel

    def pose_sign(self, zpose: np.ndarray, nums: Nums) -> np.ndarray:
        return side(zpose[self.k1], zpose[self.k2], zpose[self.joint])

    def rates(self, r: Rate, nums: Nums) -> None:
        r1, direction = nums[0], nums[2]
        z, v, a = r.z, r.v, r.a
        e = r.rot[self.barrel] * direction
        du, ddu = r.w_in[self.driver], r.a_in[self.driver]
        p = z[self.joint] - z[self.k1]
        q = z[self.joint] - z[self.k2]
        pc, qc = np.conj(p), np.conj(q)
        det = (pc * q).imag
        inv = 1.0 / det
        r.cond[self.sign] = det / (r1 * np.abs(q))
        along = dot(z[self.pin_q] - z[self.pin_p], e)  # rel . d, turned with the barrel
        c1 = (pc * v[self.k1]).real
        c2 = (qc * v[self.k2]).real + along * du
        vj = (c2 * p - c1 * q) * (1j * inv)
        w1 = (pc * (vj - v[self.k1])).imag / (r1 * r1)
        c1 = (pc * a[self.k1]).real - (w1 * r1) ** 2
        c2 = (qc * a[self.k2]).real - np.abs(vj - v[self.k2]) ** 2 + du * du + along * ddu
        aj = (c2 * p - c1 * q) * (1j * inv)
        v[self.joint], a[self.joint] = vj, aj
        if self.link not in r.om:
            r.om[self.link], r.al[self.link] = w1, (pc * (aj - a[self.k1])).imag / (r1 * r1)
        d0 = z[self.pin_q] - z[self.pin_p]
        d1, d2 = v[self.pin_q] - v[self.pin_p], a[self.pin_q] - a[self.pin_p]
        r.om[self.barrel] = np.imag((d1 - du * e) / d0)
        r.al[self.barrel] = np.imag((d2 - ddu * e) / d0 - (d1 / d0) ** 2 + (du * e / d0) ** 2)

    def describe(self, names: tuple[str, ...], nums: Nums | None) -> str | None:
        n = names
        r1 = f", {_num(nums[0])}" if nums else ""
        return (
            f"{n[self.joint]} = circle({n[self.k1]}{r1}) x circle({n[self.k2]}, actuator length of slider "
            f"{self.slider} on '{self.barrel}'); sign +1: left of {n[self.k1]}->{n[self.k2]}"
        )


@dataclass(frozen=True)
class LineLine(Step):
    """A slider block (``yoke``) translating on its guide ``on``, fixed by a block that slides in it: two lines.

    The yoke turns with ``on`` and is displaced by an unknown ``u1`` along ``d1`` (slider
    ``slider1``); a block slides in the yoke along ``d2`` (slider ``slider2``, carried by the
    yoke) and carries the known joint ``pin``.  In the frame of ``on`` (``p -> O + turn p``),
    ``(z_pin - O) / turn - pose(pin) = u1 d1 + u2 d2``: a 2x2 linear system, unique unless the
    lines are parallel (the plan refuses that), ``u1 = cross(w, d2) / cross(d1, d2)``.  The
    yoke's joints are then ``O + turn (pose(j) + u1 d1)`` (a Scotch yoke: ``x = r cos(theta)``).
    Rates: ``du1 E1 + du2 E2 = v_pin - v_O' - i w (z_pin - z_O')`` (``E = turn d``, ``O'`` the
    anchor of ``on``) and ``dd u1 E1 + dd u2 E2 = a_pin - a_O' - (i alpha - w^2)(z_pin - z_O')
    - 2 i w (du1 E1 + du2 E2)``.
    """

    yoke: str
    on: str
    anchor: int | None  # a known joint of `on` (None: `on` is the ground)
    slider1: int  # the yoke on `on`
    slider2: int  # the block on the yoke
    pin: int  # the block's known joint
    joints: tuple[int, ...]  # the yoke's joints

    def numbers(self, src: Source) -> Nums:
        anchor_s = src.shape(self.on, self.anchor) if self.anchor is not None else 0j
        return (
            anchor_s,
            src.direction(self.slider1),
            src.direction(self.slider2),
            src.pose(self.pin),
            tuple(src.pose(j) for j in self.joints),
        )

    def rotation_needs(self) -> tuple[str, ...]:
        return (self.on,)

    def writes(self) -> tuple[int, ...]:
        return self.joints

    def place(self, k: Kin, nums: Nums) -> None:
        anchor_s, d1, d2, pin, points = nums
        origin, turn = _line_frame(self.anchor, k.z, k.rot, self.on, anchor_s)
        w = (k.z[self.pin] - origin) / turn - pin  # = u1 d1 + u2 d2 in the frame of `on`
        with np.errstate(divide="ignore", invalid="ignore"):
            u1 = cross(w, d2) / cross(d1, d2)
        k.rot[self.yoke] = np.broadcast_to(turn, k.z.shape[1:])
        for j, p in zip(self.joints, points, strict=True):
            k.z[j] = origin + turn * (p + u1 * d1)

    def rates(self, r: Rate, nums: Nums) -> None:
        _, d1, d2, _, _ = nums
        w, alpha, va, aa, za = r.frame(self.on, self.anchor)
        turn = r.rot[self.on] if self.anchor is not None else 1.0
        e1, e2 = turn * d1, turn * d2
        det = cross(e1, e2)
        rr = r.z[self.pin] - za
        rel_v = r.v[self.pin] - va - 1j * w * rr  # du1 e1 + du2 e2
        du1 = cross(rel_v, e2) / det
        rel_a = r.a[self.pin] - aa - (1j * alpha - w * w) * rr - 2j * w * rel_v  # ddu1 e1 + ddu2 e2
        ddu1 = cross(rel_a, e2) / det
        r.om[self.yoke], r.al[self.yoke] = w, alpha
        for j in self.joints:
            rj = r.z[j] - za
            r.v[j] = va + 1j * w * rj + du1 * e1
            r.a[j] = aa + (1j * alpha - w * w) * rj + 2j * w * du1 * e1 + ddu1 * e1

    def describe(self, names: tuple[str, ...], nums: Nums | None) -> str | None:
        placed = ", ".join(names[j] for j in self.joints)
        return (
            f"link '{self.yoke}': {placed} slid along slider {self.slider1} until the line of slider "
            f"{self.slider2} passes {names[self.pin]} (two lines)"
        )


SIGN_STEPS = (Dyad, CircleLine, Pivot, CylinderDyad, CylinderLine, ActuatorDyad)


def is_sign_step(step: Step) -> bool:
    """Does this step choose between two solutions (circle-circle, circle-line or pivot, a cylinder's too)?"""
    return isinstance(step, SIGN_STEPS)


__all__ = [
    "ActuatorDyad",
    "Carry",
    "CircleLine",
    "Crank",
    "CylinderDyad",
    "CylinderLine",
    "Dyad",
    "Ground",
    "Kin",
    "LineLine",
    "Pivot",
    "Place",
    "Rate",
    "SliderDrive",
    "Source",
    "Step",
    "is_sign_step",
]
