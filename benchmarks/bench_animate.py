"""Animation of the Jansen leg (examples/jansen_leg.yaml): N frames, GIF and MP4.

Measures, in one run:

* ``animate`` (GIF): static parts drawn once, only the moving artists redrawn per frame
  (blitting on the Agg canvas), frames quantized to one palette by Pillow;
* the reference: matplotlib's ``FuncAnimation.save`` with ``PillowWriter`` on the same
  drawing, which redraws the whole figure for every frame;
* ``animate`` to MP4 (when an ffmpeg is found), against ``FuncAnimation.save`` with
  ``FFMpegWriter``.

Prints seconds and the ratio reference / ours (the issue's goal: 72 frames in under 10 s;
``FuncAnimation.save`` is about 5x slower).

    python benchmarks/bench_animate.py [N]
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import linkagekit as lk

ROOT = Path(__file__).resolve().parents[1]


def reference(scene, path, writer):
    """FuncAnimation.save: the whole figure drawn for every frame."""
    from matplotlib.animation import FuncAnimation
    from matplotlib.figure import Figure

    from linkagekit.viz.draw import Drawing, _aspect

    fig = Figure(figsize=(6, 6 * _aspect(scene)), dpi=100)
    ax = fig.add_axes((0.02, 0.02, 0.96, 0.9))
    fig.suptitle(scene.name)
    d = Drawing(ax, scene)
    FuncAnimation(fig, d.update, frames=scene.n, blit=False).save(path, writer=writer)


def timed(f):
    t0 = time.perf_counter()
    f()
    return time.perf_counter() - t0


def main(n=72):
    from matplotlib.animation import FFMpegWriter, PillowWriter

    from linkagekit.viz.animate import animate, find_ffmpeg
    from linkagekit.viz.scene import build_scene

    mech = lk.load(ROOT / "examples" / "jansen_leg.yaml")
    res = lk.analyze(mech, {"crank": np.linspace(0, 360, n)})
    scene = build_scene(res)
    with tempfile.TemporaryDirectory() as tmp:
        # warm up (imports, fonts) outside the timings, then the better of two runs each
        animate(build_scene(lk.analyze(mech, {"crank": [0.0, 1.0]})), Path(tmp, "warm.gif"))
        ours = min(timed(lambda: animate(scene, Path(tmp, "ours.gif"))) for _ in range(2))
        ref = min(timed(lambda: reference(scene, Path(tmp, "ref.gif"), PillowWriter(fps=24))) for _ in range(2))
        print(
            f"Jansen leg, {n} frames, GIF: animate {ours:.2f} s, FuncAnimation.save {ref:.2f} s, "
            f"ratio {ref / ours:.1f}x (goal: under 10 s)"
        )
        ffmpeg = find_ffmpeg()
        if ffmpeg:
            import matplotlib

            matplotlib.rcParams["animation.ffmpeg_path"] = ffmpeg
            ours = min(timed(lambda: animate(scene, Path(tmp, "ours.mp4"))) for _ in range(2))
            ref = min(timed(lambda: reference(scene, Path(tmp, "ref.mp4"), FFMpegWriter(fps=24))) for _ in range(2))
            print(
                f"Jansen leg, {n} frames, MP4: animate {ours:.2f} s, FuncAnimation.save {ref:.2f} s, "
                f"ratio {ref / ours:.1f}x"
            )
        else:
            print("MP4: no ffmpeg found (pip install 'linkagekit[video]'), not measured")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 72)
