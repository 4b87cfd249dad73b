"""The immutable, validated model of a mechanism.

A :class:`Mechanism` is built once from a file or a dictionary and never changes.
Points are complex numbers ``x + 1j*y`` in the file's length unit; angles are stored in
radians (converted once, here, at the boundary).  Each link carries its *shape*: the
local coordinates of its joints, registered on the reference pose, computed from the
``lengths`` the file gives (or, where it gives none, read off the pose).

Examples
--------
>>> import linkagekit as lk
>>> mech = lk.Mechanism.from_dict({
...     "joints": {"A": [0, 0], "B": [4, 1], "C": [2, 0], "D": [0.8206, 4.8589]},
...     "links": {"ground": ["A", "B"], "crank": ["A", "C"],
...               "coupler": ["C", "D"], "rocker": ["B", "D"]},
...     "drivers": [{"link": "crank", "pivot": "A", "toward": "C"}],
... })
>>> round(mech.link("coupler").length("C", "D"), 4)  # read off the (rounded) pose
5.0
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
import yaml

from . import schema
from .errors import MechanismFileError
from .units import ANGLE_UNITS, LENGTH_UNITS

if TYPE_CHECKING:
    from .plan import Plan

GROUND = "ground"
#: Relative tolerance on lengths: two joints of a link closer than this (relative to the
#: mechanism's size) are "at one spot"; given lengths may disagree by this much.
LENGTH_RTOL = 1e-9


@dataclass(frozen=True)
class Link:
    """A rigid body: its joints and their local coordinates (``shape``)."""

    name: str
    joints: tuple[str, ...]
    shape: dict[str, complex]
    mass: float = 0.0
    cg: complex | None = None  # centre of gravity, local coordinates (same frame as shape)
    inertia: float = 0.0

    def length(self, a: str, b: str) -> float:
        """Distance between two joints of this link."""
        return abs(self.shape[b] - self.shape[a])

    @property
    def has_mass_properties(self) -> bool:
        return self.mass > 0.0 or self.inertia > 0.0


@dataclass(frozen=True)
class Sweep:
    """A default input sweep ``start..stop`` by ``step`` (stop included when it lands on a step)."""

    start: float
    stop: float
    step: float

    def values(self) -> np.ndarray:
        n = math.floor((self.stop - self.start) / self.step * (1 + 1e-12) + 1e-9) + 1
        return self.start + self.step * np.arange(max(n, 1))


@dataclass(frozen=True)
class Driver:
    """One input: a link turned about a pivot (``kind='angle'``) or a slider pushed."""

    name: str
    kind: Literal["angle", "slider"]
    link: str
    sweep: Sweep
    speed: float = 1.0
    acceleration: float = 0.0
    pivot: str | None = None
    toward: str | None = None
    slider: int | None = None


@dataclass(frozen=True)
class Slider:
    """A prismatic joint: ``link`` translates relative to ``on`` along ``direction``."""

    link: str
    on: str
    through: str
    direction: complex  # unit vector, reference pose


@dataclass(frozen=True)
class Load:
    """An external force (N) at a point, and/or a torque (N*m), on one link."""

    link: str
    at: complex | None
    at_joint: str | None
    force: complex
    torque: float


@dataclass(frozen=True)
class Mechanism:
    """A validated planar mechanism.  Build it with :func:`load` or :meth:`from_dict`."""

    name: str
    length_unit: str
    angle_unit: str
    joints: dict[str, complex]
    links: tuple[Link, ...]
    drivers: tuple[Driver, ...]
    sliders: tuple[Slider, ...] = ()
    gravity: complex | None = None
    loads: tuple[Load, ...] = ()
    source: str = "<dict>"
    _by_name: dict[str, Link] = field(default_factory=dict, repr=False, compare=False)

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_dict(cls, data: Any, source: str = "<dict>") -> Mechanism:
        """Validate a mechanism given as nested dictionaries (the file's structure)."""
        spec = schema.parse(data, source)
        return _build(spec, source)

    # ------------------------------------------------------------------ queries
    def link(self, name: str) -> Link:
        return self._by_name[name]

    @property
    def joint_names(self) -> tuple[str, ...]:
        return tuple(self.joints)

    @property
    def length_scale(self) -> float:
        """A characteristic size of the mechanism (for relative tolerances)."""
        pts = np.array(list(self.joints.values()))
        size = float(np.max(np.abs(pts - pts.mean()))) if len(pts) > 1 else 0.0
        lengths = [abs(b - a) for ln in self.links for a in ln.shape.values() for b in ln.shape.values()]
        return max([size, *lengths, 1e-300])

    @property
    def length_to_si(self) -> float:
        return LENGTH_UNITS[self.length_unit]

    @property
    def angle_to_rad(self) -> float:
        return ANGLE_UNITS[self.angle_unit]

    @property
    def has_dynamics(self) -> bool:
        """True when the file gives mass properties, gravity or loads."""
        return bool(self.loads) or self.gravity is not None or any(ln.has_mass_properties for ln in self.links)

    def links_of(self, joint: str) -> tuple[str, ...]:
        return tuple(ln.name for ln in self.links if joint in ln.joints)

    @cached_property
    def plan(self) -> Plan:
        """The solve plan (triangulation order); see :mod:`linkagekit.plan`."""
        from .plan import make_plan

        return make_plan(self)


# ---------------------------------------------------------------------- loading
class _Loader(yaml.SafeLoader):
    """PyYAML's safe loader with YAML 1.2 booleans: only true/false, so `on:` stays a key."""


_Loader.yaml_implicit_resolvers = {
    ch: [(tag, rx) for tag, rx in resolvers if tag != "tag:yaml.org,2002:bool"]
    for ch, resolvers in yaml.SafeLoader.yaml_implicit_resolvers.items()
}
_Loader.add_implicit_resolver(
    "tag:yaml.org,2002:bool", re.compile(r"^(?:true|True|TRUE|false|False|FALSE)$"), list("tTfF")
)


def load(path: str | Path) -> Mechanism:
    """Read a mechanism file (YAML or JSON).  Reading never executes anything.

    Raises
    ------
    MechanismFileError
        With a message naming the file and the offending key.
    """
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise MechanismFileError(f"{p}: no such file") from None
    except IsADirectoryError:
        raise MechanismFileError(f"{p}: is a directory, not a mechanism file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise MechanismFileError(f"{p}: cannot read: {exc}") from None
    try:
        data = json.loads(text) if p.suffix.lower() == ".json" else yaml.load(text, Loader=_Loader)  # noqa: S506 - a safe loader
    except json.JSONDecodeError as exc:
        raise MechanismFileError(
            f"{p}: JSON syntax error at line {exc.lineno}, column {exc.colno}: {exc.msg}"
        ) from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark is not None else ""
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        raise MechanismFileError(f"{p}: YAML syntax error{where}: {problem}") from None
    mech = Mechanism.from_dict(data, source=str(p))
    mech.plan  # noqa: B018  (build the plan now: a file whose drivers do not fit is a file error)
    return mech


# ---------------------------------------------------------------------- building
def _build(spec: schema.FileSpec, src: str) -> Mechanism:
    joints = {name: complex(x, y) for name, (x, y) in spec.joints.items()}

    def fail(key: str, msg: str) -> MechanismFileError:
        return MechanismFileError(f"{src}: {key}: {msg}")

    if GROUND not in spec.links:
        raise fail("links", "no link named 'ground' (the fixed frame)")
    slider_links = {s.link for s in spec.sliders}
    scale = max((abs(a - b) for a in joints.values() for b in joints.values()), default=0.0) or 1.0

    links: list[Link] = []
    used: set[str] = set()
    for lname, lspec in spec.links.items():
        ls = lspec if isinstance(lspec, schema.LinkSpec) else schema.LinkSpec(joints=lspec)
        key = f"links.{lname}"
        for j in ls.joints:
            if j not in joints:
                raise fail(key, f"unknown joint '{j}' (not under joints)")
        if len(set(ls.joints)) != len(ls.joints):
            dup = next(j for j in ls.joints if ls.joints.count(j) > 1)
            raise fail(key, f"joint '{dup}' is listed twice")
        if len(ls.joints) < 2 and lname != GROUND and lname not in slider_links:
            raise fail(key, "a link needs at least two joints (only ground and a slider block may carry one)")
        for i, a in enumerate(ls.joints):
            for b in ls.joints[i + 1 :]:
                if abs(joints[a] - joints[b]) <= LENGTH_RTOL * scale:
                    raise fail(key, f"joints '{a}' and '{b}' are at one spot on one link")
        used.update(ls.joints)
        shape = _shape(lname, ls, joints, fail, scale)
        cg = None
        if ls.cg is not None:
            cg = _register(complex(*ls.cg), tuple(ls.joints), joints, shape)
        if ls.mass is not None and ls.mass < 0:
            raise fail(f"{key}.mass", "must not be negative")
        if ls.inertia is not None and ls.inertia < 0:
            raise fail(f"{key}.inertia", "must not be negative")
        if (ls.mass or 0.0) > 0 and cg is None:
            raise fail(f"{key}.cg", "a link with mass needs its centre of gravity `cg`")
        links.append(Link(lname, tuple(ls.joints), shape, ls.mass or 0.0, cg, ls.inertia or 0.0))

    for j in joints:
        if j not in used:
            raise fail(f"joints.{j}", "not carried by any link")
    by_name = {ln.name: ln for ln in links}

    sliders: list[Slider] = []
    for i, s in enumerate(spec.sliders):
        key = f"sliders[{i}]"
        for attr in ("link", "on"):
            if getattr(s, attr) not in by_name:
                raise fail(f"{key}.{attr}", f"unknown link '{getattr(s, attr)}'")
        if s.link == s.on:
            raise fail(key, "a link cannot slide on itself")
        if s.link == GROUND:
            raise fail(f"{key}.link", "the ground cannot be the sliding block (swap `link` and `on`)")
        if s.through not in joints:
            raise fail(f"{key}.through", f"unknown joint '{s.through}'")
        direction = complex(*s.direction)
        if abs(direction) == 0:
            raise fail(f"{key}.direction", "must not be the zero vector")
        sliders.append(Slider(s.link, s.on, s.through, direction / abs(direction)))

    drivers: list[Driver] = []
    for i, d in enumerate(spec.drivers):
        key = f"drivers[{i}]"
        if d.slider is not None:
            if not 0 <= d.slider < len(sliders):
                raise fail(f"{key}.slider", f"no slider with index {d.slider} (there are {len(sliders)})")
            if d.angles is not None or d.pivot is not None or d.toward is not None:
                raise fail(key, "a slider driver takes `displacements`, not `angles`/`pivot`/`toward`")
            sl = sliders[d.slider]
            if d.link is not None and d.link != sl.link:
                raise fail(f"{key}.link", f"slider {d.slider} moves link '{sl.link}', not '{d.link}'")
            sw = d.displacements or schema.SweepSpec(start=0.0, stop=0.0, step=1.0)
            drivers.append(
                Driver(
                    sl.link,
                    "slider",
                    sl.link,
                    _sweep(sw, f"{key}.displacements", fail),
                    d.speed,
                    d.acceleration,
                    slider=d.slider,
                )
            )
            continue
        if d.link is None:
            raise fail(f"{key}.link", "required key is missing (or give `slider:`)")
        if d.link not in by_name:
            raise fail(f"{key}.link", f"unknown link '{d.link}'")
        if d.link == GROUND:
            raise fail(f"{key}.link", "the ground cannot be driven")
        if d.displacements is not None:
            raise fail(key, "`displacements` belongs to a slider driver (`slider: INDEX`)")
        link = by_name[d.link]
        for attr in ("pivot", "toward"):
            j = getattr(d, attr)
            if j is None:
                raise fail(f"{key}.{attr}", "required key is missing")
            if j not in link.joints:
                raise fail(f"{key}.{attr}", f"joint '{j}' is not on link '{d.link}'")
        if d.pivot == d.toward:
            raise fail(key, "`pivot` and `toward` must be different joints")
        sw = d.angles or schema.SweepSpec(
            start=0.0,
            stop=360.0 if spec.units.angle == "deg" else 2 * math.pi,
            step=1.0 if spec.units.angle == "deg" else math.pi / 180,
        )
        # speed and acceleration are rad/s and rad/s^2 whatever the angle unit (spec section 1)
        drivers.append(
            Driver(
                d.link,
                "angle",
                d.link,
                _sweep(sw, f"{key}.angles", fail),
                d.speed,
                d.acceleration,
                pivot=d.pivot,
                toward=d.toward,
            )
        )
    names = [d.name for d in drivers]
    for n in names:
        if names.count(n) > 1:
            raise fail("drivers", f"link '{n}' is driven twice")

    loads: list[Load] = []
    for i, ld in enumerate(spec.loads):
        key = f"loads[{i}]"
        if ld.link not in by_name:
            raise fail(f"{key}.link", f"unknown link '{ld.link}'")
        if ld.force is None and ld.torque is None:
            raise fail(key, "give a `force`, a `torque`, or both")
        at_joint = None
        at: complex | None = None
        if isinstance(ld.at, str):
            if ld.at not in by_name[ld.link].joints:
                raise fail(f"{key}.at", f"joint '{ld.at}' is not on link '{ld.link}'")
            at_joint = ld.at
            at = by_name[ld.link].shape[ld.at]
        elif ld.at is not None:
            at = _register(complex(*ld.at), by_name[ld.link].joints, joints, by_name[ld.link].shape)
        if ld.force is not None and at is None:
            raise fail(f"{key}.at", "a force needs its point of application `at`")
        loads.append(Load(ld.link, at, at_joint, complex(*(ld.force or (0.0, 0.0))), ld.torque or 0.0))

    return Mechanism(
        name=spec.name,
        length_unit=spec.units.length,
        angle_unit=spec.units.angle,
        joints=joints,
        links=tuple(links),
        drivers=tuple(drivers),
        sliders=tuple(sliders),
        gravity=complex(*spec.gravity) if spec.gravity is not None else None,
        loads=tuple(loads),
        source=src,
        _by_name=by_name,
    )


def _sweep(sw: schema.SweepSpec, key: str, fail: Any) -> Sweep:
    if sw.step == 0:
        raise fail(f"{key}.step", "must not be zero")
    if (sw.stop - sw.start) * sw.step < 0:
        raise fail(f"{key}.step", "goes away from `stop`: its sign must be that of stop - start")
    if abs(sw.stop - sw.start) / abs(sw.step) > 1e8:
        raise fail(key, "more than 10^8 samples")
    return Sweep(sw.start, sw.stop, sw.step)


def _parse_pair(key: str, link: tuple[str, ...]) -> tuple[str, str] | None:
    parts = key.split("-")
    if len(parts) == 2 and parts[0] in link and parts[1] in link and parts[0] != parts[1]:
        return parts[0], parts[1]
    # joint names may themselves contain '-': try every split point
    for i in range(1, len(key)):
        if key[i] == "-" and key[:i] in link and key[i + 1 :] in link and key[:i] != key[i + 1 :]:
            return key[:i], key[i + 1 :]
    return None


def _shape(lname: str, ls: schema.LinkSpec, pose: dict[str, complex], fail: Any, scale: float) -> dict[str, complex]:
    """Local coordinates of a link's joints, registered on the pose, honouring given lengths.

    The first two joints anchor the frame (the first at its pose position, the second on
    the pose direction).  Every further joint is placed by its distances to the two
    anchors, on the side of the anchor line where the pose has it (the mirror image).
    """
    js = tuple(ls.joints)
    given: dict[frozenset[str], float] = {}
    for k, v in (ls.lengths or {}).items():
        pair = _parse_pair(k, js)
        if pair is None:
            raise fail(f"links.{lname}.lengths.{k}", f"expected 'X-Y' with X and Y two joints of link '{lname}'")
        if v <= 0:
            raise fail(f"links.{lname}.lengths.{k}", "a length must be positive")
        given[frozenset(pair)] = v

    def dist(a: str, b: str) -> float:
        return given.get(frozenset((a, b)), abs(pose[b] - pose[a]))

    if len(js) == 1:
        return {js[0]: pose[js[0]]}
    a, b = js[0], js[1]
    u = (pose[b] - pose[a]) / abs(pose[b] - pose[a])
    base = dist(a, b)
    shape = {a: pose[a], b: pose[a] + base * u}
    for k in js[2:]:
        if not given.keys() & {frozenset((a, b)), frozenset((a, k)), frozenset((b, k))}:
            # all three lengths come from the pose: take its shape as it is (no square root,
            # which would turn the rounding of a flat triangle into an error of ~1e-8)
            shape[k] = shape[a] + (pose[k] - pose[a]) / (pose[b] - pose[a]) * (shape[b] - shape[a])
            continue
        d1, d2 = dist(a, k), dist(b, k)
        along = (d1 * d1 + base * base - d2 * d2) / (2 * base)
        h2 = d1 * d1 - along * along
        if h2 < -LENGTH_RTOL * max(d1, base) ** 2 * 4:
            raise fail(f"links.{lname}.lengths", f"the lengths {a}-{b}, {a}-{k}, {b}-{k} cannot form a triangle")
        side = 1.0 if ((pose[b] - pose[a]).conjugate() * (pose[k] - pose[a])).imag >= 0 else -1.0
        shape[k] = shape[a] + complex(along, side * math.sqrt(max(h2, 0.0))) * u
    for pair_set, v in given.items():
        p, q = tuple(pair_set)
        if abs(abs(shape[q] - shape[p]) - v) > 1e-7 * max(v, scale * 1e-3):
            raise fail(
                f"links.{lname}.lengths.{p}-{q}",
                f"{v:g} contradicts the other lengths of the link (they give {abs(shape[q] - shape[p]):.9g})",
            )
    return shape


def _register(
    point: complex, link_joints: tuple[str, ...], pose: dict[str, complex], shape: dict[str, complex]
) -> complex:
    """Express a pose point of a link in the link's shape frame (ratio to its two anchors)."""
    if len(link_joints) < 2:
        return point - pose[link_joints[0]] + shape[link_joints[0]]
    a, b = link_joints[0], link_joints[1]
    ratio = (point - pose[a]) / (pose[b] - pose[a])
    return shape[a] + ratio * (shape[b] - shape[a])
