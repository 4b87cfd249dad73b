"""Fuzzing the ways in (issue 9): mutated mechanism files, mutated command lines, wrong Python calls.

The contract checked for every case:

* the command line (run in-process through :func:`linkagekit.cli.main`) exits 0 with valid output
  (``--format json`` parses, with no NaN/Infinity), or exits 2 with exactly one line on stderr:
  ``linkagekit: error: ...``, at most 300 characters, no control characters; exit 1 only for a
  valid mechanism that needs the numerical solver ("no triangulation order"); never
  ``internal error``, never a traceback, never a warning on stderr, never ESC on stdout; with
  exit 0, stderr holds nothing but ``linkagekit: note: ...`` lines (at most 300 characters each);
* every case ends within ``LINKAGEKIT_FUZZ_TIMEOUT`` CPU-seconds (default 10; CPU time, so a busy machine
  does not fail it; a case that blocks without computing fails after ten times that on the clock): a hang fails;
* the Python API returns, or raises a :class:`linkagekit.errors.LinkageError`; positions it
  returns as assembled keep every link's lengths.

``tests/corpus/`` holds the cases that once failed (the list of issue 9 and what the fuzzer
found since): :func:`test_corpus_cli` and :func:`test_corpus_api` run them on every test run.

The fuzz tests are hypothesis-based and derandomized (the same cases on every run).  Each
collects every failing case of its run and fails once at the end with a grouped summary, so
one run shows everything that is broken (no shrinking; the failing inputs are printed, and
saved under ``LINKAGEKIT_FUZZ_SAVE=DIR`` when set, ready to become corpus files).

Sizes: ``LINKAGEKIT_FUZZ_EXAMPLES`` cases per fuzz test (default 300: the whole file runs in
well under a minute).  The long run (10^4 cases per fuzz test, a different seed per run)::

    LINKAGEKIT_FUZZ_EXAMPLES=10000 LINKAGEKIT_FUZZ_RANDOM=1 LINKAGEKIT_FUZZ_SAVE=/tmp/fuzz/found \\
        pytest tests/test_fuzz.py -k test_fuzz_ -p no:cacheprovider -q
"""

from __future__ import annotations

import contextlib
import copy
import io
import json
import math
import os
import re
import signal
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

import linkagekit as lk
from linkagekit.cli import main
from linkagekit.errors import LinkageError

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"
CORPUS = Path(__file__).resolve().parent / "corpus"

N_EXAMPLES = int(os.environ.get("LINKAGEKIT_FUZZ_EXAMPLES", "300"))
TIMEOUT = float(os.environ.get("LINKAGEKIT_FUZZ_TIMEOUT", "10"))
SAVE = os.environ.get("LINKAGEKIT_FUZZ_SAVE")
FUZZ = settings(
    max_examples=N_EXAMPLES,
    deadline=None,
    derandomize=not os.environ.get("LINKAGEKIT_FUZZ_RANDOM"),
    database=None,
    phases=[Phase.explicit, Phase.generate],
    suppress_health_check=list(HealthCheck),
    print_blob=False,
)
MAX_LINE = 300
PREFIX = "linkagekit: error: "
CONTROL = re.compile(r"[\x00-\x1f\x7f]")


# ---------------------------------------------------------------------- running one case
class Hang(BaseException):
    """Raised by the alarm: a BaseException, so that no ``except Exception`` in the library swallows it."""


#: a case that waits instead of computing (no CPU time spent) fails after this many times its CPU budget on the clock
WALL_FACTOR = 10


@contextlib.contextmanager
def time_limit(seconds: float = TIMEOUT):
    """Fail a case that uses more than *seconds* of CPU time, or waits ``WALL_FACTOR`` times as long on the clock.

    The budget is CPU time of this process (user + system, ``ITIMER_PROF``), which a machine busy with other
    work does not inflate, so a slow but finite case passes there too (an editor solve of a class-3 mechanism
    costs about 1.25 CPU-s). A loop that spins is stopped by the CPU budget; one that blocks (a lock, a read)
    spends no CPU time and is stopped by the generous wall-clock limit (``ITIMER_REAL``). Main thread only.
    """

    def fire(signum, frame):
        what = "CPU-s" if signum == signal.SIGPROF else "s on the clock"
        raise Hang(f"no answer within {seconds * (1 if signum == signal.SIGPROF else WALL_FACTOR):g} {what}")

    old = {sig: signal.signal(sig, fire) for sig in (signal.SIGPROF, signal.SIGALRM)}
    signal.setitimer(signal.ITIMER_PROF, seconds)
    signal.setitimer(signal.ITIMER_REAL, seconds * WALL_FACTOR)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_PROF, 0)
        signal.setitimer(signal.ITIMER_REAL, 0)
        for sig, handler in old.items():
            signal.signal(sig, handler)


def test_time_limit_counts_cpu_time_and_stops_a_blocked_case_on_the_clock() -> None:
    """Waiting (what a busy machine adds) is not charged to the CPU budget; spinning is; blocking ends too."""
    import time

    with time_limit(0.05):
        time.sleep(0.2)  # four times the budget on the clock, no CPU time: not a hang
    t = time.process_time()
    with pytest.raises(Hang, match="0.05 CPU-s"), time_limit(0.05):
        while time.process_time() - t < 5:
            pass
    assert time.process_time() - t < 1
    t = time.monotonic()
    with pytest.raises(Hang, match="0.5 s on the clock"), time_limit(0.05):
        time.sleep(5)
    assert time.monotonic() - t < 4


@dataclass
class Outcome:
    argv: list[str]
    code: int | None
    out: str
    err: str
    warned: list[str]
    problem: str | None = None  # an escaped exception or a hang


def run_cli(argv: list[str], seconds: float = TIMEOUT) -> Outcome:
    """``linkagekit ARGV`` in this process: exit code, stdout, stderr, warnings."""
    out, err = io.StringIO(), io.StringIO()
    code, problem = None, None
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err), time_limit(seconds):
                code = main(list(argv))
        except Hang as exc:
            problem = f"HANG: {exc}"
        except BaseException as exc:  # noqa: BLE001 - main must not let anything out
            problem = f"ESCAPED {type(exc).__name__}: {str(exc)[:200]}"
    warned = [
        f"{w.category.__name__}: {w.message}"
        for w in caught
        if not issubclass(w.category, DeprecationWarning | PendingDeprecationWarning | ImportWarning | ResourceWarning)
    ]
    return Outcome(list(argv), code, out.getvalue(), err.getvalue(), warned, problem)


def _no_constant(name: str) -> Any:
    raise ValueError(f"{name} in JSON output")


def contract_violation(o: Outcome, fmt: str = "json") -> str | None:
    """What is wrong with this outcome (None: it keeps the contract).  The first word is a category."""
    if o.problem:
        return o.problem
    if o.warned:
        return f"WARNING on stderr: {o.warned[0][:150]}"
    if "\x1b" in o.out:
        return "ESC on stdout"
    if o.code == 0:
        notes = o.err.splitlines()
        if not all(n.startswith("linkagekit: note: ") and len(n) <= MAX_LINE and n.isprintable() for n in notes):
            return f"STDERR with exit 0: {o.err[:150]!r}"
        if fmt == "json" and "-o" not in o.argv:
            try:
                json.loads(o.out, parse_constant=_no_constant)
            except ValueError as exc:
                return f"BAD JSON: {str(exc)[:150]}"
        return None
    if o.code not in (1, 2):
        return f"EXIT {o.code}: {o.err[:150]!r}"
    if "Traceback" in o.err:
        return "TRACEBACK"
    if "internal error" in o.err:
        return "INTERNAL " + o.err.strip()[:200]
    lines = o.err.split("\n")
    if len(lines) != 2 or lines[1] != "":
        return f"MULTILINE {len(lines) - 1} lines: {o.err[:150]!r}"
    line = lines[0]
    if not line.startswith(PREFIX):
        return f"PREFIX {line[:150]!r}"
    if CONTROL.search(line):
        return f"CONTROL character in message: {line[:150]!r}"
    if len(line) > MAX_LINE:
        return f"LONG message of {len(line)} characters: {line[:120]!r}..."
    if o.code == 1 and "no triangulation order" not in line:
        return f"EXIT 1 (not NotSolvable): {line[:200]}"
    return None


class Failures:
    """Every contract violation of one fuzz run, reported together at its end."""

    def __init__(self, name: str) -> None:
        self.name, self.items, self.n = name, [], 0

    def record(self, what: str, case: str, data: bytes | None = None, suffix: str = ".yaml") -> None:
        self.items.append((what, case))
        if SAVE and data is not None:
            d = Path(SAVE)
            d.mkdir(parents=True, exist_ok=True)
            (d / f"{self.name}-{len(self.items):05d}{suffix}").write_bytes(data)
            (d / f"{self.name}-{len(self.items):05d}.txt").write_text(f"{what}\n{case}\n", encoding="utf-8")

    def check(self) -> None:
        if not self.items:
            return
        groups: dict[str, list[str]] = {}
        for what, case in self.items:
            key = re.sub(r"'[^']*'|\d+(\.\d+)?", "_", what)[:90]
            groups.setdefault(key, []).append(f"{what[:220]}\n        case: {case[:400]}")
        lines = [f"{len(self.items)} of {self.n} {self.name} cases break the contract, {len(groups)} kinds:"]
        for _key, items in sorted(groups.items(), key=lambda kv: -len(kv[1])):
            lines.append(f"  [{len(items)}x] {items[0]}")
        pytest.fail("\n".join(lines), pytrace=False)


# ---------------------------------------------------------------------- mutated mechanism files
def _example_data() -> dict[str, dict[str, Any]]:
    return {p.stem: yaml.safe_load(p.read_text(encoding="utf-8")) for p in sorted(EXAMPLES.glob("*.yaml"))}


BASES = _example_data()
BASE_TEXT = {p.stem: p.read_bytes() for p in sorted(EXAMPLES.glob("*.yaml"))}

NAMES = [
    "[/x]",
    "[bold red]A[/]",
    "[link=http://x]y",
    "a\nb",
    "a\rb",
    "\x1b[31mred",
    "\x00",
    "\t",
    "\u202eevil",
    "\u200b",
    "é",
    "名前",
    "😀",
    "",
    " ",
    "A" * 1000,
    "x" * 65,
    "ground",
    "A-B",
    "C-D-E",
    "-",
    "1",
    "null",
    "on",
    "true",
    "<<",
    "*",
    "&a",
    "!!set",
    "%",
    "'",
    '"',
    "\\",
    "{}",
    "[]",
    "#",
    ":",
    "\ufeff",
]
NUMBERS = [
    0,
    -0.0,
    1,
    -1,
    0.5,
    1e-300,
    5e-324,
    1e12,
    1e12 + 1,
    -1e12 - 1,
    1e15,
    1e308,
    -1e308,
    1.7976931348623157e308,
    float("nan"),
    float("inf"),
    float("-inf"),
    10**20,
    10**400,
    -(10**401),
    2**63,
    -(2**64),
    360,
    1e6,
]
YAML_RAW = [
    "!!set {A, C}",
    "!!set {A: null}",
    "!!python/object/apply:os.getpid []",
    "!!python/object:builtins.object {}",
    "!!python/name:os.system",
    "!!binary aGVsbG8=",
    "!!timestamp 2001-12-14",
    "!!float 1",
    "!!str 5",
    "!!int '7'",
    "!!omap [a: 1]",
    "!!pairs [a: 1, a: 2]",
    "!custom 1",
    "!<tag:x.org,2002:y> 1",
    "&anc [1, 2]",
    "*undefined",
    "{<<: {x: 1}}",
    "{<<: [*undefined]}",
    "1e-4",
    "1.5e3",
    "1_000",
    "0x1F",
    "0o17",
    "0b101",
    "+.inf",
    "-.inf",
    ".nan",
    "~",
    "null",
    "yes",
    "off",
    "0:0:1",
    "1:30",
    "2001-12-14",
    "'[/x]'",
    '"\\x1b[31m"',
    '"\\0"',
    '"\\u202e"',
    "[1, 2",
    "{a: 1, a: 2}",
    "? [a, b]\n",
    "|\n  multi\n  line",
    "- a\n- b",
    "%YAML 1.1",
    "---",
    "...",
    "@x",
    "`x",
    "[" * 40 + "]" * 40,
    "[" * 600 + "]" * 600,
    "{a: " * 40 + "1" + "}" * 40,
    "1" * 400,
    "1" * 4400,
    "1e400",
    "-1e400",
    "9" * 64,
    "9" * 65,
    "0." + "0" * 80 + "1",
    "\t1",
    "\u00a01",
    "１",
    "٣",
    "1e",
    "e1",
    ".",
    "-",
    "+1",
    "[*a, *a]",
    "{x: &a [1, 1], y: [*a, *a]}",
]
JSON_RAW = [
    "NaN",
    "Infinity",
    "-Infinity",
    "1e400",
    "-1e400",
    "1" * 400,
    "1" * 4400,
    "1E-400",
    '{"a": 1, "a": 2}',
    "[" * 40 + "]" * 40,
    "[" * 600 + "]" * 600,
    '"\\ud800"',
    '"\\u0000"',
    '"\\u001b[31m"',
    "true",
    "null",
    "-0",
    "0.1e1",
    "[]",
    "{}",
    '"[/x]"',
    "01",
    ".5",
    "+1",
    "1.",
    "0x10",
    "'a'",
    "[1,]",
    "{,}",
    '"a" "b"',
    "// c\n1",
]
BOMB = (
    '{a: &a ["lol","lol","lol","lol","lol","lol","lol","lol","lol"], b: &b [*a,*a,*a,*a,*a,*a,*a,*a,*a], '
    "c: &c [*b,*b,*b,*b,*b,*b,*b,*b,*b], d: &d [*c,*c,*c,*c,*c,*c,*c,*c,*c], e: &e [*d,*d,*d,*d,*d,*d,*d,*d,*d], "
    "f: &f [*e,*e,*e,*e,*e,*e,*e,*e,*e], g: [*f,*f,*f,*f,*f,*f,*f,*f,*f]}"
)
MERGE_BOMB = (
    "{"
    + ", ".join(["x0: &x0 {a: 1}"] + [f"x{i}: &x{i} {{<<: [*x{i - 1}, *x{i - 1}], k{i}: 1}}" for i in range(1, 22)])
    + "}"
)
YAML_RAW += [BOMB, MERGE_BOMB]

scalars = st.one_of(
    st.sampled_from(NUMBERS),
    st.floats(),
    st.integers(),
    st.sampled_from(NAMES),
    st.text(max_size=12),
    st.booleans(),
    st.none(),
)
values = st.recursive(
    scalars,
    lambda c: st.lists(c, max_size=4) | st.dictionaries(st.sampled_from(NAMES) | st.text(max_size=6), c, max_size=3),
    max_leaves=8,
)


def _paths(node: Any, prefix: tuple = ()) -> list[tuple]:
    out = [prefix]
    if isinstance(node, dict):
        for k, v in node.items():
            out += _paths(v, (*prefix, k))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            out += _paths(v, (*prefix, i))
    return out


def _get(node: Any, path: tuple) -> Any:
    for k in path:
        node = node[k]
    return node


def _neighbours(v: float) -> list[float]:
    """Numbers near, far from and opposite to ``v``."""
    try:
        v = float(v)
    except OverflowError:
        return [0.0]
    return [v * 10.0**k for k in (-300, -12, -6, 6, 11, 13, 300)] + [-v, v + 1e-9, v * (1 + 1e-15)]


def _rename_everywhere(node: Any, old: str, new: str) -> Any:
    """Rename a joint or link: keys, values, and the ``X-Y`` keys of ``lengths``."""

    def name(s: Any) -> Any:
        if not isinstance(s, str):
            return s
        if s == old:
            return new
        parts = s.split("-")
        return "-".join(new if p == old else p for p in parts) if old in parts and len(parts) == 2 else s

    if isinstance(node, dict):
        return {name(k): _rename_everywhere(v, old, new) for k, v in node.items()}
    if isinstance(node, list):
        return [_rename_everywhere(v, old, new) for v in node]
    return name(node)


OPS = [
    "number",
    "number",
    "number",
    "delete",
    "set",
    "set",
    "rename_key",
    "rename_entity",
    "duplicate",
    "raw",
    "raw",
    "wrap",
    "type_swap",
    "empty",
]


@st.composite
def mechanism_files(draw) -> tuple[str, bytes, str, str]:
    """(example name, file bytes, suffix, description): an example with 1-4 mutations, as YAML or JSON."""
    name = draw(st.sampled_from(sorted(BASES)))
    as_json = draw(st.integers(0, 3)) == 0
    if not as_json and draw(st.integers(0, 9)) == 0:  # the shipped text itself (comments, flow style)
        data, raw, ops = None, {}, ["original text"]
        text = BASE_TEXT[name].decode("utf-8")
    else:
        data = copy.deepcopy(BASES[name])
        raw: dict[str, str] = {}
        ops = []
        for _ in range(draw(st.sampled_from([1, 1, 1, 2, 2, 3, 4]))):
            op = draw(st.sampled_from(OPS))
            paths = _paths(data)
            if op == "number":  # a number of the file (coordinates, lengths, masses, sweeps) changed to another
                paths = [
                    p for p in paths if isinstance(_get(data, p), int | float) and not isinstance(_get(data, p), bool)
                ]
                if not paths:
                    op, paths = "set", _paths(data)
            path = draw(st.sampled_from(paths))
            ops.append(f"{op}@{'.'.join(map(str, path))}")
            parent = _get(data, path[:-1]) if path else None
            key = path[-1] if path else None
            if op == "rename_entity":
                if not isinstance(data, dict):
                    continue
                names = sorted(set(data.get("joints", {}) if isinstance(data.get("joints"), dict) else {}))
                names += sorted(data.get("links", {}) if isinstance(data.get("links"), dict) else {})
                if names:
                    old, new = draw(st.sampled_from(names)), draw(st.sampled_from(NAMES) | st.text(max_size=8))
                    ops[-1] = f"rename {old!r}->{new!r}"
                    data = _rename_everywhere(data, old, new)
                continue
            if parent is None:  # the root
                if op in ("set", "type_swap", "number"):
                    data = draw(values)
                continue
            if op == "delete":
                del parent[key]
            elif op == "number":
                parent[key] = draw(
                    st.sampled_from(NUMBERS) | st.floats() | st.integers() | st.sampled_from(_neighbours(parent[key]))
                )
            elif op == "set":
                parent[key] = draw(values)
            elif op == "rename_key" and isinstance(parent, dict):
                parent[draw(st.sampled_from(NAMES) | st.text(max_size=6))] = parent.pop(key)
            elif op == "duplicate":
                if isinstance(parent, dict):
                    token = f"__DUP{len(raw)}__"
                    raw[token] = str(key)
                    parent[token] = draw(st.sampled_from([copy.deepcopy(parent[key]), None, 1]))
                else:
                    parent.insert(key, copy.deepcopy(parent[key]))
            elif op == "raw":
                token = f"__RAW{len(raw)}__"
                raw[token] = draw(st.sampled_from(JSON_RAW if as_json else YAML_RAW))
                parent[key] = token
                ops[-1] += f"={raw[token][:40]!r}"
            elif op == "wrap":
                parent[key] = draw(st.sampled_from([[parent[key]], {"x": parent[key]}, [[[parent[key]]]]]))
            elif op == "type_swap":
                v = parent[key]
                parent[key] = (
                    {str(i): x for i, x in enumerate(v)}
                    if isinstance(v, list)
                    else list(v.values())
                    if isinstance(v, dict)
                    else str(v)
                    if isinstance(v, int | float) and not isinstance(v, bool)
                    else [v]
                )
            elif op == "empty":
                parent[key] = draw(st.sampled_from([[], {}, "", None]))
        if as_json:
            text = json.dumps(data, indent=draw(st.sampled_from([None, 1])), ensure_ascii=draw(st.booleans()))
        else:
            text = yaml.safe_dump(
                data,
                sort_keys=False,
                allow_unicode=draw(st.booleans()),
                width=10**6,
                default_flow_style=draw(st.sampled_from([None, False])),
            )
        for token, snippet in raw.items():
            if token.startswith("__DUP"):
                text = text.replace(
                    json.dumps(token) if as_json else token, json.dumps(snippet) if as_json else snippet
                )
            else:
                text = text.replace(json.dumps(token) if as_json else token, snippet)
    data_bytes = text.encode("utf-8", "surrogatepass")
    # byte-level damage, sometimes
    for _ in range(draw(st.integers(0, 2)) if draw(st.integers(0, 3)) == 0 else 0):
        kind = draw(st.sampled_from(["bom", "truncate", "flip", "insert", "crlf", "tabs", "nul"]))
        ops.append(kind)
        n = len(data_bytes)
        at = draw(st.integers(0, max(n - 1, 0)))
        if kind == "bom":
            data_bytes = b"\xef\xbb\xbf" + data_bytes
        elif kind == "truncate":
            data_bytes = data_bytes[:at]
        elif kind == "flip" and n:
            data_bytes = data_bytes[:at] + bytes([draw(st.integers(0, 255))]) + data_bytes[at + 1 :]
        elif kind == "insert":
            data_bytes = data_bytes[:at] + draw(st.binary(min_size=1, max_size=4)) + data_bytes[at:]
        elif kind == "crlf":
            data_bytes = data_bytes.replace(b"\n", b"\r\n")
        elif kind == "tabs":
            data_bytes = data_bytes.replace(b"  ", b"\t", 1)
        elif kind == "nul":
            data_bytes = data_bytes[:at] + b"\x00" + data_bytes[at:]
    return name, data_bytes, ".json" if as_json else draw(st.sampled_from([".yaml", ".yaml", ".yml"])), " ".join(ops)


def _driver_names(example: str) -> list[str]:
    return [
        d["link"]
        if "link" in d
        else d.get("name", "-".join(d["cylinder"]))
        if "cylinder" in d
        else f"slider{d['slider']}"
        for d in BASES[example]["drivers"]
    ]


def _at_args(example: str, value: str) -> list[str]:
    names = _driver_names(example)
    if len(names) == 1:
        return ["--at", value]
    return [a for n in names for a in ("--at", f"{n}={value}")]


@pytest.fixture(scope="module")
def fuzzdir(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("fuzz")


_mechanism_failures = Failures("file")


@FUZZ
@given(case=mechanism_files(), command=st.integers(0, 9), at=st.sampled_from(["0", "45", "90", "-30", "1e3", "1e11"]))
def _fuzz_mechanism_file(fuzzdir: Path, case, command: int, at: str) -> None:
    example, data, suffix, desc = case
    path = fuzzdir / f"case{suffix}"
    path.write_bytes(data)
    fmt = "table" if command == 9 else "json"
    at_args = _at_args(example, at)
    if command == 9:  # a table, of one of the three commands
        argv = [["check", str(path)], ["analyze", str(path), *at_args], ["modes", str(path), *at_args, "--mirrors"]][
            len(data) % 3
        ]
    elif command < 3:
        argv = ["check", str(path), "--format", "json"]
    elif command < 6:
        argv = ["analyze", str(path), *at_args, "--format", "json"]
    else:
        argv = ["modes", str(path), *at_args, "--format", "json"] + (["--mirrors"] if command == 8 else [])
    _mechanism_failures.n += 1
    o = run_cli(argv)
    bad = contract_violation(o, fmt)
    if bad:
        _mechanism_failures.record(bad, f"{example} [{desc}] {' '.join(argv[:1] + argv[2:])}", data, suffix)


def test_fuzz_mechanism_files(fuzzdir: Path) -> None:
    """Mutated example files through check / analyze / modes: exit 0 with valid output or 2 with one clean line."""
    _mechanism_failures.items, _mechanism_failures.n = [], 0
    _fuzz_mechanism_file(fuzzdir)
    _mechanism_failures.check()


_picture_failures = Failures("picture")
#: the picture commands are slower (matplotlib, a page): a tenth as many cases
PICTURES = settings(FUZZ, max_examples=max(N_EXAMPLES // 10, 10))


@PICTURES
@given(case=mechanism_files(), command=st.integers(0, 2))
def _fuzz_picture(fuzzdir: Path, case, command: int) -> None:
    example, data, suffix, desc = case
    path = fuzzdir / f"picture{suffix}"
    path.write_bytes(data)
    name = ("report", "plot", "animate")[command]
    out = fuzzdir / ("out.html", "out.png", "out.gif")[command]
    out.unlink(missing_ok=True)
    argv = [name, str(path), "-o", str(out)] + (["--frames", "36"] if name == "animate" else [])
    _picture_failures.n += 1
    o = run_cli(argv)
    bad = contract_violation(o, "none")
    if bad is None and o.code == 0:
        if not out.is_file() or out.stat().st_size == 0:
            bad = "NO OUTPUT with exit 0"
        elif name == "report":
            m = re.search(r'id="lk-scene">(.*?)</script>', out.read_text(encoding="utf-8"), re.S)
            try:
                json.loads(m.group(1) if m else "", parse_constant=_no_constant)
            except ValueError as exc:
                bad = f"BAD SCENE JSON in the page: {str(exc)[:150]}"
    elif bad is None and out.exists():
        bad = f"OUTPUT LEFT with exit {o.code}"
    if bad:
        _picture_failures.record(bad, f"{example} [{desc}] {name}", data, suffix)


def test_fuzz_picture_commands(fuzzdir: Path) -> None:
    """Mutated example files through report / plot / animate: a whole output and exit 0, or exit 2 and one line."""
    _picture_failures.items, _picture_failures.n = [], 0
    _fuzz_picture(fuzzdir)
    _picture_failures.check()


_editor_failures = Failures("editor")


@PICTURES
@given(case=mechanism_files(), coarse=st.booleans(), move=st.booleans())
def _fuzz_editor(fuzzdir: Path, case, coarse: bool, move: bool) -> None:
    """What the page may send the editor: a mutated document, maybe with a moved joint."""
    from linkagekit.web.editor import Session

    example, data, suffix, desc = case
    try:
        doc = json.loads(data) if suffix == ".json" else yaml.safe_load(data)
    except (ValueError, yaml.YAMLError):
        return  # not a document the page could hold
    session = _editor_sessions.setdefault(example, Session(EXAMPLES / f"{example}.yaml"))
    request: dict[str, Any] = {"doc": doc, "coarse": coarse}
    if move and isinstance(doc, dict) and isinstance(doc.get("joints"), dict) and doc["joints"]:
        request["pose"] = {next(iter(doc["joints"])): [0.5, -0.25]}
    _editor_failures.n += 1
    try:
        with time_limit(TIMEOUT):
            answer = session.solve(request)
        json.dumps(answer, allow_nan=False)  # what the server sends must be strict JSON
    except lk.LinkageError as exc:
        if "\n" in str(exc) or not str(exc):
            _editor_failures.record(f"MESSAGE {str(exc)[:150]!r}", f"{example} [{desc}]", data, suffix)
    except Hang as exc:
        _editor_failures.record(f"HANG: {exc}", f"{example} [{desc}]", data, suffix)
    except Exception as exc:  # noqa: BLE001 - the server would answer 500: a defect
        _editor_failures.record(f"ESCAPED {type(exc).__name__}: {str(exc)[:150]}", f"{example} [{desc}]", data, suffix)


_editor_sessions: dict[str, Any] = {}


def test_fuzz_editor_requests(fuzzdir: Path) -> None:
    """Mutated documents sent to the editor's solver: an answer in strict JSON, or one clean LinkageError."""
    _editor_failures.items, _editor_failures.n = [], 0
    _fuzz_editor(fuzzdir)
    _editor_failures.check()


# ---------------------------------------------------------------------- mutated command lines
NUMBER_TEXT = st.one_of(
    st.sampled_from(
        [
            "0",
            "90",
            "-90",
            "1e308",
            "-1e308",
            "1e300",
            "5e6",
            "1e12",
            "1e13",
            "nan",
            "NaN",
            "inf",
            "-inf",
            "Infinity",
            "",
            " ",
            "1" * 400,
            "1" * 5000,
            "0x10",
            "1_0",
            "١٢",
            "1e-400",
            "--",
            "-",
            "+",
            ".",
            "1e",
            "e",
            "\x00",
            "\x1b[31m",
            "[/x]",
            "a\nb",
            "é",
            "-0",
            "4.9e-324",
        ]
    ),
    st.floats().map(repr),
    st.integers(-(10**30), 10**30).map(str),
)


@st.composite
def option_values(draw, names: list[str]) -> str:
    """A value for --angles/--at/--speed/--acceleration: numbers joined by ',' and ':', maybe NAME=."""
    parts = draw(st.lists(NUMBER_TEXT, min_size=1, max_size=4))
    seps = draw(
        st.lists(st.sampled_from([",", ":", ",", ":", "", "=", ";", ",,"]), min_size=len(parts), max_size=len(parts))
    )
    text = "".join(p + s for p, s in zip(parts, seps, strict=True))[: -len(seps[-1]) or None]
    if draw(st.booleans()):
        text = draw(st.sampled_from(names + ["nobody", "", "ground", "[/x]", names[0] + "=" + names[0]])) + "=" + text
    return text


SAMPLE_RANGES = [
    "0:5e6:1",
    "1e308:-1e308:-1e300",
    "0:10:5,6",
    "0:360:0",
    "0:360:-1",
    "360:0:1",
    "0:1e12:1e-3",
    "0:360",
    "0:360:1:2",
    "::",
    "0:0:0",
    "0:200001:1",
    "0:5e5:1",
    "0:1:1e-300",
    "-1e12:1e12:1e5",
]


GOOD_NUMBER = st.one_of(
    st.floats(-720, 720).map(lambda v: f"{v:.6g}"),
    st.integers(-360, 360).map(str),
    st.sampled_from(["0", "90", "180", "1e-4", "1.5e3", "-0", "1e12", "-1e12", "1e11", "0.000001"]),
)
EXTRA_OPTIONS = [
    ["--static"],
    ["--method", "vector-loop"],
    ["--method", "nope"],
    ["--format", "csv"],
    ["--format", "table"],
    ["--format", "xml"],
    ["--mirrors"],
    ["-o"],
    ["--at"],
    ["--unknown"],
    ["-"],
    ["--"],
    ["--angles=0:10:1"],
    ["--speed=-5"],
    ["extra-positional"],
    ["--format=json"],
    ["--at", "=1"],
    ["--angles", "\x1b[2J"],
    ["-o", "/nonexistent-dir/x.json"],
    ["--speed", "1e308"],
    ["--acceleration", "-1e308"],
    ["--at", "nan"],
]


@st.composite
def command_lines(draw) -> tuple[str, list[str]]:
    """``analyze`` on an example: mostly plausible inputs and rates (so the solver runs), some mutated."""
    example = draw(st.sampled_from(["seed000_fourbar", "slider_crank", "fivebar_two_drivers", "jansen_leg"]))
    names = _driver_names(example)
    argv = ["analyze", str(EXAMPLES / f"{example}.yaml")]

    def per_driver(opt: str, value: Callable[[], str]) -> list[str]:
        if len(names) == 1 and draw(st.booleans()):
            return [opt, value()]
        return [x for n in names for x in (opt, f"{n}={value()}")]

    kind = draw(st.sampled_from(["at", "at", "angles", "angles", "none", "weird", "weird"]))
    if kind == "at":
        argv += per_driver("--at", lambda: ",".join(draw(st.lists(GOOD_NUMBER, min_size=1, max_size=5))))
    elif kind == "angles":
        argv += per_driver(
            "--angles",
            lambda: draw(
                st.sampled_from(SAMPLE_RANGES)
                | st.tuples(GOOD_NUMBER, GOOD_NUMBER, st.sampled_from(["1", "10", "45", "-5", "0.5", "1e-3"])).map(
                    ":".join
                )
            ),
        )
    elif kind == "weird":
        for _ in range(draw(st.integers(1, 3))):
            argv += [
                draw(st.sampled_from(["--angles", "--at", "--speed", "--acceleration"])),
                draw(option_values(names)),
            ]
    for opt in ("--speed", "--acceleration"):
        if draw(st.integers(0, 3)) == 0:
            argv += per_driver(opt, lambda: draw(GOOD_NUMBER | NUMBER_TEXT))
    if draw(st.integers(0, 3)) == 0:
        argv += draw(st.sampled_from(EXTRA_OPTIONS))
    if "--format" not in " ".join(argv) and draw(st.integers(0, 3)):
        argv += ["--format", "json"]
    return example, argv


_command_failures = Failures("argv")


@FUZZ
@given(case=command_lines())
def _fuzz_command_line(case) -> None:
    example, argv = case
    fmt = (
        "json"
        if ("--format" in argv and argv[argv.index("--format") + 1 :][:1] == ["json"]) or "--format=json" in argv
        else "other"
    )
    _command_failures.n += 1
    o = run_cli(argv)
    bad = contract_violation(o, fmt)
    if bad:
        _command_failures.record(bad, repr(argv[:1] + argv[2:]))


def test_fuzz_command_lines() -> None:
    """Mutated --angles/--at/--speed/--acceleration values and stray options on valid examples."""
    _command_failures.items, _command_failures.n = [], 0
    _fuzz_command_line()
    _command_failures.check()


# ---------------------------------------------------------------------- the Python API
def lengths_kept(mech: lk.Mechanism, res: lk.Result, rtol: float = 1e-6) -> str | None:
    """Where positions marked assembled break a link's length (single-design results)."""
    ok = np.asarray(res.assembled, bool)
    if ok.ndim != 1 or not ok.any():
        return None
    for link in mech.links:
        js = list(link.joints)
        for i, a in enumerate(js):
            for b in js[i + 1 :]:
                want = link.length(a, b)
                got = np.linalg.norm(res.xy(a)[ok] - res.xy(b)[ok], axis=-1)
                if not np.allclose(got, want, rtol=rtol, atol=rtol * max(1.0, abs(want))):
                    k = int(np.argmax(np.abs(got - want)))
                    return f"|{a}{b}| = {got[k]:.6g} on link {link.name}, should be {want:.6g} (marked assembled)"
    return None


_MECHS: dict[str, lk.Mechanism] = {}


def mech_of(name: str) -> lk.Mechanism:
    if name not in _MECHS:
        _MECHS[name] = lk.load(EXAMPLES / f"{name}.yaml")
    return _MECHS[name]


WEIRD = st.one_of(
    st.none(),
    st.booleans(),
    st.sampled_from(NUMBERS),
    st.floats(),
    st.integers(),
    st.sampled_from(NAMES),
    st.text(max_size=5),
    st.binary(max_size=4),
    st.complex_numbers(max_magnitude=10),
    st.sampled_from(
        [
            [],
            [[]],
            {},
            (),
            [0],
            [0.5],
            [7],
            [-1],
            [1],
            [float("nan")],
            [1, -1],
            [[1]],
            [1, 2, 3],
            set(),
            {1: 2},
            {"D": 0},
            {"D": 0.5},
            {"D": 7},
            {"D": float("nan")},
            {"D": "x"},
            {"nobody": 1},
            {"coupler": 2},
            {"coupler": float("nan")},
            {"crank": []},
            {"crank": [[0, 1]]},
            {"crank": "0"},
            {"crank": None},
            {"crank": np.zeros((2, 2))},
            {"crank": [float("inf")]},
            {"crank": [1e308]},
            {None: 1},
            {1: [0]},
            np.array([]),
            np.zeros((0, 3)),
            np.zeros((2, 3, 4)),
            np.array(["a"]),
            np.array([1 + 2j]),
            np.array([None], dtype=object),
            np.array(5.0),
            np.array([True, False]),
            np.full(3, np.nan),
            np.arange(3, dtype=np.int8),
            np.zeros((1, 5, 2)),
            np.zeros((2, 5, 2)),
            np.full((1, 5, 2), np.nan),
            np.full((1, 5, 2), 1e308),
            range(3),
            iter([1, 2]),
            object(),
            lk,
            print,
        ]
    ),
    st.lists(st.floats(), max_size=3),
)
PY_CALLS = ["load", "save", "analyze", "analyze_kw", "check", "modes", "from_dict", "with_pose", "link", "result"]
ANALYZE_KW = ["speed", "acceleration", "signs", "mirrors", "poses", "method", "rates", "dynamics", "static"]


_api_failures = Failures("api")


@FUZZ
@given(
    call=st.sampled_from(PY_CALLS),
    example=st.sampled_from(["seed000_fourbar", "slider_crank", "fivebar_two_drivers"]),
    a=WEIRD,
    b=WEIRD,
    kw=st.sampled_from(ANALYZE_KW),
    mutated=mechanism_files(),
    accessor=st.integers(0, 6),
)
def _fuzz_api(fuzzdir: Path, call: str, example: str, a, b, kw: str, mutated, accessor: int) -> None:
    mech = mech_of(example)
    desc = f"{call} {example} a={a!r:.80} b={b!r:.80} kw={kw}"
    check_lengths = False
    _api_failures.n += 1
    try:
        with warnings.catch_warnings(), time_limit():
            warnings.simplefilter("ignore")
            if call == "load":
                lk.load(a)
            elif call == "save":
                lk.save(a if isinstance(b, bool) else mech, b if not isinstance(b, str) else fuzzdir / f"out{b[:20]!r}")
            elif call == "analyze":
                lk.analyze(a if isinstance(b, bool) else mech, a)
            elif call == "analyze_kw":
                res = lk.analyze(mech, {d.name: [0.0, 30.0] for d in mech.drivers}, **{kw: b})
                check_lengths = kw in ("signs", "mirrors", "speed", "acceleration", "method", "rates")
                bad = lengths_kept(mech, res) if check_lengths else None
                if bad:
                    _api_failures.record(f"LIE {bad}", desc)
            elif call == "check":
                lk.check(a)
            elif call == "modes":
                lk.modes(mech, at=a, mirrors=b)
            elif call == "from_dict":
                _, data, suffix, d2 = mutated
                desc += f" [{d2}]"
                try:
                    parsed = json.loads(data) if suffix == ".json" else yaml.safe_load(data)
                except Exception:  # noqa: BLE001 - not even the test's own parser takes it
                    parsed = a
                lk.Mechanism.from_dict(parsed)
            elif call == "with_pose":
                mech.with_pose(a)
            elif call == "link":
                mech.link(a)
            elif call == "result":
                res = lk.analyze(mech, {d.name: [0.0, 30.0] for d in mech.drivers})
                getattr(res, ["xy", "omega", "design", "mechanism_of", "angle", "point", "alpha"][accessor])(a)
                if res.forces is not None:
                    res.forces.reaction(a, b)
    except LinkageError:
        pass
    except Hang as exc:
        _api_failures.record(f"HANG {exc}", desc)
    except BaseException as exc:  # noqa: BLE001
        _api_failures.record(f"RAISED {type(exc).__name__}: {str(exc)[:150]}", desc)


def test_fuzz_python_api(fuzzdir: Path) -> None:
    """Public functions called with wrong types, shapes and values: only LinkageError, never a lie."""
    _api_failures.items, _api_failures.n = [], 0
    _fuzz_api(fuzzdir)
    _api_failures.check()


# ---------------------------------------------------------------------- the corpus: cases that once failed
@dataclass
class Case:
    """``linkagekit ARGS`` (``{}`` is the corpus file) gives exit status in ``codes``; on exit 2 the message
    contains one of ``expect`` (case-insensitive) and none of ``forbid``; on exit 0 stdout contains ``out``."""

    file: str | None
    args: list[str]
    codes: tuple[int, ...] = (2,)
    expect: tuple[str, ...] = ()
    forbid: tuple[str, ...] = ()
    out: str | None = None
    seconds: float = TIMEOUT


FOURBAR = str(EXAMPLES / "seed000_fourbar.yaml")
SLIDER = str(EXAMPLES / "slider_crank.yaml")
J = ["--format", "json"]
CORPUS_CASES = {
    # internal errors (exit 1) in issue 9
    "empty ground link": Case("empty_ground_link.yaml", ["check", "{}", *J], expect=("ground",)),
    "401-digit speed": Case(
        "speed_401_digits.yaml", ["analyze", "{}", "--at", "0", *J], expect=("number", "digit", "speed")
    ),
    "4301-digit integer yaml": Case("int_4301_digits.yaml", ["check", "{}", *J], expect=("number", "digit")),
    "4301-digit integer json": Case("int_4301_digits.json", ["check", "{}", *J], expect=("number", "digit")),
    "lengths 1e308 on ternary": Case(
        "lengths_1e308_ternary.yaml", ["check", "{}", *J], expect=("C-D", "large", "lengths")
    ),
    "yaml nested 500": Case("nested_500.yaml", ["check", "{}", *J], expect=("deep", "depth", "nest")),
    "json nested 500": Case("nested_500.json", ["check", "{}", *J], expect=("deep", "depth", "nest")),
    "markup in a name, check": Case("markup_name.yaml", ["check", "{}"], codes=(0,), out="[/x]"),
    "markup in a name, analyze table": Case(
        "markup_name.yaml", ["analyze", "{}", "--at", "0,10"], codes=(0,), out="[/x]"
    ),
    "markup in a name, modes table": Case(
        "markup_name.yaml", ["modes", "{}", "--at", "0", "--mirrors"], codes=(0,), out="[/x]"
    ),
    "modes --mirrors table, slider": Case(None, ["modes", SLIDER, "--at", "90", "--mirrors"], codes=(0,)),
    "cg at 1e308": Case("cg_1e308.yaml", ["analyze", "{}", "--at", "90", *J], expect=("cg",)),
    "angles 1e308 range": Case(None, ["analyze", FOURBAR, "--angles", "1e308:-1e308:-1e300", *J], expect=("--angles",)),
    # hangs
    "angles 5e6 samples": Case(None, ["analyze", FOURBAR, "--angles", "0:5e6:1", *J], expect=("sample", "--angles")),
    "merge-key bomb": Case("merge_bomb_21.yaml", ["check", "{}", *J], expect=("merge", "<<")),
    "alias bomb": Case("alias_bomb.yaml", ["check", "{}", *J], expect=("alias", "values", "too many", "too large")),
    "modes, 12 sign joints": Case(
        "dyads_12.yaml", ["modes", "{}", "--at", "45", *J], codes=(0, 2), expect=("modes", "combinations", "signs")
    ),
    "modes, 12 sign joints, table": Case(
        "dyads_12.yaml", ["modes", "{}", "--at", "45"], codes=(0, 2), expect=("modes", "combinations", "signs")
    ),
    "modes, 13 sign joints": Case(
        "dyads_13.yaml", ["modes", "{}", "--at", "45", *J], codes=(0, 2), expect=("modes", "combinations", "signs")
    ),
    "analyze 400-dyad chain": Case(
        "dyads_400.yaml", ["analyze", "{}", "--at", "45", *J], codes=(0, 2), expect=("joints", "links", "too many")
    ),
    "check 400-dyad chain": Case(
        "dyads_400.yaml", ["check", "{}", *J], codes=(0, 2), expect=("joints", "links", "too many")
    ),
    "analyze 98-dyad chain": Case("dyads_98.yaml", ["analyze", "{}", "--angles", "40:50:1", *J], codes=(0,)),
    "check 98-dyad chain": Case("dyads_98.yaml", ["check", "{}", *J], codes=(0,)),
    # wrong exit code or message
    "two links on two joints": Case("same_two_joints.yaml", ["check", "{}", *J], expect=("rocker2", "same")),
    "driver on the coupler": Case("driver_on_coupler.yaml", ["check", "{}", *J], expect=("drivers", "driver")),
    "newline in a name": Case("newline_name.yaml", ["check", "{}"], expect=("name", "control", "\\n")),
    "ESC in a name": Case("esc_name.yaml", ["analyze", "{}", "--at", "0"], expect=("name", "control", "\\x1b", "\\e")),
    "speed 1e308": Case(
        None, ["analyze", FOURBAR, "--at", "0,90", "--speed", "1e308", *J], codes=(0, 2), expect=("--speed",)
    ),
    "acceleration 1e308": Case(
        None,
        ["analyze", FOURBAR, "--at", "0,90", "--acceleration", "1e308", *J],
        codes=(0, 2),
        expect=("--acceleration",),
    ),
    "python tag": Case("python_object_tag.yaml", ["check", "{}", *J], expect=("tag",), forbid=("syntax error",)),
    # silently accepted
    "duplicate keys yaml": Case("duplicate_keys.yaml", ["check", "{}", *J], expect=("duplicate key 'a'",)),
    "duplicate key line": Case("duplicate_keys.yaml", ["check", "{}", *J], expect=("line 8",)),
    "duplicate keys json": Case("duplicate_keys.json", ["check", "{}", *J], expect=("duplicate key 'format'",)),
    "joints as !!set": Case("set_joints.yaml", ["check", "{}", *J], expect=("set",)),
    "slider: true": Case("slider_true.yaml", ["check", "{}", *J], expect=("slider",)),
    # found by this fuzzer
    "angles 200001 samples": Case(None, ["analyze", FOURBAR, "--angles", "0:200000:1", *J], expect=("sample",)),
    "angles -1e12:1e12:1e7 (200001 samples)": Case(
        None, ["analyze", FOURBAR, "--angles", "-1e12:1e12:1e7", *J], expect=("sample",)
    ),
    "200000 samples of jansen_leg as json, in time": Case(
        None,
        ["analyze", str(EXAMPLES / "jansen_leg.yaml"), "--angles", "0:199999:1", *J],
        codes=(0, 2),
        expect=("sample",),
    ),
    "200000 samples of jansen_leg as csv, in time": Case(
        None,
        ["analyze", str(EXAMPLES / "jansen_leg.yaml"), "--angles", "0:199999:1", "--format", "csv"],
        codes=(0, 2),
        expect=("sample",),
    ),
    "long --angles value: line at most 300": Case(
        None, ["analyze", FOURBAR, "--angles", "0:1," + "1" * 400, *J], expect=("--angles",)
    ),
    "long driver name: line at most 300": Case(
        None, ["analyze", FOURBAR, "--speed", "x" * 400 + "=1", *J], expect=("--speed",)
    ),
    "long file name: line at most 300": Case(
        None, ["check", "/nonexistent/" + "d" * 250 + ".yaml"], expect=("no such file", "nonexistent")
    ),
    "vector-loop on a five-bar": Case(
        None,
        ["analyze", str(EXAMPLES / "fivebar_two_drivers.yaml"), "--method", "vector-loop", *J],
        expect=("vector-loop",),
    ),
    "angles 0:10:5,6": Case(None, ["analyze", FOURBAR, "--angles", "0:10:5,6", *J], expect=("--angles",)),
    "yaml 1.2 numbers": Case("yaml12_numbers.yaml", ["analyze", "{}", "--at", "0", *J], codes=(0,)),
    "json with BOM": Case("bom.json", ["analyze", "{}", "--at", "0", *J], codes=(0,)),
    "yaml with BOM": Case("bom.yaml", ["analyze", "{}", "--at", "0", *J], codes=(0,)),
    # issue 23: the numerical walk's reach, files that are not regular files, names, --angles counts; since
    # issue 29 a crank's input is a direction: 1e11 and 1e5 deg are 280 deg, inside the triad's range
    "class-3 group at 1e11 deg": Case(
        None,
        ["analyze", str(EXAMPLES / "triad_six_modes.yaml"), "--at", "1e11", *J],
        codes=(0,),
        out='"assembled": [true]',
    ),
    "class-3 group at 1e5 deg": Case(
        None,
        ["analyze", str(EXAMPLES / "triad_six_modes.yaml"), "--at", "1e5", *J],
        codes=(0,),
        out='"assembled": [true]',
    ),
    "/dev/zero as a mechanism file": Case(None, ["check", "/dev/zero", *J], expect=("not a regular file",)),
    "right-to-left override in the name": Case(
        "rtl_name.yaml", ["check", "{}"], expect=("name: a name with control or format characters (U+202E)",)
    ),
    "angles 0:100000:1 is 100001 samples": Case(
        None, ["analyze", FOURBAR, "--angles", "0:100000:1", *J], expect=("100001 samples",), forbid=("e+05",)
    ),
}


@pytest.mark.parametrize("name", list(CORPUS_CASES))
def test_corpus_cli(name: str) -> None:
    case = CORPUS_CASES[name]
    argv = [str(CORPUS / case.file) if a == "{}" else a for a in case.args]
    fmt = "json" if "json" in argv else "table"
    o = run_cli(argv, case.seconds)
    bad = contract_violation(o, fmt)
    assert bad is None, f"{name}: {bad}"
    assert o.code in case.codes, f"{name}: exit {o.code}, expected {case.codes}: {o.err.strip()[:300]}"
    if o.code == 2:
        msg = o.err.lower()
        if case.expect:
            assert any(s.lower() in msg for s in case.expect), f"{name}: message lacks {case.expect}: {o.err.strip()}"
        for s in case.forbid:
            assert s.lower() not in msg, f"{name}: message says {s!r}: {o.err.strip()}"
    if o.code == 0 and case.out is not None:
        assert case.out in o.out, f"{name}: {case.out!r} not in the output"
    if case.file and case.file.endswith(".json") and name.endswith("BOM"):
        yaml_o = run_cli([a.replace("bom.json", "bom.yaml") for a in argv])
        assert (yaml_o.code, yaml_o.out) == (o.code, o.out), "a BOM in JSON and in YAML must behave the same"


def test_corpus_speed_1e308_no_runtime_warning() -> None:
    """numpy overflow warnings must not reach stderr (in a real process, where no pytest hides them)."""
    import subprocess
    import sys

    p = subprocess.run(
        [
            sys.executable,
            "-W",
            "default",
            "-c",
            "from linkagekit.cli import main; import sys; sys.exit(main())",
            "analyze",
            FOURBAR,
            "--at",
            "0,90",
            "--speed",
            "1e308",
            *J,
        ],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert p.returncode in (0, 2), p.stderr
    assert "Warning" not in p.stderr, p.stderr
    assert len(p.stderr.splitlines()) <= 1, p.stderr


def _fourbar() -> lk.Mechanism:
    return mech_of("seed000_fourbar")


def _analyze_then(fn: Callable[[lk.Result], Any]) -> Callable[[], Any]:
    return lambda: fn(lk.analyze(mech_of("slider_crank"), {"crank": [0.0, 90.0]}))


API_CASES: dict[str, Callable[[], Any]] = {
    "from_dict(5)": lambda: lk.Mechanism.from_dict(5),
    "from_dict({})": lambda: lk.Mechanism.from_dict({}),
    "from_dict(None)": lambda: lk.Mechanism.from_dict(None),
    "from_dict(ground: [])": lambda: lk.Mechanism.from_dict(
        yaml.safe_load((CORPUS / "empty_ground_link.yaml").read_text(encoding="utf-8"))
    ),
    "from_dict(joints: list)": lambda: lk.Mechanism.from_dict({**BASES["seed000_fourbar"], "joints": [1, 2]}),
    "from_dict(links with int key)": lambda: lk.Mechanism.from_dict({**BASES["seed000_fourbar"], "links": {1: ["A"]}}),
    "from_dict(nan joint)": lambda: lk.Mechanism.from_dict(
        {**BASES["seed000_fourbar"], "joints": {**BASES["seed000_fourbar"]["joints"], "A": [float("nan"), 0]}}
    ),
    "from_dict(10**400 joint)": lambda: lk.Mechanism.from_dict(
        {**BASES["seed000_fourbar"], "joints": {**BASES["seed000_fourbar"]["joints"], "A": [10**400, 0]}}
    ),
    "from_dict(deep)": lambda: lk.Mechanism.from_dict(
        {**BASES["seed000_fourbar"], "name": json.loads("[" * 500 + "]" * 500)}
    ),
    "load(nested 500 yaml)": lambda: lk.load(CORPUS / "nested_500.yaml"),
    "load(nested 500 json)": lambda: lk.load(CORPUS / "nested_500.json"),
    "load(None)": lambda: lk.load(None),
    "load(a directory)": lambda: lk.load(CORPUS),
    "load(NUL in path)": lambda: lk.load("a\x00b.yaml"),
    "save(5, path)": lambda: lk.save(5, "/tmp/fuzz-never-written.yaml"),
    "save(mech, 5)": lambda: lk.save(_fourbar(), 5),
    "analyze([])": lambda: lk.analyze(_fourbar(), {"crank": []}),
    "analyze(np.array([]))": lambda: lk.analyze(_fourbar(), np.array([])),
    "analyze(2-d inputs)": lambda: lk.analyze(_fourbar(), {"crank": np.zeros((2, 2))}),
    "analyze(string inputs)": lambda: lk.analyze(_fourbar(), {"crank": ["a"]}),
    "analyze(unknown driver)": lambda: lk.analyze(_fourbar(), {"nobody": [0.0]}),
    "analyze(inputs=-10**400)": lambda: lk.analyze(_fourbar(), -(10**400)),
    "analyze({crank: [10**400]})": lambda: lk.analyze(_fourbar(), {"crank": [10**400]}),
    "analyze(speed=10**400)": lambda: lk.analyze(_fourbar(), [0.0], speed=10**400),
    "analyze(acceleration=[10**400])": lambda: lk.analyze(_fourbar(), [0.0], acceleration=[10**400]),
    "analyze(signs=[10**400])": lambda: lk.analyze(_fourbar(), [0.0], signs=[10**400]),
    "modes(at=10**400)": lambda: lk.modes(_fourbar(), at=10**400),
    "analyze(nan speed)": lambda: lk.analyze(_fourbar(), [0.0], speed=float("nan")),
    "analyze(method='x')": lambda: lk.analyze(_fourbar(), [0.0], method="x"),
    "analyze(poses wrong shape)": lambda: lk.analyze(_fourbar(), [0.0], poses=np.zeros((2, 3))),
    "analyze(poses nan)": lambda: lk.analyze(_fourbar(), [0.0], poses=np.full((1, 5, 2), np.nan)),
    "analyze(str)": lambda: lk.analyze("examples/seed000_fourbar.yaml", [0.0]),
    "analyze(None)": lambda: lk.analyze(None, [0.0]),
    "analyze(dict)": lambda: lk.analyze(BASES["seed000_fourbar"], [0.0]),
    "check(None)": lambda: lk.check(None),
    "check(str)": lambda: lk.check("examples/seed000_fourbar.yaml"),
    "modes(5)": lambda: lk.modes(5),
    "modes(at='x')": lambda: lk.modes(_fourbar(), at="x"),
    "modes(at=nan)": lambda: lk.modes(_fourbar(), at=float("nan")),
    "mech.link('nope')": lambda: _fourbar().link("nope"),
    "mech.link(None)": lambda: _fourbar().link(None),
    "mech.link([list])": lambda: _fourbar().link(["crank"]),
    "with_pose(10**400)": lambda: mech_of("slider_crank").with_pose(10**400),
    "with_pose([[10**400, 0]] * 3)": lambda: mech_of("slider_crank").with_pose([[10**400, 0]] * 3),
    "with_pose('x')": lambda: _fourbar().with_pose("x"),
    "with_pose(wrong shape)": lambda: _fourbar().with_pose(np.zeros((3, 2))),
    "xy('nope')": _analyze_then(lambda r: r.xy("nope")),
    "omega('nope')": _analyze_then(lambda r: r.omega("nope")),
    "xy(array)": _analyze_then(lambda r: r.xy(np.zeros(3))),
    "point(array)": _analyze_then(lambda r: r.point(np.zeros(3))),
    "omega(array)": _analyze_then(lambda r: r.omega(np.zeros(3))),
    "angle(array)": _analyze_then(lambda r: r.angle(np.zeros(3))),
    "xy(list)": _analyze_then(lambda r: r.xy(["A"])),
    "forces.reaction(array, link)": _analyze_then(lambda r: r.forces.reaction(np.zeros(3), "crank")),
    "design(0) of one design": _analyze_then(lambda r: r.design(0)),
    "mechanism_of('x')": _analyze_then(lambda r: r.mechanism_of("x")),
    "forces.reaction unknown joint": _analyze_then(lambda r: r.forces.reaction("nope", "crank")),
    "forces.reaction unknown link": _analyze_then(lambda r: r.forces.reaction("A", "nope")),
    "forces.reaction None": _analyze_then(lambda r: r.forces.reaction(None, None)),
}
for _bad in ("[0]", "[0.5]", "[7]", "[nan]", "[-2]", "['+']", "[[1, 1]]", "{'D': 0}", "{'D': 0.5}", "{'D': nan}"):
    API_CASES[f"analyze(signs={_bad})"] = lambda v=_bad: lk.analyze(
        _fourbar(), {"crank": [0.0, 30.0, 60.0]}, signs=eval(v, {"nan": math.nan})
    )
for _bad in ("[0.5]", "[7]", "[nan]", "[-1]", "{'coupler': 0.5}", "{'coupler': 'yes'}", "{'nope': True}"):
    API_CASES[f"analyze(mirrors={_bad})"] = lambda v=_bad: lk.analyze(
        _fourbar(), {"crank": [0.0, 30.0, 60.0]}, mirrors=eval(v, {"nan": math.nan})
    )


@pytest.mark.parametrize("name", list(API_CASES))
def test_corpus_api(name: str) -> None:
    """Each call raises a LinkageError (and nothing else) in time."""
    with time_limit():
        try:
            got = API_CASES[name]()
        except LinkageError:
            return
        except Exception as exc:  # noqa: BLE001
            pytest.fail(f"{name}: raised {type(exc).__name__}: {str(exc)[:200]}", pytrace=False)
    extra = (
        lengths_kept(_fourbar(), got) if isinstance(got, lk.Result) and ("signs" in name or "mirrors" in name) else None
    )
    pytest.fail(
        f"{name}: returned {type(got).__name__} instead of raising" + (f"; {extra}" if extra else ""), pytrace=False
    )


@pytest.mark.parametrize("signs", [[1], [-1], {"D": 1}, {"D": -1}])
def test_valid_signs_keep_lengths(signs) -> None:
    """The valid assembly modes: positions marked assembled keep every length."""
    mech = _fourbar()
    res = lk.analyze(mech, {"crank": np.linspace(0, 360, 37)}, signs=signs)
    assert lengths_kept(mech, res) is None
