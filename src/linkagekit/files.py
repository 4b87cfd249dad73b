"""Reading and writing mechanism files (YAML or JSON, chosen by the file's suffix).

Reading never executes anything: YAML goes through a safe loader (libyaml's C parser when
PyYAML has it) with YAML 1.2 booleans, so only ``true``/``false`` are booleans and a key
``on:`` stays the string ``"on"``.  Writing is atomic (a temporary file in the same
directory, then :func:`os.replace`) and floats are written so that they read back
bit-identical: ``load(save(m, path)) == m``.

PyYAML is imported when a YAML file is first read or written, not with this module.

Examples
--------
>>> import tempfile, pathlib
>>> from linkagekit.files import load, save
>>> m = load("examples/seed000_fourbar.yaml")
>>> with tempfile.TemporaryDirectory() as tmp:
...     out = save(m, pathlib.Path(tmp) / "copy.yaml")
...     print(out.read_text(encoding="utf-8").splitlines()[4])
...     load(out) == m
  A: [0.0, 0.0]
True
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import re
import secrets
import stat
import time
from collections.abc import Callable, Iterator, Sequence
from functools import cache
from pathlib import Path
from typing import Any, Literal

from .errors import InputError, LinkageError, MechanismFileError, shorten, shorten_path
from .model import Mechanism

__all__ = ["dumps", "load", "save"]

#: YAML 1.2 core schema booleans (PyYAML's YAML 1.1 also takes yes/no/on/off).
_BOOL = re.compile(r"^(?:true|True|TRUE|false|False|FALSE)$")
_BOOL_TAG = "tag:yaml.org,2002:bool"
# YAML 1.2 core schema scalars (https://yaml.org/spec/1.2.2/#1032-tag-resolution)
_NULL = re.compile(r"^(?:~|null|Null|NULL|)$")
_INT = re.compile(r"^[-+]?[0-9]+$")
_INT8 = re.compile(r"^0o[0-7]+$")
_INT16 = re.compile(r"^0x[0-9a-fA-F]+$")
_FLOAT = re.compile(r"^[-+]?(?:\.[0-9]+|[0-9]+(?:\.[0-9]*)?)(?:[eE][-+]?[0-9]+)?$")
_INF = re.compile(r"^[-+]?\.(?:inf|Inf|INF)$")
_NAN = re.compile(r"^\.(?:nan|NaN|NAN)$")


@cache
def _loader_class(pure: bool = False) -> type[Any]:
    """A safe YAML loader with the YAML 1.2 core schema: libyaml's C parser unless ``pure``, or unavailable.

    Only true/false are booleans (so ``on:`` stays a key), ``1e-4`` is a number, and there are
    no YAML 1.1 timestamps, sexagesimals or yes/no.  ``<<`` is still recognised, so that a
    merge key can be refused by name.
    """
    import yaml

    base: type[Any] = yaml.CSafeLoader if (yaml.__with_libyaml__ and not pure) else yaml.SafeLoader
    cls: type[Any] = type(
        "_PyLoader" if base is yaml.SafeLoader else "_Loader", (base,), {"__doc__": _loader_class.__doc__}
    )
    cls.yaml_implicit_resolvers = {}
    digits = list("-+0123456789.")
    for tag, rx, first in (
        ("bool", _BOOL, list("tTfF")),
        ("null", _NULL, ["~", "n", "N", ""]),
        ("int", _INT, digits),
        ("int", _INT8, ["0"]),
        ("int", _INT16, ["0"]),
        ("float", _FLOAT, digits),
        ("float", _INF, ["-", "+", "."]),
        ("float", _NAN, ["."]),
        ("merge", re.compile(r"^<<$"), ["<"]),
    ):
        cls.add_implicit_resolver(f"tag:yaml.org,2002:{tag}", rx, first)
    return cls


def __getattr__(name: str) -> Any:
    # `_Loader` (C parser when available) and `_PyLoader` (pure Python), built on first use
    # so that importing this module does not import PyYAML.
    if name == "_Loader":
        return _loader_class(False)
    if name == "_PyLoader":
        return _loader_class(True)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


# ---------------------------------------------------------------------- reading
#: limits that protect the machine from a hostile or broken file (docs/mechanism-files.md)
MAX_FILE_BYTES = 4 << 20
MAX_DEPTH = 32
MAX_VALUES = 200_000  # values after expanding aliases
MAX_NUMBER_CHARS = 64

_STANDARD = {f"tag:yaml.org,2002:{t}" for t in ("str", "int", "float", "bool", "null", "seq", "map")}


def _scalar(text: str, tag: str) -> Any:
    """A scalar by its (resolved or explicit) standard tag: null, bool, int, float or str."""
    kind = tag.rsplit(":", 1)[1]
    if kind == "str":
        return text
    if kind == "null":
        return None
    if kind == "bool":
        if not _BOOL.match(text):
            raise ValueError(f"!!bool needs true or false, got {shorten(repr(text))}")
        return text.lower() == "true"
    if len(text) > MAX_NUMBER_CHARS:
        raise ValueError(f"a number of {len(text)} characters (at most {MAX_NUMBER_CHARS})")
    try:
        if kind == "int":
            return int(text, 8 if text.startswith("0o") else 16 if text.startswith("0x") else 10)
        if _INF.match(text):
            return float("-inf") if text.startswith("-") else float("inf")
        return float("nan") if _NAN.match(text) else float(text)
    except ValueError:
        raise ValueError(f"!!{kind} needs a number, got {shorten(repr(text))}") from None


def yaml_data(text: str, source: str) -> Any:
    """Parse YAML into plain data with YAML 1.2 rules, refusing what a mechanism file has no use for.

    PyYAML only composes the node graph (aliases stay shared nodes, nothing is constructed
    or executed); the nodes are then converted here: YAML 1.2 core scalars (``1e-4`` is a
    number, only true/false are booleans), string keys only, no duplicate keys, no merge
    keys, no tags beyond the standard ones, bounded depth and size.
    """
    import yaml

    def fail(node: Any, msg: str) -> MechanismFileError:
        return MechanismFileError(f"{source}{_where(getattr(node, 'start_mark', None))}: {msg}")

    root = _yaml_node(text, source)
    count = 0

    def convert(node: Any, depth: int) -> Any:
        nonlocal count
        count += 1
        if count > MAX_VALUES:
            raise fail(node, f"more than {MAX_VALUES} values (after expanding aliases): not a mechanism file")
        if depth > MAX_DEPTH:
            raise fail(node, f"nested too deep (at most {MAX_DEPTH} levels)")
        if node.tag == "tag:yaml.org,2002:merge":
            raise fail(node, "merge keys (<<) are not allowed: write the keys out")
        if node.tag not in _STANDARD:
            tag = node.tag.replace("tag:yaml.org,2002:", "!!")
            raise fail(node, f"the tag {shorten(tag)} is not allowed in a mechanism file (plain data only)")
        if isinstance(node, yaml.ScalarNode):
            try:
                return _scalar(node.value, node.tag)
            except ValueError as exc:
                raise fail(node, str(exc)) from None
        if isinstance(node, yaml.SequenceNode):
            return [convert(item, depth + 1) for item in node.value]
        out: dict[str, Any] = {}
        for key_node, value_node in node.value:
            key = convert(key_node, depth + 1)
            if not isinstance(key, str):
                raise fail(key_node, f"a key must be a name, got {shorten(repr(key))} (quote it)")
            if key in out:
                raise fail(key_node, f"duplicate key '{shorten(key)}'")
            out[key] = convert(value_node, depth + 1)
        return out

    return convert(root, 0)


def _where(mark: Any) -> str:
    """`` at line L, column C`` of a YAML mark (1-based), or nothing without one."""
    return f" at line {mark.line + 1}, column {mark.column + 1}" if mark is not None else ""


def _yaml_node(text: str, source: str) -> Any:
    """The node graph of the one YAML document in ``text`` (composed, nothing constructed)."""
    import yaml

    try:
        _bounded_events(text, source)
        nodes = list(yaml.compose_all(text, Loader=_loader_class()))
    except RecursionError:
        raise MechanismFileError(f"{source}: nested too deep (at most {MAX_DEPTH} levels)") from None
    except yaml.YAMLError as exc:
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        where = _where(getattr(exc, "problem_mark", None))
        raise MechanismFileError(f"{source}: YAML syntax error{where}: {shorten(problem)}") from None
    if len(nodes) != 1:
        raise MechanismFileError(f"{source}: expected one YAML document, found {len(nodes)}")
    return nodes[0]


def _bounded_events(text: str, source: str) -> None:
    """Refuse a YAML text nested deeper than :data:`MAX_DEPTH` or with more than :data:`MAX_VALUES` nodes, from its
    parser's events, before anything is composed: libyaml composes recursively in C, and 25000 levels of ``[``
    (50 kB) crashed the interpreter (a segmentation fault, no message). The parser itself keeps a stack, not a
    recursion; aliases are not expanded here (the conversion counts them)."""
    import yaml

    depth = count = 0
    for event in yaml.parse(text, Loader=_loader_class()):
        if isinstance(event, yaml.CollectionStartEvent):
            depth += 1
            if depth > MAX_DEPTH:
                raise MechanismFileError(
                    f"{source}{_where(event.start_mark)}: nested too deep (at most {MAX_DEPTH} levels)"
                )
        elif isinstance(event, yaml.CollectionEndEvent):
            depth -= 1
            continue
        elif not isinstance(event, yaml.ScalarEvent):
            continue
        count += 1
        if count > MAX_VALUES:
            raise MechanismFileError(
                f"{source}{_where(event.start_mark)}: more than {MAX_VALUES} values: not a mechanism file"
            )


def _json_data(text: str, source: str) -> Any:
    """Parse JSON with the same refusals as YAML: duplicate keys, depth, oversized numbers."""

    def pairs(items: list[tuple[str, Any]]) -> dict[str, Any]:
        out: dict[str, Any] = {}
        for k, v in items:
            if k in out:
                raise MechanismFileError(f"{source}: duplicate key '{shorten(k)}'")
            out[k] = v
        return out

    def number(text: str) -> Any:
        if len(text) > MAX_NUMBER_CHARS:
            raise MechanismFileError(f"{source}: a number of {len(text)} characters (at most {MAX_NUMBER_CHARS})")
        return float(text) if any(c in text for c in ".eE") else int(text)

    try:
        data = json.loads(text, object_pairs_hook=pairs, parse_int=number, parse_float=number)
    except json.JSONDecodeError as exc:
        raise MechanismFileError(
            f"{source}: JSON syntax error at line {exc.lineno}, column {exc.colno}: {exc.msg}"
        ) from None
    except RecursionError:
        raise MechanismFileError(f"{source}: nested too deep (at most {MAX_DEPTH} levels)") from None

    def depth(x: Any, d: int = 0) -> int:
        if d > MAX_DEPTH:
            raise MechanismFileError(f"{source}: nested too deep (at most {MAX_DEPTH} levels)")
        if isinstance(x, dict):
            return max((depth(v, d + 1) for v in x.values()), default=d)
        if isinstance(x, list):
            return max((depth(v, d + 1) for v in x), default=d)
        return d

    depth(data)
    return data


def _path(path: Any, what: str) -> Path:
    """A file path argument, or one clear error."""
    if not isinstance(path, str | os.PathLike):
        raise InputError(f"{what}: expected a file path, got {type(path).__name__}")
    if not os.fsdecode(path):  # Path("") is Path("."): "check ''" answered ". is a directory"
        raise InputError(f"{what}: the file path is empty")
    if "\x00" in os.fsdecode(path):
        raise InputError(f"{what}: a file path with a NUL byte: {shorten(repr(os.fsdecode(path)))}")
    return Path(path)


def read_regular_file(p: Path, limit: int, what: str, fail: Callable[[str], LinkageError]) -> bytes:
    """At most ``limit + 1`` bytes of the regular file ``p``, or ``fail(message)`` raised (:func:`read_regular`)."""
    return read_regular(p, limit, what, fail)[0]


def read_regular(p: Path, limit: int, what: str, fail: Callable[[str], LinkageError]) -> tuple[bytes, os.stat_result]:
    """At most ``limit + 1`` bytes of the regular file ``p`` and its status, or ``fail(message)`` raised.

    The file is opened without blocking (a FIFO does not wait for a writer) and checked to be
    a regular file before anything is read: a directory, a device (``/dev/zero``), a FIFO or a
    socket is refused by name. At most ``limit + 1`` bytes are read, so the caller can tell a
    file over its limit (even one that grows while it is read) without holding more.

    >>> read_regular(Path("/dev/zero"), 10, "mechanism file", InputError)
    Traceback (most recent call last):
    ...
    linkagekit.errors.InputError: not a regular file (a character device): not a mechanism file
    """
    try:
        fd = os.open(p, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0))
    except FileNotFoundError:
        raise fail("no such file") from None
    except IsADirectoryError:
        raise fail(f"is a directory, not a {what}") from None
    except OSError as exc:
        raise fail(f"cannot read: {exc.strerror or exc}") from None
    except ValueError as exc:  # e.g. a path the system cannot represent
        raise fail(f"not a usable path: {exc}") from None
    st = os.fstat(fd)
    mode = st.st_mode
    if not stat.S_ISREG(mode):
        os.close(fd)
        if stat.S_ISDIR(mode):
            raise fail(f"is a directory, not a {what}")
        raise fail(f"not a regular file ({_file_kind(mode)}): not a {what}")
    with os.fdopen(fd, "rb") as f:
        with contextlib.suppress(OSError, AttributeError):
            os.set_blocking(fd, True)
        try:
            return f.read(limit + 1), st
        except OSError as exc:
            raise fail(f"cannot read: {exc.strerror or exc}") from None


def _file_kind(mode: int) -> str:
    """What a file that is not a regular file is: a character device, a FIFO, ..."""
    for test, name in (
        (stat.S_ISCHR, "a character device"),
        (stat.S_ISBLK, "a block device"),
        (stat.S_ISFIFO, "a FIFO"),
        (stat.S_ISSOCK, "a socket"),
    ):
        if test(mode):
            return name
    return "a special file"


def _mib(n: int) -> str:
    """A byte count as the limits table writes it: ``4 MiB``."""
    return f"{n / 2**20:g} MiB"


def load(path: str | Path) -> Mechanism:
    """Read a mechanism file (YAML, or JSON when the suffix is ``.json``).  Reading never executes anything.

    Parameters
    ----------
    path : str or Path
        The file: a regular file of at most :data:`MAX_FILE_BYTES` bytes.

    Returns
    -------
    Mechanism
        The validated mechanism (its ``source`` is ``str(path)``).  No solver runs here.

    Raises
    ------
    MechanismFileError
        With a message naming the file and the offending key.
    """
    p = _path(path, "load")
    return from_bytes(read_mechanism_file(p)[0], p)


def read_mechanism_file(p: Path) -> tuple[bytes, os.stat_result]:
    """The bytes of the mechanism file ``p`` (at most :data:`MAX_FILE_BYTES`) and its status, as :func:`load` reads
    them (a regular file only, never waiting on a FIFO), or :class:`MechanismFileError` naming ``p``."""

    def fail(message: str) -> MechanismFileError:
        return MechanismFileError(f"{p}: {message}")

    data, st = read_regular(p, MAX_FILE_BYTES, "mechanism file", fail)
    if len(data) > MAX_FILE_BYTES:
        raise fail(f"more than {MAX_FILE_BYTES} bytes ({_mib(MAX_FILE_BYTES)}), more than a mechanism file may have")
    return data, st


def from_bytes(data: bytes, p: Path) -> Mechanism:
    """The mechanism of the bytes ``data`` of the file ``p`` (its suffix gives the format), as :func:`load` reads it."""
    try:
        text = data.decode("utf-8-sig")  # a byte-order mark is dropped, in JSON as in YAML
    except UnicodeDecodeError as exc:
        raise MechanismFileError(f"{p}: not UTF-8 text (byte {exc.start})") from None
    parsed = _json_data(text, str(p)) if p.suffix.lower() == ".json" else yaml_data(text, str(p))
    return Mechanism.from_dict(parsed, source=str(p))


# ---------------------------------------------------------------------- writing
def save(mech: Mechanism, path: str | Path) -> Path:
    """Write a mechanism file: YAML for ``.yaml``/``.yml``, JSON for ``.json``.

    The file is written atomically (a temporary file in the same directory, then
    :func:`os.replace`): an existing file stays whole until the new one is complete.
    ``load`` of it gives back an equal mechanism, floats bit-identical.

    Parameters
    ----------
    mech : Mechanism
        The mechanism (as :meth:`Mechanism.to_dict` writes it).
    path : str or Path
        The file to write; its suffix picks the format.

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    MechanismFileError
        For another suffix, or when the file cannot be written.
    """
    if not isinstance(mech, Mechanism):
        raise InputError(f"save: expected a Mechanism, got {type(mech).__name__}")
    p = _path(path, "save")
    suffix = p.suffix.lower()
    if suffix in {".yaml", ".yml"}:
        text = dumps(mech, "yaml")
    elif suffix == ".json":
        text = dumps(mech, "json")
    else:
        what = f"suffix '{p.suffix}'" if p.suffix else "no suffix"
        raise MechanismFileError(f"{p}: cannot save a mechanism file with {what}: use .yaml, .yml or .json")
    _write_atomic(p, text)
    return p


def readable(value: Any) -> Any:
    """``value`` (text, or mappings and lists of it) with the bytes a file name could not decode (Python's lone
    surrogates, ``\\udcff``) as U+FFFD: written as they were, they made an unreadable file or page.

    >>> readable({"description": "targets tg\\udcff.csv", "n": [1, "a"]})
    {'description': 'targets tg\ufffd.csv', 'n': [1, 'a']}
    """
    if isinstance(value, str):
        return value.encode("utf-8", "surrogateescape").decode("utf-8", "replace")
    if isinstance(value, dict):
        return {readable(k): readable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return type(value)(readable(v) for v in value)
    return value


def dumps(
    mech: Mechanism, fmt: Literal["yaml", "json"] = "yaml", like: str | None = None, earlier: Sequence[str] = ()
) -> str:
    """The text of a mechanism file, YAML (readable: block style, points as flow lists) or JSON.

    Parameters
    ----------
    mech : Mechanism
        The mechanism.
    fmt : {"yaml", "json"}
        The format.
    like : str, optional
        The YAML text of the file this one replaces: each mapping and list found at the same
        place in it keeps its style there (flow ``{...}``/``[...]`` or block), and a number it
        wrote as an integer stays one while its value is a whole number.  Other comments
        than the file's first lines are not kept.  Ignored for JSON, or when it does not parse.
    earlier : sequence of str, optional
        Older YAML texts of the same file, newest first (the editor's file as opened, then as
        saved): where ``like`` has no mapping or list at a place, the first of them that has
        one gives its style, and a number any of them wrote as an integer at that place stays
        one while its value is whole (an edit undone writes the file's ``49`` back, not ``49.0``).

    Examples
    --------
    >>> from linkagekit.files import dumps, load
    >>> m = load("examples/seed000_fourbar.yaml")
    >>> print(dumps(m).splitlines()[2])
    units: {length: cm, angle: deg}
    >>> print(dumps(m, like="units:\\n  length: cm\\n  angle: deg\\n").splitlines()[2:5])
    ['units:', '  length: cm', '  angle: deg']
    """
    data = readable(mech.to_dict())
    if fmt == "json":
        return _json(data) + "\n"
    if fmt != "yaml":
        raise MechanismFileError(f"unknown mechanism file format '{fmt}' (yaml or json)")
    import yaml

    styled = _styled(data)
    nodes = [_style_node(text) for text in [like, *earlier] if text is not None]
    styled = _like(styled, nodes)
    if like is not None and nodes[0] is not None:  # the sections in the order of the file replaced
        styled = _in_order_of(styled, nodes[0])
    text: str = yaml.dump(
        styled,
        Dumper=_dumper_class(),
        sort_keys=False,
        default_flow_style=False,
        allow_unicode=True,
        width=120,
    )
    return text


#: what a line is scanned for to find its comment: a quoted string (a ``#`` inside is no comment; ``\"`` does not
#: end a double-quoted one, and ``'it''s'`` reads as two single-quoted ones, the same here) or a ``#`` at the
#: line's start or after a space or tab
_QUOTED_OR_HASH = re.compile(r'"(?:\\.|[^"\\])*"?|\'[^\']*\'?|(?<![^ \t])#')


def _split_comment(line: str) -> tuple[str, str]:
    """A YAML line as (content, comment): the comment from a ``#`` at the line's start or after a space, outside
    quotes, to the end (with the spaces before it); ``("", line)`` for a line that is only a comment or blank."""
    for match in _QUOTED_OR_HASH.finditer(line):
        if match.group() == "#":
            content = line[: match.start()].rstrip()
            return content, line[len(content) :]
    return (line.rstrip(), "") if line.strip() else ("", line)


def merge_comments(old: str, new: str) -> str:
    r"""``new`` (a YAML text) with the comments of ``old`` (the text it replaces) put back where its lines match.

    The lines of ``new`` are aligned with the content of ``old``'s lines (:mod:`difflib`): a comment
    line of ``old`` stays before the line it came before, and a line's trailing comment stays on it when
    the line is unchanged or replaced one for one (a moved joint's coordinates). Comments of removed
    lines are dropped, except above the first line of ``new``: the file's header comments stay at its top
    also when lines it began with are not written again (``---``, ``%YAML 1.2``). The caller checks that
    the result reads as ``new`` does (a comment put back cannot change what the file says, but a quote the
    splitting misread could).

    >>> old = "# a four-bar\njoints:\n  A: [0, 0]   # the crank's pivot\n  B: [4, 0]\n"
    >>> print(merge_comments(old, "joints:\n  A: [0, 0]\n  B: [5, 1]\n"), end="")
    # a four-bar
    joints:
      A: [0, 0]   # the crank's pivot
      B: [5, 1]
    """
    import difflib

    parts = [_split_comment(line) for line in old.splitlines()]
    content = [c for c, _ in parts if c]
    before: list[list[str]] = [[]]  # the comment lines before each content line (and after the last)
    trailing: list[str] = []
    for c, comment in parts:
        if c:
            trailing.append(comment)
            before.append([])
        else:
            before[-1].append(comment)
    lines = new.splitlines()
    out: list[str] = []
    for tag, i1, i2, j1, j2 in difflib.SequenceMatcher(None, content, lines, autojunk=False).get_opcodes():
        one_for_one = tag == "equal" or (tag == "replace" and i2 - i1 == j2 - j1)
        if j1 == 0 and not one_for_one:  # old lines before the first new one (`---`): their comment lines stay
            out.extend(line for i in range(i1, i2) for line in before[i])
        for k in range(j2 - j1):
            if one_for_one:
                out.extend(before[i1 + k])
                out.append(lines[j1 + k] + trailing[i1 + k])
            else:
                out.append(lines[j1 + k])
    out.extend(before[len(content)])
    return "\n".join(out) + "\n"


def _json(value: Any, indent: str = "") -> str:
    """JSON with 2-space indentation, lists and mappings of plain values on one line."""
    if isinstance(value, dict | list) and any(isinstance(v, dict | list) for v in _values(value)):
        inner = indent + "  "
        if isinstance(value, dict):
            items = [f"{inner}{json.dumps(k, ensure_ascii=False)}: {_json(v, inner)}" for k, v in value.items()]
            return "{\n" + ",\n".join(items) + f"\n{indent}}}"
        return "[\n" + ",\n".join(f"{inner}{_json(v, inner)}" for v in value) + f"\n{indent}]"
    return json.dumps(value, ensure_ascii=False, allow_nan=False)


def _values(value: dict[str, Any] | list[Any]) -> list[Any]:
    return list(value.values()) if isinstance(value, dict) else value


class _FlowList(list[Any]):
    """A list written in YAML flow style: ``[x, y]``."""


class _FlowDict(dict[str, Any]):
    """A mapping written in YAML flow style: ``{start: 0.0, stop: 360.0, step: 1.0}``."""


class _BlockList(list[Any]):
    """A list written in YAML block style (one ``- item`` a line)."""


class _BlockDict(dict[str, Any]):
    """A mapping written in YAML block style (one ``key: value`` a line)."""


def _style_node(text: str) -> Any:
    """The YAML node of a text whose styles a written file keeps (None when it does not parse: no style to keep)."""
    with contextlib.suppress(LinkageError):
        return _yaml_node(text, "the file replaced")
    return None


def _like(value: Any, nodes: list[Any]) -> Any:
    """``value`` styled as ``nodes``, the same place in the texts of the file it replaces, newest first (None: absent).

    A mapping or list takes the flow or block style of the first node that is one; a whole
    float where one of the texts wrote an integer is written as that integer (it reads back equal).
    """
    import yaml

    if isinstance(value, dict) and (maps := [n for n in nodes if isinstance(n, yaml.MappingNode)]):
        olds = [{k.value: v for k, v in n.value if isinstance(k, yaml.ScalarNode)} for n in maps]
        style = _FlowDict if maps[0].flow_style else _BlockDict
        return style({k: _like(v, [old.get(k) for old in olds]) for k, v in value.items()})
    if isinstance(value, list) and (seqs := [n for n in nodes if isinstance(n, yaml.SequenceNode)]):
        items = [_like(v, [n.value[i] if i < len(n.value) else None for n in seqs]) for i, v in enumerate(value)]
        return (_FlowList if seqs[0].flow_style else _BlockList)(items)
    whole = isinstance(value, float) and value.is_integer() and abs(value) < 2.0**53
    if whole and any(isinstance(n, yaml.ScalarNode) and n.tag == "tag:yaml.org,2002:int" for n in nodes):
        return int(value)
    return value


def _in_order_of(value: Any, node: Any) -> Any:
    """The document ``value`` with its sections (top-level keys) in the order the file it replaces (``node``) has
    them (one the file lacks right after the one the model writes before it): a file whose ``sliders:`` come before
    its ``drivers:`` keeps them there (the order of sections means nothing; inside them it is left as it is)."""
    import yaml

    if not (isinstance(node, yaml.MappingNode) and isinstance(value, dict)):
        return value
    order = {k.value: i for i, (k, _) in enumerate(node.value) if isinstance(k, yaml.ScalarNode)}
    place: dict[str, tuple[int, bool]] = {}
    anchor = -1  # the file's place of the last section the model wrote that the file has
    for k in value:
        anchor = order.get(k, anchor)
        place[k] = (anchor, k not in order)
    return type(value)({k: value[k] for k in sorted(value, key=place.__getitem__)})


def _styled(d: dict[str, Any]) -> dict[str, Any]:
    """Mark the parts of a mechanism dict that read best in flow style (block style elsewhere)."""

    def flow(v: Any) -> Any:
        if isinstance(v, list):
            return _FlowList(flow(x) for x in v)
        if isinstance(v, dict):
            return _FlowDict({k: flow(x) for k, x in v.items()})
        return v

    out: dict[str, Any] = {}
    for key, value in d.items():
        if key in {"units", "gravity"}:
            out[key] = flow(value)
        elif key == "joints":
            out[key] = {name: flow(xy) for name, xy in value.items()}
        elif key == "links":
            out[key] = {
                name: flow(ln) if isinstance(ln, list) else {k: flow(v) for k, v in ln.items()}
                for name, ln in value.items()
            }
        elif key == "drivers":
            out[key] = [{k: flow(v) for k, v in drv.items()} for drv in value]
        elif key in {"sliders", "loads", "springs", "dampers", "flywheels"}:
            out[key] = [flow(item) for item in value]
        else:
            out[key] = value
    return out


@cache
def _dumper_class() -> type[Any]:
    import yaml

    class _Dumper(yaml.SafeDumper):
        def ignore_aliases(self, data: Any) -> bool:
            return True

        def increase_indent(self, flow: bool = False, indentless: bool = False) -> None:
            super().increase_indent(flow, False)  # block lists indented under their key

    def flow_list(dumper: yaml.SafeDumper, data: list[Any]) -> yaml.Node:
        return dumper.represent_sequence("tag:yaml.org,2002:seq", data, flow_style=True)

    def flow_dict(dumper: yaml.SafeDumper, data: dict[str, Any]) -> yaml.Node:
        return dumper.represent_mapping("tag:yaml.org,2002:map", data, flow_style=True)

    def text(dumper: yaml.SafeDumper, data: str) -> yaml.Node:
        # a multi-line text (a description) as a literal block; the emitter quotes it instead
        # when a block cannot hold it exactly
        if "\n" in data:
            return dumper.represent_scalar("tag:yaml.org,2002:str", data, style="|")
        return dumper.represent_str(data)

    def block_list(dumper: yaml.SafeDumper, data: list[Any]) -> yaml.Node:
        return dumper.represent_sequence("tag:yaml.org,2002:seq", data, flow_style=False)

    def block_dict(dumper: yaml.SafeDumper, data: dict[str, Any]) -> yaml.Node:
        return dumper.represent_mapping("tag:yaml.org,2002:map", data, flow_style=False)

    _Dumper.add_representer(_FlowList, flow_list)
    _Dumper.add_representer(_FlowDict, flow_dict)
    _Dumper.add_representer(_BlockList, block_list)
    _Dumper.add_representer(_BlockDict, block_dict)
    _Dumper.add_representer(str, text)
    return _Dumper


#: random bytes in the name of a temporary file of :func:`atomic_output` (twice as many hex digits)
_TMP_BYTES = 6
#: the most characters of a file's name its temporary file's name repeats (a name is at most 255 bytes, and the
#: temporary one adds 18: a valid 240-character name was refused)
_TMP_STEM = 200


def _tmp_stem(name: str) -> str:
    """The part of a file's ``name`` its temporary file's name repeats: all of it, or, beyond :data:`_TMP_STEM`
    bytes (UTF-8), its start and a digest of the whole (so that two long names that start alike keep apart).

    >>> _tmp_stem("m.yaml"), len(_tmp_stem("a" * 240)), _tmp_stem("a" * 240) == _tmp_stem("a" * 239 + "b")
    ('m.yaml', 200, False)
    """
    raw = name.encode("utf-8", "surrogateescape")  # a name's limit is in bytes
    if len(raw) <= _TMP_STEM:
        return name
    return raw[: _TMP_STEM - 9].decode("utf-8", "ignore") + "~" + hashlib.sha256(raw).hexdigest()[:8]


def stray_temporaries(path: str | Path) -> list[Path]:
    """The temporary files :func:`atomic_output` may have left beside ``path`` (and its ``.bak``).

    Only regular files (not links) named exactly ``.NAME.<12 hex digits>.tmp`` or
    ``.NAME.bak.<12 hex digits>.tmp``, beside ``path`` and, for a symbolic link, beside the
    file it points to: what a process killed during a save leaves.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     d = pathlib.Path(tmp)
    ...     for name in (".m.yaml.0123456789ab.tmp", ".m.yaml.bak.0123456789ab.tmp", ".m.yaml.x.tmp", "m.yaml"):
    ...         _ = (d / name).write_text("")
    ...     sorted(p.name for p in stray_temporaries(d / "m.yaml"))
    ['.m.yaml.0123456789ab.tmp', '.m.yaml.bak.0123456789ab.tmp']
    """
    p = Path(path)
    found: list[Path] = []
    for q in dict.fromkeys([p, Path(os.path.realpath(p))]):
        stems = "|".join(re.escape(_tmp_stem(n)) for n in (q.name, q.name + ".bak"))
        rx = re.compile(rf"^\.(?:{stems})\.[0-9a-f]{{{2 * _TMP_BYTES}}}\.tmp$")
        try:
            names = os.listdir(q.parent)
        except OSError:
            continue
        for name in names:
            cand = q.parent / name
            with contextlib.suppress(OSError):
                same = any(os.path.samefile(cand, f) for f in found)
                if rx.match(name) and stat.S_ISREG(os.lstat(cand).st_mode) and not same:
                    found.append(cand)
    return found


def can_create_beside(path: str | Path) -> str | None:
    """Why a file cannot be written at ``path`` (its directory takes no new file: read-only, not ours, ``/proc``), or
    None: a temporary file of the name :func:`write_atomic` would use is created there exclusively and removed at
    once. A ``path`` that is a device or a pipe is written in place: nothing is created.

    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     can_create_beside(Path(tmp) / "out.yaml")
    """
    p = Path(path)
    try:
        target = _target(p, True)
        if _stream(p, target, True) is not None or os.path.isdir(target):
            return None  # written in place; a directory is said so by the caller
        probe = _tmp_name(target)
        os.close(_create(probe, None))
        probe.unlink()
    except OSError as exc:
        return str(exc.strerror or exc)
    return None


def _write_atomic(p: Path, text: str) -> None:
    """Write ``text`` (UTF-8) to ``p`` in one step (:func:`write_atomic`)."""
    write_atomic(p, text.encode("utf-8"), error=MechanismFileError)


def write_atomic(
    p: str | Path,
    data: bytes,
    follow: bool = True,
    error: type[LinkageError] = InputError,
    like: os.stat_result | None = None,
    before_replace: Callable[[Path], None] | None = None,
    label: str | None = None,
    like_open: bool = False,
) -> Path:
    """Write ``data`` to ``p`` in one step: a temporary file beside it, written, synced, then :func:`os.replace`.

    The temporary file is created exclusively, never through a link, and written through the
    descriptor that created it (never reopened by name); it takes the mode and, as far as the
    system allows, the owner and group of ``like`` (default: the file it replaces; a new file
    gets the umask's permissions).  Just before the rename its name must still be that
    descriptor's file, else nothing is replaced.  With ``follow`` a symbolic link ``p`` is
    followed (the file it points to is replaced and the link stays); without it the link
    itself is replaced by the new regular file, and nothing is ever written through it.
    ``before_replace``, when given, is called with the path about to be replaced as the last
    step before the rename (the new file complete and synced): whatever it raises stops the
    write, the old file stays, the temporary file is removed (the editor checks there that
    nobody changed the file since it was read).  A device or a pipe (``/dev/null``,
    ``/dev/full``, a FIFO; reached through a followed link too) is written in place: there is
    no file to replace, and a rename would put a regular file where the device was.

    ``like_open`` (a command's table output, which ``open`` wrote before): a file we may not write is refused, and
    one we may write in a directory that takes no new file is written in place (not in one step), as ``open`` does.

    Returns the path replaced; an ``OSError`` becomes ``error`` naming ``p`` (or ``label``: ``-o out.csv``).

    Examples
    --------
    >>> import pathlib, tempfile
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     d = pathlib.Path(tmp)
    ...     _ = (d / "victim").write_text("keep")
    ...     (d / "m.bak").symlink_to(d / "victim")
    ...     _ = write_atomic(d / "m.bak", b"new", follow=False)
    ...     (d / "m.bak").is_symlink(), (d / "victim").read_text(), (d / "m.bak").read_text()
    (False, 'keep', 'new')
    """
    with (
        _temporary(Path(p), follow, error, like, before_replace, label, like_open) as (fd, _),
        open(fd, "wb", closefd=False) as f,
    ):
        f.write(data)
    return _target(Path(p), follow)


def _target(p: Path, follow: bool) -> Path:
    """The path a write to ``p`` replaces: the file a symbolic link points to when ``follow``."""
    return Path(os.path.realpath(p)) if follow and p.is_symlink() else p


def _old_stat(target: Path) -> os.stat_result | None:
    """The file ``target`` replaces (not followed: a link's own mode is no file's), or None when there is none."""
    try:
        st = os.lstat(target)
    except FileNotFoundError:
        return None
    return st if stat.S_ISREG(st.st_mode) else None


@contextlib.contextmanager
def _temporary(
    p: Path,
    follow: bool,
    error: type[LinkageError],
    like: os.stat_result | None,
    before_replace: Callable[[Path], None] | None = None,
    label: str | None = None,
    like_open: bool = False,
) -> Iterator[tuple[int, Path]]:
    """A fresh temporary file beside ``p``'s target (its descriptor and name); on success it replaces the target.

    Created with ``O_CREAT | O_EXCL | O_NOFOLLOW`` (mode 0600, or the umask's for a file with no
    model to copy), given the model's owner (best effort) and mode through the descriptor,
    synced, and renamed over the target once its name is checked to be still the same file (and
    checked again after the rename: another user who can write the directory may still swap it in
    between, but then only puts a name of theirs in place, which that user could do anyway; nothing
    is ever written through it).  ``before_replace(target)`` runs last, just before the rename.
    A stream (:func:`_stream`) is written in place; with ``like_open`` so is a file we may write in a
    directory that takes no new file (not in one step then, as ``open`` would), and a file we may not
    write is refused.
    """
    name = label or shorten_path(str(p))
    try:
        target = _target(p, follow)
        stream = _stream(p, target, follow)
    except OSError as exc:  # a name too long to look up
        raise error(f"{name}: cannot write: {exc.strerror or exc}") from None
    if stream is not None:
        with _in_place(stream, error, label) as fd:
            yield fd, stream
        return
    if not target.name or target.name in (".", "..") or os.path.isdir(target):
        raise error(f"{name}: cannot write: it is a directory")
    old = _old_stat(target)
    model = like if like is not None else old
    if like_open and old is not None and not os.access(target, os.W_OK):
        raise error(f"{name}: cannot write: Permission denied")
    tmp = _tmp_name(target)
    try:
        fd = _create(tmp, model)
    except PermissionError as exc:
        if not like_open or old is None:
            raise error(f"{name}: cannot write: {exc.strerror or exc}") from None
        with _in_place(target, error, label, truncate=True) as fd:  # the directory takes no new file
            yield fd, target
        return
    except OSError as exc:
        raise error(f"{name}: cannot write: {exc.strerror or exc}") from None
    done = False
    try:
        yield fd, tmp
        _commit(fd, tmp, target, model, error, before_replace)
        done = True
    except OSError as exc:
        raise error(f"{label or shorten_path(str(target))}: cannot write: {exc.strerror or exc}") from None
    finally:
        os.close(fd)
        if not done:
            with contextlib.suppress(OSError):
                tmp.unlink()


def _tmp_name(target: Path) -> Path:
    """A fresh temporary file's name beside ``target``: ``.NAME.<12 hex digits>.tmp`` (:func:`stray_temporaries`)."""
    return target.with_name(f".{_tmp_stem(target.name)}.{secrets.token_hex(_TMP_BYTES)}.tmp")


def _create(tmp: Path, model: os.stat_result | None) -> int:
    """The temporary file ``tmp``, created exclusively, never through a link (0600 with a model, else the umask's)."""
    flags = os.O_RDWR | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_CLOEXEC", 0)
    return os.open(tmp, flags, 0o600 if model is not None else 0o666)  # no model: the umask applies, as for open()


def _commit(
    fd: int,
    tmp: Path,
    target: Path,
    model: os.stat_result | None,
    error: type[LinkageError],
    before_replace: Callable[[Path], None] | None,
) -> None:
    """The written temporary file ``tmp`` (open as ``fd``) given the model's owner and mode, synced, checked to be
    still ours, and renamed over ``target`` (:func:`_temporary`)."""
    if model is not None:
        _take_owner_and_mode(fd, model)
    os.fsync(fd)
    if not os.path.samestat(os.lstat(tmp), os.fstat(fd)):
        raise error(f"{target}: not written: its temporary file {tmp.name} was replaced by another program")
    if before_replace is not None:
        before_replace(target)
    os.replace(tmp, target)
    if not os.path.samestat(os.lstat(target), os.fstat(fd)):  # swapped between the check and the rename
        raise error(f"{target}: another program replaced its temporary file {tmp.name} as it was renamed")


def _stream(p: Path, target: Path, follow: bool) -> Path | None:
    """The path to write in place when ``p`` is a stream (:func:`_is_stream`): ``p`` itself where a followed link
    leads to one (``/dev/stdout`` is a link to ``/proc/self/fd/1``, whose own target reads ``pipe:[...]``, no
    path), else ``target`` when it is one; None for a file to replace."""
    if follow:
        try:
            mode = os.stat(p).st_mode
        except OSError:
            mode = 0
        if stat.S_ISCHR(mode) or stat.S_ISBLK(mode) or stat.S_ISFIFO(mode) or stat.S_ISSOCK(mode):
            return p
    return target if _is_stream(target) else None


def _is_stream(target: Path) -> bool:
    """Is ``target`` (a link already followed, or not to be followed) a device or a pipe (``/dev/null``, ``/dev/full``,
    a FIFO): a stream written in place, not a file to replace (a rename would put a regular file where the device
    was)?"""
    try:
        mode = os.lstat(target).st_mode
    except OSError:
        return False
    return stat.S_ISCHR(mode) or stat.S_ISBLK(mode) or stat.S_ISFIFO(mode) or stat.S_ISSOCK(mode)


@contextlib.contextmanager
def _in_place(
    target: Path, error: type[LinkageError], label: str | None = None, truncate: bool = False
) -> Iterator[int]:
    """A descriptor open for writing on the stream ``target`` (:func:`_is_stream`; ``truncate``: a regular file,
    emptied first); an ``OSError`` (``/dev/full``: no space left on the device) becomes ``error`` naming it, except
    ``BrokenPipeError`` (a reader gone)."""
    fd = -1
    try:
        fd = os.open(target, os.O_WRONLY | (os.O_TRUNC if truncate else 0) | getattr(os, "O_CLOEXEC", 0))
        yield fd
    except BrokenPipeError:  # a pipe whose reader has gone: the reader's choice, not a fault of the path
        raise
    except OSError as exc:
        raise error(f"{label or shorten_path(str(target))}: cannot write: {exc.strerror or exc}") from None
    finally:
        if fd >= 0:
            os.close(fd)


def _take_owner_and_mode(fd: int, model: os.stat_result) -> None:
    """Give the file of ``fd`` the owner and group of ``model`` (as far as allowed), then its permissions."""
    mine = os.fstat(fd)
    if hasattr(os, "fchown") and (mine.st_uid, mine.st_gid) != (model.st_uid, model.st_gid):
        try:
            os.fchown(fd, model.st_uid, model.st_gid)  # only root may give a file another owner
        except PermissionError:
            with contextlib.suppress(PermissionError):
                os.fchown(fd, -1, model.st_gid)  # a user may give their file a group of theirs
    os.fchmod(fd, stat.S_IMODE(model.st_mode))  # after the owner: a chown may clear the set-id bits


@contextlib.contextmanager
def atomic_output(p: str | Path, error: type[LinkageError] = InputError) -> Iterator[Path]:
    """A temporary path beside ``p`` for a writer that takes a file name; on success it replaces ``p`` in one step.

    As :func:`write_atomic` (which writes bytes through the descriptor it creates, and should be
    preferred): the old file stays whole until the new one is complete, the new file keeps the old
    one's permissions and (as far as allowed) owner, a symbolic link is followed (the file it points
    to is replaced, the link stays), and the temporary file, created exclusively and never through
    a link, must still be the same file when it is renamed (a device or a pipe is written in place:
    the path yielded is its own).  On failure it is removed; an
    ``OSError`` becomes ``error`` naming ``p``.  A temporary file left by a killed process is
    named as :func:`stray_temporaries` finds it.
    """
    with _temporary(Path(p), True, error, None) as (_, tmp):
        yield tmp


#: seconds between two tries of :func:`locked` to take a lock another program holds
LOCK_POLL = 0.01


@contextlib.contextmanager
def locked(p: str | Path, seconds: float, fail: Callable[[str], LinkageError]) -> Iterator[int | None]:
    """Hold an advisory exclusive lock (``flock``) on the regular file ``p`` (a link followed) for the block.

    Writers that take the same lock before they read the file and keep it until they have written it
    (another ``linkagekit edit``, ``flock FILE command``) then never interleave with this one.  The lock is
    on the file, not on its name: once taken, the descriptor must still be the file named ``p`` (a
    writer that replaced it meanwhile, by a rename, is waited for again on the new file).  Waits at most
    ``seconds`` for a lock another program holds, else raises ``fail(message)``.  Yields the locked
    descriptor, or None when there is nothing to lock (no such file, not a regular file: the read that
    follows says why) or the system has no ``flock``.  The lock binds only writers that take it: nothing
    stops another program from writing the file without it.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     f = pathlib.Path(tmp) / "m.yaml"
    ...     _ = f.write_text("x")
    ...     with locked(f, 1.0, InputError) as fd, locked(f, 0.05, InputError):
    ...         pass
    Traceback (most recent call last):
    ...
    linkagekit.errors.InputError: locked by another program (it holds an flock on the file)
    """
    fd = _lock(Path(p), time.monotonic() + seconds, fail)
    try:
        yield fd
    finally:
        if fd is not None:
            os.close(fd)  # releases the lock


def _lock(p: Path, deadline: float, fail: Callable[[str], LinkageError]) -> int | None:
    """The descriptor of the file ``p`` now names, flock-ed exclusively (:func:`locked`), or None."""
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0) | getattr(os, "O_CLOEXEC", 0)
    while True:
        try:
            fd = os.open(p, flags)
        except (OSError, ValueError):
            return None
        try:
            if not (stat.S_ISREG(os.fstat(fd).st_mode) and _flock(fd, deadline, fail)):
                os.close(fd)
                return None
            with contextlib.suppress(OSError):
                if os.path.samestat(os.fstat(fd), os.stat(p)):
                    return fd
        except BaseException:
            os.close(fd)
            raise
        os.close(fd)  # replaced while it was waited for: lock the file that has the name now
        if time.monotonic() >= deadline:
            raise fail("locked by another program (it keeps replacing the file)")


def _flock(fd: int, deadline: float, fail: Callable[[str], LinkageError]) -> bool:
    """Take an exclusive flock on ``fd``, waiting until ``deadline`` (then ``fail``); False when the system has none
    (no ``fcntl``, or a file system that refuses it)."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover - Windows: no advisory locks of this kind
        return False
    while True:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            return True
        except BlockingIOError:
            if time.monotonic() >= deadline:
                raise fail("locked by another program (it holds an flock on the file)") from None
            time.sleep(LOCK_POLL)
        except OSError:  # pragma: no cover - e.g. ENOLCK on a network file system without locks
            return False
