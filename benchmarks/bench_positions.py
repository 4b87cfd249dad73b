"""Positions, velocities and accelerations of seed 000's four-bar through ``lk.analyze``,
against a hand-written vectorized NumPy kernel computing the same, in one run.

Prints ns/sample for both and their ratio (goal: <= 1.5 for positions, <= 2 with rates),
and the solve time of a 360-sample sweep (goal: < 1 ms).

    python benchmarks/bench_positions.py [N]
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from timing import best_of

import linkagekit as lk
from linkagekit.api import prepare
from linkagekit.positions import solve

ROOT = Path(__file__).resolve().parents[1]


def hand_kernel(phi, w, al, with_rates=True):
    """Seed 000's closed form written out (a=2, b=c=d=e=5, A=(0,0), B=(4,1)), real arithmetic."""
    a, b, c, d, e = 2.0, 5.0, 5.0, 5.0, 5.0
    bx, by = 4.0, 1.0
    cx, cy = a * np.cos(phi), a * np.sin(phi)
    sx, sy = bx - cx, by - cy
    s = np.hypot(sx, sy)
    l1 = (b * b + s * s - c * c) / (2 * s)
    h1 = np.sqrt(b * b - l1 * l1)
    dx = cx + (l1 * sx - h1 * sy) / s
    dy = cy + (l1 * sy + h1 * sx) / s
    l2 = (d * d + b * b - e * e) / (2 * b)
    h2 = -np.sqrt(d * d - l2 * l2)  # the file's pose: P right of C->D
    ux, uy = dx - cx, dy - cy
    px = cx + (l2 * ux - h2 * uy) / b
    py = cy + (l2 * uy + h2 * ux) / b
    if not with_rates:
        return dx, dy, px, py
    vcx, vcy = -w * cy, w * cx
    acx, acy = -al * cy - w * w * cx, al * cx - w * w * cy
    # D: (D-C).(vD-vC) = 0, (D-B).vD = 0
    p1x, p1y, q1x, q1y = dx - cx, dy - cy, dx - bx, dy - by
    det = p1x * q1y - p1y * q1x
    r1 = p1x * vcx + p1y * vcy
    vdx = (r1 * q1y) / det
    vdy = (-r1 * q1x) / det
    r1 = p1x * acx + p1y * acy - ((vdx - vcx) ** 2 + (vdy - vcy) ** 2)
    r2 = -(vdx * vdx + vdy * vdy)
    adx = (r1 * q1y - r2 * p1y) / det
    ady = (p1x * r2 - q1x * r1) / det
    k1, k2 = l2 / b, h2 / b
    vpx = vcx + k1 * (vdx - vcx) - k2 * (vdy - vcy)
    vpy = vcy + k1 * (vdy - vcy) + k2 * (vdx - vcx)
    apx = acx + k1 * (adx - acx) - k2 * (ady - acy)
    apy = acy + k1 * (ady - acy) + k2 * (adx - acx)
    # link angles and rates, as lk.analyze reports them (coupler C->D, rocker B->D)
    links = []
    for x0, y0, vx0, vy0, ax0, ay0 in ((cx, cy, vcx, vcy, acx, acy), (bx, by, 0.0, 0.0, 0.0, 0.0)):
        ex, ey = dx - x0, dy - y0
        n2 = ex * ex + ey * ey
        links.append(
            (
                np.degrees(np.arctan2(ey, ex)),
                (ex * (vdy - vy0) - ey * (vdx - vx0)) / n2,
                (ex * (ady - ay0) - ey * (adx - ax0)) / n2,
            )
        )
    return dx, dy, px, py, vdx, vdy, vpx, vpy, adx, ady, apx, apy, links


def main(n=1_000_000):
    mech = lk.load(ROOT / "examples" / "seed000_fourbar.yaml")
    deg = np.linspace(0, 360, n)
    phi = np.radians(deg)
    w, al = 5.0, 2.0

    # same numbers first
    res = lk.analyze(mech, {"crank": deg[:1000]}, speed=w, acceleration=al)
    ref = hand_kernel(phi[:1000], w, al)
    assert np.allclose(res.point("P"), ref[2] + 1j * ref[3], atol=1e-12)
    assert np.allclose(res.velocity("P"), ref[6] + 1j * ref[7], atol=1e-9)
    assert np.allclose(res.acceleration("P"), ref[10] + 1j * ref[11], atol=1e-8)

    params = prepare(mech)
    q = phi[None, None, :]
    t_pos_lk = best_of(lambda: solve(params, q))
    t_pos_hand = best_of(lambda: hand_kernel(phi, w, al, with_rates=False))
    t_all_lk = best_of(lambda: lk.analyze(mech, {"crank": deg}, speed=w, acceleration=al, dynamics=False))
    t_all_hand = best_of(lambda: hand_kernel(phi, w, al))
    deg360 = np.arange(360.0)
    t_360 = best_of(lambda: solve(params, np.radians(deg360)[None, None, :]), repeat=50)
    t_360_all = best_of(lambda: lk.analyze(mech, {"crank": deg360}, dynamics=False), repeat=50)

    ns = 1e9 / n
    print(f"four-bar with coupler point (seed 000), N = {n:,} samples")
    print(
        f"positions            linkagekit {t_pos_lk * ns:8.1f} ns/sample   hand NumPy {t_pos_hand * ns:8.1f} ns/sample"
        f"   ratio {t_pos_lk / t_pos_hand:5.2f}  (goal <= 1.5)"
    )
    print(
        f"positions+vel+acc    lk.analyze {t_all_lk * ns:8.1f} ns/sample   hand NumPy {t_all_hand * ns:8.1f} ns/sample"
        f"   ratio {t_all_lk / t_all_hand:5.2f}  (goal <= 2)"
    )
    print(
        f"360-sample sweep     positions solve {t_360 * 1e3:.3f} ms (goal < 1 ms);"
        f" whole lk.analyze {t_360_all * 1e3:.3f} ms"
    )


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 1_000_000)
