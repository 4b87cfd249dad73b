"""Animations of a solved sweep: GIF (Pillow, always there with matplotlib) and MP4 (through an ffmpeg).

The static parts (ground, guides, curves) are drawn once into a background; each frame
restores it and draws only the moving artists (blitting on the Agg canvas), then hands
the pixels to the encoder.  ``FuncAnimation.save`` would redraw the whole figure for every
frame, about five times slower.

An ffmpeg is looked for on ``PATH``, then in the optional ``imageio-ffmpeg`` package
(``pip install "linkagekit[video]"``, which bundles a binary).

>>> import linkagekit as lk, tempfile, os
>>> from linkagekit.viz.animate import animate
>>> res = lk.analyze(lk.load("examples/seed000_fourbar.yaml"), {"crank": range(0, 360, 10)})
>>> with tempfile.TemporaryDirectory() as d:
...     out = animate(res, os.path.join(d, "fourbar.gif"))
...     out.stat().st_size > 1000
True
"""

from __future__ import annotations

import numbers
import os
import shutil
import subprocess
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from ..errors import InputError, LinkageError
from ..files import atomic_output
from ..result import Result
from .scene import Scene, build_scene

if TYPE_CHECKING:  # pragma: no cover - matplotlib is imported where a picture is made
    from matplotlib.figure import Figure

#: the fewest frames an animation has (spec: at least 36)
MIN_FRAMES = 36
#: the most frames (a GIF holds its frames in memory: about 0.4 MB each at the default size)
MAX_FRAMES = 1000
#: a GIF stores frame times in hundredths of a second, and viewers slow down times under 2
MAX_GIF_FPS = 50.0


class VideoError(LinkageError):
    """No ffmpeg for an MP4, or the encoder failed."""

    exit_code = 1


def find_ffmpeg() -> str | None:
    """The path of an ffmpeg: on PATH, else imageio-ffmpeg's bundled binary, else None."""
    exe = shutil.which("ffmpeg")
    if exe:
        return exe
    try:
        import imageio_ffmpeg
    except ImportError:
        return None
    try:
        return str(imageio_ffmpeg.get_ffmpeg_exe())
    except (RuntimeError, OSError):
        return None


class _AggCanvas(Protocol):
    """The blitting calls of matplotlib's Agg canvas, typed (``backend_agg`` has no annotations)."""

    def draw(self) -> None: ...
    def copy_from_bbox(self, bbox: Any) -> Any: ...
    def restore_region(self, region: Any) -> None: ...
    def buffer_rgba(self) -> memoryview: ...


def _agg_canvas(fig: Figure) -> _AggCanvas:
    """An Agg canvas for *fig*, seen through :class:`_AggCanvas` (mypy checks that it fits)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    return FigureCanvasAgg(fig)


class Frames:
    """RGB frames (height, width, 3) of a scene, one per sample; width and height even.

    ``render(i)`` draws sample ``i`` (static parts from a saved background, the moving
    artists blitted over it); iterating gives every sample in order.
    """

    def __init__(self, scene: Scene, size: float = 6.0, dpi: int = 100) -> None:
        from matplotlib.figure import Figure

        from .draw import Drawing, _aspect, _t, title_name

        self.scene = scene
        w = int(round(size * dpi / 2)) * 2
        h = int(round(size * _aspect(scene) * dpi / 2)) * 2
        fig = Figure(figsize=(w / dpi, h / dpi), dpi=dpi)
        self.canvas = _agg_canvas(fig)
        self.ax = ax = fig.add_axes((0.02, 0.02, 0.96, 0.9))
        fig.suptitle(_t(title_name(scene.name)), fontsize=10)
        self.drawing = Drawing(ax, scene, animated=True)
        # the inputs of the frame, and a thin bar of how far through the sweep it is (so two
        # frames at one input still differ, and no GIF encoder merges them)
        self.label = ax.text(0.0, 1.0, "", transform=ax.transAxes, ha="left", va="top", fontsize=9, animated=True)
        (self.bar,) = ax.plot(
            [0.0, 0.0],
            [0.0, 0.0],
            transform=ax.transAxes,
            color="#999999",
            linewidth=3,
            solid_capstyle="butt",
            clip_on=False,
            animated=True,
        )
        self.canvas.draw()
        self.background = self.canvas.copy_from_bbox(fig.bbox)
        self._t = _t

    def render(self, i: int) -> np.ndarray:
        sc = self.scene
        self.canvas.restore_region(self.background)
        self.label.set_text(self._t(sc.sample_text(i)))
        self.bar.set_xdata([0.0, (i + 1) / sc.n])
        for artist in [*self.drawing.update(i), self.label, self.bar]:
            self.ax.draw_artist(artist)
        return np.asarray(self.canvas.buffer_rgba())[..., :3].copy()

    def __iter__(self) -> Iterator[np.ndarray]:
        for i in range(self.scene.n):
            yield self.render(i)


def frames(scene: Scene, size: float = 6.0, dpi: int = 100) -> Iterator[np.ndarray]:
    """RGB frames (height, width, 3) of the scene, one per sample (see :class:`Frames`)."""
    return iter(Frames(scene, size, dpi))


def _palette(images: Frames) -> tuple[Any, np.ndarray]:
    """One palette for every frame, and a table of the colours it holds exactly.

    The drawing's own colours come first, exactly, then the median-cut colours of a few
    frames spread over the sweep.  A palette from the first frame alone missed the colours
    of links that appear later (a first frame that does not assemble has no links).  The
    table maps a 24-bit colour to its palette index (255: not exact); Pillow's mapping to a
    palette is approximate (white came out as 252, 252, 252), so exact colours go by the table.
    """
    from PIL import Image

    from .draw import CURVE_COLOR, PALETTE, PATH_COLOR

    exact = ["#ffffff", "#000000", "#b00000", "#999999", "#dddddd", "#444444", CURVE_COLOR, PATH_COLOR, *PALETTE]
    exact = list(dict.fromkeys(exact))
    fixed = [int(c[k : k + 2], 16) for c in exact for k in (1, 3, 5)]
    n = images.scene.n
    picks = sorted({int(round(k)) for k in np.linspace(0, n - 1, min(n, 8))})
    montage = Image.fromarray(np.concatenate([images.render(i) for i in picks], axis=0))
    cut = montage.quantize(colors=255 - len(exact), method=Image.Quantize.MEDIANCUT).getpalette() or []
    pal = Image.new("P", (1, 1))
    pal.putpalette((fixed + list(cut))[: 3 * 255])
    table = np.full(1 << 24, 255, dtype=np.uint8)
    keys = [int(c[1:], 16) for c in exact]
    table[keys] = np.arange(len(keys), dtype=np.uint8)
    return pal, table


def _indexed(rgb: np.ndarray, palette: Any, table: np.ndarray) -> Any:
    """A frame as palette indices: the exact colours by the table, the others by Pillow."""
    from PIL import Image

    q = np.asarray(Image.fromarray(rgb).quantize(palette=palette, dither=Image.Dither.NONE))
    key = (rgb[..., 0].astype(np.int32) << 16) | (rgb[..., 1].astype(np.int32) << 8) | rgb[..., 2]
    hit = table[key]
    out = Image.fromarray(np.where(hit != 255, hit, q).astype(np.uint8), mode="P")
    out.putpalette(palette.getpalette())
    return out


def frame_times(n: int, fps: float) -> list[int]:
    """The ``n`` frames' times in ms, whole hundredths of a second (a GIF's unit) that add up to ``k / fps`` after
    every frame ``k`` to the nearest hundredth: 30 fps alternates 30 and 40 ms (a single 30 ms played 33.3 fps).

    >>> frame_times(6, 30.0), sum(frame_times(40, 30.0))
    ([30, 40, 30, 30, 40, 30], 1330)
    """
    ends = np.round(np.arange(1, n + 1) * 100.0 / fps) * 10  # each frame's end, in whole hundredths
    return [int(t) for t in np.diff(np.concatenate([[0.0], ends]))]


def _write_gif(images: Frames, path: Path, fps: float, tick: Callable[[], None]) -> None:
    palette, table = _palette(images)
    gif = []
    for rgb in images:
        gif.append(_indexed(rgb, palette, table))
        tick()
    gif[0].save(
        path,
        format="GIF",
        save_all=True,
        append_images=gif[1:],
        duration=frame_times(len(gif), fps),
        loop=0,
        optimize=False,
        disposal=1,
    )


def _write_mp4(images: Frames, path: Path, fps: float, tick: Callable[[], None], ffmpeg: str) -> None:
    proc: subprocess.Popen[bytes] | None = None
    try:
        for rgb in images:
            if proc is None:
                h, w = rgb.shape[:2]
                cmd = [
                    ffmpeg,
                    "-y",
                    "-loglevel",
                    "error",
                    "-f",
                    "rawvideo",
                    "-pix_fmt",
                    "rgb24",
                    "-s",
                    f"{w}x{h}",
                    "-r",
                    f"{fps:g}",
                    "-i",
                    "-",
                    "-an",
                    "-vcodec",
                    "libx264",
                    "-pix_fmt",
                    "yuv420p",
                    "-f",
                    "mp4",
                    str(path),
                ]
                try:
                    proc = subprocess.Popen(
                        cmd, stdin=subprocess.PIPE, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE
                    )
                except OSError as exc:
                    raise VideoError(f"cannot run ffmpeg ({ffmpeg}): {exc.strerror or exc}") from None
            assert proc.stdin is not None
            proc.stdin.write(rgb.tobytes())
            tick()
        if proc is None:
            raise VideoError("no frames to encode")
        assert proc.stdin is not None and proc.stderr is not None
        proc.stdin.close()
        err = proc.stderr.read().decode(errors="replace").strip()
        if proc.wait() != 0:
            raise VideoError(f"ffmpeg failed: {err.splitlines()[-1] if err else 'exit ' + str(proc.returncode)}")
    except BrokenPipeError:
        assert proc is not None and proc.stderr is not None
        err = proc.stderr.read().decode(errors="replace").strip()
        proc.wait()
        raise VideoError(f"ffmpeg failed: {err.splitlines()[-1] if err else 'it stopped reading'}") from None
    finally:
        if proc is not None and proc.poll() is None:
            proc.kill()
            proc.wait()


def animate(
    res: Result | Scene,
    path: str | Path,
    fps: float = 24.0,
    size: float = 6.0,
    dpi: int = 100,
    progress: Callable[[int, int], None] | None = None,
) -> Path:
    """Write an animation of the sweep, one frame per sample, as a GIF or an MP4 (by the suffix).

    Parameters
    ----------
    res : Result or Scene
        One design's sweep, or a simulated motion (:func:`linkagekit.simulate`): its frames
        follow the time axis, one per output time, each labelled with its time.
    path : str or Path
        Ends in ``.gif`` or ``.mp4``; written atomically (a temporary file, then renamed).
    fps : float
        Frames per second.
    size, dpi : float, int
        Width in inches and pixels per inch.
    progress : callable, optional
        Called as ``progress(done, total)`` after each frame.

    Raises
    ------
    InputError
        For another suffix or bad numbers; :class:`VideoError` when an MP4 has no ffmpeg.
    """
    path, fmt = _output(path)
    _check_options(fmt, fps, size, dpi, progress)
    ffmpeg = _ffmpeg() if fmt == ".mp4" else None
    scene = res if isinstance(res, Scene) else build_scene(res)
    if scene.n > MAX_FRAMES:
        raise InputError(
            f"{scene.n} samples make {scene.n} frames, more than an animation takes ({MAX_FRAMES}): "
            "animate a coarser sweep"
        )
    tick = _counter(progress, scene.n)
    with atomic_output(path) as tmp:
        images = Frames(scene, size=float(size), dpi=int(dpi))
        if ffmpeg is None:
            _write_gif(images, tmp, float(fps), tick)
        else:
            _write_mp4(images, tmp, float(fps), tick, ffmpeg)
    return path


def _output(path: str | Path) -> tuple[Path, str]:
    """The animation's file and its format (``.gif`` or ``.mp4``, by the suffix)."""
    if not isinstance(path, str | os.PathLike):
        raise InputError(f"path: expected a file name ending in .gif or .mp4, got {type(path).__name__}")
    path = Path(path)
    fmt = path.suffix.lower()
    if fmt not in (".gif", ".mp4"):
        raise InputError(f"{path}: the output must end in .gif or .mp4")
    return path, fmt


def _check_options(fmt: str, fps: float, size: float, dpi: int, progress: object) -> None:
    """Raise an InputError for a number out of its range, or a *progress* that is not a function."""
    top_fps = MAX_GIF_FPS if fmt == ".gif" else 120.0
    for what, v, lo, hi in (("fps", fps, 0.1, top_fps), ("size", size, 1.0, 40.0), ("dpi", dpi, 20, 600)):
        if isinstance(v, bool) or not isinstance(v, numbers.Real) or not lo <= float(v) <= hi:
            extra = " (a GIF stores frame times in hundredths of a second)" if what == "fps" and fmt == ".gif" else ""
            raise InputError(f"{what}: expected a number in [{lo:g}, {hi:g}]{extra}, got {v!r}")
    if progress is not None and not callable(progress):
        raise InputError(f"progress: expected a function progress(done, total), got {type(progress).__name__}")


def _ffmpeg() -> str:
    """The ffmpeg an MP4 needs (a VideoError when there is none)."""
    ffmpeg = find_ffmpeg()
    if ffmpeg is None:
        raise VideoError(
            'an MP4 needs ffmpeg: install it (e.g. apt install ffmpeg) or pip install "linkagekit[video]"; '
            "or write a .gif"
        )
    return ffmpeg


def _counter(progress: Callable[[int, int], None] | None, total: int) -> Callable[[], None]:
    """A function to call after each frame: it tells *progress* (if any) how many of *total* are done."""
    done = 0

    def tick() -> None:
        nonlocal done
        done += 1
        if progress is not None:
            progress(done, total)

    return tick
