"""Solve plan: the topology of a mechanism as an ordered list of steps.

The plan says which joint each step places, from which joints, and which sign or mirror
slot it reads; it holds no dimension at all (those are in :mod:`linkagekit.params`), so one
plan serves every design of a topology.  It is hashable and picklable and is computed
without solving anything: a greedy search for a triangulation order,

1. start from the ground joints;
2. repeatedly place every link with two known joints (``Place``), carry every link with
   one known joint whose rotation is known (``Carry``), apply every driver whose pivot or
   guide is known (``Crank``, ``SliderDrive``);
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
from .steps import Carry, CircleLine, Crank, Dyad, Ground, Pivot, Place, SliderDrive, Step, is_sign_step

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
def make_plan(mech: Mechanism) -> Plan:
    """Find a triangulation order; raise a located error when there is none.

    Cached per mechanism (mechanisms are immutable and hashable).
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
    pending = list(range(len(mech.drivers)))
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
        found = _next_sign_step(mech, idx, known, placed, rot_known, slider_of, anchors, len(labels))
        if found is None:
            break
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
            f"{mech.source}: no triangulation order places {what}: this mechanism needs the numerical solver "
            f"(an Assur group of class 3 or more, or a slider arrangement not handled in closed form), "
            f"which linkagekit does not have yet"
        )
    needs = {link for st in steps for link in st.rotation_needs()}
    steps = [replace(st, keep_rotation=True) if isinstance(st, Place) and st.link in needs else st for st in steps]
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
