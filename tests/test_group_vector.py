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


def test_samples_past_the_walks_end_are_what_their_own_sub_steps_give(monkeypatch):
    """A sample more than ``END_MARGIN`` of a cell past where the walk's sub-steps into its cell stopped is flagged
    without sub-steps of its own, and a sub-step's Newton gives up where its residual stops halving: on 40
    perturbed triads sampled every 0.25 deg across both ends of their ranges, the same samples assemble as when
    every sample takes its own sub-steps, each of all its iterations, at the same positions (1e-12 of the size),
    and the rule skips some."""
    base = triad(EXAMPLE)
    poses = base.pose_array()[None] + np.random.default_rng(4).normal(0, 0.5, (40, len(base.joint_names), 2))
    inputs = {"crank": np.arange(-25.0, 100.0, 0.25)}
    skipped = []
    real = group.Group._past_end

    def counting(*args):
        out = real(*args)
        skipped.append(int(out.sum()))
        return out

    monkeypatch.setattr(group.Group, "_past_end", staticmethod(counting))
    fast = lk.analyze(base, inputs, poses=poses, rates=False)
    monkeypatch.setattr(group, "END_MARGIN", np.inf)
    monkeypatch.setattr(group, "GIVE_UP_AFTER", 10**9)
    slow = lk.analyze(base, inputs, poses=poses, rates=False)
    assert sum(skipped[: len(skipped) // 2]) > 50
    assert 0.3 < fast.assembled.mean() < 0.95
    assert np.array_equal(fast.assembled, slow.assembled)
    ok = fast.assembled
    assert np.max(np.abs(points(fast)[:, ok] - points(slow)[:, ok])) <= 1e-12 * scale_of(base)
