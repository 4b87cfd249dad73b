"""Velocities and accelerations against fourth-order finite differences of positions.

Random mechanisms of every supported step kind (circle-circle, rigid placement, circle-line
on a fixed and on a moving guide, pivoting guide, slider driver, two drivers), in the
pose's assembly mode and in the opposite one, with a non-zero input acceleration.
Velocities must agree to 1e-7 and accelerations to 1e-5, relative to the largest value.
"""

import zlib

import numpy as np
import pytest

import linkagekit as lk
from helpers import accelerations, fourbar_dict, points, pose_inputs, stephenson_dict, velocities, watt2_dict, xy
from helpers import random_points as pts

H_V = 1e-5  # velocity step: truncation ~ h^4, rounding ~ eps |z| / h
H_A = 1e-4  # acceleration step: rounding ~ eps |z| / h^2


def slider_crank(rng):
    p = pts(rng, "OABP")
    d = rng.normal(size=2)
    return {
        "joints": xy(p),
        "links": {"ground": ["O"], "crank": ["O", "A"], "rod": ["A", "B", "P"], "block": ["B"]},
        "sliders": [{"link": "block", "on": "ground", "through": "B", "direction": list(d)}],
        "drivers": [{"link": "crank", "pivot": "O", "toward": "A"}],
    }


def inverted_slider_crank(rng):
    p = pts(rng, "OQAR")
    return {
        "joints": xy(p),
        "links": {"ground": ["O", "Q"], "crank": ["O", "A"], "block": ["A"], "rocker": ["Q", "R"]},
        "sliders": [{"link": "block", "on": "rocker", "through": "A", "direction": list(rng.normal(size=2))}],
        "drivers": [{"link": "crank", "pivot": "O", "toward": "A"}],
    }


def guide_on_rocker(rng):
    p = pts(rng, "OQSACRK")
    return {
        "joints": xy(p),
        "links": {
            "ground": ["O", "Q", "S"],
            "crank": ["O", "A"],
            "coupler": ["A", "C"],
            "rocker": ["Q", "C", "R"],
            "arm": ["S", "K"],
            "block": ["K"],
        },
        "sliders": [{"link": "block", "on": "rocker", "through": "K", "direction": list(rng.normal(size=2))}],
        "drivers": [{"link": "crank", "pivot": "O", "toward": "A"}],
    }


def slider_driven(rng):
    p = pts(rng, "OAB")
    return {
        "joints": xy(p),
        "links": {"ground": ["O"], "crank": ["O", "A"], "rod": ["A", "B"], "block": ["B"]},
        "sliders": [{"link": "block", "on": "ground", "through": "B", "direction": list(rng.normal(size=2))}],
        "drivers": [{"slider": 0}],
    }


def fivebar(rng):
    p = pts(rng, "ABCDEP")
    return {
        "joints": xy(p),
        "links": {"ground": ["A", "B"], "c1": ["A", "C"], "c2": ["B", "D"], "l1": ["C", "E", "P"], "l2": ["D", "E"]},
        "drivers": [{"link": "c1", "pivot": "A", "toward": "C"}, {"link": "c2", "pivot": "B", "toward": "D"}],
    }


KINDS = {
    "fourbar": lambda rng: fourbar_dict(*pts(rng, "ABCDP").values()),
    "watt2": lambda rng: watt2_dict(pts(rng, "ABECDFGP")),
    "stephenson": lambda rng: stephenson_dict(pts(rng, "ABCDEFGP")),
    "slider_crank": slider_crank,
    "inverted_slider_crank": inverted_slider_crank,
    "guide_on_rocker": guide_on_rocker,
    "slider_driven": slider_driven,
    "fivebar": fivebar,
}


def finite_difference_check(mech, signs, rng):
    nd = len(mech.drivers)
    factor = np.array([mech.angle_to_rad if d.kind == "angle" else 1.0 for d in mech.drivers])

    q0 = pose_inputs(mech)[:, 0] / factor + rng.uniform(-2, 2, nd) * np.where(factor < 1, 1.0, 0.05)
    w = rng.uniform(-3, 3, nd)
    al = rng.uniform(-3, 3, nd)

    def inputs(t):
        q = q0 + (w * t + 0.5 * al * t * t) / factor
        return {d.name: [q[i]] for i, d in enumerate(mech.drivers)}

    res = lk.analyze(
        mech,
        inputs(0.0),
        speed={d.name: w[i] for i, d in enumerate(mech.drivers)},
        acceleration={d.name: al[i] for i, d in enumerate(mech.drivers)},
        signs=signs,
    )
    if not res.assembled[0] or np.min(np.abs(res.condition)) < 0.1:
        return False  # not here, or too close to a singular position for finite differences
    z = [points(lk.analyze(mech, inputs(k * H_V), signs=signs))[:, 0] for k in (-2, -1, 0, 1, 2)]
    za = [points(lk.analyze(mech, inputs(k * H_A), signs=signs))[:, 0] for k in (-2, -1, 0, 1, 2)]
    if not all(np.all(np.isfinite(zz)) for zz in z + za):
        return False
    vfd = (-z[4] + 8 * z[3] - 8 * z[1] + z[0]) / (12 * H_V)
    afd = (-za[4] + 16 * za[3] - 30 * za[2] + 16 * za[1] - za[0]) / (12 * H_A * H_A)
    v, a = velocities(res)[:, 0], accelerations(res)[:, 0]
    assert np.max(np.abs(v - vfd)) <= 1e-7 * max(np.max(np.abs(v)), 1e-3)
    assert np.max(np.abs(a - afd)) <= 1e-5 * max(np.max(np.abs(a)), 1.0)  # floor: rounding of z / h^2
    # link rates: omega and alpha by finite differences of the link angles
    ang = [lk.analyze(mech, inputs(k * H_V), signs=signs).link_angle for k in (-2, -1, 0, 1, 2)]
    anga = [lk.analyze(mech, inputs(k * H_A), signs=signs).link_angle for k in (-2, -1, 0, 1, 2)]
    for ln in mech.links:
        th = np.unwrap([ang[k][ln.name][0] * mech.angle_to_rad for k in range(5)])
        tha = np.unwrap([anga[k][ln.name][0] * mech.angle_to_rad for k in range(5)])
        wfd = (-th[4] + 8 * th[3] - 8 * th[1] + th[0]) / (12 * H_V)
        afd_l = (-tha[4] + 16 * tha[3] - 30 * tha[2] + 16 * tha[1] - tha[0]) / (12 * H_A * H_A)
        assert abs(res.link_omega[ln.name][0] - wfd) <= 1e-7 * max(abs(wfd), 1.0), ln.name
        assert abs(res.link_alpha[ln.name][0] - afd_l) <= 1e-5 * max(abs(afd_l), 1.0), ln.name
    return True


@pytest.mark.parametrize("kind", sorted(KINDS))
def test_rates_match_finite_differences(kind):
    rng = np.random.default_rng(zlib.crc32(kind.encode()))
    checked = {"pose": 0, "other": 0}
    for _ in range(400):
        try:
            mech = lk.Mechanism.from_dict(KINDS[kind](rng))
        except lk.LinkageError:
            continue
        for mode, signs in (("pose", None), ("other", [-s for s in lk.reference_signs(mech).values()])):
            if checked[mode] < 12 and finite_difference_check(mech, signs, rng):
                checked[mode] += 1
        if min(checked.values()) >= 12:
            break
    assert checked["pose"] >= 12 and checked["other"] >= 12, checked


def test_speed_and_acceleration_per_sample():
    """One speed and acceleration per sample (Python API) equals one call per sample with scalars."""
    mech = lk.load("examples/seed001_stephenson.yaml")
    th = np.array([10.0, 50.0, 130.0, 250.0])
    w = np.array([1.0, -2.0, 3.5, 0.0])
    al = np.array([0.0, 4.0, -1.0, 2.5])
    res = lk.analyze(mech, th, speed=w, acceleration=al)
    for k in range(len(th)):
        one = lk.analyze(mech, [th[k]], speed=w[k], acceleration=al[k])
        np.testing.assert_allclose(velocities(res)[:, k], velocities(one)[:, 0], rtol=1e-13, atol=1e-13)
        np.testing.assert_allclose(accelerations(res)[:, k], accelerations(one)[:, 0], rtol=1e-13, atol=1e-13)
        assert res.forces.driver_torque["input"][k] == pytest.approx(one.forces.driver_torque["input"][0], rel=1e-12)
    # velocities are linear in the speed: zero speed, zero velocity
    assert np.all(velocities(res)[:, 3] == 0)
    with pytest.raises(lk.InputError, match="speed"):
        lk.analyze(mech, th, speed=[1.0, 2.0])
