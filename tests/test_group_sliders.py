"""Sliders inside numerical groups (issue 29, item 2).

Checked against computations written here, none of which shares code with linkagekit's:

* a triad whose third leg is a block sliding on a ground line (a class-3 group with a slider,
  refused before): its own loop equations in other unknowns (the first joint's angle on its
  circle and the ternary's rotation; three equations) continued by ``scipy.optimize.root`` in
  steps of 0.25 degree from the pose: positions to 1e-7 of the size; link lengths, the line
  and the ternary's shape to 1e-10; the pose at its input; results that do not depend on the
  order of the inputs; velocities and accelerations against central differences of the
  positions;
* the Jacobian of the group's equations (points on lines, rotation locks) against central
  differences of its residuals, at random points (not only at solutions), for a group on a
  ground line and for a group whose line is carried by a moving link with a locked block;
* a slider-crank and an inverted slider-crank (a guide of two joints, a block of two) forced
  onto the numerical group equal the closed form in each of their two modes, positions to
  1e-10 of the size, velocities and accelerations (the comparison of tests/test_group.py);
* a triad with a slider leg built to have four real modes at one input: ``lk.modes`` lists
  all four, equal to a dense search (a 90 x 90 grid of Newton starts over the two angles
  above, deduplicated) to 1e-9 of the size, and two at another input; likewise with the
  slider's line carried by the (moving) crank instead of the ground;
* samples within 1e-4 degree of both ends of the range (singular positions where two modes
  meet) stay on the pose's branch (the scipy continuation in 0.02-degree steps, 1e-7);
* designs over the design axis equal their single solves (1e-10); the crank's torque from
  the kinetostatics equals the power balance of the links' motion (1e-9 relative).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import root

import linkagekit as lk
from linkagekit.group import Group
from linkagekit.params import compile
from linkagekit.plan import make_plan
from test_group import compare_numerical

TRIAD = {
    "format": "linkagekit/1",
    "joints": {"A": [0, 0], "B": [6, 0], "C": [1, 1], "D": [2, 4], "E": [5, 4], "F": [3.5, 6]},
    "links": {"ground": ["A", "B"], "crank": ["A", "C"], "l1": ["C", "D"], "l2": ["B", "E"], "block": ["F"]}
    | {"tri": ["D", "E", "F"]},
    "sliders": [{"link": "block", "on": "ground", "through": "F", "direction": [1, 0]}],
    "drivers": [{"link": "crank", "pivot": "A", "toward": "C"}],
}
#: a triad with a slider leg that has four real modes at 60 degrees (found by the dense search below)
FOUR = {"D": [3.118, 6.653], "E": [-0.558, 6.641], "F": [1.118, 2.963]}


def mech_of(doc: dict, **joints: list[float]) -> lk.Mechanism:
    return lk.Mechanism.from_dict({**doc, "joints": {**doc["joints"], **joints}})


def joints_of(mech: lk.Mechanism) -> dict[str, complex]:
    return {n: complex(mech.joints[n]) for n in mech.joint_names}


def loop(
    p: dict[str, complex], theta: float, x: np.ndarray, moving: bool = False
) -> tuple[np.ndarray, complex, complex, complex]:
    """The triad's own loop equations in (alpha, phi): D on l1's circle about C, the ternary turned by phi,
    F on the horizontal line through its pose (``moving``: that line turned with the crank about A = 0)."""
    C = p["A"] + abs(p["C"] - p["A"]) * np.exp(1j * theta)
    D = C + abs(p["D"] - p["C"]) * np.exp(1j * x[0])
    r = np.exp(1j * x[1])
    E, F = D + r * (p["E"] - p["D"]), D + r * (p["F"] - p["D"])
    turn = (C - p["A"]) / (p["C"] - p["A"]) if moving else 1.0
    return np.array([abs(E - p["B"]) - abs(p["E"] - p["B"]), ((F - turn * p["F"]) * np.conj(turn)).imag]), D, E, F


def continuation(mech: lk.Mechanism, thetas_deg: np.ndarray, step: float = 0.25, moving: bool = False) -> np.ndarray:
    """D, E, F at each input, continued from the pose in small steps with scipy (NaN past where it fails).

    The targets are walked in order away from the pose's input, each half from the pose.
    """
    p = joints_of(mech)
    t0 = float(np.degrees(np.angle(p["C"] - p["A"])))
    out = np.full((3, len(thetas_deg)), np.nan + 0j)
    for side in (1, -1):
        x, t = np.array([np.angle(p["D"] - p["C"]), 0.0]), t0
        for i in sorted(np.flatnonzero(side * (thetas_deg - t0) >= 0), key=lambda i: side * thetas_deg[i]):
            for tt in np.linspace(t, thetas_deg[i], max(2, int(abs(thetas_deg[i] - t) / step) + 2)):
                sol = root(lambda y, tt=tt: loop(p, np.radians(tt), y, moving)[0], x, tol=1e-14)
                if np.max(np.abs(loop(p, np.radians(tt), sol.x, moving)[0])) > 1e-11 or np.max(np.abs(sol.x - x)) > 0.2:
                    return out
                x = sol.x
            t = thetas_deg[i]
            out[:, i] = loop(p, np.radians(t), x, moving)[1:]
    return out


def test_triad_with_a_slider_leg_against_its_own_loop_equations():
    mech = lk.Mechanism.from_dict(TRIAD)
    plan = make_plan(mech)
    assert [type(s).__name__ for s in plan.steps if isinstance(s, Group)] == ["Group"]
    q = np.array([45.0, 50.0, 60.0, 70.0, 80.0, 89.0, 46.0, 30.0, 120.0])
    res = lk.analyze(mech, {"crank": q})
    assert res.assembled.tolist() == [True] * 7 + [False, False]  # check: assembles for [44.644, 90.135]
    z = {j: res.xy(j)[:, 0] + 1j * res.xy(j)[:, 1] for j in mech.joint_names}
    p = joints_of(mech)
    ok = res.assembled
    for a, b in (("C", "D"), ("B", "E"), ("D", "E"), ("E", "F"), ("D", "F")):
        assert np.max(np.abs(np.abs(z[a] - z[b])[ok] - abs(p[a] - p[b]))) <= 1e-10
    assert np.max(np.abs(z["F"].imag[ok] - 6.0)) <= 1e-10  # on its line
    assert abs(z["F"][0] - p["F"]) <= 1e-12 and abs(z["E"][0] - p["E"]) <= 1e-12  # the pose at its input
    ref = continuation(mech, q[ok])
    got = np.array([z["D"][ok], z["E"][ok], z["F"][ok]])
    assert np.max(np.abs(got - ref)) <= 1e-7 * 6
    shuffled = lk.analyze(mech, {"crank": q[::-1]})
    assert np.array_equal(shuffled.assembled, res.assembled[::-1])
    assert np.nanmax(np.abs(shuffled.xy("F")[::-1] - res.xy("F"))) <= 1e-12


def test_triad_with_a_slider_leg_rates_against_finite_differences():
    mech = lk.Mechanism.from_dict(TRIAD)
    # h: 1e-3 deg for velocities, 0.03 deg for accelerations (Newton's 1e-12 noise over h^2 stays below 1e-6)
    q, h, h2 = np.array([55.0, 70.0, 85.0]), 1e-3, 0.03
    w, al = 1.3, 0.7
    res = lk.analyze(mech, {"crank": q}, speed=w, acceleration=al)
    d = res.to_dict()["joints"]
    for j in "DEF":
        x = lambda qq, j=j: lk.analyze(mech, {"crank": qq}, rates=False).xy(j)  # noqa: E731
        xp, x0, xm = x(q + h), x(q), x(q - h)
        dq, dq2 = np.radians(h), np.radians(h2)
        v_fd = (xp - xm) / (2 * dq) * w  # d/dt = w d/dq
        a_fd = (x(q + h2) - 2 * x0 + x(q - h2)) / dq2**2 * w**2 + (xp - xm) / (2 * dq) * al
        v = np.array([d[j]["vx"], d[j]["vy"]]).T
        a = np.array([d[j]["ax"], d[j]["ay"]]).T
        assert np.max(np.abs(v - v_fd)) <= 1e-6 * max(1.0, np.max(np.abs(v)))
        assert np.max(np.abs(a - a_fd)) <= 1e-4 * max(1.0, np.max(np.abs(a)))


INVERTED = {
    "format": "linkagekit/1",
    "joints": {"O": [0, 0], "C": [0.1, 0.0], "A": [0.03, 0.04], "D": [-0.05, 0.1], "Q": [0.02, 0.06]},
    "links": {"ground": ["O", "C"], "crank": ["O", "A"], "guide": ["C", "D"], "block": ["A", "Q"]},
    "sliders": [{"link": "block", "on": "guide", "through": "A", "direction": [-0.08, 0.06]}],
    "drivers": [{"link": "crank", "pivot": "O", "toward": "A"}],
}
SLIDER_CRANK = {
    "format": "linkagekit/1",
    "joints": {"O": [0, 0], "A": [0.03, 0.04], "B": [0.115, 0.0], "P": [0.15, 0.02]},
    "links": {"ground": ["O"], "crank": ["O", "A"], "rod": ["A", "B"], "block": ["B", "P"]},
    "sliders": [{"link": "block", "on": "ground", "through": "B", "direction": [1, 0.2]}],
    "drivers": [{"link": "crank", "pivot": "O", "toward": "A"}],
}


@pytest.mark.parametrize(("doc", "locks"), [(TRIAD, 0), (INVERTED, 1), (SLIDER_CRANK, 1)])
def test_group_jacobian_against_finite_differences(doc, locks):
    mech = lk.Mechanism.from_dict(doc)
    params = compile(mech, None, make_plan(mech, True))
    (gi, st), *_ = [(i, s) for i, s in enumerate(params.plan.steps) if isinstance(s, Group)]
    assert st.sliders and sum(gs.lock is not None for gs in st.sliders) == locks
    n = len(st.joints) + len(st.known)
    dn = st._design_nums(params.steps[gi], np.zeros(4, int))
    rng = np.random.default_rng(3)
    P = rng.normal(size=(n, 4)) + 1j * rng.normal(size=(n, 4))
    J = st.jacobian(P, dn, n)
    h = 1e-6
    for s in range(n):
        for part, dz in ((0, h), (1, 1j * h)):
            Pp, Pm = P.copy(), P.copy()
            Pp[s] += dz
            Pm[s] -= dz
            fd = (st.residual(Pp, dn)[0] - st.residual(Pm, dn)[0]) / (2 * h)
            assert np.max(np.abs(J[:, :, 2 * s + part] - fd)) <= 1e-7


@pytest.mark.parametrize("doc", [SLIDER_CRANK, INVERTED])
def test_forced_numerical_slider_linkages_equal_the_closed_form_in_every_mode(doc):
    mech = lk.Mechanism.from_dict(doc)
    assert make_plan(mech, True).numerical and not make_plan(mech).numerical
    assert compare_numerical(mech, doc["links"]["block"][0]) == 2


def dense_modes(p: dict[str, complex], theta: float, moving: bool = False) -> list[np.ndarray]:
    """Every (D, E, F) of the slider triad at one input: Newton on the loop equations from a 90 x 90 grid."""
    a, b = np.meshgrid(*(np.linspace(0, 2 * np.pi, 90, endpoint=False),) * 2)
    x = np.stack([a.ravel(), b.ravel()])
    h = 1e-7
    with np.errstate(all="ignore"):
        for _ in range(40):
            f = loop(p, theta, x, moving)[0]
            J = np.array([(loop(p, theta, x + h * e[:, None], moving)[0] - f) / h for e in np.eye(2)])  # (var, eq, n)
            det = J[0, 0] * J[1, 1] - J[1, 0] * J[0, 1]
            x = x - np.stack([J[1, 1] * f[0] - J[1, 0] * f[1], -J[0, 1] * f[0] + J[0, 0] * f[1]]) / det
        f, D, E, F = loop(p, theta, x, moving)
    ok = np.all(np.abs(f) < 1e-10, axis=0)
    out: list[np.ndarray] = []
    for zz in np.array([D, E, F]).T[ok]:
        if all(np.max(np.abs(zz - o)) > 1e-6 for o in out):
            out.append(zz)
    return out


#: the slider triad with its line carried by the crank (a link placed before the group) instead of the ground
MOVING = TRIAD | {
    "joints": {**TRIAD["joints"], "H": [1.5, 3.0]},
    "links": {**TRIAD["links"], "crank": ["A", "C", "H"]},
    "sliders": [{"link": "block", "on": "crank", "through": "F", "direction": [1, 0]}],
}


@pytest.mark.parametrize(("doc", "counts"), [(TRIAD, ((60.0, 4), (150.0, 2))), (MOVING, ((60.0, 4), (240.0, 2)))])
def test_slider_triad_modes_are_all_listed(doc, counts):
    mech = mech_of(doc, **FOUR)
    p = joints_of(mech)
    for at, n in counts:
        ref = dense_modes(p, np.radians(at), doc is MOVING)
        got = lk.modes(mech, at=at)
        assert len(ref) == n and got.distinct == n
        found = [np.array([complex(*mo.joints[j]) for j in "DEF"]) for mo in got.modes if mo.assembled]
        for r in ref:
            assert min(np.max(np.abs(f - r)) for f in found) <= 1e-9 * 8


def test_no_branch_jump_near_a_singular_position_of_a_slider_group():
    """Samples within 0.01 degree of both ends of the slider triad's range (where the pose's mode
    turns back into the other one) stay on the pose's branch: the fine continuation's, never the
    other mode that meets it there; beyond the ends they are not assembled."""
    mech = lk.Mechanism.from_dict(TRIAD)
    lo, hi = 44.6445, 90.135  # within 1e-4 degree of the ends `check` reports (44.644445, 90.135105)
    inputs = np.array([hi, 60.0, lo, lo - 0.01, hi + 0.01, hi - 0.3, lo + 0.3, 50.0])
    res = lk.analyze(mech, {"crank": inputs})
    assert res.assembled.tolist() == [True, True, True, False, False, True, True, True]
    assert np.all(np.isnan(continuation(mech, np.array([lo - 0.01, hi + 0.01]), step=0.02)))  # beyond the ends
    ok = res.assembled
    ref = continuation(mech, inputs[ok], step=0.02)
    got = np.array([res.xy(j)[ok, 0] + 1j * res.xy(j)[ok, 1] for j in "DEF"])
    assert np.all(np.isfinite(ref)) and np.max(np.abs(got - ref)) <= 1e-7 * 6
    near = np.flatnonzero(np.isin(inputs, [lo, hi]))
    assert np.all(res.condition[near] < 0.05 * np.nanmax(res.condition))


def test_slider_triads_over_the_design_axis_equal_single_solves():
    """Three slider-triad designs in one call (poses=...) give each design's own single solve (1e-10)."""
    base = lk.Mechanism.from_dict(TRIAD)
    rng = np.random.default_rng(5)
    poses = base.pose_array()[None] + rng.normal(0, 0.3, (3, len(base.joint_names), 2))
    inputs = {"crank": np.arange(30.0, 100.0, 5.0)}
    batch = lk.analyze(base, inputs, poses=poses)
    for d in range(3):
        one = lk.analyze(base.with_pose(poses[d]), inputs)
        assert np.array_equal(batch.assembled[d], one.assembled), d
        ok = one.assembled
        assert ok.sum() >= 5
        for j in base.joint_names:
            assert np.max(np.abs(batch.xy(j)[d][ok] - one.xy(j)[ok])) <= 1e-10 * 6, (d, j)
            assert np.max(np.abs(batch.velocity(j)[d][ok] - one.velocity(j)[ok])) <= 1e-8 * 6, (d, j)


def test_driver_torque_of_a_slider_group_by_power_balance():
    """Kinetostatics through a slider group: the crank's torque times its speed equals the rate of
    change of kinetic and potential energy, sum m a.v + I alpha omega - m g.v over the links
    (velocities from the results, cgs carried rigidly), to 1e-9 relative."""
    doc = {**TRIAD, "gravity": [0, -9.81]}
    mass = {"crank": (1.0, 0.5 + 0.5j, 0.1), "l1": (1.0, 1.5 + 2.5j, 0.1), "l2": (1.0, 5.5 + 2j, 0.1)}
    mass |= {"block": (2.0, 3.5 + 6j, 0.1), "tri": (3.0, 3.5 + 4.6j, 0.5)}
    doc["links"] = {n: js if n not in mass else {"joints": js, "mass": mass[n][0], "cg": [mass[n][1].real,
                    mass[n][1].imag], "inertia": mass[n][2]} for n, js in TRIAD["links"].items()}  # fmt: skip
    mech = lk.Mechanism.from_dict(doc)
    w, al = 2.0, 0.5
    res = lk.analyze(mech, {"crank": [50.0, 60.0, 70.0]}, speed=w, acceleration=al)
    d = res.to_dict()
    p = joints_of(mech)
    z = {j: np.array(d["joints"][j]["x"]) + 1j * np.array(d["joints"][j]["y"]) for j in p}
    v = {j: np.array(d["joints"][j]["vx"]) + 1j * np.array(d["joints"][j]["vy"]) for j in p}
    a = {j: np.array(d["joints"][j]["ax"]) + 1j * np.array(d["joints"][j]["ay"]) for j in p}
    power = np.zeros(3)
    for name, (m, cg, inertia) in mass.items():
        j0 = TRIAD["links"][name][0]
        om, alpha = (np.array(d["links"][name][k]) for k in ("omega", "alpha")) if name != "block" else (0.0, 0.0)
        turn = (z["E"] - z["D"]) / (p["E"] - p["D"]) if name == "tri" else None
        if name in ("crank", "l1", "l2"):
            j1 = TRIAD["links"][name][1]
            turn = (z[j1] - z[j0]) / (p[j1] - p[j0])
        r = (cg - p[j0]) * (turn if turn is not None else 1.0)
        vc = v[j0] + 1j * om * r
        ac = a[j0] + (1j * alpha - om**2) * r
        power += m * (ac * np.conj(vc)).real + inertia * alpha * om - m * (-9.81j * np.conj(vc)).real
    torque = np.array(d["driver_torque"]["crank"])
    assert np.max(np.abs(torque * w - power)) <= 1e-9 * np.max(np.abs(power))


def test_slider_line_carried_by_a_moving_link():
    """The slider triad's line carried by the crank: the sweep equals the scipy continuation (1e-7 of the
    size), keeps every link and the line (1e-10), and gives the pose back at its input."""
    mech = lk.Mechanism.from_dict(MOVING)
    q = np.array([45.0, 30.0, 0.0, -30.0, -60.0])
    res = lk.analyze(mech, {"crank": q})
    ok = res.assembled
    assert ok.sum() >= 3 and ok[0]
    got = np.array([res.xy(j)[ok, 0] + 1j * res.xy(j)[ok, 1] for j in "DEF"])
    ref = continuation(mech, q[ok], moving=True)
    assert np.all(np.isfinite(ref)) and np.max(np.abs(got - ref)) <= 1e-7 * 6
    p = joints_of(mech)
    z = {j: res.xy(j)[ok, 0] + 1j * res.xy(j)[ok, 1] for j in "ACDEF"}
    turn = (z["C"] - z["A"]) / (p["C"] - p["A"])
    assert np.max(np.abs(((z["F"] - turn * p["F"]) * np.conj(turn)).imag)) <= 1e-10
    for a, b in (("C", "D"), ("D", "E"), ("E", "F"), ("D", "F")):
        assert np.max(np.abs(np.abs(z[a] - z[b]) - abs(p[a] - p[b]))) <= 1e-10
    assert np.max(np.abs(got[:, 0] - np.array([p["D"], p["E"], p["F"]]))) <= 1e-12


def test_check_lists_the_limit_positions_of_a_block_a_triad_moves():
    """A triad whose third leg is a block on a ground line: ``check`` listed no limit position (review 14b). The
    conditioning rows of a numerical group were stacked after the sign steps' and shifted every row after them: the
    block's velocity row read the group's conditioning, which never changes sign. Now the block's maximum is listed
    where an independent sweep of its position along the line (analyze, 0.0005 deg apart) has it: 65.3366 deg
    (1e-3 deg), 0.73262 from the pose's position (1e-6)."""
    doc = {
        "format": "linkagekit/1",
        "units": {"length": "mm", "angle": "deg"},
        "joints": {"O": [0, 0], "A": [3**0.5, 1.0], "B0": [8, 0], "J1": [2, 6], "J2": [7, 5], "J3": [5, 2]},
        "links": {
            "ground": ["O", "B0"],
            "crank": ["O", "A"],
            "l1": ["A", "J1"],
            "l2": ["B0", "J2"],
            "tern": ["J1", "J2", "J3"],
            "block": ["J3"],
        },
        "sliders": [{"link": "block", "on": "ground", "through": "J3", "direction": [1, 0.3]}],
        "drivers": [{"link": "crank", "pivot": "O", "toward": "A"}],
    }
    mech = lk.Mechanism.from_dict(doc)
    (limits,) = [s["limit_positions"] for s in lk.check(mech).to_dict()["sliders"]]
    u = np.linspace(60.0, 70.0, 20001)
    d = np.array([1, 0.3]) / np.hypot(1, 0.3)
    along = lk.analyze(mech, {"crank": u}, rates=False).xy("J3") @ d - np.array([5, 2]) @ d
    i = int(np.argmax(along))
    assert [lp["extreme"] for lp in limits] == ["max"]
    assert abs(limits[0]["input"] - u[i]) < 1e-3 and abs(limits[0]["position"] - along[i]) < 1e-6
