"""Kinetostatics: joint reactions and driver torques by the Newton-Euler equations of every link.

For every moving link ``b`` (mass ``m``, centre of gravity ``G``, inertia ``I_G``) and every
sample, with ``Q`` the link's reference point (``G`` when the link has a ``cg``, else its
first joint)::

    sum F_on_b + m g + sum F_ext          = m a_G
    sum (r - Q) x F_on_b + sum tau + (G - Q) x m g + sum (r_ext - Q) x F_ext + tau_ext
                                          = I_G alpha + (G - Q) x m a_G

The unknowns, written once each and entering two links with opposite signs (each a small
type that knows its columns, its entries in the matrix and its load on the frame:
:class:`PinForce`, :class:`SliderReaction`, :class:`DriverEffort`, listed by :func:`unknowns`):

* a revolute joint shared by links ``c`` (the first of them in the file) and ``o``: the
  force ``F`` by ``c`` on ``o`` at the joint (2 unknowns).  A joint of k links gives k - 1
  such pairs, all with the first link: the pin is part of that link.
* a slider (block on a guide): the normal force ``N`` (along ``i E``, ``E`` the slide
  direction now) at its ``through`` joint and the moment ``M`` of the guide on the block
  (2 unknowns; frictionless, so nothing along ``E``).
* a revolute driver: the torque ``T`` on its link, the frame taking ``-T`` (1 unknown); a
  slider driver: the force along ``E`` on the block, the guide taking its opposite; a
  cylinder (a massless two-force member): its force ``F`` along its axis, ``+F u`` on the
  link of its first end and ``-F u`` on that of its second (``u`` the unit vector from the
  second end to the first), so ``F > 0`` pushes its ends apart.  At a joint of several
  links it acts on the first of them, the pin's carrier.

With as many drivers as degrees of freedom this gives a square system of ``3 (n_links - 1)``
equations: seed 001's 15x15 system for a Stephenson six-bar is the special case (see
``docs/seed-errata.md`` for its corrections).  All samples are solved at once with
:func:`numpy.linalg.solve` on stacked matrices (in chunks, to bound memory).  Lengths are
converted to metres here, once; forces are in N, torques in N*m, inertia in kg*m^2.
Samples that do not assemble or sit at a singular position have NaN forces.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar, assert_never

import numpy as np

from .catalogue import ReactionKey
from .errors import UnknownNameError, shorten
from .geometry import cross
from .model import CrankType, CylinderType, SliderType
from .params import Body, LoadParams
from .rates import LinkMotion
from .units import UnitKind

if TYPE_CHECKING:
    from .model import Driver, Mechanism

#: samples per batched solve (bounds the memory of the stacked matrices)
CHUNK = 16384


@dataclass(frozen=True)
class Reaction:
    """The force (N, complex ``fx + i fy``, ground frame) by link ``by`` on link ``on`` at ``joint``.

    For a slider, ``moment`` is the moment (N*m) of the guide ``by`` on the block ``on``, and
    the force acts at the slider's ``through`` joint.
    """

    joint: str
    on: str
    by: str
    force: np.ndarray
    moment: np.ndarray | None = None

    @property
    def magnitude(self) -> np.ndarray:
        """The bearing load ``|F|`` (N)."""
        out: np.ndarray = np.abs(self.force)
        return out


@dataclass(frozen=True)
class Forces:
    """Kinetostatic result over the samples of a sweep (NaN where undefined)."""

    reactions: tuple[Reaction, ...]
    driver_torque: dict[str, np.ndarray]  # N*m, counter-clockwise positive, on the driver's link
    driver_force: dict[str, np.ndarray]  # N: along the slide direction, on the block; a cylinder's push (> 0 extends)
    input_power: np.ndarray  # W: sum of torque * omega and force * slide speed
    shaking_force: np.ndarray  # N, complex: resultant force of the mechanism on the frame
    shaking_moment: np.ndarray  # N*m: its moment about the origin of the file's frame
    residual: np.ndarray  # per sample: max |A x - b| over (max |b| + size * max |x|), size = mechanism size in m
    spring_force: dict[str, np.ndarray] = field(default_factory=dict)  # N, tension (> 0 pulls the ends together)
    spring_length: dict[str, np.ndarray] = field(default_factory=dict)  # file length unit
    damper_force: dict[str, np.ndarray] = field(default_factory=dict)  # N, tension (> 0 pulls the ends together)

    def reaction(self, joint: str, on: str, by: str | None = None) -> np.ndarray:
        """Force on link ``on`` at ``joint`` by link ``by`` (may be left out when only one link acts there)."""
        for what, value in (("joint", joint), ("on", on), ("by", by)):
            if not isinstance(value, str) and not (what == "by" and value is None):
                raise UnknownNameError(f"reaction: {what} must be a name, got {shorten(repr(value))}")
        found = []
        for r in self.reactions:
            if r.joint == joint and r.on == on and by in (None, r.by):
                found.append((r.by, r.force))
            elif r.joint == joint and r.by == on and by in (None, r.on):
                found.append((r.on, -r.force))
        if len(found) == 1:
            return found[0][1]
        what = f"at '{joint}' on '{on}'" + (f" by '{by}'" if by else "")
        if not found:
            raise UnknownNameError(f"no reaction {what}")
        raise UnknownNameError(f"several reactions {what} (by {', '.join(b for b, _ in found)}): name `by`")

    def layout(self) -> tuple[ReactionKey, ...]:
        """The reactions' layout for the output catalogue (:func:`linkagekit.catalogue.build`)."""
        return tuple(ReactionKey(r.joint, r.by, r.on, r.moment is not None) for r in self.reactions)

    def reshape(self, shape: tuple[int, ...]) -> Forces:
        """The same forces with every array reshaped (flat samples back to (designs, samples))."""
        return self.map(lambda a: a.reshape(shape))

    def map(self, f: Callable[[np.ndarray], np.ndarray]) -> Forces:
        """The same forces with ``f`` applied to every array."""
        return Forces(
            tuple(
                Reaction(r.joint, r.on, r.by, f(r.force), None if r.moment is None else f(r.moment))
                for r in self.reactions
            ),
            {k: f(v) for k, v in self.driver_torque.items()},
            {k: f(v) for k, v in self.driver_force.items()},
            f(self.input_power),
            f(self.shaking_force),
            f(self.shaking_moment),
            f(self.residual),
            {k: f(v) for k, v in self.spring_force.items()},
            {k: f(v) for k, v in self.spring_length.items()},
            {k: f(v) for k, v in self.damper_force.items()},
        )

    def arrays(self) -> list[np.ndarray]:
        """Every array, in a fixed order (the same for two Forces of one mechanism)."""
        out: list[np.ndarray] = []
        for r in self.reactions:
            out += [r.force] if r.moment is None else [r.force, r.moment]
        out += list(self.driver_torque.values()) + list(self.driver_force.values())
        out += [self.input_power, self.shaking_force, self.shaking_moment, self.residual]
        return out + [*self.spring_force.values(), *self.spring_length.values(), *self.damper_force.values()]

    def take(self, index: Any) -> Forces:
        """The same forces with every array indexed by ``index`` (one design of a batch)."""
        return self.map(lambda a: a[index])


def json_list(a: Any) -> list[Any]:
    """A 1-D array as a JSON list; NaN becomes ``None`` (``null``); nested for more dimensions."""
    arr = np.asarray(a, float)
    out: list[Any] = arr.tolist()  # Python floats, nested for more dimensions
    bad = ~np.isfinite(arr)
    if bad.any():
        if arr.ndim == 1:
            for i in np.flatnonzero(bad):
                out[i] = None
        else:
            for index in zip(*np.nonzero(bad), strict=True):
                row = out
                for i in index[:-1]:
                    row = row[i]
                row[index[-1]] = None
    return out


# ------------------------------------------------------------------------------- kinematics
def point_motion(mech: Mechanism, link: str, local: np.ndarray, km: Kinematics) -> tuple[np.ndarray, ...]:
    """Position, velocity and acceleration (file units) of a point carried by a link.

    ``local`` is the point's complex ratio to the link's first two joints a, b (a link of
    two or more joints: ``z = z_a + rho (z_b - z_a)``, and likewise ``v``, ``a``, since the
    relation is linear), or, for a one-joint block, its offset from the joint, turned with
    the block: ``r = rot * local``, ``v = v_j + i w r``, ``a = a_j + (i alpha - w^2) r``.
    """
    names = mech.joint_names
    ln = mech.link(link)
    i = names.index(ln.joints[0])
    if len(ln.joints) >= 2:
        k = names.index(ln.joints[1])
        return tuple(f[i] + local * (f[k] - f[i]) for f in (km.z, km.v, km.a))
    rot, w, al = km.motion[link]
    r = rot * local
    return km.z[i] + r, km.v[i] + 1j * w * r, km.a[i] + (1j * al - w * w) * r


@dataclass(frozen=True)
class Kinematics:
    """Flat kinematics the force solve reads: joints (n_joints, N) complex, per-link motion, flags, speeds."""

    z: np.ndarray
    v: np.ndarray
    a: np.ndarray
    motion: dict[str, LinkMotion]
    good: np.ndarray  # (N,) assembled and not singular
    speeds: np.ndarray  # (n_drivers, N)
    bodies: tuple[Body, ...]  # mass properties, arrays (N,)
    loads: tuple[LoadParams, ...]  # external loads, arrays (N,)


# ------------------------------------------------------------------------------- force elements
@dataclass(frozen=True)
class ElementForces:
    """What the springs and dampers do at each sample (arrays (N,), keyed by the element's name).

    ``spring`` and ``damper`` are tensions in N (positive pulls the two joints together);
    ``spring_length`` is each spring's length in the file's length unit.
    """

    spring: dict[str, np.ndarray]
    spring_length: dict[str, np.ndarray]
    damper: dict[str, np.ndarray]

    def pulls(self, mech: Mechanism, z: np.ndarray) -> list[tuple[str, str, np.ndarray]]:
        """``(joint, link, force)``: each element's force (N, complex) on the link carrying each of its ends.

        The tension ``S`` pulls end ``a`` toward ``b``: ``S (z_b - z_a) / |z_b - z_a|`` on ``a``'s
        carrier, the opposite on ``b``'s; the carrier of a joint of several links is the first
        of them (the pin's carrier, as for loads and cylinders).  ``z`` as in :func:`element_forces`.
        """
        names = mech.joint_names
        out: list[tuple[str, str, np.ndarray]] = []
        tensions = [(e.between, self.spring[e.name]) for e in mech.springs]
        tensions += [(e.between, self.damper[e.name]) for e in mech.dampers]
        for (a, b), tension in tensions:
            d = z[names.index(b)] - z[names.index(a)]
            with np.errstate(invalid="ignore", divide="ignore"):
                f = tension * d / np.abs(d)
            out += [(a, mech.links_of(a)[0], f), (b, mech.links_of(b)[0], -f)]
        return out


def element_forces(mech: Mechanism, z: np.ndarray, v: np.ndarray) -> ElementForces:
    """The springs' and dampers' tensions for joint positions ``z`` and velocities ``v``.

    Parameters
    ----------
    mech : Mechanism
    z, v : ndarray, complex, shape (n_joints, N)
        Joint positions (file length unit) and velocities (unit/s), joints in ``mech.joint_names`` order.

    Returns
    -------
    ElementForces
        Spring tension ``k (L - L0)``, damper tension ``c dL/dt`` (N; lengths in metres), with
        ``dL/dt = Re(conj(z_a - z_b) (v_a - v_b)) / L``.

    Examples
    --------
    >>> import numpy as np, linkagekit as lk
    >>> m = lk.load("examples/seed000_fourbar.yaml").to_dict()
    >>> m["units"]  # lengths in cm, converted to metres for the force
    {'length': 'cm', 'angle': 'deg'}
    >>> m["springs"] = [{"between": ["A", "D"], "stiffness": 1000.0, "free_length": 4.0}]
    >>> mech = lk.Mechanism.from_dict(m)
    >>> z = np.array([mech.joints[j] for j in mech.joint_names])[:, None]
    >>> el = element_forces(mech, z, np.zeros_like(z))
    >>> round(float(el.spring_length["A-D"][0]), 4), round(float(el.spring["A-D"][0]), 3)  # 1000 N/m * 0.0092770 m
    (4.9277, 9.277)
    """
    names, si = mech.joint_names, mech.length_to_si
    spring: dict[str, np.ndarray] = {}
    length: dict[str, np.ndarray] = {}
    damper: dict[str, np.ndarray] = {}
    for sp in mech.springs:
        a, b = (names.index(j) for j in sp.between)
        length[sp.name] = np.abs(z[a] - z[b])
        spring[sp.name] = sp.stiffness * (length[sp.name] - sp.free_length) * si
    for dm in mech.dampers:
        a, b = (names.index(j) for j in dm.between)
        d = z[a] - z[b]
        with np.errstate(invalid="ignore", divide="ignore"):
            rate = np.real(np.conj(d) * (v[a] - v[b])) / np.abs(d) * si  # dL/dt, m/s
        damper[dm.name] = dm.damping * rate
    return ElementForces(spring, length, damper)


def spring_energy(mech: Mechanism, z: np.ndarray) -> np.ndarray:
    """The springs' potential energy ``sum 1/2 k (L - L0)^2`` (J, lengths in metres), shape (N,); ``z`` as above."""
    names, si = mech.joint_names, mech.length_to_si
    out = np.zeros(np.shape(z)[1:])
    for sp in mech.springs:
        a, b = (names.index(j) for j in sp.between)
        out = out + 0.5 * sp.stiffness * ((np.abs(z[a] - z[b]) - sp.free_length) * si) ** 2
    return out


def element_generalised_force(mech: Mechanism, z: np.ndarray, v: np.ndarray, jac: np.ndarray) -> np.ndarray:
    """The springs' and dampers' generalised force on one driver coordinate ``q``, by virtual power.

    ``Q = - sum_e S_e dL_e/dq``, ``S_e`` the tension (N) and ``dL_e/dq = Re(conj(u_e) (J_a - J_b))``
    (m per unit of ``q``), ``u_e`` the unit vector from ``b`` to ``a``.  ``jac`` (n_joints, N)
    is the joints' velocity (file unit/s) at a unit speed of the driver (1 rad/s for a crank,
    1 length unit/s for a slider or cylinder), e.g. :func:`linkagekit.analyze` at speed 1.
    So ``Q`` is in N*m/rad for a crank, N*m per length unit for a linear driver (divide by
    ``mech.length_to_si`` for N).  For springs alone ``Q = -dV/dq`` (:func:`spring_energy`).
    """
    names, si = mech.joint_names, mech.length_to_si
    el = element_forces(mech, z, v)
    out = np.zeros(np.shape(z)[1:])
    elements = [(e.between, el.spring[e.name]) for e in mech.springs]
    elements += [(e.between, el.damper[e.name]) for e in mech.dampers]
    for (ja, jb), tension in elements:
        a, b = names.index(ja), names.index(jb)
        d = z[a] - z[b]
        with np.errstate(invalid="ignore", divide="ignore"):
            dl = np.real(np.conj(d) * (jac[a] - jac[b])) / np.abs(d) * si
        out = out - tension * dl
    return out


# ------------------------------------------------------------------------------- the system
@dataclass(frozen=True)
class _Frame:
    """What every column and the right-hand side read: rows, reference points and directions (m, per sample).

    ``row[link]`` is the first of the link's three equations (force x, force y, moment
    about ``Q[link]``); ``slide_dir[k]`` is slider k's direction now (it turns with its
    guide); ``cyl_dir[name]`` is a cylinder's unit vector from its second end to its first.
    """

    mech: Mechanism
    n: int
    row: dict[str, int]
    z: dict[str, np.ndarray]
    Q: dict[str, np.ndarray]
    slide_dir: tuple[np.ndarray, ...]
    cyl_dir: dict[str, np.ndarray]
    elements: ElementForces
    frame_pulls: tuple[tuple[Any, Any], ...]  # the springs' and dampers' loads on the frame (force, moment)


#: one entry of the stacked matrices: (row, column, coefficient: a number or one per sample)
Entry = tuple[int, int, Any]


def _force(fr: _Frame, link: str, col: int, at: np.ndarray, direction: Any, sign: float) -> list[Entry]:
    """Unit-force column ``col``: ``sign * direction`` at point ``at`` (m) on ``link`` (the frame has no rows)."""
    if link == "ground":
        return []
    r0 = fr.row[link]
    d = sign * np.broadcast_to(direction, (fr.n,))
    return [(r0, col, np.real(d)), (r0 + 1, col, np.imag(d)), (r0 + 2, col, cross(at - fr.Q[link], d))]


def _moment(fr: _Frame, link: str, col: int, sign: float) -> list[Entry]:
    """Unit-moment column ``col``: ``sign`` on ``link``'s moment row."""
    return [] if link == "ground" else [(fr.row[link] + 2, col, sign)]


#: a force (N, complex) and a moment about the origin (N*m) on the frame, per sample
Load = tuple[Any, Any]


@dataclass(frozen=True)
class PinForce:
    """The force ``F = x[col] + i x[col + 1]`` by the pin's carrier ``by`` on ``on`` at ``joint``."""

    joint: str
    on: str
    by: str
    col: int
    width: ClassVar[int] = 2

    def entries(self, fr: _Frame) -> list[Entry]:
        zj = fr.z[self.joint]
        out: list[Entry] = []
        for c, e in ((self.col, 1.0), (self.col + 1, 1j)):
            out += _force(fr, self.on, c, zj, e, +1.0) + _force(fr, self.by, c, zj, e, -1.0)
        return out

    def reaction(self, x: np.ndarray, fr: _Frame) -> Reaction:
        return Reaction(self.joint, self.on, self.by, x[:, self.col] + 1j * x[:, self.col + 1])

    def on_frame(self, r: Reaction, fr: _Frame) -> list[Load]:
        """The frame feels ``-F`` if it exerts ``F``, ``+F`` if it receives it."""
        if "ground" not in (self.by, self.on):
            return []
        f = -r.force if self.by == "ground" else r.force
        return [(f, cross(fr.z[self.joint], f))]


@dataclass(frozen=True)
class SliderReaction:
    """Slider ``k``'s normal force ``x[col]`` (along ``i E``) at ``joint`` and moment ``x[col + 1]``, guide on block."""

    k: int
    joint: str
    block: str
    guide: str
    col: int
    width: ClassVar[int] = 2

    def entries(self, fr: _Frame) -> list[Entry]:
        zt, n_dir = fr.z[self.joint], 1j * fr.slide_dir[self.k]
        out = _force(fr, self.block, self.col, zt, n_dir, +1.0) + _force(fr, self.guide, self.col, zt, n_dir, -1.0)
        return out + _moment(fr, self.block, self.col + 1, 1.0) + _moment(fr, self.guide, self.col + 1, -1.0)

    def reaction(self, x: np.ndarray, fr: _Frame) -> Reaction:
        f = x[:, self.col] * (1j * fr.slide_dir[self.k])
        return Reaction(self.joint, self.block, self.guide, f, x[:, self.col + 1])

    def on_frame(self, r: Reaction, fr: _Frame) -> list[Load]:
        if self.guide != "ground":
            return []
        assert r.moment is not None  # made by reaction() above
        return [(-r.force, -(cross(fr.z[self.joint], r.force) + r.moment))]


@dataclass(frozen=True)
class DriverEffort:
    """The driver's generalized force ``x[col]``: a crank's torque, a slider's push, a cylinder's force."""

    driver: Driver
    index: int  # in the drivers' order (its speed's row)
    col: int
    width: ClassVar[int] = 1

    def entries(self, fr: _Frame) -> list[Entry]:
        d, col = self.driver, self.col
        match d.type:
            case CrankType():  # a torque on the driven link
                return _moment(fr, d.link, col, 1.0)
            case CylinderType(ends=(a, b)):  # a massless two-force member: +F u on its first end, -F u on its second
                u, carrier = fr.cyl_dir[d.name], fr.mech.links_of
                return _force(fr, carrier(a)[0], col, fr.z[a], u, +1.0) + _force(
                    fr, carrier(b)[0], col, fr.z[b], u, -1.0
                )
            case SliderType(slider=k):  # a push along the slide, on the block (its reaction on the guide)
                sl, e = fr.mech.sliders[k], fr.slide_dir[k]
                zt = fr.z[sl.through]
                return _force(fr, sl.link, col, zt, e, +1.0) + _force(fr, sl.on, col, zt, e, -1.0)
            case _:
                assert_never(d.type)

    def on_frame(self, effort: np.ndarray, fr: _Frame) -> list[Load]:
        d = self.driver
        match d.type:
            case CrankType():  # the frame takes -T
                return [(0.0, -effort)]
            case CylinderType(ends=(a, b)):  # the frame holds an end of the cylinder
                ends = ((end, sign * effort * fr.cyl_dir[d.name]) for end, sign in ((a, 1.0), (b, -1.0)))
                return [(fe, cross(fr.z[end], fe)) for end, fe in ends if fr.mech.links_of(end)[0] == "ground"]
            case SliderType(slider=k):
                sl = fr.mech.sliders[k]
                if sl.on != "ground":
                    return []
                fe = effort * fr.slide_dir[k]
                return [(-fe, -cross(fr.z[sl.through], fe))]
            case _:
                assert_never(d.type)


Unknown = PinForce | SliderReaction | DriverEffort


def unknowns(mech: Mechanism) -> tuple[Unknown, ...]:
    """The unknowns in column order: pin forces (2 columns each), slider reactions (2), driver efforts (1).

    A joint of k links gives k - 1 pin forces, each by the first link (the pin's carrier) on another.
    """
    out: list[Unknown] = []
    col = 0
    for j in mech.joint_names:
        carrier, *others = mech.links_of(j)
        for other in others:
            out.append(PinForce(j, other, carrier, col))
            col += 2
    for k, sl in enumerate(mech.sliders):
        out.append(SliderReaction(k, sl.through, sl.link, sl.on, col))
        col += 2
    for i, d in enumerate(mech.drivers):
        out.append(DriverEffort(d, i, col))
        col += 1
    return tuple(out)


def _frame(mech: Mechanism, km: Kinematics) -> tuple[_Frame, np.ndarray]:
    """The frame of the system, and its right-hand side: inertia, gravity and loads, (n, 3 moving links)."""
    n, si = km.z.shape[1], mech.length_to_si
    moving = [ln for ln in mech.links if ln.name != "ground"]
    row = {ln.name: 3 * i for i, ln in enumerate(moving)}
    z = {j: km.z[i] * si for i, j in enumerate(mech.joint_names)}  # joint positions in metres, once
    Q: dict[str, np.ndarray] = {}
    rhs = np.zeros((n, 3 * len(moving)))
    g = mech.gravity if mech.gravity is not None else 0j
    for body in km.bodies:  # m (a_G - g) and I_G alpha, about Q = G (or the first joint when massless)
        r0 = row[body.link]
        al = np.broadcast_to(km.motion[body.link][2], (n,))
        if body.cg is not None:
            zg, _vg, ag = point_motion(mech, body.link, body.cg, km)
            Q[body.link] = zg * si
            inertial = body.mass * (ag * si - g)
            rhs[:, r0] += inertial.real
            rhs[:, r0 + 1] += inertial.imag
        else:
            Q[body.link] = z[mech.link(body.link).joints[0]]
        rhs[:, r0 + 2] += body.inertia * al
    for ld in km.loads:  # external loads move to the other side
        r0 = row[ld.link]
        rhs[:, r0 + 2] -= ld.torque
        zp = point_motion(mech, ld.link, ld.at, km)[0] * si if ld.at is not None else Q[ld.link]
        rhs[:, r0] -= ld.force.real
        rhs[:, r0 + 1] -= ld.force.imag
        rhs[:, r0 + 2] -= cross(zp - Q[ld.link], ld.force)
    elements, frame_pulls = _apply_elements(mech, km, row, z, Q, rhs)
    slide_dir = tuple(np.broadcast_to(km.motion[sl.on][0] * sl.direction, (n,)) for sl in mech.sliders)
    cyl_dir: dict[str, np.ndarray] = {}
    for d in mech.drivers:
        if isinstance(d.type, CylinderType):
            za, zb = z[d.type.ends[0]], z[d.type.ends[1]]
            with np.errstate(invalid="ignore", divide="ignore"):
                cyl_dir[d.name] = (za - zb) / np.abs(za - zb)
    return _Frame(mech, n, row, z, Q, slide_dir, cyl_dir, elements, frame_pulls), rhs


def _apply_elements(
    mech: Mechanism,
    km: Kinematics,
    row: dict[str, int],
    z: dict[str, np.ndarray],
    Q: dict[str, np.ndarray],
    rhs: np.ndarray,
) -> tuple[ElementForces, tuple[tuple[Any, Any], ...]]:
    """Springs and dampers as applied forces on the links carrying their ends (moved to ``rhs``, as loads).

    Returns their tensions and what they do to the frame (an end carried by the ground).
    """
    el = element_forces(mech, km.z, km.v)
    frame: list[tuple[Any, Any]] = []
    for joint, link, f in el.pulls(mech, km.z):
        if link == "ground":
            frame.append((f, cross(z[joint], f)))
            continue
        r0 = row[link]
        rhs[:, r0] -= f.real
        rhs[:, r0 + 1] -= f.imag
        rhs[:, r0 + 2] -= cross(z[joint] - Q[link], f)
    return el, tuple(frame)


def solve_stacked(
    entries: list[Entry], rhs: np.ndarray, good: np.ndarray, size: float
) -> tuple[np.ndarray, np.ndarray]:
    """``A x = b`` for every sample (``A`` filled from ``entries``), in chunks into one reused buffer.

    Returns ``x`` (n, m) and the relative residual per sample, max |A x - b| over
    (max |b| + size * max |x|); NaN where not ``good`` (there ``A`` is a placeholder).
    """
    n, m = rhs.shape
    rhs[~good] = 0.0
    x = np.empty((n, m))
    residual = np.empty(n)
    buf = np.empty((min(n, CHUNK), m, m))
    eye = np.eye(m)
    for start in range(0, n, CHUNK):  # no 3-D array over all samples
        stop = min(start + CHUNK, n)
        Ak, bk = buf[: stop - start], rhs[start:stop]
        Ak.fill(0.0)
        for r, c, coef in entries:
            Ak[:, r, c] += coef[start:stop] if isinstance(coef, np.ndarray) else coef
        Ak[~good[start:stop]] = eye
        xk = _solve_or_nan(Ak, bk, eye)
        x[start:stop] = xk
        err = np.max(np.abs(np.matmul(Ak, xk[..., None])[..., 0] - bk), axis=1)
        residual[start:stop] = err / np.maximum(np.max(np.abs(bk), axis=1) + size * np.max(np.abs(xk), axis=1), 1e-300)
    x[~good] = np.nan
    residual[~good] = np.nan
    return x, residual


def _solve_or_nan(A: np.ndarray, b: np.ndarray, eye: np.ndarray) -> np.ndarray:
    """``A x = b`` per matrix; NaN rows where ``A`` is exactly singular (LAPACK meets a zero pivot: the reactions of a
    flat position are not determined, as at the change point of a double parallelogram that ``--branch continuous``
    gives its kinematic limit; the whole batch raised ``LinAlgError``, an internal error)."""
    try:
        return np.asarray(np.linalg.solve(A, b[..., None])[..., 0])
    except np.linalg.LinAlgError:
        singular = ~(np.abs(np.linalg.det(A)) > 0)
        A = np.where(singular[:, None, None], eye, A)
        x = np.linalg.solve(A, b[..., None])[..., 0]
        x[singular] = np.nan
        return np.asarray(x)


def solve_forces(mech: Mechanism, km: Kinematics) -> Forces:
    """Joint reactions, driver torques/forces and derived quantities for every sample of ``km``."""
    fr, rhs = _frame(mech, km)
    cols = unknowns(mech)
    if sum(u.width for u in cols) != rhs.shape[1]:  # pragma: no cover - the model already checked the dof
        raise AssertionError(f"kinetostatics: {sum(u.width for u in cols)} unknowns for {rhs.shape[1]} equations")
    entries = [e for u in cols for e in u.entries(fr)]
    size = max(1.0, mech.length_scale * mech.length_to_si)  # lever arms are at most about this (m)
    x, residual = solve_stacked(entries, rhs, km.good, size)

    reactions: list[Reaction] = []
    torque: dict[str, np.ndarray] = {}
    push: dict[str, np.ndarray] = {}
    frame: list[Load] = []
    for u in cols:
        if isinstance(u, DriverEffort):
            effort = x[:, u.col]
            (torque if u.driver.type.effort is UnitKind.TORQUE else push)[u.driver.name] = effort
            frame += u.on_frame(effort, fr)
        else:
            reactions.append(u.reaction(x, fr))
            frame += u.on_frame(reactions[-1], fr)
    shaking, shaking_m = np.zeros(fr.n, complex), np.zeros(fr.n)
    for f, moment in [*frame, *fr.frame_pulls]:
        shaking += f
        shaking_m += moment
    power = np.zeros(fr.n)
    for u in cols:  # T w, or F ds/dt (in m/s)
        if isinstance(u, DriverEffort):
            speed = np.broadcast_to(km.speeds[u.index], (fr.n,))
            power += x[:, u.col] * speed * u.driver.type.rate_to_si(mech.length_to_si)
    bad = ~km.good
    if bad.any():
        shaking[bad] = complex(np.nan, np.nan)
        shaking_m[bad] = np.nan
        power[bad] = np.nan
    el = fr.elements
    return Forces(
        tuple(reactions), torque, push, power, shaking, shaking_m, residual, el.spring, el.spring_length, el.damper
    )
