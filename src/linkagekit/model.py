"""The immutable, validated model of a mechanism.

A :class:`Mechanism` is built once from a file or a dictionary and never changes: its
mappings are read-only (:class:`FrozenMap`), every other container is a tuple, and it is
hashable and compares by value.  Building one checks the file's consistency (names,
dimensions, degrees of freedom) but runs no solver.

Points are complex numbers ``x + 1j*y`` in the file's length unit; angles are stored in
radians (converted once, here, at the boundary).  Each link carries its *shape*: the
local coordinates of its joints, registered on the reference pose, computed from the
``lengths`` the file gives (or, where it gives none, read off the pose).  The model also
keeps what the file said (given lengths, points in the pose frame, description), so that
:meth:`Mechanism.to_dict` writes it back: ``Mechanism.from_dict(m.to_dict()) == m``.

This module imports only the standard library, NumPy and the package's ``errors`` and
``units``; the file schema (pydantic) is imported when a mechanism is first built, and
reading and writing files lives in :mod:`linkagekit.files`.

Examples
--------
>>> from linkagekit.model import Mechanism
>>> mech = Mechanism.from_dict({
...     "joints": {"A": [0, 0], "B": [4, 1], "C": [2, 0], "D": [0.8206, 4.8589]},
...     "links": {"ground": ["A", "B"], "crank": ["A", "C"],
...               "coupler": ["C", "D"], "rocker": ["B", "D"]},
...     "drivers": [{"link": "crank", "pivot": "A", "toward": "C"}],
... })
>>> round(mech.link("coupler").length("C", "D"), 4)  # read off the (rounded) pose
5.0
>>> mech.dof, mech.has_given_lengths
(1, False)
>>> Mechanism.from_dict(mech.to_dict()) == mech
True
"""

from __future__ import annotations

import math
import sys
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar, Literal, TypeVar

import numpy as np

from .errors import MechanismFileError, UnknownNameError, shorten
from .units import ANGLE_UNITS, LENGTH_UNITS, UnitKind

if TYPE_CHECKING:
    from .schema import DriverSpec, FileSpec, LinkSpec, SweepSpec

GROUND = "ground"
#: Relative tolerance on lengths: two joints of a link closer than this (relative to the
#: mechanism's size) are "at one spot"; given lengths may disagree by this much.
LENGTH_RTOL = 1e-9
#: the least a mechanism may span (the largest distance between two of its joints, in its length unit): the
#: squares of lengths underflow below 1e-154 (a four-bar at 1e-160 said "assembled" with no positions, a triad
#: at 1e-200 crashed) and a numerical group's fourth powers below 1e-77; at 1e-40 the examples solve as at full
#: size to 1e-15, and a file with joints 1e-12 apart (a slider's, its stroke 0.2) is solved
MIN_SIZE = 1e-30
FORMAT = "linkagekit/1"

K = TypeVar("K")
V = TypeVar("V")
E = TypeVar("E", "Spring", "Damper")


class FrozenMap(Mapping[K, V]):
    """A read-only, hashable mapping (insertion order kept, as a ``dict``).

    Equal to any mapping with the same items (order aside, as for ``dict``).

    Examples
    --------
    >>> m = FrozenMap({"A": 1.0, "B": 2.0})
    >>> m["A"], len(m), m == {"B": 2.0, "A": 1.0}, hash(m) == hash(FrozenMap({"B": 2.0, "A": 1.0}))
    (1.0, 2, True, True)
    >>> m["A"] = 3.0
    Traceback (most recent call last):
    ...
    TypeError: 'FrozenMap' object does not support item assignment
    """

    __slots__ = ("_d", "_hash")

    def __init__(self, items: Mapping[K, V] | Any = ()) -> None:
        self._d: dict[K, V] = dict(items)
        self._hash: int | None = None

    def __getitem__(self, key: K) -> V:
        return self._d[key]

    def __iter__(self) -> Iterator[K]:
        return iter(self._d)

    def __len__(self) -> int:
        return len(self._d)

    def __contains__(self, key: object) -> bool:
        return key in self._d

    def __hash__(self) -> int:
        # from the items, order aside (equal mappings compare equal whatever their order)
        if self._hash is None:
            self._hash = hash(frozenset(self._d.items()))
        return self._hash

    def __eq__(self, other: object) -> bool:
        if isinstance(other, FrozenMap):
            return self._d == other._d
        if isinstance(other, Mapping):
            return self._d == dict(other.items())
        return NotImplemented

    def __repr__(self) -> str:
        return f"FrozenMap({self._d!r})"

    def __reduce__(self) -> tuple[type[FrozenMap[K, V]], tuple[dict[K, V]]]:
        return (type(self), (self._d,))


@dataclass(frozen=True)
class Link:
    """A rigid body: its joints and their local coordinates (``shape``).

    Attributes
    ----------
    name : str
        The link's name (``ground`` is the fixed frame).
    joints : tuple of str
        Its joints, in the file's order (the first two anchor its frame).
    shape : FrozenMap of str to complex
        Local coordinates of its joints, registered on the reference pose.
    mass, inertia : float
        kg and kg*m^2 (about the centre of gravity); 0 when not given.
    cg : complex or None
        Centre of gravity in the shape frame (same frame as ``shape``).
    lengths : FrozenMap of str to float
        The ``lengths`` the file gave (``"X-Y"`` -> length), exactly as given; empty if none.
    cg_pose : complex or None
        The centre of gravity as the file gave it, in the reference pose frame.
    written_as_mapping : bool
        Whether the file wrote the link as a mapping (``{joints: [...]}``); formatting only,
        not compared.
    """

    name: str
    joints: tuple[str, ...]
    shape: FrozenMap[str, complex]
    mass: float = 0.0
    cg: complex | None = None  # centre of gravity, local coordinates (same frame as shape)
    inertia: float = 0.0
    lengths: FrozenMap[str, float] = field(default_factory=FrozenMap)
    cg_pose: complex | None = None
    written_as_mapping: bool = field(default=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "joints", tuple(self.joints))
        if not isinstance(self.shape, FrozenMap):
            object.__setattr__(self, "shape", FrozenMap(self.shape))
        if not isinstance(self.lengths, FrozenMap):
            object.__setattr__(self, "lengths", FrozenMap(self.lengths))

    def length(self, a: str, b: str) -> float:
        """Distance between two joints of this link."""
        return abs(self.shape[b] - self.shape[a])

    @property
    def has_mass_properties(self) -> bool:
        """True when the link has a positive mass or inertia."""
        return self.mass > 0.0 or self.inertia > 0.0

    def to_dict(self) -> list[str] | dict[str, Any]:
        """The link as the file writes it: a plain list of joints, or a mapping."""
        out: dict[str, Any] = {"joints": list(self.joints)}
        if self.lengths:
            out["lengths"] = {k: float(v) for k, v in self.lengths.items()}
        if self.mass != 0.0:
            out["mass"] = float(self.mass)
        if self.cg_pose is not None:
            out["cg"] = _xy(self.cg_pose)
        if self.inertia != 0.0:
            out["inertia"] = float(self.inertia)
        if len(out) == 1 and not self.written_as_mapping:
            return list(self.joints)
        return out


@dataclass(frozen=True)
class Sweep:
    """A default input sweep ``start..stop`` by ``step`` (stop included when it lands on a step)."""

    start: float
    stop: float
    step: float

    def count(self) -> int:
        """How many values :meth:`values` has."""
        return steps_count(self.start, self.stop, self.step)

    def values(self) -> np.ndarray:
        """The sweep's input values (file units); the last is ``stop`` itself when a step lands on it.

        >>> Sweep(0, 0.3, 0.1).values().tolist()
        [0.0, 0.1, 0.2, 0.3]
        """
        return stepped(self.start, self.stop, self.step, self.count())

    def ends(self) -> tuple[float, float]:
        """The first and the last of :meth:`values`, without them all.

        >>> Sweep(0, 78.58, 1).ends(), Sweep(0, 0.3, 0.1).ends()
        ((0.0, 78.0), (0.0, 0.3))
        """
        n = self.count()
        last = self.start + self.step * (n - 1)  # as stepped() computes it
        if n > 1 and abs(last - self.stop) <= _landing(self.start, self.stop, self.step):
            last = self.stop
        return float(self.start), float(last)

    def to_dict(self) -> dict[str, float]:
        """``{start, stop, step}`` as the file writes it."""
        return {"start": float(self.start), "stop": float(self.stop), "step": float(self.step)}


def _landing(start: float, stop: float, step: float) -> float:
    """How near ``stop`` a step must land to count as landing on it: 1e-9 of a step, and the rounding of numbers of
    the size of ``start`` and ``stop`` (``10000.8 - 10000.7`` is 0.1 only to 1.5e-12: 99.999999998 steps of 0.001,
    and the sweep lost its ``stop``)."""
    return 1e-9 * abs(step) + 8 * float(np.finfo(float).eps) * max(abs(start), abs(stop))


def steps_count(start: float, stop: float, step: float) -> int:
    """How many values ``start, start + step, ...`` up to ``stop`` (``stop`` itself where a step lands on it).

    >>> steps_count(10000.7, 10000.8, 0.001), steps_count(0, 0.35, 0.1)
    (101, 4)
    """
    return max(math.floor((stop - start) / step * (1 + 1e-12) + _landing(start, stop, step) / abs(step)) + 1, 1)


def stepped(start: float, stop: float, step: float, count: int) -> np.ndarray:
    """``start + k step`` for ``k < count``, the last value exactly ``stop`` when it is within rounding of it.

    ``0 + 3 * 0.1`` is 0.30000000000000004: a sweep written to stop at 0.3 ends at 0.3 (within 1e-9 of a
    step, the tolerance by which :meth:`Sweep.count` counts ``stop`` as landed on).

    >>> stepped(0, 0.3, 0.1, 4).tolist()
    [0.0, 0.1, 0.2, 0.3]
    >>> stepped(0, 0.35, 0.1, 4).tolist()[-1]
    0.30000000000000004
    """
    values = start + step * np.arange(count, dtype=float)
    if count > 1 and abs(values[-1] - stop) <= _landing(start, stop, step):
        values[-1] = stop
    return values


# ---------------------------------------------------------------------- driver types
class _DriverType:
    """What each driver type declares once (the subclasses below; see :class:`Driver`).

    Attributes
    ----------
    tag : str
        The type's name in files and in ``Driver.kind``: ``"angle"``, ``"slider"`` or ``"cylinder"``.
    sweep_key : str
        The file key of its default sweep (``angles``, ``displacements``, ``lengths``).
    cyclic : bool
        Whether an input value repeats every turn (an angle) rather than runs along a line.
    input_kind : UnitKind
        What its input measures: an angle, or a length.
    effort : UnitKind
        What holds its input: a torque (``T[...]`` in N·m), or a force (``F[...]`` in N).
    """

    tag: ClassVar[Literal["angle", "slider", "cylinder"]]
    sweep_key: ClassVar[str]
    cyclic: ClassVar[bool]
    input_kind: ClassVar[UnitKind]
    effort: ClassVar[UnitKind]

    def input_unit(self, mech: Mechanism) -> str:
        """The unit of its input values in the file and in every output (the file's angle or length unit)."""
        return self.input_kind.symbol(mech.length_unit, mech.angle_unit)

    def input_scale(self, mech: Mechanism) -> float:
        """Solver units per file unit of its input: rad per angle unit, 1 for a length."""
        raise NotImplementedError

    def rate_to_si(self, length_to_si: float) -> float:
        """SI units per unit of its ``speed`` (rad/s whatever the angle unit, or length unit/s -> m/s)."""
        raise NotImplementedError

    def search_span(self, size: float) -> tuple[float, float]:
        """Where its input is searched for assembly (solver units), ``size`` twice the links' sizes summed."""
        raise NotImplementedError

    def file_entry(self, name: str, link: str, sweep: Sweep) -> dict[str, Any]:
        """Its keys of a file's driver entry (speed and acceleration aside)."""
        raise NotImplementedError


@dataclass(frozen=True)
class CrankType(_DriverType):
    """A link turned about ``pivot`` (its input: the angle of ``pivot -> toward``, counter-clockwise)."""

    pivot: str
    toward: str
    tag: ClassVar[Literal["angle"]] = "angle"
    sweep_key: ClassVar[str] = "angles"
    cyclic: ClassVar[bool] = True
    input_kind: ClassVar[UnitKind] = UnitKind.ANGLE
    effort: ClassVar[UnitKind] = UnitKind.TORQUE

    def input_scale(self, mech: Mechanism) -> float:
        return mech.angle_to_rad

    def rate_to_si(self, length_to_si: float) -> float:
        return 1.0  # speeds are rad/s, accelerations rad/s^2, whatever the angle unit

    def search_span(self, size: float) -> tuple[float, float]:
        return 0.0, 2 * math.pi  # a turn

    def file_entry(self, name: str, link: str, sweep: Sweep) -> dict[str, Any]:
        return {"link": link, "pivot": self.pivot, "toward": self.toward, "angles": sweep.to_dict()}


class _LinearType(_DriverType):
    """A driver whose input is a length (file length unit) held by a force."""

    cyclic: ClassVar[bool] = False
    input_kind: ClassVar[UnitKind] = UnitKind.LENGTH
    effort: ClassVar[UnitKind] = UnitKind.FORCE

    def input_scale(self, mech: Mechanism) -> float:
        return 1.0

    def rate_to_si(self, length_to_si: float) -> float:
        return length_to_si


@dataclass(frozen=True)
class SliderType(_LinearType):
    """A slider pushed: block of slider ``slider`` displaced along its line (its input; 0 at the pose).

    ``stroke`` ``(min, max)`` bounds the displacement (samples outside do not assemble), as a
    cylinder's bounds its length: an actuator written as a barrel, a rod and a slider.
    """

    slider: int
    stroke: tuple[float, float] | None = None
    tag: ClassVar[Literal["slider"]] = "slider"
    sweep_key: ClassVar[str] = "displacements"

    def search_span(self, size: float) -> tuple[float, float]:
        if self.stroke is None:
            return -size, size
        return _around(self.stroke)

    def file_entry(self, name: str, link: str, sweep: Sweep) -> dict[str, Any]:
        out: dict[str, Any] = {"slider": self.slider, "displacements": sweep.to_dict()}
        if self.stroke is not None:
            out["stroke"] = [float(self.stroke[0]), float(self.stroke[1])]
        return out


@dataclass(frozen=True)
class CylinderType(_LinearType):
    """A linear actuator between joints ``ends`` (on two links): it imposes ``|A - B| = s``, its input.

    Not a link; ``stroke`` ``(min, max)`` bounds ``s`` (samples outside do not assemble).
    """

    ends: tuple[str, str]
    stroke: tuple[float, float] | None = None
    tag: ClassVar[Literal["cylinder"]] = "cylinder"
    sweep_key: ClassVar[str] = "lengths"

    def search_span(self, size: float) -> tuple[float, float]:
        if self.stroke is None:
            return 0.0, size
        return _around(self.stroke)

    def file_entry(self, name: str, link: str, sweep: Sweep) -> dict[str, Any]:
        out: dict[str, Any] = {"cylinder": list(self.ends)}
        if name != cylinder_name(*self.ends):
            out["name"] = name
        out["lengths"] = sweep.to_dict()
        if self.stroke is not None:
            out["stroke"] = [float(self.stroke[0]), float(self.stroke[1])]
        return out


def _around(stroke: tuple[float, float]) -> tuple[float, float]:
    """A stroke and 1 % of it either side (where an input bounded by it is searched)."""
    lo, hi = stroke
    return lo - 0.01 * (hi - lo), hi + 0.01 * (hi - lo)


#: Every driver type; a new kind of driver is one more class here (and one more case where a
#: ``match`` on it must decide: the planner, the force solve, the pose inputs).
DriverType = CrankType | SliderType | CylinderType


@dataclass(frozen=True)
class Driver:
    """One input of a mechanism: its name, the link it moves, its default sweep and rates, and its type.

    ``type`` says what kind of input it is (:class:`CrankType`, :class:`SliderType`,
    :class:`CylinderType`) and holds all that depends on it: the unit of its input, its
    conversion to solver units, the effort that holds it, how the file writes it.

    ``speed`` and ``acceleration`` are rad/s and rad/s^2 for a crank (whatever the angle
    unit), length-unit/s and length-unit/s^2 for a slider or cylinder.  A cylinder's
    ``link`` is ``""`` (it is not a link).

    Examples
    --------
    >>> d = Driver("crank", "crank", Sweep(0.0, 360.0, 1.0), CrankType("A", "C"))
    >>> d.kind, d.type.cyclic, d.type.effort.name, d.pivot, d.stroke
    ('angle', True, 'TORQUE', 'A', None)
    >>> d.to_dict()
    {'link': 'crank', 'pivot': 'A', 'toward': 'C', 'angles': {'start': 0.0, 'stop': 360.0, 'step': 1.0}}
    """

    name: str
    link: str
    sweep: Sweep
    type: DriverType
    speed: float = 1.0
    acceleration: float = 0.0

    @property
    def kind(self) -> Literal["angle", "slider", "cylinder"]:
        """The type's tag (``"angle"``, ``"slider"``, ``"cylinder"``), as files and earlier versions name it."""
        return self.type.tag

    def input_unit(self, mech: Mechanism) -> str:
        """The unit of this driver's input values (the file's angle or length unit)."""
        return self.type.input_unit(mech)

    def input_scale(self, mech: Mechanism) -> float:
        """Solver units (rad or length unit) per file unit of this driver's input."""
        return self.type.input_scale(mech)

    # read-only views of the type's fields (None where the type has no such field)
    @property
    def pivot(self) -> str | None:
        """A crank's pivot joint."""
        return self.type.pivot if isinstance(self.type, CrankType) else None

    @property
    def toward(self) -> str | None:
        """A crank's second joint (its input is the angle of ``pivot -> toward``)."""
        return self.type.toward if isinstance(self.type, CrankType) else None

    @property
    def slider(self) -> int | None:
        """A slider driver's slider index."""
        return self.type.slider if isinstance(self.type, SliderType) else None

    @property
    def ends(self) -> tuple[str, str] | None:
        """A cylinder's two joints."""
        return self.type.ends if isinstance(self.type, CylinderType) else None

    @property
    def stroke(self) -> tuple[float, float] | None:
        """The bounds ``(min, max)`` of the input, if given: a cylinder's length, a slider's displacement."""
        return self.type.stroke if isinstance(self.type, CylinderType | SliderType) else None

    def to_dict(self) -> dict[str, Any]:
        """The driver as the file writes it."""
        out = self.type.file_entry(self.name, self.link, self.sweep)
        if self.speed != 1.0:
            out["speed"] = float(self.speed)
        if self.acceleration != 0.0:
            out["acceleration"] = float(self.acceleration)
        return out


def cylinder_name(a: str, b: str) -> str:
    """The default name of a cylinder driver between joints ``a`` and ``b``: ``"a-b"``."""
    return f"{a}-{b}"


@dataclass(frozen=True)
class Slider:
    """A prismatic joint: ``link`` translates relative to ``on`` along ``direction``.

    ``direction`` is the unit vector (reference pose); ``direction_given`` the vector as the
    file gave it (formatting only, not compared).
    """

    link: str
    on: str
    through: str
    direction: complex  # unit vector, reference pose
    direction_given: complex | None = field(default=None, compare=False)

    def to_dict(self) -> dict[str, Any]:
        """The slider as the file writes it."""
        d = self.direction if self.direction_given is None else self.direction_given
        return {"link": self.link, "on": self.on, "through": self.through, "direction": _xy(d)}


@dataclass(frozen=True)
class Load:
    """An external force (N) at a point, and/or a torque (N*m), on one link.

    ``at`` is the point of application in the link's shape frame (None without a force
    point); ``at_joint`` the joint name when the file named one; ``at_pose`` the point as
    the file gave it in the reference pose frame when it gave a point.
    """

    link: str
    at: complex | None
    at_joint: str | None
    force: complex
    torque: float
    at_pose: complex | None = None

    def to_dict(self) -> dict[str, Any]:
        """The load as the file writes it."""
        out: dict[str, Any] = {"link": self.link}
        if self.at_joint is not None:
            out["at"] = self.at_joint
        elif self.at_pose is not None:
            out["at"] = _xy(self.at_pose)
        if "at" in out:
            out["force"] = _xy(self.force)
        if self.torque != 0.0 or "force" not in out:
            out["torque"] = float(self.torque)
        return out


def element_name(a: str, b: str) -> str:
    """The default name of a spring or damper between joints ``a`` and ``b``: ``"a-b"`` (as a cylinder's)."""
    return cylinder_name(a, b)


@dataclass(frozen=True)
class Spring:
    """A linear spring between two joints (on two different links).

    Its tension ``stiffness * (length - free_length)`` (N; positive pulls the joints together)
    acts along the line between them.  ``stiffness`` is N/m, ``free_length`` in the file's
    length unit (converted to metres once, by the force solve).
    """

    between: tuple[str, str]
    stiffness: float
    free_length: float = 0.0
    name: str = ""

    def __post_init__(self) -> None:
        _name_element(self)

    def to_dict(self) -> dict[str, Any]:
        """The spring as the file writes it."""
        return _element_dict(self, {"stiffness": float(self.stiffness), "free_length": float(self.free_length)})


@dataclass(frozen=True)
class Damper:
    """A linear damper between two joints: tension ``damping * d(length)/dt`` (N, N*s/m), opposing the change."""

    between: tuple[str, str]
    damping: float
    name: str = ""

    def __post_init__(self) -> None:
        _name_element(self)

    def to_dict(self) -> dict[str, Any]:
        """The damper as the file writes it."""
        return _element_dict(self, {"damping": float(self.damping)})


def _name_element(el: Spring | Damper) -> None:
    """A spring's or damper's ``between`` as a tuple, and its default name ``A-B``."""
    object.__setattr__(el, "between", tuple(el.between))
    if not el.name:
        object.__setattr__(el, "name", element_name(*el.between))


def _element_dict(el: Spring | Damper, numbers: dict[str, Any]) -> dict[str, Any]:
    """A spring or damper as the file writes it: ``between``, its ``numbers``, its name unless the default."""
    out: dict[str, Any] = {"between": list(el.between), **numbers}
    if el.name != element_name(*el.between):
        out["name"] = el.name
    return out


@dataclass(frozen=True)
class Flywheel:
    """Extra rotational inertia ``inertia`` (kg*m^2) on a moving link, centred on its first joint, no mass."""

    link: str
    inertia: float

    def to_dict(self) -> dict[str, Any]:
        """The flywheel as the file writes it."""
        return {"link": self.link, "inertia": float(self.inertia)}


@dataclass(frozen=True)
class Mechanism:
    """A validated planar mechanism.  Build it with :func:`linkagekit.files.load` or :meth:`from_dict`.

    Immutable and hashable; two mechanisms are equal when they say the same (``source``,
    the file they came from, is not compared; the order of the joints is).

    Attributes
    ----------
    name : str
        The mechanism's name (the file's ``name``).
    length_unit, angle_unit : str
        The file's units (``units.length``, ``units.angle``): every length, point and
        input value of the file and of a Result is in them.
    joints : FrozenMap of str to complex
        The reference pose: each joint's position ``x + iy`` (length unit), in the file's order.
    links : tuple of Link
        The links, the frame (``"ground"``) among them, in the file's order.
    drivers : tuple of Driver
        The inputs (cranks, slider drivers, cylinders), one per degree of freedom, in the file's order.
    sliders : tuple of Slider
        The prismatic joints (a block on a guide), in the file's order.
    gravity : complex or None
        The acceleration of gravity (m/s^2, ``gx + i gy``), None when the file gives none.
    loads : tuple of Load
        External forces and torques on links.
    springs, dampers, flywheels : tuple of Spring, Damper, Flywheel
        Force elements (docs/mechanism-files.md, springs and dampers): linear springs and dampers between two joints,
        extra rotational inertia on a link.
    source : str
        Where the mechanism came from (a file path, or ``"<dict>"``); not compared.
    description : str or None
        The file's free-text description.
    joint_names : tuple of str
        The joint names in the file's order (the order of a pose array).
    """

    name: str
    length_unit: str
    angle_unit: str
    joints: FrozenMap[str, complex]
    links: tuple[Link, ...]
    drivers: tuple[Driver, ...]
    sliders: tuple[Slider, ...] = ()
    gravity: complex | None = None
    loads: tuple[Load, ...] = ()
    springs: tuple[Spring, ...] = ()
    dampers: tuple[Damper, ...] = ()
    flywheels: tuple[Flywheel, ...] = ()
    source: str = field(default="<dict>", compare=False)
    description: str | None = None
    joint_names: tuple[str, ...] = field(init=False, repr=False)
    _by_name: FrozenMap[str, Link] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if not isinstance(self.joints, FrozenMap):
            object.__setattr__(self, "joints", FrozenMap(self.joints))
        for attr in ("links", "drivers", "sliders", "loads", "springs", "dampers", "flywheels"):
            object.__setattr__(self, attr, tuple(getattr(self, attr)))
        object.__setattr__(self, "joint_names", tuple(self.joints))
        object.__setattr__(self, "_by_name", FrozenMap({ln.name: ln for ln in self.links}))

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_dict(cls, data: Any, source: str = "<dict>") -> Mechanism:
        """Validate a mechanism given as nested dictionaries (the file's structure).

        Raises
        ------
        MechanismFileError
            With a message naming ``source`` and the offending key.
        """
        from . import schema  # pydantic is heavy: import it only when a mechanism is built

        spec = schema.parse(data, source)
        return _build(spec, source)

    def to_dict(self) -> dict[str, Any]:
        """The file's structure (plain dict, list, float, str), such that ``from_dict`` of it is equal.

        Floats are Python floats (which ``repr``, JSON and YAML write back exactly); points
        (joints, ``cg``, a load's ``at``) are in the reference pose frame, as the file gave them.
        """
        out: dict[str, Any] = {"format": FORMAT}
        if self.name:  # a file without a name is saved without one
            out["name"] = self.name
        if self.description is not None:
            out["description"] = self.description
        out["units"] = {"length": self.length_unit, "angle": self.angle_unit}
        out["joints"] = {name: _xy(z) for name, z in self.joints.items()}
        out["links"] = {ln.name: ln.to_dict() for ln in self.links}
        out["drivers"] = [d.to_dict() for d in self.drivers]
        if self.sliders:
            out["sliders"] = [s.to_dict() for s in self.sliders]
        if self.gravity is not None:
            out["gravity"] = _xy(self.gravity)
        if self.loads:
            out["loads"] = [ld.to_dict() for ld in self.loads]
        for key in ("springs", "dampers", "flywheels"):
            items = getattr(self, key)
            if items:
                out[key] = [e.to_dict() for e in items]
        return out

    def pose_array(self) -> np.ndarray:
        """The reference pose as floats ``(n_joints, 2)``, joints in :attr:`joint_names` order.

        This is one row of the ``poses`` that :func:`linkagekit.analyze` takes for a batch of designs.
        """
        return np.array([[self.joints[j].real, self.joints[j].imag] for j in self.joint_names])

    def with_pose(self, pose: Any) -> Mechanism:
        """The same mechanism with another reference pose, all dimensions read off that pose.

        Parameters
        ----------
        pose : array_like of shape (n_joints, 2), or mapping of name to (x, y)
            The new joint positions, in :attr:`joint_names` order, file length unit.

        Returns
        -------
        Mechanism
            Joints at ``pose``, with NO given ``lengths`` (every dimension, and every shape,
            is read off the new pose, which also picks the assembly mode).  Links keep
            their joints, masses and inertias; sliders keep their ``direction``; drivers
            (sweeps, speeds), gravity, name, description and units are unchanged.  Each
            link's ``cg``, and each load's ``at`` given as a point (not a joint name), moves
            with its link: it keeps its complex ratio ``rho = (p - s_a) / (s_b - s_a)`` to the
            link's first two joints ``a``, ``b``, i.e. ``p' = s'_a + rho (s'_b - s'_a)``
            (similar triangles, mirror image kept); on a one-joint link it is translated
            with that joint.

        Raises
        ------
        MechanismFileError
            A pose of the wrong shape or missing a joint, or one that fails the normal
            validation (e.g. two joints of a link at one spot).
        UnknownNameError
            A mapping naming a joint the mechanism does not have.

        Examples
        --------
        >>> from linkagekit.files import load
        >>> m = load("examples/seed000_fourbar.yaml")
        >>> pose = [[2 * z.real, 2 * z.imag] for z in m.joints.values()]
        >>> round(m.with_pose(pose).link("crank").length("A", "C"), 12)
        4.0
        """
        new = self._pose_points(pose)
        d = self.to_dict()
        d["joints"] = {name: _xy(z) for name, z in new.items()}
        for ln in self.links:
            entry = d["links"][ln.name]
            if isinstance(entry, dict):
                entry.pop("lengths", None)
                if ln.cg_pose is not None:
                    entry["cg"] = _xy(self._moved(new, ln.cg_pose, ln.joints))
                if list(entry) == ["joints"] and not ln.written_as_mapping:
                    d["links"][ln.name] = entry["joints"]
        for entry, ld in zip(d.get("loads", []), self.loads, strict=True):
            if ld.at_pose is not None and ld.at_joint is None:
                entry["at"] = _xy(self._moved(new, ld.at_pose, self.link(ld.link).joints))
        return Mechanism.from_dict(d, source=self.source)

    def _moved(self, new: Mapping[str, complex], p: complex, joints: tuple[str, ...]) -> complex:
        """Pose point ``p`` of a link through ``joints``, moved with it to the pose ``new`` (see :meth:`with_pose`)."""
        old, a = self.joints, joints[0]
        if len(joints) < 2:
            return p - old[a] + new[a]
        b = joints[1]
        rho = (p - old[a]) / (old[b] - old[a])
        return new[a] + rho * (new[b] - new[a])

    def _pose_points(self, pose: Any) -> dict[str, complex]:
        names = self.joint_names
        if isinstance(pose, Mapping):
            for k in pose:
                if k not in self.joints:
                    raise UnknownNameError(f"{self.source}: pose: no joint named '{k}' (joints: {', '.join(names)})")
            missing = [n for n in names if n not in pose]
            if missing:
                raise MechanismFileError(f"{self.source}: pose: no position for joint(s) {', '.join(missing)}")
            rows = [pose[n] for n in names]
        else:
            rows = pose
        try:
            arr = np.asarray(rows, dtype=float)
        except (TypeError, ValueError, OverflowError) as exc:
            raise MechanismFileError(
                f"{self.source}: pose: expected numbers (n_joints, 2): {shorten(str(exc))}"
            ) from None
        if arr.shape != (len(names), 2):
            raise MechanismFileError(
                f"{self.source}: pose: expected shape ({len(names)}, 2) (joints {', '.join(names)}), got {arr.shape}"
            )
        return {n: complex(float(x), float(y)) for n, (x, y) in zip(names, arr.tolist(), strict=True)}

    # ------------------------------------------------------------------ queries
    def link(self, name: str) -> Link:
        """The link named ``name``.

        Raises
        ------
        UnknownNameError
            When there is no such link.
        """
        try:
            return self._by_name[name]
        except (KeyError, TypeError):  # TypeError: an unhashable "name"
            raise UnknownNameError(
                f"no link named {shorten(repr(name))} (links: {', '.join(ln.name for ln in self.links)})"
            ) from None

    @property
    def length_scale(self) -> float:
        """A characteristic size of the mechanism (for relative tolerances)."""
        pts = np.array(list(self.joints.values()))
        size = float(np.max(np.abs(pts - pts.mean()))) if len(pts) > 1 else 0.0
        lengths = [abs(b - a) for ln in self.links for a in ln.shape.values() for b in ln.shape.values()]
        return max([size, *lengths, 1e-300])

    @property
    def length_to_si(self) -> float:
        """Metres per file length unit."""
        return LENGTH_UNITS[self.length_unit]

    @property
    def angle_to_rad(self) -> float:
        """Radians per file angle unit."""
        return ANGLE_UNITS[self.angle_unit]

    @property
    def has_dynamics(self) -> bool:
        """True when the file gives mass properties, gravity, loads or force elements (springs, dampers, flywheels)."""
        return (
            bool(self.loads or self.springs or self.dampers or self.flywheels)
            or self.gravity is not None
            or any(ln.has_mass_properties for ln in self.links)
        )

    def flywheel_inertia(self, link: str) -> float:
        """The flywheels' inertia on ``link`` summed (kg*m^2; 0 without one)."""
        return float(sum(f.inertia for f in self.flywheels if f.link == link))

    @property
    def has_given_lengths(self) -> bool:
        """True when any link gave ``lengths`` (dimensions not all read off the pose)."""
        return any(ln.lengths for ln in self.links)

    @property
    def dof(self) -> int:
        """Degrees of freedom by the Gruebler-Kutzbach count for planar lower pairs.

        ``F = 3 (n - 1) - 2 (pins + sliders)``: ``n`` links (ground included); a pin shared
        by ``m`` links counts as ``m - 1`` pins, a slider as one pair.
        """
        return _gruebler(self.links, len(self.sliders))[0]

    def links_of(self, joint: str) -> tuple[str, ...]:
        """Names of the links that carry ``joint``."""
        return tuple(ln.name for ln in self.links if joint in ln.joints)


def _xy(z: complex) -> list[float]:
    return [float(z.real), float(z.imag)]


def _gruebler(links: tuple[Link, ...] | list[Link], n_sliders: int) -> tuple[int, int, int]:
    """``(F, n, pins)`` of the Gruebler-Kutzbach count."""
    count: dict[str, int] = {}
    for ln in links:
        for j in ln.joints:
            count[j] = count.get(j, 0) + 1
    pins = sum(max(c - 1, 0) for c in count.values())
    n = len(links)
    return 3 * (n - 1) - 2 * (pins + n_sliders), n, pins


def _hanging(links: tuple[Link, ...], sliders: tuple[Slider, ...], drivers: tuple[Driver, ...] = ()) -> str | None:
    """A link (not the ground, on no slider) held at one joint alone, said as a likely cause of a freedom too many: a
    pivot left out of ``ground``, or a point put on a link of its own, leaves the link swinging about its other
    joint. A cylinder's end holds its joint. None when there is none.

    >>> from types import SimpleNamespace as L
    >>> spec = {"ground": ("O2",), "crank": ("O2", "A"), "rocker": ("O4", "A")}
    >>> ls = tuple(L(name=n, joints=j) for n, j in spec.items())
    >>> _hanging(ls, ())  # type: ignore[arg-type]
    "link 'rocker' swings about A alone (O4 on no other link: add it to ground?)"
    """
    count: dict[str, int] = {}
    for ln in links:
        for j in ln.joints:
            count[j] = count.get(j, 0) + 1
    for d in drivers:
        for j in getattr(d.type, "ends", ()):  # a cylinder's ends
            count[j] = count.get(j, 0) + 1
    on_slider = {name for s in sliders for name in (s.link, s.on)}
    for ln in links:
        held = [j for j in ln.joints if count[j] > 1]
        if ln.name != "ground" and ln.name not in on_slider and len(ln.joints) > 1 and len(held) == 1:
            free = [j for j in ln.joints if count[j] == 1]
            it = "it" if len(free) == 1 else "them"
            loose = ", ".join(free)
            return f"link '{ln.name}' swings about {held[0]} alone ({loose} on no other link: add {it} to ground?)"
    return None


# ---------------------------------------------------------------------- building
def _build(spec: FileSpec, src: str) -> Mechanism:
    """The mechanism a parsed file describes, each section checked by its own validator of :class:`_Builder`."""
    b = _Builder(spec, src)
    links = b.links()
    sliders = b.sliders()
    drivers = b.drivers(sliders)
    loads = b.loads()
    springs, dampers, flywheels = b.springs(), b.dampers(), b.flywheels()
    b.check_freedom(drivers, sliders)
    return Mechanism(
        name=spec.name,
        length_unit=spec.units.length,
        angle_unit=spec.units.angle,
        joints=FrozenMap(b.joints),
        links=links,
        drivers=drivers,
        sliders=sliders,
        gravity=complex(*spec.gravity) if spec.gravity is not None else None,
        loads=loads,
        springs=springs,
        dampers=dampers,
        flywheels=flywheels,
        source=src,
        description=spec.description,
    )


Fail = Callable[[str, str], MechanismFileError]


class _Builder:
    """The validators of a file's sections, in the order they depend on each other.

    Each raises :class:`MechanismFileError` naming the file and the offending key.
    """

    def __init__(self, spec: FileSpec, src: str) -> None:
        self.spec, self.src = spec, src
        self.joints = {name: complex(x, y) for name, (x, y) in spec.joints.items()}
        #: the mechanism's size, for relative tolerances on lengths
        size = max((abs(a - b) for a in self.joints.values() for b in self.joints.values()), default=0.0)
        if 0.0 < size < MIN_SIZE:
            raise self.fail(
                "joints",
                f"they span {size:.3g} {spec.units.length}, less than {MIN_SIZE:g} {spec.units.length}: scale the "
                "numbers up",
            )
        self.scale = size or 1.0
        self.by_name: dict[str, Link] = {}
        if GROUND not in spec.links:
            raise self.fail("links", "no link named 'ground' (the fixed frame)")

    def fail(self, key: str, msg: str) -> MechanismFileError:
        """The error for ``key`` of this file."""
        return MechanismFileError(f"{self.src}: {key}: {msg}")

    # -------------------------------------------------------------- links
    def links(self) -> tuple[Link, ...]:
        """Every link, its shape registered on the pose; two links never share two joints, every joint is carried."""
        from .schema import LinkSpec

        links = []
        for lname, lspec in self.spec.links.items():
            ls = lspec if isinstance(lspec, LinkSpec) else LinkSpec(joints=lspec)
            links.append(self._link(lname, ls, isinstance(lspec, LinkSpec)))
        for i, la in enumerate(links):  # two links through the same two joints would be one rigid body
            for lb in links[i + 1 :]:
                shared = [j for j in la.joints if j in lb.joints]
                if len(shared) >= 2:
                    raise self.fail(
                        f"links.{lb.name}",
                        f"shares joints '{shared[0]}' and '{shared[1]}' with link '{la.name}': two links through "
                        f"the same two joints are one rigid body (merge them into one link)",
                    )
        used = {j for ln in links for j in ln.joints}
        for j in self.joints:
            if j not in used:
                raise self.fail(f"joints.{j}", "not carried by any link")
        self.by_name = {ln.name: ln for ln in links}
        return tuple(links)

    def _link(self, lname: str, ls: LinkSpec, as_mapping: bool) -> Link:
        """One link: its joints checked, its shape, its mass properties."""
        key = f"links.{lname}"
        self._link_joints(lname, ls.joints)
        shape = _shape(lname, ls, self.joints, self.fail, self.scale)
        cg = cg_pose = None
        if ls.cg is not None:
            cg_pose = complex(*ls.cg)
            cg = _register(cg_pose, tuple(ls.joints), self.joints, shape)
        for attr in ("mass", "inertia"):
            if (getattr(ls, attr) or 0.0) < 0:
                raise self.fail(f"{key}.{attr}", "must not be negative")
        if (ls.mass or 0.0) > 0 and cg is None:
            raise self.fail(f"{key}.cg", "a link with mass needs its centre of gravity `cg`")
        for attr in ("mass", "inertia") if lname == GROUND else ():  # as a load or flywheel there: refused
            if getattr(ls, attr):
                raise self.fail(f"{key}.{attr}", f"the ground does not move: its {attr} does nothing")
        return Link(
            lname,
            tuple(ls.joints),
            FrozenMap(shape),
            ls.mass or 0.0,
            cg,
            ls.inertia or 0.0,
            lengths=FrozenMap(ls.lengths or {}),
            cg_pose=cg_pose,
            written_as_mapping=as_mapping,
        )

    def _link_joints(self, lname: str, js: list[str]) -> None:
        """A link's joints: known, each once, two at least (but on the ground or a block), never at one spot."""
        key = f"links.{lname}"
        for j in js:
            if j not in self.joints:
                raise self.fail(key, f"unknown joint '{j}' (not under joints)")
        if len(set(js)) != len(js):
            dup = next(j for j in js if js.count(j) > 1)
            raise self.fail(key, f"joint '{dup}' is listed twice")
        if len(js) < 2 and lname != GROUND and lname not in {s.link for s in self.spec.sliders}:
            guide = " (a slider's guide, e.g. an actuator's barrel, lists its pin and a point of its line)"
            hint = guide if lname in {s.on for s in self.spec.sliders} else ""
            raise self.fail(
                key, f"a link needs at least two joints (only ground and a slider block may carry one){hint}"
            )
        for i, a in enumerate(js):
            for b in js[i + 1 :]:
                if abs(self.joints[a] - self.joints[b]) <= LENGTH_RTOL * self.scale:
                    raise self.fail(
                        key,
                        f"joints '{a}' and '{b}' are at one spot on one link (closer than {LENGTH_RTOL:g} of the "
                        f"mechanism's size, {self.scale:.3g})",
                    )

    # -------------------------------------------------------------- sliders
    def sliders(self) -> tuple[Slider, ...]:
        """Every slider: two different known links (the ground never the block), a known joint, a direction."""
        out = []
        for i, s in enumerate(self.spec.sliders):
            key = f"sliders[{i}]"
            for attr in ("link", "on"):
                if getattr(s, attr) not in self.by_name:
                    raise self.fail(f"{key}.{attr}", f"unknown link '{getattr(s, attr)}'")
            if s.link == s.on:
                raise self.fail(key, "a link cannot slide on itself")
            if s.link == GROUND:
                raise self.fail(f"{key}.link", "the ground cannot be the sliding block (swap `link` and `on`)")
            if s.through not in self.joints:
                raise self.fail(f"{key}.through", f"unknown joint '{s.through}'")
            shared = [j for j in self.by_name[s.link].joints if j in self.by_name[s.on].joints]
            if shared:
                raise self.fail(
                    key,
                    f"link '{s.link}' is pinned to '{s.on}' at '{shared[0]}' and slides on it: a pin and a slider "
                    "between the same two links hold them together (slide it on another link, or drop the slider)",
                )
            if s.through not in self.by_name[s.link].joints:
                raise self.fail(
                    f"{key}.through",
                    f"joint '{s.through}' is not on link '{s.link}': name the block's joint on the line",
                )
            direction = complex(*s.direction)
            if abs(direction) == 0:
                raise self.fail(f"{key}.direction", "must not be the zero vector")
            out.append(Slider(s.link, s.on, s.through, direction / abs(direction), direction))
        return tuple(out)

    # -------------------------------------------------------------- drivers
    def drivers(self, sliders: tuple[Slider, ...]) -> tuple[Driver, ...]:
        """Every driver, by the keys its entry gives (``cylinder``, ``slider`` or a link); names are unique."""
        drivers = []
        for i, d in enumerate(self.spec.drivers):
            key = f"drivers[{i}]"
            if d.cylinder is not None:
                drivers.append(self._cylinder_driver(d, key))
                continue
            for attr in ("name", "lengths", "stroke"):
                if getattr(d, attr) is not None and not (attr == "stroke" and d.slider is not None):
                    raise self.fail(f"{key}.{attr}", "belongs to a cylinder driver (`cylinder: [A, B]`)")
            drivers.append(self._slider_driver(d, key, sliders) if d.slider is not None else self._crank_driver(d, key))
        names = [d.name for d in drivers]
        for n in names:
            if names.count(n) > 1:
                if any(isinstance(d.type, CylinderType) and d.name == n for d in drivers):
                    raise self.fail("drivers", f"two drivers are named '{n}' (give the cylinder another `name`)")
                raise self.fail("drivers", f"link '{n}' is driven twice")
        return tuple(drivers)

    def _slider_driver(self, d: DriverSpec, key: str, sliders: tuple[Slider, ...]) -> Driver:
        """``{slider: INDEX, displacements: {...}}``: its block pushed along the slider's line (0 at the pose)."""
        from .schema import SweepSpec

        assert d.slider is not None
        if not 0 <= d.slider < len(sliders):
            raise self.fail(f"{key}.slider", f"no slider with index {d.slider} (there are {len(sliders)})")
        if d.angles is not None or d.pivot is not None or d.toward is not None:
            raise self.fail(key, "a slider driver takes `displacements`, not `angles`/`pivot`/`toward`")
        sl = sliders[d.slider]
        if d.link is not None and d.link != sl.link:
            raise self.fail(f"{key}.link", f"slider {d.slider} moves link '{sl.link}', not '{d.link}'")
        stroke = None if d.stroke is None else _travel(key, d.stroke, self.fail)
        if d.displacements is not None:
            sw = d.displacements
        elif stroke is not None:  # as a cylinder's: its whole stroke in 100 steps
            sw = SweepSpec(start=stroke[0], stop=stroke[1], step=(stroke[1] - stroke[0]) / 100)
        else:
            sw = SweepSpec(start=0.0, stop=0.0, step=1.0)
        sweep = _sweep(sw, f"{key}.displacements", self.fail)
        _inside(f"{key}.displacements", sweep, stroke, self.fail)
        return Driver(sl.link, sl.link, sweep, SliderType(d.slider, stroke), d.speed, d.acceleration)

    def _crank_driver(self, d: DriverSpec, key: str) -> Driver:
        """``{link, pivot, toward, angles: {...}}``: a link turned about one of its joints (a turn by default)."""
        from .schema import SweepSpec

        if d.link is None:
            raise self.fail(f"{key}.link", "required key is missing (or give `slider:`)")
        if d.link not in self.by_name:
            raise self.fail(f"{key}.link", f"unknown link '{d.link}'")
        if d.link == GROUND:
            raise self.fail(f"{key}.link", "the ground cannot be driven")
        if d.displacements is not None:
            raise self.fail(key, "`displacements` belongs to a slider driver (`slider: INDEX`)")
        for attr in ("pivot", "toward"):
            j = getattr(d, attr)
            if j is None:
                raise self.fail(f"{key}.{attr}", "required key is missing")
            if j not in self.by_name[d.link].joints:
                raise self.fail(f"{key}.{attr}", f"joint '{j}' is not on link '{d.link}'")
        assert d.pivot is not None and d.toward is not None
        if d.pivot == d.toward:
            raise self.fail(key, "`pivot` and `toward` must be different joints")
        deg = self.spec.units.angle == "deg"
        sw = d.angles or SweepSpec(start=0.0, stop=360.0 if deg else 2 * math.pi, step=1.0 if deg else math.pi / 180)
        # speed and acceleration are rad/s and rad/s^2 whatever the angle unit (docs/mechanism-files.md)
        sweep = _sweep(sw, f"{key}.angles", self.fail)
        return Driver(d.link, d.link, sweep, CrankType(d.pivot, d.toward), d.speed, d.acceleration)

    def _cylinder_driver(self, d: DriverSpec, key: str) -> Driver:
        """``{cylinder: [A, B], lengths: {...}, stroke: [min, max], name: ...}``, checked."""
        extra = [
            k for k in ("link", "pivot", "toward", "angles", "slider", "displacements") if getattr(d, k) is not None
        ]
        if extra:
            raise self.fail(
                f"{key}.{extra[0]}", "a cylinder driver takes `lengths`, `stroke`, `name`, `speed`, `acceleration`"
            )
        assert d.cylinder is not None
        a, b = d.cylinder
        length = self._cylinder_length(key, a, b)
        stroke = None if d.stroke is None else _stroke(key, d.stroke, length, self.fail)
        sweep = _cylinder_sweep(key, d.lengths, stroke, length, self.fail)
        name = d.name if d.name is not None else cylinder_name(a, b)
        return Driver(name, "", sweep, CylinderType((a, b), stroke), d.speed, d.acceleration)

    def _cylinder_length(self, key: str, a: str, b: str) -> float:
        """The pose's length of a cylinder between joints ``a`` and ``b`` (known, on two links, apart)."""
        self._two_ends(f"{key}.cylinder", (a, b), "cylinder", "cannot move it")
        length = abs(self.joints[b] - self.joints[a])
        if length <= LENGTH_RTOL * self.scale:
            raise self.fail(
                f"{key}.cylinder", f"joints '{a}' and '{b}' are at one spot in the pose: a cylinder needs a length"
            )
        return length

    # -------------------------------------------------------------- loads, freedom
    def loads(self) -> tuple[Load, ...]:
        """Every load: on a known link, a force with its point (a joint of the link, or a pose point)."""
        out = []
        for i, ld in enumerate(self.spec.loads):
            key = f"loads[{i}]"
            if ld.link not in self.by_name:
                raise self.fail(f"{key}.link", f"unknown link '{ld.link}'")
            if ld.link == GROUND:  # it would move nothing, and no reaction or driver effort would show it
                raise self.fail(f"{key}.link", "a load on the ground does nothing (put it on a moving link)")
            if ld.force is None and ld.torque is None:
                raise self.fail(key, "give a `force`, a `torque`, or both")
            link = self.by_name[ld.link]
            at_joint: str | None = None
            at: complex | None = None
            at_pose: complex | None = None
            if isinstance(ld.at, str):
                if ld.at not in link.joints:
                    raise self.fail(f"{key}.at", f"joint '{ld.at}' is not on link '{ld.link}'")
                at_joint, at = ld.at, link.shape[ld.at]
            elif ld.at is not None:
                at_pose = complex(*ld.at)
                at = _register(at_pose, link.joints, self.joints, link.shape)
            if ld.force is not None and at is None:
                raise self.fail(f"{key}.at", "a force needs its point of application `at`")
            force = complex(*(ld.force or (0.0, 0.0)))
            out.append(Load(ld.link, at, at_joint, force, ld.torque or 0.0, at_pose=at_pose))
        return tuple(out)

    # -------------------------------------------------------------- force elements
    def springs(self) -> tuple[Spring, ...]:
        """Every spring: between two joints of two different links, stiffness and free length not negative."""
        out = []
        for i, s in enumerate(self.spec.springs):
            key = f"springs[{i}]"
            ends = self._element_ends(key, s.between, "spring")
            for attr in ("stiffness", "free_length"):
                if getattr(s, attr) < 0:
                    raise self.fail(f"{key}.{attr}", f"must not be negative, got {getattr(s, attr):g}")
            out.append(Spring(ends, s.stiffness, s.free_length, s.name or ""))
        return self._unique("springs", tuple(out))

    def dampers(self) -> tuple[Damper, ...]:
        """Every damper: between two joints of two different links, damping not negative."""
        out = []
        for i, d in enumerate(self.spec.dampers):
            key = f"dampers[{i}]"
            ends = self._element_ends(key, d.between, "damper")
            if d.damping < 0:
                raise self.fail(f"{key}.damping", f"must not be negative, got {d.damping:g}")
            out.append(Damper(ends, d.damping, d.name or ""))
        return self._unique("dampers", tuple(out))

    def flywheels(self) -> tuple[Flywheel, ...]:
        """Every flywheel: on a known moving link, inertia not negative."""
        out = []
        for i, f in enumerate(self.spec.flywheels):
            key = f"flywheels[{i}]"
            if f.link not in self.by_name:
                raise self.fail(f"{key}.link", f"unknown link '{f.link}'")
            if f.link == GROUND:
                raise self.fail(f"{key}.link", "a flywheel on the ground does nothing (put it on a moving link)")
            if f.inertia < 0:
                raise self.fail(f"{key}.inertia", f"must not be negative, got {f.inertia:g}")
            out.append(Flywheel(f.link, f.inertia))
        return tuple(out)

    def _element_ends(self, key: str, between: tuple[str, str], what: str) -> tuple[str, str]:
        """A spring's or damper's two joints: known, different, not on one link (it would do nothing)."""
        return self._two_ends(f"{key}.between", between, what, "does nothing")

    def _two_ends(self, key: str, ends: tuple[str, str], what: str, idle: str) -> tuple[str, str]:
        """Two joints ``ends`` under ``key`` of a ``what`` (cylinder, spring, damper): known, different, on two links.

        ``idle``: what such an element between two joints of one link would do (the message says it).
        """
        a, b = ends
        for i, j in enumerate((a, b)):
            if j not in self.joints:
                raise self.fail(f"{key}[{i}]", f"unknown joint '{j}' (not under joints)")
        if a == b:
            raise self.fail(key, f"both ends are joint '{a}': a {what} joins two different joints")
        common = next((ln.name for ln in self.by_name.values() if a in ln.joints and b in ln.joints), None)
        if common is not None:
            raise self.fail(
                key,
                f"joints '{a}' and '{b}' are both on link '{common}': a {what} between two joints of one link "
                f"{idle} (attach its ends to two different links)",
            )
        return a, b

    def _unique(self, key: str, items: tuple[E, ...]) -> tuple[E, ...]:
        """Force elements with distinct names (two between the same joints need a ``name`` each)."""
        names = [e.name for e in items]
        for i, n in enumerate(names):
            if names.index(n) != i:
                raise self.fail(f"{key}[{i}]", f"a second element named '{n}' (give it another `name`)")
        return items

    def check_freedom(self, drivers: tuple[Driver, ...], sliders: tuple[Slider, ...]) -> None:
        """One driver per degree of freedom (Gruebler count)."""
        n_sliders = len(sliders)
        dof, n_links, pins = _gruebler(tuple(self.by_name.values()), n_sliders)
        if dof == len(drivers):
            return
        cylinders = any(isinstance(d.type, CylinderType) for d in drivers)
        hanging = _hanging(tuple(self.by_name.values()), sliders, drivers) if dof > len(drivers) else None
        raise self.fail(
            "drivers",
            f"{len(drivers)} driver(s) given, but the mechanism has {dof} degree(s) "
            f"of freedom (Gruebler: 3*({n_links}-1) - 2*({pins} pins + {n_sliders} sliders) = {dof})"
            + ("; a cylinder counts as one driver, not as a link" if cylinders else "")
            + (f"; {hanging}" if hanging else ""),
        )


def _stroke(key: str, given: tuple[float, float], length: float, fail: Fail) -> tuple[float, float]:
    """A cylinder's stroke ``[min, max]``: positive, increasing, holding the pose's ``length``."""
    lo, hi = given
    if lo <= 0:
        raise fail(f"{key}.stroke", f"[min, max] with a positive min, got [{lo:g}, {hi:g}]")
    if hi <= lo:
        raise fail(f"{key}.stroke", f"[min, max] with min < max, got [{lo:g}, {hi:g}]")
    if not lo * (1 - 1e-9) <= length <= hi * (1 + 1e-9):
        raise fail(f"{key}.stroke", f"the pose has the cylinder {length:.9g} long, outside its stroke [{lo:g}, {hi:g}]")
    return lo, hi


def _travel(key: str, given: tuple[float, float], fail: Fail) -> tuple[float, float]:
    """A slider driver's stroke ``[min, max]`` of displacements: increasing, holding the pose's 0."""
    lo, hi = given
    if hi <= lo:
        raise fail(f"{key}.stroke", f"[min, max] with min < max, got [{lo:g}, {hi:g}]")
    if not lo <= 0 <= hi:
        raise fail(
            f"{key}.stroke",
            f"[{lo:g}, {hi:g}] leaves out the pose (displacement 0): a slider's stroke is measured from the pose",
        )
    return lo, hi


def _inside(key: str, sweep: Sweep, stroke: tuple[float, float] | None, fail: Fail) -> None:
    """A file's sweep lies inside the driver's stroke (to 1e-9 of its size), else a located error."""
    if stroke is None:
        return
    first, last = sweep.start, sweep.start + sweep.step * (sweep.count() - 1)
    slack = 1e-9 * max(abs(stroke[0]), abs(stroke[1]))
    if not (stroke[0] - slack <= min(first, last) and max(first, last) <= stroke[1] + slack):
        raise fail(
            key,
            f"{first:g} to {last:g} leaves the stroke [{stroke[0]:g}, {stroke[1]:g}] (keep the file's sweep "
            f"inside it; inputs asked for outside it are flagged as not assembled)",
        )


def _cylinder_sweep(
    key: str, given: SweepSpec | None, stroke: tuple[float, float] | None, length: float, fail: Fail
) -> Sweep:
    """A cylinder's sweep of lengths: as given, else its whole stroke in 100 steps, else the pose's length only.

    Every length is positive and inside the stroke.
    """
    from .schema import SweepSpec

    if given is not None:
        sw = given
    elif stroke is not None:
        sw = SweepSpec(start=stroke[0], stop=stroke[1], step=(stroke[1] - stroke[0]) / 100)
    else:  # as a slider's default is its pose
        sw = SweepSpec(start=length, stop=length, step=1.0)
    sweep = _sweep(sw, f"{key}.lengths", fail)
    first, last = sweep.start, sweep.start + sweep.step * (sweep.count() - 1)
    if min(first, last) <= 0:
        raise fail(f"{key}.lengths", f"a cylinder's length must be positive, the sweep goes to {min(first, last):g}")
    _inside(f"{key}.lengths", sweep, stroke, fail)
    return sweep


def _sweep(sw: SweepSpec, key: str, fail: Fail) -> Sweep:
    if sw.step == 0:
        raise fail(f"{key}.step", "must not be zero")
    if (sw.stop - sw.start) * sw.step < 0:
        raise fail(f"{key}.step", "goes away from `stop`: its sign must be that of stop - start")
    if abs(sw.stop - sw.start) / abs(sw.step) > 1e8:
        raise fail(key, "more than 10^8 samples")
    return Sweep(sw.start, sw.stop, sw.step)


def parse_pair(key: str, link: tuple[str, ...]) -> tuple[str, str] | None:
    """The two joints of ``link`` that a ``lengths`` key ``"A-B"`` names (None: not two of them).

    Joint names may contain ``-``: every split point is tried.

    >>> parse_pair("A-C-1", ("A", "C-1")), parse_pair("A-B", ("A", "C"))
    (('A', 'C-1'), None)
    """
    parts = key.split("-")
    if len(parts) == 2 and parts[0] in link and parts[1] in link and parts[0] != parts[1]:
        return parts[0], parts[1]
    # joint names may themselves contain '-': try every split point
    for i in range(1, len(key)):
        if key[i] == "-" and key[:i] in link and key[i + 1 :] in link and key[:i] != key[i + 1 :]:
            return key[:i], key[i + 1 :]
    return None


def _shape(lname: str, ls: LinkSpec, pose: dict[str, complex], fail: Fail, scale: float) -> dict[str, complex]:
    """Local coordinates of a link's joints, registered on the pose, honouring given lengths.

    The first two joints anchor the frame (the first at its pose position, the second on
    the pose direction).  Every further joint is placed by its distances to the two
    anchors, on the side of the anchor line where the pose has it (the mirror image).
    """
    js = tuple(ls.joints)
    given: dict[frozenset[str], float] = {}
    keys: dict[frozenset[str], str] = {}
    for k, v in (ls.lengths or {}).items():
        pair = parse_pair(k, js)
        if pair is None:
            raise fail(f"links.{lname}.lengths.{k}", f"expected 'X-Y' with X and Y two joints of link '{lname}'")
        if frozenset(pair) in keys:  # {C-D: 5, D-C: 6}: the last one silently won
            raise fail(
                f"links.{lname}.lengths.{k}",
                f"the length of {pair[0]}-{pair[1]} is given twice (as {keys[frozenset(pair)]!r} too)",
            )
        keys[frozenset(pair)] = k
        if v <= 0:
            raise fail(f"links.{lname}.lengths.{k}", "a length must be positive")
        if v <= LENGTH_RTOL * scale:
            raise fail(
                f"links.{lname}.lengths.{k}",
                f"{v:g} puts the two joints at one spot (the mechanism is {scale:g} across)",
            )
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
        h2 = 0.0 if _flat(base, d1, d2) else d1 * d1 - along * along
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


#: three lengths whose two shorter ones add up to the longest within this many units of rounding of their sum are a
#: flat triangle
FLAT_ULPS = 4.0


def _flat(a: float, b: float, c: float) -> bool:
    """Whether the triangle of sides ``a``, ``b``, ``c`` is flat to rounding (:data:`FLAT_ULPS`): the lever of 0.15,
    0.32 and 0.47 m is, but its height from the law of cosines is the square root of a rounding error, 2e-8 of its
    size (in mm, 150 + 320 = 470 exactly, it was flat).

    >>> _flat(0.15, 0.32, 0.47), _flat(150.0, 320.0, 470.0), _flat(0.15, 0.32, 0.4699)
    (True, True, False)
    """
    lo, mid, hi = sorted((a, b, c))
    return abs(lo + mid - hi) <= FLAT_ULPS * sys.float_info.epsilon * (lo + mid + hi)


def _register(
    point: complex, link_joints: tuple[str, ...], pose: Mapping[str, complex], shape: Mapping[str, complex]
) -> complex:
    """Express a pose point of a link in the link's shape frame (ratio to its two anchors)."""
    if len(link_joints) < 2:
        return point - pose[link_joints[0]] + shape[link_joints[0]]
    a, b = link_joints[0], link_joints[1]
    ratio = (point - pose[a]) / (pose[b] - pose[a])
    return shape[a] + ratio * (shape[b] - shape[a])
