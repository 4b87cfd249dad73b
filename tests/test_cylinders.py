"""Cylinder drivers, the two-lines step (Scotch yoke) and their examples, against closed forms.

Every reference here is written in the test, from another formulation than the solver's:
the law of cosines for the boom angle from the boom cylinder's length and the chain rule
for its rates; ``x = r cos(theta)`` for the Scotch yoke; the slotted lever's angle
``arg(A - O4)`` and the ram on its line for the Whitworth mechanism; fourth-order finite
differences of positions for every velocity and acceleration (hypothesis draws random
mechanisms of every new step kind); virtual work for the cylinders' static forces.

Tolerances (relative to the largest value of the quantity compared, or to the mechanism's
size): positions 1e-12, closed-form velocities 1e-11 and accelerations 1e-10; finite
differences 1e-7 for velocities and 1e-5 for accelerations (their own truncation and
rounding); virtual work 1e-6 (central differences of the potential energy).
"""

from __future__ import annotations

import json
import math
import zlib
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import linkagekit as lk
from helpers import accelerations, by_cosines, points, rigid, side, velocities
from linkagekit.api import prepare
from linkagekit.cli import main

ROOT = Path(__file__).resolve().parents[1]
EXCAVATOR = ROOT / "examples" / "excavator_boom.yaml"
YOKE = ROOT / "examples" / "scotch_yoke.yaml"
WHITWORTH = ROOT / "examples" / "whitworth_quick_return.yaml"

#: finite-difference steps, coarse and fine: rounding ~ eps |z| / h (velocities), eps |z| / h^2
#: (accelerations) for mechanisms up to 20 long; truncation ~ h^4 (see fd_check)
H_V = (1e-5, 3e-6)
H_A = (3e-4, 1e-4)


def run(args, capsys):
    code = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return code, out, err


def max_rel(a, b, floor=1e-300):
    """max |a - b| over max(max |b|, floor)."""
    a, b = np.asarray(a), np.asarray(b)
    return float(np.max(np.abs(a - b)) / max(float(np.max(np.abs(b))), floor))


# ---------------------------------------------------------------------- the excavator's boom
def boom_closed_form(mech, s, ds, dds):
    """Boom joints, velocities and accelerations from the boom cylinder's length s(t) (law of cosines).

    The triangle O (boom pivot), C1 (cylinder base), B1 (cylinder rod eye on the boom) has
    |O C1| = d, |O B1| = rb and |C1 B1| = s: the angle at O is gamma = acos((d^2 + rb^2 - s^2) / (2 d rb)),
    B1 lies at the angle arg(C1 - O) + t gamma (t the pose's side), and every boom point P at
    |P - O| e^{i(theta_B1 + delta_P)}.  Chain rule: gamma' = s / (d rb sin gamma),
    gamma'' = (1 - s cos(gamma) gamma' / sin(gamma)) / (d rb sin gamma); omega = t gamma' ds,
    alpha = t (gamma'' ds^2 + gamma' dds).
    """
    J, S = mech.joints, mech.link("boom").shape  # the boom's shape: its lengths, O-T given exactly
    o, c1, b1 = J["O"], J["C1"], J["B1"]
    d, rb = abs(c1 - o), abs(S["B1"] - S["O"])
    t = side(o, c1, b1)
    cosg = (d * d + rb * rb - s * s) / (2 * d * rb)
    g = np.arccos(cosg)
    sing = np.sin(g)
    g1 = s / (d * rb * sing)
    g2 = (1 - s * cosg * g1 / sing) / (d * rb * sing)
    theta = np.angle(c1 - o) + t * g
    omega = t * g1 * ds
    alpha = t * (g2 * ds * ds + g1 * dds)
    out = {}
    for j in ("B1", "T", "B2"):
        delta = np.angle((S[j] - S["O"]) / (S["B1"] - S["O"]))
        z = o + abs(S[j] - S["O"]) * np.exp(1j * (theta + delta))
        out[j] = (z, 1j * omega * (z - o), (1j * alpha - omega**2) * (z - o))
    return out, theta, omega, alpha


def test_boom_against_the_law_of_cosines_over_the_whole_stroke():
    mech = lk.load(EXCAVATOR)
    s = np.linspace(1.8, 2.9, 1101)  # the boom cylinder's stroke, ends included
    ds, dds = 0.13, -0.4
    res = lk.analyze(
        mech,
        {"boom_cylinder": s},
        speed={"boom_cylinder": ds, "stick_cylinder": 0.0},
        acceleration={"boom_cylinder": dds, "stick_cylinder": 0.0},
    )
    assert res.assembled.all() and not res.singular.any()
    ref, theta, omega, alpha = boom_closed_form(mech, s, ds, dds)
    errs = {"z": 0.0, "v": 0.0, "a": 0.0}
    for j, (z, v, a) in ref.items():
        errs["z"] = max(errs["z"], float(np.max(np.abs(res.point(j) - z))) / 5.7)
        errs["v"] = max(errs["v"], max_rel(res.velocity(j), v))
        errs["a"] = max(errs["a"], max_rel(res.acceleration(j), a))
    assert errs["z"] <= 1e-12 and errs["v"] <= 1e-11 and errs["a"] <= 1e-10, errs
    assert max_rel(res.omega("boom"), omega) <= 1e-11
    assert max_rel(res.alpha("boom"), alpha) <= 1e-10
    # the link angle (first joint O -> second joint T)
    S = mech.link("boom").shape
    th_t = theta + np.angle((S["T"] - S["O"]) / (S["B1"] - S["O"]))
    assert np.max(np.abs(np.angle(np.exp(1j * (np.radians(res.angle("boom")) - th_t))))) <= 1e-12
    # the cylinder's length is its input
    assert np.max(np.abs(np.abs(res.point("B1") - res.point("C1")) - s)) <= 1e-12 * 2.9
    # the stick cylinder held at its pose length: S1 by the law of cosines from T and B2
    rs, s2 = mech.link("stick").length("T", "S1"), abs(mech.joints["S1"] - mech.joints["B2"])
    t2 = side(mech.joints["T"], mech.joints["B2"], mech.joints["S1"])
    S1 = by_cosines(res.point("T"), res.point("B2"), rs, s2, t2)
    assert np.max(np.abs(res.point("S1") - S1)) <= 1e-12 * 5.7
    S = mech.link("stick").shape
    E = rigid(res.point("T"), res.point("S1"), S["E"], S["T"], S["S1"])
    assert np.max(np.abs(res.point("E") - E)) <= 1e-12 * 5.7


def test_samples_beyond_the_stroke_do_not_assemble(tmp_path, capsys):
    mech = lk.load(EXCAVATOR)
    s = [1.7, 1.8, 2.35, 2.9, 2.95, -1.0, 0.0]
    res = lk.analyze(mech, {"boom_cylinder": s})
    assert res.assembled.tolist() == [False, True, True, True, False, False, False]
    bad = ~res.assembled
    assert np.all(np.isnan(points(res)[:, bad])) and np.all(np.isnan(velocities(res)[:, bad]))
    assert np.all(np.isnan(accelerations(res)[:, bad])) and np.all(
        np.isnan(res.forces.driver_force["boom_cylinder"][bad])
    )
    doc = res.to_dict()
    assert doc["joints"]["B1"]["x"][0] is None and doc["joints"]["O"]["x"][0] is None
    assert doc["joints"]["B1"]["x"][1] is not None
    code, out, err = run(
        [
            "analyze",
            EXCAVATOR,
            "--at",
            "boom_cylinder=1.7,2.35,2.95",
            "--at",
            "stick_cylinder=3,3,3",
            "--format",
            "json",
        ],
        capsys,
    )
    assert code == 0 and err == ""
    doc = json.loads(out)
    assert doc["assembled"] == [False, True, False]
    assert doc["joints"]["T"]["vx"] == [None, doc["joints"]["T"]["vx"][1], None] and doc["joints"]["T"]["vx"][1]
    assert doc["driver_force"]["stick_cylinder"][0] is None
    # the second cylinder's stroke too, and a stroke end is inside
    res = lk.analyze(mech, {"boom_cylinder": [2.3] * 4, "stick_cylinder": [2.49, 2.5, 3.4, 3.41]})
    assert res.assembled.tolist() == [False, True, True, False]


def test_the_assembly_range_of_a_cylinder_is_its_stroke_or_the_triangle():
    mech = lk.load(EXCAVATOR)
    rep = lk.check(mech)
    assert np.allclose(rep.input_ranges["boom_cylinder"], [[1.8, 2.9]], rtol=0, atol=1e-9)
    assert np.allclose(rep.input_ranges["stick_cylinder"], [[2.5, 3.4]], rtol=0, atol=1e-9)
    assert all("stroke" in dp["detail"] for dp in rep.dead_points["boom_cylinder"])
    # without a stroke the boom turns until O, C1 and B1 are in line: s in [|d - rb|, d + rb]
    doc = mech.to_dict()
    for drv in doc["drivers"]:
        drv.pop("stroke")
    free = lk.Mechanism.from_dict(doc)
    J = free.joints
    d, rb = abs(J["C1"] - J["O"]), abs(J["B1"] - J["O"])
    got = lk.check(free).input_ranges["boom_cylinder"]
    assert np.allclose(got, [[abs(d - rb), d + rb]], rtol=0, atol=1e-9)
    details = [dp["detail"] for dp in lk.check(free).dead_points["boom_cylinder"]]
    assert details and all("in line with boom" in t for t in details), details


def test_a_batch_of_boom_designs_equals_one_solve_per_design():
    mech = lk.load(EXCAVATOR)
    rng = np.random.default_rng(7)
    poses = mech.pose_array() * rng.uniform(0.985, 1.015, (5, 1, 1)) + rng.normal(0, 0.005, (5, len(mech.joints), 2))
    inputs = {"boom_cylinder": np.linspace(1.85, 2.85, 41), "stick_cylinder": np.linspace(2.6, 3.3, 41)}
    speed = {"boom_cylinder": 0.1, "stick_cylinder": -0.05}
    batch = lk.analyze(mech, inputs, poses=poses, speed=speed)
    assert batch.xy("E").shape == (5, 41, 2)
    for i in range(5):
        one = lk.analyze(mech.with_pose(poses[i]), inputs, speed=speed)
        assert one.assembled.any()
        np.testing.assert_array_equal(batch.assembled[i], one.assembled)
        for j in mech.joint_names:
            for get in ("point", "velocity", "acceleration"):
                np.testing.assert_allclose(
                    getattr(batch, get)(j)[i], getattr(one, get)(j), rtol=0, atol=1e-12 * 100, err_msg=f"{get} {j}"
                )
        for name in ("boom_cylinder", "stick_cylinder"):
            np.testing.assert_allclose(
                batch.forces.driver_force[name][i], one.forces.driver_force[name], rtol=1e-9, atol=1e-6
            )


def test_static_cylinder_forces_by_virtual_work():
    """F_1 ds_1 + F_2 ds_2 + sum m g . dz_G = 0 for every virtual motion: F_k = dV/ds_k, V = -sum m g . z_G."""
    mech = lk.load(EXCAVATOR)
    g = mech.gravity
    s1 = np.array([1.9, 2.2, 2.5, 2.8])
    s2 = np.array([2.6, 3.3, 2.9, 3.1])
    res = lk.analyze(mech, {"boom_cylinder": s1, "stick_cylinder": s2}, static=True)

    def potential(a, b):
        r = lk.analyze(mech, {"boom_cylinder": a, "stick_cylinder": b}, rates=False)
        V = 0.0
        for ln in (mech.link("boom"), mech.link("stick")):
            j0, j1 = ln.joints[:2]
            zg = rigid(r.point(j0), r.point(j1), ln.cg, ln.shape[j0], ln.shape[j1])
            V = V - ln.mass * (g.real * zg.real + g.imag * zg.imag)
        return V

    h = 1e-6
    dv1 = (potential(s1 + h, s2) - potential(s1 - h, s2)) / (2 * h)
    dv2 = (potential(s1, s2 + h) - potential(s1, s2 - h)) / (2 * h)
    f = res.forces.driver_force
    assert max_rel(f["boom_cylinder"], dv1) <= 1e-6
    assert max_rel(f["stick_cylinder"], dv2) <= 1e-6
    assert np.all(f["boom_cylinder"] > 0)  # the boom cylinder pushes to hold the boom up
    # dynamic: the input power is the rate of the energy (kinetic + potential) along a motion
    ds = {"boom_cylinder": 0.12, "stick_cylinder": -0.08}
    dyn = lk.analyze(mech, {"boom_cylinder": s1, "stick_cylinder": s2}, speed=ds)
    p = dyn.forces.input_power
    assert (
        max_rel(p, dyn.forces.driver_force["boom_cylinder"] * 0.12 - dyn.forces.driver_force["stick_cylinder"] * 0.08)
        <= 1e-12
    )

    def energy(t):
        a, b = s1 + 0.12 * t, s2 - 0.08 * t
        r = lk.analyze(mech, {"boom_cylinder": a, "stick_cylinder": b}, speed=ds)
        kin = 0.0
        for ln in (mech.link("boom"), mech.link("stick")):
            j0, j1 = ln.joints[:2]
            rho = (ln.cg - ln.shape[j0]) / (ln.shape[j1] - ln.shape[j0])
            vg = r.velocity(j0) + rho * (r.velocity(j1) - r.velocity(j0))
            kin = kin + 0.5 * ln.mass * np.abs(vg) ** 2 + 0.5 * ln.inertia * r.omega(ln.name) ** 2
        return kin + potential(a, b)

    h = 1e-4
    dedt = (-energy(2 * h) + 8 * energy(h) - 8 * energy(-h) + energy(-2 * h)) / (12 * h)
    assert max_rel(p, dedt) <= 1e-6


# ---------------------------------------------------------------------- the Scotch yoke
def test_scotch_yoke_is_simple_harmonic():
    mech = lk.load(YOKE)
    r = mech.link("crank").length("O", "A")
    th = np.radians(np.arange(0.0, 360.0, 0.5))
    w, al = 10.0, 3.0
    res = lk.analyze(mech, np.degrees(th), speed=w, acceleration=al)
    assert res.assembled.all() and not res.singular.any()
    x, v, a = r * np.cos(th), -r * w * np.sin(th), -r * w * w * np.cos(th) - r * al * np.sin(th)
    assert np.max(np.abs(res.x("Y") - x)) <= 1e-15 and np.max(np.abs(res.y("Y"))) == 0.0
    assert np.max(np.abs(res.x("R") - (x + 0.2))) <= 1e-15
    assert np.max(np.abs(res.velocity("Y") - v)) <= 1e-14 * r * w
    assert np.max(np.abs(res.acceleration("R") - a)) <= 1e-14 * r * w * w
    assert np.all(res.omega("yoke") == 0) and np.all(res.angle("yoke") == 0)
    # the pin's block rides up and down the slot, upright
    assert np.max(np.abs(res.y("A") - r * np.sin(th))) <= 1e-15
    assert np.allclose(res.angle("pin_block"), 90.0, rtol=0, atol=1e-12)


def test_a_scotch_yoke_driven_by_its_yoke():
    """A slider driver on the yoke turns the crank: theta = acos(x / r) on the pose's side."""
    doc = lk.load(YOKE).to_dict()
    doc["drivers"] = [{"slider": 0, "displacements": {"start": -0.08, "stop": 0.0, "step": 0.001}, "speed": 0.3}]
    mech = lk.Mechanism.from_dict(doc)
    r = mech.link("crank").length("O", "A")
    x0 = mech.joints["Y"].real
    u = np.linspace(-0.085, 0.0, 86)
    res = lk.analyze(mech, u, speed=0.3, acceleration=0.0)
    x = x0 + u
    ok = np.abs(x) < r * (1 - 1e-9)
    assert np.array_equal(res.assembled, np.abs(x) <= r * (1 + 1e-12))
    th = np.arccos(x[ok] / r)  # the pose has A above the x axis
    assert np.max(np.abs(res.point("A")[ok] - r * np.exp(1j * th))) <= 1e-12 * r
    # v_A: the crank turns at dtheta/dt = -dx/dt / (r sin theta)
    dth = -0.3 / (r * np.sin(th))
    assert max_rel(res.velocity("A")[ok], 1j * dth * r * np.exp(1j * th)) <= 1e-10


# ---------------------------------------------------------------------- Whitworth
def test_whitworth_quick_return_against_its_closed_form():
    mech = lk.load(WHITWORTH)
    J = mech.joints
    r = mech.link("crank").length("O2", "A")
    lb, rod = mech.link("lever").length("O4", "B"), mech.link("rod").length("B", "C")
    yl = J["C"].imag
    th = np.radians(np.arange(0.0, 360.0, 0.25))
    w, al = 5.0, -2.0
    res = lk.analyze(mech, np.degrees(th), speed=w, acceleration=al)
    assert res.assembled.all() and not res.singular.any()
    e = np.exp(1j * th)
    q = J["O2"] + r * e - J["O4"]  # A - O4 along the slot: the lever's angle is arg(q)
    q1, q2 = 1j * r * e, -r * e  # dq/dtheta, d2q/dtheta2
    phi = np.angle(q)
    f1 = (q1 / q).imag  # dphi/dtheta = Im(q'/q), d2phi/dtheta2 = Im(q''/q - (q'/q)^2)
    f2 = (q2 / q - (q1 / q) ** 2).imag
    wl, al_l = f1 * w, f2 * w * w + f1 * al
    assert max_rel(res.omega("lever"), wl) <= 1e-11 and max_rel(res.alpha("lever"), al_l) <= 1e-10
    u = -np.exp(1j * phi)  # B is on the far side of O4 from A
    B = J["O4"] + lb * u
    vB, aB = lb * 1j * wl * u, lb * (1j * al_l - wl**2) * u
    assert np.max(np.abs(res.point("B") - B)) <= 1e-15 and max_rel(res.velocity("B"), vB) <= 1e-11
    assert max_rel(res.acceleration("B"), aB) <= 1e-10
    h = yl - B.imag  # the ram: x_C = x_B + R, R = sqrt(rod^2 - h^2)
    R = np.sqrt(rod**2 - h**2)
    dR = h * vB.imag / R
    ddR = (-(vB.imag**2) + h * aB.imag) / R - h * h * vB.imag**2 / R**3
    assert np.max(np.abs(res.point("C") - (B.real + R + 1j * yl))) <= 1e-15
    assert max_rel(res.velocity("C"), vB.real + dR) <= 1e-11
    assert max_rel(res.acceleration("C"), aB.real + ddR) <= 1e-10
    # the quick return: the ram's strokes take unequal crank turns (x_C extremes where v_C = 0)
    xc = res.x("C")
    lo, hi = int(np.argmin(xc)), int(np.argmax(xc))
    forward = (th[hi] - th[lo]) % (2 * math.pi)
    assert min(forward, 2 * math.pi - forward) < 0.8 * math.pi


# ---------------------------------------------------------------------- finite differences
def fd_check(mech, rng):
    """Velocities and accelerations (joints and links) against fourth-order finite differences.

    Each is compared with differences at two steps, a coarse and a fine one, and must agree
    with the better of the two: near a singular position (|condition| down to 0.1, with
    accelerations 10^4 times the mechanism's size) the coarse step's truncation dominates,
    elsewhere the fine step's rounding.
    """
    nd = len(mech.drivers)
    factor = np.array([mech.angle_to_rad if d.kind == "angle" else 1.0 for d in mech.drivers])
    q0 = prepare(mech).pose_inputs[:, 0] / factor
    q0 = q0 + rng.uniform(-1, 1, nd) * np.where(factor < 1, 10.0, 0.02 * mech.length_scale)
    w, al = rng.uniform(-2, 2, nd), rng.uniform(-2, 2, nd)

    def at(t):
        q = q0 + (w * t + 0.5 * al * t * t) / factor
        return {d.name: [q[i]] for i, d in enumerate(mech.drivers)}

    names = [d.name for d in mech.drivers]
    res = lk.analyze(
        mech, at(0.0), speed=dict(zip(names, w, strict=True)), acceleration=dict(zip(names, al, strict=True))
    )
    if not res.assembled[0] or np.min(np.abs(res.condition)) < 0.1:
        return False
    steps = (*H_V, *H_A)
    runs = {h: [lk.analyze(mech, at(k * h)) for k in (-2, -1, 0, 1, 2)] for h in steps}
    z = {h: [points(r)[:, 0] for r in runs[h]] for h in steps}
    if not all(np.all(np.isfinite(x)) for h in steps for x in z[h]):
        return False

    def d1(f, h):
        return (-f[4] + 8 * f[3] - 8 * f[1] + f[0]) / (12 * h)

    def d2(f, h):
        return (-f[4] + 16 * f[3] - 30 * f[2] + 16 * f[1] - f[0]) / (12 * h * h)

    def err(x, ref, floor):
        return min(np.max(np.abs(x - r)) / max(np.max(np.abs(x)), floor) for r in ref)

    v, a = velocities(res)[:, 0], accelerations(res)[:, 0]
    assert err(v, [d1(z[h], h) for h in H_V], 1e-3) <= 1e-7
    assert err(a, [d2(z[h], h) for h in H_A], 1.0) <= 1e-5
    for ln in mech.links:
        th = {h: np.unwrap([runs[h][k].angle(ln.name)[0] * mech.angle_to_rad for k in range(5)]) for h in steps}
        assert err(res.omega(ln.name)[0], [d1(th[h], h) for h in H_V], 1.0) <= 1e-7, ln.name
        assert err(res.alpha(ln.name)[0], [d2(th[h], h) for h in H_A], 1.0) <= 1e-5, ln.name
    return True


def _pts(rng, names):
    return {n: [float(x) for x in rng.uniform(-10, 10, 2)] for n in names}


def cylinder_rocker(rng):
    """A rocker O-B-P pushed by a cylinder C-B (CylinderDyad, fixed far end)."""
    return {
        "joints": _pts(rng, ["O", "C", "B", "P"]),
        "links": {"ground": ["O", "C"], "rocker": ["O", "B", "P"]},
        "drivers": [{"cylinder": ["C", "B"]}],
    }


def cylinder_fourbar(rng):
    """A cylinder drives the input link of a four-bar (CylinderDyad, then a Dyad)."""
    return {
        "joints": _pts(rng, ["O", "C", "Q", "B", "D", "P"]),
        "links": {"ground": ["O", "C", "Q"], "input": ["O", "B"], "coupler": ["B", "D", "P"], "rocker": ["Q", "D"]},
        "drivers": [{"cylinder": ["C", "B"]}],
    }


def cylinder_between_moving_links(rng):
    """A crank and a cylinder from its tip to a rocker (CylinderDyad with a moving far end): two drivers."""
    return {
        "joints": _pts(rng, ["O", "Q", "A", "B", "P"]),
        "links": {"ground": ["O", "Q"], "crank": ["O", "A"], "rocker": ["Q", "B", "P"]},
        "drivers": [{"link": "crank", "pivot": "O", "toward": "A"}, {"cylinder": ["A", "B"], "name": "cyl"}],
    }


def cylinder_block(rng):
    """A cylinder pushes a block along the ground; a rod from the block drives a rocker (CylinderLine)."""
    p = _pts(rng, ["C", "O", "B", "E"])
    return {
        "joints": p,
        "links": {"ground": ["C", "O"], "block": ["B"], "rod": ["B", "E"], "rocker": ["O", "E"]},
        "sliders": [{"link": "block", "on": "ground", "through": "B", "direction": list(rng.normal(size=2))}],
        "drivers": [{"cylinder": ["C", "B"]}],
    }


def cylinder_block_on_crank(rng):
    """A block slides on a driven crank and a cylinder from the ground pushes it (CylinderLine on a moving guide)."""
    return {
        "joints": _pts(rng, ["O", "C", "G", "B"]),
        "links": {"ground": ["O", "C"], "crank": ["O", "G"], "block": ["B"]},
        "sliders": [{"link": "block", "on": "crank", "through": "B", "direction": list(rng.normal(size=2))}],
        "drivers": [{"link": "crank", "pivot": "O", "toward": "G"}, {"cylinder": ["C", "B"]}],
    }


def yoke_on_turning_guide(rng):
    """A yoke slides on a driven guide; a crank pin's block slides in the yoke (LineLine on a moving guide)."""
    d1, d2 = rng.normal(size=2), rng.normal(size=2)
    return {
        "joints": _pts(rng, ["O", "Q", "A", "G", "Y", "R"]),
        "links": {"ground": ["O", "Q"], "crank": ["O", "A"], "guide": ["Q", "G"], "yoke": ["Y", "R"], "pin": ["A"]},
        "sliders": [
            {"link": "yoke", "on": "guide", "through": "Y", "direction": list(d1)},
            {"link": "pin", "on": "yoke", "through": "A", "direction": list(d2)},
        ],
        "drivers": [{"link": "crank", "pivot": "O", "toward": "A"}, {"link": "guide", "pivot": "Q", "toward": "G"}],
    }


KINDS = {
    "cylinder_rocker": (cylinder_rocker, "CylinderDyad"),
    "cylinder_fourbar": (cylinder_fourbar, "CylinderDyad"),
    "cylinder_between_moving_links": (cylinder_between_moving_links, "CylinderDyad"),
    "cylinder_block": (cylinder_block, "CylinderLine"),
    "cylinder_block_on_crank": (cylinder_block_on_crank, "CylinderLine"),
    "yoke_on_turning_guide": (yoke_on_turning_guide, "LineLine"),
}


@pytest.mark.parametrize("kind", sorted(KINDS))
@settings(max_examples=12, deadline=None, derandomize=True, suppress_health_check=list(HealthCheck))
@given(seed=st.integers(0, 2**32 - 1))
def test_rates_of_the_new_steps_match_finite_differences(kind, seed):
    build, step = KINDS[kind]
    rng = np.random.default_rng([seed, zlib.crc32(kind.encode())])
    for _ in range(60):  # the first random mechanism that assembles away from a singular position
        try:
            mech = lk.Mechanism.from_dict(build(rng))
            steps = {type(s).__name__ for s in prepare(mech).plan.steps}
        except lk.LinkageError:
            continue
        assert step in steps
        if fd_check(mech, rng):
            return
    pytest.fail(f"no random {kind} to check")


@pytest.mark.parametrize("path", [EXCAVATOR, YOKE, WHITWORTH], ids=lambda p: p.stem)
def test_the_examples_rates_match_finite_differences(path):
    mech = lk.load(path)
    rng = np.random.default_rng(zlib.crc32(path.stem.encode()))
    checked = sum(fd_check(mech, rng) for _ in range(10))
    assert checked >= 5


# ---------------------------------------------------------------------- files and commands
def test_cylinder_drivers_round_trip(tmp_path):
    mech = lk.load(EXCAVATOR)
    d = mech.drivers[0]
    assert (d.kind, d.name, d.ends, d.stroke, d.link) == ("cylinder", "boom_cylinder", ("C1", "B1"), (1.8, 2.9), "")
    lk.save(mech, tmp_path / "copy.yaml")
    assert lk.load(tmp_path / "copy.yaml") == mech
    # the default name is "A-B", not written back; the default sweep is the stroke in 100 steps
    doc = mech.to_dict()
    doc["drivers"][0] = {"cylinder": ["C1", "B1"], "stroke": [1.8, 2.9]}
    doc["drivers"][1] = {"cylinder": ["B2", "S1"]}
    m2 = lk.Mechanism.from_dict(doc)
    assert [x.name for x in m2.drivers] == ["C1-B1", "B2-S1"]
    assert m2.drivers[0].sweep.count() == 101 and m2.drivers[1].sweep.count() == 1
    assert "name" not in m2.to_dict()["drivers"][0] and lk.Mechanism.from_dict(m2.to_dict()) == m2
    assert prepare(m2).pose_inputs[1, 0] == pytest.approx(abs(m2.joints["S1"] - m2.joints["B2"]), rel=1e-15)
    assert lk.analyze(m2).assembled.tolist() == [True] * 101  # the stick cylinder stays at its pose length
    # a design whose cylinder is outside its stroke at its pose is not a valid mechanism
    with pytest.raises(lk.MechanismFileError, match=r"drivers\[0\]\.stroke: the pose has the cylinder .* outside"):
        mech.with_pose(1.5 * mech.pose_array())


@pytest.mark.parametrize("path", [EXCAVATOR, YOKE, WHITWORTH], ids=lambda p: p.stem)
def test_the_examples_run_from_the_command_line(path, tmp_path, capsys):
    code, out, err = run(["analyze", path], capsys)
    assert code == 0 and err == "" and "not assembled" not in out
    code, out, err = run(["check", path], capsys)
    assert code == 0 and err == "" and "solved in closed form" in out
    code, out, err = run(["plot", path, "-o", tmp_path / "x.png"], capsys)
    assert code == 0 and err == "" and (tmp_path / "x.png").stat().st_size > 1000


def test_a_cylinder_is_swept_and_timed_like_a_slider(capsys):
    code, out, err = run(
        ["analyze", EXCAVATOR, "--angles", "boom_cylinder=1.8:2.9:0.1", "--angles", "stick_cylinder=2.4:3.5:0.1",
         "--speed", "boom_cylinder=0.2", "--speed", "stick_cylinder=0", "--format", "json"],
        capsys,
    )  # fmt: skip
    assert code == 0 and err == ""
    doc = json.loads(out)
    assert doc["inputs"]["boom_cylinder"] == pytest.approx(np.arange(1.8, 2.9 + 1e-9, 0.1).tolist())
    assert doc["assembled"] == [False] + [True] * 10 + [False]  # stick_cylinder 2.4 and 3.5 are beyond its stroke
    assert doc["units"]["length"] == "m"
    mech = lk.load(EXCAVATOR)
    ref, *_ = boom_closed_form(mech, np.array(doc["inputs"]["boom_cylinder"][1:11]), 0.2, 0.0)
    assert np.allclose(doc["joints"]["T"]["vx"][1:11], ref["T"][1].real, rtol=0, atol=1e-12)


EX = EXCAVATOR.read_text()
YK = YOKE.read_text()
BAD = {
    "zero slider direction": (YK.replace("through: A, direction: [0, 1]", "through: A, direction: [0, 0]"),
                              "sliders[1].direction: must not be the zero vector"),
    "cylinder on one link": (EX.replace("cylinder: [C1, B1]", "cylinder: [O, B1]"),
                             "drivers[0].cylinder: joints 'O' and 'B1' are both on link 'boom'"),
    "cylinder on the ground": (EX.replace("cylinder: [C1, B1]", "cylinder: [C1, O]"), "both on link 'ground'"),
    "cylinder with one joint twice": (EX.replace("cylinder: [C1, B1]", "cylinder: [B1, B1]"), "both ends are joint"),
    "cylinder naming an unknown joint": (EX.replace("cylinder: [C1, B1]", "cylinder: [C1, X]"),
                                         "drivers[0].cylinder[1]: unknown joint 'X'"),
    "cylinder with three ends": (EX.replace("cylinder: [C1, B1]", "cylinder: [C1, B1, T]"),
                                 "drivers[0].cylinder: expected two joint names"),
    "unknown link of a slider": (YK.replace("on: yoke", "on: yolk"), "sliders[1].on: unknown link 'yolk'"),
    # the slider's line and its reaction are at `through`: a joint off the block gave another joint's stroke in
    # `check` and a reaction at the crank pin with a moment the block does not carry
    # before: "link 'crank' is already fixed by the rest of the mechanism", which it is not
    "crank's pivot and toward swapped": (YK.replace("pivot: O, toward: A", "pivot: A, toward: O"),
                                         "drivers[0]: link 'crank' turns about its pivot 'A', but its toward joint "
                                         "'O' is the one fixed before it: swap them (pivot: O, toward: A)"),
    # before: "the reaction 'B:rod>block' and the reaction 'B:rod>block' would both give the column ...: rename one"
    "block pinned to its guide": (YK.replace("pin_block: [A]", "pin_block: [A, Y]"),
                                  "sliders[1]: link 'pin_block' is pinned to 'yoke' at 'Y' and slides on it"),
    "slider through a joint off the block": (YK.replace("through: A,", "through: O,"),
                                             "sliders[1].through: joint 'O' is not on link 'pin_block'"),
    "unknown driven link": (YK.replace("link: crank, pivot", "link: crank2, pivot"), "drivers[0].link: unknown link"),
    "stroke min > max": (EX.replace("stroke: [1.8, 2.9]", "stroke: [2.9, 1.8]"),
                         "drivers[0].stroke: [min, max] with min < max"),
    "stroke min = max": (EX.replace("stroke: [1.8, 2.9]", "stroke: [2.4, 2.4]"), "with min < max"),
    "stroke not positive": (EX.replace("stroke: [1.8, 2.9]", "stroke: [0, 2.9]"), "with a positive min"),
    "stroke of one number": (EX.replace("stroke: [1.8, 2.9]", "stroke: [1.8]"), "expected [min, max]"),
    "stroke that misses the pose": (EX.replace("stroke: [1.8, 2.9], lengths: {start: 1.8, stop: 2.9, step: 0.011}",
                                               "stroke: [1.0, 2.0], lengths: {start: 1.0, stop: 2.0, step: 0.01}"),
                                    "the pose has the cylinder 2.39980041 long, outside its stroke"),
    "sweep beyond the stroke": (EX.replace("start: 1.8, stop: 2.9, step: 0.011", "start: 1.5, stop: 2.9, step: 0.01"),
                                "drivers[0].lengths: 1.5 to 2.9 leaves the stroke [1.8, 2.9]"),
    "sweep through zero": (EX.replace("stroke: [1.8, 2.9], lengths: {start: 1.8,", "lengths: {start: -0.2,"),
                           "drivers[0].lengths: a cylinder's length must be positive"),
    "cylinder with a pivot": (EX.replace("cylinder: [C1, B1],", "cylinder: [C1, B1], pivot: O,"),
                              "drivers[0].pivot: a cylinder driver takes"),
    "stroke on a crank": (YK.replace("speed: 10}", "speed: 10, stroke: [1, 2]}"),
                          "drivers[0].stroke: belongs to a cylinder"),
    "two drivers of one name": (EX.replace("name: stick_cylinder", "name: boom_cylinder"), "two drivers are named"),
    "a cylinder too few": (EX.replace("  - {cylinder: [B2, S1]", "  # {cylinder: [B2, S1]"),
                           "a cylinder counts as one driver"),
    "cylinder fighting a crank": (
        EX.replace("  - {cylinder: [B2, S1]", "  - {link: boom, pivot: O, toward: T}\n  # {cylinder: [B2, S1]"),
        "both ends of cylinder 'boom_cylinder' (C1, B1) are already fixed",
    ),
    "cylinder closing a triangle": (
        EX.replace("  ground: [O, C1]", "  ground: [O, C1, K]\n  strut: [K, B1]")
        .replace("  O: [0.0, 0.0]", "  O: [0.0, 0.0]\n  K: [1.5, -0.5]")
        .replace("  - {cylinder: [B2, S1]", "  # {cylinder: [B2, S1]"),
        "drivers[0]: links 'strut' and 'boom' already fix 'B1', the end of cylinder 'boom_cylinder'",
    ),
    "parallel yoke slides": (YK.replace("through: A, direction: [0, 1]", "through: A, direction: [2, 0]"),
                             "sliders[1]: its direction is parallel to that of slider 0"),
}  # fmt: skip


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_definitions_get_one_line_and_exit_2(case, tmp_path, capsys):
    text, expected = BAD[case]
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    code, out, err = run(["analyze", path], capsys)
    assert code == 2, (code, err)
    assert err.count("\n") == 1 and err.startswith("linkagekit: error: ") and expected in err, err
    assert out == ""


def test_the_report_page_draws_each_cylinder_between_its_ends(browser, tmp_path):
    out = tmp_path / "excavator.html"
    assert main(["report", str(EXCAVATOR), "-o", str(out)]) == 0
    page = browser.new_page()
    errors: list[str] = []
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.goto(out.as_uri())
    page.wait_for_selector("[data-cylinder]")
    lines = page.evaluate(
        """() => [...document.querySelectorAll('line[data-cylinder]')].map(e => [e.getAttribute('data-cylinder'),
             ...['x1', 'y1', 'x2', 'y2'].map(a => +e.getAttribute(a))])"""
    )
    joints = page.evaluate(
        """() => { const out = {}; for (const e of document.querySelectorAll('circle[data-joint]'))
             if (!(e.getAttribute('data-joint') in out)) out[e.getAttribute('data-joint')] = [+e.getAttribute('cx'),
             +e.getAttribute('cy'), +e.getAttribute('data-x'), +e.getAttribute('data-y')]; return out; }"""
    )
    page.close()
    assert errors == []
    ends = {"boom_cylinder": ("C1", "B1"), "stick_cylinder": ("B2", "S1")}
    strokes = {d.name: d.type.stroke for d in lk.load(EXCAVATOR).drivers}
    assert sorted(n for n, *_ in lines) == sorted([*ends, *ends])  # a rod and a barrel each
    for name, x1, y1, x2, y2 in lines:
        (a, da), (b, db) = ((np.array(joints[j][:2]), np.array(joints[j][2:])) for j in ends[name])
        assert np.allclose([x1, y1], a, atol=1e-6)
        along = np.array([x2, y2]) - a
        e = b - a
        assert abs(along[0] * e[1] - along[1] * e[0]) <= 1e-6 * np.hypot(*e) ** 2  # on the line between the ends
        f = np.hypot(*along) / np.hypot(
            *(b - a)
        )  # the rod to the far end; the rigid barrel, 0.85 of the stroke's start
        barrel = 0.85 * min(strokes[name]) / np.hypot(*(db - da))
        assert f == pytest.approx(1.0, abs=1e-6) or f == pytest.approx(barrel, abs=1e-6)
