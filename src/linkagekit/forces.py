"""Kinetostatics: joint reactions and driver torques by the Newton-Euler equations of every link.

For every moving link ``b`` (mass ``m``, centre of gravity ``G``, inertia ``I_G``) and every
sample, with ``Q`` the link's reference point (``G`` when the link has a ``cg``, else its
first joint)::

    sum F_on_b + m g + sum F_ext          = m a_G
    sum (r - Q) x F_on_b + sum tau + (G - Q) x m g + sum (r_ext - Q) x F_ext + tau_ext
                                          = I_G alpha + (G - Q) x m a_G

The unknowns, written once each and entering two links with opposite signs:

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

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, assert_never

import numpy as np

from .catalogue import ReactionKey
from .errors import UnknownNameError, shorten
from .geometry import cross
from .model import CrankType, CylinderType, SliderType
from .params import Body, LoadParams
from .rates import LinkMotion

if TYPE_CHECKING:
    from .model import Mechanism

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
        return np.abs(self.force)


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

    def map(self, f: Any) -> Forces:
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
        )

    def arrays(self) -> list[np.ndarray]:
        """Every array, in a fixed order (the same for two Forces of one mechanism)."""
        out: list[np.ndarray] = []
        for r in self.reactions:
            out += [r.force] if r.moment is None else [r.force, r.moment]
        out += list(self.driver_torque.values()) + list(self.driver_force.values())
        return [*out, self.input_power, self.shaking_force, self.shaking_moment, self.residual]

    def take(self, index: Any) -> Forces:
        """The same forces with every array indexed by ``index`` (one design of a batch)."""
        return self.map(lambda a: a[index])


def json_list(a: Any) -> list[Any]:
    """A 1-D array as a JSON list; NaN becomes ``None`` (``null``); nested for more dimensions."""
    arr = np.asarray(a, float)
    out = arr.tolist()  # Python floats, nested for more dimensions
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


# ------------------------------------------------------------------------------- the system
def solve_forces(mech: Mechanism, km: Kinematics) -> Forces:
    """Joint reactions, driver torques/forces and derived quantities for every sample of ``km``."""
    n = km.z.shape[1]
    si = mech.length_to_si
    moving = [ln for ln in mech.links if ln.name != "ground"]
    row = {ln.name: 3 * i for i, ln in enumerate(moving)}  # first of the link's three rows
    m = 3 * len(moving)
    names = mech.joint_names
    z_si = {j: km.z[i] * si for i, j in enumerate(names)}  # joint positions in metres, once

    # reference point Q of every link (m): the centre of gravity, or the first joint
    Q: dict[str, np.ndarray] = {}
    rhs = np.zeros((n, m))
    g = mech.gravity if mech.gravity is not None else 0j
    for body in km.bodies:
        r0 = row[body.link]
        al = np.broadcast_to(km.motion[body.link][2], (n,))
        if body.cg is not None:
            zg, _vg, ag = point_motion(mech, body.link, body.cg, km)
            Q[body.link] = zg * si
            inertial = body.mass * (ag * si - g)  # m (a_G - g), N
            rhs[:, r0] += inertial.real
            rhs[:, r0 + 1] += inertial.imag
        else:
            Q[body.link] = z_si[mech.link(body.link).joints[0]]
        rhs[:, r0 + 2] += body.inertia * al
    for ld in km.loads:
        r0 = row[ld.link]
        rhs[:, r0 + 2] -= ld.torque
        zp = point_motion(mech, ld.link, ld.at, km)[0] * si if ld.at is not None else Q[ld.link]
        rhs[:, r0] -= ld.force.real
        rhs[:, r0 + 1] -= ld.force.imag
        rhs[:, r0 + 2] -= cross(zp - Q[ld.link], ld.force)

    # columns: unknowns and where they enter, as (row, column, coefficient per sample);
    # the matrices are filled chunk by chunk into one reused buffer below
    entries: list[tuple[int, int, Any]] = []
    labels: list[tuple[str, ...]] = []
    col = 0

    def put_force(link: str, c: int, at: np.ndarray, direction: Any, sign: float) -> None:
        """Unit-force column c: ``sign * direction`` at point ``at`` (m) on ``link``."""
        if link == "ground":
            return
        r0 = row[link]
        d = sign * np.broadcast_to(direction, (n,))
        entries.extend(((r0, c, np.real(d)), (r0 + 1, c, np.imag(d)), (r0 + 2, c, cross(at - Q[link], d))))

    for j in names:
        holders = mech.links_of(j)
        if len(holders) < 2:
            continue
        zj = z_si[j]
        carrier = holders[0]
        for other in holders[1:]:
            for c, e in ((col, 1.0), (col + 1, 1j)):
                put_force(other, c, zj, e, +1.0)
                put_force(carrier, c, zj, e, -1.0)
            labels.append(("pin", j, other, carrier))
            col += 2
    slide_dir: dict[int, np.ndarray] = {}
    for k, sl in enumerate(mech.sliders):
        zt = z_si[sl.through]
        e_now = km.motion[sl.on][0] * sl.direction  # the slide direction turns with the guide
        slide_dir[k] = np.broadcast_to(e_now, (n,))
        put_force(sl.link, col, zt, 1j * slide_dir[k], +1.0)
        put_force(sl.on, col, zt, 1j * slide_dir[k], -1.0)
        for link, sign in ((sl.link, 1.0), (sl.on, -1.0)):
            if link != "ground":
                entries.append((row[link] + 2, col + 1, sign))
        labels.append(("slider", sl.through, sl.link, sl.on, str(k)))
        col += 2
    cyl_dir: dict[str, np.ndarray] = {}
    first_driver = col  # one column per driver, in the drivers' order: its generalized force
    for d in mech.drivers:
        match d.type:
            case CrankType():  # a torque on the driven link
                if d.link != "ground":
                    entries.append((row[d.link] + 2, col, 1.0))
            case CylinderType(ends=(a, b)):  # a massless two-force member: +F u on its first end, -F u on its second
                za, zb = z_si[a], z_si[b]
                with np.errstate(invalid="ignore", divide="ignore"):
                    cyl_dir[d.name] = (za - zb) / np.abs(za - zb)  # from the second end to the first
                put_force(mech.links_of(a)[0], col, za, cyl_dir[d.name], +1.0)
                put_force(mech.links_of(b)[0], col, zb, cyl_dir[d.name], -1.0)
            case SliderType(slider=k):  # a push along the slide, on the block (its reaction on the guide)
                sl = mech.sliders[k]
                zt = z_si[sl.through]
                put_force(sl.link, col, zt, slide_dir[k], +1.0)
                put_force(sl.on, col, zt, slide_dir[k], -1.0)
            case _:
                assert_never(d.type)
        col += 1
    if col != m:  # pragma: no cover - the model already checked the degrees of freedom
        raise AssertionError(f"kinetostatics: {col} unknowns for {m} equations")

    good = km.good
    rhs[~good] = 0.0
    x = np.empty((n, m))
    residual = np.empty(n)
    size = max(1.0, mech.length_scale * si)  # lever arms are at most about this (m)
    buf = np.empty((min(n, CHUNK), m, m))
    eye = np.eye(m)
    for start in range(0, n, CHUNK):  # one reused buffer: no 3-D array over all samples
        stop = min(start + CHUNK, n)
        Ak, bk = buf[: stop - start], rhs[start:stop]
        Ak.fill(0.0)
        for r, c, coef in entries:
            Ak[:, r, c] += coef[start:stop] if isinstance(coef, np.ndarray) else coef
        Ak[~good[start:stop]] = eye  # placeholders, answered NaN below
        xk = np.linalg.solve(Ak, bk[..., None])[..., 0]
        x[start:stop] = xk
        err = np.max(np.abs(np.matmul(Ak, xk[..., None])[..., 0] - bk), axis=1)
        residual[start:stop] = err / np.maximum(np.max(np.abs(bk), axis=1) + size * np.max(np.abs(xk), axis=1), 1e-300)
    x[~good] = np.nan
    residual[~good] = np.nan

    # unpack
    reactions: list[Reaction] = []
    torque: dict[str, np.ndarray] = {}
    push: dict[str, np.ndarray] = {}
    shaking = np.zeros(n, complex)
    shaking_m = np.zeros(n)
    col = 0
    for lab in labels:
        if lab[0] == "pin":
            _, j, other, carrier = lab
            f = x[:, col] + 1j * x[:, col + 1]
            reactions.append(Reaction(j, other, carrier, f))
            if "ground" in (carrier, other):  # the frame feels -f if it exerts f, +f if it receives it
                on_frame = -f if carrier == "ground" else f
                shaking += on_frame
                shaking_m += cross(z_si[j], on_frame)
            col += 2
        elif lab[0] == "slider":
            _, j, block, guide, index = lab
            f = x[:, col] * (1j * slide_dir[int(index)])
            moment = x[:, col + 1]
            reactions.append(Reaction(j, block, guide, f, moment))
            if guide == "ground":
                shaking -= f
                shaking_m -= cross(z_si[j], f) + moment
            col += 2
    for i, d in enumerate(mech.drivers):
        effort = x[:, first_driver + i]
        match d.type:
            case CrankType():
                torque[d.name] = effort
                shaking_m -= effort
            case CylinderType(ends=(a, b)):
                push[d.name] = effort
                for end, sign in ((a, 1.0), (b, -1.0)):
                    if mech.links_of(end)[0] == "ground":  # the frame holds this end of the cylinder
                        fe = sign * effort * cyl_dir[d.name]
                        shaking += fe
                        shaking_m += cross(z_si[end], fe)
            case SliderType(slider=k):
                push[d.name] = effort
                sl = mech.sliders[k]
                if sl.on == "ground":
                    fe = effort * slide_dir[k]
                    shaking -= fe
                    shaking_m -= cross(z_si[sl.through], fe)
            case _:
                assert_never(d.type)
    power = np.zeros(n)
    for i, d in enumerate(mech.drivers):  # T w, or F ds/dt (in m/s)
        speed = np.broadcast_to(km.speeds[i], (n,))
        power += x[:, first_driver + i] * speed * d.type.rate_to_si(si)
    bad = ~good
    if bad.any():
        shaking[bad] = complex(np.nan, np.nan)
        shaking_m[bad] = np.nan
        power[bad] = np.nan
    return Forces(tuple(reactions), torque, push, power, shaking, shaking_m, residual)
