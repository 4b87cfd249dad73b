"""linkagekit's four-bar synthesis on the six published problems of ``benchmarks/synthesis_problems``.

For every problem file (targets, timing, parametrisation ``cabrera``, published designs):

1. **Cross-check of the evaluators.** Every design vector of the file (``published`` and
   ``reported_in_code``) is turned into a mechanism (joints A, B ground, C crank tip, D, P
   tracer, posed at its first crank angle) and analysed by ``lk.analyze`` at its crank
   angles; the sum of squared distances must equal the value of ``evaluate_designs.py``
   (the cabrera closed form, independent of linkagekit). ``lk.check`` then says whether its
   crank turns fully and whether its transmission angle stays within [20, 160] degrees
   (what the comparison asks of every design; the published problems do not constrain it).
2. **Our synthesis.** ``synthesize(targets, "fourbar", ...)`` for a fixed budget (``--seconds``,
   fixed ``--seed``, one worker, ``min_transmission=20``, ``reach`` per ``--reach``: the joints lie
   within reach x the targets' diagonal of their centre, the library's default is 1), with
   the problem's timing as ``inputs`` (crank angle = input + one free offset; ground frame
   free) or, without timing, free crank angles (``ordered=True`` where the problem asks for
   a sequence). Two target sets (``pairs10``) are synthesised on their midpoints: for the
   same crank angles ``|P1 - C|^2 + |P2 - C|^2 = 2 |M - C|^2 + |P1 - P2|^2 / 2``, so the
   published objective and ours have the same minimisers.
3. **Our design under the published objective.** Our mechanism is converted to the cabrera
   variables (r1..r4, rcx, rcy, theta0, x0, y0, theta2^i from ``Synthesis.inputs``) and
   evaluated by ``evaluate_designs.objective``, the evaluator of the published designs
   (a design in the other assembly branch than the closed form's root is evaluated, by the
   same function, as its mirror image on the mirrored targets: same value). The value is
   also recomputed through ``lk.analyze`` and from ``Synthesis.errors``.
4. **Fair variant** where the published problem fixes the ground frame (``timing5``: theta0 =
   x0 = y0 = 0, absolute crank angles): a template four-bar with A fixed at the origin and B
   kept on the +x axis. Our API cannot also fix the timing offset (it is read off the
   pose's crank angle, and a joint's bounds are an axis-aligned box, so C cannot be held on
   the first input's ray while B is held on the x axis): the variant keeps that one extra
   degree of freedom, and the offset found is reported, with the value of the same design
   put exactly into the published formulation (theta0 = x0 = y0 = 0, theta2 = the inputs).

Printed: three markdown tables (the cross-check, the comparison with its notes on how the
formulations differ, the search), progress on stderr, every number with ``--json``. The
run is stopped by the clock, so its numbers vary a little with the machine's load.

    python benchmarks/bench_published.py [--seconds 120] [--seed 1] [--reach 1 [3 ...]] [--workers 1] [--only NAME ...]
                                         [--no-fair] [--json FILE]
"""

from __future__ import annotations

import argparse
import copy
import json
import math
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import yaml

import linkagekit as lk
from linkagekit.model import Mechanism
from linkagekit.synthesis.run import make_problem, synthesize

HERE = Path(__file__).resolve().parent
PROBLEMS = HERE / "synthesis_problems"
sys.path.insert(0, str(PROBLEMS))
from evaluate_designs import coupler_point, objective, violations  # noqa: E402

MIN_TRANSMISSION = 20.0
#: relative agreement asked of two evaluators of one design (cabrera closed form vs lk.analyze)
RTOL = 1e-6
#: goal of the search (largest target error / diagonal): small, so that the budget decides
GOAL = 1e-10
RESTARTS = 10_000  # the clock stops the run first
WORKERS: list[int | None] = [1]  # ``--workers`` (None: the library's default, every core)
TEMPLATE = {
    "format": "linkagekit/1",
    "name": "four-bar, crank pivot A fixed at the origin, B on the +x axis",
    "units": {"length": "m", "angle": "deg"},
    "joints": {"A": [0, 0], "B": [1, 0], "C": [0.3, 0], "D": [0.8, 0.6], "P": [0.5, 0.9]},
    "links": {"ground": ["A", "B"], "crank": ["A", "C"], "coupler": ["C", "D", "P"], "rocker": ["B", "D"]},
    "drivers": [{"link": "crank", "pivot": "A", "toward": "C", "angles": {"start": 0, "stop": 360, "step": 1}}],
}


# ---------------------------------------------------------------------- the problems
def load_problems(only: list[str] | None) -> list[tuple[str, dict[str, Any]]]:
    out = []
    for path in sorted(PROBLEMS.glob("*.yaml")):
        problem = yaml.safe_load(path.read_text())
        if problem.get("parametrisation", {}).get("name") != "cabrera":
            continue
        if only and not any(o in path.stem for o in only):
            continue
        out.append((path.stem, problem))
    return out


def target_sets(problem: dict[str, Any]) -> list[np.ndarray]:
    return [np.asarray(t, float) for t in (problem.get("target_sets") or [problem["targets"]])]


def fixed_frame(problem: dict[str, Any]) -> bool:
    """The published problem fixes the ground frame (no theta0 among its variables)."""
    return "theta0" not in problem["parametrisation"]["variables"]


def timing(problem: dict[str, Any]) -> tuple[str, list[float] | None]:
    """(kind, inputs in degrees or None): 'prescribed', 'free start' or 'none'."""
    n = len(problem["targets"])
    if "inputs_deg" in problem:
        return "prescribed", [float(a) for a in problem["inputs_deg"]]
    if "input_step_deg" in problem:
        return "free start", [i * float(problem["input_step_deg"]) for i in range(n)]
    return "none", None


def sequence_asked(problem: dict[str, Any]) -> bool:
    """An untimed problem whose crank angles must come in the targets' order."""
    cons = problem.get("constraints", [])
    return timing(problem)[0] == "none" and any("sequence" in c or "theta2^1 <" in c for c in cons)


def relevant(problem: dict[str, Any], design: dict[str, Any]) -> list[str]:
    """The violations (``evaluate_designs.violations``) of the constraint set the problem's source uses:
    Grashof with r2 the shortest link and a cyclic order (Nguyen-Van), or the CIDETEC link ordering and
    plainly increasing angles (when the file lists only those)."""
    nguyen_van = any(c.startswith("Grashof") for c in problem.get("constraints", []))
    keys = ["grashof s+l-p-q", "crank r2 not shortest"] if nguyen_van else ["order r2<=r3<=r4<=r1, r1+r2<=r3+r4"]
    if sequence_asked(problem):
        keys.append("not in cyclic order (either sense)" if nguyen_van else "not plainly increasing in [0, 2pi)")
    v = violations(design)
    return [k for k in keys if v.get(k, 0.0) > 0]


def entries(problem: dict[str, Any]) -> list[tuple[str, dict[str, Any], dict[str, Any]]]:
    """(kind, entry, design) of every design vector of the file: kind 'published' or 'code'."""
    out = []
    for kind, key in (("published", "published"), ("code", "reported_in_code")):
        for e in problem.get(key) or []:
            if e.get("design"):
                out.append((kind, e, e["design"]))
    return out


def label(entry: dict[str, Any]) -> str:
    by = " ".join(str(entry.get("by", "?")).split())
    for cut in (" (", ";", ","):
        if cut in by[3:]:
            by = by[: 3 + by[3:].index(cut)]
    return by[:60]


def angles(problem: dict[str, Any], design: dict[str, Any]) -> list[float]:
    """The crank angles theta2^i (radians, from the ground line) of a design, as ``objective`` uses them."""
    if design.get("theta2") is not None:
        return [float(t) for t in design["theta2"]]
    if "theta2_start" in design:
        step = math.radians(problem["input_step_deg"])
        return [design["theta2_start"] + i * step for i in range(len(problem["targets"]))]
    return [math.radians(a) for a in problem["inputs_deg"]]


# ---------------------------------------------------------------------- cabrera <-> mechanism
def frame(design: dict[str, Any]) -> tuple[float, complex]:
    return float(design.get("theta0", 0.0)), complex(design.get("x0", 0.0), design.get("y0", 0.0))


def joints_at(design: dict[str, Any], theta2: float) -> dict[str, complex] | None:
    """A, B, C, D, P of a cabrera design at crank angle ``theta2`` (the closed form's branch), None if open."""
    th0, a = frame(design)
    p = coupler_point(design, theta2)
    d = coupler_point({**design, "rcx": design["r3"], "rcy": 0.0}, theta2)  # D: the coupler point at (r3, 0)
    if p is None or d is None:
        return None
    rot = complex(math.cos(th0), math.sin(th0))
    return {
        "A": a,
        "B": a + design["r1"] * rot,
        "C": a + design["r2"] * rot * complex(math.cos(theta2), math.sin(theta2)),
        "D": complex(*d),
        "P": complex(*p),
    }


def mechanism_of(design: dict[str, Any], theta2: float, name: str) -> Mechanism | None:
    """The mechanism file of a cabrera design, posed at crank angle ``theta2``."""
    j = joints_at(design, theta2)
    if j is None:
        return None
    data = copy.deepcopy(TEMPLATE)
    data["name"] = name
    data["joints"] = {k: [v.real, v.imag] for k, v in j.items()}
    return Mechanism.from_dict(data, source=name)


def cabrera_of(mech: Mechanism) -> tuple[dict[str, Any], int]:
    """(cabrera design without crank angles, branch): branch +1 when the closed form's root
    gives the mechanism's D, -1 for the mirror assembly (then the mirrored design is in the branch)."""
    z = dict(zip(mech.joint_names, (complex(*p) for p in mech.pose_array()), strict=True))
    a, b, c, d, p = (z[k] for k in "ABCDP")
    u = (d - c) / abs(d - c)
    rc = (p - c) * u.conjugate()
    design = {
        "r1": abs(b - a),
        "r2": abs(c - a),
        "r3": abs(d - c),
        "r4": abs(d - b),
        "rcx": rc.real,
        "rcy": rc.imag,
        "theta0": math.atan2((b - a).imag, (b - a).real),
        "x0": a.real,
        "y0": a.imag,
    }
    t2 = math.atan2((c - a).imag, (c - a).real) - design["theta0"]
    j = joints_at(design, t2)
    size = max(abs(b - a), abs(c - a), abs(d - c), abs(d - b))
    branch = 1 if j is not None and abs(j["D"] - d) <= 1e-7 * size else -1
    return design, branch


def mirrored(problem: dict[str, Any], design: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
    """The problem and design mirrored in the x axis (targets y -> -y, theta0, y0, rcy, theta2 negated):
    a design of the other branch becomes one of the closed form's branch, with the same objective."""
    prob = copy.deepcopy(problem)
    prob["targets"] = [[x, -y] for x, y in problem["targets"]]
    if problem.get("target_sets"):
        prob["target_sets"] = [[[x, -y] for x, y in s] for s in problem["target_sets"]]
    des = {**design, "rcy": -design["rcy"], "theta0": -design.get("theta0", 0.0), "y0": -design.get("y0", 0.0)}
    des["theta2"] = [-t for t in angles(problem, design)]
    des.pop("theta2_start", None)
    return prob, des


def published_objective(problem: dict[str, Any], design: dict[str, Any], branch: int = 1) -> float | None:
    """``evaluate_designs.objective`` of a design (its mirror image on the mirrored targets for branch -1)."""
    if branch == 1:
        return objective(problem, design)
    return objective(*mirrored(problem, design))


def analyze_objective(problem: dict[str, Any], mech: Mechanism, crank_deg: np.ndarray) -> float:
    """The published objective through ``lk.analyze``: sum over the target sets of squared distances."""
    res = lk.analyze(mech, {"crank": np.asarray(crank_deg, float)}, rates=False, dynamics=False)
    pts = res.xy("P")
    return float(sum(np.sum((t - pts) ** 2) for t in target_sets(problem)))


def checked(mech: Mechanism) -> dict[str, Any]:
    """Full turn, transmission angle (min, max) and Grashof type by ``lk.check``."""
    rep = lk.check(mech)
    ta = rep.transmission_angle or {}
    full = rep.input_range == [[0.0, 360.0]]
    lo, hi = ta.get("min", float("nan")), ta.get("max", float("nan"))
    return {
        "full_turn": full,
        "input_range": rep.input_range,
        "mu_min": lo,
        "mu_max": hi,
        "mu_worst": min(lo, 180.0 - hi),
        "grashof": rep.grashof,
        "ok": bool(full and lo >= MIN_TRANSMISSION - 1e-9 and hi <= 180.0 - MIN_TRANSMISSION + 1e-9),
    }


# ---------------------------------------------------------------------- part 1: published designs
def cross_check(name: str, problem: dict[str, Any]) -> list[dict[str, Any]]:
    rows = []
    for kind, entry, design in entries(problem):
        value = objective(problem, design)
        th = angles(problem, design)
        th0, _ = frame(design)
        mech = mechanism_of(design, th[0], f"{name}: {label(entry)}")
        row: dict[str, Any] = {"problem": name, "kind": kind, "by": label(entry), "value": value}
        if mech is None:
            row["note"] = "does not assemble at its first crank angle"
            rows.append(row)
            continue
        crank = np.degrees(th0 + np.asarray(th))
        row["analyze"] = analyze_objective(problem, mech, crank)
        row["agree"] = value is not None and abs(row["analyze"] - value) <= RTOL * max(value, 1e-300) + 1e-18
        row.update(checked(mech))
        row["violations"] = relevant(problem, design)
        rows.append(row)
    return rows


# ---------------------------------------------------------------------- part 2/3: our synthesis
def our_targets(problem: dict[str, Any]) -> np.ndarray:
    sets = target_sets(problem)
    return sets[0] if len(sets) == 1 else np.mean(sets, axis=0)


def evaluate_ours(problem: dict[str, Any], syn: Any, strict: bool = True) -> dict[str, Any]:
    """Our design under the published objective, three ways, and its checks.

    ``strict``: also its value in the published formulation exactly (``at_published_timing``): crank angles
    from the ground line = the inputs and, for a fixed-frame problem, theta0 = x0 = y0 = 0 (meaningful when
    our frame was fixed too)."""
    mech = syn.mechanism
    design, branch = cabrera_of(mech)
    crank = np.asarray(syn.inputs, float)  # absolute crank angles (deg) where the targets are met
    design["theta0"] %= 2 * math.pi  # within the published bounds [0, 2 pi)
    design["theta2"] = [float(t) for t in (np.radians(crank) - design["theta0"]) % (2 * math.pi)]
    value = published_objective(problem, design, branch)
    via_analyze = analyze_objective(problem, mech, crank)
    sets = target_sets(problem)
    e2 = float(np.sum(np.asarray(syn.errors) ** 2))
    if len(sets) > 1:  # errors are to the midpoints
        e2 = len(sets) * e2 + sum(float(np.sum((s - our_targets(problem)) ** 2)) for s in sets)
    out: dict[str, Any] = {
        "value": value,
        "analyze": via_analyze,
        "from_errors": e2,
        "agree": value is not None and abs(via_analyze - value) <= RTOL * max(value, 1e-300) + 1e-18,
        "branch": branch,
        "design": design,
        "offset": syn.offset,
        "max_error": syn.max_error,
        "feasible": syn.feasible,
        "min_transmission_synthesis": syn.min_transmission,
        "violations": relevant(problem, design),
        "outcome": {
            "restarts": syn.outcome.restarts,
            "generations": syn.outcome.generations,
            "evaluations": syn.outcome.evaluations,
            "seconds": syn.outcome.seconds,
            "stopped_by": syn.outcome.stopped_by,
        },
    }
    out.update(checked(mech))
    kind, inputs = timing(problem)
    if kind != "none" and inputs is not None:
        rel = np.degrees(np.asarray(design["theta2"])) - np.asarray(inputs)  # crank from ground - input
        out["timing_shift_deg"] = float((rel[0] + 180.0) % 360.0 - 180.0)
        out["timing_spread_deg"] = float(np.ptp((rel - rel[0] + 180.0) % 360.0 - 180.0))
        if strict and kind == "prescribed" and branch == 1:  # at the published timing (theta2 = inputs exactly)
            exact = {**design, "theta2": [math.radians(a) for a in inputs]}
            if fixed_frame(problem):
                exact.update(theta0=0.0, x0=0.0, y0=0.0)
            out["at_published_timing"] = objective(problem, exact)
    return out


def in_box(problem_obj: Any, mech: Mechanism | None) -> bool | None:
    """Whether a mechanism's pose lies within a synthesis problem's bounds."""
    if mech is None:
        return None
    x = problem_obj.space.vector(mech)
    lo, hi = problem_obj.bounds
    return bool(np.all(x >= lo - 1e-12) and np.all(x <= hi + 1e-12))


def reach_needed(targets: np.ndarray, mech: Mechanism | None) -> float | None:
    """The ``reach`` whose default box (targets' centre +- reach x diagonal) holds joints A, B, C, D of ``mech``."""
    if mech is None:
        return None
    centre = (targets.min(axis=0) + targets.max(axis=0)) / 2
    diag = float(np.hypot(*np.ptp(targets, axis=0)))
    pose = dict(zip(mech.joint_names, mech.pose_array(), strict=True))
    return float(max(np.max(np.abs(pose[j] - centre)) for j in "ABCD") / diag)


def run_ours(
    name: str, problem: dict[str, Any], seconds: float, seed: int, best: dict[str, Any] | None, reach: float = 1.0
) -> dict[str, Any]:
    kind, inputs = timing(problem)
    ordered = sequence_asked(problem)
    targets = our_targets(problem)
    t0 = time.monotonic()
    syn = synthesize(
        targets,
        "fourbar",
        inputs=inputs,
        units="m",
        ordered=ordered,
        min_transmission=MIN_TRANSMISSION,
        reach=reach,
        seed=seed,
        seconds=seconds,
        restarts=RESTARTS,
        goal=GOAL,
        workers=WORKERS[0],
    )
    wall = time.monotonic() - t0
    out = evaluate_ours(problem, syn, strict=not fixed_frame(problem))
    out.update(
        {"problem": name, "variant": "default", "wall": wall, "ordered": ordered, "timing": kind, "reach": reach}
    )
    if best is not None:  # is the best published design inside our default search box?
        prob = make_problem(targets, "fourbar", inputs, "m", ordered, MIN_TRANSMISSION, reach=reach)
        mech = mechanism_of(best, angles(problem, best)[0], "best")
        out["best_published_in_box"] = in_box(prob, mech)
        out["best_published_reach"] = reach_needed(targets, mech)
    return out


def fixed_frame_template(targets: np.ndarray, reach: float = 1.0) -> tuple[Mechanism, dict[str, Any]]:
    """Template with A at the origin (not free), B on the +x axis (within 1e-6 diagonals), C and D in the box of
    the targets and the origin widened by ``1 + reach`` diagonals, P near the first target (as ``synthesize`` does)."""
    lo = np.minimum(targets.min(axis=0), 0.0)
    hi = np.maximum(targets.max(axis=0), 0.0)
    diag = float(np.hypot(*np.ptp(targets, axis=0)))
    w = (1.0 + reach) * diag
    box = ((lo[0] - w, hi[0] + w), (lo[1] - w, hi[1] + w))
    eps = 1e-6 * diag
    first = targets[0]
    free = {
        "B": ((eps, box[0][1]), (-eps, eps)),
        "C": box,
        "D": box,
        "P": ((first[0] - 0.05 * diag, first[0] + 0.05 * diag), (first[1] - 0.05 * diag, first[1] + 0.05 * diag)),
    }
    mech = Mechanism.from_dict(copy.deepcopy(TEMPLATE), source="fixed-frame template")
    return mech, free


def run_fixed_frame(
    name: str, problem: dict[str, Any], seconds: float, seed: int, best: dict[str, Any] | None, reach: float = 1.0
) -> dict[str, Any]:
    _, inputs = timing(problem)
    targets = our_targets(problem)
    template, free = fixed_frame_template(targets, reach)
    t0 = time.monotonic()
    syn = synthesize(
        targets,
        template,
        inputs=inputs,
        units="m",
        min_transmission=MIN_TRANSMISSION,
        free=free,
        seed=seed,
        seconds=seconds,
        restarts=RESTARTS,
        goal=GOAL,
        workers=WORKERS[0],
    )
    wall = time.monotonic() - t0
    out = evaluate_ours(problem, syn, strict=True)
    out.update(
        {
            "problem": name,
            "variant": "fixed frame",
            "wall": wall,
            "ordered": False,
            "timing": "prescribed",
            "reach": reach,
        }
    )
    if best is not None:
        prob = make_problem(targets, template, inputs, "m", False, MIN_TRANSMISSION, free=free)
        out["best_published_in_box"] = in_box(prob, mechanism_of(best, angles(problem, best)[0], "best"))
    return out


# ---------------------------------------------------------------------- notes
def differences(problem: dict[str, Any], ours: dict[str, Any]) -> list[str]:
    """How the published formulation differs from what our run optimised (and what our design does)."""
    notes = []
    kind, _ = timing(problem)
    if ours["variant"] == "fixed frame":
        notes.append(
            f"A fixed at (0, 0), B on +x (theta0 = {math.remainder(ours['design']['theta0'], 2 * math.pi):.1e}); "
            "the timing offset stays free "
            f"(ours {ours['timing_shift_deg']:+.4g} deg, published 0): not expressible in our API"
        )
        s = ours.get("at_published_timing")
        if s is not None:
            notes.append(
                f"the same r1..r4, rcx, rcy with theta0 = x0 = y0 = 0 and theta2 = the inputs exactly "
                f"(the published formulation) give {s:.4g}"
            )
    elif fixed_frame(problem):
        notes.append(
            "published: frame fixed (theta0 = x0 = y0 = 0) and absolute crank angles; ours: frame and offset free"
        )
    if kind == "prescribed" and not fixed_frame(problem):
        s = ours.get("at_published_timing")
        notes.append(
            "published: crank angle from the ground line = input (theta0 free); ours: input + a free offset, "
            f"one more freedom (ours: crank - input = {ours['timing_shift_deg']:+.4g} deg from the ground line"
            + (f"; at the published timing our design gives {s:.4g}" if s is not None else "")
            + ")"
        )
    if kind == "free start":
        notes.append("timing as published (20 deg steps from a free start angle)")
    if kind == "none":
        notes.append(
            "free crank angles; "
            + ("ordered=True (cyclic, either sense)" if ours["ordered"] else "no sequence asked")
            + (
                "; published sequence: increasing"
                if "theta2^1 < theta2^2" in " ".join(problem.get("constraints", []))
                else ""
            )
        )
    if problem.get("target_sets"):
        notes.append("two target sets: ours synthesised on their midpoints (same minimisers)")
    if ours["branch"] == -1:
        notes.append(
            "our design is in the other assembly branch than the cabrera closed form's root (value: the same "
            "formula on its mirror image), so not a point of the published parametrisation as it stands; a Roberts "
            "cognate of it may be"
        )
    if ours["violations"]:
        notes.append("our design violates the published constraints: " + ", ".join(ours["violations"]))
    if ours.get("best_published_in_box") is False:
        r = ours.get("best_published_reach")
        notes.append(
            "the best published design lies outside our search box"
            + (
                f" (it needs reach {r:.2g}, ours {ours['reach']:g})"
                if r is not None and ours["variant"] == "default"
                else ""
            )
        )
    return notes


# ---------------------------------------------------------------------- output
def fmt(v: Any, spec: str = ".4g") -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "-"
    return format(v, spec)


def best_reference(rows: list[dict[str, Any]], feasible: bool = False) -> tuple[dict[str, Any] | None, str]:
    """The best published design (else the best code result), and its label; ``feasible``: among those
    whose crank turns fully with the transmission angle within [20, 160] degrees."""
    for kind in ("published", "code"):
        cand = [r for r in rows if r["kind"] == kind and r["value"] is not None and (r.get("ok") or not feasible)]
        if cand:
            r = min(cand, key=lambda r: r["value"])
            return r, r["by"] + (" (code run, not published)" if kind == "code" else "")
    return None, ""


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=120.0, help="budget of each synthesis run (default 120)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument(
        "--reach", type=float, nargs="+", default=[1.0], help="synthesize's reach, one run per value (default 1)"
    )
    ap.add_argument("--only", nargs="*", help="problem files whose name contains one of these")
    ap.add_argument(
        "--workers", type=int, default=1, help="search processes per run (default 1; 0: the library's default)"
    )
    ap.add_argument("--no-fair", action="store_true", help="skip the fixed-frame variant")
    ap.add_argument("--json", help="write every number to this file")
    ap.add_argument("--from-json", help="print the tables of an earlier --json file (no search)")
    args = ap.parse_args(argv)
    WORKERS[0] = args.workers or None

    problems = load_problems(args.only)
    if args.from_json:
        data = json.loads(Path(args.from_json).read_text())
        names = {name for name, _ in problems}
        checks = [r for r in data["checks"] if r["problem"] in names]
        results = [o for o in data["results"] if o["problem"] in names]
        for o in results:  # the notes as this version words them
            o["notes"] = differences(dict(problems)[o["problem"]], o)
    else:
        checks, results = search(problems, args)
        if args.json:
            Path(args.json).write_text(json.dumps({"checks": checks, "results": results}, indent=1, default=str))
    render(checks, results)
    return 0


def search(problems: list[tuple[str, dict[str, Any]]], args: Any) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
    """The cross-check and every synthesis run: (rows of part 1, our results)."""
    checks: list[dict[str, Any]] = []
    results: list[dict[str, Any]] = []
    for name, problem in problems:
        rows = cross_check(name, problem)
        checks.extend(rows)
        ref, ref_label = best_reference(rows)
        feas, feas_label = best_reference(rows, feasible=True)
        best = next((d for _, e, d in entries(problem) if ref and label(e) == ref["by"]), None)
        for reach in args.reach:
            for fixed in (False, True):
                if fixed and (args.no_fair or not fixed_frame(problem)):
                    continue
                what = "fixed-frame variant" if fixed else "synthesis"
                print(f"== {name}: {what}, reach {reach:g}, {args.seconds:g} s ...", file=sys.stderr, flush=True)
                run = run_fixed_frame if fixed else run_ours
                ours = run(name, problem, args.seconds, args.seed, best, reach)
                ours["reference"] = ref["value"] if ref else None
                ours["reference_by"] = ref_label
                ours["reference_ok"] = ref.get("ok") if ref else None
                ours["feasible_reference"] = feas["value"] if feas else None
                ours["feasible_reference_by"] = feas_label
                ours["notes"] = differences(problem, ours)
                ours["points"] = len(problem["targets"]) * len(target_sets(problem))
                results.append(ours)
                print(
                    f"   {fmt(ours['value'])} (analyze {fmt(ours['analyze'])}, errors {fmt(ours['from_errors'])}), "
                    f"mu {fmt(ours['mu_worst'], '.2f')}, {ours['outcome']['restarts']} restarts, {ours['wall']:.0f} s, "
                    f"stopped by {ours['outcome']['stopped_by']}",
                    file=sys.stderr,
                    flush=True,
                )
    return checks, results


def render(checks: list[dict[str, Any]], results: list[dict[str, Any]]) -> None:
    """The three markdown tables."""
    print("## Published designs: cabrera closed form (evaluate_designs.py) vs lk.analyze, and lk.check\n")
    print("| problem | design | value (closed form) | lk.analyze | agree | full turn | transmission min / max (deg) | "
          "violations (constraints of the problem's source) |")  # fmt: skip
    print("|---|---|---|---|---|---|---|---|")
    for r in checks:
        flag = "" if r.get("ok") else " **(outside [20, 160] or no full turn)**"
        print(
            f"| `{r['problem']}` | {r['by']}{' (code)' if r['kind'] == 'code' else ''} | {fmt(r['value'], '.7g')} | "
            f"{fmt(r.get('analyze'), '.7g')} | {'yes' if r.get('agree') else 'NO'} | "
            f"{'yes' if r.get('full_turn') else 'NO'} | "
            f"{fmt(r.get('mu_min'), '.1f')} / {fmt(r.get('mu_max'), '.1f')}{flag} | "
            f"{', '.join(r.get('violations', [])) or r.get('note', 'none')} |"
        )

    print("\n## linkagekit against the best published value (published objective, min transmission 20 deg)\n")
    print("| problem | points | timing | best published (recomputed) | best with transmission in [20, 160] | ours | "
          "ratio ours / best (/ best in [20, 160]) | our min transmission (deg) | seconds | notes |")  # fmt: skip
    print("|---|---|---|---|---|---|---|---|---|---|")
    for o in results:
        ratio = o["value"] / o["reference"] if o["value"] is not None and o["reference"] else None
        ratio_f = o["value"] / o["feasible_reference"] if o["value"] is not None and o["feasible_reference"] else None
        ref = f"{fmt(o['reference'])} ({o['reference_by']})" if o["reference"] is not None else "none"
        if o["reference"] is not None and not o["reference_ok"]:
            ref += ", **transmission outside [20, 160]**"
        feas = "same" if o["feasible_reference_by"] == o["reference_by"] and o["reference"] is not None else "none"
        if feas == "none" and o["feasible_reference"] is not None:
            feas = f"{fmt(o['feasible_reference'])} ({o['feasible_reference_by']})"
        variant = (
            f" (reach {o['reach']:g})" if o["variant"] == "default" else f" ({o['variant']}, reach {o['reach']:g})"
        )
        print(
            f"| `{o['problem']}`{variant} | {o['points']} | {o['timing']} | {ref} | {feas} | {fmt(o['value'])} | "
            f"{fmt(ratio, '.3g')} ({fmt(ratio_f, '.3g')}) | {fmt(o['mu_worst'], '.1f')} | {o['wall']:.0f} | "
            f"{'; '.join(o['notes'])} |"
        )
    print("\n## Our designs: agreement of the three evaluations, search\n")
    print("| problem | cabrera closed form | lk.analyze | from Synthesis.errors | agree | branch | restarts | "
          "generations | evaluations | stopped by |")  # fmt: skip
    print("|---|---|---|---|---|---|---|---|---|---|")
    for o in results:
        oc = o["outcome"]
        variant = (
            f" (reach {o['reach']:g})" if o["variant"] == "default" else f" ({o['variant']}, reach {o['reach']:g})"
        )
        print(
            f"| `{o['problem']}`{variant} | {fmt(o['value'], '.7g')} | {fmt(o['analyze'], '.7g')} | "
            f"{fmt(o['from_errors'], '.7g')} | {'yes' if o['agree'] else 'NO'} | {o['branch']:+d} | "
            f"{oc['restarts']} | {oc['generations']} | {oc['evaluations']} | {oc['stopped_by']} |"
        )


if __name__ == "__main__":
    sys.exit(main())
