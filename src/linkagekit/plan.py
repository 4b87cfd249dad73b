"""Solve plan: the topology of a mechanism as an ordered list of steps.

The plan says which joint each step places, from which joints, and which sign or mirror
slot it reads; it holds no dimension at all (those are in :mod:`linkagekit.params`), so one
plan serves every design of a topology.  It is hashable and picklable and is computed
without solving anything: a greedy search for a triangulation order,

1. start from the ground joints;
2. repeatedly place every link with two known joints (``Place``), carry every link with
   one known joint whose rotation is known (``Carry``), apply every driver whose pivot or
   guide is known (``Crank``, ``SliderDrive``) and every cylinder with one end known (its
   other end on a circle of the cylinder's length: ``CylinderDyad``, ``CylinderLine``, each
   reading one sign); slide a yoke whose guide is placed until a block with a known joint
   fits its slot (``LineLine``: two lines, no sign);
3. otherwise find one joint of two links that each have one known joint (``Dyad``: two
   circles), of a slider block and a link (``CircleLine``), or turn a guide about its one
   known joint through a known block joint (``Pivot``); each of these reads one sign;
4. otherwise place the smallest group of joints that the links, sliders, cylinder drivers
   and actuators (slider drivers between two moving links) among them fix, numerically
   (:class:`~linkagekit.group.Group`).

A mechanism for which this stops before every joint is known has no triangulation order
(an Assur group of class 3 or more).

Examples
--------
>>> import linkagekit as lk
>>> plan = make_plan(lk.load("examples/seed000_fourbar.yaml"))
>>> print(plan.describe())
1. fixed joints A, B
2. driver 'crank': C from A at the input angle
3. D = circle(C) x circle(B); sign +1: left of C->B
4. link 'coupler': P placed rigidly on C, D (mirror image selectable)
>>> plan.n_signs, plan.sign_joints, plan.mirror_links
(1, ('D',), ('coupler',))
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from enum import Enum
from functools import lru_cache
from itertools import combinations
from typing import TYPE_CHECKING, Any, Literal, NamedTuple, assert_never

from .errors import MechanismFileError, NotSolvableError
from .group import Group, GroupCylinder, GroupLink, GroupSlider, GroupSliderDrive
from .model import CrankType, CylinderType, SliderType
from .steps import (
    ActuatorDyad,
    Carry,
    CircleLine,
    Crank,
    CylinderDyad,
    CylinderLine,
    Dyad,
    Ground,
    LineLine,
    Pivot,
    Place,
    SliderDrive,
    Step,
    is_sign_step,
)

if TYPE_CHECKING:
    from .model import Link, Mechanism, Slider

GROUND = "ground"


@dataclass(frozen=True)
class Plan:
    """The triangulation order of a topology (no dimensions, no assembly mode).

    Attributes
    ----------
    joint_names : tuple of str
        Every joint, in the file's order (the rows of every positions array).
    steps : tuple of Step
    n_signs, n_mirrors : int
        Sizes of the sign vector (one per sign step) and of the mirror flags (one per link
        of three or more joints placed rigidly).
    dof : int
    drivers : tuple of str
    mirror_links : tuple of str
    sign_labels : tuple of str
        For each sign, which side ``+1`` means.
    """

    joint_names: tuple[str, ...]
    steps: tuple[Step, ...]
    n_signs: int
    n_mirrors: int
    dof: int
    drivers: tuple[str, ...]
    mirror_links: tuple[str, ...] = ()
    sign_labels: tuple[str, ...] = ()

    @property
    def numerical(self) -> tuple[int, ...]:
        """The joints placed by numerical groups (Newton), in step order."""
        return tuple(j for st in self.steps if isinstance(st, Group) for j in st.joints)

    @property
    def nan_flagged(self) -> tuple[int, ...]:
        """Joints whose step flags a failure by NaN, not by a margin: numerical groups, driven blocks (stroke)."""
        driven = tuple(j for st in self.steps if isinstance(st, SliderDrive) for j in st.joints)
        return self.numerical + driven

    @property
    def unwritten(self) -> tuple[int, ...]:
        """Joints no step places (none for a complete plan): the solver leaves them NaN."""
        written = {j for st in self.steps for j in st.writes()}
        return tuple(i for i in range(len(self.joint_names)) if i not in written)

    @property
    def sign_steps(self) -> tuple[Any, ...]:
        """The steps that read a sign, in sign order."""
        return tuple(s for s in self.steps if is_sign_step(s))

    @property
    def sign_joints(self) -> tuple[str, ...]:
        """For each sign, the joint it places (for a pivot step, the block joint its guide passes)."""
        return tuple(self.joint_names[s.joint] for s in self.sign_steps)

    def describe(self, nums: tuple[Any, ...] | None = None) -> str:
        """A numbered listing of the steps (with the step numbers of one design, when given)."""
        lines = []
        for i, st in enumerate(self.steps):
            text = st.describe(self.joint_names, nums[i] if nums is not None else None)
            if text is not None:
                lines.append(text)
        return "\n".join(f"{i}. {t}" for i, t in enumerate(lines, 1))


@lru_cache(maxsize=256)
def make_plan(mech: Mechanism, numerical: bool = False) -> Plan:
    """Find a triangulation order; raise a located error when there is none.

    Where no closed-form step applies, the smallest group of joints fixed together by their
    links is placed numerically (:class:`~linkagekit.group.Group`). ``numerical=True``
    prefers such groups to the circle-circle steps (a cross-check of the closed form, and
    ``analyze(..., method="numerical")``). Cached per mechanism (mechanisms are immutable
    and hashable).
    """
    if mech.dof != len(mech.drivers):  # pragma: no cover - the model already refuses it
        raise MechanismFileError(f"{mech.source}: drivers: {len(mech.drivers)} driver(s) for {mech.dof} freedom(s)")
    return _Planner(mech, numerical).plan()


class _Side(Enum):
    """What a side of a slider can be to a candidate numerical group."""

    GROUND = "the ground: a fixed line"
    FRAME = "a link of two joints or more, of the group or placed: it can carry the line"
    POINT = "a link of one joint whose rotation is not known: its joint can be the point on the line"
    TURNED = "a link of one joint whose rotation is known: a constraint the group cannot write"


class _SliderSpec(NamedTuple):
    """A slider of a candidate group, by joint names (see :class:`~linkagekit.group.GroupSlider`)."""

    slider: int
    carrier: str
    frame: tuple[str, str] | None  # None: the ground
    other: str
    point: str
    lock: tuple[str, str] | None

    @property
    def joints(self) -> tuple[str, ...]:
        """The joints its equations read."""
        return (*(self.frame or ()), self.point, *(self.lock or ()))


#: A step that reads a sign, with the joints it makes known, the links whose rotation it makes known, its label.
SignStep = tuple[Step, set[str], set[str], str]


class _Planner:
    """The greedy search of :func:`make_plan`: its state (what is known) and one method per rule.

    The rules are tried in the order of the module's docstring; the first that applies acts,
    and the search starts over, until none applies.
    """

    def __init__(self, mech: Mechanism, numerical: bool) -> None:
        self.mech, self.numerical = mech, numerical
        self.names = tuple(mech.joints)
        self.idx = {n: i for i, n in enumerate(self.names)}
        self.links = {ln.name: ln for ln in mech.links}
        ground = self.links[GROUND].joints
        self.known: set[str] = set(ground)  # joints placed
        self.placed: set[str] = {GROUND}  # links placed
        self.rot_known: set[str] = {GROUND}  # links whose rotation is known
        self.steps: list[Step] = [Ground(tuple(self.idx[j] for j in ground))]
        self.mirror_links: list[str] = []
        self.labels: list[str] = []  # one per sign
        self.anchors: dict[str, int] = {}  # a known joint of each placed link, where its frame is anchored
        self.slider_of = {s.link: (i, s) for i, s in enumerate(mech.sliders)}
        self.drives: list[tuple[int, CrankType | SliderType]] = []  # applied as soon as their pivot or guide is known
        self.cylinders: list[tuple[int, CylinderType]] = []  # applied one at a time, once links are placed
        for di, d in enumerate(mech.drivers):
            match d.type:
                case CrankType() | SliderType() as t:
                    self.drives.append((di, t))
                case CylinderType() as c:
                    self.cylinders.append((di, c))
                case _:
                    assert_never(d.type)

    def plan(self) -> Plan:
        """Apply the rules until none applies, check every joint is placed, and return the plan."""
        # with ``numerical`` a cylinder's end, or an actuator's pin, goes into a numerical group when one holds it
        closed = not self.numerical
        while (
            self._place_links()
            or self._drive(actuators=closed)
            or (closed and self._cylinder())
            or self._line_line()
            or self._sign_or_group()
            or self._cylinder()
            or self._drive()
        ):
            pass
        self._check_complete()
        self._check_groups_fixed()
        needs = {link for st in self.steps for link in st.rotation_needs()}
        steps = [_keep_rotation(st, needs) for st in self.steps]
        mech = self.mech
        drivers = tuple(d.name for d in mech.drivers)
        labels, mirrors = tuple(self.labels), tuple(self.mirror_links)
        return Plan(self.names, tuple(steps), len(labels), len(mirrors), mech.dof, drivers, mirrors, labels)

    def _take(self, link: str, anchor: int, joints: tuple[str, ...] | None = None) -> None:
        """``link`` placed (its rotation known, its frame anchored at joint ``anchor``), with its joints."""
        self.known.update(self.links[link].joints if joints is None else joints)
        self.placed.add(link)
        self.rot_known.add(link)
        self.anchors[link] = anchor

    # ------------------------------------------------------------------ rules
    def _place_links(self) -> bool:
        """Place every link with two known joints, carry every link with one known joint and a known rotation."""
        progress = False
        for ln in self.mech.links:
            if ln.name in self.placed:
                continue
            kn = [j for j in ln.joints if j in self.known]
            rest = tuple(self.idx[j] for j in ln.joints if j not in self.known)
            if len(kn) >= 2:
                mirror = None
                if rest and len(ln.joints) >= 3:
                    mirror = len(self.mirror_links)
                    self.mirror_links.append(ln.name)
                self.steps.append(Place(ln.name, self.idx[kn[0]], self.idx[kn[1]], rest, mirror))
            elif len(kn) == 1 and (rot_from := self._rotation_from(ln.name)) is not None:
                self.steps.append(Carry(ln.name, rot_from, self.idx[kn[0]], rest))
            else:
                continue
            self._take(ln.name, self.idx[kn[0]])
            progress = True
        return progress

    def _rotation_from(self, link: str) -> str | None:
        """The link whose rotation ``link`` shares: itself if known, else the guide of its slider."""
        if link in self.rot_known:
            return link
        if link in self.slider_of and self.slider_of[link][1].on in self.rot_known:
            return self.slider_of[link][1].on
        return None

    def _drive(self, actuators: bool = True) -> bool:
        """Apply every crank whose pivot is known and every slider driver whose guide is placed."""
        acted = False
        for di, t in list(self.drives):
            match t:
                case CrankType():
                    done = self._crank(di, t)
                case SliderType():
                    done = self._slider_drive(di, t, actuators)
                case _:
                    assert_never(t)
            if done:
                self.drives.remove((di, t))
                acted = True
        return acted

    def _crank(self, di: int, t: CrankType) -> bool:
        """Driver ``di`` turns its link about its known pivot: its ``toward`` joint placed (:class:`Crank`)."""
        d = self.mech.drivers[di]
        if t.toward in self.known and t.pivot not in self.known and d.link not in self.placed:
            raise MechanismFileError(
                f"{self.mech.source}: drivers[{di}]: link '{d.link}' turns about its pivot '{t.pivot}', but its "
                f"toward joint '{t.toward}' is the one fixed before it: swap them "
                f"(pivot: {t.toward}, toward: {t.pivot})"
            )
        if d.link in self.placed or t.toward in self.known:
            raise MechanismFileError(
                f"{self.mech.source}: drivers[{di}]: link '{d.link}' is already fixed by the rest of the "
                f"mechanism; the drivers do not match its freedom"
            )
        if t.pivot not in self.known:
            return False
        self.steps.append(Crank(di, d.link, self.idx[t.pivot], self.idx[t.toward]))
        self.known.add(t.toward)
        return True

    def _slider_drive(self, di: int, t: SliderType, actuator: bool = True) -> bool:
        """Driver ``di`` pushes a block along its placed guide: the block placed (:class:`SliderDrive`)."""
        d, s = self.mech.drivers[di], self.mech.sliders[t.slider]
        if d.link in self.placed:
            raise MechanismFileError(
                f"{self.mech.source}: drivers[{di}]: block '{d.link}' is already fixed by the rest of the "
                f"mechanism; the drivers do not match its freedom"
            )
        if s.on not in self.rot_known or s.on not in self.placed:
            return actuator and self._actuator(di, t)
        blk = self.links[s.link]
        joints = tuple(self.idx[j] for j in blk.joints)
        self.steps.append(SliderDrive(di, t.slider, s.link, s.on, self.anchors.get(s.on), joints))
        self._take(s.link, self.idx[blk.joints[0]])
        return True

    def _actuator(self, di: int, t: SliderType) -> bool:
        """Driver ``di`` between two moving links: a barrel (the guide) and a rod (the block), each with a pin.

        Once one pin is known and the other is on a link with a known joint, the driver sets
        the pins' distance: the free pin is placed as a cylinder's free end (:class:`ActuatorDyad`),
        then the barrel's turn is known, and the barrel and the rod are carried.
        """
        mech, s = self.mech, self.mech.sliders[t.slider]
        if s.on in self.rot_known or s.link in self.rot_known:
            return False
        on_barrel = [j for j in self.links[s.on].joints if j in self.known]
        on_rod = [j for j in self.links[s.link].joints if j in self.known]
        if on_barrel and on_rod:
            raise MechanismFileError(
                f"{mech.source}: drivers[{di}]: both pins of slider {t.slider} ('{on_barrel[0]}' on '{s.on}', "
                f"'{on_rod[0]}' on '{s.link}') are already fixed by the rest of the mechanism, so it cannot set "
                f"their distance; the drivers do not match its freedom"
            )
        if not (on_barrel or on_rod):
            return False
        known_pin, free_side = (on_barrel[0], s.link) if on_barrel else (on_rod[0], s.on)
        for end in self.links[free_side].joints:
            anchored = {k: ln.name for ln, k in self._anchored(end) if ln.name not in (s.on, s.link)}
            if len(anchored) >= 2:
                fixers = " and ".join(f"'{n}'" for n in anchored.values())
                raise MechanismFileError(
                    f"{mech.source}: drivers[{di}]: links {fixers} already fix '{end}', a pin of slider {t.slider}, "
                    f"so it cannot set its length; the drivers do not match the mechanism's freedom"
                )
            for k, link in anchored.items():
                pins = (known_pin, end) if on_barrel else (end, known_pin)
                self._add_actuator(di, t, (end, k, known_pin), link, pins)
                return True
        return False

    def _add_actuator(
        self, di: int, t: SliderType, joints: tuple[str, str, str], link: str, pins: tuple[str, str]
    ) -> None:
        """Add the :class:`ActuatorDyad` placing ``joints[0]`` from ``joints[1]`` (on ``link``) and the known pin."""
        end, k, known_pin = joints
        idx, barrel = self.idx, self.mech.sliders[t.slider].on
        pin_p, pin_q = (idx[j] for j in pins)
        sign = len(self.labels)
        self.steps.append(
            ActuatorDyad(idx[end], idx[k], idx[known_pin], link, di, t.slider, barrel, pin_p, pin_q, sign)
        )
        self.known.add(end)
        self.rot_known.add(barrel)
        self.labels.append(f"{end}: left of {k}->{known_pin}")

    def _cylinder(self) -> bool:
        """Apply the first cylinder with one end known (then let the links it fixes be placed first)."""
        for ci, c in self.cylinders:
            found = self._cylinder_step(ci, c)
            if found is not None:
                step, joint, label = found
                self.steps.append(step)
                self.known.add(joint)
                self.labels.append(label)
                self.cylinders.remove((ci, c))
                return True  # another cylinder may then be in conflict
        return False

    def _cylinder_step(self, ci: int, c: CylinderType) -> tuple[Step, str, str] | None:
        """The step of cylinder driver ``ci`` once one of its ends is known: (step, joint it places, sign label).

        Its free end is found on a circle of the cylinder's length about the known end, crossed
        with a circle about a known joint of a link through the free end (:class:`CylinderDyad`)
        or with the line of a slider block whose guide is placed (:class:`CylinderLine`).  Both
        ends known already is a conflict: the rest of the mechanism fixes the cylinder's length.
        """
        mech, known, name = self.mech, self.known, self.mech.drivers[ci].name
        a, b = c.ends
        if a in known and b in known:
            raise MechanismFileError(
                f"{mech.source}: drivers[{ci}]: both ends of cylinder '{name}' ({a}, {b}) are already fixed by the "
                f"rest of the mechanism, so it cannot set their distance; the drivers do not match its freedom"
            )
        for end, other in ((b, a), (a, b)):
            if other not in known:
                continue
            free = [ln for ln in mech.links if ln.name not in self.placed and end in ln.joints]
            anchored = {next(j for j in ln.joints if j in known): ln.name for ln in free if set(ln.joints) & known}
            if len(anchored) >= 2:  # two links through `end` with known joints: a triangle, rigid without it
                fixers = " and ".join(f"'{n}'" for n in anchored.values())
                raise MechanismFileError(
                    f"{mech.source}: drivers[{ci}]: links {fixers} already fix '{end}', the end of cylinder "
                    f"'{name}', so it cannot set its length; the drivers do not match the mechanism's freedom"
                )
            for ln in free:
                k = next((j for j in ln.joints if j in known), None)
                if k is not None:
                    step: Step = CylinderDyad(
                        self.idx[end], self.idx[k], self.idx[other], ln.name, ci, len(self.labels)
                    )
                    return step, end, f"{end}: left of {k}->{other}"
            for ln in free:
                if ln.name not in self.slider_of:
                    continue
                si, s = self.slider_of[ln.name]
                if s.on in self.placed:
                    anchor = self.anchors.get(s.on)
                    step = CylinderLine(self.idx[end], self.idx[other], si, s.link, s.on, anchor, ci, len(self.labels))
                    return step, end, f"{end}: ahead of {other} along slider {si}"
        return None

    def _line_line(self) -> bool:
        """Slide a yoke (a block with no known joint, on a placed guide) until a block in it fits (:class:`LineLine`).

        The yoke's position along its guide and the block's along the yoke are the two unknowns
        of two lines crossing.  Parallel slides cannot fix the yoke: refused.
        """
        mech, known, placed = self.mech, self.known, self.placed
        for s2i, s2 in enumerate(mech.sliders):  # the block, sliding in the yoke
            yoke = s2.on
            if yoke in placed or yoke not in self.slider_of or s2.link in placed:
                continue
            pins = [j for j in self.links[s2.link].joints if j in known]
            s1i, s1 = self.slider_of[yoke]
            if not pins or s1.on not in placed or any(j in known for j in self.links[yoke].joints):
                continue
            if abs((s1.direction.conjugate() * s2.direction).imag) <= 1e-9:
                raise MechanismFileError(
                    f"{mech.source}: sliders[{s2i}]: its direction is parallel to that of slider {s1i}, which carries "
                    f"its guide '{yoke}': the block cannot fix where '{yoke}' is along its slide"
                )
            yoke_joints = tuple(self.idx[j] for j in self.links[yoke].joints)
            self.steps.append(LineLine(yoke, s1.on, self.anchors.get(s1.on), s1i, s2i, self.idx[pins[0]], yoke_joints))
            self._take(yoke, yoke_joints[0])
            return True
        return False

    def _sign_or_group(self) -> bool:
        """A step that reads a sign, else the smallest numerical group (the group first when ``numerical``)."""
        group = self._find_group() if self.numerical else None
        found = None if group else self._next_sign_step()
        if found is not None:
            step, newly_known, newly_rot, label = found
            self.steps.append(step)
            self.known.update(newly_known)
            self.rot_known.update(newly_rot)
            self.labels.append(label)
            return True
        if group is None:
            group = self._find_group()
        if group is None:
            return False
        self.steps.append(group)
        self.known.update(self.names[j] for j in group.joints)
        inner = set(group.input_drivers)
        self.cylinders = [(ci, c) for ci, c in self.cylinders if ci not in inner]
        self.drives = [(di, t) for di, t in self.drives if di not in inner]
        for gl in group.links:
            self.placed.add(gl.name)
            self.rot_known.add(gl.name)
            self.anchors[gl.name] = gl.joints[0]
        for gs in group.sliders:  # a side of one joint turns with the carrier
            if gs.other not in self.placed and gs.lock is None:
                self.steps.append(Carry(gs.other, gs.carrier, gs.point_joint, ()))
                self._take(gs.other, gs.point_joint, ())
        return True

    def _next_sign_step(self) -> SignStep | None:
        """The next circle-circle or circle-line step for an unknown joint, else a pivot step, or None."""
        for j in self.mech.joints:
            if j not in self.known:
                found = self._dyad(j) or self._circle_line(j)
                if found is not None:
                    return found
        return self._pivot()

    def _anchored(self, j: str) -> list[tuple[Link, str]]:
        """The unplaced links through joint ``j`` that have a known joint, each with its first known joint."""
        owners = [ln for ln in self.mech.links if j in ln.joints and ln.name not in self.placed]
        return [(ln, next(k for k in ln.joints if k in self.known)) for ln in owners if set(ln.joints) & self.known]

    def _dyad(self, j: str) -> SignStep | None:
        """``j`` on two circles about known joints of two links (:class:`Dyad`)."""
        anchored = self._anchored(j)
        for a, (l1, k1) in enumerate(anchored):
            for l2, k2 in anchored[a + 1 :]:
                if k1 != k2:
                    st = Dyad(self.idx[j], self.idx[k1], self.idx[k2], (l1.name, l2.name), len(self.labels))
                    return st, {j}, set(), f"{j}: left of {k1}->{k2}"
        return None

    def _circle_line(self, j: str) -> SignStep | None:
        """``j`` on a block whose guide is placed, and on a link with one known joint (:class:`CircleLine`)."""
        anchored = self._anchored(j)
        for ln in self.mech.links:
            if j not in ln.joints or ln.name in self.placed or ln.name not in self.slider_of:
                continue
            si, s = self.slider_of[ln.name]
            if s.on not in self.placed or any(k in self.known for k in ln.joints):
                continue
            for l2, k2 in anchored:
                if l2.name != ln.name:
                    anchor = self.anchors.get(s.on)
                    st = CircleLine(self.idx[j], self.idx[k2], l2.name, si, s.link, s.on, anchor, len(self.labels))
                    return st, {j}, set(), f"{j}: ahead of {k2} along slider {si}"
        return None

    def _pivot(self) -> SignStep | None:
        """A block with a known joint slides on a link with exactly one known joint: turn it (:class:`Pivot`)."""
        for si, s in enumerate(self.mech.sliders):
            if s.on in self.placed or s.on in self.rot_known:
                continue
            bj = [k for k in self.links[s.link].joints if k in self.known]
            oj = [k for k in self.links[s.on].joints if k in self.known]
            if bj and len(oj) == 1:
                st = Pivot(si, s.on, self.idx[oj[0]], self.idx[bj[0]], len(self.labels))
                return st, set(), {s.on}, f"{bj[0]}: ahead of {oj[0]} along slider {si}"
        return None

    def _find_group(self) -> Group | None:
        """The smallest set of unknown joints that the links and sliders among them fix (2 equations per joint).

        A link counts ``2 n - 3`` equations (its rigidity, natural coordinates; see
        :mod:`linkagekit.group`) once all its joints are known or in the set; a slider between
        two such sides counts 1 (a point on a line) or 2 (and a rotation lock) equations
        (:meth:`_group_slider`), and a pending cylinder driver with an end in the set and the other
        in it or known counts 1 (its ends' distance is its input). Sets are tried by size, then in
        file order, so the plan is deterministic. Links a pending driver turns or pushes are left to
        the closed-form steps. None when no set fits.
        """
        mech, known = self.mech, self.known
        unknown = [j for j in mech.joints if j not in known]
        # a slider driver between two moving links (an actuator) may be in a group: its displacement is one row
        actuators = {
            t.slider: di
            for di, t in self.drives
            if isinstance(t, SliderType) and mech.sliders[t.slider].on not in self.placed
        }
        driven = {
            mech.drivers[di].link for di, t in self.drives if not (isinstance(t, SliderType) and t.slider in actuators)
        }
        free = [
            (ln, set(ln.joints)) for ln in mech.links if ln.name not in self.placed | driven and len(ln.joints) >= 2
        ]
        sliders = [(si, s) for si, s in enumerate(mech.sliders) if s.link not in driven and s.on not in driven]
        sizes = range(1, len(unknown) + 1) if len(unknown) <= MAX_GROUP_SEARCH else [len(unknown)]
        for size in sizes:
            for subset in combinations(unknown, size):
                inside = set(subset)
                reach = inside | known
                links = [ln for ln, js in free if js & inside and js <= reach]
                if not links:
                    continue
                names = {ln.name for ln in links}
                found = [self._group_slider(si, s, inside, reach, names) for si, s in sliders]
                if False in found:
                    continue
                gsl = [g for g in found if g]
                cyl = [(ci, c.ends) for ci, c in self.cylinders if set(c.ends) & inside and set(c.ends) <= reach]
                # an actuator's displacement: along the line its guide carries (the guide is the carrier)
                drv = [(actuators[g.slider], g.slider) for g in gsl if g.slider in actuators]
                if any(mech.sliders[si].on != next(g.carrier for g in gsl if g.slider == si) for _, si in drv):
                    continue
                rows = sum(2 * len(ln.joints) - 3 for ln in links) + sum(1 + (g.lock is not None) for g in gsl)
                if rows + len(cyl) + len(drv) == 2 * size:
                    return self._group(subset, links, gsl, cyl, drv)
        return None

    def _group_slider(
        self, si: int, s: Slider, inside: set[str], reach: set[str], names: set[str]
    ) -> _SliderSpec | None | Literal[False]:
        """How slider ``si`` constrains the candidate group ``inside`` (links ``names``).

        Its *carrier* carries the line: the ground, or a side with two joints in the group or
        placed. The other side's first joint is the point on the line; when that side has two
        joints too, its rotation is locked to the carrier's (2 equations, else 1). None when
        it does not constrain the group (a side not all in it, or two sides of one joint each:
        those fix nothing by themselves and are left to the closed-form steps); False when it
        does in a way the group cannot write (a side of one joint whose rotation is known): the
        candidate is not a group.
        """
        kinds = {side: self._side(side, reach, names) for side in (s.on, s.link)}
        if None in kinds.values():
            return None
        if _Side.TURNED in kinds.values():
            return False if any(set(self.links[n].joints) & inside for n in kinds if n != GROUND) else None
        carrier = next((side for side in (s.on, s.link) if kinds[side] in (_Side.GROUND, _Side.FRAME)), None)
        other = s.link if carrier == s.on else s.on
        if carrier is None or kinds[other] is _Side.GROUND:
            return None
        cj, oj = self.links[carrier].joints, self.links[other].joints
        frame = (cj[0], cj[1]) if kinds[carrier] is _Side.FRAME else None
        lock = (oj[0], oj[1]) if kinds[other] is _Side.FRAME else None
        spec = _SliderSpec(si, carrier, frame, other, oj[0], lock)
        return spec if set(spec.joints) & inside else None

    def _side(self, name: str, reach: set[str], names: set[str]) -> _Side | None:
        """What link ``name`` can be to a slider of a candidate group (:class:`_Side`), or None (not all its
        joints in ``reach``, or a link of two joints that is neither in the group nor placed)."""
        if name == GROUND:
            return _Side.GROUND
        js = self.links[name].joints
        if not set(js) <= reach:
            return None
        if len(js) >= 2:
            return _Side.FRAME if name in names or name in self.placed else None
        return _Side.TURNED if name in self.rot_known else _Side.POINT

    def _group(
        self,
        subset: tuple[str, ...],
        links: list[Link],
        sliders: list[_SliderSpec],
        cylinders: list[tuple[int, tuple[str, str]]],
        drives: list[tuple[int, int]],
    ) -> Group:
        """The numerical group placing the joints ``subset`` by the rigidity of ``links``, by ``sliders``, by
        the ``cylinders`` (driver index, ends) and by the slider ``drives`` (driver index, slider index)."""
        inside = set(subset)
        slots = {j: i for i, j in enumerate(subset)}
        around = [j for ln in links for j in ln.joints] + [j for g in sliders for j in g.joints]
        around += [j for _, ends in cylinders for j in ends]
        held = list(dict.fromkeys(j for j in around if j not in inside))
        slots.update({j: len(subset) + i for i, j in enumerate(held)})
        group_links = []
        for ln in links:
            order = sorted(ln.joints, key=lambda j: (j in inside, ln.joints.index(j)))  # a known joint first
            group_links.append(GroupLink(ln.name, tuple(slots[j] for j in order), tuple(self.idx[j] for j in order)))
        idx = self.idx

        def pair(js: tuple[str, str] | None, where: dict[str, int]) -> tuple[int, int] | None:
            return (where[js[0]], where[js[1]]) if js else None

        group_sliders = tuple(
            GroupSlider(
                g.slider,
                g.carrier,
                pair(g.frame, slots),
                pair(g.frame, idx),
                slots[g.point],
                idx[g.point],
                g.other,
                pair(g.lock, slots),
                pair(g.lock, idx),
            )
            for g in sliders
        )
        group_cylinders = tuple(GroupCylinder(ci, (slots[a], slots[b]), (idx[a], idx[b])) for ci, (a, b) in cylinders)
        in_group = [g.slider for g in sliders]
        group_drives = tuple(GroupSliderDrive(di, in_group.index(si)) for di, si in drives)
        cyclic = tuple(d.type.cyclic for d in self.mech.drivers)
        joints, known = tuple(idx[j] for j in subset), tuple(idx[j] for j in held)
        return Group(joints, known, tuple(group_links), (), cyclic, group_sliders, group_cylinders, group_drives)

    # ------------------------------------------------------------------ the end
    def _check_complete(self) -> None:
        """Every driver applied and every joint placed, else a located error."""
        mech = self.mech
        for di, t in self.drives:  # a driver whose pivot (or guide) nothing fixed: the file asks for the impossible
            d = mech.drivers[di]
            match t:
                case CrankType():
                    raise MechanismFileError(
                        f"{mech.source}: drivers[{di}]: link '{d.link}' turns about '{t.pivot}', which nothing fixes "
                        f"before it: a driver turns a link about a pivot on the ground (or on a link placed before it)"
                    )
                case SliderType():
                    raise MechanismFileError(
                        f"{mech.source}: drivers[{di}]: slider {t.slider} slides on a link that nothing fixes "
                        f"before it (a slider driver needs its guide '{mech.sliders[t.slider].on}' placed first, or, "
                        f"as an actuator's barrel and rod, one pin placed and the other on a link with a placed joint)"
                    )
                case _:
                    assert_never(t)
        missing = [j for j in self.names if j not in self.known]
        if missing and (free := free_joints(mech)):
            raise MechanismFileError(_loose_message(mech, free))
        if missing:
            raise NotSolvableError(
                f"{mech.source}: no triangulation order places {', '.join(missing)}, and no numerical group does: "
                f"the numerical solver takes groups of links, sliders and cylinder drivers whose equations fix "
                f"their joints"
            )

    def _check_groups_fixed(self) -> None:
        """A numerical group whose equations leave a joint free at every position, not only at the pose, is a loose
        part beside one braced twice (the counts balance): refused, naming the free joints. At the pose alone a valid
        mechanism can also move (a parallelogram posed flat), so the test is at generic positions."""
        if any(isinstance(st, Group) for st in self.steps) and (free := free_joints(self.mech, generic=True)):
            raise MechanismFileError(_loose_message(self.mech, free))


def _loose_message(mech: Mechanism, free: tuple[str, ...]) -> str:
    return (
        f"{mech.source}: joint(s) {', '.join(free)} can move with every driver held: the links do not fix "
        f"them (check the links at {free[0]} and the ground's joints; counting pins missed it because "
        f"another part is braced twice)"
    )


def free_joints(mech: Mechanism, generic: bool = False) -> tuple[str, ...]:
    """The joints of a mechanism that can move at its pose with every driver held (none if it is rigid so): a part
    left loose, which Gruebler's count misses when another part is braced twice.

    The null space of the velocity constraints (:func:`_rate_rows`) over every joint's velocity and every moving
    link's angular velocity; a null vector moves the joints where it is not zero. ``generic``: the same rows at
    joints placed at random about the pose and slides along random directions (a fixed seed), whose rank is the
    structure's (the largest any placing gives): a joint free there is free wherever the mechanism is posed, while
    at the pose alone a rigid mechanism can move to first order (a parallelogram posed flat, a link's three joints
    in a line).

    >>> import linkagekit as lk
    >>> doc = lk.load("examples/seed000_fourbar.yaml").to_dict()
    >>> free_joints(lk.Mechanism.from_dict(doc))
    ()
    >>> doc["links"]["ground"] = ["A", "D"]  # a typo for [A, B]: the crank and coupler braced, the rocker loose
    >>> free_joints(lk.Mechanism.from_dict(doc))
    ('B',)
    """
    import numpy as np

    names = list(mech.joint_names)
    pose = np.array([mech.joints[j] for j in names])
    size = float(np.ptp(pose.real) + np.ptp(pose.imag)) or 1.0  # in units of the mechanism's size: the rows of
    at = {j: (z - pose[0]) / size for j, z in zip(names, pose, strict=True)}  # joints and of link rates alike
    slide = {k: sl.direction for k, sl in enumerate(mech.sliders)}
    if generic:
        rng = np.random.default_rng(0)
        at = {j: at[j] + complex(*rng.normal(size=2)) for j in names}
        slide = {k: complex(*rng.normal(size=2)) for k in slide}
    rows = _rate_rows(mech, at, {k: d / abs(d) for k, d in slide.items()})
    _, sv, vt = np.linalg.svd(rows)
    rank = int(np.sum(sv > 1e-9 * sv[0]))
    null = vt[rank:, : 2 * len(names)].reshape(-1, len(names), 2)
    moving = np.sqrt(np.sum(null**2, axis=(0, 2))) > 1e-6
    return tuple(j for j, m in zip(names, moving, strict=True) if m)


def _rate_rows(mech: Mechanism, at: dict[str, complex], slide: dict[int, complex]) -> Any:
    """The velocity constraints of ``mech`` at joint positions ``at`` (slides along ``slide``, unit, by slider) with
    every driver held, over ``[v_x, v_y]`` of each joint then ``omega`` of each moving link: (rows, columns).

    A link's joints move as one body with its first (``v_j = v_a + omega i (z_j - z_a)``, two rows each); the
    ground's stand still and turn not; a held crank's link does not turn; a slider's block turns with its guide and
    its joint ``through`` keeps off the guide's line (the normal ``n`` of its relative velocity is zero; held by a
    slider driver, the tangent too); a held cylinder keeps its ends' distance.
    """
    import numpy as np

    names = list(mech.joint_names)
    moving = [ln.name for ln in mech.links if ln.name != "ground"]
    col = {j: 2 * k for k, j in enumerate(names)}
    turn = {ln: 2 * len(names) + k for k, ln in enumerate(moving)}
    rows: list[Any] = []

    def row(terms: Sequence[tuple[str, complex]], turns: Sequence[tuple[str, float]] = ()) -> None:
        r = np.zeros(2 * len(names) + len(moving))
        for j, g in terms:
            r[col[j] : col[j] + 2] += (g.real, g.imag)
        for ln, w in turns:
            if ln in turn:
                r[turn[ln]] += w
        rows.append(r)

    def point(link: str, p: complex, g: complex) -> tuple[list[tuple[str, complex]], list[tuple[str, float]]]:
        """``g . v`` of the point of ``link`` at ``p``: on its first joint's velocity and its rate of turn."""
        a = mech.link(link).joints[0]
        return [(a, g)], [(link, (np.conj(g) * 1j * (p - at[a])).real)]

    for ln in mech.links:
        a = ln.joints[0]
        for j in ln.joints[1:] if ln.name != "ground" else ln.joints:
            for g in (1.0, 1j):  # g . (v_j - v_a - omega i (z_j - z_a)) = 0; the ground's: g . v_j = 0
                if ln.name == "ground":
                    row([(j, g)])
                else:
                    row([(j, g), (a, -g)], [(ln.name, -(np.conj(g) * 1j * (at[j] - at[a])).real)])
    for k, sl in enumerate(mech.sliders):
        row([], [(sl.link, 1.0), (sl.on, -1.0)])
        held = any(isinstance(d.type, SliderType) and d.type.slider == k for d in mech.drivers)
        for g in (1j * slide[k], slide[k]) if held else (1j * slide[k],):
            guide = point(sl.on, at[sl.through], g) if sl.on != "ground" else ([], [])
            row([(sl.through, g), *((j, -c) for j, c in guide[0])], [(ln, -w) for ln, w in guide[1]])
    for d in mech.drivers:
        t = d.type
        if isinstance(t, CrankType):
            row([], [(d.link, 1.0)])
        elif isinstance(t, CylinderType):
            e = at[t.ends[0]] - at[t.ends[1]]
            row([(t.ends[0], e), (t.ends[1], -e)])
    return np.array(rows)


def _keep_rotation(st: Step, needs: set[str]) -> Step:
    """``st``, told to keep the rotation of its links that a later step reads."""
    if isinstance(st, Place) and st.link in needs:
        return replace(st, keep_rotation=True)
    if isinstance(st, Group):
        return replace(st, keep_rotation=tuple(g.name for g in st.links if g.name in needs))
    return st


#: at most this many unknown joints are searched for the smallest numerical group (2^n subsets)
MAX_GROUP_SEARCH = 16
