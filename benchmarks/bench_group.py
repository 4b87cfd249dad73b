"""The numerical group (Newton, continued from the pose) against the closed form, in one run.

A class-3 triad (a ternary link held by three binary links, driven by a crank: 7 joints, 3
placed by Newton) over N samples of the crank, against the closed-form solver on the
Stephenson six-bar of seed 001 (8 joints, 3 placed by circle-circle steps) over the same
number of samples, and the same Stephenson forced through Newton (``method="numerical"``).
Positions only and with rates; ns per sample, best of 3.

    python benchmarks/bench_group.py [N]
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from timing import best_of  # noqa: E402

import linkagekit as lk  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]

TRIAD = {
    "format": "linkagekit/1",
    "name": "class-3 triad",
    "units": {"length": "mm", "angle": "deg"},
    "joints": {
        "O": [0, 0],
        "A": [20, 0],
        "B0": [120, -10],
        "C0": [60, 80],
        "J1": [50, 30],
        "J2": [95, 35],
        "J3": [70, 55],
    },
    "links": {
        "ground": ["O", "B0", "C0"],
        "crank": ["O", "A"],
        "l1": ["A", "J1"],
        "l2": ["B0", "J2"],
        "l3": ["C0", "J3"],
        "tern": ["J1", "J2", "J3"],
    },
    "drivers": [{"link": "crank", "pivot": "O", "toward": "A"}],
}


def main(n: int = 10_000) -> dict[str, float]:
    triad = lk.Mechanism.from_dict(TRIAD)
    six = lk.load(ROOT / "examples" / "seed001_stephenson.yaml")
    rows = {}
    cases = [
        ("triad, Newton (3 joints)", triad, {"crank": np.linspace(-10.0, 87.0, n)}, "natural"),
        ("Stephenson six-bar, closed form", six, {six.drivers[0].name: np.linspace(0.0, 360.0, n)}, "natural"),
        ("Stephenson six-bar, forced Newton", six, {six.drivers[0].name: np.linspace(0.0, 360.0, n)}, "numerical"),
    ]
    print(f"{n} samples, ns/sample (best of 3)")
    for label, mech, inputs, method in cases:
        res = lk.analyze(mech, inputs, method=method)
        assert res.assembled.mean() > 0.9, (label, res.assembled.mean())
        t_pos = best_of(lambda m=mech, i=inputs, k=method: lk.analyze(m, i, method=k, rates=False), 3)
        t_all = best_of(lambda m=mech, i=inputs, k=method: lk.analyze(m, i, method=k), 3)
        rows[label] = t_pos / n * 1e9
        print(f"  {label:36s} positions {t_pos / n * 1e9:10.0f}   with rates {t_all / n * 1e9:10.0f}")
    ratio = rows["triad, Newton (3 joints)"] / rows["Stephenson six-bar, closed form"]
    print(f"ratio, triad (Newton) / six-bar (closed form), positions: {ratio:.0f}x")
    rows["ratio"] = ratio
    return rows


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 10_000)
