"""One BLAS thread against OpenBLAS's default threads, on a large numerical group, in one run.

A strip of N dyads (2N + 3 joints' worth of links, every joint placed by one Newton group
with ``method="numerical"``) over 37 crank directions, solved in a fresh process each way:
as linkagekit runs it (``linkagekit.threads``: one BLAS thread while it computes) and with
that limit taken out (OpenBLAS's own threads: one per core). ``--busy K`` keeps K other
processes spinning meanwhile, as a shared machine does. Prints both wall times and their ratio.

    python benchmarks/bench_threads.py [N] [--busy K]
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import time

import numpy as np

CHILD = """
import contextlib, sys, time
import numpy as np
import linkagekit as lk
import linkagekit.threads as th
sys.path.insert(0, {here!r})
from bench_threads import strip
if {unlimited}:
    th.blas_limited = lambda with_scipy=False: contextlib.nullcontext()
mech = lk.Mechanism.from_dict(strip({n}))
t = time.perf_counter()
res = lk.analyze(mech, {{"crank": np.linspace(0.0, 360.0, 37)}}, method="numerical", rates=False)
print(time.perf_counter() - t, int(res.assembled.sum()))
"""


def strip(n: int, seed: int = 0) -> dict:
    """A strip of ``n`` dyads on a crank: joint ``X_k`` held by ``X_{k-1}`` and ``X_{k-2}`` (``X_0``: the crank's
    end C, ``X_{-1}``: the ground's B), zig-zagging so that no three are in line."""
    rng = np.random.default_rng(seed)
    joints = {"A": [0.0, 0.0], "B": [4.0, 1.0], "C": [2.0, 0.0]}
    links = {"ground": ["A", "B"], "crank": ["A", "C"]}
    names = ["B", "C"]
    for k in range(1, n + 1):
        joints[f"X{k}"] = [2.0 + 0.7 * k, 3.0 + 1.3 * (k % 2) + float(rng.uniform(-0.1, 0.1))]
        links[f"a{k}"] = [names[-1], f"X{k}"]
        links[f"b{k}"] = [names[-2], f"X{k}"]
        names.append(f"X{k}")
    return {
        "format": "linkagekit/1",
        "name": f"strip of {n} dyads",
        "joints": joints,
        "links": links,
        "drivers": [{"link": "crank", "pivot": "A", "toward": "C"}],
    }


def run(n: int, unlimited: bool) -> tuple[float, int]:
    """Wall seconds of the solve in a fresh process, and how many directions it assembled."""
    code = CHILD.format(here=str(__import__("pathlib").Path(__file__).parent), unlimited=unlimited, n=n)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    return float(out[0]), int(out[1])


def main(n: int = 60, busy: int = 0) -> float:
    spinners = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(busy)]
    try:
        time.sleep(0.2 if busy else 0.0)
        one, ok1 = run(n, unlimited=False)
        many, ok2 = run(n, unlimited=True)
    finally:
        for p in spinners:
            p.kill()
    assert ok1 == ok2, (ok1, ok2)
    print(f"strip of {n} dyads, 37 directions ({ok1} assembled), {busy} busy processes beside it")
    print(f"  one BLAS thread (linkagekit)   {one:8.2f} s")
    print(f"  OpenBLAS's default threads     {many:8.2f} s")
    print(f"ratio, default / one thread: {many / one:.1f}x")
    return many / one


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("n", nargs="?", type=int, default=60)
    ap.add_argument("--busy", type=int, default=0, help="processes kept spinning meanwhile")
    a = ap.parse_args()
    main(a.n, a.busy)
