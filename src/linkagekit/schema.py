"""The raw structure of a mechanism file, checked by pydantic.

This layer only checks types and shapes (numbers are numbers, names are strings,
required keys are present, unknown keys are typos).  Whether the names refer to each
other consistently is checked when the :class:`~linkagekit.model.Mechanism` is built.
"""

from __future__ import annotations

import difflib
import math
import numbers
import typing
from typing import Annotated, Any, Literal

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, ValidationError

from .errors import MechanismFileError, shorten

#: limits on what a file may hold (docs/mechanism-files.md, "Limits")
MAX_ABS = 1e12  # any number: coordinates, lengths, masses, forces, speeds
MAX_NAME = 64  # characters in a joint, link or mechanism-part name
MAX_JOINTS = 200
MAX_LINKS = 200


def _number(value: Any) -> float:
    # YAML gives bool for `yes`/`no` and str for quoted text: neither is a number here. A real number of any
    # type (numpy's int64, float32, ... register as numbers.Real) is one: np.int64(4) was refused as "not a number"
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ValueError(f"expected a number, got {shorten(repr(value))}")
    try:
        x = float(value)
    except OverflowError:
        raise ValueError(f"a number too large (at most {MAX_ABS:g} in magnitude)") from None
    if not math.isfinite(x):
        raise ValueError(f"expected a finite number, got {shorten(repr(value))}")
    if abs(x) > MAX_ABS:
        raise ValueError(f"{x:g} is too large (at most {MAX_ABS:g} in magnitude)")
    return x


def _name(value: Any) -> str:
    if not isinstance(value, str):
        raise ValueError(f"expected a name, got {shorten(repr(value))}")
    if not value:
        raise ValueError("a name must not be empty")
    if len(value) > MAX_NAME:
        raise ValueError(f"a name of {len(value)} characters (at most {MAX_NAME}): {shorten(value, 20)!r}")
    if not value.isprintable():
        raise ValueError(f"a name with control or format characters: {shorten(repr(value))}")
    return value


def _text(value: Any, what: str, allowed: str = "") -> str:
    """Text a terminal may print as it is: no control or format character (U+202E, ESC, ...) but ``allowed``."""
    if not isinstance(value, str):
        raise ValueError(f"expected text, got {shorten(repr(value))}")
    bad = next((c for c in value if not c.isprintable() and c not in allowed), None)
    if bad is not None:
        raise ValueError(f"{what} with control or format characters (U+{ord(bad):04X}): {shorten(repr(value))}")
    return value


def _title(value: Any) -> str:
    """The mechanism's name: printable text, as joint names are (it is printed in titles)."""
    return _text(value, "a name")


def _description(value: Any) -> str:
    """The free-text description: printable text over lines (newlines and tabs allowed)."""
    return _text(value, "a description", "\n\t")


def _index(value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise ValueError(f"expected a whole number (an index), got {shorten(repr(value))}")
    return int(value)


Number = Annotated[float, BeforeValidator(_number)]
Point = tuple[Number, Number]
Name = Annotated[str, BeforeValidator(_name)]
Index = Annotated[int, BeforeValidator(_index)]
Title = Annotated[str, BeforeValidator(_title)]
Description = Annotated[str, BeforeValidator(_description)]
JointList = Annotated[list[Name], Field(min_length=1)]


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class UnitsSpec(_Strict):
    length: Literal["mm", "cm", "m", "in"] = "m"
    angle: Literal["deg", "rad"] = "deg"


class SweepSpec(_Strict):
    start: Number
    stop: Number
    step: Number


class LinkSpec(_Strict):
    joints: JointList
    lengths: dict[str, Number] | None = None
    mass: Number | None = None
    cg: Point | None = None
    inertia: Number | None = None


class DriverSpec(_Strict):
    link: Name | None = None
    pivot: Name | None = None
    toward: Name | None = None
    angles: SweepSpec | None = None
    slider: Index | None = None
    displacements: SweepSpec | None = None
    cylinder: tuple[Name, Name] | None = None  # a linear actuator between two joints, driven by its length
    name: Name | None = None  # a cylinder's name (other drivers are named by their link)
    lengths: SweepSpec | None = None  # a cylinder's sweep of lengths
    stroke: Point | None = None  # a cylinder's [min, max] length, a slider driver's [min, max] displacement
    speed: Number = 1.0
    acceleration: Number = 0.0


class SliderSpec(_Strict):
    link: Name
    on: Name
    through: Name
    direction: Point


class LoadSpec(_Strict):
    link: Name
    at: Name | Point | None = None
    force: Point | None = None
    torque: Number | None = None


class SpringSpec(_Strict):
    between: tuple[Name, Name]
    stiffness: Number  # N/m
    free_length: Number = 0.0  # file length unit
    name: Name | None = None  # default "A-B"


class DamperSpec(_Strict):
    between: tuple[Name, Name]
    damping: Number  # N*s/m
    name: Name | None = None  # default "A-B"


class FlywheelSpec(_Strict):
    link: Name
    inertia: Number  # kg*m^2


class FileSpec(_Strict):
    format: Literal["linkagekit/1"] = "linkagekit/1"
    name: Title = ""
    description: Description | None = None
    units: UnitsSpec = UnitsSpec()
    joints: dict[Name, Point] = Field(min_length=1, max_length=MAX_JOINTS)
    links: dict[Name, JointList | LinkSpec] = Field(min_length=1, max_length=MAX_LINKS)
    drivers: list[DriverSpec] = Field(min_length=1)
    sliders: list[SliderSpec] = []
    gravity: Point | None = None
    loads: list[LoadSpec] = []
    springs: list[SpringSpec] = []
    dampers: list[DamperSpec] = []
    flywheels: list[FlywheelSpec] = []


_UNION_TAGS = {"LinkSpec", "str", "float", "int"}

#: our words for pydantic's error types
_MESSAGES = {
    "extra_forbidden": "unknown key",
    "missing": "required key is missing",
    "dict_type": "expected a mapping of keys",
    "model_type": "expected a mapping of keys",
    "model_attributes_type": "expected a mapping of keys",
    "list_type": "expected a list",
    "string_type": "expected text",
    "tuple_type": "expected a point [x, y]",
}


def _message(err: Any) -> str:
    """One pydantic error in the words of the file format."""
    kind, loc = err["type"], tuple(err["loc"])
    tuple_error = kind in ("missing", "too_long", "too_short", "tuple_type")
    if tuple_error and loc[:1] == ("drivers",) and len(loc) >= 3 and loc[2] in ("cylinder", "stroke"):
        return "expected two joint names [A, B]" if loc[2] == "cylinder" else "expected [min, max]: two numbers"
    if tuple_error and loc[:1] in (("springs",), ("dampers",)) and len(loc) >= 3 and loc[2] == "between":
        return "expected two joint names [A, B]"
    point = bool(loc) and isinstance(loc[-1], int) and kind in ("missing", "too_long", "too_short")
    if point or (kind in ("too_long", "too_short") and "tuple" in str(err.get("msg", "")).lower()):
        return "expected a point [x, y]: two numbers"
    if kind == "too_long" and loc in (("joints",), ("links",)):
        return f"too many entries (at most {MAX_JOINTS if loc == ('joints',) else MAX_LINKS})"
    if kind == "too_short":
        return "must not be empty (a link needs at least one joint)" if loc[:1] == ("links",) else "must not be empty"
    if kind in _MESSAGES:
        return _MESSAGES[kind]
    msg = str(err["msg"]).removeprefix("Value error, ")
    if msg.startswith("Input should be "):  # e.g. a literal: "expected 'mm', 'cm', 'm' or 'in'"
        msg = "expected " + msg.removeprefix("Input should be ").split(" or instance of ")[0]
    return msg


def _location(loc: tuple[int | str, ...]) -> str:
    """Render a pydantic location as a key path, dropping pydantic's union tags."""
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        elif part in _UNION_TAGS or part.startswith(("function-", "tuple[", "list[", "dict[")):
            continue  # the branch names of a union, not keys of the file
        else:
            out += ("." if out else "") + part
    return out or "(top level)"


def parse(data: Any, source: str) -> FileSpec:
    """Validate raw file content, raising one located :class:`MechanismFileError`."""
    if not isinstance(data, dict):
        raise MechanismFileError(f"{source}: expected a mapping of keys (format, joints, links, ...) at the top level")
    try:
        return FileSpec.model_validate(data)
    except ValidationError as exc:
        errors = exc.errors()
        # For a union (a link as list or mapping) report the branch that matches the data's shape.
        first = errors[0]
        for err in errors:
            if "LinkSpec" in err["loc"] and isinstance(_get(data, err["loc"][:2]), dict):
                first = err
                break
        beside = ""
        if first["type"] == "missing":  # a misspelt key near the missing one explains it: name that key
            first = next((e for e in errors if _misspelt(e, first)), first)
            beside = _beside(errors, first) if first["type"] == "missing" else ""
        msg = _message(first) + _meant(first) + beside
        where = shorten(_location(first["loc"]), 120)
        raise MechanismFileError(f"{source}: {where}: {shorten(msg, 200)}") from None


def _misspelt(err: Any, missing: Any) -> bool:
    """Whether ``err`` is an unknown key beside the ``missing`` one, and near it (a typo of it)."""
    loc, want = tuple(err["loc"]), tuple(missing["loc"])
    if err["type"] != "extra_forbidden" or len(loc) != len(want) or loc[:-1] != want[:-1]:
        return False
    return bool(difflib.get_close_matches(str(loc[-1]), [str(want[-1])], n=1))


def _beside(errors: list[Any], missing: Any) -> str:
    """For a missing key, the unknown key given beside it, if any (a JSON file converted from YAML 1.1 has ``on:``
    as ``"true"``)."""
    want = tuple(missing["loc"])
    for err in errors:
        loc = tuple(err["loc"])
        if err["type"] == "extra_forbidden" and len(loc) == len(want) and loc[:-1] == want[:-1]:
            return f"; {str(loc[-1])!r} beside it is not a key here"
    return ""


def _meant(err: Any) -> str:
    """For an unknown key, the file format's key of that place it is nearest to (a typo), if one is near."""
    loc = tuple(err["loc"])
    if err["type"] != "extra_forbidden":
        return ""
    cutoff = 0.6 if len(loc) == 1 else 0.7  # inside an entry, not 'true' for 'stroke'
    near = difflib.get_close_matches(str(loc[-1]), _keys_at(loc[:-1]), n=1, cutoff=cutoff)
    return f" (did you mean {near[0]!r}?)" if near else ""


def _keys_at(loc: tuple[int | str, ...]) -> list[str]:
    """The keys the file format has at the place ``loc`` (a pydantic location), none where it is not a mapping."""
    annotation: Any = FileSpec
    for part in loc:
        if isinstance(part, int) or part in _UNION_TAGS:
            continue
        if typing.get_origin(annotation) is dict:  # a name of the file's (a joint's, a link's): its value's type
            annotation = typing.get_args(annotation)[1]
            continue
        model = _model_in(annotation)
        field = None if model is None else model.model_fields.get(part)
        if field is None:
            return []
        annotation = field.annotation
    model = _model_in(annotation)
    return [] if model is None else list(model.model_fields)


def _model_in(annotation: Any) -> type[BaseModel] | None:
    """The model class an annotation holds (itself, or inside a list, union or Annotated), else None."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    if typing.get_origin(annotation) is dict:
        return None
    for arg in typing.get_args(annotation):
        found = _model_in(arg)
        if found is not None:
            return found
    return None


def _get(data: Any, loc: tuple[int | str, ...]) -> Any:
    for part in loc:
        try:
            data = data[part]
        except (KeyError, IndexError, TypeError):
            return None
    return data
