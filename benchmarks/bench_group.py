"""The numerical group (Newton, continued from the pose) against the closed form, in one run.

A class-3 triad (a ternary link held by three binary links, driven by a crank: 7 joints, 3
placed by Newton) over N samples of the crank, against the closed-form solver on the
Stephenson six-bar of seed 001 (8 joints, 3 placed by circle-circle steps) over the same
number of samples, and the same Stephenson forced through Newton (``method="numerical"``).
Positions only and with rates; ns per sample, best of 3. Then the goals of issue 29:

* the triad at 10^4 samples: positions at most 2 us a sample, with rates at most 3 us;
* a batch of 10^3 triad designs (``poses=``) x 360 samples: at most 1 us a design-sample;
* samples outside the triad's range (10^4 directions where it does not assemble): at most
  10 us each.

    python benchmarks/bench_group.py [N]

Prints each measure against its goal and exits 1 when one is missed (timings depend on the
machine and its load: the goals are for an idle machine).
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


def main(n: int = 10_000, designs: int = 1000) -> dict[str, float]:
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
        if label.startswith("triad"):
            rows["triad with rates"] = t_all / n * 1e9
    ratio = rows["triad, Newton (3 joints)"] / rows["Stephenson six-bar, closed form"]
    print(f"ratio, triad (Newton) / six-bar (closed form), positions: {ratio:.0f}x")
    rows["ratio"] = ratio
    rows["batch"] = batch(triad, designs)
    rows["outside"] = outside(triad, n)
    return rows


def batch(triad: lk.Mechanism, designs: int = 1000, samples: int = 360) -> float:
    """ns per design-sample of ``designs`` perturbed triads over ``samples`` inputs, positions, in one call."""
    rng = np.random.default_rng(7)
    poses = triad.pose_array()[None] + rng.normal(0, 0.5, (designs, len(triad.joint_names), 2))
    inputs = {"crank": np.linspace(-10.0, 87.0, samples)}
    res = lk.analyze(triad, inputs, poses=poses, rates=False)
    assert res.assembled.mean() > 0.5, res.assembled.mean()
    t = best_of(lambda: lk.analyze(triad, inputs, poses=poses, rates=False), 3)
    per = t / (designs * samples) * 1e9
    print(f"  batch of {designs} triad designs x {samples} samples, positions: {per:10.0f} ns per design-sample")
    return per


def outside(triad: lk.Mechanism, n: int) -> float:
    """ns per sample of ``n`` directions where the triad does not assemble (its range is about -10..88 deg)."""
    inputs = {"crank": np.linspace(100.0, 340.0, n)}
    res = lk.analyze(triad, inputs, rates=False)
    assert not res.assembled.any()
    t = best_of(lambda: lk.analyze(triad, inputs, rates=False), 3)
    per = t / n * 1e9
    print(f"  {n} samples outside the triad's range, positions: {per:10.0f} ns per sample")
    return per


#: the goals of issue 29 (ns): measure -> goal
GOALS = {"triad, Newton (3 joints)": 2000.0, "triad with rates": 3000.0, "batch": 1000.0, "outside": 10_000.0}


def report(rows: dict[str, float]) -> bool:
    """Each goal met or not; True when all are."""
    ok = True
    for key, goal in GOALS.items():
        met = rows[key] <= goal
        ok &= met
        print(f"goal {key:28s} {rows[key]:10.0f} ns <= {goal:8.0f} ns: {'met' if met else 'MISSED'}")
    return ok


if __name__ == "__main__":
    sys.exit(0 if report(main(int(sys.argv[1]) if len(sys.argv) > 1 else 10_000)) else 1)
