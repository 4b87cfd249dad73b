"""Function generation benchmark: linkagekit's `--task function` and pylinkage 1.3.0's `function_generation`.

Problems (public data read from /work/shared/benchmarks/motion-function/targets.json):
- ``weaving_striking_5pair_function``: 5 pairs, ground 180 mm; goal: minimax at most 0.108 deg
  (the textbooks' least squares of Freudenstein's residual leaves 0.156 deg);
- ``pylinkage_nb3_function``: 3 pairs; goal: at most 1e-9 deg;
- random crank-rockers' own 6 pairs (fixed angle scales): goal: recovered to 1e-6 deg;
  with free offsets (the pairs shifted by unknown offsets) the figure is printed, not asserted.

Every error is that of the mechanism as `lk.analyze` solves it (the pose's assembly mode at
every input), and "one branch" means it also assembles at every input from the first pair to
the last (361 samples).  pylinkage's answers (its `raw_solutions`, at the first pair) are
judged the same way.  Run: ``PYTHONPATH=src python benchmarks/bench_function.py``.
"""

from __future__ import annotations

import json
import math
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

import linkagekit as lk
from linkagekit.synthesis.function import solve
from linkagekit.synthesis.function_run import synthesize_function

TARGETS = Path("/work/shared/benchmarks/motion-function/targets.json")
GOALS = {"weaving minimax": 0.108, "nb3": 1e-9, "random": 1e-6}
SECONDS = 30.0


def judge(
    joints: dict[str, Any], x: np.ndarray, y: np.ndarray, offsets: tuple[float, float] = (0, 0)
) -> tuple[float, bool]:
    """(max output-angle error in deg, assembles from the first pair to the last) of a four-bar at its pose."""
    links = {"ground": ["A", "B"], "crank": ["A", "C"], "coupler": ["C", "D"], "output": ["B", "D"]}
    drv = [{"link": "crank", "pivot": "A", "toward": "C", "angles": {"start": 0, "stop": 360, "step": 1}}]
    mech = lk.Mechanism.from_dict({"format": "linkagekit/1", "joints": joints, "links": links, "drivers": drv})
    ground = math.degrees(math.atan2(joints["B"][1] - joints["A"][1], joints["B"][0] - joints["A"][0]))
    psi = lk.analyze(mech, {"crank": x + offsets[0] + ground}).angle("output") - ground - offsets[1]
    err = (psi - y + 180.0) % 360.0 - 180.0
    dense = lk.analyze(mech, {"crank": np.linspace(x[0], x[-1], 361) + offsets[0] + ground})
    worst = float(np.max(np.abs(err))) if np.all(np.isfinite(err)) else math.inf
    return worst, bool(np.all(dense.assembled))


def ours(name: str, x: np.ndarray, y: np.ndarray, **kw: Any) -> dict[str, Any]:
    t0 = time.perf_counter()
    if kw.get("method", "minimax") == "minimax":  # the command's path: the engine, then the minimax polish
        kw.pop("method", None)
        fit = synthesize_function(x, y, **kw).fit
    else:
        fit = solve(x, y, **kw)
    seconds = time.perf_counter() - t0
    err, one = judge(fit.joints(), x, y, fit.offsets)
    method = kw.get("method", "engine + minimax") + (" free offsets" if kw.get("free_offsets") else "")
    return {
        "problem": name,
        "tool": "linkagekit",
        "method": method,
        "max_error_deg": err,
        "one_branch": one,
        "grashof": fit.grashof,
        "seconds": seconds,
    }


def theirs(name: str, x: np.ndarray, y: np.ndarray, d: float) -> dict[str, Any]:
    row: dict[str, Any] = {"problem": name, "tool": "pylinkage 1.3.0", "method": "function_generation"}
    try:
        from pylinkage.synthesis import function_generation
    except ImportError:
        return {
            **row,
            "max_error_deg": math.nan,
            "one_branch": None,
            "seconds": math.nan,
            "note": "pylinkage not installed",
        }
    t0 = time.perf_counter()
    try:
        res = function_generation(
            [(math.radians(a), math.radians(b)) for a, b in zip(x, y, strict=True)], ground_length=d
        )
        sols = list(res.raw_solutions)
    except Exception as e:  # noqa: BLE001 - a peer's failure is a result
        return {
            **row,
            "max_error_deg": math.nan,
            "one_branch": None,
            "seconds": time.perf_counter() - t0,
            "note": f"{type(e).__name__}: {e}"[:80],
        }
    seconds = time.perf_counter() - t0
    if not sols:
        return {**row, "max_error_deg": math.nan, "one_branch": None, "seconds": seconds, "note": "0 solutions"}
    judged = [
        judge({"A": s.ground_pivot_a, "B": s.ground_pivot_d, "C": s.crank_pivot_b, "D": s.coupler_pivot_c}, x, y)
        for s in sols
    ]
    err, one = min(judged)
    return {**row, "max_error_deg": err, "one_branch": one, "seconds": seconds, "note": f"{len(sols)} solutions"}


def random_crank_rocker(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, float]:
    """Six input/output pairs (deg) of a random crank-rocker, and its ground length."""
    while True:
        a, b, c, d = rng.uniform(0.2, 0.5), *rng.uniform(1.0, 3.0, 3)
        if a + max(b, c, d) < b + c + d - max(b, c, d) - 0.1:
            break
    sigma = rng.choice([-1.0, 1.0])
    x = rng.uniform(-180, 100) + np.sort(rng.uniform(0, 200, 6))
    C = a * np.exp(1j * np.radians(x))
    far = np.abs(C - d)
    psi = np.angle(C - d) + sigma * np.arccos((c * c + far * far - b * b) / (2 * c * far))
    return x, np.degrees(psi), d


def function_rows(randoms: int = 20) -> list[dict[str, Any]]:
    """One row per (problem, tool, method): max error (deg), one branch, seconds."""
    rows: list[dict[str, Any]] = []
    if TARGETS.exists():
        data = json.loads(TARGETS.read_text())
        w = np.array(data["weaving_striking_5pair_function"]["angle_pairs_deg"], float)
        for method in ("freudenstein", "least-squares", "minimax"):
            rows.append(ours("weaving", w[:, 0], w[:, 1], ground_length=180.0, method=method))
        rows.append(theirs("weaving", w[:, 0], w[:, 1], 180.0))
        n3 = np.array(data["pylinkage_nb3_function"]["angle_pairs_deg"], float)
        rows.append(ours("nb3", n3[:, 0], n3[:, 1]))
        rows.append(theirs("nb3", n3[:, 0], n3[:, 1], 1.0))
    rng = np.random.default_rng(2026)
    for k in range(randoms):
        x, y, d = random_crank_rocker(rng)
        rows.append(ours(f"random {k}", x, y, ground_length=d))
        rows.append(theirs(f"random {k}", x, y, d))
        off = rng.uniform(-60, 60, 2)
        rows.append(ours(f"random {k}", x - off[0], y - off[1], ground_length=d, free_offsets=True))
    return rows


def _check(rows: list[dict[str, Any]]) -> list[str]:
    bad = []
    for r in rows:
        if r["tool"] != "linkagekit":
            continue
        goal = {
            "weaving": GOALS["weaving minimax"] if r["method"] == "engine + minimax" else None,
            "nb3": GOALS["nb3"],
        }.get(r["problem"], GOALS["random"] if r["method"] == "engine + minimax" else None)
        if goal is not None and not (r["max_error_deg"] <= goal and r["one_branch"]):
            bad.append(f"{r['problem']} {r['method']}: {r['max_error_deg']:.3g} deg > {goal:g} or not one branch")
        if r["seconds"] > SECONDS:
            bad.append(f"{r['problem']} {r['method']}: {r['seconds']:.1f} s > {SECONDS:g} s")
    return bad


if __name__ == "__main__":
    rows = function_rows()
    print(f"{'problem':<10} {'tool':<16} {'method':<26} {'max err deg':>12} {'one branch':>10} {'s':>7}  note")
    for r in rows:
        print(
            f"{r['problem']:<10} {r['tool']:<16} {r['method']:<26} {r['max_error_deg']:12.4g} "
            f"{str(r['one_branch']):>10} {r['seconds']:7.3f}  {r.get('note', r.get('grashof', ''))}"
        )
    failures = _check(rows)
    print("\n".join(failures) or "all goals met")
    sys.exit(1 if failures else 0)
