"""Many four-bar designs with a coupler point x 360 samples, in one run:

* ``lk.analyze(mech, inputs, poses=poses)`` (positions only, ``rates=False``, and with rates),
* a hand-written NumPy kernel over (designs x samples) computing the same numbers (checked
  equal first),
* the per-design loop ``lk.analyze(mech.with_pose(pose), inputs)`` (timed on the first
  designs and given per design-sample),

printing ns per design-sample and the ratios (goal: positions within 1.5x of the hand
kernel).  Then the cold start-up: ``import linkagekit`` and ``linkagekit --help`` (CPU
seconds of a fresh interpreter; goal for ``--help``: under 0.25 s).

    python benchmarks/bench_designs.py [N1,N2,...]     # default 10000,100000
"""

from __future__ import annotations

import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from timing import best_of

import linkagekit as lk

ROOT = Path(__file__).resolve().parents[1]
N_SAMPLES = 360
LOOP_DESIGNS = 500


def designs(mech, n, seed=0):
    """Random four-bars near seed 000's (every joint moved by up to 15 % of the crank length)."""
    rng = np.random.default_rng(seed)
    return mech.pose_array() + rng.uniform(-0.3, 0.3, (n, len(mech.joint_names), 2))


def hand_kernel(poses, phi, w=1.0, al=0.0, with_rates=False):
    """Four-bar A-C-D-B with coupler point P, over (designs, samples), real arithmetic.

    Per design (columns (D, 1)): ground A, B; crank a = |AC|; coupler b = |CD|, rocker
    c = |BD| read off the pose; the pose's side of D (left of C -> B: +1) and P as a fixed
    complex ratio of C -> D.  Returns what ``lk.analyze`` returns for the moving joints.
    """
    A, B, C0, D0, P0 = (poses[:, i, 0:1] + 1j * poses[:, i, 1:2] for i in range(5))
    a = np.abs(C0 - A)
    b = np.abs(D0 - C0)
    c = np.abs(D0 - B)
    e0 = B - C0
    t = np.where((np.conj(e0) * (D0 - C0)).imag >= 0, 1.0, -1.0)
    rho = (P0 - C0) / (D0 - C0)
    kr, ki = rho.real, rho.imag
    ax, ay, bx, by = A.real, A.imag, B.real, B.imag
    cos, sin = np.cos(phi), np.sin(phi)
    cx = ax + a * cos
    cy = ay + a * sin
    sx, sy = bx - cx, by - cy
    s2 = sx * sx + sy * sy
    s = np.sqrt(s2)
    along = (b * b - c * c + s2) / (2 * s)
    h = t * np.sqrt(np.maximum(b * b - along * along, 0.0))
    dx = cx + (along * sx - h * sy) / s
    dy = cy + (along * sy + h * sx) / s
    ux, uy = dx - cx, dy - cy
    px = cx + kr * ux - ki * uy
    py = cy + kr * uy + ki * ux
    ok = (s <= b + c) & (s >= np.abs(b - c))
    if not with_rates:
        return ok, cx, cy, dx, dy, px, py
    # C: v = i w (C - A); D from (D - C).(vD - vC) = 0, (D - B).vD = 0 by Cramer's rule
    vcx, vcy = -w * (cy - ay), w * (cx - ax)
    acx, acy = -al * (cy - ay) - w * w * (cx - ax), al * (cx - ax) - w * w * (cy - ay)
    qx, qy = dx - bx, dy - by
    det = ux * qy - uy * qx
    r1 = ux * vcx + uy * vcy
    vdx, vdy = r1 * qy / det, -r1 * qx / det
    w3 = (ux * (vdy - vcy) - uy * (vdx - vcx)) / (b * b)  # coupler
    w4 = (qx * vdy - qy * vdx) / (c * c)  # rocker
    r1 = ux * acx + uy * acy - (w3 * b) ** 2
    r2 = -((w4 * c) ** 2)
    adx = (r1 * qy - r2 * uy) / det
    ady = (ux * r2 - qx * r1) / det
    al3 = (ux * (ady - acy) - uy * (adx - acx)) / (b * b)
    al4 = (qx * ady - qy * adx) / (c * c)
    vpx = vcx + kr * (vdx - vcx) - ki * (vdy - vcy)
    vpy = vcy + kr * (vdy - vcy) + ki * (vdx - vcx)
    apx = acx + kr * (adx - acx) - ki * (ady - acy)
    apy = acy + kr * (ady - acy) + ki * (adx - acx)
    return ok, cx, cy, dx, dy, px, py, vdx, vdy, vpx, vpy, adx, ady, apx, apy, w3, w4, al3, al4


def check_equal(mech, poses, deg):
    phi = np.radians(deg)
    res = lk.analyze(mech, {"crank": deg}, poses=poses, speed=2.0, acceleration=0.5)
    ref = hand_kernel(poses, phi, 2.0, 0.5, with_rates=True)
    ok = ref[0] & res.assembled
    assert np.array_equal(ref[0], res.assembled)
    for (x, y), j in (((ref[3], ref[4]), "D"), ((ref[5], ref[6]), "P")):
        assert np.allclose(res.xy(j)[..., 0][ok], x[ok], atol=1e-9)
        assert np.allclose(res.xy(j)[..., 1][ok], y[ok], atol=1e-9)
    good = ok & ~res.singular
    assert np.allclose(res.velocity("P")[good], (ref[9] + 1j * ref[10])[good], rtol=1e-6, atol=1e-6)
    assert np.allclose(res.acceleration("D")[good], (ref[11] + 1j * ref[12])[good], rtol=1e-6, atol=1e-6)
    assert np.allclose(res.omega("rocker")[good], ref[16][good], rtol=1e-6, atol=1e-6)


def cpu_of(cmd):
    """CPU seconds (user + system) of a child process."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(cmd, check=True, capture_output=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def startup():
    exe = Path(sys.executable).parent / "linkagekit"
    runs = {
        "python -c pass": [sys.executable, "-c", "pass"],
        "import linkagekit": [sys.executable, "-c", "import linkagekit"],
        "import linkagekit + load + analyze": [
            sys.executable,
            "-c",
            "import linkagekit as lk; lk.analyze(lk.load('examples/seed000_fourbar.yaml'))",
        ],
        "linkagekit --help": [str(exe), "--help"],
    }
    print("\ncold start-up (CPU s of a fresh process, best of 5)")
    for name, cmd in runs.items():
        t = min(cpu_of(cmd) for _ in range(5))
        goal = "   (goal < 0.25)" if "--help" in name else ""
        print(f"  {name:38s} {t:6.3f}{goal}")


def main(sizes=(10_000, 100_000)):
    mech = lk.load(ROOT / "examples" / "seed000_fourbar.yaml")
    deg = np.arange(0.0, 360.0, 360.0 / N_SAMPLES)
    phi = np.radians(deg)
    check_equal(mech, designs(mech, 200, seed=1), deg)
    print(f"four-bar designs with a coupler point x {N_SAMPLES} samples (ns per design-sample; ratio to hand NumPy)")
    loop_poses = designs(mech, LOOP_DESIGNS, seed=2)
    t0 = time.perf_counter()
    for pose in loop_poses:
        lk.analyze(mech.with_pose(pose), {"crank": deg}, rates=False)
    t_loop_pos = (time.perf_counter() - t0) / (LOOP_DESIGNS * N_SAMPLES)
    t0 = time.perf_counter()
    for pose in loop_poses:
        lk.analyze(mech.with_pose(pose), {"crank": deg})
    t_loop_all = (time.perf_counter() - t0) / (LOOP_DESIGNS * N_SAMPLES)
    for n in sizes:
        poses = designs(mech, n)
        repeat = 3  # best of 3: a fresh multi-GB result is bound by page faults, which vary run to run here
        ns = 1e9 / (n * N_SAMPLES)
        rows = []
        for label, rates, loop in (("positions", False, t_loop_pos), ("with rates", True, t_loop_all)):
            t_lk = best_of(lambda r=rates, p=poses: lk.analyze(mech, {"crank": deg}, poses=p, rates=r), repeat)
            t_hand = best_of(lambda r=rates, p=poses: hand_kernel(p, phi, with_rates=r), repeat)
            rows.append((label, t_lk * ns, t_hand * ns, loop * 1e9))
        print(f"{n:,} designs")
        for label, lk_ns, hand_ns, loop_ns in rows:
            goal = "  (goal <= 1.5)" if label == "positions" else ""
            print(
                f"  {label:11s} lk.analyze(poses=) {lk_ns:7.1f}   hand NumPy {hand_ns:7.1f}"
                f"   ratio {lk_ns / hand_ns:5.2f}{goal}"
                f"   per-design loop {loop_ns:8.1f} ({loop_ns / lk_ns:5.1f}x slower)"
            )
    startup()


if __name__ == "__main__":
    main(tuple(int(x) for x in sys.argv[1].split(",")) if len(sys.argv) > 1 else (10_000, 100_000))
