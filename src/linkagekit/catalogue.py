"""The output catalogue: every per-sample quantity of an analysis, declared once.

A :class:`Kind` declares one kind of quantity (a joint's ``x``, a link's ``omega``, a
driver's torque, a reaction's bearing load, the input power...): whom it belongs to
(:class:`Owner`), its column name, its unit (:class:`UnitKind`, resolved to the file's units
at the boundary), its plot group (:class:`Group`), its table section (:class:`Section`),
whether its values wrap (an angle), its place in the JSON result and how to read it off a
:class:`~linkagekit.result.Result`.  :data:`KINDS` lists them in column order.

:func:`build` makes the :class:`Catalogue` of one analysis from the mechanism, whether it has
rates and the layout of its forces: one :class:`Quantity` per column.  ``Result.columns()``,
CSV, the CLI tables, JSON, ``to_pandas()``, ``plot --quantity``, the report page and the
editor all read it; nothing parses a column name.  A new quantity is one more :class:`Kind`.

Examples
--------
>>> import linkagekit as lk
>>> from linkagekit.catalogue import build
>>> cat = build(lk.load("examples/seed000_fourbar.yaml"), rates=True)
>>> q = cat["crank.omega"]
>>> q.owner, q.owner_name, q.kind.component, q.unit_symbol, q.group.title
(<Owner.LINK: 'link'>, 'crank', 'omega', 'rad/s', 'Angular velocities')
>>> cat["input:crank"].unit_symbol, cat["input:crank"].period
('deg', None)
>>> cat["crank.angle"].period
360.0
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from enum import Enum
from functools import cached_property
from typing import TYPE_CHECKING, Any, assert_never

from .errors import MechanismFileError, UnknownNameError, shorten
from .units import UnitKind

if TYPE_CHECKING:
    from .model import Mechanism


class Owner(Enum):
    """What a quantity belongs to."""

    JOINT = "joint"
    LINK = "link"
    DRIVER = "driver"
    REACTION = "reaction"
    MECHANISM = "mechanism"
    SPRING = "spring"
    DAMPER = "damper"


class Group(Enum):
    """The plot group of a quantity: its title, the ``plot --quantity`` short name, and whether the report plots it."""

    INPUTS = ("Inputs", "", False)
    STATE = ("State", "", False)
    JOINT_POSITIONS = ("Joint positions", "", False)
    JOINT_VELOCITIES = ("Joint velocities", "", False)
    JOINT_ACCELERATIONS = ("Joint accelerations", "", False)
    LINK_ANGLES = ("Link angles", "angles", True)
    ANGULAR_VELOCITIES = ("Angular velocities", "omegas", True)
    ANGULAR_ACCELERATIONS = ("Angular accelerations", "alphas", True)
    JOINT_SPEEDS = ("Joint speeds", "speeds", True)
    DRIVER_TORQUES = ("Driver torques", "torques", True)
    DRIVER_FORCES = ("Driver forces", "forces", True)
    BEARING_LOADS = ("Bearing loads", "bearings", True)
    REACTIONS = ("Reaction components", "", False)
    INPUT_POWER = ("Input power", "", False)
    SHAKING = ("Shaking force and moment", "", False)
    SPRING_FORCES = ("Spring forces", "springs", True)
    SPRING_LENGTHS = ("Spring lengths", "", False)
    DAMPER_FORCES = ("Damper forces", "dampers", True)

    @property
    def title(self) -> str:
        return str(self.value[0])

    @property
    def short(self) -> str:
        """The name ``plot --quantity`` takes for the whole group (``""``: none)."""
        return str(self.value[1])

    @property
    def plotted(self) -> bool:
        """Whether the report (and ``plot --quantity SHORT``) plots this group."""
        return bool(self.value[2])


class Section(Enum):
    """The ``analyze`` table a quantity is printed in (each value is the table's title)."""

    POSITIONS = "joint positions"
    VELOCITIES = "joint velocities"
    ACCELERATIONS = "joint accelerations"
    LINKS = "link angles and rates"
    FORCES = "forces (|F| at joint:by>on, driver torques and forces, input power, spring and damper tensions)"


class Needs(Enum):
    """What an analysis must have computed for a quantity to exist."""

    POSITIONS = "positions"
    RATES = "rates"
    FORCES = "forces"
    TIME = "time"  # a simulation's time axis


#: placeholders in a :attr:`Kind.json` path: the owner's name, the reaction's index
OWNER_KEY = "{owner}"
INDEX_KEY = "{index}"


@dataclass(frozen=True)
class ReactionKey:
    """One reaction of a forces layout: by link ``by`` on link ``on`` at ``joint``; ``slider`` has a moment."""

    joint: str
    by: str
    on: str
    slider: bool = False

    @property
    def tag(self) -> str:
        """``J:by>on``, the reaction's part of its column names."""
        return f"{self.joint}:{self.by}>{self.on}"


@dataclass(frozen=True)
class OwnerRef:
    """One owner of quantities: its name (a reaction's ``J:by>on``), index among its kind, and layout entry."""

    name: str
    index: int
    on_ground: bool
    reaction: ReactionKey | None = None


@dataclass(frozen=True)
class Kind:
    """One kind of per-sample quantity, declared once.

    Attributes
    ----------
    owner : Owner
        What each quantity of this kind belongs to (one quantity per owner).
    component : str
        What it is of its owner (``x``, ``omega``, ``torque``...).
    pattern : str
        The column name, ``{}`` standing for the owner's name (a reaction's ``J:by>on``).
    unit : UnitKind or None
        None: the driver's input unit (its type's ``input_kind``).
    group, section : Group, Section or None
        The plot group; the ``analyze`` table (None: in CSV/JSON only).
    json : tuple of str
        Its place in :meth:`Result.to_dict`, with :data:`OWNER_KEY` and :data:`INDEX_KEY`.
    read : callable (result, quantity) -> array
        Its values, broadcastable to ``result.shape``.
    needs : Needs
    applies : callable (mechanism, owner) -> bool, optional
        Which owners (:class:`OwnerRef`) have it (default: all).
    wraps : bool
        The values are angles modulo a turn (plots break the line at a wrap).
    table : bool
        In :meth:`Result.columns` (CSV, JSON, pandas, tables); False: plotted only.
    apart : bool
        Its quantities come after every quantity of the kinds before it, even those of the same
        owner kind (the driver forces after all driver torques), instead of owner by owner.
    """

    owner: Owner
    component: str
    pattern: str
    unit: UnitKind | None
    group: Group
    section: Section | None
    json: tuple[str, ...]
    read: Callable[[Any, Quantity], Any]
    needs: Needs = Needs.POSITIONS
    applies: Callable[[Mechanism, OwnerRef], bool] | None = None
    wraps: bool = False
    table: bool = True
    apart: bool = False


@dataclass(frozen=True)
class Quantity:
    """One column of one analysis: a :class:`Kind` of one owner, with its unit resolved."""

    name: str
    kind: Kind
    owner_name: str
    index: int
    unit: UnitKind
    unit_symbol: str
    on_ground: bool
    period: float | None

    @property
    def owner(self) -> Owner:
        return self.kind.owner

    @property
    def group(self) -> Group:
        return self.kind.group

    @property
    def json_path(self) -> tuple[str | int, ...]:
        """Where :meth:`Result.to_dict` holds the values (keys, and a list index for a reaction)."""
        subst: dict[str, str | int] = {OWNER_KEY: self.owner_name, INDEX_KEY: self.index}
        return tuple(subst.get(p, p) for p in self.kind.json)

    def values(self, result: Any) -> Any:
        """The values in ``result``, broadcastable to ``result.shape`` (an input a batch shares is not repeated)."""
        return self.kind.read(result, self)

    def to_dict(self) -> dict[str, Any]:
        """The entry as plain JSON data (the page's viewer and ``to_dict`` carry these)."""
        return {
            "name": self.name,
            "owner": self.owner.value,
            "owner_name": self.owner_name,
            "component": self.kind.component,
            "unit_kind": self.unit.value,
            "unit": self.unit_symbol,
            "group": self.group.title,
            "plotted": self.group.plotted and not self.on_ground,
            "section": None if self.kind.section is None else self.kind.section.value,
            "period": self.period,
            "table": self.kind.table,
            "on_ground": self.on_ground,
            "path": list(self.json_path) if self.kind.table else None,
        }


def input_units(mech: Mechanism) -> dict[str, str]:
    """Each driver's input unit as the file writes it (``{"crank": "deg"}``)."""
    return {d.name: d.input_unit(mech) for d in mech.drivers}


def _angle_driver(mech: Mechanism, owner: OwnerRef) -> bool:
    return mech.drivers[owner.index].type.effort is UnitKind.TORQUE


def _push_driver(mech: Mechanism, owner: OwnerRef) -> bool:
    return mech.drivers[owner.index].type.effort is UnitKind.FORCE


def _moving_joint(mech: Mechanism, owner: OwnerRef) -> bool:
    return not owner.on_ground


def _slider_reaction(mech: Mechanism, owner: OwnerRef) -> bool:
    return owner.reaction is not None and owner.reaction.slider


def _reaction(r: Any, q: Quantity) -> Any:
    return r.forces.reactions[q.index]


_O, _I = OWNER_KEY, INDEX_KEY

#: every kind of quantity, in column order (kinds of one owner kind in a row go owner by owner)
KINDS: tuple[Kind, ...] = (
    Kind(Owner.MECHANISM, "time", "time", UnitKind.TIME, Group.INPUTS, None, ("time",), lambda r, q: r.time,
         Needs.TIME),
    Kind(Owner.DRIVER, "input", "input:{}", None, Group.INPUTS, None, ("inputs", _O),
         lambda r, q: r.inputs[q.owner_name]),
    Kind(Owner.MECHANISM, "assembled", "assembled", UnitKind.NONE, Group.STATE, None, ("assembled",),
         lambda r, q: r.assembled),
    Kind(Owner.MECHANISM, "singular", "singular", UnitKind.NONE, Group.STATE, None, ("singular",),
         lambda r, q: r.singular),
    Kind(Owner.JOINT, "x", "{}.x", UnitKind.LENGTH, Group.JOINT_POSITIONS, Section.POSITIONS, ("joints", _O, "x"),
         lambda r, q: r.point(q.owner_name).real),
    Kind(Owner.JOINT, "y", "{}.y", UnitKind.LENGTH, Group.JOINT_POSITIONS, Section.POSITIONS, ("joints", _O, "y"),
         lambda r, q: r.point(q.owner_name).imag),
    Kind(Owner.JOINT, "vx", "{}.vx", UnitKind.VELOCITY, Group.JOINT_VELOCITIES, Section.VELOCITIES,
         ("joints", _O, "vx"), lambda r, q: r.velocity(q.owner_name).real, Needs.RATES),
    Kind(Owner.JOINT, "vy", "{}.vy", UnitKind.VELOCITY, Group.JOINT_VELOCITIES, Section.VELOCITIES,
         ("joints", _O, "vy"), lambda r, q: r.velocity(q.owner_name).imag, Needs.RATES),
    Kind(Owner.JOINT, "ax", "{}.ax", UnitKind.ACCELERATION, Group.JOINT_ACCELERATIONS, Section.ACCELERATIONS,
         ("joints", _O, "ax"), lambda r, q: r.acceleration(q.owner_name).real, Needs.RATES),
    Kind(Owner.JOINT, "ay", "{}.ay", UnitKind.ACCELERATION, Group.JOINT_ACCELERATIONS, Section.ACCELERATIONS,
         ("joints", _O, "ay"), lambda r, q: r.acceleration(q.owner_name).imag, Needs.RATES),
    Kind(Owner.LINK, "angle", "{}.angle", UnitKind.ANGLE, Group.LINK_ANGLES, Section.LINKS, ("links", _O, "angle"),
         lambda r, q: r.link_angle[q.owner_name], wraps=True),
    Kind(Owner.LINK, "omega", "{}.omega", UnitKind.ANGULAR_VELOCITY, Group.ANGULAR_VELOCITIES, Section.LINKS,
         ("links", _O, "omega"), lambda r, q: r.link_omega[q.owner_name], Needs.RATES),
    Kind(Owner.LINK, "alpha", "{}.alpha", UnitKind.ANGULAR_ACCELERATION, Group.ANGULAR_ACCELERATIONS, Section.LINKS,
         ("links", _O, "alpha"), lambda r, q: r.link_alpha[q.owner_name], Needs.RATES),
    Kind(Owner.REACTION, "fx", "F[{}].fx", UnitKind.FORCE, Group.REACTIONS, None, ("reactions", _I, "fx"),
         lambda r, q: _reaction(r, q).force.real, Needs.FORCES),
    Kind(Owner.REACTION, "fy", "F[{}].fy", UnitKind.FORCE, Group.REACTIONS, None, ("reactions", _I, "fy"),
         lambda r, q: _reaction(r, q).force.imag, Needs.FORCES),
    Kind(Owner.REACTION, "moment", "F[{}].moment", UnitKind.TORQUE, Group.REACTIONS, None,
         ("reactions", _I, "moment"), lambda r, q: _reaction(r, q).moment, Needs.FORCES, _slider_reaction),
    Kind(Owner.REACTION, "magnitude", "|F|[{}]", UnitKind.FORCE, Group.BEARING_LOADS, Section.FORCES,
         ("reactions", _I, "magnitude"), lambda r, q: _reaction(r, q).magnitude, Needs.FORCES),
    Kind(Owner.DRIVER, "torque", "T[{}]", UnitKind.TORQUE, Group.DRIVER_TORQUES, Section.FORCES,
         ("driver_torque", _O), lambda r, q: r.forces.driver_torque[q.owner_name], Needs.FORCES, _angle_driver),
    Kind(Owner.DRIVER, "force", "F[{}]", UnitKind.FORCE, Group.DRIVER_FORCES, Section.FORCES, ("driver_force", _O),
         lambda r, q: r.forces.driver_force[q.owner_name], Needs.FORCES, _push_driver, apart=True),
    Kind(Owner.MECHANISM, "input_power", "input_power", UnitKind.POWER, Group.INPUT_POWER, Section.FORCES,
         ("input_power",), lambda r, q: r.forces.input_power, Needs.FORCES),
    Kind(Owner.MECHANISM, "shaking_fx", "shaking.fx", UnitKind.FORCE, Group.SHAKING, None, ("shaking_force", "fx"),
         lambda r, q: r.forces.shaking_force.real, Needs.FORCES),
    Kind(Owner.MECHANISM, "shaking_fy", "shaking.fy", UnitKind.FORCE, Group.SHAKING, None, ("shaking_force", "fy"),
         lambda r, q: r.forces.shaking_force.imag, Needs.FORCES),
    Kind(Owner.MECHANISM, "shaking_moment", "shaking.moment", UnitKind.TORQUE, Group.SHAKING, None,
         ("shaking_moment",), lambda r, q: r.forces.shaking_moment, Needs.FORCES),
    Kind(Owner.SPRING, "force", "spring[{}].force", UnitKind.FORCE, Group.SPRING_FORCES, Section.FORCES,
         ("springs", _O, "force"), lambda r, q: r.forces.spring_force[q.owner_name], Needs.FORCES),
    Kind(Owner.SPRING, "length", "spring[{}].length", UnitKind.LENGTH, Group.SPRING_LENGTHS, None,
         ("springs", _O, "length"), lambda r, q: r.forces.spring_length[q.owner_name], Needs.FORCES),
    Kind(Owner.DAMPER, "force", "damper[{}].force", UnitKind.FORCE, Group.DAMPER_FORCES, Section.FORCES,
         ("dampers", _O, "force"), lambda r, q: r.forces.damper_force[q.owner_name], Needs.FORCES),
    Kind(Owner.JOINT, "speed", "|v|[{}]", UnitKind.VELOCITY, Group.JOINT_SPEEDS, None, ("joint_speeds", _O),
         lambda r, q: abs(r.velocity(q.owner_name)), Needs.RATES, _moving_joint, table=False),
)  # fmt: skip


@dataclass(frozen=True)
class Catalogue:
    """The quantities of one analysis, in column order (see the module docstring)."""

    quantities: tuple[Quantity, ...]

    def __iter__(self) -> Iterator[Quantity]:
        return iter(self.quantities)

    def __len__(self) -> int:
        return len(self.quantities)

    @cached_property
    def _by_name(self) -> dict[str, Quantity]:
        return {q.name: q for q in self.quantities}

    def __contains__(self, name: object) -> bool:
        return isinstance(name, str) and name in self._by_name

    def __getitem__(self, name: str) -> Quantity:
        try:
            return self._by_name[name]
        except (KeyError, TypeError):
            raise UnknownNameError(f"no quantity {shorten(repr(name))}") from None

    @property
    def table(self) -> tuple[Quantity, ...]:
        """The quantities of :meth:`Result.columns` (CSV, JSON, pandas, the tables)."""
        return tuple(q for q in self.quantities if q.kind.table)

    def find(self, owner: Owner, owner_name: str, component: str) -> Quantity:
        """The quantity of ``owner_name``'s ``component`` (e.g. a driver's ``input``)."""
        for q in self.quantities:
            if q.owner is owner and q.owner_name == owner_name and q.kind.component == component:
                return q
        raise UnknownNameError(f"no {component} of {owner.value} {shorten(repr(owner_name))}")

    def of_group(self, group: Group) -> tuple[Quantity, ...]:
        """The quantities a plot of ``group`` shows (owners on the ground left out)."""
        return tuple(q for q in self.quantities if q.group is group and not q.on_ground)

    def in_section(self, section: Section) -> tuple[Quantity, ...]:
        """The quantities of one ``analyze`` table (owners on the ground left out)."""
        return tuple(q for q in self.quantities if q.kind.section is section and not q.on_ground)


def _owners(mech: Mechanism, owner: Owner, reactions: Sequence[ReactionKey]) -> list[OwnerRef]:
    """Every owner of one kind, in the mechanism's order (a reaction's: the forces layout's)."""
    match owner:
        case Owner.JOINT:
            ground = set(mech.link("ground").joints)
            return [OwnerRef(j, i, j in ground) for i, j in enumerate(mech.joint_names)]
        case Owner.LINK:
            return [OwnerRef(ln.name, i, ln.name == "ground") for i, ln in enumerate(mech.links)]
        case Owner.DRIVER:
            return [OwnerRef(d.name, i, False) for i, d in enumerate(mech.drivers)]
        case Owner.REACTION:
            return [OwnerRef(r.tag, i, False, r) for i, r in enumerate(reactions)]
        case Owner.MECHANISM:
            return [OwnerRef("", 0, False)]
        case Owner.SPRING:
            return [OwnerRef(e.name, i, False) for i, e in enumerate(mech.springs)]
        case Owner.DAMPER:
            return [OwnerRef(e.name, i, False) for i, e in enumerate(mech.dampers)]
        case _:
            assert_never(owner)


def _blocks(kinds: Sequence[Kind]) -> list[list[Kind]]:
    """Runs of consecutive kinds with one owner kind (their quantities go owner by owner), a kind ``apart`` alone."""
    out: list[list[Kind]] = []
    for k in kinds:
        if out and out[-1][0].owner is k.owner and not k.apart:
            out[-1].append(k)
        else:
            out.append([k])
    return out


def build(
    mech: Mechanism,
    *,
    rates: bool,
    reactions: Sequence[ReactionKey] | None = None,
    kinds: Sequence[Kind] = KINDS,
    time: bool = False,
) -> Catalogue:
    """The catalogue of an analysis of ``mech``: with rates or not, with forces (their reactions' layout) or not,
    with a time axis (a simulation) or not."""
    have = {Needs.POSITIONS, *([Needs.RATES] if rates else []), *([Needs.FORCES] if reactions is not None else [])}
    if time:
        have.add(Needs.TIME)
    layout = tuple(reactions or ())
    lu, au = mech.length_unit, mech.angle_unit
    turn = 360.0 if au == "deg" else 2 * math.pi
    out: list[Quantity] = []
    for block in _blocks([k for k in kinds if k.needs in have]):
        for o in _owners(mech, block[0].owner, layout):
            for k in block:
                if k.applies is not None and not k.applies(mech, o):
                    continue
                unit = k.unit if k.unit is not None else mech.drivers[o.index].type.input_kind
                column = k.pattern.replace("{}", o.name)
                out.append(
                    Quantity(
                        column, k, o.name, o.index, unit, unit.symbol(lu, au), o.on_ground, turn if k.wraps else None
                    )
                )
    _refuse_clashes(mech, out)
    return Catalogue(tuple(out))


def _refuse_clashes(mech: Mechanism, quantities: Sequence[Quantity]) -> None:
    """One column name for two quantities (a joint ``input:a`` and a link ``a.x``...) is a file error."""
    seen: dict[str, Quantity] = {}
    for q in quantities:
        first = seen.setdefault(q.name, q)
        if first is not q:
            raise MechanismFileError(
                f"{mech.source}: the {first.kind.owner.value} {shorten(repr(first.owner_name))} and the "
                f"{q.kind.owner.value} {shorten(repr(q.owner_name))} would both give the column "
                f"{shorten(repr(q.name))}: rename one of them"
            )
