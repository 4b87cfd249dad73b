"""The numerical group step (issue 10, point 2): Newton on natural coordinates, continued from the pose.

Checked against other computations:

* forced onto triangulable linkages (``method="numerical"``: four-bar, Watt II, Stephenson
  III, random dimensions, every sign combination of the closed form turned into a pose), it
  agrees with the closed-form solver sample by sample to 1e-10 relative (positions,
  velocities, accelerations) and assembles at the same samples;
* on class-3 triads (a ternary link held by three binary links, no triangulation order)
  with random dimensions: every link length is kept to 1e-10 over the sweep; the pose comes
  back at its own input; velocities and accelerations match central finite differences of
  the solver's own positions; the result does not depend on the order of the inputs; and
  the branch is the one a fine continuation written here with ``scipy.optimize.root`` (0.05
  degree steps from the pose) follows: no branch jump, including on a coarse sweep that
  passes close to a singular position.
"""

from __future__ import annotations

import cmath
import copy
import functools
import math
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.optimize import fsolve, root

import linkagekit as lk
from helpers import (
    TRIAD_LINKS,
    ArclengthTriad,
    by_cosines,
    fourbar_dict,
    points,
    random_points,
    side,
    stephenson_dict,
    velocities,
    watt2_dict,
    xy,
)
from linkagekit.plan import make_plan

REL = 1e-10


def scale_of(mech) -> float:
    z = np.array(list(mech.joints.values()))
    return float(np.max(np.abs(z - z.mean())))


# ----------------------------------------------------------------------------- forced onto closed form
def closed_form_modes(mech, at_deg: float) -> list[np.ndarray]:
    """The poses of every sign combination of the closed form at one input (distinct, assembled)."""
    plan = make_plan(mech)
    k = plan.n_signs
    out = []
    for code in range(2**k):
        signs = {j: (1 if (code >> i) & 1 else -1) for i, j in enumerate(plan.sign_joints)}
        res = lk.analyze(mech, {mech.drivers[0].name: [at_deg]}, signs=signs, rates=False)
        if not res.assembled[0]:
            continue
        pose = np.array([res.xy(j)[0] for j in mech.joint_names])
        if not any(np.allclose(pose, p, rtol=0, atol=1e-9 * scale_of(mech)) for p in out):
            out.append(pose)
    return out


def compare_numerical(mech, what: str) -> int:
    """Closed form vs method='numerical' in every mode at the pose's input; returns the modes compared."""
    drv = mech.drivers[0]
    at = float(np.degrees(np.angle(mech.joints[drv.toward] - mech.joints[drv.pivot])))
    sweep = {drv.name: np.concatenate([[at], np.arange(0.0, 360.0, 3.0)])}
    s = scale_of(mech)
    n_modes = 0
    for pose in closed_form_modes(mech, at):
        m = mech.with_pose(pose)
        a = lk.analyze(m, sweep)
        b = lk.analyze(m, sweep, method="numerical")
        assert make_plan(m, True).numerical, "method='numerical' placed nothing numerically"
        # closed form and Newton assemble at the same samples, except within a hair of a limit
        diff = a.assembled != b.assembled
        if diff.any():
            assert np.all(a.condition[diff & a.assembled] < 1e-3), (what, np.flatnonzero(diff))
        both = a.assembled & b.assembled
        assert both.sum() >= 1 and both[0], f"{what}: the pose's own input is not solved"
        pa, pb = points(a)[:, both], points(b)[:, both]
        assert np.max(np.abs(pa - pb)) <= REL * s, f"{what}: positions differ by {np.max(np.abs(pa - pb)):.3g}"
        ok = both & ~a.singular & ~b.singular & (a.condition > 1e-3)
        if ok.any():
            va, vb = velocities(a)[:, ok], velocities(b)[:, ok]
            vs = max(1.0, float(np.max(np.abs(va))))
            assert np.max(np.abs(va - vb)) <= 1e-8 * vs, f"{what}: velocities differ by {np.max(np.abs(va - vb)):.3g}"
            aa = np.array([a.acceleration(j) for j in m.joint_names])[:, ok]
            ab = np.array([b.acceleration(j) for j in m.joint_names])[:, ok]
            as_ = max(1.0, float(np.max(np.abs(aa))))
            assert np.max(np.abs(aa - ab)) <= 1e-7 * as_, f"{what}: accelerations differ by {np.max(np.abs(aa - ab))}"
        n_modes += 1
    return n_modes


@pytest.mark.parametrize("name", ["seed000_fourbar", "watt2_sixbar", "seed001_stephenson", "seed004_stephenson1"])
def test_forced_numerical_matches_the_closed_form_in_every_mode(examples, name):
    mech = lk.load(examples / f"{name}.yaml")
    n = compare_numerical(mech, name)
    assert n == len(closed_form_modes(mech, 0.0)) or n >= 2


@pytest.mark.parametrize("name", ["whitworth_quick_return", "excavator_boom"])
def test_forced_numerical_answers_an_input_alone_as_the_closed_form(examples, name):
    """Forced through Newton, every step a group, each group after the first re-runs the earlier ones from their
    walks (``Group.place_walked``) at its sub-steps' inputs. That re-run set no rotation for the links a later step
    reads (Whitworth's lever: a ``KeyError`` for 35 of 36 inputs asked alone) and flagged the cylinders' strokes
    with a mask of the wrong shape (an ``IndexError`` on every input of the excavator; review 13a). Each input
    alone, and all in one list, equal the closed form (1e-9 of the size)."""
    mech = lk.load(examples / f"{name}.yaml")
    inputs = {d.name: np.linspace(d.sweep.start, d.sweep.stop, 7)[1:-1] for d in mech.drivers}
    ref = points(lk.analyze(mech, inputs, rates=False))
    assert np.isfinite(ref).all()
    listed = points(lk.analyze(mech, inputs, rates=False, method="numerical"))
    assert np.max(np.abs(listed - ref)) <= 1e-9 * scale_of(mech)
    for i in range(ref.shape[1]):
        alone = lk.analyze(mech, {k: v[i : i + 1] for k, v in inputs.items()}, rates=False, method="numerical")
        assert np.max(np.abs(points(alone)[:, 0] - ref[:, i])) <= 1e-9 * scale_of(mech), i


#: random linkages of the test (a few: each costs about 1.5 CPU-s); benchmarks/bench_long_tests.py runs more
RANDOM_LINKAGES = {"seed": st.integers(0, 2**32 - 1), "kind": st.sampled_from(["fourbar", "watt2", "stephenson"])}


@settings(max_examples=4, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(**RANDOM_LINKAGES)
def test_forced_numerical_matches_random_linkages(seed, kind):
    check_forced_numerical_random(seed, kind)


def check_forced_numerical_random(seed: int, kind: str) -> None:
    """A random four-bar, Watt II or Stephenson III forced through Newton matches its closed form in every mode."""
    rng = np.random.default_rng(seed)
    if kind == "fourbar":
        p = random_points(rng, "ABCDP")
        doc = fourbar_dict(p["A"], p["B"], p["C"], p["D"], p["P"])
    elif kind == "watt2":
        doc = watt2_dict(random_points(rng, "ABECDFGP"))
    else:
        doc = stephenson_dict(random_points(rng, "ABCDEFGP"))
    doc.setdefault("format", "linkagekit/1")
    doc.setdefault("units", {"length": "m", "angle": "deg"})
    try:
        mech = lk.Mechanism.from_dict(doc)
    except lk.LinkageError:  # a random pose with two joints of a link at one spot
        return
    compare_numerical(mech, f"{kind} seed {seed}")


# ----------------------------------------------------------------------------- class-3 triads
EXAMPLE = {"O": 0j, "A": 20 + 0j, "B0": 120 - 10j, "C0": 60 + 80j, "J1": 50 + 30j, "J2": 95 + 35j, "J3": 70 + 55j}
TRIAD_BARS = [("O", "A"), ("A", "J1"), ("B0", "J2"), ("C0", "J3"), ("J1", "J2"), ("J2", "J3"), ("J1", "J3")]


def triad(p: dict[str, complex]) -> lk.Mechanism:
    return lk.Mechanism.from_dict(
        {
            "format": "linkagekit/1",
            "units": {"length": "mm", "angle": "deg"},
            "joints": xy(p),
            "links": TRIAD_LINKS,
            "drivers": [{"link": "crank", "pivot": "O", "toward": "A"}],
        }
    )


def random_triad(seed: int) -> lk.Mechanism:
    rng = np.random.default_rng(seed)
    p = {
        "O": 0j,
        "A": complex(*rng.uniform(-1, 1, 2)) * 3,
        "B0": complex(*rng.uniform(-10, 10, 2)),
        "C0": complex(*rng.uniform(-10, 10, 2)),
    }
    c = complex(*rng.uniform(-4, 4, 2))
    for j in ("J1", "J2", "J3"):
        p[j] = c + complex(*rng.uniform(-3, 3, 2))
    return triad(p)


def pose_angle(mech) -> float:
    return float(np.degrees(np.angle(mech.joints["A"] - mech.joints["O"])))


def reference_continuation(mech, inputs_deg: np.ndarray, step_deg: float = 0.05) -> np.ndarray:
    """J1, J2, J3 along the inputs by a fine continuation from the pose with scipy.optimize.root.

    Independent of linkagekit's Newton: its own residual (7 bar lengths), its own walk.
    Returns (3, n) complex, NaN where the walk could not follow (a limit).
    """
    z0 = {j: mech.joints[j] for j in mech.joint_names}
    L = {bar: abs(z0[bar[0]] - z0[bar[1]]) for bar in TRIAD_BARS}
    r = abs(z0["A"] - z0["O"])
    unknown = ("J1", "J2", "J3")

    def residual(x, phi):
        pts = dict(z0)
        pts["A"] = r * np.exp(1j * phi)
        for i, j in enumerate(unknown):
            pts[j] = complex(x[2 * i], x[2 * i + 1])
        return [abs(pts[a] - pts[b]) - L[(a, b)] for a, b in TRIAD_BARS[1:]]

    def handed(x) -> float:  # the ternary's orientation: a rigid body, not its mirror image
        j1, j2, j3 = (complex(x[2 * i], x[2 * i + 1]) for i in range(3))
        return float(np.sign((np.conj(j2 - j1) * (j3 - j1)).imag))

    hand0 = handed([v for j in unknown for v in (z0[j].real, z0[j].imag)])

    phi0 = pose_angle(mech)
    out = np.full((3, len(inputs_deg)), complex(np.nan, np.nan))
    # each input as its angle from the pose, as given (the walk follows the motion, not modulo a turn)
    offsets = np.asarray(inputs_deg, float) - phi0
    for direction in (1, -1):
        x = np.array([v for j in unknown for v in (z0[j].real, z0[j].imag)])
        side = np.flatnonzero(offsets >= 0) if direction > 0 else np.flatnonzero(offsets < 0)
        phi = phi0
        alive = True
        for kk in side[np.argsort(np.abs(offsets[side]), kind="stable")]:
            t = phi0 + offsets[kk]
            while alive and abs(t - phi) > 1e-12:
                nxt = phi + direction * min(step_deg, abs(t - phi))
                sol = root(residual, x, args=(math.radians(nxt),), method="lm", tol=1e-14)
                good = sol.success and np.max(np.abs(residual(sol.x, math.radians(nxt)))) < 1e-9
                good = good and handed(sol.x) == hand0
                if not good or np.max(np.abs(sol.x - x)) > 0.2 * scale_of(mech):
                    alive = False
                    break
                x, phi = sol.x, nxt
            if not alive:
                break
            out[:, kk] = x[0::2] + 1j * x[1::2]
    return out


def lengths_error(res, mech) -> float:
    z0 = mech.joints
    worst = 0.0
    for a, b in TRIAD_BARS:
        d = np.abs(res.point(a) - res.point(b))[res.assembled]
        worst = max(worst, float(np.max(np.abs(d - abs(z0[a] - z0[b])), initial=0.0)))
    return worst / scale_of(mech)


def test_triad_file_is_placed_numerically():
    mech = triad(EXAMPLE)
    plan = make_plan(mech)
    assert [plan.joint_names[j] for j in plan.numerical] == ["J1", "J2", "J3"]
    res = lk.analyze(mech, {"crank": np.arange(-20.0, 100.0, 1.0)})
    assert res.assembled.sum() > 50 and not res.assembled.all()
    assert lengths_error(res, mech) < REL


#: random triads of the test (a few: the reference continuation costs about 1 CPU-s a triad);
#: benchmarks/bench_long_tests.py runs more
RANDOM_TRIADS = {"seed": st.integers(0, 2**32 - 1)}


@settings(max_examples=5, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(**RANDOM_TRIADS)
def test_random_triads(seed):
    check_random_triad(seed)


def check_random_triad(seed: int) -> None:
    """A random class-3 triad: its pose at its own input, every length kept, the order of the inputs does not
    matter, and the branch is the fine reference continuation's."""
    mech = random_triad(seed)
    phi0 = pose_angle(mech)
    inputs = np.concatenate([np.arange(-180.0, 180.0, 2.0), [phi0]])
    res = lk.analyze(mech, {"crank": inputs})
    s = scale_of(mech)
    # the pose at its own input
    assert res.assembled[-1], f"seed {seed}: the pose's own input does not assemble"
    for j in mech.joint_names:
        assert abs(res.point(j)[-1] - mech.joints[j]) <= REL * s, (seed, j)
    # every length kept
    assert lengths_error(res, mech) < REL, seed
    # the order of the inputs does not matter
    perm = np.random.default_rng(seed).permutation(len(inputs))
    res2 = lk.analyze(mech, {"crank": inputs[perm]})
    assert np.array_equal(res2.assembled, res.assembled[perm])
    ok = res.assembled[perm]
    assert np.allclose(points(res2)[:, ok], points(res)[:, perm][:, ok], rtol=0, atol=1e-9 * s), seed
    # the branch is the fine continuation's (no jump), where the fine walk reaches
    ref = reference_continuation(mech, inputs, step_deg=0.25)
    got = np.array([res.point(j) for j in ("J1", "J2", "J3")])
    reach = np.all(np.isfinite(ref), axis=0)
    assert reach[-1]
    both = reach & res.assembled
    err = np.max(np.abs(got[:, both] - ref[:, both]))
    assert err <= 1e-7 * s, f"seed {seed}: off the pose's branch by {err / s:.3g} (relative)"
    # samples the fine walk reaches are assembled by linkagekit too (except within a hair of a limit)
    missed = reach & ~res.assembled
    assert missed.sum() <= 2, f"seed {seed}: {missed.sum()} samples reached by the reference are not assembled"


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**32 - 1))
def test_triad_rates_against_finite_differences(seed):
    mech = random_triad(seed)
    phi0 = pose_angle(mech)
    # degrees: 4th-order differences. Round-off in z (about 1e-12 of the size after Newton) enters the
    # second difference as 1e-12 / h^2: at h = 0.01 deg that is 3e-5 of the size (a seed failed at
    # 1.8e-5 > 1e-5); at 0.05 deg it is 1e-6 while the truncation error stays below 1e-9 (worst over
    # 60 random triads: 6.4e-10 for velocities, 6.7e-7 for accelerations).
    h = 0.05
    xs = phi0 + np.array([-2 * h, -h, 0.0, h, 2 * h])
    w = 2.0  # rad/s
    res = lk.analyze(mech, {"crank": xs}, speed={"crank": w})
    if not res.assembled.all() or res.condition.min() < 0.05:
        return  # near a singular position the differences themselves are poor; the exact tests cover it
    z = points(res)
    hr = math.radians(h)
    dz = (-z[:, 4] + 8 * z[:, 3] - 8 * z[:, 1] + z[:, 0]) / (12 * hr)  # d/dphi, 4th order
    d2z = (-z[:, 4] + 16 * z[:, 3] - 30 * z[:, 2] + 16 * z[:, 1] - z[:, 0]) / (12 * hr * hr)
    v = velocities(res)[:, 2]
    a = np.array([res.acceleration(j) for j in mech.joint_names])[:, 2]
    s = scale_of(mech)
    vs, as_ = max(s * w, float(np.max(np.abs(v)))), max(s * w * w, float(np.max(np.abs(a))))
    assert np.max(np.abs(v - w * dz)) <= 1e-7 * vs, (seed, np.abs(v - w * dz) / vs)
    assert np.max(np.abs(a - w * w * d2z)) <= 1e-5 * as_, (seed, np.abs(a - w * w * d2z) / as_)


def test_no_branch_jump_near_a_singular_position():
    """A coarse sweep that passes close to the triad's limit: the samples beyond it are not
    assembled and those after it come back on the pose's branch (the fine reference's), never
    on the other branch that meets it at the limit."""
    mech = triad(EXAMPLE)
    grid = np.linspace(0, 120, 12001)
    fine = lk.analyze(mech, {"crank": grid}, rates=False)
    top = float(grid[fine.assembled][-1])  # the last assembled sample, within 0.01 degree of the limit
    assert 60 < top < 110 and not fine.assembled[grid > top].any()
    # a coarse sweep: far below, within 0.01 degree of the limit, beyond it, back below
    inputs = np.array([0.0, 30.0, top - 20.0, top, top + 5.0, top - 10.0, top - 0.5, 10.0])
    res = lk.analyze(mech, {"crank": inputs})
    assert list(res.assembled) == [True, True, True, True, False, True, True, True]
    ref = reference_continuation(mech, inputs[res.assembled], step_deg=0.02)
    got = np.array([res.point(j)[res.assembled] for j in ("J1", "J2", "J3")])
    reach = np.all(np.isfinite(ref), axis=0)
    assert reach.sum() >= 6
    assert np.max(np.abs(got[:, reach] - ref[:, reach])) < 1e-7 * scale_of(mech)
    # near the limit the group's Jacobian is nearly singular: the condition says so
    near = int(np.flatnonzero(inputs == top)[0])
    assert res.condition[near] < 0.05 * np.nanmax(res.condition)


def test_condition_is_the_scaled_jacobians_singular_value_ratio():
    """The conditioning reported with a triad's rates is 1 / cond_2 of its Jacobian in the group's joints, built
    here by hand (rows: each link's length over 2 L, so a unit vector; the ternary's third joint as the complex
    rho of its first two), by ``np.linalg.cond``: 1e-12 relative. Order of rows and columns does not matter."""
    mech = triad(EXAMPLE)
    res = lk.analyze(mech, {"crank": np.linspace(-8.0, 86.0, 300)})
    ok = res.assembled
    assert ok.sum() > 250
    p = {j: res.point(j)[ok] for j in mech.joint_names}
    rho = (EXAMPLE["J3"] - EXAMPLE["J1"]) / (EXAMPLE["J2"] - EXAMPLE["J1"])
    n = int(ok.sum())
    J = np.zeros((n, 6, 6))
    col = {"J1": 0, "J2": 2, "J3": 4}
    for r, (a, b) in enumerate([("A", "J1"), ("B0", "J2"), ("C0", "J3"), ("J1", "J2")]):
        u = (p[b] - p[a]) / np.abs(p[b] - p[a])  # d |z_b - z_a|^2 / (2 L): the unit vector on b, minus it on a
        for j, f in ((b, 1.0), (a, -1.0)):
            if j in col:
                J[:, r, col[j]], J[:, r, col[j] + 1] = f * u.real, f * u.imag
    for j, c in (("J3", 1.0), ("J1", rho - 1.0), ("J2", -rho)):  # z3 - z1 - rho (z2 - z1) = 0
        J[:, 4, col[j] : col[j] + 2] = [c.real, -c.imag]
        J[:, 5, col[j] : col[j] + 2] = [c.imag, c.real]
    want = 1.0 / np.linalg.cond(J)
    assert np.max(np.abs(res.condition[ok] / want - 1)) <= 1e-12


def test_condition_by_newton_on_the_tridiagonal_form_equals_the_svd():
    """The group's conditioning (Householder to tridiagonal form, Newton to the extreme eigenvalues of J^T J) against
    the SVD on random 6x6 and 8x8 matrices, with a double and a five-fold largest singular value and nearly
    dependent columns: relative error below 1e-15 / cond^2 + 1e-13 (the rounding of eigenvalues of J^T J, about
    1e-16 of the largest, as LAPACK's eigvalsh)."""
    from linkagekit.group import _condition

    rng = np.random.default_rng(5)
    for n in (6, 8):
        A = rng.normal(size=(800, n, n))
        A[:200, :, 0] = A[:200, :, 1] * (1 + 1e-2 * rng.normal(size=(200, n)))
        U, s, Vt = np.linalg.svd(A[200:600])
        s[:200, :2] = 1.0
        s[200:, :] = 1.0
        s[200:, -1] = 0.5
        A[200:600] = U @ (s[..., None] * Vt)
        sv = np.linalg.svd(A, compute_uv=False)
        want = sv[:, -1] / sv[:, 0]
        assert np.all(np.abs(_condition(A) / want - 1) <= 1e-15 / want**2 + 1e-13), n


def test_rates_solve_the_second_system_with_the_first_ones_factors():
    """The accelerations' system (the velocities' matrix) solved from the velocities' factorization: bit for bit the
    elimination of that right-hand side itself, and LAPACK's solution to 1e-10 relative."""
    from linkagekit.group import VECTOR_SAMPLES, _gauss, _RatesSystem

    rng = np.random.default_rng(11)
    B = VECTOR_SAMPLES + 900  # two chunks, vectorized
    J = rng.normal(size=(B, 6, 6))
    J[::3, 0], J[::3, 2] = J[::3, 2].copy(), J[::3, 0].copy()  # pivots that differ from column to column
    r1, r2 = rng.normal(size=(B, 6)), rng.normal(size=(B, 6))
    system = _RatesSystem(J, r1)
    x2 = system.solve(r2)
    assert np.array_equal(system.first, _RatesSystem(J, r1).first)
    assert np.array_equal(x2, _RatesSystem(J, r2).first)  # as if eliminated itself
    assert np.array_equal(x2[:2048], _gauss(J[:2048], -r2[:2048].T)[0])
    want = np.linalg.solve(J, r2[..., None])[..., 0]
    assert np.max(np.abs(x2 - want) / (np.abs(want) + 1e-3)) <= 1e-10


def test_the_walks_look_ahead_changes_no_flag(monkeypatch):
    """The walk's Newton batches solving the next columns ahead (``LOOK_AHEAD``) give the walk of one column a
    batch: the same flags, positions to 1e-10 of the size (Newton from other starts), on triads through gaps
    and the six-bar of the crank-direction defect."""
    from linkagekit import group

    mech, _ = sixbar()
    cases = [
        (random_triad(1), {"crank": np.arange(-400.0, 400.0, 2.0)}),
        (triad(EXAMPLE), {"crank": np.linspace(-30.0, 120.0, 301)}),
        (mech, {"L3": np.arange(-360.0, 360.0, 1.5)}),
    ]
    ahead = [lk.analyze(m, i, rates=False) for m, i in cases]
    monkeypatch.setattr(group, "LOOK_AHEAD", 1)
    for (m, i), a in zip(cases, ahead, strict=True):
        b = lk.analyze(m, i, rates=False)
        assert np.array_equal(a.assembled, b.assembled)
        assert 0 < a.assembled.sum() < a.assembled.size
        ok = a.assembled
        assert np.max(np.abs(points(a)[:, ok] - points(b)[:, ok])) <= 1e-10 * scale_of(m)


def test_triads_over_the_design_axis_equal_single_solves():
    """Five triad designs in one call (poses=...) give each design's own single solve (1e-10)."""
    base = triad(EXAMPLE)
    rng = np.random.default_rng(7)
    poses = base.pose_array()[None] + rng.normal(0, 2.0, (5, len(base.joint_names), 2))
    inputs = {"crank": np.arange(-20.0, 100.0, 2.0)}
    batch = lk.analyze(base, inputs, poses=poses)
    assert batch.shape == (5, len(inputs["crank"]))
    for d in range(5):
        one = lk.analyze(base.with_pose(poses[d]), inputs)
        assert np.array_equal(batch.assembled[d], one.assembled), d
        ok = one.assembled
        assert ok.sum() > 10
        for j in base.joint_names:
            assert np.max(np.abs(batch.point(j)[d][ok] - one.point(j)[ok])) <= 1e-10 * scale_of(base), (d, j)
            assert np.max(np.abs(batch.velocity(j)[d][ok] - one.velocity(j)[ok])) <= 1e-8 * scale_of(base), (d, j)


# ----------------------------------------------------------------------------- cost, at the same results
def forced_fourbar(seed: int) -> lk.Mechanism:
    rng = np.random.default_rng(seed)
    p = random_points(rng, "ABCDP")
    return lk.Mechanism.from_dict(fourbar_dict(p["A"], p["B"], p["C"], p["D"], p["P"]))


def designs_with_gaps() -> tuple[lk.Mechanism, np.ndarray]:
    """Five perturbed triads (a design axis), each with a gap over the sweep below."""
    base = random_triad(1)
    rng = np.random.default_rng(3)
    return base, base.pose_array()[None] + rng.normal(0, 0.3, (5, len(base.joint_names), 2))


def walks() -> list[lk.Result]:
    """Walks through gaps: a forced four-bar (its dyad restarts after the gap), triads, a design axis."""
    wide = {"crank": np.arange(-400.0, 400.0, 2.0)}
    base, poses = designs_with_gaps()
    return [
        lk.analyze(forced_fourbar(0), {"crank": np.arange(0.0, 360.0, 10.0)}, method="numerical", rates=False),
        lk.analyze(random_triad(1), wide, rates=False),
        lk.analyze(base, {"crank": np.arange(-180.0, 180.0, 3.0)}, poses=poses, rates=False),
    ]


def test_the_shortcuts_change_no_sample_and_no_bit(monkeypatch):
    """Chain bounds (docs/method.md, "Cost, at the same results") give exactly the walk without them: the same
    assembled samples and bit-identical positions. (The look-ahead batches this test also switched off are gone:
    the walk now follows a fixed grid, one Newton batch per step for every design.)"""
    from linkagekit import group

    fast = walks()
    assert all(0.05 < r.assembled.mean() < 0.95 for r in fast)  # every case walks through gaps
    monkeypatch.setattr(group.Group, "_possible", lambda self, K, reach: np.ones(K.shape[1:], bool))
    for a, b in zip(fast, walks(), strict=True):
        assert np.array_equal(a.assembled, b.assembled)
        assert np.array_equal(points(a), points(b), equal_nan=True)


def test_a_dyads_gap_costs_no_newton(monkeypatch):
    """Where a forced four-bar's dyad cannot close (its chain is too short), no Newton runs: before, each sample
    of the gap cost 16 iterations and 17 restarts of 64 (about 20,000 linear solves for this sweep)."""
    solves = []
    solve = np.linalg.solve
    monkeypatch.setattr(np.linalg, "solve", lambda *a, **k: solves.append(1) or solve(*a, **k))
    res = lk.analyze(forced_fourbar(0), {"crank": np.arange(0.0, 360.0, 5.0)}, method="numerical", rates=False)
    assert 0.3 < res.assembled.mean() < 0.5  # a gap, and the branch found again after it
    assert len(solves) < 1000, len(solves)  # measured 170


@pytest.mark.parametrize("seed", [1, 4, 5])
def test_chains_never_rule_out_an_assembled_sample(seed):
    """The chain bounds hold at every sample the group assembles, and rule out part of a dyad's gap.

    The held joints are computed here: ground joints stay, the crank's pin turns about its pivot.
    """
    from linkagekit.api import prepare
    from linkagekit.group import Group

    for mech, method in ((random_triad(seed), "natural"), (forced_fourbar(seed), "numerical")):
        drv = mech.drivers[0]
        x = np.arange(-360.0, 360.0, 1.0)
        res = lk.analyze(mech, {drv.name: x}, method=method, rates=False)
        params = prepare(mech, numerical=method == "numerical")
        names = params.plan.joint_names
        pivot, pin = mech.joints[drv.pivot], mech.joints[drv.toward]
        turn = np.exp(1j * (np.radians(x) - np.angle(pin - pivot)))
        z = np.array([pivot + (pin - pivot) * turn if j == drv.toward else mech.joints[j] + 0 * turn for j in names])
        ruled_out = 0
        for step, nums in zip(params.plan.steps, params.steps, strict=True):
            if isinstance(step, Group):
                dn = step._design_nums(nums, np.zeros(len(x), int))
                ok = step._possible(z[list(step.known)], step._reach(dn, len(x)))
                assert ok[res.assembled].all(), (seed, method)
                ruled_out += int(np.sum(~ok))
        assert ruled_out > 0 or res.assembled.all() or method == "natural"
        if method == "numerical":
            assert ruled_out == np.sum(~res.assembled)  # a four-bar's only gap: its dyad's circles do not meet


# ----------------------------------------------------------------------------- a crank's input is a direction
# Issue 29: a six-bar of Pyslvs' collection whose class-3 group assembles over part of the crank's turn only.
# Before, inputs were walked to as given (not modulo a turn): --at=360 and --at=-250 (110 deg) were not assembled,
# and the edge of the range moved with the other inputs asked.
SIX = {
    "format": "linkagekit/1",
    "name": "Six bar linkage mechanism (Pyslvs collection)",
    "units": {"length": "mm", "angle": "deg"},
    "joints": {
        "P0": [5.8511, -103.2831],
        "P1": [-71.3292, -109.7644],
        "P2": [77.8903, -110.263],
        "P3": [23.7994, 20.3606],
        "P4": [-33.1974, 90.658],
        "P5": [112.2951, 18.3663],
        "P6": [-117.0519, -18.5671],
    },
    "links": {
        "ground": ["P0", "P1", "P2"],
        "L2": ["P0", "P3"],
        "L3": ["P1", "P6"],
        "L5": ["P2", "P5"],
        "L1": ["P3", "P4", "P5"],
        "L4": ["P4", "P6"],
    },
    "drivers": [{"link": "L3", "pivot": "P1", "toward": "P6"}],
}


class SixbarReference:
    """The six-bar by another formulation: unknowns the angle of L2 and the rotation of the ternary L1 from its
    pose (2 reals; the ternary is rigid and keeps its handedness by construction), equations the lengths of L5 and
    L4; continued from the pose in small steps with scipy's fsolve, keeping the sign of the 2x2 Jacobian."""

    STEP = 0.5  # degrees

    def __init__(self, doc):
        J = {k: complex(*v) for k, v in doc["joints"].items()}
        self.J = J
        self.r = abs(J["P6"] - J["P1"])
        self.l2, self.l5, self.l4 = abs(J["P3"] - J["P0"]), abs(J["P5"] - J["P2"]), abs(J["P4"] - J["P6"])
        self.d4, self.d5 = J["P4"] - J["P3"], J["P5"] - J["P3"]
        self.x0 = math.degrees(cmath.phase(J["P6"] - J["P1"]))
        self.size = max(abs(z - np.mean(list(J.values()))) for z in J.values())
        start = np.array([cmath.phase(J["P3"] - J["P0"]), 0.0])
        self.sign = np.sign(np.linalg.det(self.jac(start, self.x0)))
        self.cache = {}
        self.up = self.walk(start, +1)
        self.down = self.walk(start, -1)

    def points(self, x, a):
        J = self.J
        P3 = J["P0"] + self.l2 * cmath.exp(1j * x[0])
        rot = cmath.exp(1j * x[1])
        return {
            "P3": P3,
            "P4": P3 + self.d4 * rot,
            "P5": P3 + self.d5 * rot,
            "P6": J["P1"] + self.r * cmath.exp(1j * math.radians(a)),
        }

    def F(self, x, a):
        p = self.points(x, a)
        return [abs(p["P5"] - self.J["P2"]) - self.l5, abs(p["P4"] - p["P6"]) - self.l4]

    def jac(self, x, a, h=1e-7):
        return np.array([(np.array(self.F(x + e, a)) - self.F(x - e, a)) / (2 * h) for e in np.eye(2) * h]).T

    def solve(self, x, a):
        """From x to input a (a small step): the solution on the pose's branch, or None."""
        with warnings.catch_warnings():  # it may say it cannot improve: the residual decides
            warnings.simplefilter("ignore", RuntimeWarning)
            sol = fsolve(self.F, x, args=(a,), xtol=1e-13)
        if max(abs(v) for v in self.F(sol, a)) > 1e-11 * self.size:
            return None
        if np.sign(np.linalg.det(self.jac(sol, a))) != self.sign or np.max(np.abs(sol - x)) > 0.3:
            return None
        return sol

    def walk(self, x, direction):
        """States every STEP degrees from the pose until the branch ends (at most a turn); the end to 1e-9 deg."""
        states = [(self.x0, x)]
        a = self.x0
        while abs(a - self.x0) < 360:
            nxt = self.solve(x, a + direction * self.STEP)
            if nxt is None:
                break
            a, x = a + direction * self.STEP, nxt
            states.append((a, x))
        else:
            return states, None
        lo, hi = 0.0, self.STEP  # bisection of the last step, from the last good state
        while hi - lo > 1e-10:
            mid = (lo + hi) / 2
            got = self.solve(x, a + direction * mid)
            if got is None:
                hi = mid
            else:
                lo = mid
        return states, a + direction * lo

    @property
    def range(self):
        return self.down[1], self.up[1]

    def at(self, u):
        """The joints P3, P4, P5 at direction u (deg), or None where the pose's branch does not reach it."""
        lo, hi = self.range
        a = lo + (u - lo) % 360.0  # the direction (the same for u + 360 k, to rounding)
        key = round(a, 11)
        if a > hi:
            return None
        if key not in self.cache:
            self.cache[key] = self.solve_at(a)
        return self.cache[key]

    def solve_at(self, a):
        states = self.up[0] if a >= self.x0 else self.down[0]
        k = min(int(abs(a - self.x0) // self.STEP), len(states) - 1)
        sol = self.solve(states[k][1], a)
        if sol is None:
            return None
        p = self.points(sol, a)
        return np.array([p["P3"], p["P4"], p["P5"]])


@functools.cache
def sixbar(
    dx: float = 0.0, dy: float = 0.0, at: tuple[tuple[str, float, float], ...] = ()
) -> tuple[lk.Mechanism, SixbarReference]:
    """The six-bar with joint P4 moved by (dx, dy) (other lengths of L1 and L4: another limited range), and the
    joints of ``at`` (name, x, y) placed there."""
    doc = copy.deepcopy(SIX)
    doc["joints"]["P4"] = [SIX["joints"]["P4"][0] + dx, SIX["joints"]["P4"][1] + dy]
    doc["joints"].update({name: [x, y] for name, x, y in at})
    return lk.Mechanism.from_dict(doc), SixbarReference(doc)


#: a variant of the six-bar (review 8): a shorter crank, P3 and P4 moved; its branch folds at 366.71 deg going up
#: while another branch of the pose's determinant sign begins at 366.87 deg, and it comes back at 377.56 deg
SIX_NARROW = (
    ("P3", 21.30630214985059, 20.525903917388977),
    ("P4", -38.82728188645594, 80.53462823163159),
    ("P6", -87.08321526123048, -78.34185373779296),
)


def joints_of(res) -> tuple[np.ndarray, np.ndarray]:
    """The group's joints P3, P4, P5 (3, n) and the flags (n,) of a result."""
    return np.array([res.point(j) for j in ("P3", "P4", "P5")]), np.asarray(res.assembled)


def check_against_reference(ref: SixbarReference, u: np.ndarray, pts: np.ndarray, ok: np.ndarray) -> None:
    """Samples at inputs ``u`` (degrees) assembled exactly where the reference reaches their direction, and there
    at the reference's joints (1e-9 of the size)."""
    for i, ui in enumerate(u):
        want = ref.at(float(ui))
        assert ok[i] == (want is not None), (ui, ok[i])
        if want is not None:
            err = np.max(np.abs(pts[:, i] - want)) / ref.size
            assert err <= 1e-9, (ui, err)


def same_answers(pts_a: np.ndarray, ok_a: np.ndarray, pts_b: np.ndarray, ok_b: np.ndarray, size: float) -> None:
    assert np.array_equal(ok_a, ok_b)
    assert np.max(np.abs(pts_a[:, ok_a] - pts_b[:, ok_b]), initial=0.0) <= 1e-9 * size


@pytest.mark.parametrize(
    "moved",
    [(0.0, 0.0), pytest.param((3.0, 0.0), marks=pytest.mark.long), pytest.param((-2.0, 4.0), marks=pytest.mark.long)],
)
def test_a_cranks_input_is_a_direction(moved):
    """The six-bar and two variants with other ranges: the range ``check`` reports is the reference continuation's
    (1e-6 deg); inputs u + 360 k (k = -3..3) answer alike in a shuffled list, in a 1-degree list from -1080 to
    1080 and (the six-bar) alone: positions to 1e-9 of the size, the same flags; assembled exactly where the
    direction lies in the range, and there equal to the reference continuation from the pose (1e-9 of the size)."""
    from linkagekit.checks import input_range

    mech, ref = sixbar(*moved)
    ((lo, hi),) = input_range(mech)
    assert abs(lo - ref.range[0]) <= 1e-6 and abs(hi - ref.range[1]) <= 1e-6, (lo, hi, ref.range)
    assert hi - lo < 330  # a limited range: the directions beyond it do not assemble
    # directions across the turn, and a hair (1e-4 deg) inside and outside each end
    u = np.concatenate([np.linspace(-180.0, 180.0, 12, endpoint=False), [lo + 1e-4, hi - 1e-4, lo - 1e-4, hi + 1e-4]])
    every = (u[:, None] + 360.0 * np.arange(-3, 4)[None, :]).ravel()
    perm = np.random.default_rng(29).permutation(len(every))
    pts, ok = joints_of(lk.analyze(mech, {"L3": every[perm]}, rates=False))
    check_against_reference(ref, every[perm], pts, ok)
    # a 1-degree list: each sample as the same direction in [-180, 180), and those as the reference
    x = np.arange(-1080.0, 1081.0, 1.0)
    dpts, dok = joints_of(lk.analyze(mech, {"L3": x}, rates=False))
    turn = np.flatnonzero((x >= -180) & (x < 180))
    same = turn[np.searchsorted(x[turn], (x + 180.0) % 360.0 - 180.0)]
    same_answers(dpts, dok, dpts[:, same], dok[same], ref.size)
    check_against_reference(ref, x[turn][::5], dpts[:, turn[::5]], dok[turn[::5]])
    if moved == (0.0, 0.0):  # alone: each input its own call (the issue's --at=360, --at=-250, --at=-300 too)
        for ui in [hi - 1e-4, 0.0, 110.0]:
            alone = [joints_of(lk.analyze(mech, {"L3": [ui + 360.0 * k]}, rates=False)) for k in range(-3, 4)]
            check_against_reference(
                ref,
                np.full(7, ui),
                np.concatenate([a[0] for a in alone], axis=1),
                np.concatenate([a[1] for a in alone]),
            )


def test_a_gap_where_another_branch_begins_is_not_assembled():
    """The six-bar variant ``SIX_NARROW``: its range ends at a fold 0.16 deg before another branch of the pose's
    sign begins, well inside a grid cell of the walk. Its range by ``check`` is the reference continuation's (1e-6
    deg), a gap of 10.85 deg; in a 0.5-degree list over six turns, and alone, every input is assembled exactly where
    its direction lies in the range, there at the reference's joints (1e-9 of the size). Before, the walk's grid
    step from 366 to 369 deg landed on the other branch (its way back converged home) and 22 of the list's inputs
    in the gap were assembled on it, as were the inputs alone from 9.7 deg on."""
    from linkagekit.checks import input_range

    mech, ref = sixbar(at=SIX_NARROW)
    ((lo, hi),) = input_range(mech)  # [-342.44, 6.71]: the reference's [17.56, 366.71] a turn down
    assert abs(lo + 360 - ref.range[0]) <= 1e-6 and abs(hi + 360 - ref.range[1]) <= 1e-6, (lo, hi, ref.range)
    assert 10.8 < lo + 360 - hi < 10.9
    x = np.arange(-1080.0, 1081.0, 0.5)
    pts, ok = joints_of(lk.analyze(mech, {"L3": x}, rates=False))
    check_against_reference(ref, x, pts, ok)
    gap = np.array([hi + 0.01, hi + 1, hi + 3, hi + 5.4, lo + 357, lo + 359, lo + 359.99])
    edges = np.array([hi - 1e-4, lo + 1e-4])
    for u in np.concatenate([gap, edges, gap - 720]):
        check_against_reference(ref, np.array([u]), *joints_of(lk.analyze(mech, {"L3": [u]}, rates=False)))


def agrees_with_arclength(mech, ref: ArclengthTriad, u: np.ndarray, direction: bool = True) -> None:
    """Inputs ``u`` (deg) in one list and each alone: assembled exactly where the reference's branch reaches them (the
    direction taken into its range when ``direction``), there at its joints (1e-9 of the size)."""
    listed = lk.analyze(mech, {"crank": u}, rates=False)
    for i, ui in enumerate(u):
        d = ref.range[0] + (ui - ref.range[0]) % 360.0 if direction else ui
        want = ref.at(d) if d <= ref.range[1] else None
        for res, k in ((listed, i), (lk.analyze(mech, {"crank": [ui]}, rates=False), 0)):
            assert res.assembled[k] == (want is not None), (ui, res.assembled[k])
            if want is not None:
                got = np.array([complex(*res.xy(j)[k]) for j in ref.UNKNOWN])
                assert np.max(np.abs(got - want)) <= 1e-9 * ref.size, (ui, np.max(np.abs(got - want)))


@pytest.mark.long
def test_a_triad_follows_its_branch_through_a_sharp_turn_to_its_fold():
    """A class-3 triad whose Jacobian's determinant nearly vanishes at -43.3444 deg (5e-5 of its value elsewhere)
    without changing sign: two complex roots pass near the branch, which turns sharply there (J1 moves 0.06 over
    0.0004 deg) and goes on down to a fold at -94.814 deg. ``ArclengthTriad`` (an independent pseudo-arclength
    continuation: the input falls monotonically from the pose to there) and ``modes`` (one other real mode, far
    away, at every input) agree. ``input_range`` is the reference's to 1e-6 deg; inputs through the turn and down to
    the fold are assembled at the reference's joints (1e-9 of the size), in a list and alone; past the fold not.
    Before, the walk's sub-steps could not follow the turn (failed steps were halved to 2^-10 of a path, coarser than
    the turn): inputs from -43.3453 deg down were flagged, and ``input_range`` put a fold at -43.3647 deg, as did a
    scipy continuation in 0.01-deg steps that an earlier version of this test trusted."""
    from linkagekit.checks import input_range

    p = {"O": -1.0319 + 0.6634j, "A": 1.51 - 0.7844j, "B0": 3.8161 + 7.5343j, "C0": 2.7296 + 2.4825j}
    p.update({"J1": 2.1925 + 1.8222j, "J2": 3.6188 - 1.2897j, "J3": 4.2453 + 2.4778j})
    mech = triad(p)
    ref = ArclengthTriad(p, TRIAD_BARS[1:])
    assert abs(ref.range[0] + 94.814) < 1e-3 and abs(ref.range[1] - 32.191) < 1e-3
    ((lo, hi),) = input_range(mech)
    assert abs(lo - ref.range[0]) < 1e-6 and abs(hi - ref.range[1]) < 1e-6, (lo, hi, ref.range)
    u = np.array([-43.0, -43.344, -43.3446, -43.345, -43.3647, -43.6, -44.3, -60.0, -94.81, -94.82, -100.0, 32.2])
    agrees_with_arclength(mech, ref, u, direction=False)


def test_following_the_branch_continuously_a_triad_goes_through_its_sharp_turn():
    """The triad of the sharp turn above, ``branch="continuous"``: there no zero ahead bounds the sub-steps (a
    change point is crossed on purpose), and failed ones were halved only to 2^-10 of a path, too coarse for the
    turn: 77 of 190 inputs from -43.3446 deg down to the fold were flagged. Halved now down to 2^-30 (and stopped at
    a fold as in the default mode), every input is assembled at the reference's joints (1e-9 of the size)."""
    p = {"O": -1.0319 + 0.6634j, "A": 1.51 - 0.7844j, "B0": 3.8161 + 7.5343j, "C0": 2.7296 + 2.4825j}
    p.update({"J1": 2.1925 + 1.8222j, "J2": 3.6188 - 1.2897j, "J3": 4.2453 + 2.4778j})
    ref = ArclengthTriad(p, TRIAD_BARS[1:])
    u = np.linspace(-94.8, 32.1, 190)
    res = lk.analyze(triad(p), {"crank": u}, rates=False, branch="continuous")
    assert res.assembled.all()
    got = np.array([[complex(*xy) for xy in res.xy(j)] for j in ref.UNKNOWN])
    want = np.array([ref.at(x) for x in u]).T
    assert np.max(np.abs(got - want)) <= 1e-9 * ref.size


def test_the_range_of_a_triad_whose_continuation_hopped_has_its_gap():
    """A perturbed random triad (``random_triad(29)``, pose -170.03 deg) whose branch ends at -77.04 deg going up and
    at -404.35 deg (the -44.35 direction) going down: an independent fine continuation (scipy, 0.01 deg steps) stops
    at both. ``input_range`` used to report the full turn (its continuation hopped across a fold onto another root of
    the pose's sign); now the gap, its ends to 0.01 deg, and ``analyze`` flags an input inside it."""
    from linkagekit.checks import input_range

    base = random_triad(29)
    poses = base.pose_array()[None] + np.random.default_rng(1029).normal(0, 0.5, (20, len(base.joint_names), 2))
    mech = base.with_pose(poses[11])
    ((lo, hi),) = input_range(mech)
    assert abs(lo + 44.347) < 0.01 and abs(hi - (360 - 77.036)) < 0.01
    res = lk.analyze(mech, {"crank": [-170.0, -60.0, -50.0]}, rates=False)
    assert res.assembled[0] and not res.assembled[1:].any()


def test_no_input_past_the_end_of_a_triad_whose_continuation_hopped_is_assembled():
    """The triad above, every 0.01 deg over 1.6 deg past the end of its range at -44.347 deg: none assembled. A
    sub-step from 0.04 deg inside the fold to 0.25 deg past it moved 0.13 of the group's size onto another sheet,
    and Newton's way back crept within a tenth of that move of its start in six steps without converging, which the
    way back accepted (near a fold it converges only linearly: the samples of
    ``test_a_sample_a_hair_inside_a_fold_end_is_assembled`` need that): -44.75 deg was assembled (review 29b).
    Followed on to 40 steps, that way back does not converge and ends 4.7 moves away (506 ways back of the branch's
    own sub-steps about folds converged within 1.6e-9 of theirs). Then still assembled: -45.16 deg, reached by a
    sub-step whose way back does converge home. Now no sub-step goes more than half the way to where the square of
    the Jacobian's determinant, linear through the last two states, vanishes (``Group._halving``): that sub-step is
    not taken. (``ArclengthTriad``, a pseudo-arclength continuation, turns at -404.3473 deg: -44.3473.)"""
    base = random_triad(29)
    poses = base.pose_array()[None] + np.random.default_rng(1029).normal(0, 0.5, (20, len(base.joint_names), 2))
    mech = base.with_pose(poses[11])
    res = lk.analyze(mech, {"crank": np.arange(-46.0, -44.36, 0.01)}, rates=False)
    assert not res.assembled.any()


#: a triad with a slider leg whose line the crank carries (``MOVING`` of tests/test_group_sliders.py, D, E and F moved)
MOVING_SLIDER_TRIAD = {
    "format": "linkagekit/1",
    "joints": {"A": [0, 0], "B": [6, 0], "C": [1, 1], "H": [1.5, 3.0]}
    | {"D": [2.2124, 3.997], "E": [4.681, 2.6341], "F": [3.5112, 6.5564]},
    "links": {"ground": ["A", "B"], "crank": ["A", "C", "H"], "l1": ["C", "D"], "l2": ["B", "E"], "block": ["F"]}
    | {"tri": ["D", "E", "F"]},
    "sliders": [{"link": "block", "on": "crank", "through": "F", "direction": [1, 0]}],
    "drivers": [{"link": "crank", "pivot": "A", "toward": "C"}],
}


def test_the_whole_range_of_a_slider_triad_near_a_fold_is_assembled():
    """A slider triad whose line the crank carries: ``input_range`` is [8.246186, 45.303072] deg (the test's own scipy
    continuation of its loop equations reaches every input of it). Before the way back was checked (868b6ea) every
    input in it assembled, on that continuation's positions (3.5e-13); now the inputs from the lower end to 9.4762
    deg (1.23 deg of the range, 115 of 576 samples 0.01 deg apart) were flagged while the way back had to converge
    within six iterations (near a fold it converges linearly: 108 rejections of the branch's own sub-steps); a way
    back that ends within a tenth of the move of its start is now accepted without converging, and all assemble."""
    from linkagekit.checks import input_range

    mech = lk.Mechanism.from_dict(MOVING_SLIDER_TRIAD)
    ((lo, hi),) = input_range(mech)
    assert abs(lo - 8.246186) < 1e-5 and abs(hi - 45.303072) < 1e-5
    res = lk.analyze(mech, {"crank": [8.25, 8.5, 9.0, 9.45, 30.0]}, rates=False)
    assert res.assembled.all()


def test_a_sample_extrapolated_past_a_fold_is_not_assembled():
    """A perturbed random triad (range [-155.482, -99.145] deg by ``ArclengthTriad``, the pose at -145.9): -157.48
    deg, 2 deg past the lower end, lies in the cell past the walk's last column (-154.92 deg, 0.56 deg before the
    fold); started from the extrapolation of the columns before, Newton converged on another branch and the sample
    was assembled in the list below (and alone, once the walk's steps were bounded by the determinant's zero ahead),
    while -157 and -156 deg were not. Now a sample extrapolated past where the
    determinant's square, linear through the last two columns, vanishes is left to the sub-steps, which stop at the
    fold. Inputs about the end agree with the reference (flags; joints to 1e-9 of the size)."""
    p = {"O": -0.10899343699051743 - 0.1701495325198742j, "A": -3.1495997040073225 - 2.2276040499406164j}
    p |= {"B0": -7.871886587506435 + 1.627926286529156j, "C0": -1.214171393076433 + 9.936923426857481j}
    p |= {"J1": -2.8270203263234874 - 1.7804701283986402j, "J2": -0.4068113340861727 - 1.6932176658814364j}
    p |= {"J3": -1.732560357408202 - 4.012415193087582j}
    mech = triad(p)
    ref = ArclengthTriad(p, TRIAD_BARS[1:])
    assert abs(ref.range[0] + 155.4816) < 1e-4 and abs(ref.range[1] + 99.145) < 1e-3
    u = np.array([-157.48165, -157.0, -156.0, -155.5, -155.48, -155.4, -150.0, 562.51835])
    # the list of an independent harness in which 562.51835 deg was assembled
    u = np.concatenate([u, [-180.0, -885.0, -510.0, 225.0, -480.0, -465.0, -90.0, -795.0, 300.0, -765.0, -750.0]])
    u = np.concatenate([u, [-375.0, 360.0, 375.0, 30.0, -675.0, -660.0, 435.0, 450.0, 825.0, 120.0, 135.0, 510.0]])
    u = np.concatenate([u, [525.0, -155.48164, 564.52835, -515.18165, -515.49165, -875.78165, -819.14504]])
    u = np.concatenate([u, [260.84497, 260.55497, -99.13503, -458.84503, -97.14503]])
    agrees_with_arclength(mech, ref, u)


#: two triads in sequence (review 8): the crank O-A drives triad J1 J2 J3 (legs A-J1, B0-J2, C0-J3), whose J3 drives
#: triad K1 K2 K3 (legs J3-K1, D0-K2, E0-K3); the first turns fully, not back to its configuration after a turn
TWO_TRIADS = {
    "O": 0j,
    "A": 1.5 + 0.5j,
    "B0": 6.183488855581185 - 1.9845590727742248j,
    "C0": 2.444074100721867 + 4.885477160882504j,
    "J1": 3.0984160235358154 + 4.583468868186857j,
    "J2": -1.0706135500406222 + 2.1785207235905886j,
    "J3": 1.221169412507832 + 0.31805170979358266j,
    "D0": -5.921235290488499 + 5.628700117597598j,
    "E0": 7.7662314200064575 + 4.984537937417514j,
    "K1": -0.8893042816312955 + 2.7537963517090485j,
    "K2": -0.9864735488810941 + 2.9630085139709625j,
    "K3": 2.5534940868503546 + 3.9812466837314977j,
}
TWO_TRIADS_BARS = TRIAD_BARS[1:] + [("J3", "K1"), ("D0", "K2"), ("E0", "K3"), ("K1", "K2"), ("K2", "K3"), ("K1", "K3")]


def two_triads_mechanism() -> lk.Mechanism:
    links = dict(TRIAD_LINKS, m1=["J3", "K1"], m2=["D0", "K2"], m3=["E0", "K3"], tern2=["K1", "K2", "K3"])
    links["ground"] = ["O", "B0", "C0", "D0", "E0"]
    doc = {"format": "linkagekit/1", "units": {"length": "mm", "angle": "deg"}, "joints": xy(TWO_TRIADS)}
    return lk.Mechanism.from_dict(doc | {"links": links, "drivers": [{"link": "crank", "pivot": "O", "toward": "A"}]})


@pytest.mark.long
def test_two_triads_in_sequence_take_a_direction_the_same_way_round():
    """``TWO_TRIADS``: the whole mechanism's branch runs from -286.006 deg to a fold 0.05 deg above the pose (18.487
    deg), by ``ArclengthTriad`` over both triads (12 unknowns); ``input_range`` says so. A direction such as 180 deg
    lies nearer the pose going up, where the first triad reaches it but the second does not, so both must take it
    going down, where the first triad is in another configuration (its branch turns fully without coming back to it
    after a turn). Before, the first group went up and the second could not go down without it: every input from
    -176.75 deg down was flagged (review 8). Now inputs across the range, in a list and alone, are at the
    reference's joints (1e-9 of the size), and the directions outside it are flagged."""
    from linkagekit.checks import input_range

    unknown = ("J1", "J2", "J3", "K1", "K2", "K3")
    ref = ArclengthTriad(TWO_TRIADS, TWO_TRIADS_BARS, unknown)
    assert abs(ref.range[0] + 286.006) < 1e-3 and abs(ref.range[1] - 18.487) < 1e-3
    mech = two_triads_mechanism()
    ((lo, hi),) = input_range(mech)
    assert abs(lo - ref.range[0]) < 1e-6 and abs(hi - ref.range[1]) < 1e-6, (lo, hi, ref.range)
    u = np.array([-100.0, -150.0, -180.0, -190.0, 170.0, -250.0, 90.0, -285.9, 18.4, 18.5, 30.0, 60.0, 200.0])
    agrees_with_arclength(mech, ref, u)


def test_two_triads_take_a_direction_the_same_way_round_whatever_else_is_asked():
    """``TWO_TRIADS`` asked -170.2 deg beside -165.2 deg (and two other such pairs) gave -170.2 deg in another
    configuration, 7.6 to 8.0 mm (1.9 of the size) off its answer alone: its nearest representative, 189.8 deg, lies
    above the pose, where the first triad reaches it and the second does not; the second went down by itself while
    its knowns, the first's joints, stayed a turn up, and where a neighbouring sample's column helped its Newton
    it converged on that mix. Every later group now takes each direction the way round the first took it (a
    direction neither reaches so is solved again with both a turn the other way). Each pair, as a list, is at the
    arclength reference's joints (1e-9 of the size), as each input alone is (review 11c)."""
    unknown = ("J1", "J2", "J3", "K1", "K2", "K3")
    ref = ArclengthTriad(TWO_TRIADS, TWO_TRIADS_BARS, unknown)
    mech = two_triads_mechanism()
    for pair in ([-170.2, -165.2], [-166.4, -165.4], [-169.9, -164.9], [-165.2, -170.2]):
        agrees_with_arclength(mech, ref, np.array(pair))


def _perturbed_two_triads(seed: int) -> dict[str, complex]:
    """``TWO_TRIADS`` with its triads' joints and the second's ground pivots moved by N(0, 0.15) (review 12a)."""
    rng = np.random.default_rng(seed)
    names = ("J1", "J2", "J3", "K1", "K2", "K3", "D0", "E0")
    moved = {j: TWO_TRIADS[j] + complex(*rng.normal(0, 0.15, 2)) for j in names}
    return TWO_TRIADS | moved


@pytest.mark.parametrize(
    ("seed", "lo", "hi"),
    [
        (5, -288.3595, 18.7695),
        pytest.param(6, -290.8307, 18.4379, marks=pytest.mark.long),
        pytest.param(14, -293.7743, 18.4419, marks=pytest.mark.long),
    ],
)
def test_a_later_group_follows_an_earlier_groups_sharp_turn(seed, lo, hi):
    """Two triads in sequence, perturbed (review 12a): the first turns fully, but turns sharply just above the pose
    (18.435 deg; its joint J1 moves 1.1 over 0.5 deg). The second's knowns (J3) go out of its reach through a fold
    (18.7695 deg for seed 5, 0.33 deg above the pose; 18.4379 for seed 6, 0.003 deg) and come back 0.2 deg on. With
    its knowns on the cubic through two grid columns and one Newton per grid step, the second group stepped over
    the excursion: inputs past the fold (20, 40 deg) assembled on another piece of the curve, and directions a turn
    down (-165 deg, whose nearest representative is 195) 1.7 of the size off; for seed 6, -50 deg was flagged when
    asked beside 60 deg, which assembled. Seed 14's fold lies 0.007 deg above the pose: the second group's trend
    there, read along the knowns' central difference over two grid steps, did not see it, and its first sub-step
    went over (review 13a: 18.5 to 40 deg assembled, directions a turn down 2 of the size off). Now a later group
    re-runs an earlier one at the inputs of its sub-steps, sub-steps through the cells where an earlier group did,
    and reads its trend at the pose from the knowns' local motion: every input, in a list and alone, is where the
    arclength reference over all six joints puts it (1e-9 of the size), and flagged past its range."""
    unknown = ("J1", "J2", "J3", "K1", "K2", "K3")
    pts = _perturbed_two_triads(seed)
    ref = ArclengthTriad(pts, TWO_TRIADS_BARS, unknown)
    assert abs(ref.range[0] - lo) < 1e-3 and abs(ref.range[1] - hi) < 1e-3, ref.range
    links = dict(TRIAD_LINKS, m1=["J3", "K1"], m2=["D0", "K2"], m3=["E0", "K3"], tern2=["K1", "K2", "K3"])
    links["ground"] = ["O", "B0", "C0", "D0", "E0"]
    doc = {"format": "linkagekit/1", "units": {"length": "mm", "angle": "deg"}, "joints": xy(pts), "links": links}
    mech = lk.Mechanism.from_dict(doc | {"drivers": [{"link": "crank", "pivot": "O", "toward": "A"}]})
    u = np.array([-100.0, -150.0, -165.0, -190.0, 18.43, 18.9, 20.0, 40.0, 60.0, 100.0, -50.0, -280.0, 18.5])
    agrees_with_arclength(mech, ref, u)


def _seeded_triad(seed: int) -> dict[str, complex]:
    rng = np.random.default_rng(seed)
    p = {"B0": complex(*rng.uniform(-10, 10, 2)), "C0": complex(*rng.uniform(-10, 10, 2))}
    c = complex(*rng.uniform(-4, 4, 2))
    return p | {j: c + complex(*rng.uniform(-3, 3, 2)) for j in ("J1", "J2", "J3")}


@pytest.mark.parametrize("branch", ["pose", "continuous"])
def test_two_triads_side_by_side_take_a_direction_the_same_way_round(branch):
    """Two random triads on one crank tip (review 12a): J1 J2 J3 turns fully and comes back to its configuration
    after a turn, K1 K2 K3 is limited to [-178.157, 54.048] deg (the pose at 18.435). A direction such as 190 deg
    is on K's branch only a turn down. The first group (J) takes its nearest representative, and the later one
    follows it (``Kin.took``), so the direction assembles only in the second pass with both a turn down, which
    following the branch continuously did not run (NaN at every such direction; before ``Kin.took``, K went down
    by itself). In both modes every input is at the arclength reference's joints over all six (1e-9 of the size)."""
    f, t = _seeded_triad(59), _seeded_triad(1)
    p = {"O": 0j, "A": 1.5 + 0.5j} | f | {"D0": t["B0"], "E0": t["C0"], "K1": t["J1"], "K2": t["J2"], "K3": t["J3"]}
    bars = TRIAD_BARS[1:] + [("A", "K1"), ("D0", "K2"), ("E0", "K3"), ("K1", "K2"), ("K2", "K3"), ("K1", "K3")]
    ref = ArclengthTriad(p, bars, ("J1", "J2", "J3", "K1", "K2", "K3"))
    links = dict(TRIAD_LINKS, m1=["A", "K1"], m2=["D0", "K2"], m3=["E0", "K3"], tern2=["K1", "K2", "K3"])
    links["ground"] = ["O", "B0", "C0", "D0", "E0"]
    doc = {"format": "linkagekit/1", "units": {"length": "mm", "angle": "deg"}, "joints": xy(p), "links": links}
    mech = lk.Mechanism.from_dict(doc | {"drivers": [{"link": "crank", "pivot": "O", "toward": "A"}]})
    u = np.array([-170.2, 190.0, 186.9, 183.0, -100.0, 30.0])
    res = lk.analyze(mech, {"crank": u}, rates=False, branch=branch)
    assert res.assembled.all()
    for i, ui in enumerate(u):
        d = ref.range[0] + (ui - ref.range[0]) % 360.0
        got = np.array([complex(*res.xy(j)[i]) for j in ref.UNKNOWN])
        assert np.max(np.abs(got - ref.at(d))) <= 1e-9 * ref.size, (ui, np.max(np.abs(got - ref.at(d))))


#: a five-bar (two cranks A-C, B-D) whose coupler point P holds a triad (legs P-J1, B0-J2, C0-J3; review 8)
FIVEBAR_TRIAD = {
    "A": 0j,
    "B": 50 + 0j,
    "C": -15 + 25.9807621135332j,
    "D": 65 + 25.9807621135332j,
    "E": 25 + 70.702121663529j,
    "P": 16.1807300401858 + 88.6526224191045j,
    "B0": 48.28348684464723 - 14.136258660142047j,
    "C0": -53.0345009308469 - 57.19030196015005j,
    "J1": 40.308733180561134 + 124.89278510496771j,
    "J2": 37.15819396547329 + 135.1715782451562j,
    "J3": 50.76962209827875 + 88.5548820642752j,
}


def fivebar_triad_mechanism() -> lk.Mechanism:
    doc = {"format": "linkagekit/1", "units": {"length": "mm", "angle": "deg"}, "joints": xy(FIVEBAR_TRIAD)}
    doc["links"] = {"ground": ["A", "B", "B0", "C0"], "crank1": ["A", "C"], "crank2": ["B", "D"]}
    doc["links"] |= {"link1": ["C", "E", "P"], "link2": ["D", "E"], "l1": ["P", "J1"], "l2": ["B0", "J2"]}
    doc["links"] |= {"l3": ["C0", "J3"], "tern": ["J1", "J2", "J3"]}
    doc["drivers"] = [{"link": "crank1", "pivot": "A", "toward": "C"}, {"link": "crank2", "pivot": "B", "toward": "D"}]
    return lk.Mechanism.from_dict(doc)


def straight_path_reference(p: dict[str, complex], target: np.ndarray) -> np.ndarray | None:
    """J1, J2, J3 of ``FIVEBAR_TRIAD`` at crank angles ``target`` (deg, the directions nearest the pose's), reached
    from the pose along the straight path of the two inputs in 0.1-deg steps: the five-bar by the law of cosines
    (E on the pose's side of C-D, P rigid on C-E), the triad by scipy's fsolve from the step before, keeping the
    sign of its Jacobian's determinant and moving no joint more than 1 % of the size a step; None where it fails."""
    ang = lambda a, b: math.degrees(cmath.phase(p[b] - p[a]))  # noqa: E731
    q0 = np.array([ang("A", "C"), ang("B", "D")])
    r1, r2, ce, de = abs(p["C"] - p["A"]), abs(p["D"] - p["B"]), abs(p["E"] - p["C"]), abs(p["E"] - p["D"])
    t = side(p["C"], p["D"], p["E"])
    rho = (p["P"] - p["C"]) / (p["E"] - p["C"])
    bars = [("P", "J1"), ("B0", "J2"), ("C0", "J3"), ("J1", "J2"), ("J2", "J3"), ("J1", "J3")]
    L = np.array([abs(p[a] - p[b]) for a, b in bars])

    def F(x, P):
        J = {"J1": x[0] + 1j * x[1], "J2": x[2] + 1j * x[3], "J3": x[4] + 1j * x[5], "P": P} | {
            k: p[k] for k in ("B0", "C0")
        }
        return np.array([abs(J[a] - J[b]) for a, b in bars]) - L

    def det(x, P, h=1e-6):
        return np.linalg.det(np.array([(F(x + e, P) - F(x - e, P)) / (2 * h) for e in np.eye(6) * h]).T)

    x = np.array([v for j in ("J1", "J2", "J3") for v in (p[j].real, p[j].imag)])
    sign = np.sign(det(x, p["P"]))
    steps = int(np.ceil(np.max(np.abs(target - q0)) / 0.1))
    for s in np.linspace(0, 1, steps + 1)[1:]:
        u = np.radians(q0 + s * (target - q0))
        C, D = p["A"] + r1 * cmath.exp(1j * u[0]), p["B"] + r2 * cmath.exp(1j * u[1])
        E = complex(by_cosines(C, D, ce, de, t))
        if not np.isfinite(E):
            return None
        P = C + (E - C) * rho
        with warnings.catch_warnings():  # it may say it cannot improve: the residual decides
            warnings.simplefilter("ignore", RuntimeWarning)
            y = fsolve(F, x, args=(P,), xtol=1e-13)
        if np.max(np.abs(F(y, P))) > 1e-9 or np.sign(det(y, P)) != sign or np.max(np.abs(y - x)) > 1.5:
            return None
        x = y
    return np.array([complex(x[0], x[1]), complex(x[2], x[3]), complex(x[4], x[5])])


def test_two_drivers_answer_alike_for_inputs_written_a_turn_apart():
    """``FIVEBAR_TRIAD`` (review 8): the pair (97.678, 101.935) deg, assembled alone, was flagged in a list with
    (111.675, 454.444) and (-276.403, 449.269), and so were those two, while the same directions written without
    the turns all assembled: the walk's path through the samples took crank2 at 454 deg, 394 deg from the pose's,
    not at 94. Now every angle is taken at its direction's representative nearest the pose's before the path is
    drawn: the list written either way gives the same flags and joints (1e-9 of the size), and the pair alone those
    of a straight path from the pose (``straight_path_reference``)."""
    mech = fivebar_triad_mechanism()
    a = (97.67832024, 101.93524934)
    turned = np.array([a, (111.675362, 454.443926), (-276.403291, 449.269225)]).T
    plain = np.array([a, (111.675362, 94.443926), (83.596709, 89.269225)]).T
    got = [lk.analyze(mech, {"crank1": x[0], "crank2": x[1]}, rates=False) for x in (turned, plain)]
    size = scale_of(mech)
    assert got[0].assembled.all() and got[1].assembled.all()
    for j in ("J1", "J2", "J3"):
        assert np.max(np.abs(got[0].point(j) - got[1].point(j))) <= 1e-9 * size
    alone = lk.analyze(mech, {"crank1": [a[0]], "crank2": [a[1]]}, rates=False)
    want = straight_path_reference(FIVEBAR_TRIAD, np.array(a))
    assert want is not None and alone.assembled[0]
    got_alone = np.array([complex(*alone.xy(j)[0]) for j in ("J1", "J2", "J3")])
    assert np.max(np.abs(got_alone - want)) <= 1e-9 * size
    assert np.max(np.abs(np.array([got[0].point(j)[0] for j in ("J1", "J2", "J3")]) - want)) <= 1e-9 * size


def test_two_drivers_in_a_batch_answer_as_each_design_alone():
    """``FIVEBAR_TRIAD`` and the same mechanism posed at cranks (128, 55) deg (its joints there, as ``analyze`` gives
    them), in one batch (``poses=``): pairs on a line through the first pose's inputs lie on none through the
    second's. Each design's answers in the batch are its own alone (flags; joints to 1e-9 of the size): the line
    the walk follows is each design's, or there is none."""
    base = fivebar_triad_mechanism()
    there = lk.analyze(base, {"crank1": [128.0], "crank2": [55.0]}, rates=False)
    assert there.assembled[0]
    moved = np.array([there.xy(j)[0] for j in base.joint_names])
    t = np.linspace(-30, 30, 13)
    q = {"crank1": 120.0 + t, "crank2": 60.0 + 0.5 * t}
    batch = lk.analyze(base, q, poses=np.stack([base.pose_array(), moved]), rates=False)
    assert batch.assembled.any(axis=1).all()
    size = scale_of(base)
    for k, mech in enumerate((base, base.with_pose(moved))):
        alone = lk.analyze(mech, q, rates=False)
        assert np.array_equal(batch.assembled[k], alone.assembled)
        for j in ("J1", "J2", "J3"):
            assert np.nanmax(np.abs(batch.point(j)[k] - alone.point(j))) <= 1e-9 * size


def test_a_sample_a_hair_inside_a_fold_end_is_assembled():
    """``random_triad(27)``'s range ends at folds, -165.0500215 and 100.6491420 deg (``input_range``; an independent
    scipy continuation stops within 1e-9 deg of both). Inputs 2e-5 to 3e-5 deg inside the lower end and 4e-5 deg
    inside the upper one assembled before the way back was checked (868b6ea), were flagged while it had to converge
    within six iterations, and assemble again now that a way back ending near its start is enough. Every sub-step
    ``Group._returns`` rejected on 40 random triads (four poses each, their ranges and a sweep) was the branch's own
    step along its chord (an independent continuation from its start reaches its end, 1e-10 of the size): Newton on
    the way back was within 1e-7 of the move of its start after six iterations but had not yet converged (near a
    fold it converges linearly); with twelve it converged home. The flagged zone inside a fold end grew from a
    median 1.8e-5 deg (max 4.2e-5) to 2.4e-5 deg (max 5.6e-5) over 230 ends; ``input_range`` is unchanged."""
    from linkagekit.checks import input_range

    mech = random_triad(27)
    ((lo, hi),) = input_range(mech)
    assert abs(lo + 165.0500215) < 1e-6 and abs(hi - 100.6491420) < 1e-6
    res = lk.analyze(mech, {"crank": [lo + 2e-5, lo + 2.5e-5, lo + 3e-5, hi - 4e-5]}, rates=False)
    assert res.assembled.all()


@pytest.mark.parametrize("moved", [(0.0, 0.0), (3.0, -2.0)])
def test_inputs_a_hair_inside_a_fold_end_are_assembled_and_a_hair_outside_not(moved):
    """A review: samples within 2.8e-5 deg inside a range's end were not assembled, although ``check`` finds the end
    to 3e-8 deg (the contract: each boundary exact to 1e-6). Next to a fold Newton converges only linearly, and the
    sub-steps' six iterations gave up. Against the independent continuation (ends to 1e-9 deg): inputs 1e-6, 1e-5
    and 1e-4 deg inside each end assemble at its joints, those 1e-6 deg outside do not."""
    mech, ref = sixbar(*moved)
    lo, hi = ref.range
    inside = [lo + 1e-6, lo + 1e-5, lo + 1e-4, hi - 1e-4, hi - 1e-5, hi - 1e-6]
    res = lk.analyze(mech, {"L3": [*inside, lo - 1e-6, hi + 1e-6]}, rates=False)
    pts, ok = joints_of(res)
    assert ok[:6].all() and not ok[6:].any()
    for i, u in enumerate(inside):  # next to a fold the joints move as the root of the distance: 1e-7 of the size
        assert np.max(np.abs(pts[:, i] - ref.at(u))) <= 1e-7 * ref.size, u


def test_samples_about_a_fold_end_where_only_some_last_steps_return_do_not_raise():
    """A review of the last step next to a fold: ten samples from 0.6 deg past to 0.3 deg inside the range's end of
    the triad above raised ValueError (the last step's way back kept some columns, and the start's knowns were still
    those of all): every sample inside assembles, none more than 1e-6 deg past, as the code before the last step."""
    base = random_triad(29)
    poses = base.pose_array()[None] + np.random.default_rng(1029).normal(0, 0.5, (20, len(base.joint_names), 2))
    mech = base.with_pose(poses[11])
    lo = -44.34732450999293  # input_range's lower end (test above: within 0.01 deg of an independent continuation)
    u = np.linspace(lo - 0.6, lo + 0.3, 10)
    res = lk.analyze(mech, {"crank": u}, rates=False)
    assert res.assembled[u > lo + 1e-6].all() and not res.assembled[u < lo - 1e-6].any()


def test_a_range_that_nearly_spans_a_turn_is_assembled_to_both_its_ends():
    """A perturbed random triad (``random_triad(17)``, pose -46.07 deg) whose branch turns from 37.99 deg up to
    -321.78 deg down (``input_range``): the directions between its ends past 37.99 (38.22..40.8 deg, the last
    2.6 deg of the range going down) lie in the cell where the up leg stopped, and were tried only there: not
    assembled, alone or in a sweep (a review's scipy continuation reached them). Now they are tried a turn the
    other way: assembled alone and among others alike, at that continuation's joints to 1e-9 of the size, and the
    0.23 deg between the two ends is not."""
    from linkagekit.checks import input_range

    base = random_triad(17)
    pose = base.pose_array() + np.random.default_rng(1017).normal(0, 0.5, (4, 7, 2))[1]
    mech = base.with_pose(pose - pose[base.joint_names.index("O")])  # O at the origin, as the reference has it
    ((lo, hi),) = input_range(mech)
    assert abs(lo + 321.7767) < 1e-3 and abs(hi - 37.9948) < 1e-3
    u = np.array([-318.5, -319.2, -320.0, -321.0, -321.7, 39.0, 40.5, 38.0, 38.1, 38.2, 30.0])
    inside = (u <= hi) | (u >= lo) & (u <= -300.0) | (u >= lo + 360 + 1e-6)
    assert inside.tolist() == [True] * 7 + [False] * 3 + [True]
    sweep = lk.analyze(mech, {"crank": u}, rates=False)
    assert sweep.assembled.tolist() == inside.tolist()
    size = scale_of(mech)
    pts = np.array([sweep.point(j) for j in ("J1", "J2", "J3")])  # (3, n)
    for i, v in enumerate(u):
        alone = lk.analyze(mech, {"crank": [v]}, rates=False)
        assert bool(alone.assembled[0]) == inside[i], v
        if inside[i]:
            got = np.array([alone.point(j)[0] for j in ("J1", "J2", "J3")])
            assert np.max(np.abs(got - pts[:, i])) < 1e-9 * size, v
    # the branch going down from the pose (39 and 40.5 deg are -321 and -319.5 deg that way)
    down = np.array([-318.5, -319.2, -320.0, -321.0, -321.7, 39.0 - 360, 40.5 - 360, 30.0])
    ref = reference_continuation(mech, down)
    assert np.all(np.isfinite(ref))
    assert np.max(np.abs(ref - pts[:, [0, 1, 2, 3, 4, 5, 6, 10]])) < 1e-9 * size


#: a Pyslvs six-bar variant (review 8: P3, P4 moved, the crank L3 shortened), posed at -36.38 deg on its branch
SIX_HOPPED = {
    "P0": [5.8511, -103.2831],
    "P1": [-71.3292, -109.7644],
    "P2": [77.8903, -110.263],
    "P3": [-115.53673850000327, -101.02544384405543],
    "P4": [-214.29633080267575, -82.54211187455198],
    "P5": [-39.26002305950783, -46.978018459488034],
    "P6": [-46.283350409997794, -128.21640169088874],
}


def test_sub_steps_follow_the_inputs_not_the_chord_of_the_held_joints():
    """The six-bar above: its range [-347.746, 7.051] deg ends at folds both ways. The sub-steps from a grid point
    to a sample moved the held joint P6 along the chord between its two places, inside the crank's circle, and near
    the lower end that chord led to another branch: inputs 0.6 to 5 deg above the lower end were assembled with
    joints 2.0 times the size away from the reference continuation, and inputs past both ends were assembled. Now
    the sub-steps re-run the steps before the group at the inputs between (P6 on its circle): every input is as
    the reference continuation has it (flags, and joints to 1e-9 of the size), in a list and alone."""
    from linkagekit.checks import input_range

    doc = copy.deepcopy(SIX)
    doc["joints"] = copy.deepcopy(SIX_HOPPED)
    mech, ref = lk.Mechanism.from_dict(doc), SixbarReference(doc)
    ((lo, hi),) = input_range(mech)
    assert abs(lo - ref.range[0]) <= 1e-6 and abs(hi - ref.range[1]) <= 1e-6, (lo, hi, ref.range)
    u = np.array([lo + 0.6, lo + 1.0, lo + 2.0, lo + 2.6, lo + 5.0, lo - 0.5, lo - 1.5, hi + 1.0, hi + 3.0])
    pts, ok = joints_of(lk.analyze(mech, {"L3": u}, rates=False))
    assert ok.tolist() == [True] * 5 + [False] * 4
    check_against_reference(ref, u, pts, ok)
    for i in range(4):
        alone = joints_of(lk.analyze(mech, {"L3": u[i : i + 1]}, rates=False))
        check_against_reference(ref, u[i : i + 1], *alone)


def test_a_slider_triad_answers_alone_as_in_a_list():
    """``MOVING_SLIDER_TRIAD`` (range [8.246186, 45.303072] deg, pose 45 deg): inputs from 9.02 to 9.52 deg asked
    alone were not assembled while the same inputs in one list were (review 8): alone, the sample's sub-steps went
    from the last grid point along the chord of the crank's joints C and H, inside the crank's circle, where the
    slider's line no longer reaches the triad. Every 0.05 deg from 8.26 to 12 deg: the same flags alone and in one
    list (all assembled), and the same joints to 1e-9 of the size."""
    mech = lk.Mechanism.from_dict(MOVING_SLIDER_TRIAD)
    us = np.arange(8.26, 12.0, 0.05)
    together = lk.analyze(mech, {"crank": us}, rates=False)
    assert together.assembled.all()
    size = scale_of(mech)
    for i, x in enumerate(us):
        alone = lk.analyze(mech, {"crank": [x]}, rates=False)
        assert alone.assembled[0], x
        err = max(abs(alone.point(j)[0] - together.point(j)[i]) for j in ("D", "E", "F"))
        assert err <= 1e-9 * size, (x, err)
