"""Target points for dimensional synthesis, read from a CSV file or an SVG path.

``linkagekit synthesize TARGET ...`` reads its targets with :func:`read_targets`:

CSV (any file name not ending in ``.svg``)
    A header line ``x,y`` (path synthesis) or ``x,y,input`` (prescribed timing: the driver's
    angle at each target, in degrees), then one point a line.  Column names are
    case-insensitive, may have spaces around them and may come in any order.  Blank lines and
    lines starting with ``#`` are skipped everywhere; the header is the first other line.
    Every value is a finite number.
SVG (``.svg``)
    The first ``<path>`` element (in any namespace) that has a ``d`` attribute, sampled at
    ``points`` points equally spaced in arc length.  The path's numbers are read as lengths in
    ``units`` (``width``, ``height`` and ``viewBox`` are ignored); SVG's y axis points down, so
    y is negated and the picture is not mirrored.  A ``transform`` on the path or on any of
    its ancestors is refused (flatten the path in the editor first), and so is a path of
    several subpaths (several ``M`` commands that each draw something): only one curve can be
    a target.  A file with a DOCTYPE or an ENTITY declaration is refused: reading never expands
    entities.

The targets describe a closed curve when the last point repeats the first (the repeated point
is dropped; with timing, the inputs must also agree modulo 360 degrees), or for an SVG path
when it ends with ``Z``/``z`` or where it started.  A hand-drawn CSV file (more than 40
points, no timing) is closed too when it goes round a loop without repeating its first point:
the gap from its last point to its first is at most 1.5 times its longest step between
consecutive points and at most a tenth of the diagonal (:data:`LOOP_GAP`).

Synthesis works at sizes from :data:`MIN_DIAGONAL` to :data:`MAX_DIAGONAL` (the bounding-box
diagonal, in the file's unit); :func:`read_targets` refuses other sizes (:func:`check_scale`).

Every problem raises :class:`~linkagekit.errors.InputError` with one line that starts with
the file name and names the line or the element at fault.

Examples
--------
>>> t = targets_from_array([[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 0.0]], unit="mm")
>>> len(t), t.closed, t.unit, round(t.diagonal, 4)
(3, True, 'mm', 2.2361)
>>> t.xy.flags.writeable
False
"""

from __future__ import annotations

import csv
import math
import operator
import os
import re
import xml.etree.ElementTree as ET
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError, one_line, shorten
from ..files import read_regular_file
from ..units import LENGTH_UNITS

#: the largest target file read, in bytes
MAX_FILE_BYTES = 10 * 1024 * 1024
#: the most target points a file (or an SVG sampling) may have
MAX_POINTS = 100_000
#: the fewest target points a synthesis needs
MIN_POINTS = 3
#: the most segments an SVG path may have
MAX_SEGMENTS = 100_000
#: two points closer than this fraction of the bounding-box diagonal are the same point
CLOSE_TOL = 1e-9
#: two inputs (degrees) closer than this modulo 360 are the same input
INPUT_TOL = 360.0 * 1e-9

_HEADERS = ("x,y", "x,y,input")
_NAME_LIMIT = 150  # the longest file name quoted in a message


def _error(source: str, message: str) -> InputError:
    """An :class:`InputError` of one line, starting with the (shortened) source name."""
    return InputError(one_line(f"{shorten(source, _NAME_LIMIT)}: {message}"))


def plural(n: int, word: str, many: str = "") -> str:
    """``n`` and ``word``, or its plural ``many`` (default: with an ``s``) unless ``n`` is 1.

    >>> plural(1, "value"), plural(3, "value"), plural(1, "search", "searches"), plural(2, "search", "searches")
    ('1 value', '3 values', '1 search', '2 searches')
    """
    return f"{n} {word}" if n == 1 else f"{n} {many or word + 's'}"


@dataclass(frozen=True)
class Targets:
    """Target points of a synthesis problem.

    Build one with :func:`targets_from_array` or :func:`read_targets`; the constructor checks
    the arrays (shapes, finite values, at least 3 points with some extent) and stores
    read-only copies, but applies no closing rule.

    Attributes
    ----------
    xy : ndarray, shape (m, 2), float
        The points, in the length unit ``unit``; read-only.
    inputs : ndarray, shape (m,), float, or None
        The driver's angle at each target in degrees (prescribed timing), else None; read-only.
    unit : str
        The length unit, one of :data:`linkagekit.units.LENGTH_UNITS`.
    closed : bool
        The targets describe a closed curve (the last point is not a copy of the first).
    source : str
        The file name, for messages (``"<memory>"`` for arrays).
    smoothed : str
        Empty, or the line that says how hand-drawn targets were smoothed (:func:`smooth`).

    Examples
    --------
    >>> t = Targets(xy=[[0, 0], [1, 0], [0, 1]], inputs=None, unit="m", closed=False, source="<memory>")
    >>> t
    Targets(3 points, unit='m', closed=False, timed=False, source='<memory>')
    >>> t.diagonal == 2**0.5
    True
    """

    xy: np.ndarray
    inputs: np.ndarray | None
    unit: str
    closed: bool
    source: str
    smoothed: str = ""

    def __post_init__(self) -> None:
        source = str(self.source)
        object.__setattr__(self, "source", source)
        if not isinstance(self.unit, str) or self.unit not in LENGTH_UNITS:
            raise _error(source, f"unknown length unit {_quote(self.unit)} (one of {', '.join(LENGTH_UNITS)})")
        if not isinstance(self.closed, bool | np.bool_):
            raise _error(source, f"closed must be True or False, got {type(self.closed).__name__}")
        object.__setattr__(self, "closed", bool(self.closed))
        xy = _float_array(self.xy, source, "the target points")
        if xy.ndim != 2 or xy.shape[1] != 2:
            raise _error(source, f"the target points must have shape (m, 2), got {xy.shape}")
        _check_finite(xy, source, ("x", "y"))
        m = len(xy)
        if m > MAX_POINTS:
            raise _error(source, f"{m} target points; at most {MAX_POINTS} are allowed")
        if m < MIN_POINTS:
            raise _error(source, f"{plural(m, 'target point')}; at least {MIN_POINTS} are needed")
        diagonal = _diagonal(xy)
        if not math.isfinite(diagonal):
            raise _error(source, "the target points spread too far: their extent is not a finite number")
        if diagonal == 0.0:
            raise _error(
                source, f"every target point is ({_num(xy[0, 0])}, {_num(xy[0, 1])}): the targets have no extent"
            )
        xy.setflags(write=False)
        object.__setattr__(self, "xy", xy)
        if self.inputs is not None:
            inputs = _float_array(self.inputs, source, "the inputs")
            if inputs.shape != (m,):
                raise _error(source, f"the inputs must have shape ({m},) like the points, got {inputs.shape}")
            _check_finite(inputs[:, None], source, ("input",))
            _check_timing(xy, inputs, source)
            inputs.setflags(write=False)
            object.__setattr__(self, "inputs", inputs)

    @property
    def diagonal(self) -> float:
        """The diagonal of the points' bounding box, in ``unit``.

        Examples
        --------
        >>> targets_from_array([[0, 0], [3, 0], [3, 4]]).diagonal
        5.0
        """
        return _diagonal(self.xy)

    @property
    def timed(self) -> bool:
        """The targets prescribe the driver's input at each point (``inputs`` is not None)."""
        return self.inputs is not None

    def __len__(self) -> int:
        return int(self.xy.shape[0])

    def __repr__(self) -> str:
        return (
            f"Targets({len(self)} points, unit={self.unit!r}, closed={self.closed}, "
            f"timed={self.timed}, source={self.source!r})"
        )

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Targets):
            return NotImplemented
        same_inputs = (self.inputs is None and other.inputs is None) or (
            self.inputs is not None and other.inputs is not None and np.array_equal(self.inputs, other.inputs)
        )
        return (
            np.array_equal(self.xy, other.xy)
            and same_inputs
            and (self.unit, self.closed, self.source) == (other.unit, other.closed, other.source)
        )

    def __hash__(self) -> int:
        inputs = None if self.inputs is None else self.inputs.tobytes()
        return hash((self.xy.tobytes(), inputs, self.unit, self.closed, self.source))


# ---------------------------------------------------------------------- helpers
def _quote(value: Any) -> str:
    return f"'{shorten(str(value))}'"


def _num(value: float) -> str:
    return f"{float(value):.6g}"


def _float_array(values: Any, source: str, what: str) -> np.ndarray:
    """A float copy of ``values``, or one clear error."""
    try:
        arr = np.array(values, dtype=float)
    except (TypeError, ValueError, OverflowError) as exc:
        raise _error(source, f"{what} are not numbers ({shorten(str(exc))})") from None
    return arr


def _check_finite(arr: np.ndarray, source: str, names: Sequence[str]) -> None:
    """Raise naming the first non-finite value (``point k: x is not finite (nan)``), if any."""
    bad = np.argwhere(~np.isfinite(arr))
    if len(bad):
        i, j = (int(v) for v in bad[0])
        raise _error(source, f"point {i + 1}: {names[j]} is not finite ({arr[i, j]})")


def _diagonal(xy: np.ndarray) -> float:
    """The bounding-box diagonal, in Python floats (an overflow gives inf, never a warning)."""
    if len(xy) == 0:
        return 0.0
    width = float(xy[:, 0].max()) - float(xy[:, 0].min())
    height = float(xy[:, 1].max()) - float(xy[:, 1].min())
    return math.hypot(width, height)


#: the largest magnitude of a target's input angle, degrees (a thousand turns; 1e300 made every other input print 0)
MAX_INPUT = 360_000.0


def _check_timing(xy: np.ndarray, inputs: np.ndarray, source: str) -> None:
    """Refuse inputs beyond :data:`MAX_INPUT`, and two targets at different places with one input (modulo 360
    degrees): the tracer is at one place at one input, so no mechanism meets them (all at one input were taken)."""
    big = np.flatnonzero(np.abs(inputs) > MAX_INPUT)
    if len(big):
        raise _error(source, f"target {big[0] + 1}: an input of {_num(inputs[big[0]])} deg (at most {MAX_INPUT:g})")
    turn = np.mod(inputs, 360.0)
    order = np.argsort(turn, kind="stable")
    gaps = np.diff(np.append(turn[order], turn[order[0]] + 360.0))
    apart = np.hypot(*(xy[np.roll(order, -1)] - xy[order]).T) > CLOSE_TOL * _diagonal(xy)
    clash = np.flatnonzero((gaps <= INPUT_TOL) & apart)
    if len(clash):
        a, b = sorted((int(order[clash[0]]) + 1, int(np.roll(order, -1)[clash[0]]) + 1))
        raise _error(
            source, f"targets {a} and {b} are at different places with one input ({_num(inputs[a - 1])} deg): "
            "the tracer is at one place at one input"
        )  # fmt: skip


def _repeats_first(xy: np.ndarray, inputs: np.ndarray | None) -> bool:
    """The last point is the first again: within ``CLOSE_TOL`` of the diagonal, inputs equal modulo 360."""
    if len(xy) < 2:
        return False
    gap = math.hypot(float(xy[-1, 0]) - float(xy[0, 0]), float(xy[-1, 1]) - float(xy[0, 1]))
    if not gap <= CLOSE_TOL * _diagonal(xy):
        return False
    if inputs is None:
        return True
    turn = (float(inputs[-1]) - float(inputs[0])) % 360.0
    return min(turn, 360.0 - turn) <= INPUT_TOL


def _check_units(units: Any, source: str) -> str:
    if not isinstance(units, str) or units not in LENGTH_UNITS:
        raise _error(source, f"unknown length unit {_quote(units)} (one of {', '.join(LENGTH_UNITS)})")
    return units


# ---------------------------------------------------------------------- arrays
def targets_from_array(
    xy: Any,
    inputs: Any = None,
    unit: str = "m",
    closed: bool | None = None,
    source: str = "<memory>",
) -> Targets:
    """Targets from arrays, with the closing rule of the target files.

    Parameters
    ----------
    xy : array_like, shape (m, 2)
        The points, in ``unit``.
    inputs : array_like, shape (m,), optional
        The driver's angle at each point, in degrees (prescribed timing).
    unit : str, default "m"
        The length unit, one of :data:`linkagekit.units.LENGTH_UNITS`.
    closed : bool, optional
        None: closed when the last point repeats the first (within ``1e-9`` of the bounding-box
        diagonal, and with inputs equal modulo 360 degrees); the repeated point is dropped.
        True: closed (a repeated last point is dropped all the same).  False: open, every point kept.
    source : str, default "<memory>"
        The name that starts every error message.

    Returns
    -------
    Targets

    Raises
    ------
    InputError
        Not an (m, 2) array of finite numbers, fewer than 3 or more than 100000 points, every
        point the same, inputs of another length, an unknown unit.

    Examples
    --------
    >>> t = targets_from_array([[0, 0], [1, 0], [1, 1], [0, 0]], inputs=[0, 90, 180, 360])
    >>> len(t), t.closed, t.inputs.tolist()
    (3, True, [0.0, 90.0, 180.0])
    >>> targets_from_array([[0, 0], [1, 0], [1, 1], [0, 0]], inputs=[0, 90, 180, 270]).closed
    False
    """
    source = str(source)
    _check_units(unit, source)
    if closed is not None and not isinstance(closed, bool | np.bool_):
        raise _error(source, f"closed must be True, False or None, got {type(closed).__name__}")
    # the constructor checks shapes, values, counts and extent before the closing rule looks at them
    checked = Targets(xy=xy, inputs=inputs, unit=unit, closed=bool(closed), source=source)
    pts, ins = checked.xy, checked.inputs
    check_scale(pts, source, unit)  # before the closing rule: beside 1e300, (2, 0) was a repeat of (0, 0)
    if (closed is not None and not closed) or not _repeats_first(pts, ins):
        return checked  # forced open, or nothing to drop (closed only when forced)
    m = len(pts) - 1
    if m < MIN_POINTS:
        raise _error(
            source,
            f"{plural(m, 'target point')} once the last, a repeat of the first, is dropped; "
            f"at least {MIN_POINTS} are needed",
        )
    return Targets(xy=pts[:-1], inputs=None if ins is None else ins[:-1], unit=unit, closed=True, source=source)


# ---------------------------------------------------------------------- files
def read_targets(path: str | os.PathLike[str], units: str = "m", points: int = 40, smooth: bool = True) -> Targets:
    """Read target points from a CSV file, or from the first path of an SVG file.

    Parameters
    ----------
    path : str or PathLike
        The file: SVG when its name ends in ``.svg`` (any case), CSV otherwise.
    units : str, default "m"
        The length unit of the file's numbers, one of :data:`linkagekit.units.LENGTH_UNITS`;
        the targets keep it (nothing is converted).
    points : int, default 40
        How many points to sample along an SVG path (3 to 100000); unused for CSV.
    smooth : bool, default True
        Smooth hand-drawn targets (more than 40 CSV points, an SVG path of more than 40
        segments) with :func:`smooth`; False takes every point as it is.

    Returns
    -------
    Targets
        ``source`` is ``str(path)``.  For SVG, ``inputs`` is None and ``closed`` tells whether
        the path is closed (then its start is not repeated at the end).

    Raises
    ------
    InputError
        One line that starts with the file name: a missing, empty, binary or too large file
        (more than 10 MiB, more than 100000 points), a bad header or value (naming the line),
        a bad SVG (naming what is wrong), an unknown unit.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     f = pathlib.Path(tmp) / "targets.csv"
    ...     _ = f.write_text("# a triangle, closed\\nx,y,input\\n0,0,0\\n10,0,120\\n0,10,240\\n0,0,360\\n")
    ...     t = read_targets(f, units="mm")
    >>> len(t), t.closed, t.unit, t.inputs.tolist()
    (3, True, 'mm', [0.0, 120.0, 240.0])
    """
    if not isinstance(path, str | os.PathLike):
        raise InputError(f"read_targets: expected a file path, got {type(path).__name__}")
    try:
        name = os.fsdecode(path)
    except (TypeError, ValueError, UnicodeError) as exc:
        raise InputError(one_line(f"read_targets: not a usable path: {shorten(str(exc))}")) from None
    if "\x00" in name:
        raise InputError(one_line(f"read_targets: a file path with a NUL byte: {shorten(repr(name))}"))
    _check_units(units, name)
    count = _check_points(points, name)
    text = _read_text(Path(name), name)
    if name.lower().endswith(".svg"):
        return _svg_targets(text, name, units, count, smooth)
    return _drawing(_csv_targets(text, name, units), smooth)


def _drawing(targets: Targets, smooth: bool) -> Targets:
    """CSV targets as they are (a few, or timed), or a hand-drawn curve: closed if it loops, smoothed (``smooth``)
    and, beyond :data:`SMOOTHED_POINTS`, taken at that many of its points, evenly by index."""
    check_scale(targets.xy, targets.source, targets.unit)
    if len(targets) <= DENSE_POINTS or targets.timed:
        return targets
    if not targets.closed and _loops(targets.xy):
        targets = Targets(targets.xy, None, targets.unit, True, targets.source)
    if not smooth:
        return targets
    return _smoothed(targets, targets.xy, SMOOTHED_POINTS if len(targets) > SMOOTHED_POINTS else None)


#: the smallest and the largest bounding-box diagonal of targets that synthesis takes, in their unit
#: (far below it, at 1e-12, the solvers' fixed tolerances fail; mechanism files hold no number above 1e12)
MIN_DIAGONAL, MAX_DIAGONAL = 1e-6, 1e6
#: the largest magnitude of a target coordinate, in the targets' unit, and in target diagonals
MAX_COORDINATE, MAX_OFFSET = 1e9, 1e6


def check_scale(xy: np.ndarray, source: str, unit: str) -> None:
    """Refuse targets (m, 2) of a size synthesis does not work at, with one line that starts with ``source``.

    The bounding-box diagonal must be from :data:`MIN_DIAGONAL` to :data:`MAX_DIAGONAL` and
    every coordinate at most :data:`MAX_COORDINATE`, and at most :data:`MAX_OFFSET` diagonals,
    in magnitude: the numbers of a file given in another unit (micrometres, kilometres) fit.

    >>> check_scale(np.array([[0.0, 0.0], [1e-3, 0.0], [0.0, 1e-3]]), "a.csv", "m")
    >>> check_scale(np.array([[0.0, 0.0], [1e-9, 0.0], [0.0, 1e-9]]), "b.csv", "m")
    Traceback (most recent call last):
    ...
    linkagekit.errors.InputError: b.csv: the targets' diagonal is 1.41e-09 m; synthesis takes 1e-06 to 1e+06 ...
    """
    diagonal = _diagonal(xy)
    size = float(np.max(np.abs(xy))) if len(xy) else 0.0
    if not MIN_DIAGONAL <= diagonal <= MAX_DIAGONAL:
        raise _error(
            source,
            f"the targets' diagonal is {diagonal:.3g} {unit}; synthesis takes {MIN_DIAGONAL:g} to {MAX_DIAGONAL:g} "
            "(scale the numbers, e.g. give them in another unit)",
        )
    if size > MAX_COORDINATE or size > MAX_OFFSET * diagonal:
        raise _error(
            source,
            f"a target coordinate of magnitude {size:.12g} {unit}; synthesis takes at most {MAX_COORDINATE:g} and "
            f"{MAX_OFFSET:g} target diagonals (move the targets nearer the origin)",
        )


#: a dense list of points is a closed loop when the gap from its last point to its first is at most this
#: many times its longest step between consecutive points (and at most a tenth of the diagonal)
LOOP_GAP = 1.5


def _loops(xy: np.ndarray) -> bool:
    """The points, listed without repeating the first at the end, go round a closed loop (:data:`LOOP_GAP`).

    >>> t = np.linspace(0, 2 * np.pi, 60, endpoint=False)
    >>> _loops(np.c_[np.cos(t), np.sin(t)]), _loops(np.c_[np.cos(t[:-3]), np.sin(t[:-3])])
    (True, False)
    """
    pts = (xy - xy.min(axis=0)) / _diagonal(xy)  # scaled first: no overflow for any finite numbers
    gap = float(np.hypot(*(pts[-1] - pts[0])))
    longest = float(np.max(np.hypot(*np.diff(pts, axis=0).T)))
    return gap <= LOOP_GAP * longest and gap <= 0.1


#: more target points than this in a CSV file, or segments in an SVG path, are hand-drawn: they are smoothed
#: (12 to 40 points is what a designer lists by hand; a digitised sketch or a pen's path has hundreds)
DENSE_POINTS = 40
#: harmonics kept by :func:`smooth` (a curve of the LINK-ABC letters' detail needs about 10 to 16)
SMOOTH_HARMONICS = 16
#: points an SVG path of many segments is sampled at before it is smoothed and its ``points`` taken
SMOOTH_SAMPLES = 512
#: a smoothed CSV drawing of more points is taken at this many, evenly by index: its 16 harmonics need far fewer,
#: and every evaluation of a search costs in proportion (2000 points made a 10 s run take 22 s, 10^5 points 1.5 GB)
SMOOTHED_POINTS = 400
#: the most points of a hand-drawn CSV file that ``synthesize --no-smooth`` takes as they are: the atlas's placement,
#: the dense checks and every evaluation cost in proportion before the clock is read (10000 points ran 25 s of a
#: 3 s budget, 100000 over 150 s and 3 GB)
MAX_UNSMOOTHED = 2000


def smooth(xy: np.ndarray, closed: bool, harmonics: int = SMOOTH_HARMONICS) -> np.ndarray:
    """Hand-drawn points (m, 2) with their wiggles removed: a low-pass Fourier filter along the point sequence.

    A closed curve is periodic: of its discrete Fourier series the harmonics ``|k| <= harmonics``
    are kept. An open one has its chord (the straight line from its first point to its last,
    linear in the index) taken off, so that both ends are 0, and is extended by its odd mirror
    image (``d_0 .. d_{m-1}, -d_{m-2} .. -d_1``): a periodic sequence whose value and slope
    are continuous, so cutting it off leaves no ringing at the ends; of its twice as long
    period the harmonics ``|k| <= 2 harmonics`` are kept, and the chord is added back. The
    ends of an open curve stay where they were.

    >>> t = np.linspace(0, 2 * np.pi, 200, endpoint=False)
    >>> circle = np.c_[np.cos(t), np.sin(t)]
    >>> float(np.max(np.abs(smooth(circle, closed=True) - circle))) < 1e-12
    True

    The points are centred and scaled to the unit square first, so any finite numbers work:

    >>> float(np.max(np.abs(smooth(1e307 * circle, closed=False) / 1e307 - circle))) < 0.02
    True
    """
    lo, hi = xy.min(axis=0), xy.max(axis=0)
    centre = lo / 2 + hi / 2  # halves first: no overflow for any finite numbers
    size = float(np.max(hi / 2 - lo / 2)) or 1.0
    z = ((xy[:, 0] - centre[0]) + 1j * (xy[:, 1] - centre[1])) / size  # within the unit square: no overflow
    m = len(z)
    if closed:
        ext, keep, chord = z, harmonics, np.zeros(m)
    else:
        chord = z[0] + (z[-1] - z[0]) * np.arange(m) / (m - 1)
        d = z - chord
        ext, keep = np.concatenate([d, -d[-2:0:-1]]), 2 * harmonics
    F = np.fft.fft(ext)
    F[np.abs(np.fft.fftfreq(len(ext), 1.0 / len(ext))) > keep] = 0.0
    out = np.fft.ifft(F)[:m] + chord
    smoothed: np.ndarray = np.column_stack([out.real, out.imag]) * size + centre
    return smoothed


def _smoothed(targets: Targets, dense: np.ndarray, count: int | None = None) -> Targets:
    """``targets`` replaced by the smoothed ``dense`` points (``count`` of them taken evenly), with the note."""
    xy = smooth(dense, targets.closed)
    moved = float(np.max(np.hypot(*(xy - dense).T)))
    if count is not None:
        idx = np.linspace(0, len(xy), count, endpoint=False) if targets.closed else np.linspace(0, len(xy) - 1, count)
        xy = xy[np.round(idx).astype(int)]
    taken = f"; {count} of them taken, evenly by index" if count is not None and count < len(dense) else ""
    note = (
        f"{targets.source}: hand-drawn (more than {DENSE_POINTS} points): smoothed as "
        f"{'a closed' if targets.closed else 'an open'} curve, Fourier harmonics above "
        f"{SMOOTH_HARMONICS} removed (points moved by at most {moved:.3g} {targets.unit}){taken}"
    )
    return Targets(xy, targets.inputs, targets.unit, targets.closed, targets.source, note)


def _check_points(points: Any, source: str) -> int:
    try:
        if isinstance(points, bool):
            raise TypeError
        count = operator.index(points)
    except TypeError:
        raise _error(source, f"points must be an integer, got {_quote(points)}") from None
    if not MIN_POINTS <= count <= MAX_POINTS:
        raise _error(source, f"points must be from {MIN_POINTS} to {MAX_POINTS}, got {count}")
    return count


def _read_text(p: Path, name: str) -> str:
    """The file's text (UTF-8, a byte-order mark dropped), or one clear error.

    Read as a mechanism file is (:func:`linkagekit.files.read_regular_file`): a regular file
    only (a FIFO, a device such as ``/dev/zero`` or a directory is refused before anything is
    read), at most :data:`MAX_FILE_BYTES` bytes.
    """
    data = read_regular_file(p, MAX_FILE_BYTES, "target file", lambda message: _error(name, message))
    if len(data) > MAX_FILE_BYTES:
        raise _error(name, f"more than {MAX_FILE_BYTES} bytes (10 MiB), more than a target file may have")
    if not data.strip():
        raise _error(name, "empty file")
    nul = data.find(b"\x00")
    if nul >= 0:
        raise _error(name, f"a binary file, not text (a NUL byte at byte {nul})")
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise _error(name, f"not UTF-8 text (byte {exc.start})") from None


# ---------------------------------------------------------------------- CSV
def _csv_cells(text: str, name: str) -> Iterator[tuple[int, list[str]]]:
    """The line number and stripped cells of every CSV row of ``text`` (blank lines and ``#`` comments skipped)."""
    for number, line in enumerate(text.replace("\r\n", "\n").replace("\r", "\n").split("\n"), start=1):
        stripped = line.strip()
        if not stripped or stripped.startswith("#"):
            continue
        try:
            yield number, [c.strip() for c in next(csv.reader([line], strict=True))]
        except (csv.Error, StopIteration) as exc:
            raise _error(name, f"line {number}: not a CSV row ({shorten(str(exc))})") from None


def _csv_targets(text: str, name: str, units: str) -> Targets:
    columns: list[str] | None = None
    rows: list[list[float]] = []
    for number, cells in _csv_cells(text, name):
        if columns is None:
            columns = _header(cells, name)
            continue
        if len(cells) != len(columns):
            raise _error(
                name,
                f"line {number}: {plural(len(cells), 'value')}, expected {len(columns)} ({','.join(columns)})",
            )
        if len(rows) == MAX_POINTS:
            raise _error(name, f"line {number}: more than {MAX_POINTS} target points")
        rows.append([_value(cell, column, number, name) for cell, column in zip(cells, columns, strict=True)])
    if columns is None:
        raise _error(name, "no header line 'x,y' or 'x,y,input' (only comments and blank lines)")
    if not rows:
        raise _error(name, f"no target points after the header; at least {MIN_POINTS} are needed")
    table = np.array(rows, dtype=float).reshape(len(rows), len(columns))
    xy = table[:, [columns.index("x"), columns.index("y")]]
    inputs = table[:, columns.index("input")] if "input" in columns else None
    return targets_from_array(xy, inputs=inputs, unit=units, closed=None, source=name)


def read_table(
    path: str | os.PathLike[str], headers: Sequence[Sequence[str]], what: str = "row"
) -> tuple[list[str], np.ndarray]:
    """The columns and the numbers (rows, columns) of a CSV file whose header is one of ``headers``.

    Read as target files are (comments, blank lines, size limits, one-line errors naming the
    file and the line); used by motion (``x,y,angle[,input]``) and function generation
    (``input,output``). The header's names are case-insensitive, in any order.
    """
    name = str(path)
    text = _read_text(Path(path), name)
    allowed = {tuple(sorted(h)) for h in headers}
    expected = " or ".join(repr(",".join(h)) for h in headers)
    columns: list[str] | None = None
    rows: list[list[float]] = []
    for number, cells in _csv_cells(text, name):
        if columns is None:
            columns = [c.lower() for c in cells]
            if tuple(sorted(columns)) not in allowed:
                raise _error(name, f"expected the header {expected}, got {_quote(','.join(cells))}")
            continue
        if len(cells) != len(columns):
            raise _error(name, f"line {number}: {plural(len(cells), 'value')}, expected {len(columns)}")
        if len(rows) == MAX_POINTS:
            raise _error(name, f"line {number}: more than {MAX_POINTS} {what}s")
        rows.append([_value(cell, column, number, name) for cell, column in zip(cells, columns, strict=True)])
    if columns is None:
        raise _error(name, f"no header line {expected} (only comments and blank lines)")
    return columns, np.array(rows, dtype=float).reshape(len(rows), len(columns))


def _header(cells: list[str], name: str) -> list[str]:
    columns = [c.lower() for c in cells]
    if sorted(columns) not in (["x", "y"], ["input", "x", "y"]):
        raise _error(name, f"expected the header 'x,y' or 'x,y,input', got {_quote(','.join(cells))}")
    return columns


def _value(cell: str, column: str, number: int, name: str) -> float:
    if not cell:
        raise _error(name, f"line {number}: {column} is empty")
    text = cell.strip()  # plain ASCII numbers, as a mechanism file's: Python's float() also takes 1_0 and fullwidth
    if not (_NUMBER.fullmatch(text) or text.lower().lstrip("+-") in ("inf", "infinity", "nan")):
        raise _error(name, f"line {number}: {_quote(cell)} is not a number")
    value = float(text)
    if not math.isfinite(value):
        raise _error(name, f"line {number}: {column} is not finite ({shorten(cell)})")
    return value


# ---------------------------------------------------------------------- SVG
_DECLARATION = re.compile(r"<!\s*(DOCTYPE|ENTITY)", re.IGNORECASE)
_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?", re.ASCII)  # ASCII digits only
_MOST_ARGUMENTS = 7  # an arc command's numbers: no command takes more


def _local(tag: Any) -> str:
    return tag.rsplit("}", 1)[-1] if isinstance(tag, str) else ""


def _svg_targets(text: str, name: str, units: str, count: int, smooth: bool = True) -> Targets:
    declaration = _DECLARATION.search(text)
    if declaration:
        raise _error(
            name, f"a {declaration.group(1).upper()} declaration: not read (SVG targets never expand entities)"
        )
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise _error(name, f"not valid XML ({shorten(str(exc))})") from None
    except (ValueError, TypeError, RecursionError) as exc:
        raise _error(name, f"not valid XML ({shorten(str(exc))})") from None
    element, ancestors = _first_path(root)
    if element is None:
        raise _error(name, "no <path> element with a 'd' attribute")
    for node in (element, *ancestors):
        if node.get("transform") is not None:
            where = "the <path>" if node is element else f"its ancestor <{shorten(_local(node.tag), 40)}>"
            raise _error(
                name,
                f"{where} has a transform ({_quote(node.get('transform'))}): transforms are not supported "
                "(flatten the path first)",
            )
    path_id = element.get("id")
    label = f"<path id={_quote(path_id)}>" if path_id else "<path>"
    d = element.get("d") or ""
    segments, ends_closed = _segments(d, name, label)
    drawn = smooth and len(segments) > DENSE_POINTS  # a pen's path: many short segments
    xy, closed = _sample(segments, ends_closed, max(count, SMOOTH_SAMPLES) if drawn else count, name, label)
    xy[:, 1] = 0.0 - xy[:, 1]  # SVG's y axis points down (0.0 - y: no negative zeros)
    targets = Targets(xy=xy, inputs=None, unit=units, closed=closed, source=name)
    check_scale(xy, name, units)
    return _smoothed(targets, xy, count) if drawn else targets


def _first_path(root: ET.Element) -> tuple[ET.Element | None, list[ET.Element]]:
    """The first ``<path>`` with a ``d`` attribute in document order, and its ancestors (nearest first)."""
    found = next((e for e in root.iter() if _local(e.tag) == "path" and e.get("d") is not None), None)
    if found is None:
        return None, []
    parents = {child: parent for parent in root.iter() for child in parent}
    ancestors: list[ET.Element] = []
    node = found
    while node in parents:
        node = parents[node]
        ancestors.append(node)
    return found, ancestors


def _segments(d: str, name: str, label: str) -> tuple[list[Any], bool]:
    """The drawing segments of the path's one subpath, and whether the path ends with ``Z``."""
    from svg.path import Close, Move, parse_path

    data = d.strip()
    if not data:
        raise _error(name, f"{label}: the 'd' attribute is empty")
    if data[0] not in "Mm":
        raise _error(name, f"{label}: the path data must start with M or m, got {_quote(data[:20])}")
    if len(_NUMBER.findall(data)) > _MOST_ARGUMENTS * MAX_SEGMENTS:  # a cheap bound before parsing
        raise _error(name, f"{label}: more than {MAX_SEGMENTS} segments")
    try:
        parsed = list(parse_path(data))
    except Exception as exc:  # svg.path fails on bad data with several exception types
        raise _error(name, f"{label}: not valid path data ({shorten(str(exc) or type(exc).__name__)})") from None
    if len(parsed) > MAX_SEGMENTS:
        raise _error(name, f"{label}: more than {MAX_SEGMENTS} segments")
    groups: list[list[Any]] = []
    current: list[Any] | None = None
    for seg in parsed:
        if isinstance(seg, Move):
            current = None
            continue
        if current is None:
            current = []
            groups.append(current)
        current.append(seg)
    if not groups:
        raise _error(name, f"{label}: the path draws nothing")
    if len(groups) > 1:
        raise _error(
            name,
            f"{label}: {len(groups)} subpaths (several M commands); only one curve can be a target: "
            "keep one, or join them into one subpath",
        )
    drawn = groups[0]
    return drawn, isinstance(drawn[-1], Close)


class _Curve:
    """The segments of a path as arrays, evaluated at many (segment, parameter) pairs at once.

    Lines, quadratic and cubic Béziers are all stored as cubic Béziers (degree elevation is
    exact); elliptical arcs by their centre parameterisation (SVG implementation notes F.6),
    taken from :class:`svg.path.Arc`.
    """

    def __init__(self, segments: list[Any]) -> None:
        from svg.path import Arc, CubicBezier, Linear, QuadraticBezier

        n = len(segments)
        self.bezier = np.zeros((4, n), dtype=complex)
        self.is_arc = np.zeros(n, dtype=bool)
        self.arc = np.zeros((6, n))  # centre x, centre y, rx, ry, start angle, sweep (angles in radians)
        self.rotation = np.zeros(n)
        for k, seg in enumerate(segments):
            if isinstance(seg, CubicBezier):
                self.bezier[:, k] = (seg.start, seg.control1, seg.control2, seg.end)
            elif isinstance(seg, QuadraticBezier):
                c = seg.control
                self.bezier[:, k] = (
                    seg.start,
                    seg.start + 2 * (c - seg.start) / 3,
                    seg.end + 2 * (c - seg.end) / 3,
                    seg.end,
                )
            elif isinstance(seg, Arc) and seg.start != seg.end and seg.radius.real != 0 and seg.radius.imag != 0:
                self.is_arc[k] = True
                radius = seg.radius * seg.radius_scale
                self.arc[:, k] = (seg.center.real, seg.center.imag, radius.real, radius.imag, seg.theta, seg.delta)
                self.rotation[k] = seg.rotation
            elif isinstance(seg, Linear | Arc):  # lines, Z, and arcs that SVG draws as lines
                a, b = seg.start, seg.end
                self.bezier[:, k] = (a, a + (b - a) / 3, b + (a - b) / 3, b)
            else:
                raise TypeError(f"unknown segment {type(seg).__name__}")
        self.arc[4:] = np.radians(self.arc[4:])
        self.rotation = np.radians(self.rotation)

    def __call__(self, k: np.ndarray, t: np.ndarray) -> np.ndarray:
        """Points (complex) of segments ``k`` at parameters ``t``."""
        p0, p1, p2, p3 = self.bezier[:, k]
        s = 1.0 - t
        out = s**3 * p0 + 3 * s * s * t * p1 + 3 * s * t * t * p2 + t**3 * p3
        arc = self.is_arc[k]
        if np.any(arc):
            ka, ta = k[arc], t[arc]
            cx, cy, rx, ry, theta, delta = self.arc[:, ka]
            angle = theta + delta * ta
            cos_r, sin_r = np.cos(self.rotation[ka]), np.sin(self.rotation[ka])
            x = cos_r * np.cos(angle) * rx - sin_r * np.sin(angle) * ry + cx
            y = sin_r * np.cos(angle) * rx + cos_r * np.sin(angle) * ry + cy
            out[arc] = x + 1j * y
        return np.asarray(out, dtype=complex)


def _sample(segments: list[Any], ends_closed: bool, count: int, name: str, label: str) -> tuple[np.ndarray, bool]:
    """``count`` points equally spaced in arc length along the segments, and whether the path is closed.

    Each curved segment is sampled densely (lines at their ends); the length of that polyline
    maps arc length to a segment parameter by linear interpolation, and the points are then
    evaluated on the segments themselves: they lie on the curve, not on the polyline.
    """
    from svg.path import Linear

    try:
        curve = _Curve(segments)
    except (ArithmeticError, ValueError, TypeError, AttributeError) as exc:
        raise _error(name, f"{label}: a segment cannot be drawn ({shorten(str(exc) or type(exc).__name__)})") from None
    straight = np.array([isinstance(seg, Linear) for seg in segments])
    dense = int(min(1025, max(9, 1_000_000 // max(int((~straight).sum()), 1))))
    per = np.where(straight, 2, dense)
    which = np.repeat(np.arange(len(segments)), per)
    first = np.concatenate([[0], np.cumsum(per)[:-1]])
    t = (np.arange(len(which)) - first[which]) / (per[which] - 1.0)
    with np.errstate(all="ignore"):
        pts = curve(which, t)
        if not np.all(np.isfinite(pts)):
            raise _error(name, f"{label}: numbers too large (a point of the path is not finite)")
        steps = np.abs(np.diff(pts))
        steps[which[1:] != which[:-1]] = 0.0  # from one segment's end to the next one's start
        run = np.concatenate([[0.0], np.cumsum(steps)])
    total = float(run[-1])
    if not math.isfinite(total):
        raise _error(name, f"{label}: the path is too long (its length is not a finite number)")
    if total <= 0.0:
        raise _error(name, f"{label}: the path has no length (every point is the same)")
    span = _diagonal(np.column_stack([pts.real, pts.imag]))
    closed = ends_closed or abs(pts[-1] - pts[0]) <= CLOSE_TOL * span
    s = np.linspace(0.0, total, count + 1)[:-1] if closed else np.linspace(0.0, total, count)
    j = np.clip(np.searchsorted(run, s, side="right") - 1, 0, len(run) - 2)
    within = which[j] == which[j + 1]
    width = run[j + 1] - run[j]
    with np.errstate(all="ignore"):
        fraction = np.where(width > 0, np.clip((s - run[j]) / width, 0.0, 1.0), 0.0)
    k = np.where(within, which[j], which[j + 1])
    u = np.where(within, t[j] + (t[j + 1] - t[j]) * fraction, 0.0)
    out = curve(k, u)
    if not np.all(np.isfinite(out)):
        raise _error(name, f"{label}: numbers too large (a sampled point is not finite)")
    return np.column_stack([out.real, out.imag]), bool(closed)
