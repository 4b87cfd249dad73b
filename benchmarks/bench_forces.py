"""Kinetostatics of seed 001's Stephenson six-bar (examples/seed001_stephenson.yaml) for N samples.

Prints ns/sample for the force solve alone (the batched 15x15 Newton-Euler systems), for the
kinematics alone (positions, velocities, accelerations) and for the whole ``lk.analyze``,
measured in one run, plus the kinetostatics/kinematics ratio.

    python benchmarks/bench_forces.py [N]
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from timing import best_of

import linkagekit as lk

ROOT = Path(__file__).resolve().parents[1]


def main(n=100_000):
    mech = lk.load(ROOT / "examples" / "seed001_stephenson.yaml")
    deg = np.linspace(0, 360, n)
    kin = lk.analyze(mech, deg, dynamics=False)
    assert kin.assembled.all()
    t_kin = best_of(lambda: lk.analyze(mech, deg, dynamics=False), 3)
    t_all = best_of(lambda: lk.analyze(mech, deg), 3)
    t_forces = t_all - t_kin
    f = lk.analyze(mech, deg).forces
    ns = 1e9 / n
    print(f"Stephenson six-bar of seed 001 (15 x 15 Newton-Euler per sample), N = {n:,} samples")
    print(f"kinetostatics (whole - kin.)   {t_forces * ns:8.1f} ns/sample")
    print(f"kinematics (pos + vel + acc)   {t_kin * ns:8.1f} ns/sample")
    print(f"whole lk.analyze               {t_all * ns:8.1f} ns/sample   forces/kinematics {t_forces / t_kin:5.2f}")
    print(f"largest relative residual |A x - b| over the sweep: {np.nanmax(f.residual):.1e}")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 100_000)
