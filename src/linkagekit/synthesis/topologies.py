"""The path topologies ``synthesize`` knows, declared once: built of dyads on one crank, named.

Every topology is a template mechanism with a driver ``crank`` (pivot ``A``, tip ``C``) and
a tracer point ``P``: a crank, then RRR dyads, each a new joint ``k`` on two new binary links
to two places already there; a place is a joint, a new ground pivot, or a new point of a
moving link (that link becomes ternary). The tracer is a point of a moving link. A dyad's
two places must lie on different bodies (else ``k`` is rigidly fixed to one of them), so
each dyad keeps one degree of freedom. Two rules keep only the topologies that are not a
smaller one in disguise: the tracer's link carries no ground pivot (else ``P`` draws an arc),
and the tracer moves with every moving joint (each dyad is an ancestor of the tracer's link).

Joints are counted as ``--max-joints`` counts them: ground pivots and ``P`` included. The four-bar
has 5 joints; Watt II and Stephenson III (``watt2``, ``stephenson3``, hand-drawn in
:mod:`.space`) have 8 and are found again by the enumeration, under their own names. The
others are named ``<links>bar-<k>``: ``sixbar-1``, ``eightbar-12``, ... numbered in the
enumeration's order (which is deterministic); :data:`NAMED` maps a structure to its name.

Two enumerated mechanisms that differ only by the names of their joints are one topology:
each is reduced to a canonical form (colour refinement of the joint graph, then the
smallest adjacency over the orderings within colour classes).

Examples
--------
>>> [t.name for t in enumerate_topologies(6)]
['fourbar', 'sixbar-1']
>>> [len(enumerate_topologies(n)) for n in (7, 8, 9, 10)]
[16, 84, 311, 636]
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from functools import cache, lru_cache

from ..errors import InputError

#: the fewest joints a path topology has (the four-bar: A, B, C, D and P)
MIN_JOINTS = 5
#: ``--max-joints``' default
MAX_JOINTS = 10
#: the most links (ground included) of an enumerated topology: four-, six- and eight-bars
MAX_LINKS = 8
#: the most joints the enumeration goes to (beyond, the count of topologies explodes)
ENUMERATED_JOINTS = 10

# names of joints in the order they are made (A, C first; P is the tracer's)
_NAMES = "ABCDEFGHIJKLMNOQRSTUVWXYZ"
# joint labels of the canonical form
_PIVOT, _TIP, _GROUND, _MOVING, _TRACER = "A", "C", "g", "j", "P"


@dataclass(frozen=True)
class Topology:
    """One topology: a template's links and a pose, its tracer and its dyads' transmission angles.

    Attributes
    ----------
    name : str
        ``fourbar``, ``watt2``, ``stephenson3`` or ``<links>bar-<k>``.
    links : tuple of (str, tuple of str)
        ``(link name, its joints)``; ``ground`` and ``crank`` (``A``, ``C``) among them.
    transmission : tuple of (joint, a, b)
        The angle ``a - joint - b`` of each dyad (kept within ``[MIN, 180 - MIN]``).
    order : tuple of str
        The joints in the order they are placed (the tracer ``P`` last).
    """

    name: str
    links: tuple[tuple[str, tuple[str, ...]], ...]
    transmission: tuple[tuple[str, str, str], ...]
    order: tuple[str, ...]

    @property
    def n_joints(self) -> int:
        """Joints, ground pivots and ``P`` included."""
        return len(self.order)

    @property
    def n_links(self) -> int:
        """Links, ground included."""
        return len(self.links)

    @property
    def tracer_link(self) -> tuple[str, ...]:
        """The joints of the link that carries ``P`` (``P`` last)."""
        return next(j for _, j in self.links if "P" in j)

    def pose(self) -> dict[str, list[float]]:
        """A reference pose in the unit square (:func:`_pose`: every dyad well open)."""
        return _pose(self)


# ----------------------------------------------------------------------------- enumeration
@dataclass(frozen=True)
class _State:
    """A partial mechanism: joints (by index), links (joint index tuples), who placed each joint."""

    ground: tuple[int, ...]  # ground joints (0 = A first)
    links: tuple[tuple[int, ...], ...]  # links[0] = ground, links[1] = crank
    parents: tuple[tuple[int, ...], ...]  # per joint: the joints it is placed from (() for ground)
    dyads: tuple[tuple[int, int, int], ...]  # (k, a, b): joint k on links to a and b

    @property
    def n(self) -> int:
        return len(self.parents)


def _start() -> _State:
    """A (0, ground pivot) and C (1, the crank's tip)."""
    return _State((0,), ((0,), (0, 1)), ((), (0,)), ())


def _places(s: _State) -> list[tuple[str, int]]:
    """Where a dyad's end may go: ``("joint", i)``, ``("ground", -1)``, ``("point", link index)``."""
    out: list[tuple[str, int]] = [("joint", i) for i in range(s.n)]
    out.append(("ground", -1))
    out += [("point", li) for li in range(1, len(s.links))]
    return out


def _bodies(s: _State, place: tuple[str, int]) -> set[int]:
    """The links (indices) a place is fixed to."""
    kind, i = place
    if kind == "joint":
        return {li for li, ln in enumerate(s.links) if i in ln}
    return {0} if kind == "ground" else {i}


def _put(s: _State, place: tuple[str, int]) -> tuple[_State, int]:
    """``s`` with the place made a joint if new; and its joint index."""
    kind, i = place
    if kind == "joint":
        return s, i
    k = s.n
    links = list(s.links)
    if kind == "ground":
        links[0] = (*links[0], k)
        return _State((*s.ground, k), tuple(links), (*s.parents, ()), s.dyads), k
    links[i] = (*links[i], k)
    return _State(s.ground, tuple(links), (*s.parents, links[i][:2]), s.dyads), k


def _add_dyad(s: _State, p: tuple[str, int], q: tuple[str, int]) -> _State | None:
    """``s`` with a dyad on places ``p`` and ``q``; None when both lie on one body (rigid)."""
    if _bodies(s, p) & _bodies(s, q) or (p[0] == "ground" and q[0] == "ground") or p == q:
        return None
    if p[0] == "point" and q[0] == "point" and p[1] == q[1]:
        return None
    s, a = _put(s, p)
    s, b = _put(s, q)
    k = s.n
    links = (*s.links, (a, k), (b, k))
    return _State(s.ground, links, (*s.parents, (a, b)), (*s.dyads, (k, a, b)))


def _ancestors(s: _State, joints: tuple[int, ...]) -> set[int]:
    seen: set[int] = set()
    todo = list(joints)
    while todo:
        j = todo.pop()
        if j not in seen:
            seen.add(j)
            todo += s.parents[j]
    return seen


def _tracer_links(s: _State) -> list[int]:
    """Links that may carry ``P``: moving, no ground pivot on them, moving with every moving joint."""
    moving = set(range(s.n)) - set(s.ground)
    on = [sum(j in ln for ln in s.links) for j in range(s.n)]
    return [
        li
        for li, ln in enumerate(s.links)
        if li > 1
        and not set(ln) & set(s.ground)
        and moving <= _ancestors(s, ln)
        and all(on[j] >= 2 or j in ln for j in moving)
    ]


def _grow(max_joints: int, max_links: int) -> list[tuple[_State, int]]:
    """Every (mechanism, tracer link) with at most ``max_joints`` joints (``P`` counted), duplicates included."""
    out: list[tuple[_State, int]] = []
    frontier = [_start()]
    seen: set[tuple[object, ...]] = set()
    while frontier:
        nxt = []
        for s in frontier:
            for p, q in itertools.combinations(_places(s), 2):
                t = _add_dyad(s, p, q)
                if t is None or t.n + 1 > max_joints or len(t.links) > max_links:
                    continue
                key = _canonical(t, -1)
                if key in seen:
                    continue
                seen.add(key)
                nxt.append(t)
                out += [(t, li) for li in _tracer_links(t)]
        frontier = nxt
    return out


# ------------------------------------------------------------------------- canonical form
def _labels_edges(s: _State, tracer: int) -> tuple[list[str], set[tuple[int, int]]]:
    """Joint labels (``P`` as the last joint, when a tracer link is given) and the joint graph's edges."""
    labels = [_PIVOT, _TIP] + [_GROUND if i in s.ground else _MOVING for i in range(2, s.n)]
    links = [list(ln) for ln in s.links]
    if tracer >= 0:
        labels.append(_TRACER)
        links[tracer].append(s.n)
    edges = {(min(a, b), max(a, b)) for ln in links for a, b in itertools.combinations(ln, 2)}
    return labels, edges


def _canonical(s: _State, tracer: int) -> tuple[object, ...]:
    """A form equal for two mechanisms exactly when they differ only by joint names.

    A triangle of binary links never occurs (it would be rigid), so the joint graph with
    every link a clique, and the labels, say which joints share a link.
    """
    labels, edges = _labels_edges(s, tracer)
    n = len(labels)
    adj = [[(min(a, b), max(a, b)) in edges for b in range(n)] for a in range(n)]
    colour = list(labels)
    for _ in range(n):  # colour refinement
        new = [f"{colour[a]}|{sorted(colour[b] for b in range(n) if adj[a][b])}" for a in range(n)]
        ranks = {c: str(r) for r, c in enumerate(sorted(set(new)))}
        new = [ranks[c] for c in new]
        if len(set(new)) == len(set(colour)):
            colour = new
            break
        colour = new
    classes = [[a for a in range(n) if colour[a] == c] for c in sorted(set(colour))]
    best: tuple[object, ...] | None = None
    for perm in itertools.product(*(itertools.permutations(c) for c in classes)):
        order = [a for part in perm for a in part]
        form = (tuple(labels[a] for a in order), tuple(adj[a][b] for a in order for b in order))
        if best is None or form < best:
            best = form
    assert best is not None
    return best


# ------------------------------------------------------------------------------- topologies
def _topology(s: _State, tracer: int, name: str) -> Topology:
    """The named template of a state and its tracer link (joints lettered in placing order)."""
    letter = _letters(s)
    links: list[tuple[str, tuple[str, ...]]] = [("ground", tuple(letter[j] for j in s.links[0]))]
    links.append(("crank", ("A", "C")))
    for k, ln in enumerate(s.links[2:], start=2):
        joints = tuple(letter[j] for j in ln) + (("P",) if k == tracer else ())
        links.append((f"link{k - 1}", joints))
    if s.links[1] != (0, 1):
        links[1] = ("crank", tuple(letter[j] for j in s.links[1]))
    transmission = tuple((letter[k], letter[a], letter[b]) for k, a, b in s.dyads)
    order = (*(letter[j] for j in range(s.n)), "P")
    return Topology(name, tuple(links), transmission, order)


def _letters(s: _State) -> list[str]:
    """A, C for the crank; then B, D, E, ... in placing order (P skipped)."""
    rest = iter(c for c in _NAMES if c not in "ACP")
    return ["A", "C"] + [next(rest) for _ in range(2, s.n)]


_BAR_NAMES = {4: "fourbar", 6: "sixbar", 8: "eightbar", 10: "tenbar", 12: "twelvebar"}


@cache
def _all(max_joints: int, max_links: int = MAX_LINKS) -> tuple[Topology, ...]:
    found: dict[tuple[object, ...], tuple[_State, int]] = {}
    for s, li in _grow(max_joints, max_links):
        found.setdefault(_canonical(s, li), (s, li))
    named = _named_forms()
    counts: dict[int, int] = {}
    out = []
    for form, (s, li) in sorted(found.items(), key=lambda kv: (kv[1][0].n, _order_key(kv[1]))):
        bars = len(s.links)
        if form in named:
            name = named[form]
        else:
            counts[bars] = counts.get(bars, 0) + 1
            name = f"{_BAR_NAMES.get(bars, f'{bars}link')}-{counts[bars]}"
        out.append(_topology(s, li, name))
    return tuple(out)


def _order_key(item: tuple[_State, int]) -> tuple[object, ...]:
    s, li = item
    return (len(s.links), s.dyads, s.links, li)


@lru_cache(maxsize=1)
def _named_forms() -> dict[tuple[object, ...], str]:
    """The canonical forms of the hand-drawn templates of :mod:`.space` (``fourbar``, ``watt2``, ``stephenson3``)."""
    s = _add_dyad(_start(), ("joint", 1), ("ground", -1))  # four-bar: D on C and B
    assert s is not None
    rocker = next(li for li, ln in enumerate(s.links) if ln == (2, 3))  # B-D
    coupler = next(li for li, ln in enumerate(s.links) if ln == (1, 3))  # C-D
    out = {_canonical(s, coupler): "fourbar"}  # P on the coupler
    watt = _add_dyad(s, ("point", rocker), ("ground", -1))
    steph = _add_dyad(s, ("point", coupler), ("ground", -1))
    assert watt is not None and steph is not None
    out[_canonical(watt, len(watt.links) - 2)] = "watt2"  # P on F-G
    out[_canonical(steph, len(steph.links) - 2)] = "stephenson3"  # P on E-G
    return out


def enumerate_topologies(max_joints: int = MAX_JOINTS) -> tuple[Topology, ...]:
    """Every topology with at most ``max_joints`` joints (ground pivots and ``P`` counted), fewest joints first.

    Raises
    ------
    InputError
        ``max_joints`` below :data:`MIN_JOINTS` or above :data:`ENUMERATED_JOINTS`.
    """
    if not isinstance(max_joints, int) or not MIN_JOINTS <= max_joints <= ENUMERATED_JOINTS:
        raise InputError(
            f"--max-joints: expected a whole number from {MIN_JOINTS} (a four-bar and its tracer) "
            f"to {ENUMERATED_JOINTS}, got {max_joints!r}"
        )
    return _all(max_joints)


def by_name(name: str) -> Topology:
    """A topology of :func:`enumerate_topologies` (up to :data:`ENUMERATED_JOINTS` joints) by its name."""
    for t in _all(ENUMERATED_JOINTS):
        if t.name == name:
            return t
    raise InputError(f"topology: no topology named '{name}'")


# ------------------------------------------------------------------------------------- pose
def _pose(t: Topology) -> dict[str, list[float]]:
    """A pose where every dyad is well open: ground pivots and points spread, dyad joints off their base.

    Joints are placed in order: ground pivots on a ring, a dyad's joint at the apex of an
    isosceles triangle over its two places (its height a fraction of the base that changes
    side and size from joint to joint), a new point of a link and ``P`` likewise over the
    link's first two joints.
    """
    parents = {k: (a, b) for k, a, b in t.transmission}
    links = dict(t.links)
    ground = links["ground"]
    pos: dict[str, complex] = {"A": 0j, "C": 0.3 + 0.1j}
    for k, j in enumerate(t.order[1:]):
        if j in pos:
            continue
        if j in ground:
            g = ground.index(j)
            pos[j] = complex(math.cos(0.9 * g), math.sin(0.9 * g)) * (0.8 + 0.15 * g)
        elif j in parents:  # alternate sides and heights: two dyads on the same two places stay apart
            pos[j] = _apex(pos[parents[j][0]], pos[parents[j][1]], (0.5 + 0.13 * k) * (-1) ** k)
        else:  # a point of a link, or P
            host = next(ln for name, ln in t.links if j in ln and name != "ground")
            pos[j] = _apex(pos[host[0]], pos[host[1]], 0.4 - 0.1 * k)
    return {j: [round(z.real, 6), round(z.imag, 6)] for j, z in pos.items()}


def _apex(a: complex, b: complex, h: float) -> complex:
    return (a + b) / 2 + 1j * h * (b - a)
