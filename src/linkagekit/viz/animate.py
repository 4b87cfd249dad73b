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

import shutil
import subprocess
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np

from ..errors import InputError, LinkageError
from ..files import atomic_output
from ..result import Result
from .scene import Scene, build_scene

#: the fewest frames an animation has (spec: at least 36)
MIN_FRAMES = 36


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


def frames(scene: Scene, size: float = 6.0, dpi: int = 100) -> Iterator[np.ndarray]:
    """RGB frames (height, width, 3) of the scene, one per sample; width and height even."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from .draw import Drawing, _aspect

    w = int(round(size * dpi / 2)) * 2
    h = int(round(size * _aspect(scene) * dpi / 2)) * 2
    fig = Figure(figsize=(w / dpi, h / dpi), dpi=dpi)
    canvas = FigureCanvasAgg(fig)
    ax = fig.add_axes((0.02, 0.02, 0.96, 0.9))
    fig.suptitle(scene.name or "mechanism", fontsize=10)
    drawing = Drawing(ax, scene, animated=True)
    # the inputs of the frame, and a thin bar of how far through the sweep it is (so two
    # frames at one input still differ, and no GIF encoder merges them)
    label = ax.text(0.0, 1.0, "", transform=ax.transAxes, ha="left", va="top", fontsize=9, animated=True)
    (bar,) = ax.plot(
        [0.0, 0.0],
        [0.0, 0.0],
        transform=ax.transAxes,
        color="#999999",
        linewidth=3,
        solid_capstyle="butt",
        clip_on=False,
        animated=True,
    )
    canvas.draw()
    background = canvas.copy_from_bbox(fig.bbox)
    for i in range(scene.n):
        canvas.restore_region(background)
        label.set_text(", ".join(f"{k} = {scene.inputs[k][i]:.6g} {scene.input_units[k]}" for k in scene.drivers))
        bar.set_xdata([0.0, (i + 1) / scene.n])
        for artist in [*drawing.update(i), label, bar]:
            ax.draw_artist(artist)
        yield np.asarray(canvas.buffer_rgba())[..., :3].copy()


def _write_gif(images: Iterator[np.ndarray], path: Path, fps: float, tick: Callable[[], None]) -> None:
    from PIL import Image

    first: Image.Image | None = None
    rest: list[Image.Image] = []
    palette: Image.Image | None = None
    for rgb in images:
        img = Image.fromarray(rgb)
        if palette is None:
            palette = img.quantize(colors=255, method=Image.Quantize.MEDIANCUT)
            first = palette
        else:
            rest.append(img.quantize(palette=palette, dither=Image.Dither.NONE))
        tick()
    assert first is not None
    first.save(
        path,
        format="GIF",
        save_all=True,
        append_images=rest,
        duration=round(1000 / fps),
        loop=0,
        optimize=False,
        disposal=1,
    )


def _write_mp4(images: Iterator[np.ndarray], path: Path, fps: float, tick: Callable[[], None], ffmpeg: str) -> None:
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
                proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
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
        One design's sweep.
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
    path = Path(path)
    fmt = path.suffix.lower()
    if fmt not in (".gif", ".mp4"):
        raise InputError(f"{path}: the output must end in .gif or .mp4")
    for what, v, lo, hi in (("fps", fps, 0.1, 120.0), ("size", size, 1.0, 40.0), ("dpi", dpi, 20, 600)):
        if not isinstance(v, int | float) or not lo <= float(v) <= hi:
            raise InputError(f"{what}: expected a number in [{lo:g}, {hi:g}], got {v!r}")
    ffmpeg = None
    if fmt == ".mp4":
        ffmpeg = find_ffmpeg()
        if ffmpeg is None:
            raise VideoError(
                'an MP4 needs ffmpeg: install it (e.g. apt install ffmpeg) or pip install "linkagekit[video]"; '
                "or write a .gif"
            )
    scene = res if isinstance(res, Scene) else build_scene(res)
    total = scene.n
    done = 0

    def tick() -> None:
        nonlocal done
        done += 1
        if progress is not None:
            progress(done, total)

    with atomic_output(path) as tmp:
        images = frames(scene, size=size, dpi=int(dpi))
        if ffmpeg is None:
            _write_gif(images, tmp, fps, tick)
        else:
            _write_mp4(images, tmp, fps, tick, ffmpeg)
    return path
