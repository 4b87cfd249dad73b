"""The raw structure of a mechanism file, checked by pydantic.

This layer only checks types and shapes (numbers are numbers, names are strings,
required keys are present, unknown keys are typos).  Whether the names refer to each
other consistently is checked when the :class:`~linkagekit.model.Mechanism` is built.
"""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, ValidationError

from .errors import MechanismFileError


def _number(value: Any) -> float:
    # YAML gives bool for `yes`/`no` and str for quoted text: neither is a number here.
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ValueError(f"expected a number, got {value!r}")
    if not math.isfinite(value):
        raise ValueError(f"expected a finite number, got {value!r}")
    return float(value)


Number = Annotated[float, BeforeValidator(_number)]
Point = tuple[Number, Number]


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
    joints: list[str] = Field(min_length=1)
    lengths: dict[str, Number] | None = None
    mass: Number | None = None
    cg: Point | None = None
    inertia: Number | None = None


class DriverSpec(_Strict):
    link: str | None = None
    pivot: str | None = None
    toward: str | None = None
    angles: SweepSpec | None = None
    slider: int | None = None
    displacements: SweepSpec | None = None
    speed: Number = 1.0
    acceleration: Number = 0.0


class SliderSpec(_Strict):
    link: str
    on: str
    through: str
    direction: Point


class LoadSpec(_Strict):
    link: str
    at: str | Point | None = None
    force: Point | None = None
    torque: Number | None = None


class FileSpec(_Strict):
    format: Literal["linkagekit/1"] = "linkagekit/1"
    name: str = ""
    description: str | None = None
    units: UnitsSpec = UnitsSpec()
    joints: dict[str, Point] = Field(min_length=1)
    links: dict[str, list[str] | LinkSpec] = Field(min_length=1)
    drivers: list[DriverSpec] = Field(min_length=1)
    sliders: list[SliderSpec] = []
    gravity: Point | None = None
    loads: list[LoadSpec] = []


def _location(loc: tuple[int | str, ...]) -> str:
    """Render a pydantic location as a key path, dropping pydantic's union tags."""
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        elif part in {"list[str]", "LinkSpec", "str", "tuple[float, float]"} or "[" in part:
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
        msg = first["msg"].removeprefix("Value error, ")
        if first["type"] == "extra_forbidden":
            msg = "unknown key"
        elif first["type"] == "missing":
            msg = "required key is missing"
        raise MechanismFileError(f"{source}: {_location(first['loc'])}: {msg}") from None


def _get(data: Any, loc: tuple[int | str, ...]) -> Any:
    for part in loc:
        try:
            data = data[part]
        except (KeyError, IndexError, TypeError):
            return None
    return data
