"""IFToMM forward-dynamics benchmarks A01, A02 and A03 (issue 25) against independent references.

The mechanism files are ``examples/iftomm_a01_pendulum.yaml``, ``iftomm_a02_double_fourbar.yaml``
and ``iftomm_a03_andrews.yaml``; the references (``tests/iftomm_reference.py``) never call
linkagekit. Two kinds of checks:

* the file is the benchmark: kinetostatics at chosen (q, q', q'') gives the needed driver
  torque tau = M(q) q'' + h(q, q') - Q(q), and M, h and Q are compared with the statement's
  own model (A01: M = m L^2, Q = -m g L cos(theta); A02: M = 3, h = 0, Q = -3.5 g cos(theta)
  on the parallelogram branch; A03: the test set's relative-angle formulation reduced to the
  crank angle beta with dq/dbeta from its constraint Jacobian);
* the simulation is the benchmark's motion: A01 against the exact elliptic-function solution
  over the whole 10 s, A02 against the reduced equation over a window with two flat
  crossings (the full 10 s run is in ``benchmarks/bench_iftomm.py``), A03 against the IVP test
  set's published solution at t = 0.03 s, itself cross-checked here by integrating the test
  set's index-1 DAE.

A03's centres of gravity come from the kinetic energy behind the test set's mass matrix: with
G2 = P + c e(beta + Theta), |v_G2|^2 has the beta'^2 coefficient rr^2 + c^2 + 2 rr c cos(Theta);
the test set's m11 has m2 (rr^2 - 2 da rr cos(Theta) + da^2), so c = -da (G2 at da from P
toward E); likewise G4 at e - ea from F toward E (m55's + 2 zt (e - ea) sin(Phi)) and G6 at
zf - fa from H toward E (m77's - 2 u (zf - fa) sin(Omega)). Bodies 1, 3, 5 and 7 turn about
fixed pivots: only their centre's distance from the pivot enters.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import linkagekit as lk
from iftomm_reference import (
    A02_M,
    A02_V,
    A03,
    A03_Q0,
    A03_Q_END,
    A03_T_END,
    G,
    a01_tip,
    a02_theta,
    a03_angles,
    a03_energy,
    a03_force,
    a03_g,
    a03_gamma,
    a03_integrate,
    a03_jac,
    a03_mass,
    a03_points,
)

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


@pytest.fixture(scope="module")
def a01():
    return lk.load(EXAMPLES / "iftomm_a01_pendulum.yaml")


@pytest.fixture(scope="module")
def a02():
    return lk.load(EXAMPLES / "iftomm_a02_double_fourbar.yaml")


@pytest.fixture(scope="module")
def a03():
    return lk.load(EXAMPLES / "iftomm_a03_andrews.yaml")


def points_along(qs):
    """a03_points of each row of qs, stacked: name -> (n, 2)."""
    each = [a03_points(q) for q in qs]
    return {k: np.array([p[k] for p in each]) for k in each[0]}


def needed_torque(mech, driver, inputs, speed, acceleration, **kw):
    res = lk.analyze(mech, inputs, speed=speed, acceleration=acceleration, **kw)
    return res.forces.driver_torque[driver]


def reduced_terms(mech, driver, inputs, **kw):
    """M, h (at unit speed) and Q of the driver's equation, read off kinetostatics."""
    t0 = needed_torque(mech, driver, inputs, 0.0, 0.0, **kw)
    m = needed_torque(mech, driver, inputs, 0.0, 1.0, **kw) - t0
    h = needed_torque(mech, driver, inputs, 1.0, 0.0, **kw) - t0
    return m, h, -t0


# ------------------------------------------------------------------ the files are the benchmarks


def test_a01_file_is_the_point_mass_pendulum(a01):
    deg = np.arange(0.5, 360.0, 7.0)
    th = np.radians(deg)
    res = lk.analyze(a01, deg)
    np.testing.assert_allclose(res.xy("P"), np.stack([np.cos(th), np.sin(th)], -1), atol=1e-15)
    m, h, q = reduced_terms(a01, "bar", deg)
    np.testing.assert_allclose(m, 1.0, atol=1e-12)  # m L^2 (a point mass, a massless bar)
    np.testing.assert_allclose(h, 0.0, atol=1e-12)
    np.testing.assert_allclose(q, -G * np.cos(th), atol=1e-12)  # moment of m g about O


def test_a02_file_is_the_parallelogram_pair(a02):
    # two turns backwards from the pose (the benchmark's direction), through four flat positions,
    # on the continuous branch: samples avoid the flat positions themselves (rates undefined there)
    deg = 90.0 - np.arange(0.5, 720.0, 7.0)
    th = np.radians(deg)
    res = lk.analyze(a02, deg, branch="continuous")
    for joint, x0 in (("B0", 0.0), ("B1", 1.0), ("B2", 2.0)):
        np.testing.assert_allclose(res.xy(joint), np.stack([x0 + np.cos(th), np.sin(th)], -1), atol=1e-12)
    m, h, q = reduced_terms(a02, "crank0", deg, branch="continuous")
    np.testing.assert_allclose(m, A02_M, atol=1e-9)
    np.testing.assert_allclose(h, 0.0, atol=1e-9)
    np.testing.assert_allclose(q, -A02_V * np.cos(th), atol=1e-9)


def a03_on_constraints(betas):
    """The test set's q solving g(q) = 0 at each beta (Newton, continued from q0), and dq/dbeta."""
    qs, js = [], []
    q = A03_Q0.copy()
    for b in betas:  # a reference, not a hot path: 37 samples
        q = q.copy()
        q[0] = b
        for _ in range(20):
            q[1:] -= np.linalg.solve(a03_jac(q)[:, 1:], a03_g(q))
        jac = a03_jac(q)
        qs.append(q)
        js.append(np.concatenate([[1.0], np.linalg.solve(jac[:, 1:], -jac[:, 0])]))
    return np.array(qs), np.array(js)


def a03_reduced(q, j):
    """The test set's model reduced to beta: M = j^T M j, h = j^T (M j' - f_v) at beta' = 1, Q = j^T f(q, 0)."""
    jac = a03_jac(q)
    jdot = np.concatenate([[0.0], np.linalg.solve(jac[:, 1:], -a03_gamma(q, j))])
    f0 = a03_force(q, np.zeros(7))
    f_velocity = a03_force(q, j) - f0
    return j @ a03_mass(q) @ j, j @ (a03_mass(q) @ jdot - f_velocity), j @ f0


def test_a03_file_is_the_test_set_mechanism(a03):
    np.testing.assert_allclose(a03_g(A03_Q0), 0.0, atol=1e-16)  # the test set's q0 is consistent
    betas = A03_Q0[0] + np.linspace(0.0, 2 * np.pi, 37)[:-1] + 0.01
    qs, js = a03_on_constraints(betas)
    res = lk.analyze(a03, betas)
    pts = points_along(qs)
    for joint in "PEDFH":
        np.testing.assert_allclose(res.xy(joint), pts[joint], atol=1e-15, err_msg=joint)
    for name in ("E_via_B", "E_via_F", "E_via_H"):  # the reference's own closure
        np.testing.assert_allclose(pts[name], pts["E"], atol=1e-15, err_msg=name)
    np.testing.assert_allclose(a03_angles(pts), np.angle(np.exp(1j * qs)), atol=1e-12)
    ref = np.array([a03_reduced(q, j) for q, j in zip(qs, js, strict=True)]).T
    got = reduced_terms(a03, "body1", betas)
    for what, r, g in zip(("M", "h", "Q"), ref, got, strict=True):
        np.testing.assert_allclose(g, r, rtol=1e-9, atol=1e-9 * np.abs(r).max(), err_msg=what)


def test_a03_published_solution_is_the_test_set_dae():
    """The published q(0.03) (PSIDE at 1e-14) against our integration of the index-1 DAE, whose
    energy (kinetic + spring - drive work) must stay constant: a transcription check of M and f."""
    q_end, sol = a03_integrate(rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(q_end, A03_Q_END, rtol=1e-8)
    assert np.abs(a03_g(q_end)).max() < 1e-10  # m: the drift of the index-1 form
    energy = [a03_energy(y[:7], y[7:]) for y in sol.y.T[:: max(1, sol.y.shape[1] // 20)]]
    kinetic = 0.5 * sol.y[7:, -1] @ a03_mass(sol.y[:7, -1]) @ sol.y[7:, -1]
    assert np.ptp(energy) < 1e-8 * kinetic


# ------------------------------------------------------------------ the simulations are the benchmarks


def test_a01_simulation_follows_the_exact_pendulum(a01):
    t = np.linspace(0.0, 10.0, 1001)
    res = lk.simulate(a01, t)
    np.testing.assert_array_equal(res.time, t)
    err = np.abs(res.xy("P") - a01_tip(t)).max()
    assert err < 1e-6, f"A01 tip error {err:.2e} m"


def test_a02_simulation_stays_a_parallelogram_pair_through_flat_positions(a02):
    t = np.linspace(0.0, 1.5, 151)  # through two flat positions (theta = 0 at t = 0.714 s, -pi at 1.228 s)
    theta, _ = a02_theta(t)
    assert np.sum(np.diff(np.sign(np.sin(theta))) != 0) == 2
    res = lk.simulate(a02, t, speed=-1.0)
    tip = np.stack([np.cos(theta), np.sin(theta)], -1)
    err = np.abs(res.xy("B0") - tip).max()
    assert err < 1e-6, f"A02 tip error {err:.2e} m"
    np.testing.assert_allclose(res.vxy("B0")[0], [1.0, 0.0], atol=1e-12)
    for joint, dx in (("B1", 1.0), ("B2", 2.0)):  # still parallelograms after the flat positions
        np.testing.assert_allclose(res.xy(joint), res.xy("B0") + [dx, 0.0], atol=1e-6, err_msg=joint)


def a03_simulated_angles(res):
    """The seven test-set angles along a simulation, followed continuously in time from q0
    (every q0 angle is in (-pi, pi]; samples close enough that no angle moves by pi between them)."""
    pts = {k: res.xy(k) for k in "OABCPEDFH"}
    beta = np.broadcast_to(np.asarray(res.inputs["body1"], float), res.time.shape)  # rad, the file's unit
    return np.unwrap(a03_angles(pts), axis=0), beta


def test_a03_simulation_reaches_the_published_solution(a03):
    t = np.linspace(0.0, A03_T_END, 121)  # 0.25 ms: under half a turn of the crank per step
    res = lk.simulate(a03, t)
    q, beta = a03_simulated_angles(res)
    np.testing.assert_allclose(q[0], A03_Q0, atol=1e-12)
    np.testing.assert_allclose(q[:, 0], beta, atol=1e-9)
    rel = np.abs(q[-1] - A03_Q_END) / np.abs(A03_Q_END)
    assert rel.max() < 1e-6, f"A03 relative errors at 0.03 s: {np.array2string(rel, precision=1)}"


def test_a03_drive_torque_as_the_torque_law(a03):
    """The same motion with the drive as `torque=` instead of the file's load (one A03 window)."""
    doc = a03.to_dict()
    doc.pop("loads")
    bare = lk.Mechanism.from_dict(doc)
    t = np.linspace(0.0, 0.01, 11)
    a = lk.simulate(a03, t)
    b = lk.simulate(bare, t, torque=A03["mom"])
    np.testing.assert_allclose(b.xy("E"), a.xy("E"), atol=1e-9)
    np.testing.assert_allclose(b.inputs["body1"], a.inputs["body1"], rtol=1e-9)
