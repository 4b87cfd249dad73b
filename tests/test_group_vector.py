"""The numerical group's small linear systems as array operations (``group._gauss``), against LAPACK.

* ``_gauss`` against ``numpy.linalg.solve`` and ``numpy.linalg.det`` on random systems whose
  pivots force row swaps in some columns and not in others (1e-12 relative), a singular
  matrix (zero determinant, a step that is not finite) and a NaN (NaN);
* a class-3 triad and a batch of triad designs, both past the ends of their ranges, solved
  with every Newton (and the rates) through ``_gauss`` equal the same solves through LAPACK:
  the same samples assembled, positions to 1e-10 of the size, velocities to 1e-8 (the two
  differ by rounding only).
"""

from __future__ import annotations

import numpy as np

import linkagekit as lk
from helpers import points, velocities
from linkagekit import group
from linkagekit.params import compile  # noqa: A004
from linkagekit.plan import make_plan
from test_group import EXAMPLE, random_triad, scale_of, triad


def test_gauss_equals_lapack_with_swaps_singular_and_nan():
    rng = np.random.default_rng(5)
    J = rng.normal(size=(64, 6, 6))
    J[::2, 0, 0] = 1e-3  # half the columns swap at the first pivot, half do not
    J[1::4, 2] *= 1e-6
    res = rng.normal(size=(6, 64))
    dx, det = group._gauss(J, res)
    want = np.linalg.solve(J, -res.T[..., None])[..., 0]
    assert np.max(np.abs(dx - want) / np.max(np.abs(want), axis=1, keepdims=True)) < 1e-12
    assert np.max(np.abs(det / np.linalg.det(J) - 1)) < 1e-12
    bad = rng.normal(size=(2, 6, 6))
    bad[0, 3] = bad[0, 1]  # singular
    bad[1, 2, 4] = np.nan
    dx, det = group._gauss(bad, rng.normal(size=(6, 2)))
    assert det[0] == 0 and not np.all(np.isfinite(dx[0]))
    assert np.isnan(det[1]) and np.all(np.isnan(dx[1]))
    # an exactly zero pivot before the last (a zero column; two proportional rows): 0 as LAPACK's, not NaN
    flat = np.array([[[0.0, 1, 0], [0, 2, 1], [0, 0, 3]], [[1.0, 2, 3], [2, 4, 6], [0, 1, 1]]])
    assert np.array_equal(group._gauss(flat, np.ones((3, 2)))[1], [0.0, 0.0])


def test_a_design_whose_ternary_link_has_zero_length_is_flagged_among_the_others():
    """A batch design whose ternary link's base joints coincide (a row scale ``1 / (2 L)`` infinite, its
    conditioning's matrix NaN) raised ``LinAlgError`` in the rates; it is not assembled, and the other designs
    answer as each alone."""
    mech = random_triad(1)
    names = mech.joint_names
    poses = mech.pose_array()[None] + np.random.default_rng(3).normal(0, 0.3, (4, len(names), 2))
    poses[2, names.index("J2")] = poses[2, names.index("J1")]
    u = {"crank": np.arange(-180.0, 180.0, 5.0)}
    res = lk.analyze(mech, u, poses=poses)
    assert not res.assembled[2].any() and res.assembled[[0, 1, 3]].any()
    for i in (0, 1, 3):
        alone = lk.analyze(mech, u, poses=poses[i : i + 1])
        assert np.array_equal(res.assembled[i], alone.assembled[0])
        ok = alone.assembled[0]
        assert np.max(np.abs(points(res)[:, i][:, ok] - points(alone)[:, 0][:, ok])) <= 1e-10 * scale_of(mech)


def _solve_all(monkeypatch, vector: bool) -> list[lk.Result]:
    """A triad and a batch of perturbed triads, every solve through ``_gauss`` or through LAPACK."""
    big = 1 if vector else 10**9
    monkeypatch.setattr(group, "VECTOR_SAMPLES", big)
    monkeypatch.setattr(group, "VECTOR_DESIGNS", big)
    base = random_triad(1)
    poses = base.pose_array()[None] + np.random.default_rng(3).normal(0, 0.3, (5, len(base.joint_names), 2))
    return [
        lk.analyze(triad(EXAMPLE), {"crank": np.arange(-30.0, 120.0, 1.5)}),
        lk.analyze(base, {"crank": np.arange(-180.0, 180.0, 3.0)}, poses=poses),
    ]


def test_the_vectorized_solves_equal_lapacks(monkeypatch):
    fast = _solve_all(monkeypatch, True)
    slow = _solve_all(monkeypatch, False)
    for a, b, mech in zip(fast, slow, (triad(EXAMPLE), random_triad(1)), strict=True):
        s = scale_of(mech)
        assert 0.05 < a.assembled.mean() < 1.0  # each case reaches a limit of its range
        assert np.array_equal(a.assembled, b.assembled)
        ok = a.assembled
        assert np.max(np.abs(points(a)[:, ok] - points(b)[:, ok])) <= 1e-10 * s
        va, vb = velocities(a), velocities(b)
        fin = np.isfinite(va) & np.isfinite(vb)
        assert np.array_equal(np.isfinite(va), np.isfinite(vb))
        assert np.max(np.abs(va[fin] - vb[fin])) <= 1e-8 * s


#: a six-bar: a four-bar's coupler point P holds a class-3 triad (J1, J2, J3 on links from P, B0 and C0); its range is
#: 2.4 degrees, inside the grid cell after the pose's input, where P moves 1.14 and 0.115 off the cell's chord
COUPLER_TRIAD = {
    "format": "linkagekit/1",
    "units": {"length": "mm", "angle": "deg"},
    "joints": {
        "O": [-0.2913, -0.3408],
        "A": [1.3464, 0.9153],
        "D": [4.1644, -0.2442],
        "B": [-0.0894, 1.8201],
        "P": [0.4858, -2.5396],
        "B0": [-9.0411, 10.3852],
        "C0": [2.8923, -5.6876],
        "J1": [1.9325, 2.443],
        "J2": [-0.6538, 0.4767],
        "J3": [1.0183, -2.3397],
    },
    "links": {
        "ground": ["O", "D", "B0", "C0"],
        "crank": ["O", "A"],
        "coupler": ["A", "B", "P"],
        "rocker": ["D", "B"],
        "l1": ["P", "J1"],
        "l2": ["B0", "J2"],
        "l3": ["C0", "J3"],
        "tern": ["J1", "J2", "J3"],
    },
    "drivers": [{"link": "crank", "pivot": "O", "toward": "A"}],
}


def test_samples_in_the_range_assemble_where_the_walks_chord_left_it():
    """The triad held by a fast coupler point: its range is 36.97-39.38 deg (``input_range``, a continuation to
    1e-9 rad), all inside the cell after the pose's input (37.49 deg). Stepping to the next grid column, the walk's
    sub-steps move P along the cell's chord, which leaves the range at 0.33 of the cell (38.47 deg); every input of
    the range still assembles (its own sub-steps move P along its own chord), at the same positions (1e-12 of the
    size) whether or not an input past the cell makes the walk step into it."""
    from linkagekit.checks import input_range

    mech = lk.Mechanism.from_dict(COUPLER_TRIAD)
    ((lo, hi),) = input_range(mech)
    assert 36.9 < lo < 37.0 and 39.36 < hi < 39.4
    u = np.arange(37.0, 39.36, 0.05)
    alone = lk.analyze(mech, {"crank": u}, rates=False)
    wider = lk.analyze(mech, {"crank": np.append(u, 45.0)}, rates=False)
    assert alone.assembled.all()
    assert wider.assembled[:-1].all() and not wider.assembled[-1]
    assert np.max(np.abs(points(wider)[:, :-1] - points(alone))) <= 1e-12 * scale_of(mech)


def test_a_determinant_kept_across_a_converged_step_has_the_sign_and_nearly_the_size_at_the_solution():
    """``_newton_vector(reuse=True)`` (the samples' Newton) keeps a column's determinant from before its last step
    when the step is too small to move it (``Group._kept_det``: the step's change of the Jacobian is below 1/20 of
    a lower bound of its smallest singular value). On 4000 triad configurations, each started 1e-7 to 1e-4 of the
    size off one of 200 solved states, some within 1e-7 deg of a fold: the same solutions, converged flags and
    determinant signs as without it, and each determinant within (1 +/- 1/20)^6 of LAPACK's at the solution; a
    third of the factorizations skipped (about one a column, of three). The bound itself is below numpy's
    smallest singular value on random matrices, badly conditioned ones included."""
    rng = np.random.default_rng(11)
    J = rng.normal(size=(500, 6, 6)) * np.logspace(-8, 0, 500)[:, None, None] ** rng.uniform(0, 1, (500, 6, 1))
    lb = group._smallest_singular_bound(J, np.linalg.det(J))
    assert np.all(lb <= np.linalg.svd(J, compute_uv=False)[:, -1] * (1 + 1e-12))
    mech = triad(EXAMPLE)
    u = np.linspace(-30.0, 120.0, 2000)
    res = lk.analyze(mech, {"crank": u}, rates=False)
    lo, hi = u[res.assembled][[0, -1]]
    u = np.concatenate([np.linspace(lo, hi, 190), lo + np.geomspace(1e-7, 1e-3, 5), hi - np.geomspace(1e-7, 1e-3, 5)])
    res = lk.analyze(mech, {"crank": u}, rates=False)
    assert res.assembled.all()
    params = compile(mech, None, make_plan(mech))
    gi, st = next((i, s) for i, s in enumerate(params.plan.steps) if isinstance(s, group.Group))
    names = params.plan.joint_names
    z = np.array([[complex(*p) for p in res.xy(names[j])] for j in (*st.joints, *st.known)])
    reps = 20
    U0 = np.tile(z[: len(st.joints)], reps)
    K = np.tile(z[len(st.joints) :], reps)
    U = U0 + rng.normal(size=U0.shape) * np.repeat(np.geomspace(1e-7, 1e-4, reps), len(u)) * scale_of(mech)
    ar = st._arrays(st._design_nums(params.steps[gi], np.zeros(U.shape[1], int)), U.shape[1])
    assert st._reduced is not None  # the triad's further joint substituted: a 4 x 4 system
    factored = []
    spy, spy_elim = group._solve_small, group._eliminate
    group._solve_small = lambda *a, **k: factored.append(0 if a[3] else a[0].shape[0]) or spy(*a, **k)
    group._eliminate = lambda *a, **k: factored.append(a[0].shape[2]) or spy_elim(*a, **k)
    try:
        plain = st._newton_vector(U, K, ar, group.NEWTON_ITER)
        n_plain = sum(factored)
        kept = st._newton_vector(U, K, ar, group.NEWTON_ITER, reuse=True)
        n_kept = sum(factored) - n_plain
    finally:
        group._solve_small, group._eliminate = spy, spy_elim
    assert np.array_equal(plain[0], kept[0], equal_nan=True) and np.array_equal(plain[1], kept[1])
    assert plain[1].mean() > 0.95
    assert np.array_equal(np.sign(plain[2]), np.sign(kept[2]))
    ratio = kept[2][plain[1]] / plain[2][plain[1]]
    assert np.all((ratio >= (1 - 1 / 20) ** 6) & (ratio <= (1 + 1 / 20) ** 6)), (ratio.min(), ratio.max())
    assert n_kept < 0.75 * n_plain, (n_kept, n_plain)


def _reduced_groups():
    """(group, its numbers' arrays for 300 columns, slot positions near its pose's) of every group that substitutes
    its further joints (``Group._reduced``): the triad; four-bars and six-bars forced through Newton (groups whose
    further joint's link starts at a known joint, or at an unknown one)."""
    rng = np.random.default_rng(2)
    cases = [(triad(EXAMPLE), False)]
    names = ("seed000_fourbar", "seed001_stephenson", "jansen_leg")
    cases += [(lk.load(f"examples/{name}.yaml"), True) for name in names]
    out = []
    for mech, forced in cases:
        params = compile(mech, None, make_plan(mech, forced))
        pose = np.array([complex(*p) for p in mech.pose_array()])
        for st, nums in zip(params.plan.steps, params.steps, strict=True):
            if isinstance(st, group.Group) and st._reduced is not None:
                B = 300
                ar = st._arrays(st._design_nums(nums, np.zeros(B, int)), B)
                slots = pose[[*st.joints, *st.known]]
                P = slots[:, None] + rng.normal(0, 0.05, (len(slots), B)) * scale_of(mech) * (1 + 1j)
                out.append((st, ar, P))
    return out


def _schur(J, st):
    """``A - B C`` of ``J`` (B, n, n) from the whole Jacobian, by numpy: the further joints' rows and columns last."""
    rw, red = st._rows, st._reduced
    rows_l = np.concatenate([(r, r + 1) for r in rw.lin])
    cols_k = np.concatenate([(2 * k, 2 * k + 1) for k in red.k])
    cols_c = np.concatenate([(2 * c, 2 * c + 1) for c in red.cols])
    A, Bk = J[:, rw.dist][:, :, cols_c], J[:, rw.dist][:, :, cols_k]
    C, eye = J[:, rows_l][:, :, cols_c], J[:, rows_l][:, :, cols_k]
    assert np.array_equal(eye, np.broadcast_to(np.eye(len(cols_k)), eye.shape))  # the identity the reduction needs
    return A - Bk @ C


def test_the_reduced_system_gives_the_whole_systems_steps_and_determinants():
    """``Group._reduced``: Newton's step and the Jacobian's determinant from the system with the further joints
    substituted (4 x 4 for a triad) equal LAPACK's on the whole one (1e-9 relative; 300 configurations up to 5 % of
    the size off the pose, per group); its weights give the change of ``A - B C`` (computed from the whole Jacobian
    by numpy) along a step exactly (1e-9), and its bound is below that matrix's smallest singular value. The rates'
    reduced solve (``_ReducedRates``) equals LAPACK's for two right-hand sides."""
    groups = _reduced_groups()
    assert len(groups) >= 5
    for st, ar, P in groups:
        m = len(st.joints)
        U, K = P[:m], P[m:]
        res = st._res(P, ar.L, ar.R)
        J = st._jac(P, ar.J_lin, ar.R)
        dx, det, bound = st._reduced_step(P, ar, res, None)
        want = np.linalg.solve(J, -res.T[..., None])[..., 0]
        assert np.max(np.abs(dx - want) / np.max(np.abs(want), axis=1, keepdims=True)) < 1e-9
        assert np.max(np.abs(det / np.linalg.det(J) - 1)) < 1e-9
        smin, W = bound(np.ones(P.shape[1], bool))
        Jr = _schur(J, st)
        assert np.all(smin <= np.linalg.svd(Jr, compute_uv=False)[:, -1] * (1 + 1e-12))
        step = np.random.default_rng(0).normal(0, 1e-3, U.shape) * (1 + 1j)
        P2 = np.concatenate([U + step, K])
        dJ = _schur(st._jac(P2, ar.J_lin, ar.R), st) - Jr
        d = np.concatenate([step, np.zeros_like(K)])
        de = d[st._rows.b] - d[st._rows.a]
        change = np.sum(W * np.abs(de) ** 2, axis=0)
        assert np.allclose(change, np.einsum("bij,bij->b", dJ, dJ), rtol=1e-9, atol=0)
        Ju = J[:, :, : 2 * m]
        rhs1, rhs2 = np.random.default_rng(1).normal(size=(2, P.shape[1], 2 * m))
        system = group._ReducedRates(st, P, ar.R, rhs1)
        for rhs, x in ((rhs1, system.first), (rhs2, system.solve(rhs2))):
            ref = np.linalg.solve(Ju, rhs[..., None])[..., 0]
            assert np.max(np.abs(x - ref) / np.max(np.abs(ref), axis=1, keepdims=True)) < 1e-9
