"""Recovering known curves: how close, and how long, on this machine (the issue's goal: within 0.1 % of
the targets' diagonal, in 60 s on 2 cores).

For each topology, the first ``K`` random designs whose whole motion lies in the default search
box of their own coupler curve (the designs of ``tests/test_synthesis.py``): 12 targets on the
curve, then ``synthesize(..., seconds=60, workers=2)``. The error is measured independently
(the written mechanism's curve by ``lk.analyze`` every 0.01 degree, point-to-segment
distances).

    python benchmarks/bench_recovery.py [K]        # default 3 per topology
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

import linkagekit as lk
from linkagekit.synthesis.run import synthesize

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from test_synthesis import curve_distance, diagonal, random_designs  # noqa: E402


def main(k: int = 3, seconds: float = 60.0, workers: int = 2) -> list[tuple[str, int, float, float]]:
    rows = []
    print(f"{'topology':12s} {'design':>6s} {'max error % diag':>17s} {'seconds':>8s}  stopped by")
    for topology in ("fourbar", "watt2", "stephenson3"):
        for i, mech in enumerate(random_designs(topology, k, seed=11)):
            T = lk.analyze(mech, {"crank": np.linspace(0.0, 360.0, 12, endpoint=False) + 7.0}).xy("P")
            t = time.monotonic()
            out = synthesize(T, topology, seconds=seconds, workers=workers)
            took = time.monotonic() - t
            err = float(np.max(curve_distance(out.mechanism, T)) / diagonal(T))
            rows.append((topology, i, 100 * err, took))
            print(f"{topology:12s} {i:6d} {100 * err:17.4f} {took:8.1f}  {out.outcome.stopped_by}", flush=True)
    ok = sum(r[2] <= 0.1 and r[3] <= seconds + 1 for r in rows)
    print(f"{ok} of {len(rows)} within 0.1 % in {seconds:g} s")
    return rows


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 3)
