"""Springs, dampers and flywheels (spec section 7): the file format and the kinetostatics.

Every force is checked against an independent computation written here:

* statics of a spring-loaded four-bar and slider-crank against virtual work: the torque
  (or force) that holds the mechanism is ``dV/dq`` of the springs' energy, by central finite
  differences of ``1/2 k (L - L0)^2`` with ``L`` from the solved positions;
* a damper's tension against ``c dL/dt`` with ``dL/dt`` by finite differences of the length,
  and the driver torque it needs, ``c (dL/dtheta)^2 w`` (virtual power);
* a flywheel: at a constant angular acceleration the driver needs ``I alpha`` more on the
  driven link, ``I alpha_r w_r / w`` more for a flywheel on the rocker (virtual power).
"""

from __future__ import annotations

import numpy as np
import pytest

import linkagekit as lk
from linkagekit.cli import main
from linkagekit.errors import MechanismFileError
from linkagekit.web.editor import Session

FOURBAR = {
    "name": "spring-loaded four-bar",
    "units": {"length": "cm", "angle": "deg"},
    "joints": {"A": [0, 0], "B": [4, 1], "C": [2, 0], "D": [0.820550528229663, 4.85889894354067]},
    "links": {"ground": ["A", "B"], "crank": ["A", "C"], "coupler": ["C", "D"], "rocker": ["B", "D"]},
    "drivers": [{"link": "crank", "pivot": "A", "toward": "C"}],
}
#: A on the ground, D on the coupler (its carrier), C on the crank and B on the ground
SPRINGS = [
    {"between": ["A", "D"], "stiffness": 4530.0, "free_length": 4.0},
    {"between": ["C", "B"], "stiffness": 800.0, "free_length": 3.0},
]
CM = 0.01
ANGLES = np.array([10.0, 75.0, 140.0, 215.0, 300.0])


def mech_with(**extra):
    return lk.Mechanism.from_dict({**FOURBAR, **extra})


def energy(res, springs, scale):
    """The springs' energy ``sum 1/2 k (L - L0)^2`` (J) from the solved joint positions."""
    v = np.zeros(res.shape)
    for s in springs:
        a, b = s["between"]
        length = np.abs(res.point(a) - res.point(b)) * scale
        v += 0.5 * s["stiffness"] * (length - s.get("free_length", 0.0) * scale) ** 2
    return v


def test_spring_statics_of_a_four_bar_is_the_derivative_of_its_energy():
    mech = mech_with(springs=SPRINGS)
    res = lk.analyze(mech, ANGLES, static=True)
    h = 1e-3  # deg
    v_plus = energy(lk.analyze(mech, ANGLES + h, rates=False), SPRINGS, CM)
    v_minus = energy(lk.analyze(mech, ANGLES - h, rates=False), SPRINGS, CM)
    dv = (v_plus - v_minus) / (2 * np.radians(h))  # J/rad, truncation ~ h^2 V''' ~ 1e-10 relative
    torque = res.forces.driver_torque["crank"]
    assert np.max(np.abs(dv)) > 1, "a test that can fail: the springs load the crank"
    np.testing.assert_allclose(torque, dv, rtol=1e-7, atol=1e-9 * np.max(np.abs(dv)))
    # the tensions and lengths the result reports: k (L - L0), L in the file's unit
    for s in SPRINGS:
        a, b = s["between"]
        length = np.abs(res.point(a) - res.point(b))
        name = f"{a}-{b}"
        np.testing.assert_allclose(res.forces.spring_length[name], length, rtol=1e-12)
        np.testing.assert_allclose(
            res.forces.spring_force[name], s["stiffness"] * (length - s["free_length"]) * CM, rtol=1e-12
        )
        cols = res.columns()
        np.testing.assert_array_equal(cols[f"spring[{name}].force"], res.forces.spring_force[name])


def test_spring_on_the_frame_is_felt_by_the_frame():
    """Massless, static, springs only: the frame holds the whole machine, so it feels nothing overall.

    Its pins, the crank's motor and the springs' ends on the ground balance: shaking force and
    moment vanish (they would not if the springs' pull on the frame were left out).
    """
    res = lk.analyze(mech_with(springs=SPRINGS), ANGLES, static=True)
    scale = float(np.max(np.abs(res.forces.reaction("A", "crank"))))
    assert scale > 10
    np.testing.assert_allclose(res.forces.shaking_force, 0, atol=1e-10 * scale)
    np.testing.assert_allclose(res.forces.shaking_moment, 0, atol=1e-10 * scale)
    # at D (coupler first, then rocker) the spring acts on the coupler, the pin's carrier: the
    # rocker, loaded at B and D only, stays a two-force member (its pin force along B-D)
    zb, zd = res.point("B"), res.point("D")
    f = res.forces.reaction("D", "rocker", "coupler")
    np.testing.assert_allclose(np.imag(np.conj(zd - zb) * f) / np.abs(zd - zb), 0, atol=1e-10 * scale)
    assert np.min(np.abs(f)) > 1


def test_spring_statics_of_a_slider_crank_is_the_derivative_of_its_energy():
    """A slider driver: the force that holds the block against a spring from the frame to the crank pin."""
    doc = {
        "units": {"length": "mm", "angle": "deg"},
        "joints": {"O": [0, 0], "A": [30, 40], "B": [115, 0]},
        "links": {"ground": ["O"], "crank": ["O", "A"], "rod": ["A", "B"], "block": ["B"]},
        "sliders": [{"link": "block", "on": "ground", "through": "B", "direction": [1, 0]}],
        "drivers": [{"slider": 0}],
        "springs": [{"between": ["O", "A"], "stiffness": 1.0, "free_length": 0.0}],  # on one link: refused
    }
    with pytest.raises(MechanismFileError, match=r"springs\[0\]\.between: joints 'O' and 'A' are both on link"):
        lk.Mechanism.from_dict(doc)
    springs = [{"between": ["O", "B"], "stiffness": 2000.0, "free_length": 100.0}]
    with pytest.raises(MechanismFileError, match=r"springs\[1\]\.between: joints 'A' and 'B' are both on link 'rod'"):
        lk.Mechanism.from_dict({**doc, "springs": [*springs, {"between": ["A", "B"], "stiffness": 1.0}]})
    mech = lk.Mechanism.from_dict({**doc, "springs": springs})
    s = np.array([-20.0, -5.0, 0.0, 8.0])  # mm from the pose
    res = lk.analyze(mech, s, static=True)
    h, mm = 1e-4, 1e-3
    v_plus = energy(lk.analyze(mech, s + h, rates=False), springs, mm)
    v_minus = energy(lk.analyze(mech, s - h, rates=False), springs, mm)
    dv = (v_plus - v_minus) / (2 * h * mm)  # N
    # the spring pulls the block toward O (x < 0): holding it takes a push along +x equal to dV/ds
    assert np.all(np.abs(dv) > 1)
    np.testing.assert_allclose(res.forces.driver_force["block"], dv, rtol=1e-7)


def test_damper_tension_is_damping_times_the_length_rate():
    dampers = [{"between": ["C", "B"], "damping": 12.0}, {"between": ["A", "D"], "damping": 3.0}]
    mech = mech_with(dampers=dampers)
    w = 7.0  # rad/s, constant
    res = lk.analyze(mech, ANGLES, speed=w, acceleration=0.0)
    h = 1e-3  # deg
    plus, minus = lk.analyze(mech, ANGLES + h, rates=False), lk.analyze(mech, ANGLES - h, rates=False)
    torque = np.zeros(len(ANGLES))
    for d in dampers:
        a, b = d["between"]
        dl = (np.abs(plus.point(a) - plus.point(b)) - np.abs(minus.point(a) - minus.point(b))) * CM / np.radians(2 * h)
        np.testing.assert_allclose(res.forces.damper_force[f"{a}-{b}"], d["damping"] * dl * w, rtol=1e-7, atol=1e-10)
        torque += d["damping"] * dl**2 * w  # virtual power: T w = sum c (dL/dt)^2
    assert np.all(torque > 1e-4)
    np.testing.assert_allclose(res.forces.driver_torque["crank"], torque, rtol=1e-7)
    # a static analysis has no speed: no damper force
    np.testing.assert_array_equal(lk.analyze(mech, ANGLES, static=True).forces.damper_force["C-B"], 0.0)


def test_flywheel_adds_its_inertia_times_the_acceleration():
    masses = {
        "crank": {"joints": ["A", "C"], "mass": 0.3, "cg": [1, 0], "inertia": 2e-4},
        "coupler": {"joints": ["C", "D"], "mass": 0.5, "cg": [1.4, 2.4], "inertia": 1e-3},
        "rocker": {"joints": ["B", "D"], "mass": 0.4, "cg": [2.4, 2.9], "inertia": 8e-4},
    }
    links = {**FOURBAR["links"], **masses}
    w, alpha, inertia = 4.0, 25.0, 0.4
    kw = {"speed": w, "acceleration": alpha}
    bare = lk.analyze(mech_with(links=links, gravity=[0, -9.81]), ANGLES, **kw)
    on_crank = lk.analyze(
        mech_with(links=links, gravity=[0, -9.81], flywheels=[{"link": "crank", "inertia": inertia}]), ANGLES, **kw
    )
    extra = on_crank.forces.driver_torque["crank"] - bare.forces.driver_torque["crank"]
    np.testing.assert_allclose(extra, inertia * alpha, rtol=1e-9)
    on_rocker = lk.analyze(
        mech_with(links=links, gravity=[0, -9.81], flywheels=[{"link": "rocker", "inertia": inertia}]), ANGLES, **kw
    )
    extra = on_rocker.forces.driver_torque["crank"] - bare.forces.driver_torque["crank"]
    expected = inertia * bare.link_alpha["rocker"] * bare.link_omega["rocker"] / w  # virtual power
    assert np.all(np.abs(expected) > 1e-3)
    np.testing.assert_allclose(extra, expected, rtol=1e-8)
    assert on_crank.mechanism.flywheel_inertia("crank") == inertia


def test_force_elements_round_trip_through_files_and_the_editor(tmp_path):
    extra = {
        "springs": [*SPRINGS, {"between": ["A", "D"], "stiffness": 10.0, "free_length": 2.5, "name": "soft"}],
        "dampers": [{"between": ["C", "B"], "damping": 12.0}],
        "flywheels": [{"link": "crank", "inertia": 0.4}],
    }
    mech = mech_with(**extra)
    assert [s.name for s in mech.springs] == ["A-D", "C-B", "soft"]
    assert mech.springs[0].free_length == 4.0 and mech.dampers[0].damping == 12.0 and mech.has_dynamics
    assert lk.Mechanism.from_dict(mech.to_dict()) == mech
    assert mech != mech_with(**{**extra, "flywheels": [{"link": "crank", "inertia": 0.5}]})
    for suffix in ("yaml", "json"):
        path = tmp_path / f"m.{suffix}"
        lk.save(mech, path)
        assert lk.load(path) == mech
    session = Session(tmp_path / "m.yaml")
    out = session.solve({"doc": mech.to_dict(), "pose": {"D": [0.9, 4.8]}})
    assert out["ok"] is True
    kept = lk.Mechanism.from_dict(out["doc"])
    assert (kept.springs, kept.dampers, kept.flywheels) == (mech.springs, mech.dampers, mech.flywheels)
    assert session.save({"doc": out["doc"], "base": session.base})["ok"] is True
    assert lk.load(tmp_path / "m.yaml").springs == mech.springs


BAD = {
    "negative stiffness": ("springs: [{between: [A, D], stiffness: -1, free_length: 4}]", "springs[0].stiffness"),
    "negative free length": ("springs: [{between: [A, D], stiffness: 1, free_length: -4}]", "springs[0].free_length"),
    "one link": ("springs: [{between: [C, D], stiffness: 1}]", "both on link 'coupler'"),
    "unknown joint": ("dampers: [{between: [A, X], damping: 1}]", "dampers[0].between[1]: unknown joint 'X'"),
    "negative damping": ("dampers: [{between: [A, D], damping: -2}]", "dampers[0].damping"),
    "negative inertia": ("flywheels: [{link: crank, inertia: -0.1}]", "flywheels[0].inertia"),
    "flywheel on ground": ("flywheels: [{link: ground, inertia: 1}]", "flywheels[0].link"),
    # a load on the ground was taken and did nothing (a flywheel there was refused)
    "load on ground": (
        "loads: [{link: ground, at: A, force: [0, -10]}]",
        "loads[0].link: a load on the ground does nothing (put it on a moving link)",
    ),
    "unknown link": ("flywheels: [{link: wheel, inertia: 1}]", "flywheels[0].link: unknown link 'wheel'"),
    "typo": ("springs: [{between: [A, D], stifness: 1}]", "springs[0]"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_force_elements_get_one_line_and_exit_2(tmp_path, capsys, case):
    text, where = BAD[case]
    path = tmp_path / "bad.yaml"
    path.write_text(
        "joints: {A: [0, 0], B: [4, 1], C: [2, 0], D: [0.82, 4.86]}\n"
        "links: {ground: [A, B], crank: [A, C], coupler: [C, D], rocker: [B, D]}\n"
        "drivers: [{link: crank, pivot: A, toward: C}]\n" + text + "\n"
    )
    code = main(["check", str(path)])
    out, err = capsys.readouterr()
    assert code == 2, (out, err)
    lines = err.strip().splitlines()
    assert len(lines) == 1 and where in lines[0] and "bad.yaml" in lines[0], err


@pytest.mark.parametrize("props", ["mass: 100, cg: [1, 0]", "inertia: 5"])
def test_a_mass_or_inertia_on_the_ground_is_refused(tmp_path, capsys, props):
    """Accepted and ignored before (every force the same to 0.0 as without it; review 17a), as a load there was,
    while a flywheel there was refused."""
    path = tmp_path / "m.yaml"
    path.write_text(
        "joints: {A: [0, 0], B: [4, 1], C: [2, 0], D: [0.82, 4.86]}\n"
        f"links: {{ground: {{joints: [A, B], {props}}}, crank: [A, C], coupler: [C, D], rocker: [B, D]}}\n"
        "drivers: [{link: crank, pivot: A, toward: C}]\n"
    )
    attr = props.split(":")[0]
    assert main(["check", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"m.yaml: links.ground.{attr}: the ground does not move: its {attr} does" in err
