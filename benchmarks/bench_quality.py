"""Speed to quality (issue 30): what ``linkagekit synthesize`` reaches with its default options, by the clock.

Each run is the command a user types (a fresh process: the wall time includes Python's start and the
atlas's lookup; the atlas must exist: ``linkagekit atlas build`` first, or the first run builds it), and
each result is measured again independently of the search: the written file is swept by ``lk.analyze``
every 0.01 degree of its crank and each target's distance to that polyline is computed here (point to
segment, brute force).

``crank``
    ``K`` random crank-rockers (``tests/test_synthesis.random_designs``, seed 11), 12 targets on each
    one's coupler curve, ``--seconds 10``: the max error in % of the targets' diagonal. Goal: within
    0.1 % in at least 9 of 10 cases.
``line``
    Six points on the line x = 20 (``benchmarks/synthesis_problems/aligned6_vertical_line.yaml``'s
    targets, which an exact four-bar meets), ``--seconds 30``: the sum of squared distances (SSE).
    Goal: at most 1e-8.

The published problems in 60 s are ``python benchmarks/bench_published.py --seconds 60``.

    python benchmarks/bench_quality.py [crank|line ...] [--k K] [--seconds S] [--workers N]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import linkagekit as lk

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from test_synthesis import random_designs  # noqa: E402

LINE = np.array([[20.0, 20], [20, 25], [20, 30], [20, 35], [20, 40], [20, 45]])


def load() -> str:
    one, five, fifteen = os.getloadavg()
    return f"load average {one:.2f} {five:.2f} {fifteen:.2f} on {os.cpu_count()} cores"


def distances(path: Path, T: np.ndarray) -> np.ndarray:
    """Each target's distance to the written mechanism's curve, swept every 0.01 degree (polyline, brute force)."""
    mech = lk.load(path)
    d = mech.drivers[0]
    lo, hi = float(d.sweep.start), float(d.sweep.stop)
    P = lk.analyze(mech, {d.name: np.arange(lo, hi + 0.005, 0.01)}, rates=False).xy("P")
    assert np.all(np.isfinite(P)), f"{path}: does not assemble over its sweep"
    A, B = P[:-1], P[1:]
    AB = B - A
    out = np.empty(len(T))
    for i, t in enumerate(T):  # 6 or 12 targets: a loop over targets, not over samples
        s = np.clip(np.einsum("ij,ij->i", t - A, AB) / np.maximum(np.einsum("ij,ij->i", AB, AB), 1e-300), 0, 1)
        out[i] = np.sqrt(np.min(np.sum((A + s[:, None] * AB - t) ** 2, axis=1)))
    return out


def run(T: np.ndarray, seconds: float, workers: int | None, tmp: Path, name: str) -> tuple[float, np.ndarray]:
    """``linkagekit synthesize`` on ``T`` in a fresh process: (wall seconds, distances of the written file)."""
    csv, out = tmp / f"{name}.csv", tmp / f"{name}.yaml"
    np.savetxt(csv, T, delimiter=",", header="x,y", comments="", fmt="%.17g")
    cmd = ["linkagekit", "synthesize", str(csv), "--seconds", str(seconds), "-o", str(out)]
    if workers:
        cmd += ["--workers", str(workers)]
    t0 = time.monotonic()
    done = subprocess.run(cmd, capture_output=True, text=True)
    took = time.monotonic() - t0
    if done.returncode != 0:
        raise SystemExit(f"{name}: exit {done.returncode}: {done.stderr.strip().splitlines()[-1:]}")
    return took, distances(out, T)


def crank(k: int, seconds: float, workers: int | None, tmp: Path) -> bool:
    print(f"== crank: {k} random crank-rockers, 12 targets, --seconds {seconds:g} ({load()})")
    good = 0
    for i, mech in enumerate(random_designs("fourbar", k, seed=11)):
        T = lk.analyze(mech, {"crank": np.linspace(0.0, 360.0, 12, endpoint=False) + 7.0}).xy("P")
        diag = float(np.hypot(*np.ptp(T, axis=0)))
        took, d = run(T, seconds, workers, tmp, f"crank{i}")
        err = 100 * d.max() / diag
        good += err <= 0.1
        print(f"case {i}: max error {err:.4f} % of the diagonal, {took:.1f} s wall", flush=True)
    need = int(np.ceil(0.9 * k))
    print(f"within 0.1 %: {good} of {k} (goal: at least {need}) ({load()})")
    return good >= need


def line(seconds: float, workers: int | None, tmp: Path) -> bool:
    print(f"== line: six points on x = 20, --seconds {seconds:g} ({load()})")
    took, d = run(LINE, seconds, workers, tmp, "line")
    sse = float(np.sum(d * d))
    print(f"SSE {sse:.3g} (goal <= 1e-8), max distance {d.max():.3g}, {took:.1f} s wall ({load()})")
    return sse <= 1e-8


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("parts", nargs="*", help="crank, line (default: both)")
    ap.add_argument("--k", type=int, default=10)
    ap.add_argument("--seconds", type=float, default=None, help="the budget of every run (default: 10 and 30)")
    ap.add_argument("--workers", type=int, default=None)
    a = ap.parse_args(argv)
    a.parts = a.parts or ["crank", "line"]
    if set(a.parts) - {"crank", "line"}:
        ap.error(f"unknown parts: {sorted(set(a.parts) - {'crank', 'line'})}")
    ok = True
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        if "crank" in a.parts:
            ok &= crank(a.k, a.seconds or 10.0, a.workers, tmp)
        if "line" in a.parts:
            ok &= line(a.seconds or 30.0, a.workers, tmp)
    print("goals met" if ok else "a goal is missed")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
