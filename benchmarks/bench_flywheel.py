"""Flywheel sizing of the motor-driven beam pump (examples/motor_fourbar.yaml), checked by simulating.

Issue 25's acceptance: a motor-driven four-bar from rest (T = T0 (1 - w/W0)) reaches a
periodic steady state; the flywheel for Cs = 0.02 keeps a simulation of that steady state
within 0.02, and ``--flywheel`` finds it in at most 5 s.  Prints, in one run:

1. the wall time of ``linkagekit simulate FILE --motor T0,W0 --flywheel 0.02`` in a fresh
   process (imports included), best of 3, against the 5 s goal;
2. ``lk.simulate`` of the pump with that flywheel from rest for 60 s: the speed at the start
   angle turn after turn (it converges geometrically, by the period map's contraction) and
   Cs over the last turn, against the periodic solution found by collocation;
3. the same from rest without a flywheel (Cs there against ``cs_without``);
4. Cs(I) on a grid of flywheels (it falls: the monotone search is justified on this case).

    python benchmarks/bench_flywheel.py
"""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

import linkagekit as lk
from linkagekit.dynamics import TorqueLaw
from linkagekit.flywheel import steady_state

ROOT = Path(__file__).resolve().parents[1]
FILE = ROOT / "examples" / "motor_fourbar.yaml"
MOTOR = (6500.0, 6.5)
CS = 0.02
GOAL_SECONDS = 5.0


def cli_seconds() -> tuple[float, float]:
    """Best-of-3 wall time of the command in a fresh process, and the inertia it printed."""
    cmd = [sys.executable, "-c", "import sys; from linkagekit.cli import main; sys.exit(main())"]
    args = ["simulate", str(FILE), "--motor", f"{MOTOR[0]},{MOTOR[1]}", "--flywheel", str(CS)]
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"))
    best, out = np.inf, ""
    for _ in range(3):
        t = time.perf_counter()
        out = subprocess.run(cmd + args, env=env, check=True, capture_output=True, text=True).stdout
        best = min(best, time.perf_counter() - t)
    return best, float(out)


def from_rest(mech: lk.Mechanism, inertia: float, seconds: float) -> tuple[np.ndarray, np.ndarray, float]:
    """Speed at each return to the start angle, the turn count at each, and Cs over the last full turn."""
    data = mech.to_dict()
    if inertia:
        data["flywheels"] = [{"link": mech.drivers[0].link, "inertia": inertia}]
    fly = lk.Mechanism.from_dict(data)
    times = np.arange(0.0, seconds, 1e-4)
    res = lk.simulate(fly, times, motor=MOTOR)
    q = np.unwrap(np.radians(res.inputs["crank"]))
    w = res.omega("crank")
    q0 = q[0]
    turns = np.arange(1, int((q[-1] - q0) / (2 * np.pi)) + 1)
    at = q0 + 2 * np.pi * turns
    w_at = np.interp(at, q, w)
    last = (q >= at[-2]) & (q <= at[-1])
    cs = (w[last].max() - w[last].min()) / ((w[last].max() + w[last].min()) / 2)
    return turns, w_at, float(cs)


def main() -> None:
    mech = lk.load(FILE)
    seconds, printed = cli_seconds()
    size = lk.size_flywheel(mech, CS, motor=MOTOR)
    st = size.steady
    print(f"beam pump, motor T0 = {MOTOR[0]:g} N*m, W0 = {MOTOR[1]:g} rad/s, Cs asked {CS}")
    print(f"--flywheel {CS}: {printed:.6f} kg*m^2 in {seconds:.2f} s wall (fresh process, goal {GOAL_SECONDS} s)")
    print(f"  steady state (collocation): Cs {size.cs:.9f} (without the flywheel {size.cs_without:.6f}),")
    print(f"  speed {abs(st.w_min):.6f} .. {abs(st.w_max):.6f} rad/s, period map contraction {st.contraction:.4f}")

    turns, w_at, cs_sim = from_rest(mech, size.inertia, 60.0)
    print(f"lk.simulate with the flywheel from rest, {turns[-1]} turns in 60 s:")
    for k in (1, 2, 5, 10, 20, turns[-1]):
        off = w_at[k - 1] - st.w[0]
        print(f"  turn {k:3d}: w at the start angle {w_at[k - 1]:.9f} rad/s, off the periodic one by {off:+.2e}")
    print(f"  Cs over the last turn {cs_sim:.9f} (collocation {size.cs:.9f}; asked {CS})")

    turns0, w0_at, cs0_sim = from_rest(mech, 0.0, 20.0)
    base = steady_state(lk.reduced(mech), TorqueLaw(MOTOR[0], MOTOR[1]))
    print(f"without a flywheel from rest: Cs over turn {turns0[-1]} {cs0_sim:.6f} (collocation {base.cs:.6f}), ")
    print(f"  w at the start angle {w0_at[-1]:.9f} (collocation {base.w[0]:.9f})")

    grid = size.inertia * np.array([0.0, 0.1, 0.3, 0.6, 1.0, 1.5, 2.0])
    red, law = lk.reduced(mech), TorqueLaw(MOTOR[0], MOTOR[1])
    cs_grid = [steady_state(red, law, i).cs for i in grid]
    print("Cs(I): " + ", ".join(f"{i:.0f}: {c:.5f}" for i, c in zip(grid, cs_grid, strict=True)))

    assert seconds <= GOAL_SECONDS, seconds
    assert abs(printed - size.inertia) <= 1e-9 * size.inertia
    assert cs_sim <= CS * (1 + 1e-6) and abs(cs_sim - size.cs) <= 1e-6 * CS
    assert abs(w_at[-1] - st.w[0]) <= 1e-8 * abs(st.w[0])
    assert abs(cs0_sim - base.cs) <= 1e-5 * base.cs
    assert all(a > b for a, b in zip(cs_grid, cs_grid[1:], strict=False))


if __name__ == "__main__":
    main()
