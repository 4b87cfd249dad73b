"""``--shape-only`` and ``--partial`` on random cases: how close, how long (issue 30's shape-only goal:
targets that are a turned, scaled and moved copy of a four-bar's coupler curve matched to 0.1 % of the
diagonal, the written mechanism lying on them).

Shape-only: for each of ``K`` random four-bars whose crank turns fully (the designs of
``tests/test_synthesis.py``), 12 targets at random crank angles on its coupler curve, turned by a
random angle, scaled by 0.2 to 5 and moved; ``synthesize(..., shape_only=True)``. A random Watt II
case is added. Partial: a random non-Grashof four-bar (its crank cannot turn fully) with 10 targets
spread over 100 to 150 degrees of its crank's range; ``synthesize(..., partial=True)``, with and
without ``shape_only``.

Every error is measured independently of the synthesis: the written mechanism's curve by
``lk.analyze`` every 0.01 degree over its own sweep, point-to-segment distances; the written
sweep is checked to assemble everywhere (and to be at least 90 degrees when partial). Printed per
case: the error (% of the diagonal), the time to the first answer within 0.1 % (from the
progress callback), the whole time, the crank's range.

    python benchmarks/bench_shape.py [K] [SECONDS] [shape,partial]   # default 5 cases, 30 s each, one worker
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

import linkagekit as lk
from linkagekit.synthesis.run import synthesize

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from test_synthesis import diagonal, random_designs  # noqa: E402


def sweep_distance(mech: lk.Mechanism, T: np.ndarray, step: float = 0.01) -> tuple[np.ndarray, float]:
    """Distances (m,) from the targets to the tracer's polyline over the file's own sweep, and the sweep (deg)."""
    sw = mech.drivers[0].sweep
    lo, hi = sorted((sw.start, sw.values()[-1]))
    res = lk.analyze(mech, {"crank": np.arange(lo, hi + step / 2, step)})
    assert np.all(res.assembled), "the written mechanism does not assemble over its sweep"
    P = res.xy("P")
    a, ab = P[:-1], P[1:] - P[:-1]
    s = np.clip(np.einsum("kij,ij->ki", T[:, None] - a[None], ab) / np.sum(ab * ab, axis=1), 0.0, 1.0)
    return np.min(np.hypot(*np.moveaxis(a[None] + s[..., None] * ab[None] - T[:, None], -1, 0)), axis=1), hi - lo


def run(name: str, T: np.ndarray, topology: str, seconds: float, **options: object) -> dict[str, object]:
    """One synthesis, measured: its error, time to 0.1 %, and its sweep."""
    L = diagonal(T)
    first = [np.inf]
    t0 = time.monotonic()

    def progress(p: object) -> None:
        if getattr(p, "best_error", np.nan) <= 1e-3 and first[0] == np.inf:
            first[0] = time.monotonic() - t0

    out = synthesize(T, topology, seconds=seconds, progress=progress, **options)  # type: ignore[arg-type]
    took = time.monotonic() - t0
    d, span = sweep_distance(out.mechanism, T)
    err = float(np.max(d) / L)
    if err <= 1e-3 and first[0] == np.inf:
        first[0] = took
    row = {"case": name, "error %": 100 * err, "to 0.1 % [s]": first[0], "time [s]": took, "sweep [deg]": span}
    row["feasible"] = out.feasible
    row["printed = measured"] = bool(np.allclose(d, out.errors, atol=1e-6 * L))
    print(
        f"{name:28s} {100 * err:10.4f} {first[0]:10.1f} {took:8.1f} {span:8.1f}  {out.feasible!s:5s} "
        f"{row['printed = measured']!s:5s} {out.outcome.stopped_by}",
        flush=True,
    )
    return row


def similar(P: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Points (m, 2) turned by a random angle, scaled by 0.2 to 5 and moved by up to 10."""
    z = (P[:, 0] + 1j * P[:, 1]) * np.exp(1j * rng.uniform(0, 2 * np.pi)) * np.exp(rng.uniform(np.log(0.2), np.log(5)))
    z += complex(*rng.uniform(-10, 10, 2))
    return np.c_[z.real, z.imag]


def rocking_fourbar(rng: np.random.Generator) -> tuple[lk.Mechanism, tuple[float, float]]:
    """A random non-Grashof four-bar whose crank rocks through more than 160 deg, and that range (deg)."""
    while True:
        a, b, c = rng.uniform(0.5, 2.0, 3) * [1.6, 1.0, 1.0]
        th = rng.uniform(-0.5, 0.5)
        C = a * np.exp(1j * th)
        data = {
            "format": "linkagekit/1",
            "joints": {"A": [0, 0], "B": [2, 0], "C": [C.real, C.imag], "D": [0, 0], "P": [0, 0]},
            "links": {"ground": ["A", "B"], "crank": ["A", "C"], "coupler": ["C", "D", "P"], "rocker": ["B", "D"]},
            "drivers": [{"link": "crank", "pivot": "A", "toward": "C", "angles": {"start": 0, "stop": 360, "step": 1}}],
        }
        d = abs(2 - C)
        if not abs(b - c) < d < b + c:
            continue
        cosg = (b * b + d * d - c * c) / (2 * b * d)
        D = C + b * (2 - C) / d * np.exp(1j * np.arccos(cosg))
        P = C + (D - C) * complex(*rng.uniform(-1, 1.5, 2))
        data["joints"]["D"], data["joints"]["P"] = [D.real, D.imag], [P.real, P.imag]
        mech = lk.Mechanism.from_dict(data, "<random rocking four-bar>")
        rep = lk.check(mech)
        ranges = rep.input_ranges["crank"]
        if len(ranges) == 1 and 160 < ranges[0][1] - ranges[0][0] < 360:
            return mech, (ranges[0][0], ranges[0][1])


def main(k: int = 5, seconds: float = 30.0, parts: str = "shape,partial") -> list[dict[str, object]]:
    """``parts``: which cases run (``shape``, ``partial``); the random cases are the same either way."""
    rng = np.random.default_rng(30)
    rows = []
    print(f"{'case':28s} {'error %':>10s} {'to 0.1 %':>10s} {'time':>8s} {'sweep':>8s}  feas. print stopped by")
    shapes = [(f"fourbar {i}", "fourbar", mech) for i, mech in enumerate(random_designs("fourbar", k, seed=17))]
    for name, topology, mech in [*shapes, ("watt2", "watt2", random_designs("watt2", 1, seed=11)[0])]:
        T = similar(lk.analyze(mech, {"crank": np.sort(rng.uniform(0, 360, 12))}).xy("P"), rng)
        if "shape" in parts:
            rows.append(run(f"shape-only {name}", T, topology, seconds, shape_only=True))
    for i in range(max(2, k // 2) if "partial" in parts else 0):
        mech, (lo, hi) = rocking_fourbar(rng)
        span = rng.uniform(100, min(150, hi - lo - 10))
        start = rng.uniform(lo + 5, hi - 5 - span)
        P = lk.analyze(mech, {"crank": np.linspace(start, start + span, 10)}).xy("P")
        rows.append(run(f"partial {i} ({span:.0f} deg)", P, "fourbar", seconds, partial=True, min_transmission=10))
        T = similar(P, rng)
        rows.append(
            run(f"partial+shape {i}", T, "fourbar", seconds, partial=True, shape_only=True, min_transmission=10)
        )
    ok = [r for r in rows if str(r["case"]).startswith("shape-only")]
    met = sum(float(r["error %"]) <= 0.1 for r in ok)  # type: ignore[arg-type]
    print(f"shape-only: {met} of {len(ok)} within 0.1 % of the diagonal in {seconds:g} s")
    assert all(r["printed = measured"] for r in rows), "a printed error differs from the written mechanism's"
    assert all(float(r["sweep [deg]"]) >= 90.0 - 1e-9 for r in rows)  # type: ignore[arg-type]
    return rows


if __name__ == "__main__":
    args = sys.argv[1:]
    main(int(args[0]) if args else 5, float(args[1]) if len(args) > 1 else 30.0, *args[2:3])
