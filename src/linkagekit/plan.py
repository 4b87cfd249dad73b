"""Solve plan: topology, degrees of freedom and the order of triangulation steps.

The plan is a list of steps, each of which places joints from joints already placed:

``Ground``
    the joints of the frame, fixed.
``Crank``
    a driven link: ``toward = pivot + r * exp(i*phi)``.
``Place``
    a link with two known joints ``k1, k2``: every other joint ``j`` of it is
    ``z_j = z_k1 + rho_j * (z_k2 - z_k1)`` with the constant complex ratio
    ``rho_j = (s_j - s_k1) / (s_k2 - s_k1)`` of its shape (seed 000, eq. 18, in complex
    form).  Its mirror image uses ``conj(rho_j)``.
``Dyad``
    a joint of two links that each have one known joint: intersection of two circles
    (seed 000, eqs. 11-15).  One sign per step picks the side of the directed line
    ``k1 -> k2``.
``CircleLine``
    a joint of a slider block (on a line carried by a placed link) and of a link with
    one known joint: intersection of a circle and a line.  The sign picks the side of
    the foot of the perpendicular along the slider direction.
``Pivot``
    the link a block slides on, turning about its one known joint so that its line
    passes through the block's known joint (inverted slider-crank).  Same sign rule.
``SliderDrive``
    a driven slider block, displaced along its line.
``Carry``
    a link with one known joint whose rotation is known (a block turns with the link
    it slides on; the link a block slides on after a ``Pivot`` step).

Examples
--------
>>> import linkagekit as lk
>>> mech = lk.load("examples/seed000_fourbar.yaml")  # doctest: +SKIP
>>> print(mech.plan.describe())  # doctest: +SKIP
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from .errors import MechanismFileError, NotSolvableError

if TYPE_CHECKING:
    from .model import Mechanism

GROUND = "ground"


@dataclass(frozen=True)
class Ground:
    joints: tuple[int, ...]
    z: tuple[complex, ...]


@dataclass(frozen=True)
class Crank:
    driver: int
    link: str
    pivot: int
    toward: int
    radius: float


@dataclass(frozen=True)
class Place:
    link: str
    k1: int
    k2: int
    scale: complex  # s_k2 - s_k1: rotation of the link is (z_k2 - z_k1) / scale
    joints: tuple[int, ...]
    ratios: tuple[complex, ...]
    mirror: int | None = None  # index into the mirror flags, for links of 3+ joints


@dataclass(frozen=True)
class Dyad:
    joint: int
    k1: int
    k2: int
    r1: float
    r2: float
    links: tuple[str, str]
    sign: int  # index into the sign vector


@dataclass(frozen=True)
class CircleLine:
    joint: int
    center: int
    radius: float
    slider: int
    block: str
    on: str
    point: complex  # the joint's line in `on`'s frame: point + u * direction
    direction: complex
    anchor: int | None  # a known joint of `on` and its shape position (None: on is ground)
    anchor_s: complex
    sign: int


@dataclass(frozen=True)
class Pivot:
    slider: int
    on: str
    center: int  # the known joint of `on` it turns about
    joint: int  # the known joint of the block
    offset: complex  # pose(joint) - shape_on(center), in `on`'s frame
    direction: complex
    sign: int


@dataclass(frozen=True)
class SliderDrive:
    driver: int
    slider: int
    block: str
    on: str
    anchor: int | None
    anchor_s: complex
    direction: complex
    joints: tuple[int, ...]
    points: tuple[complex, ...]  # reference positions in `on`'s frame


@dataclass(frozen=True)
class Carry:
    link: str
    rot_of: str  # the link whose rotation this link shares
    anchor: int
    joints: tuple[int, ...]
    offsets: tuple[complex, ...]  # s_j - s_anchor


Step = Ground | Crank | Place | Dyad | CircleLine | Pivot | SliderDrive | Carry


@dataclass(frozen=True)
class Plan:
    """The triangulation order of a mechanism, with its default signs."""

    joint_names: tuple[str, ...]
    steps: tuple[Step, ...]
    n_signs: int
    n_mirrors: int
    dof: int
    drivers: tuple[str, ...]
    signs: tuple[int, ...] = ()  # the assembly mode of the reference pose
    mirror_links: tuple[str, ...] = ()
    sign_labels: tuple[str, ...] = field(default=())

    @property
    def rotation_links(self) -> frozenset[str]:
        """Links whose rotation later steps use (guides of sliders, links others turn with)."""
        out = {st.on for st in self.steps if isinstance(st, CircleLine | SliderDrive | Pivot)}
        out |= {st.rot_of for st in self.steps if isinstance(st, Carry)}
        return frozenset(out)

    def sign_steps(self) -> list[Dyad | CircleLine | Pivot]:
        return [s for s in self.steps if isinstance(s, Dyad | CircleLine | Pivot)]

    def describe(self) -> str:
        """A human-readable listing of the steps."""
        n = self.joint_names
        out = []
        for st in self.steps:
            if isinstance(st, Ground):
                text = "fixed joints " + ", ".join(n[j] for j in st.joints)
            elif isinstance(st, Crank):
                text = f"driver '{st.link}': {n[st.toward]} from {n[st.pivot]} at the input angle (r = {st.radius:.6g})"
            elif isinstance(st, Place):
                if not st.joints:
                    continue
                m = " (mirror image selectable)" if st.mirror is not None else ""
                placed = ", ".join(n[j] for j in st.joints)
                text = f"link '{st.link}': {placed} placed rigidly on {n[st.k1]}, {n[st.k2]}{m}"
            elif isinstance(st, Dyad):
                text = (
                    f"{n[st.joint]} = circle({n[st.k1]}, {st.r1:.6g}) x circle({n[st.k2]}, {st.r2:.6g}); "
                    f"sign +1: left of {n[st.k1]}->{n[st.k2]}"
                )
            elif isinstance(st, CircleLine):
                text = (
                    f"{n[st.joint]} = circle({n[st.center]}, {st.radius:.6g}) x line of slider {st.slider} "
                    f"('{st.block}' on '{st.on}'); sign +1: {n[st.joint]} ahead of {n[st.center]} along the slider"
                )
            elif isinstance(st, Pivot):
                text = (
                    f"link '{st.on}' turns about {n[st.center]} until slider {st.slider}'s line passes "
                    f"{n[st.joint]}; sign +1: {n[st.joint]} ahead of {n[st.center]} along the slider"
                )
            elif isinstance(st, SliderDrive):
                text = f"driver '{st.block}': slider {st.slider} displaced along its line"
            else:
                if not st.joints:
                    continue
                moved = ", ".join(n[j] for j in st.joints)
                text = f"link '{st.link}': {moved} carried with '{st.rot_of}' from {n[st.anchor]}"
            out.append(text)
        return "\n".join(f"{i}. {t}" for i, t in enumerate(out, 1))


def grubler(mech: Mechanism) -> int:
    """Degrees of freedom by the Gruebler-Kutzbach count for planar lower pairs.

    ``F = 3 (n - 1) - 2 p``: ``n`` links (ground included), ``p`` one-freedom pairs; a pin
    shared by ``m`` links counts as ``m - 1`` pins, a slider as one pair.
    """
    n = len(mech.links)
    pins = sum(max(len(mech.links_of(j)) - 1, 0) for j in mech.joints)
    return 3 * (n - 1) - 2 * (pins + len(mech.sliders))


def make_plan(mech: Mechanism) -> Plan:
    """Find a triangulation order; raise a located error when there is none."""
    names = tuple(mech.joints)
    idx = {n: i for i, n in enumerate(names)}
    dof = grubler(mech)
    if dof != len(mech.drivers):
        n = len(mech.links)
        pins = sum(max(len(mech.links_of(j)) - 1, 0) for j in mech.joints)
        raise MechanismFileError(
            f"{mech.source}: drivers: {len(mech.drivers)} driver(s) given, but the mechanism has {dof} degree(s) "
            f"of freedom (Gruebler: 3*({n}-1) - 2*({pins} pins + {len(mech.sliders)} sliders) = {dof})"
        )

    links = {ln.name: ln for ln in mech.links}
    known: set[str] = set(links[GROUND].joints)
    placed: set[str] = {GROUND}
    steps: list[Step] = [
        Ground(tuple(idx[j] for j in links[GROUND].joints), tuple(links[GROUND].shape[j] for j in links[GROUND].joints))
    ]
    rot_known: set[str] = {GROUND}
    pending = list(range(len(mech.drivers)))
    n_signs = 0
    mirror_links: list[str] = []
    slider_of = {s.link: (i, s) for i, s in enumerate(mech.sliders)}
    labels: list[str] = []

    def anchor_of(link: str) -> tuple[int | None, complex]:
        if link == GROUND:
            return None, 0j
        for st in steps:
            if isinstance(st, Place) and st.link == link:
                return st.k1, links[link].shape[names[st.k1]]
            if isinstance(st, Carry) and st.link == link:
                return st.anchor, links[link].shape[names[st.anchor]]
        raise AssertionError(link)

    def place_all() -> bool:
        progress = False
        for ln in mech.links:
            if ln.name in placed:
                continue
            kn = [j for j in ln.joints if j in known]
            if len(kn) >= 2:
                k1, k2 = kn[0], kn[1]
                rest = [j for j in ln.joints if j not in known]
                base = ln.shape[k2] - ln.shape[k1]
                ratios = tuple((ln.shape[j] - ln.shape[k1]) / base for j in rest)
                mirror = None
                if rest and len(ln.joints) >= 3:
                    mirror = len(mirror_links)
                    mirror_links.append(ln.name)
                steps.append(Place(ln.name, idx[k1], idx[k2], base, tuple(idx[j] for j in rest), ratios, mirror))
                known.update(rest)
                placed.add(ln.name)
                rot_known.add(ln.name)
                progress = True
            elif len(kn) == 1:
                rot_from = None
                if ln.name in rot_known:
                    rot_from = ln.name
                elif ln.name in slider_of and slider_of[ln.name][1].on in rot_known:
                    rot_from = slider_of[ln.name][1].on
                if rot_from is None:
                    continue
                rest = [j for j in ln.joints if j not in known]
                steps.append(
                    Carry(
                        ln.name,
                        rot_from,
                        idx[kn[0]],
                        tuple(idx[j] for j in rest),
                        tuple(ln.shape[j] - ln.shape[kn[0]] for j in rest),
                    )
                )
                known.update(rest)
                placed.add(ln.name)
                rot_known.add(ln.name)
                progress = True
        return progress

    while True:
        if place_all():
            continue
        # drivers, as soon as they can act
        acted = False
        for di in list(pending):
            d = mech.drivers[di]
            if d.kind == "angle":
                assert d.pivot is not None and d.toward is not None
                if d.link in placed or d.toward in known:
                    raise MechanismFileError(
                        f"{mech.source}: drivers[{di}]: link '{d.link}' is already fixed by the rest of the "
                        f"mechanism; the drivers do not match its freedom"
                    )
                if d.pivot in known:
                    r = links[d.link].length(d.pivot, d.toward)
                    steps.append(Crank(di, d.link, idx[d.pivot], idx[d.toward], r))
                    known.add(d.toward)
                    pending.remove(di)
                    acted = True
            else:
                assert d.slider is not None
                s = mech.sliders[d.slider]
                if d.link in placed:
                    raise MechanismFileError(
                        f"{mech.source}: drivers[{di}]: block '{d.link}' is already fixed by the rest of the "
                        f"mechanism; the drivers do not match its freedom"
                    )
                if s.on in rot_known and s.on in placed:
                    a, a_s = anchor_of(s.on)
                    blk = links[s.link]
                    pts = tuple(mech.joints[j] for j in blk.joints)
                    steps.append(
                        SliderDrive(
                            di, d.slider, s.link, s.on, a, a_s, s.direction, tuple(idx[j] for j in blk.joints), pts
                        )
                    )
                    known.update(blk.joints)
                    placed.add(s.link)
                    rot_known.add(s.link)
                    pending.remove(di)
                    acted = True
        if acted:
            continue
        found = _next_sign_step(mech, names, idx, known, placed, rot_known, slider_of, steps, n_signs, anchor_of)
        if found is None:
            break
        step, newly_known, newly_rot, label = found
        steps.append(step)
        known.update(newly_known)
        rot_known.update(newly_rot)
        labels.append(label)
        n_signs += 1

    missing = [j for j in names if j not in known]
    if missing or pending:
        what = ", ".join(missing) if missing else ", ".join(mech.drivers[d].name for d in pending)
        raise NotSolvableError(
            f"{mech.source}: no triangulation order places {what}: this mechanism needs the numerical solver "
            f"(an Assur group of class 3 or more, or a slider arrangement not handled in closed form), "
            f"which linkagekit does not have yet"
        )
    plan = Plan(
        names,
        tuple(steps),
        n_signs,
        len(mirror_links),
        dof,
        tuple(d.name for d in mech.drivers),
        mirror_links=tuple(mirror_links),
        sign_labels=tuple(labels),
    )
    from .positions import pose_signs

    return _with_signs(plan, pose_signs(mech, plan))


def _with_signs(plan: Plan, signs: tuple[int, ...]) -> Plan:
    from dataclasses import replace

    return replace(plan, signs=signs)


def _next_sign_step(mech, names, idx, known, placed, rot_known, slider_of, steps, n_signs, anchor_of):  # type: ignore[no-untyped-def]
    """The next circle-circle, circle-line or pivot step, or None when there is none."""
    links = {ln.name: ln for ln in mech.links}
    for j in names:
        if j in known:
            continue
        owners = [ln for ln in mech.links if j in ln.joints and ln.name not in placed]
        anchored = [
            (ln, next(k for k in ln.joints if k in known)) for ln in owners if any(k in known for k in ln.joints)
        ]
        # two circles
        for a in range(len(anchored)):
            for b in range(a + 1, len(anchored)):
                (l1, k1), (l2, k2) = anchored[a], anchored[b]
                if k1 == k2:
                    continue
                st = Dyad(idx[j], idx[k1], idx[k2], l1.length(k1, j), l2.length(k2, j), (l1.name, l2.name), n_signs)
                return st, {j}, set(), f"{j}: left of {k1}->{k2}"
        # circle and line: j on a block whose guide is placed, and on a link with one known joint
        for ln in owners:
            if ln.name in slider_of:
                si, s = slider_of[ln.name]
                if s.on not in placed or any(k in known for k in ln.joints):
                    continue
                for l2, k2 in anchored:
                    if l2.name == ln.name:
                        continue
                    a, a_s = anchor_of(s.on)
                    st = CircleLine(
                        idx[j],
                        idx[k2],
                        l2.length(k2, j),
                        si,
                        s.link,
                        s.on,
                        mech.joints[j],
                        s.direction,
                        a,
                        a_s,
                        n_signs,
                    )
                    return st, {j}, set(), f"{j}: ahead of {k2} along slider {si}"
    # pivot: a block with a known joint slides on a link with exactly one known joint
    for si, s in enumerate(mech.sliders):
        if s.on in placed or s.on in rot_known:
            continue
        blk = links[s.link]
        on = links[s.on]
        bj = [k for k in blk.joints if k in known]
        oj = [k for k in on.joints if k in known]
        if bj and len(oj) == 1:
            st = Pivot(si, s.on, idx[oj[0]], idx[bj[0]], mech.joints[bj[0]] - on.shape[oj[0]], s.direction, n_signs)
            return st, set(), {s.on}, f"{bj[0]}: ahead of {oj[0]} along slider {si}"
    return None
