"""IFToMM forward-dynamics benchmarks A01, A02 and A03 (issue 25): time and error of each, in one run.

Each case is simulated by ``lk.simulate`` from its mechanism file in ``examples/`` and compared
with an independent reference (``tests/iftomm_reference.py``, which never calls linkagekit):

* A01 simple pendulum, 10 s, outputs every 10 ms: the mass's position against the exact
  solution (Jacobi elliptic functions), over the whole run;
* A02 double four-bar, 10 s, outputs every 10 ms (ten flat, singular positions): B0's position
  against the reduced equation 3 theta'' = -3.5 g cos(theta) integrated by DOP853 at 1e-13,
  over the whole run, B0's velocity likewise (the LIM statement's measure), and how far
  B1, B2 stray from a parallelogram pair;
* A03 Andrews' squeezing mechanism, 0.03 s, outputs every 0.25 ms: the seven test-set angles
  at 0.03 s against the IVP test set's published solution (relative error per angle), itself
  checked against our integration of the test set's index-1 DAE.

Goals (issue 25): tip error <= 1e-6 m over the whole run (A01, A02), <= 1e-6 relative per
angle (A03), and each simulation in <= 1 s (wall, best of 3; OpenSim's published A02 run:
0.455 s). Also printed: the drift of the total mechanical energy along the outputs (A01, A02:
no dissipation). Exits 1 when a goal is missed.

    python benchmarks/bench_iftomm.py
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np
from timing import best_of

import linkagekit as lk

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
from iftomm_reference import (  # noqa: E402
    A02_M,
    A02_V,
    A03_Q_END,
    A03_T_END,
    G,
    a01_tip,
    a02_theta,
    a03_angles,
    a03_integrate,
)

TIME_GOAL = 1.0  # s per case
TIP_GOAL = 1e-6  # m (A01, A02)
REL_GOAL = 1e-6  # per angle (A03)


def timed(mech, t, **kw):
    """The result of one simulation and the best wall time of three."""
    res = lk.simulate(mech, t, **kw)
    return res, best_of(lambda: lk.simulate(mech, t, **kw), 3)


def case_a01():
    mech = lk.load(ROOT / "examples" / "iftomm_a01_pendulum.yaml")
    t = np.linspace(0.0, 10.0, 1001)
    res, secs = timed(mech, t)
    err = np.abs(res.xy("P") - a01_tip(t)).max()
    v = res.vxy("P")
    energy = 0.5 * (v**2).sum(-1) + G * res.y("P")  # m = 1 kg, L = 1 m
    drift = np.ptp(energy) / G
    return dict(case="A01 pendulum, 10 s", secs=secs, error=err, goal=TIP_GOAL, unit="m (tip)", drift=drift)


def case_a02():
    mech = lk.load(ROOT / "examples" / "iftomm_a02_double_fourbar.yaml")
    t = np.linspace(0.0, 10.0, 1001)
    theta, rate = a02_theta(t)
    res, secs = timed(mech, t, speed=-1.0)
    b0 = res.xy("B0")
    err = np.abs(b0 - np.stack([np.cos(theta), np.sin(theta)], -1)).max()
    v_err = np.abs(res.vxy("B0") - rate[:, None] * np.stack([-np.sin(theta), np.cos(theta)], -1)).max()
    stray = max(np.abs(res.xy(j) - b0 - [dx, 0.0]).max() for j, dx in (("B1", 1.0), ("B2", 2.0)))
    w = np.asarray(res.omega("crank0"))
    energy = 0.5 * A02_M * w**2 + A02_V * b0[:, 1]
    crossings = int(np.sum(np.diff(np.sign(b0[:, 1])) != 0))
    note = f"{crossings} flat crossings; B0 velocity error {v_err:.1e} m/s; parallelogram error {stray:.1e} m"
    return dict(
        case="A02 double four-bar, 10 s", secs=secs, error=err, goal=TIP_GOAL, unit="m (tip)",
        drift=np.ptp(energy) / A02_V, note=note,
    )  # fmt: skip


def case_a03():
    mech = lk.load(ROOT / "examples" / "iftomm_a03_andrews.yaml")
    t = np.linspace(0.0, A03_T_END, 121)
    res, secs = timed(mech, t)
    pts = {k: res.xy(k) for k in "OABCPEDFH"}
    q = np.unwrap(a03_angles(pts), axis=0)  # continuous in time from q0 (all q0 angles in (-pi, pi])
    rel = np.abs(q[-1] - A03_Q_END) / np.abs(A03_Q_END)
    t0 = time.perf_counter()
    q_dae, _ = a03_integrate(rtol=1e-12, atol=1e-12)
    t_dae = time.perf_counter() - t0
    dae = np.abs(q_dae - A03_Q_END).max()
    dae_rel = (np.abs(q_dae - A03_Q_END) / np.abs(A03_Q_END)).max()
    note = (
        f"worst angle {int(np.argmax(rel)) + 1} of 7; reference check: test-set DAE by DOP853 at 1e-12 "
        f"({t_dae:.2f} s) vs published: {dae_rel:.1e} relative ({dae:.1e} rad)"
    )
    return dict(case="A03 Andrews, 0.03 s", secs=secs, error=rel.max(), goal=REL_GOAL, unit="relative", note=note)


def main():
    rows = []
    for case in (case_a01, case_a02, case_a03):
        try:
            rows.append(case())
        except Exception as exc:  # one failing case must not hide the others' numbers
            rows.append(dict(case=case.__name__, secs=np.nan, error=np.nan, goal=0.0, unit="", note=f"FAILED: {exc!r}"))
    head = f"{'case':28s} {'time (s)':>9s} {'goal':>5s} {'error':>9s} {'goal':>7s} {'unit':10s} {'energy drift':>12s}"
    print(head + "  pass")
    ok = True
    for r in rows:
        good = bool(r["secs"] <= TIME_GOAL and r["error"] <= r["goal"])
        ok &= good
        drift = f"{r['drift']:12.1e}" if "drift" in r else f"{'-':>12s}"
        print(
            f"{r['case']:28s} {r['secs']:9.3f} {TIME_GOAL:5.1f} {r['error']:9.1e} {r['goal']:7.0e} {r['unit']:10s} "
            f"{drift}  {'yes' if good else 'NO'}"
        )
        if r.get("note"):
            print(f"{'':28s} {r['note']}")
    print("time: wall, best of 3 runs of lk.simulate (model, integration, output analysis); OpenSim A02: 0.455 s")
    print("energy drift: (max - min) of the total mechanical energy over m g L (A01) or 3.5 m g L (A02)")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
