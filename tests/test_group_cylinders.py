"""Cylinder drivers inside numerical groups (issue 29, item 2).

A cylinder whose ends are joints of a class-3 group (or one end a known joint) adds one
distance row to the group whose length is the driver's input at each sample. Checked
against computations written here, none of which shares code with linkagekit's:

* a triad whose third leg is a cylinder (refused before): its six distance equations solved
  by ``scipy.optimize.least_squares`` continued from the pose in steps of 0.005 m of the
  cylinder (or 0.25 degree of the crank): positions to 1e-9 of the size; the pose at its
  input; results that do not depend on the order of the inputs;
* velocities and accelerations against central differences of the positions in the
  cylinder's length (and in the crank's angle, velocities with both drivers moving);
* the cylinder's force and the crank's torque against virtual work: ``F ds = -(sum of the
  loads' work)``, the loads' displacements by central differences (1e-7 relative);
* samples beyond the stroke are flagged (NaN, not assembled), inside it not; ``check`` names
  the stroke's end as the end of the range; ``modes`` lists the continued mode with a note;
* the excavator examples forced onto numerical groups (their cylinders inside them) equal
  the closed form: positions, velocities, accelerations and the cylinders' forces to 1e-10
  of their size (force: relative), the same flags over sweeps that leave the stroke;
* the actuator written as a barrel, a rod, a slider and a slider driver inside the triad (a
  displacement row in the group) equals the cylinder form: positions and rates to 1e-12 of the
  size, the driver's force to 1e-10 relative, the same flags beyond the stroke; likewise the
  excavator's bucket written so (``excavator_bucket_slider.yaml``) forced onto groups equals
  its closed form.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import least_squares

import linkagekit as lk
from linkagekit.api import pose_inputs
from linkagekit.group import Group
from linkagekit.plan import make_plan

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
TRIAD = {
    "format": "linkagekit/1",
    "units": {"length": "m", "angle": "deg"},
    "joints": {"A": [0, 0], "B": [6, 0], "G": [3, 8], "C": [1, 1], "D": [2, 4], "E": [5, 4], "F": [3.5, 6]},
    "links": {"ground": ["A", "B", "G"], "crank": ["A", "C"], "l1": ["C", "D"], "l2": ["B", "E"]}
    | {"tri": ["D", "E", "F"]},
    "drivers": [
        {"link": "crank", "pivot": "A", "toward": "C"},
        {"cylinder": ["G", "F"], "name": "lift", "stroke": [1.5, 2.5]},
    ],
}
LOADS = [{"link": "tri", "at": "F", "force": [300.0, -500.0]}, {"link": "tri", "torque": 40.0}]
SIZE = 6.0
S0 = float(np.hypot(0.5, 2.0))  # the cylinder's length in the pose


#: the same triad with the cylinder written as an actuator: a barrel pinned at G, a rod pinned at F, a slider
#: along G -> F between them (the line through both pins, so its length is the pose's plus the displacement)
ACTUATOR = TRIAD | {
    "joints": TRIAD["joints"] | {"GH": [3.2, 7.2], "FR": [3.3, 6.8]},
    "links": TRIAD["links"] | {"barrel": ["G", "GH"], "rod": ["F", "FR"]},
    "sliders": [{"link": "rod", "on": "barrel", "through": "F", "direction": [0.5, -2.0]}],
    "drivers": [TRIAD["drivers"][0], {"slider": 0, "stroke": [1.5 - S0, 2.5 - S0]}],
}


def triad(**extra: object) -> lk.Mechanism:
    return lk.Mechanism.from_dict({**TRIAD, **extra})


def reference(crank_deg: np.ndarray, lift: np.ndarray, step: float) -> np.ndarray:
    """D, E, F (3, n) by the triad's own six distance equations, continued from the pose along a straight path
    of both inputs to each sample (steps of at most ``step`` of the moving input, from one sample to the next)."""
    P = {k: complex(*v) for k, v in TRIAD["joints"].items()}
    d = {k: abs(P[a] - P[b]) for k, (a, b) in {"l1": "CD", "l2": "BE", "de": "DE", "df": "DF", "ef": "EF"}.items()}

    def res(x: np.ndarray, c: complex, s: float) -> np.ndarray:
        D, E, F = x[0] + 1j * x[1], x[2] + 1j * x[3], x[4] + 1j * x[5]
        return np.array(
            [
                abs(D - c) - d["l1"],
                abs(E - P["B"]) - d["l2"],
                abs(E - D) - d["de"],
                abs(F - D) - d["df"],
                abs(F - E) - d["ef"],
                abs(F - P["G"]) - s,
            ]
        )

    x = np.array([P["D"].real, P["D"].imag, P["E"].real, P["E"].imag, P["F"].real, P["F"].imag])
    q = np.array([45.0, S0])
    out = np.zeros((3, len(lift)), complex)
    for i, target in enumerate(np.stack([crank_deg, lift], axis=1)):
        n = max(1, int(np.ceil(np.max(np.abs(target - q) / np.array([step * 50, step])))))
        for t in np.linspace(0, 1, n + 1)[1:]:
            a, s = q + t * (target - q)
            c = np.sqrt(2) * np.exp(1j * np.radians(a))
            x = least_squares(res, x, args=(c, s), xtol=1e-15, ftol=1e-15, gtol=1e-15, method="lm").x
        q = target
        out[:, i] = x[0::2] + 1j * x[1::2]
    return out


def solved(res: lk.Result) -> np.ndarray:
    return np.array([res.xy(j) @ [1, 1j] for j in "DEF"])


def test_the_triad_with_a_cylinder_leg_is_one_group_holding_the_cylinder():
    plan = make_plan(triad())
    (group,) = [st for st in plan.steps if isinstance(st, Group)]
    assert len(group.cylinders) == 1 and group.cylinders[0].driver == 1
    assert {plan.joint_names[j] for j in group.joints} == {"D", "E", "F"} and not group.dyad_like


def test_positions_equal_an_independent_continuation_and_the_pose():
    mech = triad()
    lift = np.array([2.05, 2.1, 2.2, 2.3, 2.4, 2.49])  # the pose's mode ends near 2.0298 (a singular position)
    crank = np.full(len(lift), 45.0)
    res = lk.analyze(mech, {"crank": crank, "lift": lift})
    assert res.assembled.all()
    np.testing.assert_allclose(solved(res), reference(crank, lift, 0.005), rtol=0, atol=1e-9 * SIZE)
    # the crank turning with the cylinder held at 2.2 m
    crank2 = np.array([45.0, 55.0, 70.0, 85.0])
    res2 = lk.analyze(mech, {"crank": crank2, "lift": np.full(4, 2.2)})
    ref2 = reference(np.concatenate([[45.0], crank2]), np.concatenate([[2.2], np.full(4, 2.2)]), 0.005)[:, 1:]
    np.testing.assert_allclose(solved(res2), ref2, rtol=0, atol=1e-9 * SIZE)
    # the pose at its input, and the same answers in another order
    at = lk.analyze(mech, {"crank": [45.0], "lift": [S0]})
    pose = np.array([complex(*TRIAD["joints"][j]) for j in "DEF"])
    np.testing.assert_allclose(solved(at)[:, 0], pose, rtol=0, atol=1e-12 * SIZE)
    order = np.array([3, 0, 5, 2, 4, 1])
    back = lk.analyze(mech, {"crank": crank, "lift": lift[order]})
    np.testing.assert_allclose(solved(back), solved(res)[:, order], rtol=0, atol=1e-12 * SIZE)


def test_rates_equal_central_differences():
    mech = triad()
    s, h, h2 = 2.25, 1e-6, 1e-4
    lift = np.array([s - h2, s - h, s, s + h, s + h2])
    res = lk.analyze(
        mech,
        {"crank": np.full(5, 45.0), "lift": lift},
        speed={"crank": 0.0, "lift": 0.3},
        acceleration={"crank": 0.0, "lift": 0.2},
    )
    z = solved(res)
    dz = (z[:, 3] - z[:, 1]) / (2 * h)
    d2z = (z[:, 4] - 2 * z[:, 2] + z[:, 0]) / h2**2
    d = res.to_dict()["joints"]
    v = np.array([d[j]["vx"][2] + 1j * d[j]["vy"][2] for j in "DEF"])
    a = np.array([d[j]["ax"][2] + 1j * d[j]["ay"][2] for j in "DEF"])
    np.testing.assert_allclose(v, 0.3 * dz, rtol=0, atol=1e-7 * np.max(np.abs(dz)))
    np.testing.assert_allclose(a, 0.2 * dz + 0.09 * d2z, rtol=0, atol=1e-5 * np.max(np.abs(d2z)))
    # both drivers moving: the velocity is the sum of each input's
    th = np.radians(1e-6)
    both = lk.analyze(
        mech,
        {"crank": [45.0 - 1e-6, 45.0, 45.0 + 1e-6], "lift": [s, s, s]},
        speed={"crank": 2.0, "lift": -0.4},
    )
    dth = (solved(both)[:, 2] - solved(both)[:, 0]) / (2 * th)
    vb = np.array([both.to_dict()["joints"][j]["vx"][1] + 1j * both.to_dict()["joints"][j]["vy"][1] for j in "DEF"])
    np.testing.assert_allclose(vb, 2.0 * dth - 0.4 * dz, rtol=0, atol=1e-6 * np.max(np.abs(dth)))


def test_the_cylinder_force_and_the_crank_torque_equal_virtual_work():
    mech = triad(loads=LOADS)
    s, h = 2.3, 1e-6
    res = lk.analyze(mech, {"crank": [45.0, 45.0, 45.0], "lift": [s - h, s, s + h]})
    zF, ang = res.xy("F") @ [1, 1j], np.radians(res.to_dict()["links"]["tri"]["angle"])
    work = LOADS[0]["force"][0] * (zF[2] - zF[0]).real + LOADS[0]["force"][1] * (zF[2] - zF[0]).imag
    work += LOADS[1]["torque"] * (ang[2] - ang[0])
    force = res.to_dict()["driver_force"]["lift"][1]
    assert force == pytest.approx(-work / (2 * h), rel=1e-7)
    th = np.radians(1e-5)
    res = lk.analyze(mech, {"crank": [45.0 - 1e-5, 45.0, 45.0 + 1e-5], "lift": [s, s, s]})
    zF, ang = res.xy("F") @ [1, 1j], np.radians(res.to_dict()["links"]["tri"]["angle"])
    work = LOADS[0]["force"][0] * (zF[2] - zF[0]).real + LOADS[0]["force"][1] * (zF[2] - zF[0]).imag
    work += LOADS[1]["torque"] * (ang[2] - ang[0])
    assert res.to_dict()["driver_torque"]["crank"][1] == pytest.approx(-work / (2 * th), rel=1e-7)


def test_beyond_the_stroke_is_flagged_and_check_and_modes_say_so():
    mech = triad()
    lift = np.array([1.4, 2.1, 2.5, 2.5 + 1e-6, 2.51, 2.6, 2.2])
    res = lk.analyze(mech, {"crank": np.full(len(lift), 45.0), "lift": lift})
    assert res.assembled.tolist() == [False, True, True, False, False, False, True]
    assert np.isnan(res.xy("F")[[0, 3, 4, 5]]).all() and np.isfinite(res.xy("F")[[1, 2, 6]]).all()
    rep = lk.check(mech).to_dict()
    (lo, hi), *_ = rep["input_ranges"]["lift"] if "input_ranges" in rep else [rep["input_range"]["lift"]]
    assert hi == pytest.approx(2.5, abs=1e-9) and 2.0 < lo < 2.05
    assert "cylinder 'lift' at the end of its stroke (longest)" in lk.checks.check_text(rep)
    modes = lk.modes(mech, {"crank": 45.0, "lift": 2.2})
    assert len(modes.modes) == 1 and any("holds driver lift" in n for n in modes.notes)


def test_the_actuator_written_as_a_slider_inside_the_group_equals_the_cylinder():
    act, cyl = lk.Mechanism.from_dict(ACTUATOR | {"loads": LOADS}), triad(loads=LOADS)
    (group,) = [st for st in make_plan(act).steps if isinstance(st, Group)]
    assert len(group.drives) == 1 and not group.cylinders
    u = np.array([-0.6, -0.02, 0.0, 0.1, 0.3, 2.5 - S0, 2.5 - S0 + 1e-6, 0.5])
    crank = np.full(len(u), 45.0)
    ra = lk.analyze(act, {"crank": crank, "rod": u}, speed={"crank": 0.3, "rod": 0.2}, acceleration={"rod": -0.3})
    rc = lk.analyze(
        cyl, {"crank": crank, "lift": S0 + u}, speed={"crank": 0.3, "lift": 0.2}, acceleration={"lift": -0.3}
    )
    assert ra.assembled.tolist() == rc.assembled.tolist() == [False, True, True, True, True, True, False, False]
    da, dc = ra.to_dict(), rc.to_dict()
    for j in "DEF":
        for key in ("x", "y", "vx", "vy", "ax", "ay"):
            np.testing.assert_allclose(
                np.array(da["joints"][j][key], float), np.array(dc["joints"][j][key], float), rtol=0, atol=1e-12 * SIZE
            )
    fa, fc = (np.array(x, float) for x in (da["driver_force"]["rod"], dc["driver_force"]["lift"]))
    np.testing.assert_allclose(fa, fc, rtol=1e-10, atol=0)


@pytest.mark.parametrize("name", ["excavator_bucket", "excavator_boom", "excavator_bucket_slider"])
def test_cylinders_in_groups_equal_the_closed_form(name):
    mech = lk.load(EXAMPLES / f"{name}.yaml")
    groups = [st for st in make_plan(mech, True).steps if isinstance(st, Group)]
    assert sum(len(g.input_drivers) for g in groups) == len(mech.drivers)
    p0 = pose_inputs(mech)
    x = np.linspace(-0.6, 0.6, 25)
    inputs = {d.name: p0[d.name] + (x if i == 0 else -0.5 * x) for i, d in enumerate(mech.drivers)}
    a = lk.analyze(mech, inputs).to_dict()
    b = lk.analyze(mech, inputs, method="numerical").to_dict()
    assert a["assembled"] == b["assembled"] and 3 < sum(a["assembled"]) < len(x)  # the sweep leaves the stroke
    size = max(abs(complex(*p)) for p in (mech.joints[j] for j in mech.joint_names) for p in [(p.real, p.imag)])
    for j in mech.joint_names:
        for key in ("x", "y", "vx", "vy", "ax", "ay"):
            va, vb = (np.array(r["joints"][j][key], float) for r in (a, b))
            np.testing.assert_allclose(vb, va, rtol=0, atol=1e-10 * size * (1 + np.nanmax(np.abs(va))), err_msg=key)
    for d in mech.drivers:
        fa, fb = (np.array(r["driver_force"][d.name], float) for r in (a, b))
        np.testing.assert_allclose(fb, fa, rtol=1e-10, atol=1e-10 * np.nanmax(np.abs(fa)))


def test_check_of_a_group_holding_a_cylinder_warns_nothing():
    """``lk.check`` of a triad whose third leg is a cylinder driver leaked numpy's "invalid value encountered in
    subtract" from the refinement of its range's ends (a bracket's secant where it has none; review 14b). The same
    report, with every warning an error: its range within the stroke."""
    import warnings

    doc = {
        "format": "linkagekit/1",
        "units": {"length": "mm", "angle": "deg"},
        "joints": {"A0": [0, 1], "B0": [8, 0], "C0": [4, -5], "J1": [2, 6], "J2": [7, 5], "J3": [5, 2]},
        "links": {"ground": ["A0", "B0", "C0"], "l1": ["A0", "J1"], "l2": ["B0", "J2"], "tern": ["J1", "J2", "J3"]},
        "drivers": [{"cylinder": ["C0", "J3"], "name": "cyl", "stroke": [5.5, 8.5], "speed": 1}],
    }
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        rep = lk.check(lk.Mechanism.from_dict(doc))
    ((a, b),) = rep.input_range
    assert 5.5 <= a < b <= 8.5
