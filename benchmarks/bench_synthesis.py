"""The synthesis benchmark: N four-bar designs x 360 crank samples in one run, positions only.

Designs: ``bench_designs.designs`` (random poses near seed 000's: ground A, B, crank A-C driven
at A toward C, coupler C-D with coupler point P, rocker B-D; all of them turn fully).
Timed, ns per design-sample, every joint's position at 360 crank angles (0, 1, ..., 359 deg):

* ``lk.analyze(mech, {"crank": deg}, poses=poses, rates=False)``,
* one layer below, what the synthesis objective calls: ``compile(mech, poses, make_plan(mech))``
  then ``solve(params, q, out=...)`` (compile included; each call writes into the chunk's one
  positions array, as ``lk.analyze`` does), one call per chunk of designs and in calls of 2^17
  (``lk.analyze``'s) and 2^16 (``CHUNK`` of ``linkagekit.synthesis.objective``) design-samples,
* the hand-written NumPy kernel of ``bench_designs`` (the same numbers, checked equal first),
* pylinkage (optional: ``pip install pylinkage numba``): its batch over designs,
  ``pylinkage.population.Ensemble(linkage, dimensions, positions).simulate(iterations)`` (one
  topology, N parameter vectors, each member run through the numba-compiled ``simulate``
  loop); the same numba kernel called directly per design (``pylinkage.solver.simulate``, the
  solver's documented direct access, without the Ensemble's bookkeeping); and the per-design
  path ``Linkage.set_completely`` + ``step_fast`` timed on the first designs only (given per
  design-sample: its cost per design does not depend on N).
  pylinkage's positions are checked equal to ours (same crank angles, same assembly mode)
  before anything is timed; numba's JIT compilation is excluded (warmed up first).

Printed: ns per design-sample and the ratios pylinkage / linkagekit, against the faster of
the two pylinkage paths timed on every design (goal: at least 5).
Memory stays bounded: the designs go through in chunks (default 10^4 designs), the times of
the chunks summed, each chunk's time the best of ``repeat`` runs.

    python benchmarks/bench_synthesis.py [N]      # default N = 100000
"""

from __future__ import annotations

import resource
import sys
from pathlib import Path

import numpy as np
from bench_designs import check_equal, designs, hand_kernel
from timing import best_of

import linkagekit as lk
from linkagekit.params import compile as compile_params
from linkagekit.plan import make_plan
from linkagekit.positions import solve

ROOT = Path(__file__).resolve().parents[1]
N_SAMPLES = 360
CHUNK = 10_000  # designs per chunk: ~0.3 GB of positions per method at 360 samples
LOOP_DESIGNS = 2000  # designs of pylinkage's per-design path (step_fast)
RTOL = 1e-9  # pylinkage against us: largest difference / largest coordinate of the design
#: design-samples per compile + solve call (None: the whole chunk in one call)
SOLVE_CALLS = (None, 1 << 17, 1 << 16)


# ---------------------------------------------------------------------- linkagekit
def lk_solve(mech, poses, q, per_call=None):
    """Positions (n_joints, N, n) of ``poses`` by compile + solve, ``per_call`` design-samples a call (None: one call).

    Every call writes its designs' positions into one array of the batch, as ``lk.analyze``
    does, and drops the rest of its solve (margins, link rotations) when done.
    """
    n = q.shape[-1]
    out = np.empty((len(mech.joint_names), len(poses), n), complex)
    step = len(poses) if per_call is None else max(1, per_call // n)
    for s in range(0, len(poses), step):
        params = compile_params(mech, poses[s : s + step], make_plan(mech))
        solve(params, q, out=out[:, s : s + step])
    return out


# ---------------------------------------------------------------------- pylinkage
def pylinkage_or_reason():
    """``(pylinkage, None)``, or ``(None, why it is skipped)``."""
    try:
        import pylinkage
    except ImportError:
        return None, "pylinkage not installed (pip install pylinkage numba): pylinkage skipped"
    try:
        import numba  # noqa: F401
    except ImportError as exc:  # pylinkage would run its pure-Python solver: nothing to compare with
        return None, f"numba not installed or not importable ({exc}): pylinkage skipped"
    return pylinkage, None


def pylinkage_inputs(poses, n_samples=N_SAMPLES):
    """pylinkage's constraint vectors (N, 5) and start positions (N, 5, 2) of ``poses`` (joints A, B, C, D, P).

    Constraints in ``Linkage.get_constraints()`` order: crank radius |AC|, the RRR dyad's
    |CD| and |BD|, the fixed dyad's |CP| and angle of C->P from C->D.  pylinkage's crank
    turns by its angular velocity before each recorded step, so C starts one step before
    0 deg: step k is at k x 360/n_samples deg, our samples.  D starts at the pose's D: the
    RRR dyad keeps the circle intersection nearest the previous D, the pose's branch.
    """
    z = poses[..., 0] + 1j * poses[..., 1]
    a, c, d, p = z[:, 0], z[:, 2], z[:, 3], z[:, 4]
    radius = np.abs(c - a)
    dims = np.stack([radius, np.abs(d - c), np.abs(d - z[:, 1]), np.abs(p - c), np.angle((p - c) / (d - c))], axis=1)
    start = z.copy()
    start[:, 2] = a + radius * np.exp(-2j * np.pi / n_samples)
    return dims, np.stack([start.real, start.imag], axis=-1)


def pylinkage_fourbar(pl, pose, n_samples=N_SAMPLES):
    """The four-bar A, B, C (crank), D (RRR dyad), P (fixed dyad) as a pylinkage Linkage, dimensions of ``pose``."""
    dims, pos = pylinkage_inputs(pose[None], n_samples)
    (r, b, c, e, ang), (pa, pb) = dims[0], pos[0, :2]
    A = pl.Ground(*pa, name="A")
    B = pl.Ground(*pb, name="B")
    crank = pl.Crank(A, r, angular_velocity=2 * np.pi / n_samples, name="C")
    D = pl.RRRDyad(crank.output, B, distance1=b, distance2=c, name="D")
    P = pl.FixedDyad(crank.output, D, distance=e, angle=ang, name="P")
    return pl.Linkage([A, B, crank, D, P], name="four-bar")


def pylinkage_batch(pl, linkage, poses, n_samples=N_SAMPLES):
    """pylinkage's batch over designs: (N, n_samples, 5, 2) positions."""
    dims, pos = pylinkage_inputs(poses, n_samples)
    return pl.Ensemble(linkage, dims, pos).simulate(iterations=n_samples, store=False)


def pylinkage_solver(linkage, poses, n_samples=N_SAMPLES):
    """pylinkage's documented direct access to its numba solver, one call per design, no batch bookkeeping.

    ``pylinkage.solver.linkage_to_solver_data`` once (the topology), then ``simulate`` per
    design with that design's constraints and start positions, into one (N, n_samples, 5, 2) array.
    """
    from pylinkage.solver import linkage_to_solver_data, simulate

    data = linkage_to_solver_data(linkage)
    assert data.constraints.size == 6 and data.constraints[1] == 2 * np.pi / n_samples  # the crank's step
    dims, pos = pylinkage_inputs(poses, n_samples)
    cons = np.empty((len(poses), 6))
    cons[:, [0, 2, 3, 4, 5]] = dims  # solver order: radius, angular velocity, then the dyads'
    cons[:, 1] = data.constraints[1]
    args = (data.joint_types, data.parent_indices, data.constraint_offsets, data.solve_order, n_samples, 1.0)
    out = np.empty((len(poses), n_samples, 5, 2))
    for i in range(len(poses)):
        out[i] = simulate(pos[i], cons[i], *args)  # moves pos[i] along: a throwaway copy
    return out


def pylinkage_each(linkage, poses, n_samples=N_SAMPLES):
    """pylinkage's per-design path: set the dimensions and start positions, then ``step_fast``."""
    dims, pos = pylinkage_inputs(poses, n_samples)
    out = []
    for d, p in zip(dims, pos, strict=True):
        linkage.set_completely(d.tolist(), [tuple(x) for x in p])
        out.append(linkage.step_fast(iterations=n_samples))
    return np.array(out)


def check_pylinkage(mech, poses, deg, pl, linkage):
    """pylinkage's positions (every path timed) equal ours to RTOL, on designs that turn fully."""
    res = lk.analyze(mech, {"crank": deg}, poses=poses, rates=False)
    ours = np.stack([res.xy(j) for j in mech.joint_names], axis=2)  # (N, n, 5, 2)
    full = res.assembled.all(axis=1)
    assert full.sum() >= len(poses) // 2, "the check needs designs that turn fully"
    scale = np.abs(ours[full]).max(axis=(1, 2, 3))
    worst = 0.0
    n = len(deg)
    paths = (pylinkage_batch(pl, linkage, poses, n), pylinkage_solver(linkage, poses, n))
    for theirs in (*paths, pylinkage_each(pylinkage_fourbar(pl, mech.pose_array(), n), poses, n)):
        assert theirs.shape == ours.shape and np.isfinite(theirs[full]).all()
        rel = np.abs(theirs[full] - ours[full]).max(axis=(1, 2, 3)) / scale
        worst = max(worst, float(rel.max()))
        assert worst <= RTOL, f"pylinkage differs from linkagekit by {worst:.2e} (relative)"
    return int(full.sum()), worst


# ---------------------------------------------------------------------- the run
def main(n=100_000, chunk=CHUNK, repeat=3, loop_designs=LOOP_DESIGNS):
    """Time every method on ``n`` designs x 360 samples; returns the ns per design-sample by method."""
    mech = lk.load(ROOT / "examples" / "seed000_fourbar.yaml")
    deg = np.arange(N_SAMPLES) * (360.0 / N_SAMPLES)
    phi = np.radians(deg)
    q = phi[None, None, :]
    check = designs(mech, 200, seed=1)
    check_equal(mech, check, deg)  # the hand kernel = lk.analyze
    res = lk.analyze(mech, {"crank": deg}, poses=check, rates=False)
    for per_call in SOLVE_CALLS:  # compile + solve = lk.analyze
        z = lk_solve(mech, check, q, per_call)
        ref = np.stack([res.point(j) for j in mech.joint_names])
        assert np.allclose(z, ref, rtol=0, atol=1e-12, equal_nan=True)

    pl, why = pylinkage_or_reason()
    if pl is not None:
        linkage = pylinkage_fourbar(pl, mech.pose_array())
        pylinkage_batch(pl, linkage, check[:2])  # warm-up: numba's JIT compilation (or its cache) is not timed
        pylinkage_solver(linkage, check[:2])
        n_full, worst = check_pylinkage(mech, check, deg, pl, linkage)
        print(
            f"pylinkage {pl.__version__} (numba {sys.modules['numba'].__version__}): positions equal to ours on "
            f"{n_full} designs x {N_SAMPLES} samples, largest difference {worst:.1e} of the design's size"
        )
    else:
        print(why)

    poses = designs(mech, n)
    chunk = max(1, min(chunk, n))
    labels = {"analyze": "lk.analyze(poses=, rates=False)"}
    for per_call in SOLVE_CALLS:
        labels[f"solve{per_call}"] = "compile + solve, " + (
            f"{chunk:,} designs a call" if per_call is None else f"2^{per_call.bit_length() - 1} design-samples a call"
        )
    labels["hand"] = "hand NumPy kernel"
    if pl is not None:
        labels["pylinkage"] = "pylinkage Ensemble.simulate (numba)"
        labels["pylinkage_solver"] = "pylinkage.solver.simulate, a call per design"
    total = dict.fromkeys(labels, 0.0)
    for s in range(0, n, chunk):
        p = poses[s : s + chunk]
        total["analyze"] += best_of(lambda p=p: lk.analyze(mech, {"crank": deg}, poses=p, rates=False), repeat)
        for per_call in SOLVE_CALLS:
            total[f"solve{per_call}"] += best_of(lambda p=p, c=per_call: lk_solve(mech, p, q, c), repeat)
        total["hand"] += best_of(lambda p=p: hand_kernel(p, phi), repeat)
        if pl is not None:
            total["pylinkage"] += best_of(lambda p=p: pylinkage_batch(pl, linkage, p), repeat)
            total["pylinkage_solver"] += best_of(lambda p=p: pylinkage_solver(linkage, p), repeat)
    ns = {k: v * 1e9 / (n * N_SAMPLES) for k, v in total.items()}
    if pl is not None:
        m = min(loop_designs, n)
        each = pylinkage_fourbar(pl, mech.pose_array())
        ns["pylinkage_each"] = best_of(lambda: pylinkage_each(each, poses[:m]), repeat) * 1e9 / (m * N_SAMPLES)
        labels["pylinkage_each"] = f"pylinkage set_completely + step_fast ({m:,} designs)"
        ns["pylinkage_best"] = min(ns["pylinkage"], ns["pylinkage_solver"])

    print(
        f"{n:,} four-bar designs x {N_SAMPLES} samples, positions of every joint, "
        f"chunks of {chunk:,} designs (ns per design-sample, best of {repeat} per chunk)"
    )
    for key, label in labels.items():
        line = f"  {label:52s} {ns[key]:8.1f}"
        if pl is not None and (key == "analyze" or key.startswith("solve")):
            line += f"   ratio pylinkage / this {ns['pylinkage_best'] / ns[key]:5.2f}"
            # the goal is about the paths a user and the synthesis take; one call over a whole chunk works out of cache
            line += "  (goal >= 5)" if key != "solveNone" else "  (out of cache: for comparison)"
        elif key == "hand":
            line += f"   ratio lk.analyze / this {ns['analyze'] / ns[key]:5.2f}"
        elif key.startswith("pylinkage"):
            line += f"   {ns[key] / ns['analyze']:5.2f}x lk.analyze"
        print(line)
    if pl is not None:
        print(
            "  (ratios against the faster pylinkage path timed on every design; its per-design "
            "step_fast path is timed on the first designs: its cost per design does not depend on N)"
        )
    ns["objective"] = objective_ns(mech, poses, repeat)
    print(
        f"  the synthesis objective on the same designs (12 targets: the {N_SAMPLES}-sample curve, nearest points "
        f"refined by one Newton step, transmission angle, penalties): {ns['objective']:.1f} ns per design-sample "
        f"of the curve"
    )
    print(f"  peak RSS {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20:.2f} GB")
    return ns


def objective_ns(mech, poses, repeat):
    """ns per design-sample of ``evaluate`` (what a generation of the synthesis costs), over ``poses``."""
    from linkagekit.synthesis.objective import evaluate
    from linkagekit.synthesis.run import make_problem

    targets = lk.analyze(mech, {"crank": np.arange(0.0, 360.0, 30.0)}).xy("P")
    problem = make_problem(targets, "fourbar", units="cm", samples=N_SAMPLES)
    sp = problem.space
    X = np.stack([np.concatenate([p[mech.joint_names.index(j)] for j in sp.free]) for p in poses])
    t = best_of(lambda: evaluate(problem, X), repeat)
    return t * 1e9 / (len(X) * N_SAMPLES)


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 100_000)
