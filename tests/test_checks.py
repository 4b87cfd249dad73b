"""``lk.check`` / ``linkagekit check``: four-bar loops, Grashof types, transmission angle, dead points,
limit positions and time ratio, peak loads, drivers held at the pose.

Every expected number is computed here by another formulation:

* ranges, dead points, transmission angles and limit positions of a four-bar by the law of
  cosines on the triangle O2-A-O4 / A-B-O4 / O2-B-O4 (crank and coupler collinear:
  |O2 B| = b + a or b - a);
* the loops of a file by enumerating its links (not through the solve plan);
* the slider-crank's driver torque by an energy balance on closed-form slider-crank
  kinematics, and its bearing loads by Newton-Euler written out by hand for its three links.

Tolerances: inputs of dead points and limit positions 1e-8 deg (1.7e-10 rad; the check refines
them to ~1e-12 rad), link angles 1e-8 deg, transmission angles 1e-9 deg, time ratios 1e-9
relative, torques and forces 1e-9 relative (1e-6 against finite differences).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

import linkagekit as lk
from linkagekit.cli import main

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
DEG = 1e-8  # deg: inputs and angles (1.7e-10 rad)
MU = 1e-9  # deg: transmission angle values
REL = 1e-9


# ----------------------------------------------------------------------------- hand geometry
def cosines(a, b, c):
    """The angle (rad) opposite side c in a triangle of sides a, b, c."""
    return math.acos((a * a + b * b - c * c) / (2 * a * b))


def wrap(deg):
    """An angle in degrees to (-180, 180]."""
    return 180.0 - (180.0 - deg) % 360.0


def cross(u, v):
    return (np.conj(u) * v).imag


def fourbar(g, a, b, c, theta, gamma=0.0, mode=1, angle_unit="deg"):
    """A four-bar: O2 = 0, O4 = g e^{i gamma}, crank a at theta (deg), coupler b, rocker c.

    B is placed by the law of cosines on side ``mode`` of the directed line A -> O4 (the
    solver's sign for B, which it keeps at every input).
    """
    O2, O4 = 0j, g * np.exp(1j * math.radians(gamma))
    A = a * np.exp(1j * math.radians(theta))
    f = abs(O4 - A)
    B = A + b * np.exp(1j * (np.angle(O4 - A) + mode * cosines(b, f, c)))
    sweep = {"start": 0, "stop": 360, "step": 1} if angle_unit == "deg" else {"start": 0, "stop": 6.2, "step": 0.1}
    return lk.Mechanism.from_dict(
        {
            "units": {"length": "m", "angle": angle_unit},
            "joints": {k: [v.real, v.imag] for k, v in dict(O2=O2, O4=O4, A=A, B=B).items()},
            "links": {"ground": ["O2", "O4"], "crank": ["O2", "A"], "coupler": ["A", "B"], "rocker": ["O4", "B"]},
            "drivers": [{"link": "crank", "pivot": "O2", "toward": "A", "angles": sweep}],
        }
    )


def crank_angles_at_diagonal(g, a, f, gamma=0.0):
    """Crank angles (deg) where |A O4| = f: gamma +- the angle at O2 of the triangle (a, g, f)."""
    t = math.degrees(cosines(a, g, f))
    return gamma - t, gamma + t


def limit_positions_by_hand(g, a, b, c, gamma=0.0, mode=1):
    """Crank-rocker limit positions by the law of cosines: crank and coupler collinear.

    Extended: |O2 B| = a + b, A on the segment O2 B; folded: |O2 B| = b - a, A opposite B.
    Of the two mirror images of each, the one with B on side ``mode`` of A -> O4.
    Returns {name: (crank angle deg in [0, 360), rocker angle deg)} for 'extended', 'folded'.
    """
    O4 = g * np.exp(1j * math.radians(gamma))
    out = {}
    for name, reach, flip in (("extended", a + b, 0.0), ("folded", b - a, 180.0)):
        psi = math.degrees(cosines(reach, g, c))
        for s in (1, -1):
            u = np.exp(1j * math.radians(gamma + s * psi))
            B = reach * u
            A = a * u * (1 if flip == 0.0 else -1)
            if np.sign(cross(O4 - A, B - A)) == mode:
                out[name] = ((gamma + s * psi + flip) % 360.0, math.degrees(np.angle(B - O4)))
    return out


def fourbar_in_range(g, a, b, c, mode=1):
    """A four-bar posed in the middle of its first assembly arc (law of cosines), or None."""
    lo, hi = abs(c - b), b + c
    # |A O4|^2 = a^2 + g^2 - 2 a g cos(theta) must lie in [lo^2, hi^2]
    cmin = max(-1.0, (a * a + g * g - hi * hi) / (2 * a * g))
    cmax = min(1.0, (a * a + g * g - lo * lo) / (2 * a * g))
    if cmin >= cmax:
        return None
    theta = math.degrees(0.5 * (math.acos(cmax) + math.acos(cmin)))
    return fourbar(g, a, b, c, theta, mode=mode)


# ----------------------------------------------------------------------------- Grashof
@pytest.mark.parametrize(
    ("dims", "kind", "detail"),
    [
        ((4.0, 1.0, 3.5, 3.0), "crank-rocker", "crank-rocker"),  # s = crank, 1 + 4 < 3.5 + 3
        ((3.0, 2.5, 3.5, 1.0), "crank-rocker", "rocker-crank"),  # s = rocker
        ((1.0, 3.0, 3.5, 3.2), "double-crank", "double crank"),  # s = ground, 1 + 3.5 < 3 + 3.2
        ((3.0, 3.5, 1.0, 3.2), "double-rocker", "Grashof double rocker"),  # s = coupler
        ((4.0, 2.0, 4.0, 2.0), "change-point", "change-point"),  # parallelogram: 2 + 4 = 2 + 4
        ((2.0, 3.0, 2.5, 4.0), "non-grashof", "non-Grashof"),  # 2 + 4 > 3 + 2.5
    ],
)
def test_grashof_of_each_kind(dims, kind, detail):
    g, a, b, c = dims
    mech = fourbar_in_range(g, a, b, c)
    rep = lk.check(mech).to_dict()
    assert rep["grashof"] == kind and rep["grashof_detail"].startswith(detail)
    (loop,) = rep["fourbars"]
    assert loop["grashof"] == kind and loop["joints"] == ["O2", "A", "B", "O4"]
    assert loop["lengths"] == pytest.approx({"ground": g, "crank": a, "coupler": b, "rocker": c}, rel=1e-12)
    assert rep["fourbar"] == {"joints": loop["joints"], "lengths": loop["lengths"]}
    assert loop["input"] == {"link": "crank", "driver": "crank", "moved_by": "driver 'crank'"}


# ----------------------------------------------------------------------------- transmission angle
@pytest.mark.parametrize("gamma", [0.0, 33.0, -120.0])
def test_transmission_angle_of_a_crank_rocker_by_the_law_of_cosines(gamma):
    """cos mu = (b^2 + c^2 - f^2) / (2 b c) with f = |A O4| = g - a (crank along O2 O4) or g + a."""
    g, a, b, c = 4.0, 1.0, 3.5, 3.0
    rep = lk.check(fourbar(g, a, b, c, 50.0 + gamma, gamma)).to_dict()
    ta = rep["fourbars"][0]["transmission_angle"]
    mu_min = math.degrees(cosines(b, c, g - a))
    mu_max = math.degrees(cosines(b, c, g + a))
    assert rep["transmission_angle"] == pytest.approx({"min": mu_min, "max": mu_max}, abs=MU)
    assert ta["min"] == pytest.approx(mu_min, abs=MU) and ta["max"] == pytest.approx(mu_max, abs=MU)
    assert wrap(ta["min_at"] - gamma) == pytest.approx(0.0, abs=DEG)
    assert wrap(ta["max_at"] - gamma - 180.0) == pytest.approx(0.0, abs=DEG)
    assert ta["joint"] == "B"


# ----------------------------------------------------------------------------- dead points and ranges
@pytest.mark.parametrize(
    ("dims", "how"),
    [
        ((350.0, 700.0, 300.0, 500.0), "stretched"),  # |A O4| <= b + c = 800 limits the crank
        ((2.0, 3.0, 2.5, 4.0), "folded"),  # |A O4| >= c - b = 1.5 limits it
    ],
)
def test_dead_points_of_a_non_grashof_fourbar(dims, how):
    g, a, b, c = dims
    f = b + c if how == "stretched" else c - b
    lo, hi = crank_angles_at_diagonal(g, a, f)  # symmetric about the ground line
    mech = fourbar_in_range(g, a, b, c)
    rep = lk.check(mech).to_dict()
    assert rep["grashof"] == "non-grashof"
    ((start, stop),) = rep["input_range"]
    expected = (lo, hi) if how == "stretched" else (hi, 360.0 + lo)  # through 0, or around 180
    assert start == pytest.approx(expected[0], abs=DEG) and stop == pytest.approx(expected[1], abs=DEG)
    dead = rep["dead_points"]["crank"]
    assert [d["input"] for d in dead] == pytest.approx(list(expected), abs=DEG)
    for d in dead:
        assert d["kind"] == "end of range" and d["joint"] == "B" and set(d["links"]) == {"coupler", "rocker"}
        assert d["detail"].endswith(f"({how})")
    # the solver flags each as singular (or not assembled a hair outside): the mechanism locks there
    res = lk.analyze(mech, [d["input"] for d in dead])
    assert np.all(res.singular | ~res.assembled) and res.assembled.any()


def test_dead_points_of_a_double_rocker():
    """Ground 4, input 3, coupler 1, output 3.5: the input rocks between |A O4| = 4.5 and 2.5, on two arcs."""
    g, a, b, c = 4.0, 3.0, 1.0, 3.5
    fold = crank_angles_at_diagonal(g, a, c - b)  # (-38.62, 38.62)
    stretch = crank_angles_at_diagonal(g, a, c + b)  # (-78.58, 78.58)
    mech = fourbar_in_range(g, a, b, c)
    rep = lk.check(mech).to_dict()
    assert rep["grashof"] == "double-rocker"
    expected = sorted([fold[1], stretch[1], 360 + stretch[0], 360 + fold[0]])
    ranges = rep["input_range"]
    assert len(ranges) == 2
    np.testing.assert_allclose(ranges, [expected[:2], expected[2:]], atol=DEG)
    dead = rep["dead_points"]["crank"]
    np.testing.assert_allclose([d["input"] for d in dead], expected, atol=DEG)
    assert [d["detail"].split("(")[-1] for d in dead] == ["folded)", "stretched)", "stretched)", "folded)"]
    res = lk.analyze(mech, [d["input"] for d in dead])
    assert np.all(res.singular | ~res.assembled)


def test_change_points_of_the_parallelogram(examples):
    """Seed 003 example 2.2: the four pivots are collinear at crank 0 and 180 deg; it turns fully."""
    rep = lk.check(lk.load(examples / "seed003_ex22.yaml")).to_dict()
    assert rep["input_range"] == [[0.0, 360.0]]
    dead = rep["dead_points"]["crank"]
    assert [d["kind"] for d in dead] == ["change point", "change point"]
    assert [d["input"] for d in dead] == pytest.approx([0.0, 180.0], abs=DEG)
    assert [d["detail"].split("(")[-1] for d in dead] == ["folded)", "stretched)"]  # |A O2| = 500 = 1000 - 500, 1500


@pytest.mark.parametrize("gamma", [0.0, 37.0, -121.5])
def test_a_rhombus_lists_where_its_joint_is_undetermined(gamma):
    """A rhombus (four equal sides) with its ground at ``gamma`` deg: at crank ``gamma`` the crank's tip lies on the
    rocker's pivot, both of B1's circles coincide and B1 can be anywhere on them (by hand: the tip ``e^(i theta)``
    meets the pivot ``e^(i gamma)`` at ``theta = gamma``). ``check`` ran its range over the whole turn from a hair past
    that input to a hair before it and listed only the stretched change point at ``gamma + 180``; ``analyze`` flags
    ``gamma`` itself. Now ``gamma`` is a change point too (folded, B1 undetermined), to 1e-6 deg."""
    pivot, tip = np.exp(1j * math.radians(gamma)), np.exp(1j * math.radians(gamma + 90.0))
    doc = {
        "format": "linkagekit/1",
        "units": {"length": "m", "angle": "deg"},
        "joints": {"A0": [0, 0], "A1": [pivot.real, pivot.imag], "B0": [tip.real, tip.imag]}
        | {"B1": [(pivot + tip).real, (pivot + tip).imag]},
        "links": {"ground": ["A0", "A1"], "crank": ["A0", "B0"], "coupler": ["B0", "B1"], "rocker": ["A1", "B1"]},
        "drivers": [{"link": "crank", "pivot": "A0", "toward": "B0"}],
    }
    mech = lk.Mechanism.from_dict(doc)
    rep = lk.check(mech).to_dict()
    ((lo, hi),) = rep["input_range"]
    assert hi - lo == pytest.approx(360.0, abs=1e-6) and (hi - gamma + 180.0) % 360.0 == pytest.approx(180.0, abs=1e-6)
    dead = rep["dead_points"]["crank"]
    assert [d["kind"] for d in dead] == ["change point", "change point"]
    at = sorted(dead, key=lambda d: (d["input"] - gamma + 90.0) % 360.0)
    assert (at[0]["input"] - gamma + 180.0) % 360.0 - 180.0 == pytest.approx(0.0, abs=1e-6)
    assert (at[1]["input"] - gamma) % 360.0 == pytest.approx(180.0, abs=1e-6)
    assert at[0]["joint"] == "B1" and at[0]["detail"].endswith("B1 undetermined at this input (analyze flags it)")
    assert "(folded)" in at[0]["detail"] and "(stretched)" in at[1]["detail"]
    res = lk.analyze(mech, {"crank": [gamma, gamma - 1e-6, gamma + 1e-6]}, rates=False)
    assert res.assembled.tolist() == [False, True, True]


def test_full_turn_has_no_dead_point(examples):
    rep = lk.check(lk.load(examples / "seed000_fourbar.yaml")).to_dict()
    assert rep["dead_points"] == {"crank": []}


# ----------------------------------------------------------------------------- limit positions
@pytest.mark.parametrize(("gamma", "mode"), [(0.0, 1), (0.0, -1), (140.0, 1), (-75.0, -1)])
def test_limit_positions_and_time_ratio_of_a_crank_rocker(gamma, mode):
    g, a, b, c = 4.0, 1.0, 3.5, 3.0
    hand = limit_positions_by_hand(g, a, b, c, gamma, mode)
    (th_e, phi_e), (th_f, phi_f) = hand["extended"], hand["folded"]
    # which limit is the rocker's largest angle: the other is reached by turning back through the swing
    swing = abs(wrap(phi_e - phi_f))
    top, bottom = ((th_e, phi_e), (th_f, phi_f)) if wrap(phi_e - phi_f) > 0 else ((th_f, phi_f), (th_e, phi_e))
    rising = (top[0] - bottom[0]) % 360.0
    ratio = max(rising, 360 - rising) / min(rising, 360 - rising)

    mech = fourbar(g, a, b, c, gamma + 50.0, gamma, mode)
    loop = lk.check(mech).to_dict()["fourbars"][0]
    lims = {lim["extreme"]: lim for lim in loop["limit_positions"]}
    assert len(loop["limit_positions"]) == 2 and set(lims) == {"min", "max"}
    for lim, (theta, phi) in ((lims["max"], top), (lims["min"], bottom)):
        assert wrap(lim["input"] - theta) == pytest.approx(0.0, abs=DEG)
        assert wrap(lim["angle"] - phi) == pytest.approx(0.0, abs=DEG)
    assert loop["rocker_turns_fully"] is False
    assert loop["swing"] == pytest.approx(swing, abs=DEG)
    assert loop["time_ratio"] == pytest.approx(ratio, rel=REL)
    assert loop["strokes"]["rising"] == pytest.approx(rising, abs=DEG)
    assert loop["strokes"]["falling"] == pytest.approx(360.0 - rising, abs=DEG)


def test_limit_positions_in_radians():
    """A file in radians reports the same positions in radians."""
    g, a, b, c = 4.0, 1.0, 3.5, 3.0
    hand = limit_positions_by_hand(g, a, b, c)
    loop = lk.check(fourbar(g, a, b, c, 50.0, angle_unit="rad")).to_dict()["fourbars"][0]
    got = sorted(lim["input"] for lim in loop["limit_positions"])
    want = sorted(math.radians(t) for t, _ in hand.values())
    assert got == pytest.approx(want, abs=math.radians(DEG))
    assert loop["swing"] == pytest.approx(math.radians(abs(wrap(hand["extended"][1] - hand["folded"][1]))), abs=1e-9)


def test_double_crank_rocker_turns_fully():
    loop = lk.check(fourbar_in_range(1.0, 3.0, 3.5, 3.2)).to_dict()["fourbars"][0]
    assert loop["rocker_turns_fully"] is True and loop["limit_positions"] == []
    assert "swing" not in loop and "time_ratio" not in loop


# ----------------------------------------------------------------------------- loops of a file
def loops_by_enumeration(mech):
    """Every four-bar loop (O2, A, B, O4) from the links alone, each once (one orientation)."""
    ground = set(mech.link("ground").joints)
    links = [ln for ln in mech.links if ln.name != "ground" and not any(s.link == ln.name for s in mech.sliders)]
    pinned = {ln.name: [j for j in ln.joints if j in ground] for ln in links}
    found = set()
    for l2 in links:
        for l4 in links:
            if l2 is l4 or len(pinned[l2.name]) != 1 or len(pinned[l4.name]) != 1:
                continue
            o2, o4 = pinned[l2.name][0], pinned[l4.name][0]
            if o2 == o4:
                continue
            for l3 in links:
                if l3 in (l2, l4):
                    continue
                for A in set(l2.joints) & set(l3.joints) - ground:
                    for B in set(l4.joints) & set(l3.joints) - ground - {A}:
                        key = min((o2, A, B, o4), (o4, B, A, o2))
                        found.add((key, frozenset({l2.name, l3.name, l4.name})))
    return found


def as_found(rep):
    out = set()
    for lp in rep["fourbars"]:
        j = tuple(lp["joints"])
        out.add((min(j, j[::-1]), frozenset(v for k, v in lp["links"].items() if k != "ground")))
    return out


@pytest.mark.parametrize(
    ("name", "count"),
    [
        ("seed001_stephenson.yaml", 1),
        ("watt2_sixbar.yaml", 2),
        ("jansen_leg.yaml", 2),
        ("seed000_fourbar.yaml", 1),
        ("seed004_stephenson1.yaml", 1),
        ("slider_crank.yaml", 0),
        ("fivebar_two_drivers.yaml", 0),
    ],
)
def test_every_loop_of_the_examples_is_found(examples, name, count):
    mech = lk.load(examples / name)
    rep = lk.check(mech).to_dict()
    assert len(rep["fourbars"]) == count
    assert as_found(rep) == loops_by_enumeration(mech)
    for lp in rep["fourbars"]:  # lengths: distances between the loop's joints in the reference pose
        o2, a, b, o4 = (mech.joints[j] for j in lp["joints"])
        want = {"ground": abs(o4 - o2), "crank": abs(a - o2), "coupler": abs(b - a), "rocker": abs(b - o4)}
        assert lp["lengths"] == pytest.approx(want, rel=1e-9)


def test_the_stephenson_loop_of_seed001(examples):
    """OA-S-W-OB: ground 4, input link OA-S 1.5, link4 S-W 4, output OB-W 3 (the file's lengths)."""
    rep = lk.check(lk.load(examples / "seed001_stephenson.yaml")).to_dict()
    (lp,) = rep["fourbars"]
    assert lp["joints"] == ["OA", "S", "W", "OB"]
    assert lp["links"] == {"ground": "ground", "crank": "input", "coupler": "link4", "rocker": "output"}
    assert lp["lengths"] == pytest.approx({"ground": 4.0, "crank": 1.5, "coupler": 4.0, "rocker": 3.0}, rel=1e-9)
    assert lp["grashof"] == "crank-rocker" and rep["grashof"] == "crank-rocker"  # 1.5 + 4 < 4 + 3, input shortest
    assert lp["input"]["driver"] == "input"
    # the input link OA-S turns with the driver: the transmission angle's extremes are the crank-rocker's
    g, a, b, c = 4.0, 1.5, 4.0, 3.0
    ta = lp["transmission_angle"]
    assert ta["min"] == pytest.approx(math.degrees(cosines(b, c, g - a)), abs=MU)
    assert ta["max"] == pytest.approx(math.degrees(cosines(b, c, g + a)), abs=MU)
    assert rep["transmission_angle"] == {"min": ta["min"], "max": ta["max"]}
    # and its limit positions: OA-S and S-W collinear, |OB W| = 3 with |OA W| = 5.5 or 2.5
    phi_qs = math.degrees(cosines(2.0, 1.5, abs(1.285575219373 + 1.532088886238j - (1.477211629518 + 0.260472266500j))))
    ground = math.degrees(math.atan2(0.487477373621, 3.970184606565))  # 7 deg
    hand = limit_positions_by_hand(g, a, b, c, ground, mode=1)
    got = sorted(lim["input"] for lim in lp["limit_positions"])
    want = sorted((t + phi_qs) % 360 for t, _ in hand.values())  # driver angle = OA->Q = OA->S + 40 deg
    assert phi_qs == pytest.approx(40.0, abs=1e-6)
    assert got == pytest.approx(want, abs=DEG)


def test_watt2_second_loop_is_moved_by_the_first(examples):
    """Loop 2's input is loop 1's rocker; its output stops where loop 1's rocker stops or loop 2 folds flat."""
    mech = lk.load(examples / "watt2_sixbar.yaml")
    rep = lk.check(mech).to_dict()
    first, second = rep["fourbars"]
    assert second["input"] == {"link": "rocker", "driver": "crank", "moved_by": "loop 1 (its rocker 'rocker')"}
    res = lk.analyze(mech, [lim["input"] for lim in second["limit_positions"]])
    P = {j: res.point(j) for j in "ABCDEFG"}
    loop1_flat = np.abs(cross(P["C"] - P["A"], P["D"] - P["C"])) / (20 * 70)  # crank and coupler1 in line
    loop2_flat = np.abs(cross(P["F"] - P["B"], P["G"] - P["F"])) / (50 * 38)  # rocker and coupler2 in line
    assert np.all(np.minimum(loop1_flat, loop2_flat) < 1e-9)
    assert len(second["limit_positions"]) >= 2
    # the rocker of loop 1 stops at loop 1's limit positions: those inputs are among loop 2's
    for lim in first["limit_positions"]:
        assert min(abs(wrap(lim["input"] - x["input"])) for x in second["limit_positions"]) < DEG


# ----------------------------------------------------------------------------- several drivers
def test_drivers_held_at_their_pose_values(examples, capsys):
    mech = lk.load(examples / "fivebar_two_drivers.yaml")
    rep = lk.check(mech).to_dict()
    # the pose: A->C at 120 deg, B->D at 60 deg (C = (-15, 25.98), D = (65, 25.98), B = (50, 0))
    held = rep["held_at"]
    assert held["crank1"] == pytest.approx({"crank2": 60.0}, abs=1e-9)
    assert held["crank2"] == pytest.approx({"crank1": 120.0}, abs=1e-9)
    assert main(["check", str(examples / "fivebar_two_drivers.yaml")]) == 0
    out = capsys.readouterr().out
    assert "Assembles for crank1 in [0.000000, 360.000000] deg (crank2 = 60.000000 deg held at the pose)" in out
    assert "(crank1 = 120.000000 deg held at the pose)" in out


# ----------------------------------------------------------------------------- peak loads
def slider_crank_by_hand(theta_deg, w=10.0):
    """Closed-form kinematics of examples/slider_crank.yaml and its kinetostatics by hand.

    Crank r = 0.05 from O, rod L from A to B, B on the x axis on the +x side; constant speed w.
    Returns (torque by energy balance, torque by Newton-Euler, {reaction name: |F|}).
    """
    r, L = 0.05, 0.0939414711402797
    mc, ic, mr, ir, mb = 0.5, 0.000104166666666667, 0.3, 0.000220625, 0.4
    g = -9.81j
    th = np.radians(theta_deg)
    s, c = np.sin(th), np.cos(th)
    S = np.sqrt(L * L - r * r * s * s)
    dS = -r * r * s * c / S
    d2S = -r * r * (c * c - s * s) / S - r**4 * s * s * c * c / S**3
    A = r * np.exp(1j * th)
    vA, aA = 1j * w * A, -(w**2) * A
    B = r * c + S + 0j
    vB = w * (-r * s + dS) + 0j
    aB = w**2 * (-r * c + d2S) + 0j
    d = B - A
    w_rod = cross(d, vB - vA) / L**2
    a_rod = cross(d, aB - aA) / L**2
    Gc, vGc, aGc = A / 2, vA / 2, aA / 2
    Gr, vGr, aGr = (A + B) / 2, (vA + vB) / 2, (aA + aB) / 2

    def dot(u, v):
        return (np.conj(u) * v).real

    # energy balance: T w = d(kinetic energy)/dt - power of gravity - power of the 50 N load
    kinetic = mc * dot(aGc, vGc) + mr * dot(aGr, vGr) + ir * a_rod * w_rod + mb * dot(aB, vB)
    gravity = mc * dot(g, vGc) + mr * dot(g, vGr) + mb * dot(g, vB)
    load = dot(-50 + 0j, vB)
    t_energy = (kinetic - gravity - load) / w
    # Newton-Euler: block (x: P_x - 50 = mb aBx), rod (moments about A), crank (moments about O)
    Px = mb * aB.real + 50.0
    Py = (d.imag * Px - ir * a_rod - cross(Gr - A, mr * (aGr - g))) / d.real
    P = Px + 1j * Py  # by the rod on the block, at B
    Q = mr * (aGr - g) + P  # by the crank on the rod, at A
    N = mb * 9.81 - Py  # by the ground on the block, normal to the slide
    R = mc * (aGc - g) + Q  # by the ground on the crank, at O
    t_newton = cross(A, Q) + cross(Gc, mc * (aGc - g)) + ic * 0.0
    return t_energy, t_newton, {"O": np.abs(R), "A": np.abs(Q), "B": np.abs(P), "B slider": np.abs(N)}


def test_peak_loads_of_the_slider_crank(examples):
    mech = lk.load(examples / "slider_crank.yaml")
    dyn = lk.check(mech).to_dict()["dynamics"]
    theta = np.arange(0.0, 361.0, 1.0)  # the file's sweep
    t_energy, t_newton, bearings = slider_crank_by_hand(theta)
    np.testing.assert_allclose(t_newton, t_energy, rtol=1e-12, atol=1e-12)  # the two hand formulations agree
    i = int(np.argmax(np.abs(t_energy)))
    second = np.sort(np.abs(t_energy[theta < 360]))[-2]
    assert abs(t_energy[i]) - second > 1e-6  # the peak sample is well defined (360 repeats 0)
    peak = dyn["peak_driver_torque"]["crank"]
    assert peak["at"] == {"crank": theta[i]}
    assert peak["value"] == pytest.approx(t_energy[i], rel=REL)
    assert dyn["samples"] == 361 and dyn["speeds"] == {"crank": 10.0}
    # bearing loads: the largest |F| of the four reactions over the sweep
    names = list(bearings)
    mags = np.array([bearings[k] for k in names])
    k, j = np.unravel_index(int(np.argmax(mags)), mags.shape)
    assert np.sort(mags[:, :-1].ravel())[-2] < mags[k, j] * (1 - 1e-6)  # a well-defined peak sample
    bl = dyn["peak_bearing_load"]
    assert bl["value"] == pytest.approx(mags[k, j], rel=REL)
    assert bl["at"] == {"crank": theta[j]}
    joint_links = {
        "O": ("O", {"ground", "crank"}, "pin"),
        "A": ("A", {"crank", "rod"}, "pin"),
        "B": ("B", {"rod", "block"}, "pin"),
        "B slider": ("B", {"ground", "block"}, "slider"),
    }
    joint, links, kind = joint_links[names[k]]
    assert (bl["joint"], {bl["on"], bl["by"]}, bl["kind"]) == (joint, links, kind)


def link_points(mech, link):
    """The complex ratio of a link's centre of gravity to its first two joints, in the reference pose."""
    ln = mech.link(link)
    j0, j1 = (mech.joints[j] for j in ln.joints[:2])
    return ln.joints[0], ln.joints[1], (ln.cg_pose - j0) / (j1 - j0)


def test_peak_torque_of_seed001_by_the_energy_balance(examples):
    """No gravity, no load: T w = d(kinetic energy)/dt = sum m a_G . v_G + I alpha w over the links.

    Positions only from the solver (rates=False); every derivative by fourth-order central
    differences in the input angle (h = 1e-3 rad; they agree to ~1e-10): v = w z',
    a = alpha z' + w^2 z'' (w = 3 rad/s, alpha = -2 rad/s^2).
    The peak is negative here (-515 N*m), so a peak taken on the signed torque would be wrong.
    """
    mech = lk.load(examples / "seed001_stephenson.yaml")
    dyn = lk.check(mech).to_dict()["dynamics"]
    theta = np.arange(0.0, 361.0, 2.0)
    w, alpha, h = 3.0, -2.0, 1e-3  # h in rad
    offsets = np.array([-2, -1, 0, 1, 2]) * h
    res = lk.analyze(mech, (theta[:, None] + np.degrees(offsets)[None, :]).ravel(), rates=False, dynamics=False)

    def derivatives(z):
        z = z.reshape(len(theta), 5)
        d1 = (z[:, 0] - 8 * z[:, 1] + 8 * z[:, 3] - z[:, 4]) / (12 * h)
        d2 = (-z[:, 0] + 16 * z[:, 1] - 30 * z[:, 2] + 16 * z[:, 3] - z[:, 4]) / (12 * h * h)
        return d1, d2

    power = np.zeros(len(theta))
    for ln in mech.links:
        if ln.name == "ground":
            continue
        j0, j1, rho = link_points(mech, ln.name)
        z0, z1 = res.point(j0), res.point(j1)
        g1, g2 = derivatives(z0 + rho * (z1 - z0))
        p1, p2 = derivatives(np.unwrap(np.angle(z1 - z0).reshape(len(theta), 5), axis=1).ravel())
        vg, ag = w * g1, alpha * g1 + w * w * g2
        om, al = w * p1, alpha * p1 + w * w * p2
        power += ln.mass * (np.conj(ag) * vg).real + ln.inertia * al * om
    torque = power / w
    i = int(np.argmax(np.abs(torque)))
    assert torque[i] < 0 and np.sort(np.abs(torque))[-2] < abs(torque[i]) - 1.0  # a clear, negative peak
    peak = dyn["peak_driver_torque"]["input"]
    assert peak["at"] == {"input": theta[i]}
    assert peak["value"] == pytest.approx(torque[i], rel=1e-8)


def test_peak_loads_in_text_and_json(examples, capsys):
    path = str(examples / "seed001_stephenson.yaml")
    assert main(["check", path, "--format", "json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert set(doc["dynamics"]) >= {"peak_driver_torque", "peak_bearing_load", "samples", "speeds"}
    assert len(doc["fourbars"]) == 1 and doc["grashof"] == "crank-rocker" and "transmission_angle" in doc
    assert main(["check", path]) == 0
    out = capsys.readouterr().out
    assert "Four-bar loop OA-S-W-OB: crank-rocker (the input turns fully)" in out
    assert "Transmission angle: min" in out and "Limit positions of output" in out and "Time ratio" in out
    assert "Peak driver torque of input: " in out and " N*m at input = " in out and "Peak bearing load: " in out
    assert "Dead points of input (where the mechanism locks): none" in out


def test_no_dynamics_without_masses(examples):
    assert "dynamics" not in lk.check(lk.load(examples / "seed000_fourbar.yaml")).to_dict()


# ----------------------------------------------------------------------------- a property
def grashof_by_hand(g, a, b, c):
    """(Grashof?, which link is shortest) of a four-bar."""
    lengths = {"ground": g, "crank": a, "coupler": b, "rocker": c}
    s, p, q, ell = sorted(lengths.values())
    return s + ell < p + q, min(lengths, key=lengths.get)


@settings(max_examples=40, deadline=None, suppress_health_check=list(HealthCheck))
@given(
    dims=st.tuples(*(st.floats(1.0, 10.0) for _ in range(4))),
    mode=st.sampled_from([1, -1]),
)
def test_grashof_class_decides_whether_the_crank_turns(dims, mode):
    """Grashof's law: the crank turns fully iff s + l < p + q with the crank or the ground shortest.

    Away from the change point (|s + l - p - q| > 2 % of l): then a crank that turns has no dead
    point and two limit positions of its rocker, which are crank-coupler collinear positions;
    a crank that does not turn has a dead point at each end of each arc, and the solver flags them.
    """
    g, a, b, c = dims
    s, p, q, ell = sorted(dims)
    assume(abs(s + ell - p - q) > 0.02 * ell)
    mech = fourbar_in_range(g, a, b, c, mode)
    assume(mech is not None)
    rep = lk.check(mech).to_dict()
    grashof_law, shortest = grashof_by_hand(g, a, b, c)
    turns = grashof_law and shortest in ("crank", "ground")
    assert (rep["input_range"] == [[0.0, 360.0]]) == turns
    assert (rep["grashof"] in ("crank-rocker", "double-crank")) == (grashof_law and shortest != "coupler")
    dead = rep["dead_points"]["crank"]
    loop = rep["fourbars"][0]
    if turns:
        assert dead == []
        rocks = shortest == "crank"
        assert loop["rocker_turns_fully"] is (not rocks)
        if rocks:
            assert len(loop["limit_positions"]) == 2 and loop["time_ratio"] >= 1.0
            res = lk.analyze(mech, [lim["input"] for lim in loop["limit_positions"]])
            O2, A, B = res.point("O2"), res.point("A"), res.point("B")
            assert np.all(np.abs(cross(A - O2, B - A)) / (a * b) < 1e-9)  # crank and coupler in line
    else:
        assert len(dead) == 2 * len(rep["input_range"])
        res = lk.analyze(mech, [d["input"] for d in dead])
        assert np.all(res.singular | ~res.assembled)


# ----------------------------------------------------------------------------- brackets (checks._Bracket)
def test_each_bracket_refines_to_its_root_or_minimum():
    """One vectorized refine takes every bracket of a crank-rocker to the law-of-cosines value.

    The rocker's angular velocity changes sign at the two limit positions (roots, bisection);
    the transmission angle is smallest with the crank along O2 O4 (theta = 0) and largest
    opposite (theta = 180 deg), smooth extremes: roots of d mu / d theta.  Inputs to 1e-8 deg.
    """
    from linkagekit import checks
    from linkagekit.api import prepare

    g, a, b, c = 4.0, 1.0, 3.5, 3.0
    mech = fourbar(g, a, b, c, 50.0)
    params = prepare(mech)
    loop = checks.fourbar_loops(mech, params)[0]
    run = checks._run(mech, params, 0, checks._assembly_intervals(mech, 0, params), [(0, loop)])
    limits = checks._limit_brackets(run, 0)
    extremes = checks._extreme_brackets(run, 0)
    assert [br.row for br in limits] == [run.q.w(0)] * 2 and all(br.sign in (1.0, -1.0) for br in limits)
    assert set(extremes) == {1, -1} and {br.row for br in extremes.values()} == {run.q.dmu(0)}
    brackets = limits + list(extremes.values())
    assert all(br.a < br.b and math.isnan(br.x) for br in brackets)
    checks._refine(params, 0, run.q, brackets, [])
    hand = limit_positions_by_hand(g, a, b, c)
    got = sorted(math.degrees(br.x) % 360.0 for br in limits)
    assert got == pytest.approx(sorted(theta for theta, _ in hand.values()), abs=DEG)
    assert wrap(math.degrees(extremes[1].x)) == pytest.approx(0.0, abs=DEG)
    assert wrap(math.degrees(extremes[-1].x) - 180.0) == pytest.approx(0.0, abs=DEG)
    # a golden-section search on the same minimum: mu is smooth there, so x is found to ~sqrt(eps)
    i = extremes[1].sample
    mins = [checks._Bracket(run.sw.px[i], run.sw.nx[i], run.q.mu(0), i)]
    checks._refine(params, 0, run.q, [], mins)
    assert wrap(math.degrees(mins[0].x)) == pytest.approx(0.0, abs=1e-5)


# ----------------------------------------------------------------------------- text of a report document
def test_text_of_a_report_without_the_loop_list():
    """A document with only the first loop's fields (no ``fourbars``) prints that loop."""
    rep = {
        "name": "old",
        "dof": 1,
        "drivers": ["crank"],
        "solvable": "closed-form",
        "units": {"length": "mm", "angle": "deg"},
        "grashof": "crank-rocker",
        "grashof_detail": "crank-rocker (the input turns fully)",
        "fourbar": {"joints": ["A", "C", "D", "B"], "lengths": {"ground": 4.0, "crank": 1.0}},
        "transmission_angle": {"min": 24.5, "max": 75.25},
    }
    from linkagekit.checks import check_text

    lines = check_text(rep).splitlines()
    assert lines[0] == "old: valid; 1 degree(s) of freedom, driven by crank; solved in closed form."
    assert lines[-3:] == [
        "Four-bar loop A-C-D-B: crank-rocker (the input turns fully)",
        "  lengths: ground 4 mm, input side 1 mm, coupler — mm, output side — mm",
        "  Transmission angle: min 24.5000°, max 75.2500°; worst 24.5000° (min, as synthesize counts it)",
    ]


def test_text_lists_at_most_so_many_dead_points():
    from linkagekit.checks import MAX_TEXT_DEAD_POINTS, check_text

    n = MAX_TEXT_DEAD_POINTS + 6
    dps = [{"input": 0.5 * k, "kind": "change point", "detail": f"step {k}"} for k in range(n)]
    rep = {"name": "m", "dof": 1, "drivers": ["s"], "input_ranges": {"s": [[0.0, 20.0]]}, "dead_points": {"s": dps}}
    lines = check_text(rep, units={"s": "mm"}).splitlines()
    assert lines[1] == "Solve plan:"
    assert lines[2] == "Assembles for s in [0.000000, 20.000000] mm"
    assert lines[3] == "Dead points of s (where the mechanism locks):"
    assert lines[4] == "  s = 0.000000 mm: change point; step 0"
    last = MAX_TEXT_DEAD_POINTS - 1
    assert lines[4 + last] == f"  s = {0.5 * last:.6f} mm: change point; step {last}"
    assert lines[-1] == "  ... and 6 more (check --format json lists them all)"
    rep["dead_points"] = {"s": []}
    assert check_text(rep).splitlines()[-1] == "Dead points of s (where the mechanism locks): none"


# ----------------------------------------------------------------------------- sliders on the frame (issue 23)
def shaper(d=300.0, r=100.0, lever=600.0, rod=200.0, height=600.0):
    """A crank-and-slotted-lever shaper (mm): lever pivot O4 = 0, crank pivot O2 = (0, d), crank r; the
    crank's pin A slides in the lever; the lever's tip L drives the ram C on the line y = height by a rod."""
    A = complex(r, d)  # the pose: crank at 0 deg
    L = lever * A / abs(A)
    C = complex(L.real + math.sqrt(rod**2 - (height - L.imag) ** 2), height)
    pts = {"O2": 1j * d, "O4": 0j, "A": A, "L": L, "C": C}
    return lk.Mechanism.from_dict(
        {
            "units": {"length": "mm", "angle": "deg"},
            "joints": {k: [v.real, v.imag] for k, v in pts.items()},
            "links": {
                "ground": ["O2", "O4"],
                "crank": ["O2", "A"],
                "block": ["A"],
                "lever": ["O4", "L"],
                "rod": ["L", "C"],
                "ram": ["C"],
            },
            "sliders": [
                {"link": "block", "on": "lever", "through": "A", "direction": [A.real, A.imag]},
                {"link": "ram", "on": "ground", "through": "C", "direction": [1, 0]},
            ],
            "drivers": [
                {"link": "crank", "pivot": "O2", "toward": "A", "angles": {"start": 0, "stop": 360, "step": 1}}
            ],
        }
    )


def shaper_ram_x(theta_deg, d=300.0, r=100.0, lever=600.0, rod=200.0, height=600.0):
    """The ram's x by hand: the lever points at the crank pin; the rod closes the triangle to the ram's line."""
    t = np.radians(theta_deg)
    ax, ay = r * np.cos(t), d + r * np.sin(t)
    phi = np.arctan2(ay, ax)
    lx, ly = lever * np.cos(phi), lever * np.sin(phi)
    return lx + np.sqrt(rod**2 - (height - ly) ** 2)


def extremes_by_brute_force(f, lo=0.0, hi=360.0):
    """Crank angles (deg) of the min and max of f: sampled every 0.01 deg, then a bounded scalar search."""
    from scipy.optimize import minimize_scalar

    th = np.arange(lo, hi, 0.01)
    x = f(th)
    out = []
    for sgn, i in ((1, int(np.argmin(x))), (-1, int(np.argmax(x)))):
        res = minimize_scalar(
            lambda t, sgn=sgn: sgn * f(np.array([t]))[0],
            bounds=(th[i] - 0.02, th[i] + 0.02),
            method="bounded",
            options={"xatol": 1e-10},
        )
        out.append((res.x % 360.0, f(np.array([res.x]))[0]))
    return out  # [(angle of min, min), (angle of max, max)]


def test_shaper_stroke_and_time_ratio_against_brute_force():
    """The new user's shaper: 400 mm and 1.55 by the textbook (stroke 2 lever r / d; return stroke over
    2 acos(r / d) of the crank), and exactly what brute-force sampling of a hand-written closed form gives."""
    rep = lk.check(shaper()).to_dict()
    (sl,) = rep["sliders"]
    assert (sl["slider"], sl["link"], sl["joint"], sl["driver"]) == (1, "ram", "C", "crank")
    (t_min, x_min), (t_max, x_max) = extremes_by_brute_force(shaper_ram_x)
    assert sl["stroke"] == pytest.approx(x_max - x_min, abs=1e-6)
    assert sl["stroke"] == pytest.approx(400.0, abs=2.0)  # by hand: 2 * 600 * 100 / 300
    rising = (t_max - t_min) % 360.0  # the ram advances (x grows) from its min to its max
    assert sl["input_travel"]["rising"] == pytest.approx(rising, abs=1e-5)
    assert sl["time_ratio"] == pytest.approx(max(rising, 360 - rising) / min(rising, 360 - rising), abs=1e-6)
    by_hand = (180 + 2 * math.degrees(math.asin(1 / 3))) / (180 - 2 * math.degrees(math.asin(1 / 3)))
    assert sl["time_ratio"] == pytest.approx(1.553, abs=0.005) and by_hand == pytest.approx(1.552, abs=1e-3)
    lims = {lim["extreme"]: lim for lim in sl["limit_positions"]}
    assert lims["min"]["input"] == pytest.approx(t_min, abs=1e-5) and lims["max"]["input"] == pytest.approx(
        t_max, abs=1e-5
    )
    x0 = shaper_ram_x(np.array([0.0]))[0]  # positions are measured from the pose's
    assert lims["max"]["position"] == pytest.approx(x_max - x0, abs=1e-6)
    text = lk.check(shaper()).text()
    assert "Slider 1 ('ram' on the frame, joint C), moved by crank: stroke 4" in text
    assert f"Time ratio {sl['time_ratio']:.6f} at constant input speed" in text


def test_whitworth_example_stroke_and_time_ratio(examples):
    """examples/whitworth_quick_return.yaml: the ram's x sampled through lk.analyze at 0.01 deg and refined."""
    mech = lk.load(examples / "whitworth_quick_return.yaml")
    (sl,) = lk.check(mech).to_dict()["sliders"]

    def ram_x(th):
        return lk.analyze(mech, {"crank": np.atleast_1d(th)}, rates=False, dynamics=False).xy("C")[:, 0]

    (t_min, x_min), (t_max, x_max) = extremes_by_brute_force(ram_x)
    assert sl["stroke"] == pytest.approx(x_max - x_min, abs=1e-9) and sl["stroke"] == pytest.approx(0.3, abs=1e-9)
    rising = (t_max - t_min) % 360.0
    assert sl["time_ratio"] == pytest.approx(max(rising, 360 - rising) / min(rising, 360 - rising), abs=1e-6)
    assert sl["time_ratio"] == pytest.approx(2.0, abs=1e-9)


def test_pressure_angle_of_the_slider_crank(examples):
    """Slider-crank without offset: the rod's angle to the slide is asin(r sin(theta) / l), largest at
    theta = 90 and 270 deg (asin(r / l)), zero at the dead centres."""
    mech = lk.load(examples / "slider_crank.yaml")
    (sl,) = lk.check(mech).to_dict()["sliders"]
    r, rod = 0.05, 0.0939414711402797
    pa = sl["pressure_angle"]
    assert pa["rod"] == "rod"
    assert pa["max"] == pytest.approx(math.degrees(math.asin(r / rod)), abs=1e-9)
    assert min(abs(wrap(pa["max_at"] - 90)), abs(wrap(pa["max_at"] - 270))) < 1e-3
    assert pa["min"] == pytest.approx(0.0, abs=1e-9)
    assert sl["stroke"] == pytest.approx(2 * r, abs=1e-12) and sl["time_ratio"] == pytest.approx(1.0, abs=1e-9)
    assert "Pressure angle (between rod 'rod' and the slide): max 32.1574°" in lk.check(mech).text()


def test_a_resting_slider_has_one_dwell_not_hundreds_of_limit_positions(examples, tmp_path, capsys):
    """An isosceles slider-crank (crank = rod = 50 mm, no offset; review item 5). By hand: in the pose's mode
    the block is at 100 cos(theta) mm from O for theta in [-90, 90] deg and rests at O for theta in [90, 270]
    (the rod folded back over the crank), so its limit positions are the max 100 mm at 0 deg and the min at O,
    held from 90 to 270 deg, and it advances over 90 deg of crank and returns over 90.  The rounding of its
    resting velocity (1e-10) used to flip sign at hundreds of samples: 627 alternating min and max entries,
    and no time ratio.  The shipped slider-crank keeps its two exact limit positions and time ratio 1."""
    s2 = 50 * math.sqrt(0.5)
    doc = {
        "units": {"length": "mm", "angle": "deg"},
        "joints": {"O": [0, 0], "A": [s2, s2], "B": [2 * s2, 0]},
        "links": {
            "ground": ["O"],
            "crank": {"joints": ["O", "A"], "mass": 0.2, "cg": [s2 / 2, s2 / 2], "inertia": 1e-4},
            "rod": {"joints": ["A", "B"], "mass": 0.2, "cg": [1.5 * s2, s2 / 2], "inertia": 1e-4},
            "block": {"joints": ["B"], "mass": 0.5, "cg": [2 * s2, 0]},
        },
        "sliders": [{"link": "block", "on": "ground", "through": "B", "direction": [1, 0]}],
        "drivers": [{"link": "crank", "pivot": "O", "toward": "A", "angles": {"start": 0, "stop": 360, "step": 1}}],
    }
    (sl,) = lk.check(lk.Mechanism.from_dict(doc)).to_dict()["sliders"]
    top, rest = sl["limit_positions"]
    assert top == {"input": pytest.approx(0.0, abs=DEG), "position": pytest.approx(100 - 2 * s2, abs=1e-12),
                   "extreme": "max"}  # fmt: skip
    # the dwell's ends: where the block comes within 1e-10 of its stroke of O (slope 100 mm/rad: 1e-10 rad)
    assert rest == {"input": pytest.approx(90.0, abs=1e-7), "position": pytest.approx(-2 * s2, abs=1e-12),
                    "extreme": "min", "until": pytest.approx(270.0, abs=1e-7)}  # fmt: skip
    assert sl["stroke"] == pytest.approx(100.0, abs=1e-9) and sl["time_ratio"] == pytest.approx(1.0, rel=REL)
    assert sl["input_travel"] == pytest.approx({"rising": 90.0, "falling": 90.0, "rest": 180.0}, abs=1e-7)
    path = tmp_path / "iso.json"
    path.write_text(json.dumps(doc))
    assert main(["check", str(path)]) == 0
    out = capsys.readouterr().out
    assert "crank = 90.000000 deg to 270.000000 deg: block at -70.710678 mm (min, at rest)" in out
    assert "90.000000 deg while it returns, 180.000000 deg at rest)" in out and len(out.splitlines()) < 40
    (sc,) = lk.check(lk.load(examples / "slider_crank.yaml")).to_dict()["sliders"]
    r, rod, x0 = 0.05, 0.0939414711402797, 0.115  # the block at r + l and l - r from O, at 0 and 180 deg
    assert [(lim["input"], lim["extreme"]) for lim in sc["limit_positions"]] == [
        (pytest.approx(0.0, abs=DEG), "max"), (pytest.approx(180.0, abs=DEG), "min")]  # fmt: skip
    assert [lim["position"] for lim in sc["limit_positions"]] == pytest.approx([r + rod - x0, rod - r - x0], abs=1e-12)
    assert sc["time_ratio"] == pytest.approx(1.0, rel=REL) and sc["input_travel"] == {"rising": 180.0, "falling": 180.0}


def test_a_slider_driver_is_not_a_slider_fact():
    """A slider whose position is the input has nothing to report (its stroke is the sweep)."""
    mech = lk.Mechanism.from_dict(
        {
            "joints": {"O": [0, 0], "A": [0.03, 0.04], "B": [0.115, 0]},
            "links": {"ground": ["O"], "crank": ["O", "A"], "rod": ["A", "B"], "block": ["B"]},
            "sliders": [{"link": "block", "on": "ground", "through": "B", "direction": [1, 0]}],
            "drivers": [{"slider": 0, "displacements": {"start": -0.01, "stop": 0.01, "step": 0.001}}],
        }
    )
    assert lk.check(mech).to_dict()["sliders"] == []


# ----------------------------------------------------------------------------- a loop moved by a rocker
def circles(p, r1, q, r2, side):
    """The intersection of circle (p, r1) and circle (q, r2) on side `side` of p -> q."""
    d = abs(q - p)
    a = (r1 * r1 - r2 * r2 + d * d) / (2 * d)
    h = math.sqrt(r1 * r1 - a * a)
    u = (q - p) / d
    return p + a * u + side * h * 1j * u


def watt_with_grashof_second_loop():
    """Loop 1: crank 20, coupler 70, rocker 50, ground 60 (a crank-rocker). Loop 2 on the rocker's pivot B:
    input side |B F| = 10 (the shortest), coupler 35, output 30, ground |B E| = 40: Grashof with its input
    side shortest, but that input is loop 1's rocker, which only rocks."""
    A, B, E = 0j, 60 + 0j, 60 - 40j
    C = 20j
    D = circles(C, 70, B, 50, 1)
    F = B + 10 * (D - B) / abs(D - B) * np.exp(1j * math.radians(-120))
    G = circles(F, 35, E, 30, -1)
    pts = dict(A=A, B=B, E=E, C=C, D=D, F=F, G=G)
    return lk.Mechanism.from_dict(
        {
            "units": {"length": "mm", "angle": "deg"},
            "joints": {k: [complex(v).real, complex(v).imag] for k, v in pts.items()},
            "links": {
                "ground": ["A", "B", "E"],
                "crank": ["A", "C"],
                "coupler1": ["C", "D"],
                "rocker": ["B", "D", "F"],
                "coupler2": ["F", "G"],
                "output": ["E", "G"],
            },
            "drivers": [{"link": "crank", "pivot": "A", "toward": "C", "angles": {"start": 0, "stop": 360, "step": 1}}],
        }
    )


def test_a_loop_moved_by_a_rocker_is_not_called_a_turning_crank():
    mech = watt_with_grashof_second_loop()
    rep = lk.check(mech).to_dict()
    first, second = rep["fourbars"]
    # by hand: loop 1 is a crank-rocker (20 + 70 < 60 + 50, crank shortest): its rocker swings less than a turn
    assert first["grashof"] == "crank-rocker" and first["rocker_turns_fully"] is False and first["swing"] < 180
    assert first["grashof_detail"] == "crank-rocker (the input turns fully)" and first["input_turns_fully"] is True
    # loop 2: Grashof by its lengths, input side shortest (10 + 40 < 35 + 30); its input is loop 1's rocker
    assert second["grashof"] == "crank-rocker" and second["input"]["link"] == "rocker"
    assert second["input_turns_fully"] is False
    assert "turns fully" not in second["grashof_detail"]
    assert second["grashof_detail"] == (
        "crank-rocker by its lengths (the input side is the shortest link); its input link 'rocker' only rocks here"
    )
    assert "Four-bar loop 2 of 2 B-F-G-E: crank-rocker by its lengths" in lk.check(mech).text()


# ----------------------------------------------------------------------------- ranges through 0
def test_a_range_through_zero_prints_its_gap():
    """Non-Grashof g=4, a=3, b=2.5, c=2: it assembles while |A O4| <= b + c, i.e. |theta| <= acos((9 + 16
    - 20.25) / 24) by the law of cosines: the range runs through 0 and the gap is the rest of the turn."""
    mech = fourbar_in_range(4.0, 3.0, 2.5, 2.0)
    rep = lk.check(mech).to_dict()
    t = math.degrees(math.acos((9 + 16 - 4.5**2) / 24))
    (rng,), (gap,) = rep["input_range"], rep["assembly_gaps"]["crank"]
    assert rng == pytest.approx([-t, t], abs=1e-8) and gap == pytest.approx([t, 360 - t], abs=1e-8)
    line = next(x for x in lk.check(mech).text().splitlines() if x.startswith("Assembles"))
    assert line == f"Assembles for crank in all but ({t:.6f}, {360 - t:.6f}) deg ([{-t:.6f}, {t:.6f}])"


def test_the_issue_range_prints_as_all_but_its_gap():
    from linkagekit.checks import assembly_gaps, check_text

    rep = {
        "name": "m",
        "dof": 1,
        "drivers": ["crank"],
        "input_ranges": {"crank": [[-341.593352, 4.792542]]},
        "assembly_gaps": {"crank": assembly_gaps([[-341.593352, 4.792542]], math.pi / 180)},
        "input_units": {"crank": "deg"},
    }
    (gap,) = rep["assembly_gaps"]["crank"]
    assert gap == pytest.approx([4.792542, 18.406648], abs=1e-9)
    assert check_text(rep).splitlines()[2] == (
        "Assembles for crank in all but (4.792542, 18.406648) deg ([-341.593352, 4.792542])"
    )


# ----------------------------------------------------------------------------- warnings
def test_warning_when_the_transmission_angle_leaves_20_to_160():
    """Crank-rocker g=4, a=2.45, b=3.5, c=3: the transmission angle is extreme with the crank along the
    ground line, |A O4| = g -+ a: mu = acos((b^2 + c^2 - f^2) / (2 b c)), 26.2 and 165.7 deg: warned;
    a = 2.0 gives 34.8 and 134.6 deg: no warning."""
    from linkagekit.checks import MIN_TRANSMISSION

    def mu(f, b=3.5, c=3.0):
        return math.degrees(math.acos((b * b + c * c - f * f) / (2 * b * c)))

    rep = lk.check(fourbar(4.0, 2.45, 3.5, 3.0, 50.0)).to_dict()
    (w,) = rep["warnings"]
    assert w["kind"] == "transmission-angle" and w["limit"] == MIN_TRANSMISSION == 20.0
    assert w["min"] == pytest.approx(mu(4.0 - 2.45), abs=MU) and w["max"] == pytest.approx(mu(4.0 + 2.45), abs=MU)
    assert (
        "Warning: the transmission angle of loop O2-A-B-O4 leaves [20°, 160°]"
        in lk.check(fourbar(4.0, 2.45, 3.5, 3.0, 50.0)).text()
    )
    assert lk.check(fourbar(4.0, 2.0, 3.5, 3.0, 50.0)).to_dict()["warnings"] == []
    assert mu(2.0) > 20 and mu(6.0) < 160


def test_min_transmission_is_the_synthesis_default():
    import inspect

    from linkagekit.checks import MIN_TRANSMISSION
    from linkagekit.synthesis.objective import Problem
    from linkagekit.synthesis.run import synthesize_path

    # path generation's bound when none is given (None: the task's default; motion and function have none)
    assert inspect.signature(synthesize_path).parameters["min_transmission"].default is None
    assert inspect.signature(Problem).parameters["min_transmission"].default == MIN_TRANSMISSION


def cylinder_arm(start):
    """An arm |O B| = 1 m about O, lifted by a cylinder from C = (2, 0) to B, against a 10 N*m load torque.

    By hand: |B C| = s gives cos(theta) = (5 - s^2) / 4; the cylinder's force F along C -> B balances the
    torque: F |O B| sin(gamma) = 10, gamma the angle between O B and C B; gamma -> 0 as s -> 1 (in line)."""
    s0 = 1.8
    th = math.acos((5 - s0 * s0) / 4)
    B = complex(math.cos(th), math.sin(th))
    return lk.Mechanism.from_dict(
        {
            "joints": {"O": [0, 0], "C": [2, 0], "B": [B.real, B.imag]},
            "links": {"ground": ["O", "C"], "arm": ["O", "B"]},
            "drivers": [
                {"cylinder": ["C", "B"], "name": "cyl", "lengths": {"start": start, "stop": 2.5, "step": 0.005}}
            ],
            "loads": [{"link": "arm", "torque": -10}],
        }
    )


def test_warning_when_a_driver_force_peaks_next_to_a_toggle():
    from linkagekit.checks import TOGGLE_ANGLE

    s = 1.005
    th = math.acos((5 - s * s) / 4)
    B = complex(math.cos(th), math.sin(th))
    gamma = math.degrees(math.asin(abs(cross(B - 0, B - 2)) / (abs(B) * abs(B - 2))))
    rep = lk.check(cylinder_arm(s)).to_dict()
    peak = rep["dynamics"]["peak_driver_force"]["cyl"]
    assert peak["at"] == {"cyl": pytest.approx(s, abs=1e-12)}
    assert abs(peak["value"]) == pytest.approx(10 / math.sin(math.radians(gamma)), rel=1e-9)
    assert peak["toggle"]["angle"] == pytest.approx(gamma, abs=1e-9) and gamma < TOGGLE_ANGLE
    assert peak["toggle"]["joint"] == "B"
    (w,) = rep["warnings"]
    assert w["kind"] == "toggle" and w["driver"] == "cyl" and w["toggle"]["angle"] == pytest.approx(gamma, abs=1e-9)
    assert "Warning: the driver force of cyl peaks at" in lk.check(cylinder_arm(s)).text()
    # NEGATIVE: from s = 1.5 on the smallest angle is far from the toggle: no warning
    assert lk.check(cylinder_arm(1.5)).to_dict()["warnings"] == []


def test_check_json_keeps_every_key_and_adds_the_new_ones(examples, capsys):
    assert main(["check", str(examples / "whitworth_quick_return.yaml"), "--format", "json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert {"dof", "input_range", "input_ranges", "dead_points", "fourbars", "held_at", "units"} <= set(doc)
    assert doc["sliders"][0]["time_ratio"] == pytest.approx(2.0, abs=1e-9)
    assert doc["warnings"] == [] and doc["assembly_gaps"] == {"crank": []}


def test_a_dyad_that_stays_tangent_is_not_a_change_point_at_every_sample():
    """Two rhombus windows (all bars 1): past 180 deg the first folds into a kite, which puts B1 on A0
    and B2's two circles tangent (|A2 - A0| = 2 = 1 + 1) for half a turn.  Before, every sample
    of that half turn was listed as a change point (about 3400); now the run counts by its ends."""
    doc = {
        "format": "linkagekit/1",
        "units": {"length": "m", "angle": "deg"},
        "joints": {"A0": [0, 0], "A1": [1, 0], "A2": [2, 0], "B0": [0, 1], "B1": [1, 1], "B2": [2, 1]},
        "links": {
            "ground": ["A0", "A1", "A2"],
            "c0": ["A0", "B0"],
            "c1": ["A1", "B1"],
            "c2": ["A2", "B2"],
            "k1": ["B0", "B1"],
            "k2": ["B1", "B2"],
        },
        "drivers": [{"link": "c0", "pivot": "A0", "toward": "B0", "angles": {"start": 90, "stop": 450, "step": 1}}],
    }
    rep = lk.check(lk.Mechanism.from_dict(doc))
    dead = rep.dead_points["c0"]
    changes = [d for d in dead if d["kind"] == "change point"]
    assert 1 <= len(changes) <= 3, [round(d["input"], 4) for d in changes]
    assert any(abs(d["input"] - 180) < 1e-6 for d in changes)  # the rhombus's own flat position


def test_a_resting_rocker_has_no_limit_positions_from_rounding(tmp_path, capsys):
    """A rhombus (ground and every side 1) in its pose's mode: a parallelogram for crank in (0, 180) deg, where
    the rocker turns with the crank (rocker angle = crank angle), then folded into a kite, D on A, the rocker
    resting at 180 deg until the crank reaches the ground again.  By hand: no zero crossing of the rocker's speed
    (it rises, then rests), and a swing of 180 deg.  The rounding of the resting rocker's speed (1e-15) used to
    flip sign at hundreds of samples, each listed as a limit position at +-180 deg, and the swing came out 0."""
    from helpers import fourbar_dict

    C = np.exp(1j * np.radians(60.0))
    mech = lk.Mechanism.from_dict(fourbar_dict(0j, 1 + 0j, C, C + 1, C + 0.5 + 0.7j))
    fb = lk.check(mech)["fourbars"][0]
    assert fb["limit_positions"] == []
    assert fb["swing"] == pytest.approx(180.0, abs=0.01)  # the dense samples' range (0.05 deg grid)
    path = tmp_path / "rhombus.json"
    path.write_text(json.dumps(mech.to_dict()))
    assert main(["check", str(path)]) == 0
    out = capsys.readouterr().out
    assert "Limit positions of rocker: none" in out and len(out.splitlines()) < 40


@pytest.mark.parametrize("pose_deg", [0.0, 0.01, 180.0])
def test_a_pose_at_a_change_point_is_said_to_pick_no_mode(tmp_path, capsys, pose_deg):
    """A parallelogram (100 mm ground and coupler, 40 mm cranks) posed flat (0 deg) or folded flat (180 deg): the
    coupler's circle about A and the rocker's about O2 touch there, so the side B lies on is rounding and the sign
    check printed ('B +1') was no choice of the pose's, without a word. By hand: the triangle A-B-O2 has area 0 at
    0 and 180 deg, and sin = 1.7e-4 at 0.01 deg (far above rounding: that pose picks its mode)."""
    c, s = 40 * math.cos(math.radians(pose_deg)), 40 * math.sin(math.radians(pose_deg))
    doc = {
        "units": {"length": "mm", "angle": "deg"},
        "joints": {"O1": [0, 0], "O2": [100, 0], "A": [c, s], "B": [100 + c, s]},
        "links": {"ground": ["O1", "O2"], "crank": ["O1", "A"], "coupler": ["A", "B"], "rocker": ["O2", "B"]},
        "drivers": [{"link": "crank", "pivot": "O1", "toward": "A"}],
    }
    path = tmp_path / "para.json"
    path.write_text(json.dumps(doc))
    flat = pose_deg != 0.01
    assert main(["check", str(path), "--format", "json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    assert rep["signs"]["B"]["at_change_point"] is flat
    assert (rep["warnings"][0] == {"kind": "pose-at-change-point", "joints": ["B"]}) is flat
    assert main(["check", str(path)]) == 0
    lines = capsys.readouterr().out.splitlines()
    k = next(i for i, line in enumerate(lines) if line.startswith("Assembly mode of the reference pose: B"))
    warned = lines[k + 1].startswith("Warning: the reference pose sits at a change point of B")
    assert warned is flat and sum("change point of B" in line for line in lines) == flat  # said once


@pytest.mark.parametrize("span", [30.0, 78.0])
def test_a_transmission_warning_gives_the_file_sweeps_extremes_where_it_does_not_cover_the_range(tmp_path, span):
    """A ``synthesize --partial`` file rocks its crank through part of its range, bounded there; ``check`` warned of
    the transmission angle over the whole range and said nothing of the sweep written (review 14c). The warning
    now gives the extremes over the file's sweep too (against an independent dense sweep: the angle between coupler
    and rocker from the joints, 20001 samples, to 0.01 deg) and says when they lie within the bounds."""
    text = (EXAMPLES / "nongrashof_rocker.yaml").read_text()
    path = tmp_path / "rocks.yaml"
    path.write_text(text.replace("start: -78, stop: 78", f"start: {-span:g}, stop: {span:g}"))
    mech = lk.load(path)
    rep = lk.check(mech)
    (w,) = [w for w in rep.warnings if w["kind"] == "transmission-angle"]
    assert w["max"] > 179.9  # over the range: the rocker's toggles
    res = lk.analyze(mech, {"crank": np.linspace(-span, span, 20001)}, rates=False)
    C, D, B = res.point("C"), res.point("D"), res.point("B")
    mu = np.degrees(np.abs(np.angle((C - D) / (B - D))))
    sw = w["sweep"]
    assert (sw["driver"], sw["from"], sw["to"]) == ("crank", -span, span)
    assert abs(sw["min"] - mu.min()) < 0.01 and abs(sw["max"] - mu.max()) < 0.01
    inside = min(mu.min(), 180 - mu.max()) >= 20
    assert inside == (span == 30.0)
    line = next(x for x in rep.text().splitlines() if x.startswith("Warning: the transmission angle"))
    assert line.endswith(
        f"over the file's sweep (crank from {-span:g} to {span:g} deg) min {sw['min']:.4f}°, max "
        f"{sw['max']:.4f}°" + (": within the bounds there" if inside else "")
    )
    full = lk.check(lk.load(EXAMPLES / "seed003_ex21.yaml"))  # its sweep a turn: nothing more to say
    assert all("sweep" not in w for w in full.warnings) and "file's sweep" not in full.text()


def test_the_sweep_extremes_of_a_cylinder_swept_whole_are_not_added_and_a_sweep_past_the_range_warns_nothing(tmp_path):
    """Review 15a: a cylinder driver's sweep never counted as covering its range (``0 * inf``), so its warning always
    added the sweep's sampled extremes; and a sweep running past the range (samples that do not assemble) raised a
    numpy RuntimeWarning from ``lk.check``."""
    import warnings

    text = (EXAMPLES / "excavator_bucket.yaml").read_text().replace("stroke: [2.15, 2.9]", "stroke: [1.7, 3.3]")
    (tmp_path / "bucket.yaml").write_text(text.split("gravity:")[0])
    bucket = lk.check(lk.load(tmp_path / "bucket.yaml"))
    ws = [w for w in bucket.warnings if w["kind"] == "transmission-angle"]
    lines = [x for x in bucket.text().splitlines() if x.startswith("Warning: the transmission angle")]
    assert ws and all("sweep" not in w for w in ws) and lines and all("file's sweep" not in x for x in lines)
    wide = (EXAMPLES / "nongrashof_rocker.yaml").read_text().replace("start: -78, stop: 78", "start: -100, stop: 50")
    (tmp_path / "wide.yaml").write_text(wide)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        rep = lk.check(lk.load(tmp_path / "wide.yaml"))
    (w,) = [w for w in rep.warnings if w["kind"] == "transmission-angle"]
    assert w["sweep"]["max"] > 170  # the sweep passes the toggle at -78.58 deg: there the angle is 180 deg


def test_the_sweep_extremes_are_over_the_values_the_file_sweeps(tmp_path):
    """Review 15a: the sweep's extremes were taken from ``start`` to ``stop`` even where no step lands on ``stop``:
    ``start: 0, stop: 78.58, step: 1`` sweeps 0 to 78, but the warning said "to 78.58" and gave the maximum at the
    toggle past it (178.86 deg). Now from the first value to the last (an independent dense sweep: 0.01 deg)."""
    text = (EXAMPLES / "nongrashof_rocker.yaml").read_text()
    path = tmp_path / "short.yaml"
    path.write_text(text.replace("start: -78, stop: 78, step: 1", "start: 0, stop: 78.58, step: 1"))
    mech = lk.load(path)
    (w,) = [w for w in lk.check(mech).warnings if w["kind"] == "transmission-angle"]
    res = lk.analyze(mech, {"crank": np.linspace(0.0, 78.0, 7801)}, rates=False)
    C, D, B = res.point("C"), res.point("D"), res.point("B")
    mu = np.degrees(np.abs(np.angle((C - D) / (B - D))))
    assert w["sweep"]["to"] == 78.0 and abs(w["sweep"]["max"] - mu.max()) < 0.01 and w["sweep"]["max"] < 170


def test_a_rocker_turning_back_at_a_change_point_swings_to_it() -> None:
    """A change-point four-bar (ground 40, crank 20, coupler 30, rocker 30: 20 + 40 = 30 + 30) in its pose's mode:
    the rocker falls to 90 deg (a limit position, crank 36.87 deg), then rises to 180 deg at the flat position (crank
    180 deg) and turns back there with its speed not zero. The swing was taken from the limit positions alone: one,
    so 0 deg (review 19c). By an independent solve of the pose's mode at 0.001-deg steps: 90 deg."""
    from helpers import fourbar_dict, fourbar_reference

    r = math.sqrt(80.0)  # D 30 from both C and B, left of C -> B
    pose = {"A": 0j, "B": 40 + 0j, "C": 20j, "D": complex(20 + r, 10 + 2 * r), "P": 20 + 25j}
    fb = lk.check(lk.Mechanism.from_dict(fourbar_dict(*pose.values(), unit="mm")))["fourbars"][0]
    phi = np.radians(np.linspace(0.0, 360.0, 360_001))
    ref = fourbar_reference(pose, phi)
    rocker = np.unwrap(np.angle(ref["D"] - ref["B"]))
    assert np.ptp(np.degrees(rocker)) == pytest.approx(90.0, abs=1e-6)  # the reference itself: 90 to 180 deg
    assert fb["swing"] == pytest.approx(np.ptp(np.degrees(rocker)), abs=1e-6)
    assert [lp["extreme"] for lp in fb["limit_positions"]] == ["min"]


def test_golden_section_minima_are_refined_by_a_parabola() -> None:
    """A change point of a slider's step and a pressure angle's extremes were found by golden section alone: to a few
    1e-8 rad, where the quantity is flat to rounding (review 19c: an isosceles slider-crank's change points at
    90.00000045 and 269.9999995 deg, Whitworth's largest pressure angle at 90.000002 deg). By hand: with crank = rod
    the rod is square to the slide at 90 and 270 deg; Whitworth's lever stands square to the ram's line at 90 deg
    (B at its farthest from it) and lies along it at 210 and 330 deg (the crank's end level with O4, 0.1 below O2)."""
    r = 50.0
    iso = lk.Mechanism.from_dict(
        {
            "format": "linkagekit/1",
            "name": "isosceles slider-crank",
            "units": {"length": "mm", "angle": "deg"},
            "joints": {"O": [0, 0], "A": [r / math.sqrt(2), r / math.sqrt(2)], "B": [r * math.sqrt(2), 0]},
            "links": {"ground": ["O"], "crank": ["O", "A"], "rod": ["A", "B"], "block": ["B"]},
            "sliders": [{"link": "block", "on": "ground", "through": "B", "direction": [1, 0]}],
            "drivers": [{"link": "crank", "pivot": "O", "toward": "A"}],
        }
    )
    dead = [d["input"] for d in lk.check(iso).dead_points["crank"]]
    assert dead == pytest.approx([90.0, 270.0], abs=1e-9)
    pa = lk.check(lk.load(EXAMPLES / "whitworth_quick_return.yaml")).sliders[0]["pressure_angle"]
    assert pa["max_at"] == pytest.approx(90.0, abs=1e-8)
    assert min(abs(pa["min_at"] - 210.0), abs(pa["min_at"] - 330.0)) < 1e-8
    assert pa["max"] == pytest.approx(math.degrees(math.asin(0.15 / 0.5)), abs=1e-9) and pa["min"] == 0.0


def test_a_loops_worst_transmission_angle_is_the_one_synthesize_bounds() -> None:
    """``check`` printed the raw min and max of the transmission angle mu, ``synthesize`` the smallest of mu and 180 -
    mu, and a user saw two minima that disagree (review 19c: 64.8 against 53.67 deg). ``check`` now also gives that
    figure, ``worst``. Andrews' loop O-P-E-B: mu in [82.6, 124.8] deg, so its worst is 180 - max. By an independent
    sampling of the angle at E between the coupler E-P and the rocker E-B, every 0.01 deg of the crank."""
    mech = lk.load(EXAMPLES / "iftomm_a03_andrews.yaml")
    ta = next(fb for fb in lk.check(mech).fourbars if fb["joints"] == ["O", "P", "E", "B"])["transmission_angle"]
    lo, hi = mech.drivers[0].sweep.values()[[0, -1]]
    res = lk.analyze(mech, {mech.drivers[0].name: np.arange(lo, hi + 1e-9, 0.01)}, rates=False, dynamics=False)
    E, P, B = (res.point(j) for j in "EPB")
    mu = np.degrees(np.abs(np.angle((P - E) / (B - E))))
    worst = np.min(np.minimum(mu, 180.0 - mu))
    assert ta["worst"] == pytest.approx(worst, abs=1e-5) and ta["worst"] == pytest.approx(180.0 - ta["max"], abs=1e-12)
    assert ta["max"] == pytest.approx(np.max(mu), abs=1e-5) and ta["worst"] < ta["min"]


def test_a_transmission_angle_down_to_0_at_a_change_point_is_found_there() -> None:
    """Ground 4, crank 2, coupler 1, rocker 3: at crank 0 the crank's end is 2 from O2, the rocker less the coupler,
    so they fold in line there: the transmission angle is 0 at crank 0 (by hand). The bisection on its slope ended
    where the rates next to the change point are flagged singular: min 0.0001 deg at -0.000035 deg; the sweep's
    figure came from its samples alone, 0.0272 deg (review 19b)."""
    doc = {
        "format": "linkagekit/1",
        "name": "folds at crank 0",
        "units": {"length": "mm", "angle": "deg"},
        "joints": {"O1": [0, 0], "O2": [4, 0], "A": [1, math.sqrt(3)], "B": [1.9082482904638631, 2.1504824541606125]},
        "links": {
            "ground": ["O1", "O2"],
            "crank": {"joints": ["O1", "A"], "lengths": {"O1-A": 2}},
            "coupler": {"joints": ["A", "B"], "lengths": {"A-B": 1}},
            "rocker": {"joints": ["O2", "B"], "lengths": {"O2-B": 3}},
        },
        "drivers": [{"link": "crank", "pivot": "O1", "toward": "A", "angles": {"start": -60, "stop": 70, "step": 1}}],
    }
    rep = lk.check(lk.Mechanism.from_dict(doc))
    ta = rep.fourbars[0]["transmission_angle"]
    assert ta["min"] < 1e-7 and abs(ta["min_at"]) < 1e-8, ta
    warning = next(w for w in rep.warnings if w["kind"] == "transmission-angle")
    assert warning["sweep"]["min"] < 1e-7 and warning["sweep"]["from"] == -60.0 and warning["sweep"]["to"] == 70.0


def test_with_several_intervals_the_poses_is_named(capsys) -> None:
    """A Grashof double rocker (ground 4, crank 3, coupler 1.5, rocker 3.5; 1.5 + 4 < 3 + 3.5) posed at crank 60
    deg assembles with its sign for crank in [28.96, 90] and [270, 331.04] deg: by hand, crank 90 puts A 5 from O2,
    coupler and rocker stretched, and crank 270 likewise. The second interval is the other circuit; nothing said
    which one the pose is in (review 19b)."""
    doc = {
        "format": "linkagekit/1",
        "name": "double rocker",
        "units": {"length": "mm", "angle": "deg"},
        "joints": {
            "O1": [0, 0],
            "O2": [4, 0],
            "A": [1.5, 2.598076211353316],
            "B": [2.8269230769230775, 3.297558268256132],
        },
        "links": {
            "ground": ["O1", "O2"],
            "crank": {"joints": ["O1", "A"], "lengths": {"O1-A": 3}},
            "coupler": {"joints": ["A", "B"], "lengths": {"A-B": 1.5}},
            "rocker": {"joints": ["O2", "B"], "lengths": {"O2-B": 3.5}},
        },
        "drivers": [{"link": "crank", "pivot": "O1", "toward": "A"}],
    }
    rep = lk.check(lk.Mechanism.from_dict(doc))
    (a, b), (c, d) = rep.input_ranges["crank"]
    assert (b, c) == pytest.approx((90.0, 270.0), abs=1e-9) and rep.to_dict()["pose_input"] == pytest.approx(
        {"crank": 60.0}, abs=1e-9
    )
    from linkagekit.checks import check_text

    text = check_text(rep.to_dict())
    assert f"  the pose (crank = 60.000000 deg) is in [{math.ceil(a * 1e6) / 1e6:.6f}, 90.000000]: moving the" in text


def test_the_printed_range_ends_assemble() -> None:
    """Seed 003 example 2.1's range ends, 86.7827301063 and 273.2172698937 deg (the law of cosines), printed to the
    nearest sixth decimal, 86.782730 and 273.217270, did not assemble when given back to analyze (review 19b); they
    are rounded into the range. A round end (0 and 360 deg) stays as it is."""
    mech = lk.load(EXAMPLES / "seed003_ex21.yaml")
    line = next(x for x in lk.check(mech).text().splitlines() if x.startswith("Assembles"))
    assert line == "Assembles for crank in [86.782731, 273.217269] deg"
    assert lk.analyze(mech, {"crank": [86.782731, 273.217269]}, rates=False).assembled.all()
    assert not lk.analyze(mech, {"crank": [86.782730, 273.217270]}, rates=False).assembled.any()
    line = next(x for x in lk.check(lk.load(EXAMPLES / "seed000_fourbar.yaml")).text().splitlines() if "Assembles" in x)
    assert line == "Assembles for crank in [0.000000, 360.000000] deg"


def test_a_stretch_where_a_dyad_stays_flat_starts_where_it_does() -> None:
    """IFToMM's double four-bar (three parallel cranks of 1, couplers of 1, 1 apart) in its pose's mode folds into a
    kite at crank 180 deg and its second dyad stays stretched until 360: by hand the change points are at 0 and
    180 deg and loop 2's largest transmission angle, 180 deg, starts at 180. Golden section on the flat stretch put
    them anywhere on it: 180.049963 deg and 180.05 (review 19b)."""
    rep = lk.check(lk.load(EXAMPLES / "iftomm_a02_double_fourbar.yaml"))
    dead = sorted((d["joint"], d["input"]) for d in rep.dead_points["crank0"])
    assert [j for j, _ in dead] == ["B1", "B1", "B2"]  # both dyads at 180 (one was dropped as the other's: 19g)
    assert [v for _, v in dead] == pytest.approx([0.0, 180.0, 180.0], abs=1e-8)
    second = rep.fourbars[1]["transmission_angle"]
    assert second["max"] == pytest.approx(180.0, abs=1e-9) and second["max_at"] == pytest.approx(180.0, abs=1e-8)


def test_a_slider_turning_back_at_a_change_point_strokes_to_it() -> None:
    """An offset slider-crank (crank 1, rod 1.5, offset 0.5 = rod - crank) turns back at its change point, the rod
    square to the slide, with its speed not zero: the stroke came from the samples and the limit positions alone,
    4.8e-5 m short where the change point falls between samples (the slide turned 13.7123 deg: crank 283.7123 deg;
    review 19e). Against an independent sampling of the block's place along its slide at 0.0001-deg steps."""
    r, rod, e = 1.0, 1.5, 0.5
    u = np.exp(1j * np.radians(13.7123))
    A = r * np.exp(1j * np.radians(30.0))
    xa, ya = (np.conj(u) * A).real, (np.conj(u) * A).imag
    B = u * complex(xa + math.sqrt(rod**2 - (e - ya) ** 2), e)
    doc = {
        "format": "linkagekit/1",
        "name": "tilted offset slider-crank",
        "units": {"length": "m", "angle": "deg"},
        "joints": {"O": [0, 0], "A": [A.real, A.imag], "B": [B.real, B.imag]},
        "links": {
            "ground": ["O"],
            "crank": {"joints": ["O", "A"], "lengths": {"O-A": r}},
            "rod": {"joints": ["A", "B"], "lengths": {"A-B": rod}},
            "block": ["B"],
        },
        "drivers": [{"link": "crank", "pivot": "O", "toward": "A"}],
        "sliders": [{"link": "block", "on": "ground", "through": "B", "direction": [u.real, u.imag]}],
    }
    rep = lk.check(lk.Mechanism.from_dict(doc))
    z = r * np.exp(1j * np.radians(np.linspace(0.0, 360.0, 3_600_001)))
    along, across = (np.conj(u) * z).real, (np.conj(u) * z).imag
    place = along + np.sqrt(np.maximum(rod**2 - (e - across) ** 2, 0.0))
    assert rep.sliders[0]["stroke"] == pytest.approx(np.ptp(place), abs=1e-9)
    assert rep.dead_points["crank"][0]["input"] == pytest.approx(283.7123, abs=1e-8)


def test_a_sliders_stroke_over_the_poses_interval() -> None:
    """A crank of 2 and a rod of 1, the slide 0.3 off the crank's pivot: it assembles in two intervals, one per way
    round, and the stroke (4.86 m) spanned both, where the pose's interval travels 1.47 m (review 19e). The stroke
    over the pose's interval is given beside it: by an independent sampling of B = A + sqrt(1 - (0.3 - y_A)^2) over
    that interval's exact ends."""
    doc = {
        "format": "linkagekit/1",
        "name": "long crank",
        "units": {"length": "m", "angle": "deg"},
        "joints": {"O": [0, 0], "A": [1.8793852415718169, 0.6840402866513374], "B": [2.802701578603042, 0.3]},
        "links": {
            "ground": ["O"],
            "crank": {"joints": ["O", "A"], "lengths": {"O-A": 2}},
            "rod": {"joints": ["A", "B"], "lengths": {"A-B": 1}},
            "block": ["B"],
        },
        "drivers": [{"link": "crank", "pivot": "O", "toward": "A"}],
        "sliders": [{"link": "block", "on": "ground", "through": "B", "direction": [1, 0]}],
    }
    rep = lk.check(lk.Mechanism.from_dict(doc))
    (a, b), _ = rep.input_ranges["crank"]
    t = np.radians(np.linspace(a, b, 2_000_001))
    place = 2 * np.cos(t) + np.sqrt(np.maximum(1 - (0.3 - 2 * np.sin(t)) ** 2, 0.0))
    assert rep.sliders[0]["pose_stroke"] == pytest.approx(np.ptp(place), abs=1e-9)
    assert rep.sliders[0]["stroke"] > 3 * rep.sliders[0]["pose_stroke"]
    from linkagekit.checks import check_text

    assert f"({rep.sliders[0]['pose_stroke']:.6f} m over the pose's interval)" in check_text(rep.to_dict())
