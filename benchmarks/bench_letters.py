"""LINK-ABC: the 26 letters by ``synthesize --topology auto``, scored by the benchmark's similarity chamfer.

Reads the letters and LInK's results from the shared benchmark directory (by path, never
copied) and scores each written mechanism's curve with ``similarity_chamfer`` of its
``score.py`` (imported from there, not reimplemented). One run, fixed seed; per letter:
ours, LInK's, joints, topology, crank range, time; then the goal counts (issue 30: below
0.99 x LInK's on at least 16 letters, at least one closed; mean at most 0.018).

    PYTHONPATH=src python benchmarks/bench_letters.py                 # 60 s a letter, 2 workers: 26 min
    PYTHONPATH=src python benchmarks/bench_letters.py --seconds 5 --letters A,C,O
    PYTHONPATH=src python benchmarks/bench_letters.py --min-transmission 0   # no transmission bound, as LInK
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import sys
import time
from typing import Any

import numpy as np

import linkagekit as lk
from linkagekit.synthesis.auto import synthesize_auto

LINK_ABC = "/work/shared/benchmarks/link-abc"


def _score_module() -> Any:
    spec = importlib.util.spec_from_file_location("link_abc_score", os.path.join(LINK_ABC, "score.py"))
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def run_letter(
    letter: dict[str, Any], seconds: float, seed: int, workers: int, max_joints: int, **problem: Any
) -> dict[str, Any]:
    """Synthesize one letter (shape-only, partial if open) and score its written mechanism; ``problem``: further
    keywords of the synthesis (``min_transmission``)."""
    score = _score_module()
    T = np.asarray(letter["target_xy"], float)
    closed = str(letter["closed"]) == "True"
    t0 = time.monotonic()
    out = synthesize_auto(
        T, max_joints=max_joints, seconds=seconds, seed=seed, workers=workers, partial=not closed, **problem
    )
    took = time.monotonic() - t0
    mech = out.mechanism
    a = mech.to_dict()["drivers"][0]["angles"]
    res = lk.analyze(mech, {"crank": np.linspace(a["start"], a["stop"], 2001)}, rates=False, dynamics=False)
    P = res.xy("P")
    return {
        "letter": letter["letter"],
        "closed": closed,
        "ours": float(score.similarity_chamfer(P, T)),
        "link": float(letter["link_result"]["CD_similarity"]),
        "joints": len(mech.joint_names),
        "topology": out.topology,
        "crank": abs(a["stop"] - a["start"]),
        "assembles": bool(np.all(res.assembled)),
        "feasible": out.feasible,
        "seconds": took,
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=60.0, help="time per letter (default 60)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--max-joints", type=int, default=10)
    ap.add_argument("--letters", default="", help="comma-separated letters (default all 26)")
    ap.add_argument(
        "--min-transmission", type=float, default=None, help="degrees (default: the library's, 20; LInK has none)"
    )
    a = ap.parse_args()
    problem = {} if a.min_transmission is None else {"min_transmission": a.min_transmission}
    with open(os.path.join(LINK_ABC, "letters.json")) as fh:
        data = json.load(fh)
    want = set(a.letters.split(",")) if a.letters else None
    rows = []
    print(f"{'letter':6} {'ours':>8} {'LInK':>8} {'joints':>6} {'topology':>14} {'crank':>7} {'time':>6}  ok")
    for letter in data["letters"]:
        if want and letter["letter"] not in want:
            continue
        r = run_letter(letter, a.seconds, a.seed, a.workers, a.max_joints, **problem)
        rows.append(r)
        ok = "yes" if r["assembles"] and r["feasible"] else "NO"
        print(
            f"{r['letter']:6} {r['ours']:8.5f} {r['link']:8.5f} {r['joints']:6d} {r['topology']:>14} "
            f"{r['crank']:6.1f}° {r['seconds']:5.1f}s  {ok}",
            flush=True,
        )
    wins = [r for r in rows if r["ours"] < 0.99 * r["link"]]
    mean = float(np.mean([r["ours"] for r in rows]))
    print(
        f"below 0.99 x LInK: {len(wins)} of {len(rows)} ({sum(r['closed'] for r in wins)} closed); "
        f"mean {mean:.5f} (LInK {np.mean([r['link'] for r in rows]):.5f}); "
        f"every mechanism assembles and meets the rules: {all(r['assembles'] and r['feasible'] for r in rows)}"
    )
    goal = len(wins) >= 16 and any(r["closed"] for r in wins) and mean <= 0.018
    print("goal (>= 16 letters below, one closed, mean <= 0.018):", "met" if goal else "NOT met")
    return 0 if goal else 1


if __name__ == "__main__":
    sys.exit(main())
