"""The public API as a user sees it: the names ``import linkagekit`` offers, and a docstring on each.

The rule for docstrings:

* every name in ``linkagekit.__all__`` has its own docstring;
* the API's classes are the exported ones and the linkagekit classes an exported function
  returns (``Synthesis``, ``Targets``, ``CheckReport``, ...);
* every public member of an API class, defined in linkagekit (not inherited from Python's
  ``Exception`` or ``object``), that is a method, class method, static method, property or
  cached property has its own docstring;
* every public data attribute of an exported class (a dataclass field, a class constant such as
  ``exit_code``) is listed in the numpydoc ``Attributes`` section of the class's docstring or of
  the docstring of a linkagekit base class (``name : type`` lines; ``a, b : type`` lists both).
"""

from __future__ import annotations

import dataclasses
import inspect
import re
import typing
from functools import cached_property

import pytest

import linkagekit as lk


def _own_doc(obj: object) -> str:
    """The docstring an object carries itself (a class's own, not one inherited from a base)."""
    if isinstance(obj, (classmethod, staticmethod)):
        obj = obj.__func__
    if isinstance(obj, property):
        return obj.fget.__doc__ or "" if obj.fget is not None else ""
    if inspect.isclass(obj):
        return obj.__dict__.get("__doc__") or ""
    return getattr(obj, "__doc__", None) or ""


def documented_attributes(doc: str) -> set[str]:
    """The names listed in the numpydoc ``Attributes`` section of a docstring."""
    lines = inspect.cleandoc(doc).splitlines()
    names: set[str] = set()
    inside = False
    for i, line in enumerate(lines):
        underline = i + 1 < len(lines) and re.fullmatch(r"-{3,}", lines[i + 1].strip())
        if underline:
            inside = line.strip() == "Attributes"
        elif inside and line and not line[0].isspace() and not re.fullmatch(r"-{3,}", line.strip()):
            names |= {n.strip() for n in line.split(" : ")[0].split(",")}
    return names


def _linkagekit_bases(cls: type) -> list[type]:
    return [c for c in cls.__mro__ if c.__module__.startswith("linkagekit")]


def _is_code(member: object) -> bool:
    return isinstance(member, (classmethod, staticmethod, property, cached_property)) or inspect.isfunction(member)


def public_members(cls: type) -> dict[str, object]:
    """Public names defined on ``cls`` or its linkagekit bases (the nearest definition), with dataclass fields."""
    members: dict[str, object] = {}
    for base in reversed(_linkagekit_bases(cls)):
        members.update({k: v for k, v in vars(base).items() if not k.startswith("_")})
        if dataclasses.is_dataclass(base):
            members.update({f.name: f for f in dataclasses.fields(base) if not f.name.startswith("_")})
    return members


def _linkagekit_classes(annotation: object) -> set[type]:
    """The linkagekit classes named in a type (``Iterator[tuple[slice, Result]]`` names ``Result``)."""
    found = {annotation} if inspect.isclass(annotation) and annotation.__module__.startswith("linkagekit") else set()
    for arg in typing.get_args(annotation):
        found |= _linkagekit_classes(arg)
    return found


def api_classes() -> dict[str, type]:
    """The exported classes and the linkagekit classes the exported functions return, by name."""
    classes = {name: getattr(lk, name) for name in lk.__all__ if inspect.isclass(getattr(lk, name))}
    for name in lk.__all__:
        function = inspect.unwrap(getattr(lk, name))  # a decorated entry's annotations name its own module's types
        if inspect.isfunction(function) and "return" in function.__annotations__:
            returned = function.__annotations__["return"]
            returned = eval(returned, function.__globals__) if isinstance(returned, str) else returned
            classes.update({c.__name__: c for c in _linkagekit_classes(returned)})
    return classes


def missing_docs() -> set[str]:
    """``name`` or ``Class.member`` for every public name of the API without its documentation."""
    missing = {name for name in lk.__all__ if not _own_doc(getattr(lk, name)).strip()}
    for name, obj in api_classes().items():
        if not _own_doc(obj).strip():
            missing.add(name)
        listed = set().union(*(documented_attributes(_own_doc(c)) for c in _linkagekit_bases(obj)))
        for member, value in public_members(obj).items():
            ok = _own_doc(value).strip() if _is_code(value) else member in listed
            if not ok:
                missing.add(f"{name}.{member}")
    return missing


def test_dir_shows_exactly_the_public_names() -> None:
    dunders = {n for n in dir(lk) if n.startswith("__") and n.endswith("__")}
    assert set(dir(lk)) - dunders == set(lk.__all__)
    assert len(lk.__all__) == len(set(lk.__all__))


@pytest.mark.parametrize("name", ["Any", "import_module", "TYPE_CHECKING", "annotations", "errors"])
def test_helpers_are_not_public(name: str) -> None:
    assert name not in dir(lk)
    if name != "errors":  # a submodule stays importable as an attribute once loaded
        with pytest.raises(AttributeError):
            getattr(lk, name)


@pytest.mark.parametrize("name", lk.__all__)
def test_every_public_name_resolves(name: str) -> None:
    obj = getattr(lk, name)
    assert obj is not None and getattr(obj, "__name__", name) == name


def test_an_unknown_name_is_an_attribute_error() -> None:
    with pytest.raises(AttributeError, match="no attribute 'nonexistent'"):
        lk.nonexistent  # noqa: B018


def test_the_attributes_section_is_read() -> None:
    doc = """Summary.

    Attributes
    ----------
    a, b : int
        Two numbers.
    c
        Untyped.

    Notes
    -----
    d : not an attribute
    """
    assert documented_attributes(doc) == {"a", "b", "c"}


def test_the_docstring_check_can_fail() -> None:
    @dataclasses.dataclass
    class Bare:
        """Documented, but not its field or method.

        Attributes
        ----------
        listed : int
            Documented.
        """

        listed: int
        bare: int

        def method(self) -> None:
            pass

    Bare.__module__ = "linkagekit.probe"
    listed = documented_attributes(_own_doc(Bare))
    members = public_members(Bare)
    assert {m for m, v in members.items() if not (_own_doc(v).strip() if _is_code(v) else m in listed)} == {
        "bare",
        "method",
    }


def test_returned_classes_are_part_of_the_api() -> None:
    assert {"Result", "Synthesis", "Targets", "Mechanism", "LinkageError"} <= set(api_classes())


def test_every_public_name_is_documented() -> None:
    missing = missing_docs()
    assert not missing, f"without a docstring: {sorted(missing)}"
