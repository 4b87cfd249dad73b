"""Re-evaluate the design vectors stored in this folder's YAML files.

Independent of linkagekit on purpose: it implements the closed-form coupler
point of the "Cabrera-style" parametrisation described in each YAML file's
``parametrisation`` block, so that a stored value can be checked before it is
compared with linkagekit's own result.

    python benchmarks/synthesis_problems/evaluate_designs.py

prints, for every design vector in every YAML file of this folder that uses
the ``cabrera`` parametrisation, the value recomputed here, the value stated
by its source, and the constraint violations.
"""

from __future__ import annotations

import math
import pathlib
import sys

import yaml

HERE = pathlib.Path(__file__).resolve().parent


def coupler_point(d: dict, theta2: float) -> tuple[float, float] | None:
    """Coupler point for crank angle ``theta2`` (radians), or None if the
    loop does not close.

    theta3 = 2 atan((-B + sqrt(A^2 + B^2 - C^2)) / (C - A)) with
    A = 2 r3 (r2 cos t2 - r1), B = 2 r3 r2 sin t2,
    C = r1^2 + r2^2 + r3^2 - r4^2 - 2 r1 r2 cos t2 (ground link along the
    local x axis, theta1 = 0); the coupler point is
    r2 e^{i t2} + (rcx + i rcy) e^{i t3}, then rotated by theta0 and
    translated by (x0, y0).
    """
    r1, r2, r3, r4 = d["r1"], d["r2"], d["r3"], d["r4"]
    rcx, rcy = d["rcx"], d["rcy"]
    th0, x0, y0 = d.get("theta0", 0.0), d.get("x0", 0.0), d.get("y0", 0.0)
    a = 2 * r3 * (r2 * math.cos(theta2) - r1)
    b = 2 * r3 * r2 * math.sin(theta2)
    c = r1**2 + r2**2 + r3**2 - r4**2 - 2 * r1 * r2 * math.cos(theta2)
    disc = a * a + b * b - c * c
    if disc < 0:
        return None
    theta3 = 2 * math.atan((-b + math.sqrt(disc)) / (c - a))
    cxr = r2 * math.cos(theta2) + rcx * math.cos(theta3) - rcy * math.sin(theta3)
    cyr = r2 * math.sin(theta2) + rcx * math.sin(theta3) + rcy * math.cos(theta3)
    return (
        cxr * math.cos(th0) - cyr * math.sin(th0) + x0,
        cxr * math.sin(th0) + cyr * math.cos(th0) + y0,
    )


def objective(problem: dict, design: dict) -> float | None:
    angles = design.get("theta2")
    if angles is None and "theta2_start" in design:
        step = math.radians(problem["input_step_deg"])
        n = len(problem["targets"])
        angles = [design["theta2_start"] + i * step for i in range(n)]
    if angles is None:
        angles = [math.radians(a) for a in problem["inputs_deg"]]
    sets = problem.get("target_sets") or [problem["targets"]]
    total = 0.0
    for targets in sets:
        for (tx, ty), t2 in zip(targets, angles, strict=True):
            p = coupler_point(design, t2)
            if p is None:
                return None
            total += (tx - p[0]) ** 2 + (ty - p[1]) ** 2
    return total


def violations(design: dict) -> dict:
    """Positive numbers are violations; zero entries are dropped by main()."""
    r1, r2, r3, r4 = design["r1"], design["r2"], design["r3"], design["r4"]
    links = sorted([r1, r2, r3, r4])
    out = {
        # Grashof with the crank r2 the shortest link (crank-rocker or double crank)
        "grashof s+l-p-q": max(0.0, links[0] + links[3] - links[1] - links[2]),
        "crank r2 not shortest": max(0.0, r2 - links[0]),
        # the stricter ordering coded by the CIDETEC codes (roydes, jmejia8)
        "order r2<=r3<=r4<=r1, r1+r2<=r3+r4": max(0.0, r1 + r2 - r3 - r4)
        + max(0.0, r2 - r3)
        + max(0.0, r3 - r4)
        + max(0.0, r4 - r1),
    }
    t = design.get("theta2")
    if t:
        tau = 2 * math.pi
        fwd = sum((t[i + 1] - t[i]) % tau for i in range(len(t) - 1))
        bwd = sum((t[i] - t[i + 1]) % tau for i in range(len(t) - 1))
        # cyclic order: the crank visits the targets in the listed order within one turn
        # (a closed target list repeating its first point may use exactly one turn)
        out["not in cyclic order (either sense)"] = 0.0 if min(fwd, bwd) <= tau + 1e-6 else 1.0
        out["not plainly increasing in [0, 2pi)"] = sum(max(0.0, t[i] - t[i + 1]) for i in range(len(t) - 1))
    return out


def main() -> int:
    for path in sorted(HERE.glob("*.yaml")):
        problem = yaml.safe_load(path.read_text())
        if problem.get("parametrisation", {}).get("name") != "cabrera":
            continue
        print(f"== {path.name}")
        for entry in problem.get("published", []) + problem.get("reported_in_code", []):
            design = entry.get("design")
            if not design:
                continue
            value = objective(problem, design)
            viol = {k: v for k, v in violations(design).items() if v > 0}
            print(f"  {entry.get('by', '?')[:70]}")
            print(f"    stated {entry.get('value')!r}  recomputed {value!r}  violations {viol or 'none'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
