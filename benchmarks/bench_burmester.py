"""Exact motion generation (Burmester theory) on the hsieh2 poses and on many random four-bars.

For the 5 exact poses of the hsieh2 mechanism (public benchmark data, when on this machine)
and for ``N`` random four-bars, each through 5 poses of its coupler in order along the run of
crank angles it assembles over (the generator of ``tests/test_burmester.py``): whether the
generating four-bar is listed (its dyads within ``1e-9`` and ``1e-6`` of its size), the
largest residual of every listed four-bar (``lk.analyze`` in both modes, relative to the
size), how many four-bars are listed, and the time per call of ``exact_motion``.

    python benchmarks/bench_burmester.py [N [SEED]]     # default 2000 four-bars, seed 7
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from linkagekit.synthesis import burmester as bm  # noqa: E402
from test_burmester import TARGETS, pose_errors, random_poses, same_dyads  # noqa: E402


def hsieh2() -> None:
    """The hsieh2 generator among the four-bars of its 5 exact poses."""
    if not TARGETS.exists():
        print("hsieh2: the public benchmark data is not on this machine")
        return
    poses = np.array(json.loads(TARGETS.read_text())["hsieh2_generating_mechanism"]["exact5_poses"]["poses"])
    xya = (poses[:, 0], poses[:, 1], np.arctan2(poses[:, 3], poses[:, 2]))
    t = time.perf_counter()
    bm.exact_motion(xya)  # the first call imports and builds what every later one reuses
    first = time.perf_counter() - t
    t = time.perf_counter()
    fbs = bm.exact_motion(xya)
    took = time.perf_counter() - t
    print(
        f"hsieh2 exact5: {len(fbs)} four-bars in {took * 1e3:.1f} ms (first call, with imports: {first * 1e3:.0f} ms)"
    )
    for fb in fbs:
        pos, ang = pose_errors(fb)
        print(
            f"  crank at ({fb.crank.ground.real:+.6f}, {fb.crank.ground.imag:+.6f}) rocker at "
            f"({fb.rocker.ground.real:+.6f}, {fb.rocker.ground.imag:+.6f})  {fb.grashof:13s}"
            f" in order {fb.in_order!s:5s}"
            f"  residual {pos:.1e} / {np.degrees(ang):.1e} deg"
        )
        assert pos <= 1e-9 and ang <= 1e-9


def random(n: int, seed: int) -> None:
    """``n`` random four-bars recovered from 5 of their poses."""
    rng = np.random.default_rng(seed)
    found9 = found6 = 0
    worst, took, counts = 0.0, 0.0, np.zeros(7, int)
    for _ in range(n):
        z, res, xya = random_poses(rng, 5)
        size = float(np.max(np.abs(z[:4, None] - z[None, :4])))
        t = time.perf_counter()
        fbs = bm.exact_motion(xya)
        took += time.perf_counter() - t
        counts[len(fbs)] += 1
        crank, rocker = bm.Dyad(z[0], res.point("A1")[0]), bm.Dyad(z[3], res.point("B1")[0])
        found9 += any(same_dyads(fb, crank, rocker, 1e-9 * size) for fb in fbs)
        found6 += any(same_dyads(fb, crank, rocker, 1e-6 * size) for fb in fbs)
        for fb in fbs:
            pos, ang = pose_errors(fb)
            worst = max(worst, pos / size, ang)
    print(f"random four-bars: {n} (seed {seed}); four-bars listed: {dict(enumerate(counts.tolist()))}")
    print(f"  generator listed, dyads within 1e-9 of size: {found9}/{n}; within 1e-6: {found6}/{n}")
    print(f"  largest residual of any listed four-bar: {worst:.1e} (of size, and rad)")
    print(f"  exact_motion: {took / n * 1e3:.1f} ms per call")
    assert found6 == n and worst <= 1e-9


def main(n: int = 2000, seed: int = 7) -> None:
    hsieh2()
    random(n, seed)


if __name__ == "__main__":
    main(*(int(a) for a in sys.argv[1:3]))
