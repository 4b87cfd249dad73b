"""matplotlib drawings of a scene: the mechanism as in a textbook, its curves, and plots of any quantity.

The drawing functions take and return a matplotlib ``Axes`` so they compose in notebooks:

>>> import matplotlib
>>> matplotlib.use("Agg")
>>> import matplotlib.pyplot as plt
>>> import linkagekit as lk
>>> from linkagekit.viz import draw
>>> res = lk.analyze(lk.load("examples/seed000_fourbar.yaml"))
>>> fig, (a, b) = plt.subplots(1, 2)
>>> draw.draw_mechanism(a, res, at=30.0) is a, draw.plot_quantity(b, res, "coupler.omega") is b
(True, True)
>>> plt.close(fig)

The drawing of a pose is a :class:`Drawing`: static parts (ground, guides on the ground,
curves) drawn once, moving parts as artists updated per sample, which is what the
animation redraws (and only that).  Every position drawn comes from the scene, so from the
solver; a sample that does not assemble draws no mechanism, and curves break there.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Polygon
from matplotlib.text import Text

from ..catalogue import input_units
from ..errors import InputError, UnknownNameError
from ..files import atomic_output
from ..result import Result
from .scene import Scene, broken_at_wraps, build_scene

#: colours of the links, in order (the ground is drawn in black)
PALETTE = ("#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2", "#17becf", "#bcbd22")
#: coupler curves
CURVE_COLOR = "#e6007e"
#: a cylinder: its rod (the whole length) and its rigid barrel (the scene link's ``barrel`` from its first end)
CYLINDER_ROD, CYLINDER_BARREL = "#9a9a9a", "#505050"
#: other joint paths
PATH_COLOR = "#9a9a9a"
BACKGROUND = "#ffffff"
#: the most assembly modes a modes figure draws
MAX_MODE_PANELS = 64
#: PNG metadata key holding the map from file units to pixels (see :func:`save_figure`)
TRANSFORM_KEY = "linkagekit:transform"
#: pixels per inch of a figure: a 6-inch drawing is 1200 px wide (text and lines are sized in points)
DPI = 200.0


def figure_inches(
    width: float, height: float, dpi: float = DPI, pixels: tuple[int, int | None] | None = None
) -> tuple[float, float]:
    """The size in inches of a figure whose natural size is ``width`` x ``height`` inches.

    ``pixels`` (``(W, H)`` or ``(W, None)``) asks for an exact size in pixels at ``dpi``:
    ``W`` x ``H``, or ``W`` wide with the natural aspect.  Without it, the natural size.

    >>> figure_inches(6.0, 3.0, 200.0, (1000, None))
    (5.0, 2.5)
    >>> figure_inches(6.0, 3.0, 100.0, (800, 600))
    (8.0, 6.0)
    """
    if pixels is None:
        return width, height
    w, h = pixels
    return w / dpi, (h / dpi if h is not None else w / dpi * height / width)


def _t(text: str) -> str:
    """A name as literal text: matplotlib would read ``$...$`` as mathematics."""
    return text.replace("$", r"\$")


#: the most characters of a mechanism's name that a picture's title shows (then an ellipsis): a 100 kB name took
#: 10 s to lay out, 1 MB 112 s
MAX_TITLE_NAME = 80


def title_name(name: str | None, limit: int = MAX_TITLE_NAME) -> str:
    """A mechanism's name for a picture's title: ``mechanism`` when it has none, cut to ``limit`` characters.

    >>> title_name("x" * 200, 10), title_name(""), title_name("crank")
    ('xxxxxxxxx…', 'mechanism', 'crank')
    """
    text = name or "mechanism"
    return text if len(text) <= limit else text[: limit - 1] + "…"


def _title(fig: Figure, text: str, size: float = 10) -> None:
    """``fig``'s title, broken into lines that fit its width (a long name was cut off on both sides at 800 px)."""
    import textwrap

    per_line = max(20, int(fig.get_figwidth() * 72 / (0.6 * size)))
    fig.suptitle(_t(textwrap.fill(text, per_line)), fontsize=size)


def _scene(obj: Result | Scene) -> Scene:
    if isinstance(obj, Scene):
        return obj
    return build_scene(obj)


def _axes(ax: Any) -> Axes:
    if not isinstance(ax, Axes):
        raise InputError(f"ax: expected a matplotlib Axes (e.g. plt.subplots()[1]), got {type(ax).__name__}")
    return ax


def _sample(sc: Scene, at: Any) -> int:
    """The sample nearest to ``at`` along the plots' axis (the plotted driver's input, or a simulation's time).

    None: the first assembled sample.  ``at`` outside the sweep is refused: the drawing would
    show another input than asked.
    """
    if at is None:
        ok = np.flatnonzero(sc.assembled)
        return int(ok[0]) if ok.size else 0
    what = "the time" if sc.timed else f"the input of {sc.x_driver}"
    if isinstance(at, bool) or not isinstance(at, numbers.Real) or not math.isfinite(float(at)):
        raise InputError(f"at: expected a finite number ({what}), got {at!r}")
    x = sc.x
    lo, hi = float(np.min(x)), float(np.max(x))
    slack = 1e-9 * max(hi - lo, abs(lo), abs(hi), 1.0)
    if not lo - slack <= float(at) <= hi + slack:
        raise InputError(
            f"at: {float(at):g} is outside the sweep of {sc.x_name} [{lo:g}, {hi:g}]; analyze a sweep through it"
        )
    return int(np.argmin(np.abs(x - float(at))))


def _with_breaks(xy: np.ndarray, breaks: Sequence[int]) -> np.ndarray:
    """Points with a NaN row after each sample of ``breaks``: no line across a gap between samples."""
    if not breaks:
        return xy
    return np.insert(np.asarray(xy, float), [b + 1 for b in breaks], np.nan, axis=0)


#: how a pin is drawn: a white circle with a black edge
PIN: dict[str, Any] = {
    "linestyle": "none",
    "marker": "o",
    "markersize": 6,
    "markerfacecolor": "white",
    "markeredgecolor": "black",
    "markeredgewidth": 1.3,
    "zorder": 6,
}


def _hatched(ax: Axes, points: Any) -> Polygon:
    """A hatched region without an outline (the ground under a pivot or a guide)."""
    patch = Polygon(points, closed=True, facecolor="none", edgecolor="black", hatch="////", linewidth=0.0, zorder=2)
    ax.add_patch(patch)
    return patch


class Drawing:
    """The mechanism of a scene on an Axes: :meth:`update` moves it to a sample.

    Parameters
    ----------
    ax : Axes
    scene : Scene
    labels : bool
        Write the joints' names.
    curves : bool
        Draw the joint paths (coupler curves in colour, the other paths thin and grey).
    animated : bool
        Mark the moving artists as animated (drawn only on request, for blitting).
    ground : bool
        Draw the ground (pivots, fixed guides); off for a second pose on the same Axes.
    size : float, optional
        The length that sizes the symbols (default the scene's): give the first drawing's
        when several scenes share an Axes, so that they are drawn alike.
    ground_labels : bool
        Write the ground pivots' names with the ground (``plot``'s picture; an animation's frames
        leave them out).
    """

    def __init__(
        self,
        ax: Axes,
        scene: Scene,
        labels: bool = True,
        curves: bool = True,
        animated: bool = False,
        ground: bool = True,
        size: float | None = None,
        ground_labels: bool = False,
    ):
        self.ax, self.scene = ax, scene
        self.pin = 0.012 * (scene.size if size is None else size)
        self.static: list[Any] = []
        ax.set_aspect("equal")
        ax.set_xlim(scene.bounds[0], scene.bounds[2])
        ax.set_ylim(scene.bounds[1], scene.bounds[3])
        ax.set_axis_off()
        ax.set_facecolor(BACKGROUND)
        if curves:
            self._curves()
        if ground:
            self._ground()
        # moving artists, in the order they are added (which one is on top at equal zorder)
        self.links = self._links(animated)
        self.moving_guides: list[tuple[Any, Line2D]] = []
        for sl in scene.sliders:
            if sl.on != "ground":
                line = Line2D([], [], color="#444444", linewidth=1.5, zorder=2.5, animated=animated)
                ax.add_line(line)
                self.moving_guides.append((sl, line))
        self.moving = [i for i, j in enumerate(scene.joints) if j not in scene.ground_joints]
        self.pins = Line2D([], [], animated=animated, **PIN)
        ax.add_line(self.pins)
        self.labels: list[tuple[int, Text]] = [(i, self._label(i, animated)) for i in self.moving] if labels else []
        for j in scene.ground_joints if ground_labels and ground else ():  # fixed: named once, where they stay
            x, y = scene.ground_xy[j]
            self.static.append(ax.text(x + 0.8 * self.pin, y + 0.8 * self.pin, _t(j), fontsize=8, zorder=7))
        self.note = ax.text(
            0.5,
            0.02,
            "",
            transform=ax.transAxes,
            ha="center",
            va="bottom",
            fontsize=9,
            color="#b00000",
            zorder=8,
            animated=animated,
        )

    # ---------------------------------------------------------------- moving parts
    def _links(self, animated: bool) -> list[tuple[Any, Any, tuple[int, ...]]]:
        """Every moving link's artist (two for a cylinder), with the link and its outline's joint indices."""
        sc = self.scene
        links: list[tuple[Any, Any, tuple[int, ...]]] = []
        k = 0
        for ln in sc.links:
            if ln.kind == "ground":
                continue
            idx = tuple(sc.index(j) for j in ln.outline)
            if ln.kind == "cylinder":  # a rod over the whole length, a barrel over its first part
                for width, shade in ((2.5, CYLINDER_ROD), (8, CYLINDER_BARREL)):
                    part = Line2D([], [], color=shade, linewidth=width, solid_capstyle="butt", zorder=3.2)
                    part.set_animated(animated)
                    self.ax.add_line(part)
                    links.append((ln, part, idx))
                continue
            links.append((ln, self._link_artist(ln.kind, PALETTE[k % len(PALETTE)], len(idx), animated), idx))
            k += 1
        return links

    def _link_artist(self, kind: str, color: str, joints: int, animated: bool) -> Any:
        """A link of this *kind* on the Axes: a plate (a polygon of its *joints*), a block, or a bar."""
        if kind == "plate":
            return self.ax.add_patch(
                Polygon(
                    np.zeros((joints, 2)),
                    closed=True,
                    facecolor=color,
                    alpha=0.35,
                    edgecolor=color,
                    linewidth=2.5,
                    joinstyle="round",
                    zorder=3,
                    animated=animated,
                )
            )
        if kind == "block":
            return self.ax.add_patch(
                Polygon(
                    np.zeros((4, 2)),
                    closed=True,
                    facecolor=color,
                    alpha=0.8,
                    edgecolor="black",
                    linewidth=1.0,
                    zorder=4,
                    animated=animated,
                )
            )
        bar = Line2D([], [], color=color, linewidth=5, solid_capstyle="round", zorder=3, animated=animated)
        return self.ax.add_line(bar)

    def _label(self, i: int, animated: bool) -> Text:
        """The name of joint *i*, placed (and shown) by :meth:`update`."""
        name = _t(self.scene.joints[i])
        return self.ax.text(0, 0, name, fontsize=8, zorder=7, animated=animated, ha="left", va="bottom", visible=False)

    # ---------------------------------------------------------------- static parts
    def _curves(self) -> None:
        sc, ax = self.scene, self.ax
        xy, breaks = (sc.xy, sc.breaks) if sc.path_xy is None else (sc.path_xy, sc.path_breaks)  # on to dead points
        for j in sc.other_paths:
            p = _with_breaks(xy[:, sc.index(j)], breaks)
            (line,) = ax.plot(p[:, 0], p[:, 1], color=PATH_COLOR, linewidth=0.8, linestyle=(0, (4, 3)), zorder=1)
            self.static.append(line)
        for j in sc.coupler_curves:
            p = _with_breaks(xy[:, sc.index(j)], breaks)
            (line,) = ax.plot(p[:, 0], p[:, 1], color=CURVE_COLOR, linewidth=1.6, zorder=1.5, label=_t(f"path of {j}"))
            self.static.append(line)

    def _ground(self) -> None:
        """Ground pivots as hatched triangles, guides on the ground as hatched lines."""
        sc, ax = self.scene, self.ax
        h = 3.2 * self.pin
        for j in sc.ground_joints:
            x, y = sc.ground_xy[j]  # fixed: drawn even when no sample assembles
            tri = Polygon(
                [[x, y], [x - 0.8 * h, y - h], [x + 0.8 * h, y - h]],
                closed=True,
                facecolor="#dddddd",
                edgecolor="black",
                linewidth=1.0,
                zorder=2,
            )
            ax.add_patch(tri)
            base = _hatched(
                ax,
                [[x - 1.3 * h, y - h], [x + 1.3 * h, y - h], [x + 1.3 * h, y - 1.45 * h], [x - 1.3 * h, y - 1.45 * h]],
            )
            (pin,) = ax.plot([x], [y], **PIN)
            self.static += [tri, base, pin]
        for sl in sc.sliders:
            if sl.on != "ground":
                continue
            o, d = sl.origin[0], sl.direction[0]
            a, b = o + sl.span[0] * d, o + sl.span[1] * d
            (line,) = ax.plot([a[0], b[0]], [a[1], b[1]], color="black", linewidth=1.5, zorder=2)
            nrm = np.array([d[1], -d[0]]) * 0.9 * h  # hatch below the guide (to its right)
            strip = _hatched(ax, [a, b, b + nrm, a + nrm])
            self.static += [line, strip]

    # ---------------------------------------------------------------- moving parts
    def artists(self) -> list[Any]:
        """Every artist :meth:`update` changes."""
        return (
            [a for _, a, _ in self.links]
            + [g for _, g in self.moving_guides]
            + [self.pins]
            + [t for _, t in self.labels]
            + [self.note]
        )

    def update(self, i: int) -> list[Any]:
        """Move the drawing to sample ``i``; returns the artists changed."""
        sc = self.scene
        p = sc.xy[i]
        ok = bool(sc.assembled[i])
        for ln, art, idx in self.links:
            pts = p[list(idx)]
            if ln.kind == "block":
                sl = next(s for s in sc.sliders if s.block == ln.name)
                c, d = p[sc.index(sl.through)], sl.direction[i]
                n = np.array([-d[1], d[0]])
                w, h = 2.6 * self.pin, 1.6 * self.pin
                art.set_xy(np.array([c - w * d - h * n, c + w * d - h * n, c + w * d + h * n, c - w * d + h * n]))
                art.set_visible(ok)
            elif ln.kind == "plate":
                art.set_xy(pts)
                art.set_visible(ok)
            elif ln.kind == "cylinder" and art.get_linewidth() > 5:  # the barrel: rigid, cut at the rod's end
                length = float(np.hypot(*(pts[1] - pts[0])))
                end = pts[0] + min(ln.barrel / length, 1.0) * (pts[1] - pts[0]) if length > 0 else pts[0]
                art.set_data([pts[0, 0], end[0]], [pts[0, 1], end[1]])
                art.set_visible(ok)
            else:
                art.set_data(pts[:, 0], pts[:, 1])
                art.set_visible(ok)
        for sl, line in self.moving_guides:
            o, d = sl.origin[i], sl.direction[i]
            a, b = o + sl.span[0] * d, o + sl.span[1] * d
            line.set_data([a[0], b[0]], [a[1], b[1]])
            line.set_visible(ok)
        # every pin, the ground's too: blitted artists are drawn over the static background,
        # so a ground pin left in the background would be hidden under the bars
        self.pins.set_data(p[:, 0], p[:, 1])
        self.pins.set_visible(ok)
        for j, t in self.labels:
            t.set_position((p[j, 0] + 0.8 * self.pin, p[j, 1] + 0.8 * self.pin))
            t.set_visible(ok)
        inputs = ", ".join(f"{k} = {sc.inputs[k][i]:.6g} {sc.input_units[k]}" for k in sc.drivers)
        last = sc.stopped is not None and i == sc.n - 1  # a simulated motion's last frame where it stopped
        self.note.set_text(_t(f"does not assemble at {inputs}") if not ok else stop_note(sc.stopped) if last else "")
        return self.artists()


def draw_mechanism(
    ax: Axes, res: Result | Scene, at: float | None = None, labels: bool = True, curves: bool = True
) -> Axes:
    """Draw the mechanism at input ``at`` (the sample nearest to it; default the first assembled) with its curves.

    The sample drawn is the sweep's: where it is not ``at`` itself, the drawing's note says which
    input it shows (the mechanism may not assemble at ``at`` itself: analyze there to know).

    Parameters
    ----------
    ax : Axes
    res : Result or Scene
        One design's sweep (:func:`linkagekit.analyze`).
    at : float, optional
        Input of the plotted driver (the first that varies over the sweep), in the file's
        units, within the sweep.
    """
    ax = _axes(ax)
    sc = _scene(res)
    d = Drawing(ax, sc, labels=bool(labels), curves=bool(curves))
    i = _sample(sc, at)
    d.update(i)
    x = float(sc.x[i])
    if at is not None and abs(x - float(at)) > 1e-9 * max(abs(x), abs(float(at)), 1.0):
        unit = sc.x_unit
        shown = f"the nearest sample, {sc.x_name} = {x:.6g} {unit} (asked {float(at):.6g} {unit})"
        d.note.set_text(_t(f"{d.note.get_text()}; {shown}" if d.note.get_text() else shown))
    return ax


def plot_quantity(
    ax: Axes, res: Result | Scene, name: str, label: str | None = None, period: float | None = None
) -> Axes:
    """Plot one column of :meth:`Result.columns` (or a joint speed ``|v|[J]``) against the first driver's input.

    A simulated motion (:func:`linkagekit.simulate`) is plotted against its time, in seconds.
    Samples that do not assemble (or sit at a singular position, for rates and forces) are
    gaps in the line, shaded grey where the mechanism does not assemble.  A link angle is
    not drawn across its jump from +180 to -180 degrees (or ``period``, for other columns).
    """
    ax = _axes(ax)
    sc = _scene(res)
    if not isinstance(name, str) or name not in sc.columns:
        raise UnknownNameError(f"no quantity {name!r} (quantities: {', '.join(list(sc.columns)[:12])}, ...)")
    if label is not None and not isinstance(label, str):
        raise InputError(f"label: expected text, got {type(label).__name__}")
    if period is not None and (isinstance(period, bool) or not isinstance(period, numbers.Real) or not period > 0):
        raise InputError(f"period: expected a positive number, got {period!r}")
    x = sc.x
    y = np.asarray(sc.columns[name], float)
    if period is None and name in sc.catalogue:
        period = sc.catalogue[name].period
    if sc.breaks:  # no line across a gap between two samples
        cut = [b + 1 for b in sc.breaks]
        x, y = np.insert(x, cut, np.nan), np.insert(y, cut, np.nan)
    xb, yb = broken_at_wraps(x, y, period if period is None else float(period))
    ax.plot(xb, yb, label=_t(label or name), linewidth=1.4)
    for lo, hi in sc.shaded:
        ax.axvspan(lo, hi, color="#e8e8e8", zorder=0, linewidth=0)
    ax.set_xlabel(_t(f"{sc.x_name} [{sc.x_unit}]"))
    unit = sc.units.get(name, "")
    ax.set_ylabel(_t(f"{name} [{unit}]" if unit else name))
    ax.grid(True, linewidth=0.4, alpha=0.6)
    return ax


def plot_quantities(ax: Axes, res: Result | Scene, names: Sequence[str]) -> Axes:
    """Several quantities on one Axes, with a legend (their units should agree)."""
    sc = _scene(res)
    for n in names:
        plot_quantity(ax, sc, n)
    units = {sc.units.get(n, "") for n in names}
    if len(names) > 1:
        ax.set_ylabel(" / ".join(sorted(units)) if units != {""} else "")
        ax.legend(fontsize=7, loc="best")
    _roundoff_range(ax, np.concatenate([np.asarray(sc.columns[n], float) for n in names]))
    return ax


#: values whose spread is below this fraction of their magnitude (or, all below it in magnitude, in display units)
#: are drawn as the constant they are, not zoomed into: as the tables print round-off as 0
PLOT_ROUNDOFF = 1e-9


def _roundoff_range(ax: Axes, y: np.ndarray) -> None:
    """A y-range that shows rounding as rounding: a constant (a coupler that only translates, a constant force) drew
    its last digits' noise as full-height jags under a '1e-13' or '1e-9+4e2' offset label."""
    y = y[np.isfinite(y)]
    if not len(y):
        return
    top = float(np.max(np.abs(y)))
    if top < PLOT_ROUNDOFF:  # zero, to rounding
        ax.set_ylim(-1.0, 1.0)
    elif float(np.ptp(y)) < PLOT_ROUNDOFF * top:  # a constant, to rounding
        mid = float(np.mean(y))
        ax.set_ylim(mid - 0.05 * top, mid + 0.05 * top)
    else:
        return
    ax.ticklabel_format(axis="y", useOffset=False)


def mechanism_figure(
    res: Result,
    poses: Result | None = None,
    size: float = 6.0,
    dpi: float = DPI,
    pixels: tuple[int, int | None] | None = None,
) -> Figure:
    """A figure of the mechanism with the paths of its joints over the sweep ``res``.

    The mechanism is drawn at each sample of ``poses`` (a result at a few inputs; earlier
    ones faded), by default at the reference pose's own input, whether or not the sweep
    passes through it (else, where the pose's input does not assemble, at the first sample
    that does); a simulated motion (:func:`linkagekit.simulate`) at its first time.
    ``size`` is the width in inches, ``dpi`` the pixels per inch, ``pixels``
    an exact size (:func:`figure_inches`).
    """
    sc = build_scene(res)
    if poses is None and not sc.timed:  # a simulated motion is drawn where it starts, with its time
        poses = _at_pose(res.mechanism)
    pose_scene = build_scene(poses) if poses is not None else None
    bounds = sc.bounds
    if pose_scene is not None:
        b = pose_scene.bounds
        bounds = (min(bounds[0], b[0]), min(bounds[1], b[1]), max(bounds[2], b[2]), max(bounds[3], b[3]))
    fig = Figure(figsize=figure_inches(size, size * _aspect(sc), dpi, pixels), dpi=dpi)
    ax = fig.add_axes((0.02, 0.02, 0.96, 0.9))
    Drawing(ax, sc, labels=False, curves=True, ground_labels=True)  # the curves, the ground and its names
    if pose_scene is None:
        shown, indices = sc, [_sample(sc, None)]
    else:
        shown, indices = pose_scene, list(range(pose_scene.n))
    for k, i in enumerate(indices):
        d = Drawing(ax, shown, labels=k == len(indices) - 1, curves=False, ground=False, size=sc.size)
        d.update(i)
        if k < len(indices) - 1:
            for a in d.artists():
                a.set_alpha(0.3)
            d.note.set_visible(False)
    ax.set_xlim(bounds[0], bounds[2])
    ax.set_ylim(bounds[1], bounds[3])
    i = indices[-1]

    def inputs_at(i: int) -> str:
        return shown.sample_text(i)

    # one note for every input drawn that does not assemble (each drawing's own would overlap), and where a simulated
    # motion stopped (its curves end there: the picture alone looked like the whole time asked)
    missing = [inputs_at(k) for k in indices if not shown.assembled[k]]
    notes = ([_t("does not assemble at " + "; ".join(missing))] if missing else []) + [stop_note(sc.stopped)]
    d.note.set_text("; ".join(n for n in notes if n))
    _title(fig, f"{title_name(sc.name)}  ({inputs_at(i)})")
    return fig


def stop_note(stopped: str | None) -> str:
    """The picture's note for a simulated motion that stopped early: where (the line's first two clauses), or "".

    >>> stop_note("simulate: stopped at t = 0.486796 s, crank = 78.5 deg: the model ... (toggle)")
    'the motion stopped at t = 0.486796 s, crank = 78.5 deg'
    """
    if not stopped:
        return ""
    where = stopped.removeprefix("simulate: ").split(": ")[0]
    return _t(f"the motion {where}")


#: colour of synthesis targets and of their error segments
TARGET_COLOR = "#0050b4"


def synthesis_figure(
    res: Result, targets: Any, errors: Any = None, closed: bool = False, tracer: str = "P", size: float = 6.0
) -> Figure:
    """The mechanism of a synthesis with its curves, and the targets on them.

    ``res``: the synthesised mechanism over a crank turn; ``targets`` (m, 2); ``errors``
    (m,) the distances the synthesis found (in the title, in the mechanism's length unit). Each target is a
    numbered ring; a thin segment joins it to the nearest sampled point of the tracer's curve, so a target
    the curve misses shows how far off it is.
    """
    fig = mechanism_figure(res, size=size)
    ax = fig.axes[0]
    t = np.asarray(targets, float)
    P = res.xy(tracer)
    ok = np.all(np.isfinite(P), axis=1)
    if ok.any():
        d = np.hypot(P[ok][None, :, 0] - t[:, None, 0], P[ok][None, :, 1] - t[:, None, 1])
        near = P[ok][np.argmin(d, axis=1)]
        for (x, y), (u, v) in zip(t, near, strict=True):
            ax.plot([x, u], [y, v], color=TARGET_COLOR, linewidth=0.8, zorder=6)
    ax.plot(t[:, 0], t[:, 1], "o", markersize=6, markerfacecolor="none", markeredgecolor=TARGET_COLOR, zorder=7)
    for i, (x, y) in enumerate(t):
        ax.annotate(str(i + 1), (x, y), xytext=(4, 4), textcoords="offset points", fontsize=7, color=TARGET_COLOR)
    x0, x1 = ax.get_xlim()
    y0, y1 = ax.get_ylim()
    pad = 0.03 * max(x1 - x0, y1 - y0)
    ax.set_xlim(min(x0, t[:, 0].min() - pad), max(x1, t[:, 0].max() + pad))
    ax.set_ylim(min(y0, t[:, 1].min() - pad), max(y1, t[:, 1].max() + pad))
    if errors is not None:
        e = np.asarray(errors, float)
        kind = "closed" if closed else "open"
        u = res.mechanism.length_unit
        _title(fig, f"{len(t)} targets ({kind}): max error {np.max(e):.4g} {u}, rms {np.sqrt(np.mean(e * e)):.4g} {u}")
    return fig


def function_figure(curve: Any, pairs: Any, errors: Any, title: str = "", size: float = 6.0) -> tuple[Figure, Axes]:
    """Function generation: the output angle against the input angle, the wanted pairs, and the errors.

    ``curve`` (k, 2): input and output angle (degrees) of the mechanism, densely; ``pairs``
    (n, 2): the wanted input, output pairs; ``errors`` (n,): the output-angle error at each
    pair (degrees).  The upper axes (returned, for :func:`save_figure`'s pixel map) draw the
    curve with the pairs as rings; the lower axes the error at each pair.
    """
    fig = Figure(figsize=(size, size * 0.9), dpi=DPI)
    top, bottom = fig.subplots(2, 1, height_ratios=[3, 1.4], sharex=True)
    c, p, e = np.asarray(curve, float), np.asarray(pairs, float), np.asarray(errors, float)
    top.plot(c[:, 0], c[:, 1], color=CURVE_COLOR, linewidth=1.6, zorder=3)
    top.plot(p[:, 0], p[:, 1], "o", markersize=8, markerfacecolor="none", markeredgecolor=TARGET_COLOR, zorder=4)
    top.set_ylabel("output [deg]")
    top.grid(True, color="#dddddd", linewidth=0.5)
    bottom.axhline(0.0, color="#999999", linewidth=0.8)
    bottom.vlines(p[:, 0], 0.0, e, color=TARGET_COLOR, linewidth=1.2)
    bottom.plot(p[:, 0], e, "o", markersize=4, color=TARGET_COLOR)
    worst = float(np.max(np.abs(e))) if len(e) else 0.0
    for s in (-1.0, 1.0):
        bottom.axhline(s * worst, color=CURVE_COLOR, linewidth=0.8, linestyle="--")
    bottom.set_ylim(-1.25 * worst - 1e-12, 1.25 * worst + 1e-12)
    bottom.set_xlabel("input [deg]")
    bottom.set_ylabel("error [deg]")
    _title(fig, title or f"{len(p)} pairs: max error {worst:.4g} deg")
    return fig, top


#: colour of the coupler's achieved frames (P -> Q) at the poses of a motion synthesis
ACHIEVED_COLOR = "#1a7f37"
#: a pose's frame: its line this fraction of the poses' diagonal long, its second axis half that
FRAME_LENGTH = 0.12


def motion_figure(
    mech: Any, poses: Any, inputs: Any, closed: bool = False, size: float = 6.0, dpi: float = DPI
) -> Figure:
    """A motion synthesis: the four-bar, the paths of ``P`` and ``Q``, and each pose as a small frame.

    ``poses`` (m, 3): ``x, y, angle`` (degrees); ``inputs`` (m,): the crank angle (degrees) at
    each pose. A wanted pose is drawn in ``TARGET_COLOR``: a ring at ``(x, y)``, a line of
    ``FRAME_LENGTH`` diagonals along ``angle`` and a shorter one at right angles (so a frame
    shows its orientation and its handedness); the coupler's achieved frame at the pose's
    crank angle (P to the direction of Q) in ``ACHIEVED_COLOR``, dashed.
    """
    from ..api import analyze

    P = np.asarray(poses, float)
    ins = np.asarray(inputs, float)
    driver = mech.drivers[0].name
    lo, hi = float(np.min(ins)), float(np.max(ins))
    sweep = np.linspace(lo, lo + 360.0, 721) if closed else np.linspace(lo, hi, max(2, int(4 * (hi - lo)) + 2))
    res = analyze(mech, {driver: sweep}, rates=False, dynamics=False)
    at = analyze(mech, {driver: ins[:1]}, rates=False, dynamics=False)
    fig = mechanism_figure(res, at, size=size, dpi=dpi)
    ax = fig.axes[0]
    diag = float(np.hypot(np.ptp(P[:, 0]), np.ptp(P[:, 1]))) or 1.0
    ell = FRAME_LENGTH * diag
    u = np.exp(1j * np.radians(P[:, 2]))
    z = P[:, 0] + 1j * P[:, 1]
    for i, (zi, ui) in enumerate(zip(z, u, strict=True)):
        for end in (zi + ell * ui, zi + 0.5 * ell * ui * 1j):
            ax.plot([zi.real, end.real], [zi.imag, end.imag], color=TARGET_COLOR, linewidth=1.4, zorder=7)
        ax.annotate(str(i + 1), (zi.real, zi.imag), xytext=(-9, 4), textcoords="offset points", fontsize=7,
                    color=TARGET_COLOR)  # fmt: skip
    ax.plot(z.real, z.imag, "o", markersize=5, markerfacecolor="none", markeredgecolor=TARGET_COLOR, zorder=7)
    got = analyze(mech, {driver: ins}, rates=False, dynamics=False)
    p0, q0 = got.point("P"), got.point("Q")
    w = (q0 - p0) / np.abs(q0 - p0)
    for a, b in zip(p0, p0 + ell * w, strict=True):
        ax.plot([a.real, b.real], [a.imag, b.imag], color=ACHIEVED_COLOR, linewidth=1.0, linestyle="--", zorder=8)
    x0, x1 = ax.get_xlim()
    y0, y1 = ax.get_ylim()
    pad = ell * 1.2
    ax.set_xlim(min(x0, z.real.min() - pad), max(x1, z.real.max() + pad))
    ax.set_ylim(min(y0, z.imag.min() - pad), max(y1, z.imag.max() + pad))
    kind = "closed" if closed else "open"
    _title(fig, f"{len(P)} poses ({kind}): {title_name(mech.name) if mech.name else ''}")
    return fig


def _at_pose(mech: Any) -> Result | None:
    """The mechanism solved at its pose's own inputs (positions only), or None where it does not assemble there."""
    from ..api import analyze, pose_inputs

    res = analyze(mech, {k: [v] for k, v in pose_inputs(mech).items()}, rates=False, dynamics=False)
    return res if bool(np.all(res.assembled)) else None


def _aspect(sc: Scene) -> float:
    x0, y0, x1, y1 = sc.bounds
    return float(np.clip((y1 - y0) / max(x1 - x0, 1e-12), 0.4, 1.6))


def modes_figure(
    mech: Any,
    at: Any = None,
    mirrors: bool = False,
    size: float = 3.2,
    dpi: float = DPI,
    pixels: tuple[int, int | None] | None = None,
) -> Figure:
    """Every distinct assembly mode at one input, side by side (as in the figures of seeds 000 and 004).

    Each panel is the mechanism in one mode (positions from :func:`linkagekit.modes`),
    titled with its signs (and a numerical group's mode index); the file's own mode is marked ``(pose)``.
    Each panel is ``size`` inches wide (so the figure grows with the number of panels, up to
    four a row), ``dpi`` pixels per inch; ``pixels`` an exact size of the whole figure.
    """
    from ..checks import modes as find_modes

    found = find_modes(mech, at, mirrors=mirrors)
    shown = [m for m in found.modes if m.assembled and m.same_as is None]
    units = input_units(mech)
    inp = ", ".join(f"{k} = {v:g} {units[k]}" for k, v in found.input.items())
    if not shown:
        raise InputError(f"modes: the mechanism does not assemble at {inp}")
    if len(shown) > MAX_MODE_PANELS:
        raise InputError(
            f"modes: {len(shown)} distinct assembly modes at {inp}, more than a figure shows ({MAX_MODE_PANELS}); "
            "'linkagekit modes' lists them all"
        )
    names = mech.joint_names
    xy = np.array([[m.joints[j] if m.joints[j] is not None else (np.nan, np.nan) for j in names] for m in shown])
    cols = min(len(shown), 4)
    rows = math.ceil(len(shown) / cols)
    sc = _static_scene(mech, xy, found.input)
    fig = Figure(figsize=figure_inches(size * cols, size * rows * _aspect(sc) + 0.5, dpi, pixels), dpi=dpi)
    axes = fig.subplots(rows, cols, squeeze=False)
    for k, ax in enumerate(axes.ravel()):
        if k >= len(shown):
            ax.set_axis_off()
            continue
        d = Drawing(ax, sc, curves=False)
        d.update(k)
        m = shown[k]
        signs = " ".join(f"{j}{'+' if s > 0 else '-'}" for j, s in m.signs.items())
        if m.mirrors:
            signs += " " + " ".join(f"{ln}{'~' if s < 0 else ''}" for ln, s in m.mirrors.items() if s < 0)
        for g, gi in (m.groups or {}).items():  # a numerical group's mode: its index among the group's
            signs += f" {g} " + (f"{gi['index'] + 1}/{gi['of']}" if gi["of"] > 0 else "(continued)")
        signs = signs.strip()
        ax.set_title(_t(f"{k + 1}: {signs or 'the only mode'}{' (pose)' if m.reference else ''}"), fontsize=9)
    _title(fig, f"{title_name(mech.name)}: {len(shown)} assembly mode(s) at {inp}")
    return fig


def _static_scene(mech: Any, xy: np.ndarray, inputs: dict[str, float]) -> Scene:
    """A scene whose samples are given positions (the modes), with guides from their links."""
    from .scene import SceneSlider, _gaps, _ground_xy, _pose_angle, path_kinds, scene_links

    names = mech.joint_names
    n = xy.shape[0]
    z = xy[..., 0] + 1j * xy[..., 1]
    sliders = []
    for s in mech.sliders:
        if s.on == "ground":
            o = np.full(n, mech.joints[s.through])
            d = np.full(n, s.direction)
        else:
            on = mech.link(s.on)
            if len(on.joints) >= 2:
                a, b = names.index(on.joints[0]), names.index(on.joints[1])
                turn = np.exp(1j * (np.angle(z[:, b] - z[:, a]) - _pose_angle(mech, s.on)))
            else:
                turn = np.ones(n)
            ref = on.joints[0]
            o = z[:, names.index(ref)] + turn * (mech.joints[s.through] - mech.joints[ref])
            d = turn * s.direction
        t = ((z[:, names.index(s.through)] - o) * np.conj(d)).real
        ext = float(np.nanmax(np.ptp(xy.reshape(-1, 2), axis=0)))
        span = (float(np.nanmin(t)) - 0.2 * ext, float(np.nanmax(t)) + 0.2 * ext)
        sliders.append(
            SceneSlider(s.link, s.on, s.through, np.stack([o.real, o.imag], -1), np.stack([d.real, d.imag], -1), span)
        )
    fin = xy[np.isfinite(xy[..., 0])]
    x0, y0 = fin.min(axis=0)
    x1, y1 = fin.max(axis=0)
    pad = 0.15 * max(x1 - x0, y1 - y0, 1e-9)
    coupler, other = path_kinds(mech)
    assembled = np.isfinite(xy[..., 0]).all(axis=1)
    return Scene(
        name=mech.name,
        length_unit=mech.length_unit,
        angle_unit=mech.angle_unit,
        joints=names,
        ground_joints=mech.link("ground").joints,
        ground_xy=_ground_xy(mech),
        links=scene_links(mech),
        sliders=tuple(sliders),
        drivers=tuple(inputs),
        x_driver=next(iter(inputs), ""),
        input_units={k: "" for k in inputs},
        inputs={k: np.full(n, v) for k, v in inputs.items()},
        xy=xy,
        assembled=assembled,
        coupler_curves=coupler,
        other_paths=other,
        gaps=_gaps(assembled),
        bounds=(float(x0 - pad), float(y0 - pad), float(x1 + pad), float(y1 + pad)),
        columns={},
        units={},
    )


def quantities_figure(
    res: Result | Scene,
    groups: Sequence[Sequence[str]],
    size: float = 6.0,
    dpi: float = DPI,
    pixels: tuple[int, int | None] | None = None,
) -> Figure:
    """One plot per group of quantities (column names), stacked, against the first driver's input (or the time).

    ``size`` is the width in inches, ``dpi`` the pixels per inch, ``pixels`` an exact size (:func:`figure_inches`).
    """
    sc = _scene(res)
    fig = Figure(figsize=figure_inches(size, 2.6 * len(groups) + 0.4, dpi, pixels), dpi=dpi)
    axes = fig.subplots(len(groups), 1, squeeze=False)[:, 0]
    for ax, names in zip(axes, groups, strict=True):
        plot_quantities(ax, sc, names)
    _title(fig, title_name(sc.name))
    fig.tight_layout()
    return fig


def data_to_pixels(ax: Axes) -> list[float]:
    """``[sx, tx, sy, ty]``: pixel ``(col, row)`` of a point ``(x, y)`` is ``(sx x + tx, sy y + ty)``.

    Rows count from the top of the image (as in a PNG); valid after the figure is drawn.
    """
    fig = ax.figure
    h = fig.bbox.height
    (x0, y0), (x1, y1) = ax.transData.transform([(0.0, 0.0), (1.0, 1.0)])
    return [float(x1 - x0), float(x0), float(-(y1 - y0)), float(h - y0)]


def save_figure(fig: Figure, path: str | Path, ax: Axes | None = None) -> Path:
    """Save a figure (format from the suffix: png, svg, pdf) atomically.

    For a PNG of a mechanism drawing, the map from file units to pixels of ``ax`` is stored
    in the image's metadata under :data:`TRANSFORM_KEY` (so a test or a script can find
    where a computed point is drawn).
    """
    import json

    from matplotlib.backends.backend_agg import FigureCanvasAgg

    path = Path(path)
    fmt = path.suffix.lower().lstrip(".")
    if fmt not in ("png", "svg", "pdf"):
        raise InputError(f"{path}: the output must end in .png, .svg or .pdf")
    FigureCanvasAgg(fig)
    fig.canvas.draw()
    meta: dict[str, Any] = {}
    if fmt == "png" and ax is not None:
        meta[TRANSFORM_KEY] = json.dumps(data_to_pixels(ax))
    with atomic_output(path) as tmp:
        fig.savefig(tmp, format=fmt, metadata=meta or None, facecolor=BACKGROUND)
    return path
