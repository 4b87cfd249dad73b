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
   known joint through a known block joint (``Pivot``); each of these reads one sign.

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

from dataclasses import dataclass, replace
from functools import lru_cache
from typing import TYPE_CHECKING, Any

from .errors import MechanismFileError, NotSolvableError
from .group import Group, GroupLink
from .steps import (
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
    from .model import Mechanism

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
    names = tuple(mech.joints)
    idx = {n: i for i, n in enumerate(names)}
    if mech.dof != len(mech.drivers):  # pragma: no cover - the model already refuses it
        raise MechanismFileError(f"{mech.source}: drivers: {len(mech.drivers)} driver(s) for {mech.dof} freedom(s)")

    links = {ln.name: ln for ln in mech.links}
    known: set[str] = set(links[GROUND].joints)
    placed: set[str] = {GROUND}
    steps: list[Step] = [Ground(tuple(idx[j] for j in links[GROUND].joints))]
    rot_known: set[str] = {GROUND}
    pending = [i for i, d in enumerate(mech.drivers) if d.kind != "cylinder"]
    cylinders = [i for i, d in enumerate(mech.drivers) if d.kind == "cylinder"]  # not in `pending`: see below
    mirror_links: list[str] = []
    slider_of = {s.link: (i, s) for i, s in enumerate(mech.sliders)}
    labels: list[str] = []
    anchors: dict[str, int] = {}  # a known joint of each placed link, where its frame is anchored

    def place_all() -> bool:
        progress = False
        for ln in mech.links:
            if ln.name in placed:
                continue
            kn = [j for j in ln.joints if j in known]
            if len(kn) >= 2:
                k1, k2 = kn[0], kn[1]
                rest = [j for j in ln.joints if j not in known]
                mirror = None
                if rest and len(ln.joints) >= 3:
                    mirror = len(mirror_links)
                    mirror_links.append(ln.name)
                steps.append(Place(ln.name, idx[k1], idx[k2], tuple(idx[j] for j in rest), mirror))
                anchors[ln.name] = idx[k1]
            elif len(kn) == 1:
                rot_from = None
                if ln.name in rot_known:
                    rot_from = ln.name
                elif ln.name in slider_of and slider_of[ln.name][1].on in rot_known:
                    rot_from = slider_of[ln.name][1].on
                if rot_from is None:
                    continue
                rest = [j for j in ln.joints if j not in known]
                steps.append(Carry(ln.name, rot_from, idx[kn[0]], tuple(idx[j] for j in rest)))
                anchors[ln.name] = idx[kn[0]]
            else:
                continue
            known.update(ln.joints)
            placed.add(ln.name)
            rot_known.add(ln.name)
            progress = True
        return progress

    while True:
        if place_all():
            continue
        acted = False
        for di in list(pending):  # drivers, as soon as they can act
            d = mech.drivers[di]
            if d.kind == "angle":
                assert d.pivot is not None and d.toward is not None
                if d.link in placed or d.toward in known:
                    raise MechanismFileError(
                        f"{mech.source}: drivers[{di}]: link '{d.link}' is already fixed by the rest of the "
                        f"mechanism; the drivers do not match its freedom"
                    )
                if d.pivot in known:
                    steps.append(Crank(di, d.link, idx[d.pivot], idx[d.toward]))
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
                    blk = links[s.link]
                    anchor = anchors.get(s.on)
                    steps.append(SliderDrive(di, d.slider, s.link, s.on, anchor, tuple(idx[j] for j in blk.joints)))
                    anchors[s.link] = idx[blk.joints[0]]
                    known.update(blk.joints)
                    placed.add(s.link)
                    rot_known.add(s.link)
                    pending.remove(di)
                    acted = True
        if acted:
            continue
        for ci in list(cylinders):  # a cylinder acts once one end is known: a circle of its length about it
            cyl = _cylinder_step(mech, idx, known, placed, slider_of, anchors, ci, len(labels))
            if cyl is not None:
                steps.append(cyl[0])
                known.add(cyl[1])
                labels.append(cyl[2])
                cylinders.remove(ci)
                acted = True
                break  # let the links it fixes be placed first (another cylinder may then be in conflict)
        if acted:
            continue
        yoke = _line_line_step(mech, idx, known, placed, slider_of, anchors)
        if yoke is not None:
            steps.append(yoke)
            known.update(links[yoke.yoke].joints)
            placed.add(yoke.yoke)
            rot_known.add(yoke.yoke)
            anchors[yoke.yoke] = yoke.joints[0]
            continue
        group = _find_group(mech, idx, known, placed, slider_of, pending) if numerical else None
        found = None if group else _next_sign_step(mech, idx, known, placed, rot_known, slider_of, anchors, len(labels))
        if found is None:
            if group is None:
                group = _find_group(mech, idx, known, placed, slider_of, pending)
            if group is None:
                break
            steps.append(group)
            known.update(names[j] for j in group.joints)
            for gl in group.links:
                placed.add(gl.name)
                rot_known.add(gl.name)
                anchors[gl.name] = gl.joints[0]
            continue
        step, newly_known, newly_rot, label = found
        steps.append(step)
        known.update(newly_known)
        rot_known.update(newly_rot)
        labels.append(label)

    missing = [j for j in names if j not in known]
    for di in pending:  # a driver whose pivot (or guide) nothing fixed: the file asks for the impossible
        d = mech.drivers[di]
        if d.kind == "angle":
            raise MechanismFileError(
                f"{mech.source}: drivers[{di}]: link '{d.link}' turns about '{d.pivot}', which nothing fixes "
                f"before it: a driver turns a link about a pivot on the ground (or on a link placed before it)"
            )
        raise MechanismFileError(
            f"{mech.source}: drivers[{di}]: slider {d.slider} slides on a link that nothing fixes before it"
        )
    if missing:
        what = ", ".join(missing)
        raise NotSolvableError(
            f"{mech.source}: no triangulation order places {what}, and no numerical group does: the numerical "
            f"solver takes groups of revolute joints only (a slider or a cylinder inside an Assur group of "
            f"class 3 or more is not handled yet)"
        )
    needs = {link for st in steps for link in st.rotation_needs()}
    steps = [replace(st, keep_rotation=True) if isinstance(st, Place) and st.link in needs else st for st in steps]
    steps = [
        replace(st, keep_rotation=tuple(g.name for g in st.links if g.name in needs)) if isinstance(st, Group) else st
        for st in steps
    ]
    return Plan(
        names,
        tuple(steps),
        len(labels),
        len(mirror_links),
        mech.dof,
        tuple(d.name for d in mech.drivers),
        mirror_links=tuple(mirror_links),
        sign_labels=tuple(labels),
    )


def _cylinder_step(  # type: ignore[no-untyped-def]
    mech, idx, known, placed, slider_of, anchors, ci, n_signs
) -> tuple[Step, str, str] | None:
    """The step of cylinder driver ``ci`` once one of its ends is known: (step, joint it places, sign label).

    Its free end is found on a circle of the cylinder's length about the known end, crossed
    with a circle about a known joint of a link through the free end (:class:`CylinderDyad`)
    or with the line of a slider block whose guide is placed (:class:`CylinderLine`).  Both
    ends known already is a conflict: the rest of the mechanism fixes the cylinder's length.
    """
    d = mech.drivers[ci]
    a, b = d.ends
    if a in known and b in known:
        raise MechanismFileError(
            f"{mech.source}: drivers[{ci}]: both ends of cylinder '{d.name}' ({a}, {b}) are already fixed by the "
            f"rest of the mechanism, so it cannot set their distance; the drivers do not match its freedom"
        )
    for end, other in ((b, a), (a, b)):
        if other not in known:
            continue
        anchored = {
            next(j for j in ln.joints if j in known): ln.name
            for ln in mech.links
            if ln.name not in placed and end in ln.joints and any(j in known for j in ln.joints)
        }
        if len(anchored) >= 2:  # two links through `end` with known joints: a triangle, rigid without it
            fixers = " and ".join(f"'{n}'" for n in anchored.values())
            raise MechanismFileError(
                f"{mech.source}: drivers[{ci}]: links {fixers} already fix '{end}', the end of cylinder "
                f"'{d.name}', so it cannot set its length; the drivers do not match the mechanism's freedom"
            )
        for ln in mech.links:
            if ln.name in placed or end not in ln.joints:
                continue
            k = next((j for j in ln.joints if j in known), None)
            if k is not None:
                step: Step = CylinderDyad(idx[end], idx[k], idx[other], ln.name, ci, n_signs)
                return step, end, f"{end}: left of {k}->{other}"
        for ln in mech.links:
            if ln.name in placed or end not in ln.joints or ln.name not in slider_of:
                continue
            si, s = slider_of[ln.name]
            if s.on in placed and not any(j in known for j in ln.joints):
                step = CylinderLine(idx[end], idx[other], si, s.link, s.on, anchors.get(s.on), ci, n_signs)
                return step, end, f"{end}: ahead of {other} along slider {si}"
    return None


def _line_line_step(mech, idx, known, placed, slider_of, anchors) -> LineLine | None:  # type: ignore[no-untyped-def]
    """A yoke (a slider block with no known joint, on a placed guide) fixed by a block with a known joint sliding in it.

    The yoke's position along its guide and the block's along the yoke are the two unknowns
    of two lines crossing (:class:`LineLine`).  Parallel slides cannot fix the yoke: refused.
    """
    links = {ln.name: ln for ln in mech.links}
    for s2i, s2 in enumerate(mech.sliders):  # the block, sliding in the yoke
        yoke = s2.on
        if yoke in placed or yoke not in slider_of or s2.link in placed:
            continue
        pins = [j for j in links[s2.link].joints if j in known]
        s1i, s1 = slider_of[yoke]
        if not pins or s1.on not in placed or any(j in known for j in links[yoke].joints):
            continue
        if abs((s1.direction.conjugate() * s2.direction).imag) <= 1e-9:
            raise MechanismFileError(
                f"{mech.source}: sliders[{s2i}]: its direction is parallel to that of slider {s1i}, which carries its "
                f"guide '{yoke}': the block cannot fix where '{yoke}' is along its slide"
            )
        yoke_joints = tuple(idx[j] for j in links[yoke].joints)
        return LineLine(yoke, s1.on, anchors.get(s1.on), s1i, s2i, idx[pins[0]], yoke_joints)
    return None


def _next_sign_step(mech, idx, known, placed, rot_known, slider_of, anchors, n_signs):  # type: ignore[no-untyped-def]
    """The next circle-circle, circle-line or pivot step, or None when there is none."""
    links = {ln.name: ln for ln in mech.links}
    for j in mech.joints:
        if j in known:
            continue
        owners = [ln for ln in mech.links if j in ln.joints and ln.name not in placed]
        anchored = [
            (ln, next(k for k in ln.joints if k in known)) for ln in owners if any(k in known for k in ln.joints)
        ]
        for a in range(len(anchored)):  # two circles
            for b in range(a + 1, len(anchored)):
                (l1, k1), (l2, k2) = anchored[a], anchored[b]
                if k1 == k2:
                    continue
                st = Dyad(idx[j], idx[k1], idx[k2], (l1.name, l2.name), n_signs)
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
                    st = CircleLine(idx[j], idx[k2], l2.name, si, s.link, s.on, anchors.get(s.on), n_signs)
                    return st, {j}, set(), f"{j}: ahead of {k2} along slider {si}"
    # pivot: a block with a known joint slides on a link with exactly one known joint
    for si, s in enumerate(mech.sliders):
        if s.on in placed or s.on in rot_known:
            continue
        bj = [k for k in links[s.link].joints if k in known]
        oj = [k for k in links[s.on].joints if k in known]
        if bj and len(oj) == 1:
            st = Pivot(si, s.on, idx[oj[0]], idx[bj[0]], n_signs)
            return st, set(), {s.on}, f"{bj[0]}: ahead of {oj[0]} along slider {si}"
    return None


#: at most this many unknown joints are searched for the smallest numerical group (2^n subsets)
MAX_GROUP_SEARCH = 16


def _find_group(mech, idx, known, placed, slider_of, pending):  # type: ignore[no-untyped-def]
    """The smallest set of unknown joints that the links among them fix (2 equations per joint), or None.

    A link counts ``2 n - 3`` equations (its rigidity, natural coordinates; see
    :mod:`linkagekit.group`) once all its joints are known or in the set. Sets are tried by
    size, then in file order, so the plan is deterministic. Slider blocks and guides, and
    links a pending driver turns, are left to the closed-form steps.
    """
    from itertools import combinations

    unknown = [j for j in mech.joints if j not in known]
    if not unknown:
        return None
    driven = {mech.drivers[di].link for di in pending}
    sliding = set(slider_of) | {s.on for s in mech.sliders}
    free = [ln for ln in mech.links if ln.name not in placed and ln.name not in driven and ln.name not in sliding]
    sizes = range(1, len(unknown) + 1) if len(unknown) <= MAX_GROUP_SEARCH else [len(unknown)]
    for size in sizes:
        for subset in combinations(unknown, size):
            inside = set(subset)
            links = [
                ln
                for ln in free
                if len(ln.joints) >= 2
                and any(j in inside for j in ln.joints)
                and all(j in inside or j in known for j in ln.joints)
            ]
            if sum(2 * len(ln.joints) - 3 for ln in links) != 2 * size:
                continue
            slots = {j: i for i, j in enumerate(subset)}
            held = [j for ln in links for j in ln.joints if j not in inside]
            held = list(dict.fromkeys(held))
            for i, j in enumerate(held):
                slots[j] = size + i
            group_links = []
            for ln in links:
                order = sorted(ln.joints, key=lambda j: (j in inside, ln.joints.index(j)))  # a known joint first
                group_links.append(GroupLink(ln.name, tuple(slots[j] for j in order), tuple(idx[j] for j in order)))
            angular = tuple(d.kind == "angle" for d in mech.drivers)
            return Group(tuple(idx[j] for j in subset), tuple(idx[j] for j in held), tuple(group_links), (), angular)
    return None
