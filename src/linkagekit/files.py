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
import json
import os
import re
import secrets
import stat
from functools import cache
from pathlib import Path
from typing import Any, Literal

from .errors import InputError, MechanismFileError
from .model import Mechanism

__all__ = ["dumps", "load", "save"]

#: YAML 1.2 core schema booleans (PyYAML's YAML 1.1 also takes yes/no/on/off).
_BOOL = re.compile(r"^(?:true|True|TRUE|false|False|FALSE)$")
_BOOL_TAG = "tag:yaml.org,2002:bool"


@cache
def _loader_class(pure: bool = False) -> type[Any]:
    """A safe YAML loader with YAML 1.2 booleans: libyaml's C parser unless ``pure``, or unavailable."""
    import yaml

    base: type[Any] = yaml.CSafeLoader if (yaml.__with_libyaml__ and not pure) else yaml.SafeLoader
    doc = "PyYAML's safe loader with YAML 1.2 booleans: only true/false, so `on:` stays a key."
    cls: type[Any] = type("_PyLoader" if base is yaml.SafeLoader else "_Loader", (base,), {"__doc__": doc})
    # the number, null, ... rules of the safe loader; booleans narrowed to true/false
    cls.yaml_implicit_resolvers = {
        ch: [(tag, rx) for tag, rx in resolvers if tag != _BOOL_TAG]
        for ch, resolvers in base.yaml_implicit_resolvers.items()
    }
    cls.add_implicit_resolver(_BOOL_TAG, _BOOL, list("tTfF"))
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
def _path(path: Any, what: str) -> Path:
    """A file path argument, or one clear error."""
    if not isinstance(path, str | os.PathLike):
        raise InputError(f"{what}: expected a file path, got {type(path).__name__}")
    return Path(path)


def load(path: str | Path) -> Mechanism:
    """Read a mechanism file (YAML, or JSON when the suffix is ``.json``).  Reading never executes anything.

    Parameters
    ----------
    path : str or Path
        The file.

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
    try:
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise MechanismFileError(f"{p}: no such file") from None
    except IsADirectoryError:
        raise MechanismFileError(f"{p}: is a directory, not a mechanism file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise MechanismFileError(f"{p}: cannot read: {exc}") from None
    if p.suffix.lower() == ".json":
        try:
            data = json.loads(text)
        except json.JSONDecodeError as exc:
            raise MechanismFileError(
                f"{p}: JSON syntax error at line {exc.lineno}, column {exc.colno}: {exc.msg}"
            ) from None
    else:
        import yaml

        try:
            data = yaml.load(text, Loader=_loader_class())  # noqa: S506 - a safe loader
        except yaml.YAMLError as exc:
            mark = getattr(exc, "problem_mark", None)
            where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark is not None else ""
            problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
            raise MechanismFileError(f"{p}: YAML syntax error{where}: {problem}") from None
    return Mechanism.from_dict(data, source=str(p))


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


def dumps(mech: Mechanism, fmt: Literal["yaml", "json"] = "yaml") -> str:
    """The text of a mechanism file, YAML (readable: block style, points as flow lists) or JSON.

    Examples
    --------
    >>> from linkagekit.files import dumps, load
    >>> print(dumps(load("examples/seed000_fourbar.yaml")).splitlines()[2])
    units: {length: cm, angle: deg}
    """
    data = mech.to_dict()
    if fmt == "json":
        return _json(data) + "\n"
    if fmt != "yaml":
        raise MechanismFileError(f"unknown mechanism file format '{fmt}' (yaml or json)")
    import yaml

    text: str = yaml.dump(
        _styled(data),
        Dumper=_dumper_class(),
        sort_keys=False,
        default_flow_style=False,
        allow_unicode=True,
        width=120,
    )
    return text


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
        elif key in {"sliders", "loads"}:
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

    _Dumper.add_representer(_FlowList, flow_list)
    _Dumper.add_representer(_FlowDict, flow_dict)
    _Dumper.add_representer(str, text)
    return _Dumper


def _write_atomic(p: Path, text: str) -> None:
    """Write ``text`` (UTF-8) to ``p`` through a temporary file in the same directory and :func:`os.replace`."""
    data = text.encode("utf-8")
    tmp = p.with_name(f".{p.name}.{secrets.token_hex(6)}.tmp")
    done = False
    try:
        try:
            mode = stat.S_IMODE(os.stat(p).st_mode)
        except FileNotFoundError:
            mode = None
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)  # the umask applies, as for open()
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        if mode is not None:
            os.chmod(tmp, mode)  # keep the permissions of the file it replaces
        os.replace(tmp, p)
        done = True
    except OSError as exc:
        raise MechanismFileError(f"{p}: cannot write: {exc.strerror or exc}") from None
    finally:
        if not done:
            with contextlib.suppress(OSError):
                tmp.unlink()
