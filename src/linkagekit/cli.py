"""The ``linkagekit`` command line: parse the arguments, call the library, format its answer.

Commands: ``analyze``, ``modes``, ``check``, ``plot``, ``animate``, ``report``, ``edit`` (spec, section 2).
Exit status: 0 on success, 2 on a bad file or bad arguments, 1 on anything else; every failure is one line on stderr,
``linkagekit: error: <message>`` (``linkagekit: internal error: <Class>: <message>`` for
an unexpected exception), never a traceback.

Start-up is kept short: this module imports only the standard library, :mod:`linkagekit.errors`
and the declarations of :mod:`linkagekit.catalogue` (no NumPy); NumPy and the library are
imported by the command that needs them, so ``linkagekit --help`` never loads them.

Tables (``--format table``, the default) are plain text: every header carries its unit,
round-off prints as ``0``, NaN as ``—``, and the columns are split into as many tables as
the terminal width needs, each repeating the input and state columns.  Long sweeps show an
evenly spaced subset of the samples; ``--format csv`` gives them all.

Examples
--------
>>> print(format_csv({"input:crank": [0.0, 90.0], "assembled": [True, False], "C.x": [2.0, float("nan")]}), end="")
input:crank,assembled,C.x
0.0,true,2.0
90.0,false,
>>> format_cells([2.0, 1.2246467991473532e-16, float("nan"), 123456789.0])
['2', '0', '—', '1.23457e+08']
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import io
import json
import math
import re
import shutil
import sys
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from typing import TYPE_CHECKING, Any, NamedTuple, NoReturn

from .catalogue import Group
from .errors import MAX_MESSAGE, InputError, LinkageError, MethodNotApplicableError, one_line, shorten, shorten_path
from .options import BranchMode

if TYPE_CHECKING:  # pragma: no cover - for the type checker only: nothing heavy at start-up
    import numpy as np

    from linkagekit import Mechanism, Result

    from .catalogue import Catalogue

PROG = "linkagekit"
MAX_ROWS = 37
#: samples one command computes and prints at most (a file's sweep and --angles/--at)
MAX_SAMPLES = 100_000
#: the largest magnitude of an input value, speed or acceleration
MAX_ABS = 1e12
"""Most rows a table shows; a longer sweep shows an evenly spaced subset (first and last included)."""
ROUNDOFF = 1e-12
"""A value below this fraction of the largest magnitude in its column prints as ``0``."""
DIGITS = 6
"""Significant digits in tables."""
NAN = "—"
"""How a table shows a value that does not exist (not assembled, or singular)."""
SEP = "  "
"""Between two table columns."""

#: options whose value may start with a minus sign (`--at -30`, `--pivots -1:1,-1:1`): attached with `=` before parsing
_RATE_OPTIONS = (
    "--angles",
    "--at",
    "--speed",
    "--acceleration",
    "--time",
    "--torque",
    "--motor",
    "--pivots",
    "--lengths",
)
_NEGATIVE_VALUE = re.compile(r"-\.?\d")


# ---------------------------------------------------------------------- argument parsing
class _ParserExit(Exception):
    """The parser is done (after ``--help`` or ``--version``): leave with this status."""

    def __init__(self, status: int) -> None:
        super().__init__(status)
        self.status = status


class _Parser(argparse.ArgumentParser):
    """An :class:`argparse.ArgumentParser` that raises instead of printing and exiting.

    A usage error becomes an :class:`~linkagekit.errors.InputError` (exit status 2, one line
    on stderr, printed by :func:`main`); ``--help`` and ``--version`` print as usual and then
    raise :class:`_ParserExit`.
    """

    def error(self, message: str) -> NoReturn:
        """Raise the usage error *message* (with a pointer to the command's help) as an InputError."""
        raise InputError(f"{message} (see '{self.prog} --help')")

    def exit(self, status: int = 0, message: str | None = None) -> NoReturn:
        """Raise :class:`_ParserExit` (or an InputError, for a message with a non-zero status)."""
        if message and status:
            raise InputError(message.strip())
        if message:
            sys.stderr.write(message)
        raise _ParserExit(status)


def _float(text: str) -> float:
    """``text`` as a number written as the file reader takes one: Python's ``float`` also took ``1_000`` and other
    scripts' digits (``１２``), which a file refuses.

    >>> _float("1e2"), _float(" -3.5")
    (100.0, -3.5)
    >>> _float("1_000")
    Traceback (most recent call last):
    ...
    ValueError: 1_000
    """
    if not text.isascii() or "_" in text:
        raise ValueError(text)
    return float(text)


def _numbers(text: str, what: str) -> list[float]:
    """Comma-separated finite numbers.

    >>> _numbers("0, 90,1e2", "--at")
    [0.0, 90.0, 100.0]
    """
    out = []
    parts = text.split(",")
    if len(parts) > MAX_SAMPLES:
        raise InputError(f"{what}: more than {MAX_SAMPLES} values")
    for part in parts:
        part = part.strip()
        try:
            v = _float(part)
        except ValueError:
            raise InputError(f"{what}: {shorten(repr(part))} is not a number") from None
        if not math.isfinite(v) or abs(v) > MAX_ABS:
            raise InputError(f"{what}: {shorten(part)} is not a finite number of at most {MAX_ABS:g} in magnitude")
        out.append(v)
    return out


def _one_number(text: str, what: str) -> float:
    values = _numbers(text, what)
    if len(values) != 1:
        raise InputError(f"{what}: expected one number, got {shorten(repr(text))}")
    return values[0]


def _range(text: str, what: str) -> np.ndarray:
    """``START:STOP:STEP`` as an array, STOP included when the steps land on it.

    >>> _range("0:360:90", "--angles").tolist()
    [0.0, 90.0, 180.0, 270.0, 360.0]
    >>> _range("0:0.3:0.1", "--time").tolist()
    [0.0, 0.1, 0.2, 0.3]
    """
    parts = text.split(":")
    if len(parts) != 3:
        raise InputError(f"{what}: expected START:STOP:STEP, got {shorten(repr(text))}")
    start, stop, step = (_one_number(p, what) for p in parts)
    if step == 0 or (stop - start) * step < 0:
        raise InputError(f"{what}: STEP must be non-zero and go from START toward STOP, got {shorten(repr(text))}")
    from .model import stepped, steps_count

    steps = (stop - start) / step  # may overflow to inf: counted only when not far above the limit
    n = steps_count(start, stop, step) if steps <= 10 * MAX_SAMPLES else None
    if n is None or n > MAX_SAMPLES:
        many = f"over {10 * MAX_SAMPLES}" if n is None else str(n)
        raise InputError(
            f"{what}: {many} samples, more than the command line takes ({MAX_SAMPLES}); "
            f"use a coarser STEP, or the Python API ({'lk.simulate' if what == '--time' else 'lk.analyze_chunks'}) "
            "for more"
        )
    return stepped(start, stop, step, n)


def _by_driver(mech: Mechanism, items: list[str], option: str, parse: Callable[[str, str], Any]) -> dict[str, Any]:
    """Split ``NAME=VALUE`` items (or a bare VALUE for a single driver) by driver.

    NAME is everything before the last ``=`` (a value never holds one), so a driver whose name
    holds ``=``, ``,`` or ``:`` (a link's name is any string) is named as written in the file.

    >>> class M:  # only the drivers' names are read
    ...     drivers = [type("D", (), {"name": n}) for n in ("arm=left", "arm,right")]
    >>> _by_driver(M, ["arm=left=0,90", "arm,right = 5"], "--at", _numbers)
    {'arm=left': [0.0, 90.0], 'arm,right': [5.0]}
    """
    names = [d.name for d in mech.drivers]
    listed = ", ".join(f"'{n}'" for n in names)
    out: dict[str, Any] = {}
    for item in items:
        if "=" in item:
            name, _, text = item.rpartition("=")
            name = name if name in names else name.strip()
            if name not in names:
                raise InputError(f"{option}: no driver named '{shorten(name, 40)}' (drivers: {listed})")
        else:
            if len(names) != 1:
                raise InputError(f"{option}: this mechanism has drivers {listed}: write {option} NAME=...")
            name, text = names[0], item
        if name in out:
            raise InputError(f"{option}: driver '{name}' given twice")
        out[name] = parse(text, f"{option} {shorten(item, 40)}")
    return out


def _inputs(mech: Mechanism, at: list[str] | None, angles: list[str] | None) -> dict[str, np.ndarray] | None:
    """The input values of ``--at`` and ``--angles`` by driver (None: the file's sweep); each driver from one of
    them (``--angles crank1=0:360:1 --at crank2=75``)."""
    import numpy as np

    if not (at or angles):
        return None
    given = {k: np.array(v) for k, v in _by_driver(mech, at or [], "--at", _numbers).items()}
    swept = _by_driver(mech, angles or [], "--angles", _range)
    for name in given.keys() & swept.keys():
        raise InputError(f"driver '{name}': give --at or --angles, not both")
    return given | swept


def _rates(mech: Mechanism, items: list[str] | None, option: str) -> dict[str, float] | None:
    """One ``--speed`` or ``--acceleration`` value per driver (None: the file's)."""
    if not items:
        return None
    return {k: v[0] if len(v) == 1 else _too_many(option) for k, v in _by_driver(mech, items, option, _numbers).items()}


def _too_many(option: str) -> float:
    raise InputError(f"{option}: one value per driver")


def _attach_negative_values(argv: Sequence[str]) -> list[str]:
    """Write ``--at -30,0`` as ``--at=-30,0``, so that the parser takes a negative value as a value.

    >>> _attach_negative_values(["analyze", "f", "--angles", "-90:90:1", "--speed", "-2e3"])
    ['analyze', 'f', '--angles=-90:90:1', '--speed=-2e3']
    """
    out: list[str] = []
    i = 0
    while i < len(argv):
        arg = argv[i]
        if arg in _RATE_OPTIONS and i + 1 < len(argv) and _NEGATIVE_VALUE.match(argv[i + 1]):
            out.append(f"{arg}={argv[i + 1]}")
            i += 2
            continue
        out.append(arg)
        i += 1
    return out


def _version() -> str:
    from . import __version__

    return f"{PROG} {__version__}"


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the command line (it raises instead of exiting; see :func:`main`).

    Each command is one :class:`_Command` of :data:`_COMMANDS`: its summary, its description,
    the function that declares its arguments and the function that runs it.
    """
    parser = _Parser(
        formatter_class=argparse.RawDescriptionHelpFormatter,
        prog=PROG,
        description="Analyse planar linkages described in YAML or JSON mechanism files.",
        epilog="Exit status: 0 on success, 2 on a bad file or bad arguments, 1 on anything else.\n"
        f"'{PROG} COMMAND --help' describes a command.",
        allow_abbrev=False,
    )
    parser.add_argument("--version", action="version", version=_version(), help="print the version and exit")
    subparsers = parser.add_subparsers(title="commands", dest="command", metavar="COMMAND")
    for command in _COMMANDS:
        p = subparsers.add_parser(
            command.name, help=command.summary, description=command.description, allow_abbrev=False
        )
        command.arguments(p)
        p.set_defaults(run=command.run)
    return parser


class _Command(NamedTuple):
    """One command of the command line: its name, help, arguments and what runs it."""

    name: str
    summary: str
    """Its line in ``linkagekit --help``."""
    description: str
    """The paragraph of ``linkagekit NAME --help``."""
    arguments: Callable[[argparse.ArgumentParser], None]
    """Declares its arguments, in the order its help lists them."""
    run: Callable[[argparse.Namespace], int]


# Options that several commands share, each declared once.
def _file_argument(p: argparse.ArgumentParser) -> None:
    p.add_argument("file", metavar="FILE", help="mechanism file (YAML or JSON)")


def _output_option(p: argparse.ArgumentParser, written: str | None = None) -> None:
    """``-o OUT``: stdout by default, or (given what is *written*) a file that must be named."""
    if written is None:
        p.add_argument("-o", "--output", metavar="OUT", help="write to this file instead of stdout")
    else:
        p.add_argument("-o", "--output", metavar="OUT", required=True, help=written)


def _format_option(p: argparse.ArgumentParser, *choices: str) -> None:
    p.add_argument("--format", choices=choices, default="table", help="output format (default: %(default)s)")


def _sweep_option(p: argparse.ArgumentParser) -> None:
    """``--angles`` (and ``--branch``, how the sweep follows its branch) of the picture commands."""
    p.add_argument(
        "--angles",
        action="append",
        metavar="START:STOP:STEP",
        help="the sweep (NAME=START:STOP:STEP per driver; repeatable); default: the file's",
    )
    _branch_option(p)


def _analyze_arguments(p: argparse.ArgumentParser) -> None:
    _file_argument(p)
    p.add_argument(
        "--angles",
        action="append",
        metavar="START:STOP:STEP",
        help="sweep from START to STOP by STEP (NAME=START:STOP:STEP per driver; repeatable); "
        "default: the file's sweep",
    )
    p.add_argument(
        "--at", action="append", metavar="V1,V2,...", help="these input values (NAME=V1,V2,... per driver; repeatable)"
    )
    p.add_argument(
        "--speed",
        action="append",
        metavar="W",
        help="input speed, rad/s (length unit/s for a slider or cylinder); NAME=W per driver; default: the file's",
    )
    p.add_argument(
        "--acceleration",
        action="append",
        metavar="A",
        help="input acceleration, rad/s² (length unit/s² for a slider or cylinder); NAME=A per driver; "
        "default: the file's",
    )
    _format_option(p, "table", "csv", "json")
    _output_option(p)
    p.add_argument(
        "--method",
        choices=("natural", "vector-loop", "numerical"),
        default="natural",
        help="natural: triangulation in joint coordinates, Newton only where no triangulation exists "
        "(any mechanism); vector-loop: link angles by iteration (four-bars, Stephenson six-bars); "
        "numerical: Newton continued from the pose wherever it applies, a cross-check "
        "(default: %(default)s)",
    )
    p.add_argument(
        "--static",
        action="store_true",
        help="zero input speed and acceleration: the driver torques that balance gravity and the loads",
    )
    _branch_option(p)


def _branch_option(p: argparse.ArgumentParser) -> None:
    """``--branch`` of ``analyze`` and the picture commands' sweeps."""
    p.add_argument(
        "--branch",
        choices=BranchMode.words(),
        default=BranchMode.POSE.value,
        help="pose: every joint keeps the reference pose's assembly sign; continuous: follow the branch "
        "through change points (a parallelogram stays a parallelogram) from the pose's input up and down "
        "(default: %(default)s)",
    )


def _simulate_arguments(p: argparse.ArgumentParser) -> None:
    _file_argument(p)
    what = p.add_mutually_exclusive_group(required=True)
    what.add_argument("--time", metavar="START:STOP:STEP", help="output times, s (the motion starts at START)")
    what.add_argument(
        "--flywheel",
        metavar="CS",
        help="instead of a motion, print the smallest extra inertia (kg*m^2) on the driver's crank that keeps "
        "the periodic steady state's coefficient of speed fluctuation at most CS",
    )
    _law_options(p)
    _format_option(p, "table", "csv", "json")
    _output_option(p)


def _law_options(p: argparse.ArgumentParser) -> None:
    """``--torque``, ``--motor``, ``--speed``: what drives a simulated motion and how it starts."""
    p.add_argument(
        "--torque",
        action="append",
        metavar="T",
        help="a constant driver torque, N*m (N for a slider or cylinder); NAME=T per driver; default 0",
    )
    p.add_argument(
        "--motor",
        action="append",
        metavar="T0,W0",
        help="the linear motor curve T = T0 (1 - w/W0), W0 in rad/s (length unit/s for a slider or cylinder); "
        "NAME=T0,W0 per driver",
    )
    p.add_argument(
        "--speed",
        action="append",
        metavar="V",
        help="starting speed, rad/s (length unit/s for a slider or cylinder); NAME=V per driver; default 0",
    )


def _motion_options(p: argparse.ArgumentParser) -> None:
    """``--time`` and the torque law: draw a simulated motion (as ``simulate`` computes it) instead of a sweep."""
    p.add_argument(
        "--time",
        metavar="START:STOP:STEP",
        help="instead of a sweep, the motion that 'simulate' computes at these times, s (plots run along time)",
    )
    _law_options(p)


def _timed(args: argparse.Namespace) -> bool:
    """Whether a picture command draws a simulated motion (``--time``); refuses options that do not go with it."""
    if args.time is None:
        given = [o for o, v in (("--torque", args.torque), ("--motor", args.motor), ("--speed", args.speed)) if v]
        if given:
            raise InputError(f"{given[0]} drives a simulated motion: give --time START:STOP:STEP too")
        return False
    if args.angles:
        raise InputError("--time draws a simulated motion, --angles a sweep: give one of them")
    if BranchMode.parse(args.branch) is BranchMode.CONTINUOUS:
        raise InputError(
            "--branch goes with a sweep: a simulated motion (--time) follows its branch through change points"
        )
    return True


def _motion(mech: Mechanism, args: argparse.Namespace, times: np.ndarray | None = None) -> Result | None:
    """The simulated motion ``--time`` asks for (at ``times``, when given), or None for a sweep."""
    import linkagekit as lk

    if not _timed(args):
        return None
    if times is None:
        times = _range(args.time, "--time")
    torque, motor = _torque_law(mech, args)
    speed = _by_driver(mech, args.speed, "--speed", _one_number) if args.speed else None
    return lk.simulate(mech, times, torque=torque, motor=motor, speed=speed)


def _solved(mech: Mechanism, args: argparse.Namespace) -> Result:
    """What a picture command draws: the simulated motion of ``--time``, else the sweep (``--angles`` or the file's)."""

    res = _motion(mech, args)
    return _swept(mech, args, _sweep(mech, args.angles, args.file)) if res is None else res


def _swept(mech: Mechanism, args: argparse.Namespace, inputs: Any) -> Result:
    """The sweep a picture command draws, on the branch ``--branch`` says."""
    import linkagekit as lk

    return lk.analyze(mech, inputs, branch=BranchMode.parse(args.branch))


def _torque_law(mech: Mechanism, args: argparse.Namespace) -> tuple[dict[str, float] | None, dict[str, Any] | None]:
    """``--torque`` and ``--motor`` by driver (None where not given)."""
    torque = _by_driver(mech, args.torque, "--torque", _one_number) if args.torque else None
    motor = _by_driver(mech, args.motor, "--motor", _motor_curve) if args.motor else None
    return torque, motor


def _stopped(res: Result) -> int:
    """Exit status of a picture of ``res``: 1, with its one line, when a simulated motion stopped at a toggle."""
    if res.stopped:
        print(f"{PROG}: {res.stopped}", file=sys.stderr)
        return 1
    return 0


def _motor_curve(text: str, what: str) -> tuple[float, float]:
    values = _numbers(text, what)
    if len(values) != 2:
        raise InputError(f"{what}: expected T0,W0 (stall torque, no-load speed), got {shorten(repr(text))}")
    if values[1] == 0:  # (named as the option, not as the API's motor[NAME])
        raise InputError(f"{what}: the no-load speed W0 must not be zero")
    return values[0], values[1]


def _flywheel(args: argparse.Namespace, mech: Mechanism, torque: Any, motor: Any) -> int:
    """``simulate --flywheel CS``: the smallest extra inertia (kg*m^2), or its steady state in JSON."""
    import linkagekit as lk

    if args.speed:
        raise InputError("--speed: not used with --flywheel (the steady state does not depend on the start)")
    size = lk.size_flywheel(mech, _one_number(args.flywheel, "--flywheel"), torque=torque, motor=motor)
    if args.format != "json":
        _emit(f"{size.inertia:.10g}\n", args.output)  # the number alone, as the file format has it (kg*m^2 always)
        return 0
    st = size.steady
    out = {
        "format": "linkagekit-flywheel/1",
        "units": {"inertia": "kg*m^2", "speed": "rad/s"},
        "link": mech.drivers[0].link,
        "inertia": size.inertia,
        "cs": size.cs,
        "cs_without": size.cs_without,
        "speed": {"min": abs(st.w_min), "max": abs(st.w_max), "mean": abs(st.mean_speed)},
    }
    _emit(json.dumps(out, allow_nan=False) + "\n", args.output)
    return 0


def _simulate(args: argparse.Namespace) -> int:
    """``linkagekit simulate``: writes the motion (so far), then exit 1 with one line if it met a toggle."""
    import linkagekit as lk

    mech = lk.load(args.file)
    torque, motor = _torque_law(mech, args)
    if args.flywheel is not None:
        return _flywheel(args, mech, torque, motor)
    times = _range(args.time, "--time")
    speed = _by_driver(mech, args.speed, "--speed", _one_number) if args.speed else None
    res = lk.simulate(mech, times, torque=torque, motor=motor, speed=speed)
    if args.format == "json":
        _emit(json.dumps(res.to_dict(), allow_nan=False) + "\n", args.output)
    elif args.format == "csv":
        _emit(format_csv(res.columns()), args.output)
    else:
        cat = res.catalogue
        shown = {q.name: q.owner_name or q.name for q in cat.table if q.group is Group.INPUTS}
        units = res.column_units()
        text = analysis_tables(
            res.columns(), units, analysis_sections(cat, mech.name or ""), inputs=shown, width=terminal_width()
        )
        _emit(text, args.output)
    return _stopped(res)


def _modes_arguments(p: argparse.ArgumentParser) -> None:
    _file_argument(p)
    p.add_argument(
        "--at",
        action="append",
        metavar="V",
        help="the input value (NAME=V per driver; repeatable); default: the pose's input",
    )
    p.add_argument("--mirrors", action="store_true", help="also flip each link of three or more joints")
    _format_option(p, "table", "json")
    _output_option(p)


def _check_arguments(p: argparse.ArgumentParser) -> None:
    _file_argument(p)
    _format_option(p, "table", "json")
    _output_option(p)


def _plot_arguments(p: argparse.ArgumentParser) -> None:
    _file_argument(p)
    _output_option(p, "the picture: .png, .svg or .pdf")
    p.add_argument(
        "--at",
        action="append",
        metavar="V1,V2,...",
        help="draw the mechanism at these inputs (earlier ones faded; NAME=... per driver); default: the pose's",
    )
    _sweep_option(p)
    p.add_argument("--modes", action="store_true", help="every assembly mode at --at (default: the pose's input)")
    p.add_argument("--mirrors", action="store_true", help="with --modes: also flip links of three or more joints")
    p.add_argument(
        "--size",
        metavar="W[xH]",
        help="the picture's size in pixels: W wide (the height follows the drawing), or W x H exactly "
        "(default: 6 inches at --dpi, 1200 px wide at the default 200, 640 px a panel with --modes)",
    )
    p.add_argument(
        "--dpi",
        metavar="N",
        help="pixels per inch (default: 200): text and lines are sized in points, so a larger N draws them "
        "larger in a picture of the same --size",
    )
    p.add_argument(
        "--quantity",
        "-q",
        action="append",
        metavar="NAME[,NAME...]",
        help="plot these columns of 'analyze --format csv' against the input (with --time: against time), "
        "one plot per option (e.g. coupler.omega or 'T[crank]'), or a group: " + ", ".join(_QUANTITY_GROUPS),
    )
    _motion_options(p)


def _animate_arguments(p: argparse.ArgumentParser) -> None:
    _file_argument(p)
    _output_option(p, "the animation: .gif or .mp4")
    _sweep_option(p)
    p.add_argument(
        "--frames", metavar="N", help="this many frames (36 to 1000), evenly over the sweep (or over --time)"
    )
    p.add_argument("--fps", metavar="F", default="24", help="frames per second (default: %(default)s)")
    _motion_options(p)


def _report_arguments(p: argparse.ArgumentParser) -> None:
    _file_argument(p)
    _output_option(p, "the page: .html")
    _sweep_option(p)
    _motion_options(p)


def _edit_arguments(p: argparse.ArgumentParser) -> None:
    _file_argument(p)
    p.add_argument("--port", metavar="N", help="listen on this port (default: a free one)")
    p.add_argument("--no-browser", action="store_true", help="do not open a browser; just print the URL")
    p.add_argument(
        "--solve-seconds",
        metavar="S",
        default=None,
        help="stop a solve that runs longer than S seconds and say so on the page (default 30)",
    )


def _topology_arguments(p: argparse.ArgumentParser) -> None:
    """``synthesize --topology`` and ``--max-joints``."""
    p.add_argument(
        "--topology",
        default="fourbar",
        metavar="NAME|FILE",
        help="fourbar (default), watt2, stephenson3, auto (every built-in topology up to --max-joints), a "
        "topology that auto names (sixbar-4, eightbar-85, ...), or a mechanism file used as a template (see --free)",
    )
    p.add_argument(
        "--max-joints",
        metavar="N",
        default=None,
        help="with --topology auto: at most N joints, ground pivots and P included (default 10)",
    )


def _synthesize_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("targets", metavar="TARGET", help="target points: .csv (x,y[,input]) or .svg (its first path)")
    _topology_arguments(p)
    _output_option(p, "the mechanism file to write: .yaml or .json")
    p.add_argument(
        "--seconds", metavar="S", default=_DEFAULT_SECONDS, help="time budget (default 60; 10 for --task function)"
    )
    p.add_argument("--seed", metavar="N", default="0", help="random seed (default 0)")
    p.add_argument(
        "--min-transmission",
        metavar="DEG",
        help="smallest transmission angle, degrees (default 20; 0 with --task motion or function)",
    )
    p.add_argument(
        "--workers",
        metavar="N",
        help="local processes, each running its own searches (default: every core of this machine)",
    )
    p.add_argument(
        "--pareto",
        action="store_true",
        help="also search at raised transmission bounds and list designs from the most accurate to the "
        "best-transmitting (-o OUT.yaml: the most accurate; OUT-2.yaml, ...: the others in that order)",
    )
    p.add_argument("--scheduler", metavar="ADDRESS", help="evaluate on a running Dask cluster (tcp://host:port)")
    p.add_argument(
        "--checkpoint",
        metavar="FILE",
        help="save the search as it goes (every generation; with --topology auto every phase and 10 s); "
        "the same command resumes from it",
    )
    p.add_argument("--units", metavar="UNIT", default="m", help="length unit of the targets: mm, cm, m, in (default m)")
    p.add_argument("--points", metavar="N", help="points sampled along an SVG path (default 40)")
    p.add_argument("--no-smooth", action="store_true", help="take hand-drawn targets (over 40 points) as they are")
    p.add_argument("--ordered", action="store_true", help="meet the targets in their order along the curve")
    _shape_arguments(p)
    p.add_argument("--free", metavar="J1,J2,...", help="with a template file: the joints that move (default all)")
    p.add_argument("--pivots", metavar="X0:X1,Y0:Y1", help="the region of the ground pivots")
    p.add_argument("--lengths", metavar="MIN:MAX", help="bounds on every link length")
    p.add_argument("--reach", metavar="R", help="joints lie within R target diagonals of the targets (default 3)")
    p.add_argument(
        "--restarts",
        metavar="N",
        default=_DEFAULT_RESTARTS,
        help="independent searches at most (default 1000; 32 for --task function)",
    )
    p.add_argument(
        "--generations", metavar="N", default="500", help="differential-evolution generations per search (default 500)"
    )
    p.add_argument(
        "--goal",
        metavar="F",
        help="stop once every target is within F target diagonals of the curve (default 1e-5; 0: search to the end)",
    )
    p.add_argument("--plot", metavar="OUT", help="draw the targets on the achieved curve: .png, .svg or .pdf")
    _task_arguments(p)


def _task_arguments(p: argparse.ArgumentParser) -> None:
    """``synthesize --task`` and the options of motion and function generation (docs/commands.md)."""
    p.add_argument(
        "--task",
        choices=SYNTHESIS_TASKS,
        default="path",
        help="path (default: a point follows the targets), motion (a body passes through poses x,y,angle) "
        "or function (an output angle follows an input angle)",
    )
    p.add_argument(
        "--approximate", action="store_true", help="motion, 3 to 5 poses: the approximate route, not Burmester's"
    )
    p.add_argument(
        "--angle-weight",
        metavar="W",
        help="motion: one radian of orientation error weighs as much as W diagonals of position error (default 0.05)",
    )
    p.add_argument("--full-turn", action="store_true", help="motion: the crank turns fully through the poses")
    p.add_argument("--free-offsets", action="store_true", help="function: each angle scale may start anywhere")
    p.add_argument("--ground-length", metavar="L", help="function: distance between the ground pivots (default 1)")


def _shape_arguments(p: argparse.ArgumentParser) -> None:
    """``synthesize --shape-only`` and ``--partial`` (docs/commands.md, path synthesis)."""
    p.add_argument(
        "--shape-only",
        action="store_true",
        help="match the curve up to translation, rotation and scale; the mechanism is placed on the targets",
    )
    p.add_argument(
        "--partial",
        action="store_true",
        help="the targets may lie on the part of the curve traced while the crank rocks through a range (>= 90 deg)",
    )


#: ``--ground-length``'s largest value (a mechanism file holds no number above 1e12; targets' diagonals are at most 1e6)
MAX_GROUND_LENGTH = 1e6
#: the tasks of ``synthesize --task`` (docs/commands.md)
SYNTHESIS_TASKS = ("path", "motion", "function")
#: the options of one task only: given with another, they are refused, not ignored (a user who gave --pivots to a
#: motion synthesis believed the pivots were bounded)
_TASK_OPTIONS = {
    "path": ("shape_only", "partial", "pareto", "no_smooth", "pivots", "lengths", "free", "ordered", "max_joints")
    + ("points", "reach", "goal"),
    "motion": ("approximate", "angle_weight", "full_turn"),
    "function": ("free_offsets", "ground_length"),
}


#: path generation's options whose defaults are applied when they are read (given with another task: refused)
_PATH_DEFAULTS = {"points": "40", "reach": "3", "goal": "1e-5"}


def _path_option(args: argparse.Namespace, name: str) -> str:
    """``--NAME`` as given, or its default (:data:`_PATH_DEFAULTS`)."""
    value = getattr(args, name)
    return _PATH_DEFAULTS[name] if value is None else str(value)


def _task_options(args: argparse.Namespace) -> None:
    """Refuse an option of another task than ``--task`` (:data:`_TASK_OPTIONS`), and a topology function generation
    does not design."""
    for task, names in _TASK_OPTIONS.items():
        for name in names:
            if task != args.task and getattr(args, name) not in (None, False):
                raise InputError(f"--{name.replace('_', '-')}: goes with --task {task}, not --task {args.task}")
    if args.task == "function" and args.topology != "fourbar":
        raise InputError(f"--topology {shorten(args.topology, 80)}: function generation designs four-bars only")


#: --quantity groups: the report's plots, by their short name
_QUANTITY_GROUPS = {g.short: g for g in Group if g.plotted}


def _frames(text: str) -> int:
    try:
        n = int(text)
    except ValueError:
        raise InputError(f"--frames: expected a whole number, got {shorten(repr(text))}") from None
    from .viz.animate import MAX_FRAMES, MIN_FRAMES

    if not MIN_FRAMES <= n <= MAX_FRAMES:  # an animation has at least 36 frames (docs/commands.md, `animate`)
        raise InputError(f"--frames: expected {MIN_FRAMES} to {MAX_FRAMES} frames, got {n}")
    return n


#: plot --dpi: the range taken (the default is the drawing's, ``viz.draw.DPI``)
MIN_DPI, MAX_DPI = 10.0, 1200.0
#: plot --size: each side in pixels, and the most pixels of one picture
MIN_SIDE, MAX_SIDE, MAX_PIXELS = 16, 20_000, 100_000_000


def _dpi(text: str | None) -> dict[str, float]:
    """``plot --dpi``: ``{"dpi": pixels per inch}``, or nothing for the drawing's default.

    >>> _dpi(None), _dpi("96")
    ({}, {'dpi': 96.0})
    """
    if text is None:
        return {}
    v = _one_number(text, "--dpi")
    if not MIN_DPI <= v <= MAX_DPI:
        raise InputError(f"--dpi: expected {MIN_DPI:g} to {MAX_DPI:g} pixels per inch, got {shorten(text)}")
    return {"dpi": v}


def _size(text: str | None) -> tuple[int, int | None] | None:
    """``plot --size W[xH]``: (width, height or None) in pixels, or None for the default size.

    >>> _size("1600"), _size("1600x900"), _size(None)
    ((1600, None), (1600, 900), None)
    """
    if text is None:
        return None
    parts = text.lower().replace("×", "x").split("x")
    if len(parts) > 2 or not all(p.strip().isdigit() for p in parts):
        raise InputError(
            f"--size: expected W or WxH in whole pixels (e.g. 1600 or 1600x900), got {shorten(repr(text))}"
        )
    sides = [int(p) for p in parts]
    if not all(MIN_SIDE <= v <= MAX_SIDE for v in sides):
        raise InputError(f"--size: each side must be {MIN_SIDE} to {MAX_SIDE} pixels, got {shorten(text)}")
    if len(sides) == 2 and sides[0] * sides[1] > MAX_PIXELS:
        raise InputError(f"--size: at most {MAX_PIXELS:,} pixels in all, got {shorten(text)}")
    return (sides[0], sides[1] if len(sides) == 2 else None)


def _fps(text: str) -> float:
    v = _one_number(text, "--fps")
    if not 0.1 <= v <= 120:
        raise InputError(f"--fps: expected 0.1 to 120 frames per second, got {text}")
    return v


# ---------------------------------------------------------------------- output
def terminal_width() -> int:
    """Columns of the terminal (``COLUMNS`` when set; 80 when stdout is not a terminal)."""
    return shutil.get_terminal_size((80, 24)).columns


def _emit(text: str, out: str | None) -> None:
    """Write *text* to the file *out*, or to stdout."""
    if out is None:
        try:
            sys.stdout.write(text)
        except UnicodeEncodeError:  # a terminal that cannot show '—' or '²'
            enc = sys.stdout.encoding or "ascii"
            sys.stdout.write(text.encode(enc, "replace").decode(enc))
        sys.stdout.flush()
        return
    from .files import write_atomic

    # in one step (a failed write leaves the old file, not half of a new one); a FIFO or a device is written in
    # place, and a reader gone (BrokenPipeError) stays quiet, as on standard output (main)
    write_atomic(out, text.encode("utf-8"), label=f"-o {shorten_path(out, 80)}", like_open=True)


def format_csv(columns: Mapping[str, Any]) -> str:
    """CSV of named columns: a header of the names, then one row per sample.

    Boolean columns print as ``true``/``false``, other values as Python's ``repr`` of the
    float, and NaN (or an infinity) as an empty field.
    """
    import numpy as np

    cells: list[list[str]] = []
    for values in columns.values():
        a = np.asarray(values)
        if a.dtype == bool:
            cells.append(["true" if v else "false" for v in a.tolist()])
        else:
            cells.append([repr(v) if math.isfinite(v) else "" for v in a.astype(float).tolist()])
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(list(columns))
    w.writerows(zip(*cells, strict=True))
    return buf.getvalue()


def _number(v: float, scale: float) -> str:
    """One value for a table: ``—`` for NaN, ``0`` for round-off below ``ROUNDOFF * scale``."""
    if v != v:
        return NAN
    if v == 0 or abs(v) < ROUNDOFF * scale:
        return "0"
    return f"{v:.{DIGITS}g}"


def _largest(values: Any) -> float:
    """The largest finite magnitude among *values* (0 when none)."""
    import numpy as np

    a = np.asarray(values, dtype=float)
    return float(np.max(np.abs(a), initial=0.0, where=np.isfinite(a)))


def format_cells(values: Any, rows: Sequence[int] | None = None, scale: float = 0.0) -> list[str]:
    """Table cells of one column (at *rows*, default all): 6 significant digits, round-off as 0, NaN as ``—``.

    The round-off threshold is relative to the largest finite magnitude in the whole column, or *scale* if larger
    (the largest among the columns of one unit in a section: a joint's x at 90 deg next to its y).

    >>> format_cells([1e-20, 5e-9, -0.0])
    ['1e-20', '5e-09', '0']
    >>> format_cells([1.0, 1e-13, 3.0], rows=[1, 2])
    ['0', '3']
    >>> format_cells([1.2246467991473532e-16], scale=1.0)
    ['0']
    """
    import numpy as np

    a = np.asarray(values, dtype=float)
    picked = a if rows is None else a[np.asarray(rows, dtype=int)]
    return [_number(v, max(scale, _largest(a))) for v in picked.tolist()]


def _unit_scales(
    columns: Mapping[str, Any], units: Mapping[str, str], keys: Sequence[Sequence[str]]
) -> dict[str, float]:
    """Per unit, the largest finite magnitude among a section's columns *keys* of that unit."""
    scales: dict[str, float] = {}
    for k in (k for g in keys for k in g if k in columns):
        u = units.get(k, "")
        scales[u] = max(scales.get(u, 0.0), _largest(columns[k]))
    return scales


def sample_rows(n: int, max_rows: int = MAX_ROWS) -> list[int]:
    """Indices of the rows a table shows: all of them, or about *max_rows* evenly spaced, first and last included.

    >>> sample_rows(361)[:3], len(sample_rows(361)), sample_rows(361)[-1]
    ([0, 10, 20], 37, 360)
    >>> sample_rows(3)
    [0, 1, 2]
    """
    if n <= max_rows:
        return list(range(n))
    return sorted({round(i * (n - 1) / (max_rows - 1)) for i in range(max_rows)})


class Column:
    """One column of a text table: a header and its cells, right-aligned unless *left*."""

    __slots__ = ("cells", "header", "left")

    def __init__(self, header: str, cells: list[str], left: bool = False) -> None:
        self.header = header
        self.cells = cells
        self.left = left

    @property
    def width(self) -> int:
        """Characters the column needs."""
        return max([len(self.header), *map(len, self.cells)])

    def shortened(self, width: int) -> Column:
        """This column with its header cut (ending in ``…``) to at most *width* characters, if it can be."""
        if len(self.header) <= width or width < 2:
            return self
        return Column(self.header[: width - 1] + "…", self.cells, self.left)


def _wrap(text: str, width: int) -> list[str]:
    """*text* as lines of at most *width* characters (broken at spaces when it can)."""
    if len(text) <= width:
        return [text]
    import textwrap

    return textwrap.wrap(text, width, break_on_hyphens=False) or [text]


def split_columns(fixed: Sequence[Column], groups: Sequence[Sequence[Column]], width: int) -> list[list[Column]]:
    """Share the data columns among tables that fit *width*, each also showing the *fixed* columns.

    A group (the x and y of a joint, say) stays in one table when it fits in one.
    """
    room = width - (sum(c.width for c in fixed) + len(SEP) * (len(fixed) - 1))
    tables: list[list[Column]] = []
    cur: list[Column] = []
    used = 0
    for group in groups:
        group = [c.shortened(room - len(SEP)) for c in group]
        need = sum(len(SEP) + c.width for c in group)
        if cur and used + need > room and need <= room:
            tables.append(cur)
            cur, used = [], 0
        for c in group:
            if cur and used + len(SEP) + c.width > room:
                tables.append(cur)
                cur, used = [], 0
            cur.append(c)
            used += len(SEP) + c.width
    if cur:
        tables.append(cur)
    return tables


def render_table(columns: Sequence[Column]) -> list[str]:
    """The lines of one table: header, a rule of dashes, then the rows."""
    widths = [c.width for c in columns]

    def line(cells: Iterable[str]) -> str:
        parts = (s.ljust(w) if c.left else s.rjust(w) for s, w, c in zip(cells, widths, columns, strict=True))
        return SEP.join(parts).rstrip()

    n = len(columns[0].cells) if columns else 0
    out = [line(c.header for c in columns), SEP.join("-" * w for w in widths)]
    out += [line(c.cells[i] for c in columns) for i in range(n)]
    return out


def render_tables(title: str, fixed: Sequence[Column], groups: Sequence[Sequence[Column]], width: int) -> list[str]:
    """One titled table, split into as many as *width* needs (titled ``(1/3)``, ``(2/3)``, ...)."""
    if not any(groups):
        return []
    parts = split_columns(fixed, groups, width)
    out: list[str] = []
    for k, part in enumerate(parts):
        head = title if len(parts) == 1 else f"{title} ({k + 1}/{len(parts)})"
        if out:
            out.append("")
        out += _wrap(head, width)
        out += render_table([*fixed, *part])
    return out


def _header(key: str, units: Mapping[str, str]) -> str:
    unit = units.get(key, "")
    return f"{key} [{unit}]" if unit else key


def _state_cells(columns: Mapping[str, Any], rows: Sequence[int]) -> list[str]:
    import numpy as np

    n = len(rows)
    assembled = np.asarray(columns["assembled"], bool)[rows] if "assembled" in columns else np.ones(n, bool)
    singular = np.asarray(columns["singular"], bool)[rows] if "singular" in columns else np.zeros(n, bool)
    return [
        ("singular" if s else "ok") if a else "not assembled"
        for a, s in zip(assembled.tolist(), singular.tolist(), strict=True)
    ]


def analysis_tables(
    columns: Mapping[str, Any],
    units: Mapping[str, str],
    sections: Sequence[tuple[str, Sequence[Sequence[str]]]],
    *,
    inputs: Mapping[str, str],
    width: int = 80,
    max_rows: int = MAX_ROWS,
) -> str:
    """The ``analyze`` tables: each section's columns beside the inputs and the state of every sample.

    Parameters
    ----------
    columns : mapping of str to array
        As :meth:`linkagekit.Result.columns`: the input columns, the ``assembled`` and
        ``singular`` flags, then the values.
    units : mapping of str to str
        The unit of each column (``""``: none).
    sections : sequence of (title, groups)
        Each section's title and its column names, in groups kept together when they fit
        (:func:`analysis_sections`).
    inputs : mapping of str to str
        The input columns, by column name, to the driver name their header shows.
    width : int
        Most characters on a line.
    max_rows : int
        Most rows per table; a longer sweep shows an evenly spaced subset, said under the tables.

    Returns
    -------
    str
        The text, ending in a newline.
    """
    n = len(next(iter(columns.values()))) if columns else 0
    rows = sample_rows(n, max_rows)
    fixed = [Column(_header(d, {d: units.get(k, "")}), format_cells(columns[k], rows)) for k, d in inputs.items()]
    fixed.append(Column("state", _state_cells(columns, rows), left=True))
    out: list[str] = []
    for title, keys in sections:
        scales = _unit_scales(columns, units, keys)
        groups = [
            [
                Column(_header(k, units), format_cells(columns[k], rows, scales[units.get(k, "")]))
                for k in g
                if k in columns
            ]
            for g in keys
        ]
        lines = render_tables(title, fixed, [g for g in groups if g], width)
        if lines:
            if out:
                out.append("")
            out += lines
    if len(rows) < n:
        out += ["", *_wrap(f"{len(rows)} of {n} samples shown, evenly spaced; --format csv gives all of them.", width)]
    return "\n".join(out) + "\n"


def analysis_sections(catalogue: Catalogue, name: str = "") -> list[tuple[str, list[list[str]]]]:
    """Titles and column groups of the ``analyze`` tables, from the result's catalogue.

    Each :class:`~linkagekit.catalogue.Section` in turn (joint positions, velocities and
    accelerations of the moving joints; the angle and rates of every link but the ground;
    and, when there are forces, the bearing loads ``|F|``, driver torques and forces and the
    input power); a joint's or a link's columns form one group, kept together.  A section
    with no columns is left out.

    >>> import linkagekit as lk
    >>> res = lk.analyze(lk.load("examples/seed000_fourbar.yaml"), [0.0, 90.0])
    >>> for title, groups in analysis_sections(res.catalogue, "four-bar")[::2]:
    ...     print(title, groups)
    four-bar: joint positions [['C.x', 'C.y'], ['D.x', 'D.y'], ['P.x', 'P.y']]
    joint accelerations [['C.ax', 'C.ay'], ['D.ax', 'D.ay'], ['P.ax', 'P.ay']]
    """
    from .catalogue import Owner, Section

    out: list[tuple[str, list[list[str]]]] = []
    for section in Section:
        groups: list[list[str]] = []
        last: tuple[Owner, str] | None = None
        for q in catalogue.in_section(section):
            owner = (q.owner, q.owner_name)
            if groups and owner == last and q.owner in (Owner.JOINT, Owner.LINK):
                groups[-1].append(q.name)
            else:
                groups.append([q.name])
            last = owner
        if groups:
            out.append((f"{name}: {section.value}" if name and not out else section.value, groups))
    return out


def modes_table(
    doc: Mapping[str, Any], moving: Sequence[str], length_unit: str, *, mirrors: bool, width: int, title: str = ""
) -> str:
    """The ``modes`` table of a :meth:`Modes.to_dict` document: one row per mode.

    Columns ``#``, ``signs`` (``D+ E-``), ``mirrors`` when asked for (``-`` when the
    mechanism has no link to mirror), ``group modes`` with numerical groups (``2/6``: the
    second of the six modes of a group there), ``assembled`` (``yes (pose)`` for the reference
    pose's mode, ``yes (same as #i)`` for a repeated configuration), then ``x`` and ``y``
    of every moving joint.
    """
    modes = list(doc["modes"])

    def signs(d: Mapping[str, int] | None) -> str:
        return " ".join(f"{k}{'+' if v > 0 else '-'}" for k, v in d.items()) if d else "-"

    def group_modes(d: Mapping[str, Mapping[str, int]] | None) -> str:
        parts = [f"{g['index'] + 1}/{g['of']}" if g["index"] >= 0 else "-" for g in (d or {}).values()]
        return " ".join(parts) or "-"

    def state(mo: Mapping[str, Any]) -> str:
        if not mo["assembled"]:  # the pose's signs that do not assemble here are still the pose's (as the JSON says)
            return "no (pose)" if mo.get("reference") else "no"
        if "same_as" in mo:
            return f"yes (same as #{mo['same_as']})"
        return "yes (pose)" if mo.get("reference") else "yes"

    fixed = [
        Column("#", [str(i) for i in range(len(modes))]),
        Column("signs", [signs(m["signs"]) for m in modes], True),
    ]
    if mirrors:
        fixed.append(Column("mirrors", [signs(m.get("mirrors")) for m in modes], True))
    if any(m.get("groups") for m in modes):  # numerical groups: which of their modes, "2/6"
        fixed.append(Column("group modes", [group_modes(m.get("groups")) for m in modes], True))
    fixed.append(Column("assembled", [state(m) for m in modes], True))
    coords = [xy for m in modes for xy in m["joints"].values() if xy is not None]
    scale = max((abs(v) for xy in coords for v in xy if math.isfinite(v)), default=0.0)
    groups = []
    for j in moving:
        pts = [m["joints"].get(j) for m in modes]
        groups.append(
            [
                Column(f"{j}.{c} [{length_unit}]", [NAN if p is None else _number(float(p[i]), scale) for p in pts])
                for i, c in enumerate("xy")
            ]
        )
    title = title or "assembly modes at " + ", ".join(f"{k} = {v:g}" for k, v in doc.get("input", {}).items())
    lines = render_tables(title, fixed, groups, width) if groups else [*_wrap(title, width), *render_table(fixed)]
    distinct = doc.get("distinct", sum(1 for m in modes if m["assembled"] and "same_as" not in m))
    lines += ["", f"{distinct} distinct assembled configuration(s) of {len(modes)}."]
    lines += [f"Note: {note}" for note in doc.get("notes", [])]
    return "\n".join(lines) + "\n"


def check_text(rep: Mapping[str, Any], units: Mapping[str, str] | None = None, name: str | None = None) -> str:
    """The plain-text report of ``check``: :func:`linkagekit.checks.check_text` (imported when called)."""
    from .checks import check_text as text

    return text(rep, units, name)


# ---------------------------------------------------------------------- commands
def _input_units(mech: Mechanism) -> dict[str, str]:
    from .catalogue import input_units

    return input_units(mech)


def _moving_joints(mech: Mechanism) -> list[str]:
    ground = set(mech.link("ground").joints)
    return [j for j in mech.joint_names if j not in ground]


def _analyze(args: argparse.Namespace) -> int:
    """``linkagekit analyze``."""
    import linkagekit as lk

    mech = lk.load(args.file)
    if args.static and (args.speed or args.acceleration):
        raise InputError("--static: do not give --speed or --acceleration with it")
    branch = BranchMode.parse(args.branch)
    if branch is BranchMode.CONTINUOUS and args.method == "vector-loop":
        raise InputError(
            "--branch continuous chooses the signs itself; --method vector-loop solves in the pose's mode: "
            "give one of them"
        )
    inputs = _inputs(mech, args.at, args.angles)
    if inputs is None and mech.drivers[0].sweep.count() > MAX_SAMPLES:
        raise InputError(
            f"{args.file}: the file's sweep has {mech.drivers[0].sweep.count()} samples, more than the "
            f"command line takes ({MAX_SAMPLES}); give --angles with a coarser STEP"
        )
    try:
        res = lk.analyze(
            mech,
            inputs,
            speed=_rates(mech, args.speed, "--speed"),
            acceleration=_rates(mech, args.acceleration, "--acceleration"),
            method=args.method,
            static=args.static,
            branch=branch,
        )
    except MethodNotApplicableError as exc:  # the method's own words name the mechanism, not the file or option
        raise MethodNotApplicableError(f"{args.file}: --method {args.method}: {exc}") from exc
    if args.format == "json":
        _emit(json.dumps(res.to_dict(), allow_nan=False) + "\n", args.output)
        return 0
    columns = res.columns()
    if args.format == "csv":
        _emit(format_csv(columns), args.output)
        return 0
    cat = res.catalogue
    shown = {q.name: q.owner_name for q in cat.table if q.group is Group.INPUTS}
    text = analysis_tables(
        columns, res.column_units(), analysis_sections(cat, mech.name or ""), inputs=shown, width=terminal_width()
    )
    _emit(text, args.output)
    return 0


def _modes_at(mech: Mechanism, at: list[str]) -> dict[str, float]:
    """``modes --at``: one value for every driver."""
    given = _by_driver(mech, at, "--at", _numbers)
    missing = [d.name for d in mech.drivers if d.name not in given]
    if missing:
        raise InputError(f"--at: give a value for every driver ({', '.join(d.name for d in mech.drivers)})")
    for name, values in given.items():
        if len(values) != 1:
            raise InputError(f"--at: one value per driver for modes, got {len(values)} for '{name}'")
    return {k: v[0] for k, v in given.items()}


def _modes(args: argparse.Namespace) -> int:
    """``linkagekit modes``."""
    import linkagekit as lk

    mech = lk.load(args.file)
    doc = lk.modes(mech, None if args.at is None else _modes_at(mech, args.at), mirrors=args.mirrors).to_dict()
    if args.format == "json":
        _emit(json.dumps(doc, allow_nan=False) + "\n", args.output)
        return 0
    units = _input_units(mech)
    at = ", ".join(f"{k} = {v:g} {units[k]}" for k, v in doc.get("input", {}).items())
    title = f"{mech.name or args.file}: assembly modes at {at}"
    width = terminal_width()
    _emit(
        modes_table(doc, _moving_joints(mech), mech.length_unit, mirrors=args.mirrors, width=width, title=title),
        args.output,
    )
    return 0


def _check(args: argparse.Namespace) -> int:
    """``linkagekit check``."""
    import linkagekit as lk

    mech = lk.load(args.file)
    rep = lk.check(mech).to_dict()
    if args.format == "json":
        _emit(json.dumps(rep, allow_nan=False) + "\n", args.output)
    else:
        _emit(check_text(rep, _input_units(mech), mech.name or args.file), args.output)
    return 0


def _suffix(path: str, allowed: tuple[str, ...], option: str = "-o") -> None:
    """Refuse an output path, before any work, whose suffix is not ``allowed`` or whose directory is not there (a
    synthesis into a missing directory failed only after its whole search, and the result was lost)."""
    import os

    ext = os.path.splitext(path)[1].lower()
    if ext not in allowed:
        raise InputError(f"{option} {shorten_path(path, 80)}: expected a file ending in {', '.join(allowed)}")
    if os.path.isdir(path):  # `-o out.yaml/`: refused only after a whole search, its result lost
        raise InputError(f"{option} {shorten_path(path, 80)}: cannot write there: it is a directory")
    folder = os.path.dirname(path) or "."
    if not os.path.isdir(folder):
        raise InputError(
            f"{option} {shorten_path(path, 80)}: cannot write there: no directory {shorten_path(folder, 80)}"
        )
    from .files import can_create_beside

    why = can_create_beside(path)
    if why is not None:  # `-o /proc/x.yaml`: a synthesis failed only after its whole search
        raise InputError(f"{option} {shorten_path(path, 80)}: cannot write there: {why}")


def _sweep(mech: Mechanism, angles: list[str] | None, file: str) -> dict[str, np.ndarray] | None:
    """The ``--angles`` sweep of the picture commands, or the file's (refused when too long, naming the ``file``)."""
    inputs = _inputs(mech, None, angles)
    if inputs is None and mech.drivers[0].sweep.count() > MAX_SAMPLES:
        raise InputError(
            f"{shorten_path(file, 80)}: the file's sweep has {mech.drivers[0].sweep.count()} samples, more than "
            f"the command line takes ({MAX_SAMPLES}); give --angles with a coarser STEP"
        )
    return inputs


def _plot(args: argparse.Namespace) -> int:
    """``linkagekit plot``."""

    import linkagekit as lk

    from .viz import draw

    _suffix(args.output, (".png", ".svg", ".pdf"))
    picture: dict[str, Any] = {"pixels": _size(args.size), **_dpi(args.dpi)}
    mech = lk.load(args.file)
    if args.modes and args.quantity:
        raise InputError("--modes and --quantity: give one of them")
    if args.mirrors and not args.modes:
        raise InputError("--mirrors goes with --modes")
    if args.modes and args.angles:
        raise InputError("--modes draws one input (--at), not a sweep: leave out --angles")
    if args.quantity and args.at:
        raise InputError("--quantity plots over the sweep (--angles), not at --at")
    if args.time is not None and (args.modes or args.at):
        raise InputError(f"--time draws a simulated motion, not {'--modes' if args.modes else '--at'}")
    if args.modes:
        at: Any = None
        if args.at:
            given = _by_driver(mech, args.at, "--at", _numbers)
            if any(len(v) != 1 for v in given.values()):
                raise InputError("--at: one value per driver with --modes")
            at = {k: v[0] for k, v in given.items()}
        fig = draw.modes_figure(mech, at, mirrors=args.mirrors, **picture)
        _check_pixels(fig)
        draw.save_figure(fig, args.output)
        return 0
    at = _poses_at(mech, args.at) if args.at else None  # before the sweep is solved: a list too long is refused first
    res = _solved(mech, args)
    if args.quantity:
        from .viz.scene import build_scene

        scene = build_scene(res)
        groups = [_quantities(res.catalogue, item) for item in args.quantity]
        fig = draw.quantities_figure(scene, groups, **picture)
        _check_pixels(fig)
        draw.save_figure(fig, args.output, fig.axes[0])  # a PNG maps the first plot's (x, value) to pixels
        return _stopped(res)
    poses = None
    if at is not None:
        poses = _swept(mech, args, at)  # on the sweep's branch: a parallelogram past flat stays one
    fig = draw.mechanism_figure(res, poses, **picture)
    _check_pixels(fig)
    draw.save_figure(fig, args.output, fig.axes[0])
    return _stopped(res)


#: the most poses ``plot --at`` draws, as many as an animation's frames (:data:`linkagekit.viz.animate.MAX_FRAMES`):
#: each is drawn (about 4 ms), where a sweep (``--angles``, up to :data:`MAX_SAMPLES`) is drawn as curves
MAX_POSES = 1000


def _poses_at(mech: Mechanism, items: list[str]) -> dict[str, np.ndarray]:
    """The inputs of the poses ``plot --at`` draws, by driver: at most :data:`MAX_POSES` (100,000 took minutes)."""
    import numpy as np

    at = {k: np.asarray(v) for k, v in _by_driver(mech, items, "--at", _numbers).items()}
    n = max(len(v) for v in at.values())
    if n > MAX_POSES:
        raise InputError(
            f"--at: {n} values, more poses than plot draws ({MAX_POSES}): give fewer, or --angles for the curves "
            "of a sweep"
        )
    return at


def _check_pixels(fig: Any) -> None:
    """Refuse a picture of more than :data:`MAX_PIXELS` pixels (a large --dpi, or --size W on a tall drawing)."""
    w, h = (float(v) * fig.dpi for v in fig.get_size_inches())
    if w * h > MAX_PIXELS or max(w, h) > MAX_SIDE:
        raise InputError(
            f"the picture would be {w:.0f} x {h:.0f} pixels, more than {MAX_SIDE} a side or {MAX_PIXELS:,} in all: "
            "give a smaller --size or --dpi"
        )


def _why_none(catalogue: Catalogue) -> str:
    """Why a plot group of forces is empty, when no force was computed at all."""
    if catalogue.of_group(Group.BEARING_LOADS):
        return ""
    return " (forces are computed when the file gives masses, gravity, loads, springs or dampers)"


def _quantities(catalogue: Catalogue, item: str) -> list[str]:
    """The column names one ``--quantity NAME[,NAME...]`` asks for: columns, or whole plot groups."""
    names: list[str] = []
    for name in (n.strip() for n in item.split(",")):
        if name in _QUANTITY_GROUPS:
            group = _QUANTITY_GROUPS[name]
            series = [q.name for q in catalogue.of_group(group)]
            if not series:
                raise InputError(
                    f"--quantity {name}: this mechanism has no {group.title.lower()}{_why_none(catalogue)}"
                )
            names += series
        elif name in catalogue:
            names.append(name)
        else:
            examples = ", ".join(q.name for q in catalogue.quantities[3:6])
            raise InputError(
                f"--quantity: no quantity {shorten(repr(name), 60)}; the names are the columns of "
                f"'analyze --format csv' (e.g. {examples}) or a group: " + ", ".join(_QUANTITY_GROUPS)
            )
    return names


def _animate(args: argparse.Namespace) -> int:
    """``linkagekit animate``."""
    import numpy as np

    import linkagekit as lk

    from .viz.animate import MAX_FRAMES, MAX_GIF_FPS, MIN_FRAMES, animate

    _suffix(args.output, (".gif", ".mp4"))
    fps = _fps(args.fps)
    if args.output.lower().endswith(".gif") and fps > MAX_GIF_FPS:
        raise InputError(f"--fps: a GIF plays at most {MAX_GIF_FPS:g} frames per second (write an .mp4 for more)")
    wanted = _frames(args.frames) if args.frames is not None else None
    mech = lk.load(args.file)
    timed = _timed(args)
    inputs = {"time": _range(args.time, "--time")} if timed else _sweep(mech, args.angles, args.file)
    values = inputs or {d.name: d.sweep.values() for d in mech.drivers}
    n = max(len(v) for v in values.values())
    frames = wanted or (n if n >= MIN_FRAMES else MIN_FRAMES)
    if frames > MAX_FRAMES:
        raise InputError(
            f"the {'motion' if timed else 'sweep'} has {n} samples, more frames than an animation takes "
            f"({MAX_FRAMES}): give --frames N or a coarser {'--time' if timed else '--angles'}"
        )
    if frames != n:  # evenly over each driver's sweep (or over the times), ends included
        values = {k: np.linspace(v[0], v[-1], frames) for k, v in values.items()}
    res = _motion(mech, args, values["time"]) if timed else _swept(mech, args, values)
    assert res is not None
    with _progress("frames") as tick:
        animate(res, args.output, fps=fps, progress=tick)
    return _stopped(res)


def _report(args: argparse.Namespace) -> int:
    """``linkagekit report``."""
    import linkagekit as lk

    from .web.report import write_report

    _suffix(args.output, (".html", ".htm"))
    mech = lk.load(args.file)
    _report_samples(mech, args)
    res = _solved(mech, args)
    write_report(res, args.output, source=_source_text(args.file))
    return _stopped(res)


def _report_samples(mech: Mechanism, args: argparse.Namespace) -> None:
    """Refuse, before any work and naming the option (or the file's sweep), more samples than a page holds."""
    import numpy as np

    from .web.report import MAX_REPORT_SAMPLES

    if _timed(args):
        n, what = len(_range(args.time, "--time")), "--time"
    else:
        inputs = _sweep(mech, args.angles, args.file)
        n = max((np.size(v) for v in inputs.values()), default=0) if inputs else mech.drivers[0].sweep.count()
        what = "--angles" if args.angles else f"{shorten_path(args.file, 80)}: the file's sweep"
    if n > MAX_REPORT_SAMPLES:
        raise InputError(f"{what}: {n} samples, more than a report page holds ({MAX_REPORT_SAMPLES}): a coarser STEP")


def _source_text(path: str) -> str | None:
    """The file's text as it stands, read under the same guard as :func:`linkagekit.load`.

    None when it cannot be read now (it was read a moment ago): the page then shows the
    mechanism as saved instead of the file.
    """
    from pathlib import Path

    from .errors import InputError
    from .files import MAX_FILE_BYTES, read_regular_file

    try:
        data = read_regular_file(Path(path), MAX_FILE_BYTES, "mechanism file", InputError)
        return None if len(data) > MAX_FILE_BYTES else data.decode("utf-8-sig")
    except (InputError, UnicodeDecodeError):
        return None


def _edit(args: argparse.Namespace) -> int:
    """``linkagekit edit``: serve until interrupted (Ctrl-C ends it with status 0)."""
    from .web.editor import SOLVE_SECONDS, serve

    port = 0
    if args.port is not None:
        try:
            port = int(args.port)
        except ValueError:
            raise InputError(f"--port: expected a whole number, got {shorten(repr(args.port))}") from None
        if not 0 <= port <= 65535:
            raise InputError(f"--port: expected 0 to 65535, got {port}")
    budget = SOLVE_SECONDS if args.solve_seconds is None else _one_number(args.solve_seconds, "--solve-seconds")
    if not 0 < budget <= 86400:
        raise InputError(f"--solve-seconds: expected a time over 0 and at most 86400 s, got {args.solve_seconds}")
    try:
        serve(args.file, port=port, open_browser=not args.no_browser, solve_seconds=budget)
    except KeyboardInterrupt:
        print(f"{PROG}: editor stopped", file=sys.stderr)
    return 0


def _integer(text: str, option: str, low: int, high: int) -> int:
    try:
        v = int(text)
    except ValueError:
        raise InputError(f"{option}: expected a whole number, got {shorten(repr(text))}") from None
    if not low <= v <= high:
        raise InputError(f"{option}: expected {low} to {high}, got {v}")
    return v


def _interval(text: str, option: str) -> tuple[float, float]:
    parts = text.split(":")
    if len(parts) != 2:
        raise InputError(f"{option}: expected LOW:HIGH, got {shorten(repr(text))}")
    lo, hi = (_one_number(p, option) for p in parts)
    if not lo < hi:
        raise InputError(f"{option}: LOW must be below HIGH, got {shorten(repr(text))}")
    return lo, hi


def _synthesize(args: argparse.Namespace) -> int:
    """``linkagekit synthesize``: a run stopped (Ctrl-C, SIGTERM, its workers lost) says in one line how to go on,
    whatever its task."""
    from .synthesis.distribute import WorkersLost

    try:
        return _synthesize_task(args)
    except KeyboardInterrupt as exc:
        print(f"{PROG}: {_stop_word(exc)}; {_synthesize_resume(args)}", file=sys.stderr)
        return 1
    except WorkersLost as e:
        raise LinkageError(f"{e}; {_synthesize_resume(args)}") from None


def _synthesize_task(args: argparse.Namespace) -> int:
    """:func:`_synthesize` of a path, a motion or a function."""
    import dataclasses
    import os
    import time

    t0 = time.monotonic()

    from .synthesis.run import synthesize_path
    from .synthesis.targets import read_targets
    from .units import LENGTH_UNITS

    _suffix(args.output, (".yaml", ".yml", ".json"))
    if args.plot:
        _suffix(args.plot, (".png", ".svg", ".pdf"), "--plot")
    _task_options(args)
    if args.units not in LENGTH_UNITS:  # named as the option, before any file is read or search run
        raise InputError(f"--units: {shorten(repr(args.units))} is not one of {', '.join(LENGTH_UNITS)}")
    if args.task == "motion":
        return _synthesize_motion(args)
    if args.task == "function":
        return _synthesize_function(args)
    search = _search_options(args)
    targets = read_targets(args.targets, units=args.units, points=search.pop("points"), smooth=not args.no_smooth)
    _unsmoothed_count(args, len(targets), targets.timed)
    targets = dataclasses.replace(targets, source=_synthesize_source(args.targets))
    if args.topology == "auto":
        return _synthesize_auto(args, targets, search, t0)
    if args.max_joints is not None:
        raise InputError("--max-joints goes with --topology auto")
    topology = _topology(args, targets.unit)
    budget = search["seconds"]
    search["seconds"] = max(budget - (time.monotonic() - t0), 1e-3)  # the command's start counts too
    with _Search(budget) as progress:
        out = synthesize_path(targets, topology, **search, progress=progress, pareto=args.pareto)
    paths = _write_designs(out, targets, args) if out.feasible else []
    for path in stale_pareto(args.output, len(paths)) if args.pareto and out.feasible else ():
        os.remove(path)
        print(f"removed {path}: a design of an earlier --pareto run, not of this one")
    if args.plot and out.feasible:
        _plot_synthesis(out, targets, args.plot)
    if targets.smoothed:
        print(targets.smoothed)
    print(
        synthesis_text(out, targets.xy, targets.inputs, targets.unit, _written(out.feasible, args.output), args.ordered)
    )
    if out.pareto and paths:
        print(pareto_text(out, targets.unit, paths))
    return _met(out.feasible, args.output)


def _write_designs(out: Any, targets: Any, args: argparse.Namespace) -> list[str]:
    """Write a path synthesis's design (``--pareto``: its designs, ``OUT.yaml``, ``OUT-2.yaml``, ...); the files, as
    the list prints them. An ``OUT-k`` that is there and is no design of an earlier ``--pareto`` run of this ``OUT``
    (the best design of ``-o OUT-2.yaml``, say) is kept, and that design not written."""
    import dataclasses

    import linkagekit as lk

    paths = pareto_paths(args.output, len(out.pareto))
    shown = []
    for k, (design, path) in enumerate(zip(out.pareto or (out,), paths, strict=True), 1):
        if k > 1 and not _pareto_own(path, args.output, k):
            print(f"kept {path}: not a design of an earlier --pareto run of {args.output} (design {k} not written)")
            shown.append("(not written)")
            continue
        described = f"{design.mechanism.description}\ncommand: {_synthesize_command(args)}"
        described += f"\n{targets.smoothed}" if targets.smoothed else ""
        described += f"\n{pareto_mark(args.output, k, len(paths))}" if args.pareto else ""
        lk.save(dataclasses.replace(design.mechanism, description=described), path)
        shown.append(path)
    return shown


def _met(feasible: bool, path: str) -> int:
    """The exit status of a synthesis: 0, or 1 with one line when the best design found breaks a constraint (then
    nothing is written: the command line's rule is exit 0 when a file was written; the table shows that design)."""
    if feasible:
        return 0
    print(
        f"{PROG}: synthesize: no design found meets the constraints; {path} is not written (the best one found, "
        "which breaks one, is shown above)",
        file=sys.stderr,
    )
    return 1


def _written(feasible: bool, path: str) -> str | None:
    """Where a synthesis wrote its design, or None (an infeasible best design is not written)."""
    return path if feasible else None


def _wrote(path: str | None) -> str:
    """The summary's last line: where the design was written (:func:`_written`), or that it was not."""
    return f"wrote {path}" if path is not None else "nothing written: the design breaks a constraint"


def pareto_paths(output: str, n: int) -> list[str]:
    """Where ``--pareto`` writes its ``n`` designs: ``OUT.yaml`` the most accurate, then ``OUT-2.yaml``, ...

    >>> pareto_paths("d/out.yaml", 3)
    ['d/out.yaml', 'd/out-2.yaml', 'd/out-3.yaml']
    """
    import os

    stem, ext = os.path.splitext(output)
    return [output] + [f"{stem}-{i}{ext}" for i in range(2, n + 1)]


def pareto_mark(output: str, k: int, n: int) -> str:
    """The line that marks design ``k`` of ``n`` that ``--pareto`` wrote for ``-o output`` (a later run of the same
    output may remove it when it writes fewer designs; a file of another series is never taken for one of it).

    >>> pareto_mark("d/out.yaml", 2, 3)
    "--pareto: design 2 of 3 of 'out.yaml'"
    """
    import os

    return _PARETO_MARK.format(k=k, n=n, name=repr(os.path.basename(output)))


#: :func:`pareto_mark`'s line, read back by :func:`_pareto_own` (any ``n``)
_PARETO_MARK = "--pareto: design {k} of {n} of {name}"


def stale_pareto(output: str, n: int) -> list[str]:
    """``OUT-k`` files past the ``n`` written that an earlier ``--pareto`` run of the same ``output`` wrote (their
    description says design k of that series), up to the first that is not one: only linkagekit's own files of this
    series (``run-3.yaml``, the first design of ``-o run-3.yaml``, is not design 3 of ``-o run.yaml``)."""
    import itertools
    import os

    stem, ext = os.path.splitext(output)
    out: list[str] = []
    for k in itertools.count(n + 1):
        path = f"{stem}-{k}{ext}"
        if not (os.path.isfile(path) and _pareto_own(path, output, k)):
            return out
        out.append(path)
    return out


def _pareto_own(path: str, output: str, k: int) -> bool:
    """Whether ``--pareto -o output`` may write (or remove) ``path`` as its design ``k``: nothing is there, or an
    earlier run of the same output wrote its design ``k`` there (the mark says so)."""
    import os
    import re

    import linkagekit as lk

    if not os.path.lexists(path):
        return True
    name = re.escape(repr(os.path.basename(output)))
    mark = _PARETO_MARK.format(k=k, n=r"\d+", name=name)  # its literal words hold no pattern characters
    try:
        return os.path.isfile(path) and re.search(mark, lk.load(path).description or "") is not None
    except (LinkageError, OSError):
        return False


def pareto_text(out: Any, unit: str, paths: list[str]) -> str:
    """``--pareto``'s list: each design's error and smallest transmission angle, the most accurate first."""
    cols = [
        Column("design", [str(i + 1) for i in range(len(out.pareto))]),
        Column(f"max error [{unit}]", format_cells([d.max_error for d in out.pareto])),
        Column("error [% diag]", format_cells([100 * d.max_error / d.diagonal for d in out.pareto])),
        Column("smallest transmission [deg]", format_cells([d.min_transmission for d in out.pareto])),
        Column("above the bound [deg]", format_cells([d.margin for d in out.pareto])),
        Column("file", paths),
    ]
    head = f"{len(out.pareto)} designs from the most accurate to the best-transmitting (none better in both):"
    return "\n".join(["", head, *render_table(cols)])


def _synthesize_auto(args: argparse.Namespace, targets: Any, search: dict[str, Any], t0: float) -> int:
    """``synthesize --topology auto``: the best of the built-in topologies up to ``--max-joints``; names it."""
    import dataclasses
    import time

    import linkagekit as lk

    from .synthesis.auto import synthesize_auto
    from .synthesis.topologies import MAX_JOINTS

    if args.free or args.pareto or search.get("pivots") or search.get("lengths") or args.reach is not None:
        raise InputError("--topology auto: --free, --pivots, --lengths, --reach and --pareto do not apply")
    if search.get("scheduler"):  # its searches are whole local ones, one a process: a cluster would sit idle
        raise InputError("--topology auto: --scheduler does not apply (its searches run on local processes)")
    max_joints = MAX_JOINTS if args.max_joints is None else _integer(args.max_joints, "--max-joints", 5, 10)
    for key in ("free", "pivots", "lengths", "reach"):
        search.pop(key, None)
    if search.get("workers") is None:  # every core by default, as for one topology
        from .synthesis.optimize import default_workers

        search["workers"] = default_workers()
    budget = search["seconds"]
    search["seconds"] = max(budget - (time.monotonic() - t0), 1e-3)
    with _Search(budget) as progress:
        out = synthesize_auto(targets, max_joints=max_joints, **search, progress=progress)
    described = f"{out.mechanism.description}\ncommand: {_synthesize_command(args)}"
    described += f"\n{targets.smoothed}" if targets.smoothed else ""
    if out.feasible:
        lk.save(dataclasses.replace(out.mechanism, description=described), args.output)
    if targets.smoothed:
        print(targets.smoothed)
    summary = synthesis_text(out, targets.xy, None, targets.unit, _written(out.feasible, args.output), args.ordered)
    text = summary.splitlines()
    a = out.mechanism.to_dict()["drivers"][0]["angles"]
    joints = len(out.mechanism.joint_names)
    tried = ", ".join(f"{t.name} {_percent(t.error)} ({_percent(t.two_sided)})" for t in out.tried)
    text.insert(-1, f"topology {out.topology} ({joints} joints), crank {a['start']:.6g} to {a['stop']:.6g} deg")
    text.insert(-1, f"searched: {tried}: rms error / diagonal (the two-sided distance / diagonal, which chose)")
    print("\n".join(text))
    return _met(out.feasible, args.output)


def _percent(x: float) -> str:
    """A share as a percentage, or what it means where it is not finite (:class:`~.synthesis.auto.Tried`: a design
    that breaks a constraint: the assembly over its sweep, a transmission angle, the curve's size, a link's length).

    >>> _percent(0.0123), _percent(float("inf"))
    ('1.23 %', 'breaks a constraint')
    """
    return f"{100 * x:.3g} %" if math.isfinite(x) else "breaks a constraint"


#: ``synthesize --seconds``' default, and the engine's time budget for ``--task function`` when it is not given
_DEFAULT_SECONDS, FUNCTION_SECONDS = "60", 10.0
#: ``synthesize --restarts``' default: more than fit in the time (the clock or the goal ends the run);
#: ``--task function``'s when it is not given
_DEFAULT_RESTARTS, FUNCTION_RESTARTS = "1000", 32


def _synthesize_function(args: argparse.Namespace) -> int:
    """``linkagekit synthesize --task function``: a four-bar whose output angle follows the pairs."""
    import dataclasses
    import os

    import linkagekit as lk

    from .synthesis.function import read_pairs
    from .synthesis.function_run import synthesize_function

    length = 1.0 if args.ground_length is None else _positive(args.ground_length, "--ground-length")
    if length > MAX_GROUND_LENGTH:  # 1e13 named no option: '<dict>: joints.B[0]: ...'
        raise InputError(f"--ground-length: at most {MAX_GROUND_LENGTH:g}, got {shorten(args.ground_length)}")
    x, y = read_pairs(args.targets)
    engine = {
        k: v
        for k, v in _search_options(args).items()
        if k in ("seconds", "seed", "restarts", "generations", "workers", "scheduler", "checkpoint")
    }
    if args.seconds == _DEFAULT_SECONDS:
        engine["seconds"] = FUNCTION_SECONDS
    if args.restarts == _DEFAULT_RESTARTS:
        engine["restarts"] = FUNCTION_RESTARTS
    given = args.min_transmission is not None  # the task imposes no bound unless asked
    engine["min_transmission"] = _one_number(args.min_transmission, "--min-transmission") if given else 0.0
    out = synthesize_function(
        x,
        y,
        free_offsets=args.free_offsets,
        ground_length=length,
        units=args.units,
        source=os.path.basename(args.targets),
        **engine,
    )
    fit, mech = out.fit, out.mechanism
    words = [PROG, "synthesize", os.path.basename(args.targets), "--task function", f"--units {args.units}"]
    words += ["--free-offsets"] * args.free_offsets + [f"--ground-length {length!r}", f"--seed {engine['seed']}"]
    words += [f"--seconds {engine['seconds']!r}", f"--min-transmission {engine['min_transmission']!r}"]
    words += [f"--restarts {engine['restarts']}", f"--generations {engine['generations']}"]
    mech = dataclasses.replace(mech, description=_function_description(out, args.units, " ".join(words)))
    if fit.valid:
        lk.save(mech, args.output)
    if args.plot and fit.valid:
        _plot_function(mech, fit, args.plot)
    print(function_text(out, args.units, _written(fit.valid, args.output)))
    return _met(fit.valid, args.output)


def _plot_function(mech: Any, fit: Any, path: str) -> None:
    """``--plot`` of a function generator: its output angle (by ``analyze``) against the input, with the pairs."""
    import numpy as np

    import linkagekit as lk

    from .viz import draw

    phi0, psi0 = fit.offsets
    x = np.linspace(fit.inputs[0], fit.inputs[-1], 361)
    psi = lk.analyze(mech, {"crank": x + phi0}).angle("output")
    out = fit.outputs[0] + (psi - psi0 - fit.outputs[0] + 180.0) % 360.0 - 180.0  # unwrapped near the first pair
    pairs = np.stack([fit.inputs, fit.outputs], axis=1)
    fig, ax = draw.function_figure(np.stack([x, out], axis=1), pairs, fit.errors)
    draw.save_figure(fig, path, ax)


def _positive(text: str, option: str) -> float:
    try:
        value = _float(text)
    except ValueError:
        raise InputError(f"{option}: expected a number, got {shorten(repr(text))}") from None
    if not (math.isfinite(value) and value > 0):
        raise InputError(f"{option}: expected a positive number, got {shorten(repr(text))}")
    return value


def _transmission_warning(lo: float, hi: float = 90.0) -> list[str]:
    """A warning line when a designed four-bar's transmission angle (deg, from ``lo`` to ``hi``) leaves ``check``'s
    ``[MIN, 180 - MIN]`` (:data:`linkagekit.checks.MIN_TRANSMISSION`): motion and function generation bound none by
    default."""
    from .checks import MIN_TRANSMISSION

    worst = min(lo, 180.0 - hi)
    if not worst < MIN_TRANSMISSION - 1e-3:  # (a design held at that bound meets it to the polish's tolerance)
        return []
    at = f"down to {lo:.4g}" if lo <= 180.0 - hi else f"up to {hi:.4g}"
    bound = f"{MIN_TRANSMISSION:g}"
    return [
        f"warning: the transmission angle goes {at} deg (outside [{bound}, {180 - MIN_TRANSMISSION:g}]): there the "
        f"coupler pushes the output mostly into its bearing; --min-transmission {bound} bounds it"
    ]


def _function_description(out: Any, unit: str, command: str) -> str:
    """A function generator's ``description``: what the command prints of it (its pairs, errors, offsets, lengths),
    the offsets to full precision (the output angle is ``output + offset``: the file alone does not say it), and
    the command."""
    lines = function_text(out, unit, None).splitlines()[:-1]  # not the line about the file
    if out.fit.offsets != (0.0, 0.0):
        crank, output = (float(v) for v in out.fit.offsets)
        lines.append(
            f"offsets to full precision: crank angle = input {crank:+.17g} deg, "
            f"output angle = output {output:+.17g} deg"
        )
    return "\n".join([*lines, f"command: {command}"])


def function_text(out: Any, unit: str, path: str | None) -> str:
    """The table of pairs and errors, and the summary, that ``synthesize --task function`` prints."""
    fit = out.fit
    cols = [
        Column("pair", [str(i + 1) for i in range(len(fit.inputs))]),
        Column("input [deg]", format_cells(fit.inputs)),
        Column("output [deg]", format_cells(fit.outputs)),
        Column("error [deg]", format_cells(fit.errors)),
    ]
    a, b, c, d = fit.lengths
    side = "left" if fit.branch > 0 else "right"
    lines = [*render_table(cols), ""]
    lines.append(f"max error {fit.max_error:.6g} deg ({fit.method})")
    if len(fit.inputs) == 3 and fit.method != "exact" and fit.offsets == (0.0, 0.0):
        lines.append(
            "three pairs are met exactly only by Freudenstein's four-bar, and here its crank or output would point "
            "180 deg away from the angles given (or not assemble on one branch): --free-offsets may meet them"
        )
    if fit.offsets != (0.0, 0.0):
        lines.append(
            f"offsets: crank angle = input {fit.offsets[0]:+.6g} deg, output angle = output {fit.offsets[1]:+.6g} deg"
        )
    lines.append(f"crank {a:.6g}, coupler {b:.6g}, output {c:.6g}, ground {d:.6g} {unit}; Grashof type {fit.grashof}")
    state = "one branch from the first pair to the last" if fit.valid else "NOT ON ONE BRANCH (no valid design found)"
    lines.append(f"branch {fit.branch:+d} (D {side} of the line from C to B): {state}")
    lines.append(f"transmission angle {fit.transmission[0]:.4g} to {fit.transmission[1]:.4g} deg")
    lines += _transmission_warning(*fit.transmission)
    if out.engine is not None:
        from .synthesis.targets import plural

        o = out.engine.outcome
        lines.append(
            f"engine: {plural(o.restarts, 'search', 'searches')}, {plural(o.evaluations, 'design')} in "
            f"{o.seconds:.1f} s "
            f"(its best, before the minimax polish: {math.degrees(out.engine.error):.6g} deg)"
        )
    lines.append(_wrote(path))
    return "\n".join(lines)


def _synthesize_motion(args: argparse.Namespace) -> int:
    """``linkagekit synthesize POSES.csv --task motion``: a four-bar whose coupler passes through the poses."""
    import dataclasses

    import linkagekit as lk

    from .synthesis.motion import read_poses
    from .synthesis.run import synthesize_motion

    if args.topology != "fourbar":
        _motion_template(args.topology)
    seconds = _seconds(args)
    weight = None if args.angle_weight is None else _one_number(args.angle_weight, "--angle-weight")
    pf = read_poses(args.targets)
    out = synthesize_motion(
        pf.poses,
        inputs=None if pf.inputs is None else list(pf.inputs),
        closed=pf.closed,
        approximate=args.approximate,
        weight=weight,
        min_transmission=_one_number(args.min_transmission, "--min-transmission") if args.min_transmission else 0.0,
        units=args.units,
        seed=_integer(args.seed, "--seed", 0, 2**32 - 1),
        seconds=seconds,
        full_turn=args.full_turn,
        engine=_motion_engine(args),
        source=shorten_path(pf.source),
    )
    best = out.best
    described = f"{motion_text(out, pf.poses, args.units, None)}\ncommand: {_synthesize_command(args)}"
    lk.save(dataclasses.replace(best.mechanism, description=described), args.output)
    if args.plot:
        from .viz import draw

        fig = draw.motion_figure(best.mechanism, pf.poses, best.inputs, closed=pf.closed or args.full_turn)
        draw.save_figure(fig, args.plot, fig.axes[0])
    print(motion_text(out, pf.poses, args.units, args.output))
    return 0


def _motion_template(path: str) -> None:
    """``--topology FILE`` with ``--task motion``: refused unless a four-bar whose coupler carries ``P`` and ``Q``."""
    import os

    import linkagekit as lk

    if not os.path.exists(path):
        raise InputError(
            f"--topology {shorten_path(path)}: motion generation designs four-bars only (--topology fourbar)"
        )
    mech = lk.load(path)
    if not any({"P", "Q"} <= set(link.joints) for link in mech.links):
        raise InputError(f"{shorten_path(path)}: a motion template needs tracer joints P and Q on one link")
    raise InputError(f"{shorten_path(path)}: motion generation designs four-bars only (--topology fourbar)")


def motion_text(out: Any, poses: Any, unit: str, path: str | None) -> str:
    """The table of poses and errors, the summary and the other four-bars found, that ``--task motion`` prints."""
    import numpy as np

    best = out.best
    cols = [
        Column("pose", [str(i + 1) for i in range(len(poses))]),
        Column(f"x [{unit}]", format_cells(poses[:, 0])),
        Column(f"y [{unit}]", format_cells(poses[:, 1])),
        Column("angle [deg]", format_cells(poses[:, 2])),
        Column("crank [deg]", format_cells(np.mod(best.inputs, 360.0))),
        Column(f"error [{unit}]", format_cells(best.position_errors)),
        Column("error [deg]", format_cells(best.angle_errors)),
    ]
    lines = render_table(cols)
    lines.append("")
    lines.append(
        f"{best.method} four-bar: max error {best.max_position_error:.6g} {unit} "
        f"({100 * best.max_position_error / out.diagonal:.4g} % of the poses' diagonal {out.diagonal:.6g} {unit}) "
        f"and {best.max_angle_error:.4g} deg"
    )
    branch = "met in order on one branch" if best.one_branch else "NOT met in order on one branch"
    lines.append(f"{best.grashof}; poses {branch}; smallest transmission angle {best.min_transmission:.4g} deg")
    lines += _transmission_warning(best.min_transmission)
    if len(out.fourbars) > 1:
        lines.append(f"{len(out.fourbars)} four-bars found (best first):")
        for i, f in enumerate(out.fourbars):
            order = "one branch" if f.one_branch else "not in order on one branch"
            lines.append(
                f"  {i + 1}. {f.method}, {f.grashof}, {order}: max error {f.max_position_error:.4g} {unit}, "
                f"{f.max_angle_error:.4g} deg"
            )
    if path is not None:
        lines.append(f"wrote {path}")
    return "\n".join(lines)


def _synthesize_resume(args: argparse.Namespace) -> str:
    """How to go on after a run that stopped before its end (a checkpoint is said saved only when it is there: a run
    stopped before its first save has none)."""
    import os

    if args.checkpoint and os.path.isfile(args.checkpoint):
        return f"the search is saved in {shorten(args.checkpoint, 80)}: the same command resumes it"
    if args.checkpoint:
        return f"stopped before its first save to {shorten(args.checkpoint, 80)}: the same command starts it again"
    return "nothing was saved (with --checkpoint FILE the same command resumes a run)"


def _unsmoothed_count(args: argparse.Namespace, count: int, timed: bool) -> None:
    """Refuse more untimed targets than ``--no-smooth`` takes as they are (the search's clock is read only after
    the atlas has placed, refitted and checked its answers on every one of them)."""
    from .synthesis.targets import MAX_UNSMOOTHED

    if args.no_smooth and not timed and count > MAX_UNSMOOTHED:
        raise InputError(
            f"{shorten_path(args.targets, 80)}: {count} points; --no-smooth takes at most {MAX_UNSMOOTHED} as they "
            "are (every evaluation costs in proportion): leave it out to smooth them, or give fewer points"
        )


def _synthesize_source(path: str) -> str:
    """The targets' file as the written mechanism records it: its name and the start of its SHA-256."""
    import hashlib
    import os

    digest = hashlib.sha256()
    with open(path, "rb") as f:  # read a moment ago (a regular file within read_targets' limit)
        digest.update(f.read(1 << 26))
    return f"{os.path.basename(path)}, sha256 {digest.hexdigest()[:16]}"


#: the options of ``synthesize`` that decide its result (those that say where it runs or writes do not)
_SYNTHESIZE_DECIDING = (
    "topology",
    "max_joints",
    "units",
    "seed",
    "seconds",
    "restarts",
    "generations",
    "goal",
    "min_transmission",
    "reach",
    "points",
    "free",
    "pivots",
    "lengths",
)


#: the options that decide a ``--task motion`` result (besides --task, --approximate and --angle-weight)
_MOTION_DECIDING = ("units", "seed", "seconds", "min_transmission")


def _synthesize_command(args: argparse.Namespace) -> str:
    """The command that gives this result again, from the targets' directory (every deciding option spelt out)."""
    import os
    import shlex

    words = [PROG, "synthesize", os.path.basename(args.targets)]
    deciding = _MOTION_DECIDING if args.task == "motion" else _SYNTHESIZE_DECIDING
    for name in deciding:
        value = _path_option(args, name) if name in _PATH_DEFAULTS else getattr(args, name)
        if name == "min_transmission" and value is None and args.task == "path":
            value = "20"
        if value is not None:
            words += ["--" + name.replace("_", "-"), str(value)]
    # --pareto decides the searches (half at raised bounds)
    flags = ("ordered", "shape-only", "partial", "pareto", "no-smooth")
    words += [f"--{flag}" for flag in flags if getattr(args, flag.replace("-", "_"))]
    if args.task != "path":
        words += ["--task", args.task] + (["--approximate"] if args.approximate else [])
        words += ["--full-turn"] if args.task == "motion" and args.full_turn else []
        words += ["--angle-weight", str(args.angle_weight)] if args.angle_weight is not None else []
    return " ".join(shlex.quote(w) for w in words)


def _motion_engine(args: argparse.Namespace) -> dict[str, Any]:
    """The engine options given on the command line for motion's search of seeds (the rest: its short default)."""
    options = _search_options(args)
    defaults = {"restarts": int(_DEFAULT_RESTARTS), "generations": 500, "workers": None}
    defaults.update(scheduler=None, checkpoint=None)
    return {k: options[k] for k, d in defaults.items() if options[k] != d}


def _seconds(args: argparse.Namespace) -> float:
    """``--seconds``, within the engine's limit (:data:`~linkagekit.synthesis.optimize.LIMITS`)."""
    from .synthesis.optimize import LIMITS

    return float(LIMITS["seconds"].check(_one_number(args.seconds, "--seconds"), "--seconds"))


def _whole(args: argparse.Namespace, name: str) -> int:
    """The whole-number search option ``--NAME``, within the engine's limit for ``name``."""
    from .synthesis.optimize import LIMITS

    limit = LIMITS[name]
    return _integer(getattr(args, name), f"--{name}", int(limit.low), int(limit.high))


def _search_options(args: argparse.Namespace) -> dict[str, Any]:
    """The keyword arguments of :func:`~linkagekit.synthesis.run.synthesize` that the options give, checked.

    Also ``points`` (the samples along an SVG path), which goes to the targets' reader instead.
    """
    import os

    seconds = _seconds(args)
    options: dict[str, Any] = {
        "seconds": seconds,
        "seed": _integer(args.seed, "--seed", 0, 2**32 - 1),
        "min_transmission": _one_number(args.min_transmission or "20", "--min-transmission"),
        "workers": None if args.workers is None else _whole(args, "workers"),
    }
    options["points"] = _integer(
        _path_option(args, "points"), "--points", 3, 100_000
    )  # of an SVG path: read_targets's, not synthesize's
    options["restarts"] = _whole(args, "restarts")
    options["generations"] = _whole(args, "generations")
    options["goal"] = _one_number(_path_option(args, "goal"), "--goal")
    if not 0 <= options["goal"] < 1:
        raise InputError(f"--goal: expected a fraction of the targets' diagonal in [0, 1), got {args.goal}")
    options["reach"] = _one_number(_path_option(args, "reach"), "--reach")
    if not 0 < options["reach"] <= 100:
        raise InputError(f"--reach: expected a positive number up to 100, got {args.reach}")
    options["pivots"] = _pivots(args.pivots) if args.pivots else None
    options["lengths"] = _interval(args.lengths, "--lengths") if args.lengths else None
    if options["lengths"] is not None and options["lengths"][0] < 0:
        raise InputError("--lengths: lengths are not negative")
    if args.checkpoint and os.path.isdir(args.checkpoint):
        raise InputError(f"--checkpoint {shorten(args.checkpoint, 80)}: is a directory")
    folder = os.path.dirname(args.checkpoint or "") or "."
    if args.checkpoint and not os.path.isdir(folder):  # found only after the atlas's answer, exit 1
        raise InputError(f"--checkpoint {shorten_path(args.checkpoint, 80)}: no directory {shorten_path(folder, 80)}")
    if args.checkpoint:
        _writable(args.checkpoint)
    options["free"] = [j.strip() for j in args.free.split(",") if j.strip()] if args.free else None
    options.update(ordered=args.ordered, scheduler=args.scheduler, checkpoint=args.checkpoint)
    options.update(shape_only=args.shape_only, partial=args.partial)
    return options


def _writable(checkpoint: str) -> None:
    """Refuse a checkpoint that cannot be written where it is to be (``/proc/ck.npz``, a read-only folder) before the
    search: it failed at the first save, after the screen (exit 1). A temporary file of the name its writer would
    use is made and removed (:func:`~linkagekit.files.can_create_beside`)."""
    from .files import can_create_beside

    reason = can_create_beside(checkpoint)
    if reason is not None:
        raise InputError(f"--checkpoint {shorten_path(checkpoint, 80)}: cannot be written ({reason})")


def _pivots(text: str) -> tuple[tuple[float, float], tuple[float, float]]:
    """``--pivots X0:X1,Y0:Y1``: the region of the ground pivots."""
    xy = text.split(",")
    if len(xy) != 2:
        raise InputError(f"--pivots: expected X0:X1,Y0:Y1, got {shorten(repr(text))}")
    return _interval(xy[0], "--pivots"), _interval(xy[1], "--pivots")


def _topology(args: argparse.Namespace, unit: str) -> Any:
    """``--topology``: a topology's name, or the template mechanism its file holds (in the targets' *unit*)."""
    import os

    import linkagekit as lk

    from .synthesis.space import TOPOLOGIES, is_builtin

    name: str = args.topology
    if is_builtin(name):  # a hand-drawn one, or an enumerated one that --topology auto names (sixbar-1, ...)
        if args.free:
            raise InputError("--free goes with a template file given as --topology")
        return name
    if not os.path.exists(name):
        known = ", ".join(TOPOLOGIES)
        raise InputError(
            f"--topology: '{shorten_path(name)}' is neither a topology ({known}, or a name --topology auto prints, "
            "such as sixbar-1) nor a file"
        )
    template = lk.load(name)
    if template.length_unit != unit:
        raise InputError(
            f"--topology {shorten(name, 80)}: its length unit is {template.length_unit}, "
            f"the targets' is {unit} (--units)"
        )
    return template


def _plot_synthesis(out: Any, targets: Any, path: str) -> None:
    """``--plot``: the targets on the curve the synthesized mechanism draws over a full turn of its crank."""
    import numpy as np

    import linkagekit as lk

    from .viz import draw

    start, stop = out.sweep if out.sweep is not None else (0.0, 360.0)  # a partial sweep: only its range
    res = lk.analyze(out.mechanism, {out.mechanism.drivers[0].name: np.linspace(start, stop, 721)})
    fig = draw.synthesis_figure(res, targets.xy, out.errors, closed=targets.closed)
    draw.save_figure(fig, path, fig.axes[0])


def synthesis_text(out: Any, xy: Any, inputs: Any, unit: str, path: str | None, ordered: bool = False) -> str:
    """The table of targets and errors, and the summary, that ``synthesize`` prints (``ordered``: the targets are
    met in their order, a max error the tolerance line does not measure)."""
    cols = [
        Column("target", [str(i + 1) for i in range(len(xy))]),
        Column(f"x [{unit}]", format_cells(xy[:, 0])),
        Column(f"y [{unit}]", format_cells(xy[:, 1])),
    ]
    if inputs is not None:
        cols.append(Column("input [deg]", format_cells(inputs)))
    crank = out.inputs if getattr(out, "sweep", None) is not None else out.inputs % 360.0  # partial: in its sweep
    cols.append(Column("crank [deg]", format_cells(crank)))
    cols.append(Column(f"error [{unit}]", format_cells(out.errors)))
    cols.append(Column("error [% diag]", format_cells(100.0 * out.errors / out.diagonal)))
    o = out.outcome
    lines = render_table(cols)
    lines.append("")
    lines.append(
        f"max error {out.max_error:.6g} {unit} ({100 * out.max_error / out.diagonal:.4g} % of the targets' "
        f"diagonal {out.diagonal:.6g} {unit}), rms {out.rms_error:.6g} {unit}"
    )
    if out.offset is not None:
        lines.append(f"input offset {out.offset:.6g} deg (crank angle = input + offset)")
    lines += [] if ordered else _tolerance_lines(out, xy, inputs, unit)
    from .synthesis.run import transmission_line

    lines += _shape_lines(out, unit)
    state = "the crank turns fully" if out.feasible else "CONSTRAINTS NOT MET (the best design found breaks one)"
    if out.sweep is not None and out.feasible:
        start, stop = out.sweep
        state = f"the crank rocks from {start:.4g} to {stop:.4g} deg ({stop - start:.4g} deg) on one branch"
    lines.append(f"{state}; {transmission_line(out)}")
    from .synthesis.targets import plural

    why = {"goal": "reaching the goal", "restarts": "the last search", "time": "the time limit"}[o.stopped_by]
    lines.append(
        f"{plural(o.restarts, 'search', 'searches')}, {plural(o.generations, 'generation')}, "
        f"{plural(o.evaluations, 'design')} evaluated in {o.seconds:.1f} s; stopped by {why}"
    )
    lines.append(_wrote(path))
    return "\n".join(lines)


#: a max error raised by more than this many times the move of one joint is said to need tight tolerances
SENSITIVE = 10.0


def _tolerance_lines(out: Any, xy: Any, inputs: Any, unit: str) -> list[str]:
    """The tolerance line (:mod:`~linkagekit.synthesis.tolerance`) of a written design whose targets are untimed,
    and a warning where one joint's move costs more than :data:`SENSITIVE` times itself in max error."""
    if inputs is not None or not out.feasible or "P" not in out.mechanism.joint_names:
        return []
    from .synthesis.tolerance import SHARE, tolerance

    tol = tolerance(out.mechanism, xy[:, 0] + 1j * xy[:, 1], "P")
    if not math.isfinite(tol.exact):  # the design as written does not assemble over the sweep it was checked on
        return []
    if not math.isfinite(tol.worst):
        return [
            f"tolerance: with joint {tol.joint} {tol.step:.3g} {unit} off its place ({100 * SHARE:g} % of the "
            "diagonal) the design no longer assembles over its whole sweep",
            "warning: this design's accuracy hangs on making its joints exactly where they are",
        ]
    gain, more = tol.gain, f"{tol.worst - tol.exact:.3g} {unit}"
    effect = (
        f"raises the max error by {more} ({gain:.3g} times the move) to {tol.worst:.4g} {unit}"
        if gain > 0
        else (f"keeps the max error at most {tol.worst:.4g} {unit}")
    )
    lines = [
        f"tolerance: joint {tol.joint} {tol.step:.3g} {unit} off its place ({100 * SHARE:g} % of the diagonal) {effect}"
    ]
    if gain > SENSITIVE:
        lines.append("warning: this design's accuracy hangs on making its joints exactly where they are")
    return lines


def _shape_lines(out: Any, unit: str) -> list[str]:
    """``--shape-only``: the line that says how the design was placed on the targets (none otherwise)."""
    import cmath

    if out.placement is None:
        return []
    a, b = out.placement
    return [
        f"placed on the targets (--shape-only): scaled by {abs(a):.6g}, turned by {math.degrees(cmath.phase(a)):.6g} "
        f"deg, moved by ({b.real:.6g}, {b.imag:.6g}) {unit}"
    ]


class _Search:
    """The synthesis progress on stderr: a bar on a terminal, else a plain line after ``first`` seconds, then
    every ``every`` seconds."""

    every, first = 5.0, 1.0

    def __init__(self, seconds: float) -> None:
        self.seconds = seconds
        self.bar: Any = None
        self.task: Any = None
        self.last = -math.inf  # time.monotonic() of the last plain line
        self.atlas: Any = None  # the atlas's answer: the best so far until a search beats it

    def __enter__(self) -> Callable[[Any], None]:
        if sys.stderr.isatty():
            from rich.console import Console
            from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

            self.bar = Progress(
                TextColumn("{task.fields[where]}"),
                BarColumn(),
                TextColumn("best error {task.fields[best]}"),
                TimeElapsedColumn(),
                console=Console(stderr=True),
                transient=True,
            )
            self.bar.start()
            self.task = self.bar.add_task("synthesis", total=self.seconds, where="search 1 gen 0", best="-")
        else:
            import time

            self.last = time.monotonic() - self.every + min(self.first, self.every)  # the first after ``first`` s
        return self.update

    def best(self, p: Any) -> str:
        """The best design so far, as the progress shows it: the searches' or the atlas's answer, whichever is better
        (a search's "best 23 %" after the atlas's 1.03 % read as if the run had lost it)."""
        a = self.atlas
        if a is not None and a is not p and not a.best_error >= p.best_error:  # the searches' NaN: none polished yet
            return f"{self.best(a)} (the atlas's)"
        if p.best_error != p.best_error:  # NaN: no search is finished (polished) yet
            return f"cost {p.best_cost:.3g} (no search polished yet)"
        if not math.isfinite(p.best_error):
            return "max error: no design meets the constraints yet"
        return f"max error {100 * p.best_error:.3g} % of the targets' diagonal"

    def update(self, p: Any) -> None:
        import time

        if hasattr(p, "line"):  # --topology auto's stages (synthesis.auto.Stage): each line as it comes
            self.say(p.line(self.seconds - p.seconds, self.seconds))  # its budget: what was left after the start
            if self.bar is not None:  # the bar: the stage, and the best so far as the run chooses
                best = "-" if p.best != p.best else f"{100 * p.best:.3g} % (two-sided)"
                where = p.what if len(p.what) <= 48 else p.what[:47] + "…"
                self.bar.update(self.task, completed=min(p.elapsed + self.seconds - p.seconds, self.seconds))
                self.bar.update(self.task, where=where, best=best)
            return
        if p.source == "atlas":  # the atlas's answer, before any search: said at once
            self.atlas = p
            line = (
                f"the atlas's nearest four-bar, placed and polished: {self.best(p)} ({p.elapsed:.1f} s); searching on"
            )
            self.say(line)
            if self.bar is None:
                self.last = time.monotonic()  # a progress line too: the next comes ``every`` s after it (on a busy
                # machine the atlas took past ``first`` s, and a run its answer ended said "search 1, generation 0")
        if self.bar is not None:
            self.bar.update(
                self.task, completed=min(p.elapsed, self.seconds), where=f"search {p.restart + 1} gen {p.generation}"
            )
            self.bar.update(self.task, best=self.best(p).removeprefix("max error "))  # its column: "best error"
        elif time.monotonic() - self.last >= self.every:
            self.last = time.monotonic()
            print(
                f"{PROG}: synthesize: search {p.restart + 1}, generation {p.generation}, best {self.best(p)}, "
                f"{p.evaluations} designs, {p.elapsed:.0f} of {self.seconds:g} s",
                file=sys.stderr,
                flush=True,
            )

    def say(self, line: str) -> None:
        """One line of progress: above the bar on a terminal, else on stderr."""
        if self.bar is not None:
            self.bar.console.print(line)
        else:
            print(f"{PROG}: synthesize: {line}", file=sys.stderr, flush=True)

    def __exit__(self, *exc: object) -> None:
        if self.bar is not None:
            self.bar.stop()


class _progress:
    """A progress bar on stderr, when it is a terminal: ``with _progress(what) as tick: tick(done, total)``."""

    def __init__(self, what: str) -> None:
        self.what = what
        self.bar: Any = None
        self.task: Any = None

    def __enter__(self) -> Callable[[int, int], None]:
        if sys.stderr.isatty():
            from rich.console import Console
            from rich.progress import BarColumn, MofNCompleteColumn, Progress, TimeRemainingColumn

            self.bar = Progress(
                "[progress.description]{task.description}",
                BarColumn(),
                MofNCompleteColumn(),
                TimeRemainingColumn(),
                console=Console(stderr=True),
                transient=True,
            )
            self.bar.start()
        return self.tick

    def tick(self, done: int, total: int) -> None:
        if self.bar is None:
            return
        if self.task is None:
            self.task = self.bar.add_task(self.what, total=total)
        self.bar.update(self.task, completed=done)

    def __exit__(self, *exc: object) -> None:
        if self.bar is not None:
            self.bar.stop()


def _atlas_arguments(p: argparse.ArgumentParser) -> None:
    actions = ("build", "info")
    p.add_argument(
        "action",
        choices=actions,
        metavar="{" + ",".join(actions) + "}",  # named so in argparse's 'required' message too, as in the usage
        help="build the atlas now (unless cached), or say what is cached",
    )
    p.add_argument("--workers", type=int, metavar="N", help="processes that build it (default: every core)")


def _atlas(args: argparse.Namespace) -> int:
    """``linkagekit atlas build|info``."""
    import time

    from .synthesis import atlas

    if args.workers is not None and args.workers < 1:
        raise InputError(f"--workers: expected at least 1, got {args.workers}")
    if args.workers is not None and args.action != "build":
        raise InputError("--workers: only 'atlas build' builds; 'atlas info' never does")
    t0 = time.monotonic()
    if atlas.size() == 0:
        raise InputError("LINKAGEKIT_ATLAS_SIZE is 0: the atlas is turned off")
    if args.action == "build":
        atlas.build(tick=atlas.build_report(), workers=args.workers)
    got = atlas.info()
    state = f"built, {got.bytes / 1e6:.1f} MB" if got.built else "not built yet"
    if got.damaged:
        state = f"damaged: a {got.bytes / 1e6:.1f} MB file that is not a whole atlas; the next use rebuilds it"
    print(f"four-bar atlas, format {got.version}: {got.file} ({state})")
    print(f"{got.entries} entries: {got.closed} closed curves (the crank turns fully), {got.open} open")
    if got.chunks:
        print(f"{got.chunks} of {got.entries // atlas.chunk_entries(got.entries)} chunks of an unfinished build")
    if args.action == "build":
        print(f"ready in {time.monotonic() - t0:.1f} s")
    return 0


#: every command, in the order ``linkagekit --help`` lists them
_COMMANDS = (
    _Command(
        "analyze",
        "positions, velocities, accelerations (and forces) over a sweep of the inputs",
        "Positions, velocities and accelerations (and forces, when the file gives masses, "
        "gravity or loads) over a sweep of the inputs. Input values are in the file's angle unit "
        "(length unit for a slider's displacement or a cylinder's length); with several drivers give NAME=... "
        "per driver.",
        _analyze_arguments,
        _analyze,
    ),
    _Command(
        "simulate",
        "forward dynamics: the motion under a driver torque or motor curve",
        "Integrate the equations of motion from the pose (at rest, or at --speed) under a constant torque "
        "(--torque) or the linear motor curve T0 (1 - w/W0) (--motor), with the file's masses, gravity, loads, "
        "springs, dampers and flywheels; one row per output time, with the columns of analyze plus time. "
        "A motion that meets a toggle it cannot pass is written up to it, then one line says where (exit 1). "
        "With --flywheel CS instead of --time: the smallest extra inertia on the driver's crank that keeps the "
        "periodic steady state's speed fluctuation (w_max - w_min) / mean within CS.",
        _simulate_arguments,
        _simulate,
    ),
    _Command(
        "modes",
        "every assembly mode at one input value",
        "Every assembly mode at one input value, with its joint positions.",
        _modes_arguments,
        _modes,
    ),
    _Command(
        "check",
        "validate a file: degrees of freedom, solve plan, where it assembles",
        "Validate a mechanism file; print its degrees of freedom, solve plan, the input "
        "range where it assembles and, for a four-bar loop, its Grashof type and transmission angle.",
        _check_arguments,
        _check,
    ),
    _Command(
        "plot",
        "draw the mechanism and its coupler curves, its assembly modes, or any quantity",
        "Draw the mechanism (hatched ground, pins, links, sliders) with the path of every "
        "moving joint over the sweep (coupler curves in colour, broken where it does not assemble); "
        "--modes draws every assembly mode side by side; --quantity plots quantities against the input.",
        _plot_arguments,
        _plot,
    ),
    _Command(
        "animate",
        "an animation of the sweep: GIF, or MP4 with an ffmpeg",
        "Animate the mechanism over the sweep, one frame per sample (at least 36). "
        "MP4 needs an ffmpeg on PATH or pip install 'linkagekit[video]'.",
        _animate_arguments,
        _animate,
    ),
    _Command(
        "report",
        "one self-contained HTML page: the mechanism moving, its curves, plots, checks",
        "Write one self-contained HTML page: the mechanism moving under a slider, its "
        "curves, plots of its rates (and forces), the checks, the solve plan and the file itself.",
        _report_arguments,
        _report,
    ),
    _Command(
        "edit",
        "edit the mechanism in the browser: drag joints, see it re-solved; save the file",
        "Serve an editor of FILE on 127.0.0.1 (its URL, with a random token, is the first line "
        "printed) and open it in the browser. Drag joints, change numbers, add links, choose the assembly "
        "mode; every picture is solved by linkagekit. Save writes FILE atomically and keeps FILE.bak. "
        "Stop with Ctrl-C.",
        _edit_arguments,
        _edit,
    ),
    _Command(
        "synthesize",
        "find a linkage (four-, six- or eight-bar) whose tracer point P passes near target points, a body "
        "through poses, or an output angle as a function of the input",
        "Dimensional synthesis: read target points (CSV with the header x,y or x,y,input, or an SVG "
        "path) and write a mechanism file whose tracer point P passes near every target, its driver the link "
        "'crank'. With an input column (the crank angle at each target, degrees) the tracer must be at each "
        "target at its own angle, up to one common offset. The crank turns fully (with --partial it may rock "
        "through part of a turn) and every transmission angle stays within [MIN, 180 - MIN]. A four-bar search "
        "starts from the atlas's nearest four-bars; differential evolution and CMA-ES in turn over whole "
        "generations, each search then polished by least squares; the same --seed gives the same result "
        "(unless --seconds stops the run). --task motion and --task function are described with their options.",
        _synthesize_arguments,
        _synthesize,
    ),
    _Command(
        "atlas",
        "build the atlas of four-bar curves that synthesis starts from, or say what is cached",
        "The atlas: about a million four-bars, each with the normalised descriptor of its tracer's curve, "
        "that path synthesis with the built-in four-bar looks up first. It is built on first use (or by "
        "'atlas build', on every core) into the user's cache directory (LINKAGEKIT_CACHE_DIR overrides it), "
        "once per release; an interrupted build resumes.",
        _atlas_arguments,
        _atlas,
    ),
)


# ---------------------------------------------------------------------- entry point
def _run(argv: list[str]) -> int:
    parser = build_parser()
    if not argv:
        parser.print_help()
        return 0
    try:
        args = parser.parse_args(_attach_negative_values(argv))
    except _ParserExit as done:
        return done.status
    if getattr(args, "run", None) is None:  # options but no command, e.g. `linkagekit -h` is handled above
        *others, last = (c.name for c in _COMMANDS)
        raise InputError(f"give a command: {', '.join(others)} or {last} (see '{PROG} --help')")
    _output_not_input(args)
    code: int = args.run(args)
    return code


def _output_not_input(args: argparse.Namespace) -> None:
    """Refuse an empty input path, a file written (``-o``, ``--plot``, ``--checkpoint``) that is the command's input
    file (the same file by any name: the output replaced it), and two written files that are one (each overwrote
    the other)."""
    written = _files_written(args)
    for source in (getattr(args, "file", None), getattr(args, "targets", None)):
        if source == "":  # Path("") is the current directory: ". is a directory" named no empty path
            raise InputError("the file path is empty: give the file to read")
        if not isinstance(source, str) or not source:
            continue
        for flag, path in written:
            if _same_file(source, path):
                raise InputError(
                    f"{flag} {shorten_path(path, 80)}: is the input file {shorten_path(source, 80)}; give another"
                )
    for i, (flag, path) in enumerate(written):
        for earlier, other in written[:i]:
            if _same_file(path, other):
                raise InputError(f"{flag} {shorten_path(path, 80)}: is also {earlier}'s file; give each its own")


def _files_written(args: argparse.Namespace) -> list[tuple[str, str]]:
    """The files a command writes: (option, path)."""
    flags = (("output", "-o"), ("plot", "--plot"), ("checkpoint", "--checkpoint"))
    return [(flag, v) for key, flag in flags if isinstance(v := getattr(args, key, None), str) and v]


def _same_file(a: str, b: str) -> bool:
    """Whether paths ``a`` and ``b`` name one file (by any name: links, hard links), or would."""
    import os

    try:
        if os.path.exists(a) and os.path.exists(b) and os.path.samefile(a, b):
            return True
    except OSError:  # unreadable: compare the names
        pass
    return os.path.realpath(a) == os.path.realpath(b)


def main(argv: list[str] | None = None) -> int:
    """Run the command line on *argv* (default: ``sys.argv[1:]``) and return its exit status.

    0 on success, 2 on a bad file or bad arguments, 1 on anything else; a failure prints one
    line on stderr.  Called without *argv* (as the ``linkagekit`` script), it exits with
    that status.
    """
    import warnings

    args = sys.argv[1:] if argv is None else list(argv)
    if argv is None:
        _terminate_as_interrupt()
    try:
        with warnings.catch_warnings():
            # a value that overflows is NaN/null in the output, not a warning on stderr; nor is
            # matplotlib's note that a font lacks a glyph of a name (the picture shows a box)
            warnings.simplefilter("ignore", RuntimeWarning)
            warnings.filterwarnings("ignore", message="Glyph .* missing from", category=UserWarning)
            with _checked_stdout():
                code = _run(args)
                sys.stdout.flush()  # an output that cannot be written fails here, not silently at the exit
    except _OutputFailed as exc:  # `> /dev/full`, a full disk: as `-o` says it (_emit), not 'internal error'
        print(f"{PROG}: error: standard output: cannot write: {exc}", file=sys.stderr)
        code = InputError.exit_code
        if argv is None:
            _silence_stdout()
    except LinkageError as exc:
        prefix = f"{PROG}: error: "
        print(prefix + (one_line(str(exc), MAX_MESSAGE - len(prefix)) or type(exc).__name__), file=sys.stderr)
        code = exc.exit_code
    except KeyboardInterrupt as exc:
        print(f"{PROG}: {_stop_word(exc)}", file=sys.stderr)
        code = 1  # the command line's exit statuses: 0 success, 2 bad input, 1 anything else (not 128 + SIGINT)
    except BrokenPipeError:  # `linkagekit analyze ... | head`: the reader has gone; nothing to say
        code = 1
        if argv is None:  # the script: no second error when Python flushes stdout at exit
            _silence_stdout()
    except Exception as exc:  # noqa: BLE001 - the promise is: never a traceback
        prefix = f"{PROG}: internal error: {type(exc).__name__}: "
        print(prefix + one_line(str(exc), max(MAX_MESSAGE - len(prefix), 40)), file=sys.stderr)
        code = 1
    if argv is None:
        _exit(code)
    return code


class Terminated(KeyboardInterrupt):
    """SIGTERM (``kill PID``, ``timeout``, a batch system's end of a job) in the ``linkagekit`` script: handled as
    Ctrl-C is, so that a search saves its checkpoint with the time it used, the editor stops, and a file being
    written is left as it was with no temporary file beside it (Python's default ends the process on the spot)."""


def _stop_word(exc: KeyboardInterrupt) -> str:
    """What stopped the command: 'terminated' (SIGTERM, :class:`Terminated`) or 'interrupted' (Ctrl-C)."""
    return "terminated" if isinstance(exc, Terminated) else "interrupted"


def _terminate_as_interrupt() -> None:
    """SIGTERM raises :class:`Terminated` in the main thread (where the script runs; elsewhere nothing changes)."""
    import signal
    import threading

    def handler(signum: int, frame: object) -> None:
        raise Terminated

    # (a SIGTERM ignored by whoever started the script stays ignored, as Python leaves an ignored SIGINT)
    if threading.current_thread() is threading.main_thread() and signal.getsignal(signal.SIGTERM) == signal.SIG_DFL:
        signal.signal(signal.SIGTERM, handler)


class _OutputFailed(Exception):
    """Standard output could not take what a command wrote (its ``str`` is the system's reason)."""


class _CheckedStdout:
    """``sys.stdout`` while a command runs: a write or flush that fails (a full disk, ``> /dev/full``) raises
    :class:`_OutputFailed`, so that the failure is told from any other ``OSError``; everything else is the stream's.
    A reader gone (``BrokenPipeError``) stays what it is."""

    def __init__(self, stream: Any) -> None:
        self._stream = stream

    def write(self, text: str) -> int:
        try:
            return int(self._stream.write(text))
        except BrokenPipeError:
            raise
        except OSError as exc:
            raise _OutputFailed(exc.strerror or exc) from exc

    def flush(self) -> None:
        try:
            self._stream.flush()
        except BrokenPipeError:
            raise
        except OSError as exc:
            raise _OutputFailed(exc.strerror or exc) from exc

    def __getattr__(self, name: str) -> Any:
        return getattr(self._stream, name)


@contextlib.contextmanager
def _checked_stdout() -> Iterator[None]:
    """Run the block with :class:`_CheckedStdout` as ``sys.stdout``, restored after."""
    stream = sys.stdout
    sys.stdout = _CheckedStdout(stream)
    try:
        yield
    finally:
        if isinstance(sys.stdout, _CheckedStdout):
            sys.stdout = stream


def _silence_stdout() -> None:
    """Point the script's standard output at the null device, so that Python's own flush at exit, which would fail
    the same way, says nothing more (what was not written is lost either way)."""
    try:
        import os

        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):
        pass


def _exit(code: int) -> None:
    """The script's exit with ``code``: at once when a thread it started still runs (the manager thread of a worker
    pool killed on Ctrl-C can wait for ever on a worker that is gone: the line 'interrupted' was printed, then the
    interpreter's exit, which joins every thread, hung), else the interpreter's own. SIGTERM ends the process as
    the system's default does again (no :class:`Terminated` past the command's handling)."""
    import signal
    import threading

    with contextlib.suppress(ValueError):  # (not the main thread)
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
    lingering = [t for t in threading.enumerate() if t is not threading.main_thread() and not t.daemon]
    if lingering:
        import os

        for stream in (sys.stdout, sys.stderr):
            with contextlib.suppress(OSError, ValueError):
                stream.flush()
        os._exit(code)
    sys.exit(code)


if __name__ == "__main__":  # pragma: no cover
    main()
