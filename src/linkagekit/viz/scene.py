"""One scene description of a solved sweep, drawn by matplotlib (files) and by the page's viewer (SVG).

A :class:`Scene` holds only numbers the solver computed, arranged for drawing:

* the joints, per sample (``xy``, NaN where the mechanism does not assemble);
* the links, each drawn as a ``bar`` (two joints), a ``plate`` (three or more joints: a
  filled polygon through its joints in angular order about their centroid), a ``block`` (a
  slider block: one joint, drawn as a rectangle along its guide) or the ``ground``; and the
  cylinder drivers (``cylinder``: a barrel and a rod between their two ends);
* each slider's guide line per sample (a point and a unit direction): a guide on a moving
  link turns and moves with that link, which is read off the link's solved angle;
* the paths of the moving joints, split into *coupler curves* (joints of links that touch
  neither the ground nor a guide on the ground: the curves users look for) and the other
  paths (arcs of cranks and rockers, a slider's line);
* the runs of samples where the mechanism does not assemble;
* the quantities (every entry of the result's :mod:`~linkagekit.catalogue`: the columns of
  :meth:`Result.columns` plus the plotted speed of each moving joint) and their plots, one
  per plotted :class:`~linkagekit.catalogue.Group`;
* the axis the plots run along (:attr:`Scene.x_axis`): the first moving driver's input over
  a sweep, or the time of a simulated motion (:func:`linkagekit.simulate`), whose samples
  follow the time axis.

Nothing here solves anything: the viewer in the page and the matplotlib drawing both read
this scene, so a picture can only show what the solver returned.

Examples
--------
>>> import linkagekit as lk
>>> from linkagekit.viz.scene import build_scene
>>> sc = build_scene(lk.analyze(lk.load("examples/seed000_fourbar.yaml")))
>>> sc.coupler_curves, [ln.kind for ln in sc.links]
(('P',), ['ground', 'bar', 'plate', 'bar'])
>>> sc.xy.shape
(361, 5, 2)
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..catalogue import Catalogue, Group, Needs, Owner, input_units
from ..errors import InputError, shorten
from ..model import CylinderType, Mechanism
from ..result import Result

#: margin around the drawing, as a fraction of its size
MARGIN = 0.08


@dataclass(frozen=True)
class SceneLink:
    """A link as drawn: ``kind`` is ``ground``, ``bar``, ``plate``, ``block`` or ``cylinder``.

    A ``cylinder`` is a cylinder driver (named by the driver), drawn between its two ends: a rod
    over the whole length and a rigid barrel of length ``barrel`` (file units) from its first end
    (:func:`barrel_length`; cut at the current length, so it never passes the second end).

    ``outline`` is the order of its joints around its polygon (a plate), else its joints.
    """

    name: str
    kind: str
    joints: tuple[str, ...]
    outline: tuple[str, ...]
    barrel: float = 0.0


@dataclass(frozen=True)
class SceneSlider:
    """A slider: ``block`` slides on ``on`` through joint ``through``.

    ``origin`` (n, 2) is a point of the guide and ``direction`` (n, 2) its unit direction at
    each sample (fixed for a guide on the ground); ``span`` the stretch of the guide to draw,
    as offsets along ``direction`` from ``origin``.
    """

    block: str
    on: str
    through: str
    origin: np.ndarray
    direction: np.ndarray
    span: tuple[float, float]


@dataclass(frozen=True)
class Plot:
    """One plot of the report or of ``plot --quantity``: ``series`` are column names sharing ``unit``."""

    title: str
    unit: str
    series: tuple[str, ...]
    #: the values are angles modulo this period: a line is broken where it wraps, not drawn across
    period: float | None = None


@dataclass(frozen=True)
class Scene:
    """Everything a drawing of a solved sweep needs, in file units (see the module docstring).

    Attributes
    ----------
    name : str
        The mechanism's name.
    length_unit, angle_unit : str
        The file's units (every length and input angle here is in them).
    joints : tuple of str
        Joint names, in the order of the second axis of :attr:`xy`.
    ground_joints : tuple of str
        The joints fixed on the ground.
    ground_xy : dict of str to (float, float)
        Where each ground joint sits.
    links : tuple of SceneLink
        Every link as drawn (its kind and outline), cylinder drivers included.
    sliders : tuple of SceneSlider
        Every slider's guide, per sample.
    drivers : tuple of str
        The driver names.
    input_units : dict of str to str
        Each driver's input unit (from the output catalogue).
    inputs : dict of str to ndarray
        Each driver's input value per sample (file units).
    xy : ndarray, shape (n, n_joints, 2)
        Joint positions per sample; NaN where the mechanism does not assemble.
    assembled : ndarray of bool, shape (n,)
        Whether each sample assembles.
    coupler_curves, other_paths : tuple of str
        The joints whose paths are coupler curves, and the moving joints whose paths are not.
    gaps : tuple of (int, int)
        Runs ``[start, stop)`` of samples that do not assemble.
    bounds : (float, float, float, float)
        ``(x0, y0, x1, y1)`` of everything drawn over the sweep.
    columns : dict of str to ndarray
        Every quantity's values per sample (the catalogue's entries, plotted-only ones included).
    units : dict of str to str
        The unit of each of :attr:`columns`.
    plots : tuple of Plot
        One plot per plotted catalogue group.
    x_driver : str
        The driver the plots run along: the first whose input varies over the sweep.
    breaks : tuple of int
        Samples ``i`` whose segment to ``i + 1`` must not be drawn: both assemble, but the
        mechanism does not assemble somewhere between them (a gap no sample landed in).
    catalogue : Catalogue
        What each column is (owner, unit, group, period): the result's output catalogue.
    x_axis : str
        The column the plots run along: ``time`` for a simulated motion, else the input of
        :attr:`x_driver` (``""``: a drawing without columns, whose x is :attr:`x_driver`'s input).
    stopped : str or None
        A simulation that met a toggle: the message of where it stopped (the samples end there).
    exact_shading : tuple of (float, float), optional
        With one driver (not a simulated motion), the intervals of its input over the sweep where
        the mechanism does not assemble: the complement of its exact assembly range (a gap no
        sample landed in too). None where unknown (:attr:`shaded` then goes by the samples).
    path_xy : ndarray, shape (m, n_joints, 2), optional
        The joints' paths as drawn: the samples with the exact ends of the assembly range inside the
        sweep put between the two samples they lie between, so that a path runs on to a dead point
        (it stopped at the last sample, up to 50 px short next to a toggle); None: :attr:`xy`.
    path_breaks : tuple of int
        Points ``k`` of :attr:`path_xy` whose segment to ``k + 1`` must not be drawn (it crosses a
        stretch where the mechanism does not assemble).
    """

    name: str
    length_unit: str
    angle_unit: str
    joints: tuple[str, ...]
    ground_joints: tuple[str, ...]
    ground_xy: dict[str, tuple[float, float]]
    links: tuple[SceneLink, ...]
    sliders: tuple[SceneSlider, ...]
    drivers: tuple[str, ...]
    input_units: dict[str, str]
    inputs: dict[str, np.ndarray]
    xy: np.ndarray
    assembled: np.ndarray
    coupler_curves: tuple[str, ...]
    other_paths: tuple[str, ...]
    gaps: tuple[tuple[int, int], ...]
    bounds: tuple[float, float, float, float]
    columns: dict[str, np.ndarray] = field(repr=False)
    units: dict[str, str] = field(repr=False)
    plots: tuple[Plot, ...] = ()
    x_driver: str = ""
    breaks: tuple[int, ...] = ()
    catalogue: Catalogue = field(default=Catalogue(()), repr=False)
    x_axis: str = ""
    stopped: str | None = None
    exact_shading: tuple[tuple[float, float], ...] | None = None
    path_xy: np.ndarray | None = field(default=None, repr=False)
    path_breaks: tuple[int, ...] = ()

    @property
    def timed(self) -> bool:
        """Whether the samples are the times of a simulated motion (the plots run along time)."""
        return self.x_axis in self.catalogue and self.catalogue[self.x_axis].kind.needs is Needs.TIME

    @property
    def x(self) -> np.ndarray:
        """The values the plots run along, per sample (:attr:`x_axis`'s column)."""
        if self.x_axis in self.columns:
            return np.asarray(self.columns[self.x_axis], float)
        return np.asarray(self.inputs[self.x_driver], float)

    @property
    def shaded(self) -> tuple[tuple[float, float], ...]:
        """Intervals of :attr:`x` to shade where the mechanism does not assemble: :attr:`exact_shading`, and each
        run of samples that do not assemble outside it (every run, without it) from the assembled sample before it
        to the one after."""
        return _sample_shading(self.assembled, self.x, self.exact_shading)

    @property
    def x_name(self) -> str:
        """What the plots run along: ``time``, or the driver's name."""
        return "time" if self.timed else self.x_driver

    @property
    def x_unit(self) -> str:
        """The unit of :attr:`x`."""
        if self.x_axis in self.units:
            return self.units[self.x_axis]
        return self.input_units.get(self.x_driver, "")

    def sample_text(self, i: int) -> str:
        """What sample ``i`` is: each driver's input, after the time of a simulated motion (``t = 0.25 s, ...``)."""
        inputs = [f"{k} = {self.inputs[k][i]:.6g} {self.input_units[k]}" for k in self.drivers]
        return ", ".join([f"t = {self.x[i]:.6g} {self.x_unit}"] * self.timed + inputs)

    @property
    def n(self) -> int:
        """Number of samples."""
        return int(self.xy.shape[0])

    @property
    def size(self) -> float:
        """The larger side of :attr:`bounds` (a length scale for symbols)."""
        x0, y0, x1, y1 = self.bounds
        return max(x1 - x0, y1 - y0)

    def index(self, joint: str) -> int:
        """Position of a joint in :attr:`joints`."""
        return self.joints.index(joint)

    def to_dict(self) -> dict[str, Any]:
        """The scene as plain JSON data (NaN as None) for the page's viewer.

        Per-sample positions are in ``columns`` (``J.x``, ``J.y``), not repeated.
        """
        return {
            "format": "linkagekit-scene/1",
            "name": self.name,
            "units": {"length": self.length_unit, "angle": self.angle_unit},
            "joints": list(self.joints),
            "ground_joints": list(self.ground_joints),
            "ground_xy": {j: list(p) for j, p in self.ground_xy.items()},
            "links": [
                {"name": ln.name, "kind": ln.kind, "joints": list(ln.outline)}
                | ({"barrel": ln.barrel} if ln.kind == "cylinder" else {})
                for ln in self.links
            ],
            "sliders": [
                {
                    "block": s.block,
                    "on": s.on,
                    "through": s.through,
                    "origin": _json_array(s.origin),
                    "direction": _json_array(s.direction),
                    "span": list(s.span),
                }
                for s in self.sliders
            ],
            "drivers": list(self.drivers),
            "input_units": self.input_units,
            "n": self.n,
            "coupler_curves": list(self.coupler_curves),
            "other_paths": list(self.other_paths),
            "gaps": [list(g) for g in self.gaps],
            "shaded": [list(g) for g in self.shaded],
            "shaded_exact": self.exact_shading is not None,
            "breaks": list(self.breaks),
            "paths": None if self.path_xy is None else self._paths_dict(),
            "path_breaks": list(self.path_breaks),
            "x_driver": self.x_driver,
            "x_axis": {"column": self.x_axis, "name": self.x_name, "unit": self.x_unit, "time": self.timed},
            "stopped": self.stopped,
            "bounds": list(self.bounds),
            "columns": {k: _json_array(v) for k, v in self.columns.items()},
            "units_of": self.units,
            "quantities": [q.to_dict() for q in self.catalogue],
            "plots": [
                {"title": p.title, "unit": p.unit, "series": list(p.series), "period": p.period} for p in self.plots
            ],
        }

    def _paths_dict(self) -> dict[str, dict[str, list[Any]]]:
        """:attr:`path_xy` of the joints whose paths are drawn, ``{joint: {"x": [...], "y": [...]}}``."""
        assert self.path_xy is not None
        drawn = (*self.coupler_curves, *self.other_paths)
        return {j: {c: _json_array(self.path_xy[:, self.index(j), k]) for k, c in enumerate("xy")} for j in drawn}


def _json_array(a: np.ndarray) -> list[Any]:
    """A float array as nested lists with None for NaN (booleans stay booleans)."""
    arr = np.asarray(a)
    if arr.dtype == bool:
        return [bool(v) for v in arr.ravel()] if arr.ndim == 1 else arr.tolist()
    obj = arr.astype(object)
    obj[~np.isfinite(arr)] = None
    return obj.tolist()  # type: ignore[no-any-return]


def _outline(points: list[complex], names: tuple[str, ...]) -> tuple[str, ...]:
    """The joints of a plate in angular order about their centroid (a simple polygon)."""
    c = sum(points) / len(points)
    order = sorted(range(len(points)), key=lambda i: math.atan2((points[i] - c).imag, (points[i] - c).real))
    return tuple(names[i] for i in order)


def _collinear(points: list[complex]) -> bool:
    """Whether a link's joints lie on one line (to 1e-6 of its extent, far thinner than any drawing shows): it is
    drawn as a bar, not as a plate (a polygon of no area was a pale ghost of a link in the pictures, a solid line
    on the page). A triangle given by lengths that add up (Whitworth's lever: 0.15 + 0.32 = 0.47) is placed off its
    line by the square root of rounding, 6e-9 of its extent there.

    >>> _collinear([0j, 1 + 1j, 3 + 3j]), _collinear([0j, 1 + 0j, 1j]), _collinear([0j, 1 + 4e-9j, 2 + 0j])
    (True, False, True)
    """
    c = sum(points) / len(points)
    u = np.array([p - c for p in points])
    extent = float(np.max(np.abs(u)))
    _, sv, _ = np.linalg.svd(np.stack([u.real, u.imag]))
    return bool(sv[-1] <= 1e-6 * max(extent, 1e-300) * math.sqrt(len(points)))


def _along(points: list[complex], names: tuple[str, ...]) -> tuple[str, ...]:
    """A bar's joints, its two ends first (the page draws a bar between its first two), then the others.

    >>> _along([0j, 2 + 0j, 1 + 0j], ("A", "B", "C")), _along([1 + 0j, 0j, 3 + 0j], ("M", "A", "B"))
    (('A', 'B', 'C'), ('A', 'B', 'M'))
    """
    if len(points) <= 2:
        return names
    pairs = [(j, i) for i in range(len(points)) for j in range(i)]
    a, b = max(pairs, key=lambda p: abs(points[p[0]] - points[p[1]]))
    return (names[a], names[b], *(n for k, n in enumerate(names) if k not in (a, b)))


def scene_links(mech: Mechanism) -> tuple[SceneLink, ...]:
    """How each link is drawn (its kind and outline), from the reference pose."""
    blocks = {s.link for s in mech.sliders}
    out = []
    for ln in mech.links:
        if ln.name == "ground":
            kind = "ground"
        elif ln.name in blocks and len(ln.joints) == 1:
            kind = "block"
        elif len(ln.joints) >= 3 and not _collinear([ln.shape[j] for j in ln.joints]):
            kind = "plate"
        else:
            kind = "bar"
        points = [ln.shape[j] for j in ln.joints]  # its rigid shape: the file's exact lengths, not the pose's digits
        outline = _outline(points, ln.joints) if kind == "plate" else _along(points, ln.joints)
        out.append(SceneLink(ln.name, kind, ln.joints, outline))
    for d in mech.drivers:  # a cylinder is not a link, but it is drawn: a bar between its two ends
        if isinstance(d.type, CylinderType):
            a, b = d.type.ends
            length = abs(mech.joints[b] - mech.joints[a])
            out.append(SceneLink(d.name, "cylinder", d.type.ends, d.type.ends, barrel_length(length, d.type.stroke)))
    return tuple(out)


#: a cylinder's barrel as drawn: this fraction of its retracted length (the stroke's shorter end), else of its
#: length in the pose
BARREL_OF_RETRACTED, BARREL_OF_POSE = 0.85, 0.55


def barrel_length(pose_length: float, stroke: tuple[float, float] | None) -> float:
    """A cylinder's barrel as drawn: rigid, :data:`BARREL_OF_RETRACTED` of the stroke's shorter end when there is a
    stroke (never past the rod's end, however far the cylinder retracts), else :data:`BARREL_OF_POSE` of its
    length in the pose.

    >>> barrel_length(2.35, (1.8, 2.9)), barrel_length(2.0, None)
    (1.53, 1.1)
    """
    return BARREL_OF_RETRACTED * min(stroke) if stroke is not None else BARREL_OF_POSE * pose_length


def path_kinds(mech: Mechanism) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """(coupler-curve joints, other moving joints).

    A coupler curve is the path of a joint none of whose links touches the ground (by a
    pivot, or as a block sliding on a guide fixed to the ground): its path is not an arc or
    a line, and it is what users trace.
    """
    ground = set(mech.link("ground").joints)
    on_ground = {s.link for s in mech.sliders if s.on == "ground"} | {s.on for s in mech.sliders if s.link == "ground"}
    grounded_links = {ln.name for ln in mech.links if ln.name == "ground" or ground & set(ln.joints)} | on_ground
    coupler: list[str] = []
    other: list[str] = []
    for j in mech.joint_names:
        if j in ground:
            continue
        (other if set(mech.links_of(j)) & grounded_links else coupler).append(j)
    return tuple(coupler), tuple(other)


def _ground_xy(mech: Mechanism) -> dict[str, tuple[float, float]]:
    """The ground joints where the file puts them (the ground never moves)."""
    return {j: (mech.joints[j].real, mech.joints[j].imag) for j in mech.link("ground").joints}


def _pose_angle(mech: Mechanism, link: str) -> float:
    """A link's angle in the reference pose, by the same rule as :attr:`Result.link_angle` (radians)."""
    ln = mech.link(link)
    if ln.name == "ground":
        return 0.0
    if len(ln.joints) >= 2:
        d = mech.joints[ln.joints[1]] - mech.joints[ln.joints[0]]
        return math.atan2(d.imag, d.real)
    sl = next((s for s in mech.sliders if s.link == ln.name), None)
    d = sl.direction if sl is not None else 1.0 + 0j
    return math.atan2(d.imag, d.real)


def _guides(res: Result, z: np.ndarray) -> tuple[SceneSlider, ...]:
    """Each slider's guide line per sample, moved with the link that carries it."""
    mech = res.mechanism
    unit = mech.angle_to_rad
    names = mech.joint_names
    out = []
    for s in mech.sliders:
        through_pose = mech.joints[s.through]
        if s.on == "ground":
            origin = np.full(z.shape[0], through_pose)
            direction = np.full(z.shape[0], s.direction)
        else:
            on = mech.link(s.on)
            turn = np.exp(1j * (np.asarray(res.angle(s.on), float) * unit - _pose_angle(mech, s.on)))
            ref = on.joints[0] if on.joints else s.through
            origin = z[:, names.index(ref)] + turn * (through_pose - mech.joints[ref])
            direction = turn * s.direction
        # the stretch of the guide the joint travels along, plus a margin
        with np.errstate(invalid="ignore"):
            t = ((z[:, names.index(s.through)] - origin) * np.conj(direction)).real
        t = t[np.isfinite(t)]
        lo, hi = (float(t.min()), float(t.max())) if t.size else (0.0, 0.0)
        pad = 0.15 * max(hi - lo, 1e-9) + 0.05 * _extent(z)
        out.append(
            SceneSlider(
                s.link,
                s.on,
                s.through,
                np.stack([origin.real, origin.imag], axis=-1),
                np.stack([direction.real, direction.imag], axis=-1),
                (lo - pad, hi + pad),
            )
        )
    return tuple(out)


def _extent(z: np.ndarray) -> float:
    fin = z[np.isfinite(z)]
    if fin.size == 0:
        return 1.0
    return float(max(np.ptp(fin.real), np.ptp(fin.imag), 1e-12))


def _gaps(assembled: np.ndarray) -> tuple[tuple[int, int], ...]:
    """Runs ``[first, last]`` (inclusive sample indices) where the mechanism does not assemble."""
    bad = ~np.asarray(assembled, bool)
    edges = np.flatnonzero(np.diff(np.concatenate([[0], bad.astype(np.int8), [0]])))
    return tuple((int(a), int(b) - 1) for a, b in zip(edges[::2], edges[1::2], strict=True))


def broken_at_wraps(x: np.ndarray, y: np.ndarray, period: float | None) -> tuple[np.ndarray, np.ndarray]:
    """``(x, y)`` with a NaN point put where the angle ``y`` wraps (jumps by more than half a period).

    A line through the result is not drawn across the jump from +180 to -180 degrees.
    """
    x, y = np.asarray(x, float), np.asarray(y, float)
    if period is None:
        return x, y
    with np.errstate(invalid="ignore"):
        jumps = np.flatnonzero(np.abs(np.diff(y)) > period / 2) + 1
    return np.insert(x, jumps, np.nan), np.insert(y, jumps, np.nan)


def _x_driver(inputs: dict[str, np.ndarray], drivers: tuple[str, ...]) -> str:
    """The first driver whose input changes over the sweep (the first driver if none does)."""
    return next((d for d in drivers if np.ptp(inputs[d]) > 0), drivers[0])


def _gaps_between_samples(
    res: Result, x: np.ndarray, exact: bool, known: list[list[float]] | None
) -> tuple[tuple[int, ...], list[tuple[float, float]] | None]:
    """:func:`_breaks` and :func:`_exact_shading` of one driver's sweep ``x`` from its assembly range (``known``, or
    :func:`linkagekit.checks.input_range`); ``((), None)`` without ``exact`` or with several drivers."""
    if not (exact and len(res.mechanism.drivers) == 1 and res.n >= 2):
        return (), None
    if known is None:
        from ..checks import input_range

        known = input_range(res.mechanism, 0)
    return _breaks(res, x, known), _exact_shading(res, x, known)


def _exact_shading(res: Result, x: np.ndarray, known: list[list[float]]) -> list[tuple[float, float]] | None:
    """Where over the sweep ``x`` (its one driver's input) the mechanism does not assemble: the complement of its
    assembly intervals ``known`` (an angle's repeated every turn) within ``[min x, max x]``; None for a mode longer
    than a turn (its samples tell, not its range)."""
    from ..checks import beyond_a_turn

    mech = res.mechanism
    ranges = np.array(known, float).reshape(-1, 2)
    lo, hi = float(np.nanmin(x)), float(np.nanmax(x))
    if mech.drivers[0].type.cyclic:
        period = 2 * math.pi / mech.drivers[0].input_scale(mech)
        if ranges.shape[0] == 1 and beyond_a_turn(ranges[0], period):
            return None
        turns = [
            (s + k * period, e + k * period)
            for s, e in ranges
            for k in range(math.floor((lo - e) / period), math.ceil((hi - s) / period) + 1)
        ]
    else:
        turns = [(float(s), float(e)) for s, e in ranges]
    out, at = [], lo
    for s, e in sorted(turns):
        if s > at and s > lo:
            out.append((at, min(s, hi)))
        at = max(at, e)
        if at >= hi:
            break
    if at < hi:
        out.append((at, hi))
    return [(float(a), float(b)) for a, b in out if b > a]


def _paths_to_ends(res: Result, x: np.ndarray, z: np.ndarray, shaded: list[tuple[float, float]] | None) -> Any:
    """:attr:`Scene.path_xy` and :attr:`Scene.path_breaks`, as keywords: the samples ``z`` (n, J) along the sweep
    ``x`` of one driver, with each end of the assembly range inside the sweep (an edge of an interval of ``shaded``)
    next to the sample nearest it inside the range, on the side the path leaves the range (:func:`_end_slots`),
    solved a hair inside the range in that sample's signs; none when there is none. An end whose joints lie farther
    from that sample than three of the sweep's largest steps (not the same assembly mode) is left out."""
    if not shaded or len(res.mechanism.drivers) != 1:
        return {}
    slots = _end_slots(x, res.assembled, shaded)  # (after sample, end, inward, sample)
    if not slots:
        return {}
    at = np.array([v + d * 1e-10 * max(1.0, abs(v)) for _, v, d, _ in slots])
    near = [k for *_, k in slots]
    ze = _solve_at(res, at, near)
    step = np.nanmax(np.abs(np.diff(z, axis=0)), initial=0.0)
    ze[np.nanmax(np.abs(ze - z[near]), axis=1) > 3 * step] = np.nan
    after = np.array([a for a, *_ in slots])
    pos = np.arange(len(x)) + np.searchsorted(after, np.arange(len(x)), side="left")  # the ends before each sample
    ins = after + 1 + np.arange(len(slots))  # after its sample and the ends before it
    path = np.full((len(x) + len(slots), z.shape[1]), np.nan + 0j)
    path[pos], path[ins] = z, ze
    xs = np.empty(len(path))
    xs[pos], xs[ins] = x, at
    gap = np.array(shaded, float).reshape(-1, 2)  # a segment overlapping a gap is not drawn
    lo, hi = np.minimum(xs[:-1], xs[1:])[:, None], np.maximum(xs[:-1], xs[1:])[:, None]
    crossing = np.any(np.maximum(lo, gap[None, :, 0]) < np.minimum(hi, gap[None, :, 1]), axis=1)
    breaks = np.flatnonzero(crossing & np.all(np.isfinite(path[:-1]) & np.isfinite(path[1:]), axis=1))
    return {"path_xy": np.stack([path.real, path.imag], axis=-1), "path_breaks": tuple(int(k) for k in breaks)}


def _end_slots(
    x: np.ndarray, assembled: np.ndarray, shaded: list[tuple[float, float]]
) -> list[tuple[int, float, float, int]]:
    """Where each end of the range inside the sweep goes in the path: ``(after, end, inward, sample)``, sorted: the
    end put after sample ``after`` (-1: first), ``inward`` the side of the range (+1 above the end), ``sample`` the
    assembled sample nearest it inside the range. The path leaves the range at the end where that sample's neighbour
    in the path lies past it (or does not assemble, or there is none): the sweep's order, not the inputs' (a page
    adds the pose's input last, off the grid).

    >>> _end_slots(np.array([0.0, 1.0, 2.0, 3.0]), np.array([True, True, False, False]), [(1.5, 3.0)])
    [(1, 1.5, -1.0, 1)]
    """
    lo, hi, n = float(np.nanmin(x)), float(np.nanmax(x)), len(x)
    out = []
    for v, d in [(a, -1.0) for a, _ in shaded if lo < a < hi] + [(b, 1.0) for _, b in shaded if lo < b < hi]:
        inside = np.flatnonzero(assembled & (d * (x - v) > 0))
        if not len(inside):
            continue
        k = int(inside[np.argmin(np.abs(x[inside] - v))])

        def past(m: int, v: float = v, d: float = d) -> bool:
            return m < 0 or m >= n or not assembled[m] or d * (x[m] - v) <= 0

        if past(k + 1):
            out.append((k, v, d, k))
        elif past(k - 1):
            out.append((k - 1, v, d, k))

    def along(slot: tuple[int, float, float, int]) -> tuple[int, float]:  # two ends after one sample: the sweep's way
        a = slot[0]
        way = np.sign(x[a + 1] - x[a]) if 0 <= a < n - 1 else np.sign(x[-1] - x[0]) if n > 1 else 1.0
        return a, float(way * slot[1])

    return sorted(out, key=along)


def _solve_at(res: Result, at: np.ndarray, near: list[int]) -> np.ndarray:
    """The joints (m, J) of ``res``'s mechanism at its one driver's inputs ``at``, each in the signs of sample
    ``near[k]`` of ``res``."""
    from ..api import analyze

    mech = res.mechanism
    per_sample = [np.asarray(v)[near] if np.ndim(v) else np.full(len(near), v) for v in res.signs.values()]
    signs = np.array(per_sample, float) if per_sample else None  # one column per end (the branch followed: its own)
    ends = analyze(mech, {mech.drivers[0].name: at}, signs=signs, rates=False, dynamics=False)
    return np.stack([ends.point(j) for j in mech.joint_names], axis=-1)


def _sample_shading(
    assembled: np.ndarray, x: np.ndarray, exact: Sequence[tuple[float, float]] | None
) -> tuple[tuple[float, float], ...]:
    """The intervals to shade: ``exact`` (:func:`_exact_shading`), and for each run of samples that do not assemble
    outside it (every run, without it) the span from the assembled sample before it to the one after."""
    out = list(exact or [])
    for a, b in _gaps(assembled):
        if exact is not None and all(any(s <= x[i] <= e for s, e in exact) for i in range(a, b + 1)):
            continue
        lo, hi = x[max(a - 1, 0)], x[min(b + 1, len(x) - 1)]
        out.append((float(min(lo, hi)), float(max(lo, hi))))
    return tuple(sorted(out))


def _breaks(res: Result, x: np.ndarray, known: list[list[float]] | None = None) -> tuple[int, ...]:
    """Segments between two assembled samples that cross a stretch where the mechanism does not assemble.

    Only for one driver: its assembly intervals (:func:`linkagekit.checks.input_range`,
    boundaries exact to ~1e-12, or ``known`` when they were computed already) are compared
    with each segment; an angle's intervals repeat every turn.
    """
    mech = res.mechanism
    if len(mech.drivers) != 1 or res.n < 2:
        return ()
    from ..checks import beyond_a_turn, input_range

    ranges = np.array(input_range(mech, 0) if known is None else known, float).reshape(-1, 2)
    both = res.assembled[:-1] & res.assembled[1:]
    if not both.any():
        return ()
    lo, hi = np.minimum(x[:-1], x[1:]), np.maximum(x[:-1], x[1:])
    tol = 1e-9 * max(float(np.max(np.abs(x))), 1.0)
    if mech.drivers[0].type.cyclic:
        period = 2 * math.pi / mech.drivers[0].input_scale(mech)
        if ranges.shape[0] == 1 and beyond_a_turn(ranges[0], period):
            return _jumps_between_configurations(mech, lo, hi, ranges[0], both)
        if ranges.shape[0] == 1 and ranges[0, 1] - ranges[0, 0] >= period * (1 - 1e-12):
            return ()  # a full turn
        k = np.floor((lo[:, None] - ranges[None, :, 0] + tol) / period)
        start, end = ranges[None, :, 0] + k * period, ranges[None, :, 1] + k * period
    else:
        start, end = ranges[None, :, 0], ranges[None, :, 1]
    inside = ((start - tol <= lo[:, None]) & (hi[:, None] <= end + tol)).any(axis=1)
    return tuple(int(i) for i in np.flatnonzero(both & ~inside))


def _jumps_between_configurations(
    mech: Mechanism, lo: np.ndarray, hi: np.ndarray, rng: np.ndarray, both: np.ndarray
) -> tuple[int, ...]:
    """The segments (from ``lo`` to ``hi``, both ends assembled where ``both``) of a sweep over a mode longer than a
    turn that does not close (``rng``, as walked from the pose's input), that cross a direction where the answer goes
    from one of the two configurations of a direction reached twice to the other (``check`` says where:
    :func:`linkagekit.checks.direction_jumps`): a jump to draw as a break, not as motion."""
    from ..api import prepare
    from ..checks import direction_jumps

    scale = mech.drivers[0].input_scale(mech)
    period = 2 * math.pi / scale
    jumps = direction_jumps([float(rng[0]), float(rng[1])], float(prepare(mech).pose_inputs[0, 0]) / scale, period)
    out = np.zeros(len(lo), bool)
    for c in jumps:  # (lo, hi] holds a copy of c: c itself is answered as past the jump
        out |= c + (np.floor((lo - c) / period) + 1) * period <= hi
    return tuple(int(i) for i in np.flatnonzero(both & out))


def _plots(catalogue: Catalogue) -> tuple[Plot, ...]:
    """The plots of the report: one per plotted group of the catalogue that has quantities."""
    plots = []
    for group in Group:
        shown = catalogue.of_group(group) if group.plotted else ()
        if shown:
            plots.append(Plot(group.title, shown[0].unit_symbol, tuple(q.name for q in shown), shown[0].period))
    return tuple(plots)


def _bounds(mech: Mechanism, z: np.ndarray, sliders: tuple[SceneSlider, ...]) -> tuple[float, float, float, float]:
    """``(x0, y0, x1, y1)`` around every joint at every sample, the pose, and the drawn guides, with a margin."""
    pts = [z[np.isfinite(z)], np.array([mech.joints[j] for j in mech.joint_names])]
    for s in sliders:
        o = s.origin[..., 0] + 1j * s.origin[..., 1]
        d = s.direction[..., 0] + 1j * s.direction[..., 1]
        pts += [o + s.span[0] * d, o + s.span[1] * d]
    allp = np.concatenate([np.ravel(p) for p in pts])
    allp = allp[np.isfinite(allp)]
    x0, x1, y0, y1 = allp.real.min(), allp.real.max(), allp.imag.min(), allp.imag.max()
    pad = MARGIN * max(x1 - x0, y1 - y0, 1e-9)
    return (float(x0 - pad), float(y0 - pad), float(x1 + pad), float(y1 + pad))


def _checked_range(given: Any) -> list[list[float]] | None:
    """``input_range`` as a list of finite ``[start, stop]`` pairs (``start <= stop``; none: it assembles nowhere),
    or None; else InputError.

    >>> _checked_range([[0, 90.5]])
    [[0.0, 90.5]]
    >>> _checked_range("x")
    Traceback (most recent call last):
    ...
    linkagekit.errors.InputError: input_range: expected a list of [start, stop] pairs of finite numbers, start <= ...
    """
    if given is None:
        return None
    try:
        a = np.asarray(given, dtype=float)
    except (TypeError, ValueError):
        a = np.zeros((0, 3))
    if a.shape == (0,):  # assembles nowhere
        return []
    if a.ndim != 2 or a.shape[1] != 2 or not np.all(np.isfinite(a)) or np.any(a[:, 0] > a[:, 1]):
        raise InputError(
            "input_range: expected a list of [start, stop] pairs of finite numbers, start <= stop, got "
            + shorten(repr(given))
        )
    return [[float(x), float(y)] for x, y in a]


def build_scene(res: Result, exact_breaks: bool = True, input_range: list[list[float]] | None = None) -> Scene:
    """The scene of one mechanism's solved sweep.

    Parameters
    ----------
    res : Result
        From :func:`linkagekit.analyze` for one design (``res.design(i)`` for one of a batch).
    exact_breaks : bool
        False: no :attr:`Scene.breaks` (curves lifted only where samples do not assemble), as
        the editor draws while a joint is dragged: the exact range of a class-3 group is costly.
    input_range : list of [float, float], optional
        The first driver's :func:`linkagekit.checks.input_range`, when it is known already.

    Raises
    ------
    InputError
        For a batch result, a result with no samples, or a malformed ``input_range``.
    """
    ranges = _checked(res, input_range)
    mech, cat = res.mechanism, res.catalogue
    names = mech.joint_names
    z = np.stack([res.point(j) for j in names], axis=-1)  # (n, J)
    ground_joints = mech.link("ground").joints
    coupler, other = path_kinds(mech)
    columns = {q.name: np.broadcast_to(q.values(res), res.shape) for q in cat}
    sliders = _guides(res, z)
    drivers = tuple(d.name for d in mech.drivers)
    inputs = {d: np.asarray(columns[cat.find(Owner.DRIVER, d, "input").name], float).copy() for d in drivers}
    x_driver = _x_driver(inputs, drivers)
    timed = res.time is not None  # a simulated motion: continuous in time (no breaks), plotted along it
    breaks, shaded = _gaps_between_samples(res, inputs[drivers[0]], exact_breaks and not timed, ranges)
    return Scene(
        name=mech.name,
        length_unit=mech.length_unit,
        angle_unit=mech.angle_unit,
        joints=names,
        ground_joints=ground_joints,
        ground_xy=_ground_xy(mech),
        links=scene_links(mech),
        sliders=sliders,
        drivers=drivers,
        input_units=input_units(mech),
        inputs=inputs,
        xy=np.stack([z.real, z.imag], axis=-1),
        assembled=np.asarray(res.assembled, bool).copy(),
        coupler_curves=coupler,
        other_paths=tuple(j for j in other if j not in ground_joints),
        gaps=_gaps(res.assembled),
        bounds=_bounds(mech, z, sliders),
        columns=columns,
        units={q.name: q.unit_symbol for q in cat},
        plots=_plots(cat),
        x_driver=x_driver,
        breaks=breaks,
        catalogue=cat,
        x_axis=cat.find(Owner.MECHANISM, "", "time").name if timed else cat.find(Owner.DRIVER, x_driver, "input").name,
        stopped=res.stopped,
        exact_shading=None if shaded is None else tuple(shaded),
        **_paths_to_ends(res, inputs[drivers[0]], z, shaded),
    )


def _checked(res: Any, input_range: Any) -> list[list[float]] | None:
    """``input_range`` checked (:func:`_checked_range`) once ``res`` is (:func:`_check_result`)."""
    _check_result(res)
    return _checked_range(input_range)


def _check_result(res: Any) -> None:
    """Raise an InputError unless ``res`` is one design's Result."""
    if not isinstance(res, Result):
        raise InputError(f"expected a linkagekit Result (lk.analyze(...)), got {type(res).__name__}")
    if res.n_designs is not None:
        raise InputError("a scene draws one design: pass res.design(i)")
