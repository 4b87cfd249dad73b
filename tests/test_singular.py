"""Singular positions: rates there are flagged and NaN (``null`` in JSON), never huge numbers.

* The parallelogram of seed 003's example 2.2 at its change points (theta2 = 0 and 180 deg):
  all four pivots are collinear and the parallelogram and anti-parallelogram branches meet.
* A Grashof double-rocker at the limit positions of its input rocker, computed here by the
  law of cosines (|A O2| = L3 + L4 and |A O2| = |L4 - L3|): the coupler and the output
  rocker are aligned, the dyad's triangle is flat.
Both methods (natural coordinates and vector loop) must agree on the flags.
"""

import json
import math

import numpy as np
import pytest

import linkagekit as lk
from helpers import accelerations, fourbar_dict, points, velocities

METHODS = ["natural", "vector-loop"]


def assert_undefined_rates(res, k):
    """Sample k is assembled, flagged singular, has finite positions and NaN rates."""
    assert res.assembled[k] and res.singular[k]
    assert np.all(np.isfinite(points(res)[:, k]))
    assert np.all(np.isnan(velocities(res)[:, k])) and np.all(np.isnan(accelerations(res)[:, k]))
    moving = [ln.name for ln in res.mechanism.links if ln.name != "ground"]
    assert all(np.isnan(res.link_omega[n][k]) and np.isnan(res.link_alpha[n][k]) for n in moving)


@pytest.mark.parametrize("method", METHODS)
def test_parallelogram_change_points(method):
    mech = lk.load("examples/seed003_ex22.yaml")
    res = lk.analyze(mech, [0.0, 180.0, 360.0, 60.0, 1.0], speed=5.0, method=method)
    for k in range(3):
        assert_undefined_rates(res, k)
    # away from them, ordinary finite rates: the parallelogram's coupler translates
    assert not res.singular[3:].any()
    assert res.link_omega["rocker"][3] == pytest.approx(5.0, rel=1e-12)
    assert res.link_omega["coupler"][3] == pytest.approx(0.0, abs=1e-12)
    assert np.all(np.abs(velocities(res)[:, 4]) < 5.0 * 1000 * 1.0001)  # |v| <= omega * L2 on a translating coupler


def double_rocker():
    """Ground 4, input 3, coupler 1, output 3.5: Grashof with the coupler shortest."""
    g, l2, l3, l4 = 4.0, 3.0, 1.0, 3.5
    A, B = 0j, complex(g, 0)
    th = math.radians(75.0)
    C = A + l2 * np.exp(1j * th)
    d2 = abs(B - C)
    # D by the law of cosines on the left of C -> B
    gamma = math.acos((l3**2 + d2**2 - l4**2) / (2 * l3 * d2))
    D = C + l3 * np.exp(1j * (np.angle(B - C) + gamma))
    return lk.Mechanism.from_dict(fourbar_dict(A, B, C, D, (C + D) / 2 + 0.3j)), (g, l2, l3, l4)


def limit_angles(g, l2, l3, l4):
    """Input angles (deg, in (0, 180)), ascending, where |A O2| = |l4 - l3| and |A O2| = l3 + l4."""
    return sorted(math.degrees(math.acos((l2**2 + g**2 - s**2) / (2 * l2 * g))) for s in (l3 + l4, abs(l4 - l3)))


def test_double_rocker_is_classified_and_its_range_is_the_limit_positions():
    check = lk.check

    mech, dims = double_rocker()
    info = check(mech)
    assert info["grashof"] == "double-rocker"
    lo, hi = limit_angles(*dims)
    assert info["input_range"][0] == pytest.approx([lo, hi], abs=1e-6)


@pytest.mark.parametrize("method", METHODS)
def test_double_rocker_limit_positions(method):
    mech, dims = double_rocker()
    lo, hi = limit_angles(*dims)
    inside = 1e-4  # deg: close to the limits but clearly assembled
    res = lk.analyze(
        mech, [lo, hi, lo + inside, hi - inside, 0.5 * (lo + hi)], speed=2.0, acceleration=1.0, method=method
    )
    for k in (0, 1):
        # at the limit: the exact angle rounds to either side of it; if it assembles, it is singular
        if res.assembled[k]:
            assert_undefined_rates(res, k)
        else:
            assert np.all(np.isnan(points(res)[2:, k]))
    # just inside: assembled, not singular, large but true rates (omega of the output ~ 1/sqrt(distance))
    assert res.assembled[2:].all() and not res.singular[2:].any()
    assert np.all(np.isfinite(velocities(res)[:, 2:]))
    w = abs(res.link_omega["rocker"][2])
    assert 10 < w < 1e4


def test_singular_samples_are_null_in_json_and_flagged(capsys):
    from linkagekit.cli import main

    assert main(["analyze", "examples/seed003_ex22.yaml", "--at", "0,60,180", "--format", "json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["singular"] == [True, False, True]
    assert out["assembled"] == [True, True, True]
    b = out["joints"]["B"]
    assert b["vx"][0] is None and b["ay"][2] is None and b["vx"][1] is not None
    assert b["x"][0] == pytest.approx(1500.0, abs=1e-6)  # the position itself is defined
    assert out["links"]["coupler"]["omega"][0] is None


def test_a_sample_that_does_not_assemble_is_null_everywhere_in_json(capsys):
    from linkagekit.cli import main

    assert main(["analyze", "examples/seed003_ex21.yaml", "--at", "0,120", "--format", "json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["assembled"] == [False, True]
    for joint in out["joints"].values():  # ground joints included: the mechanism is not there at all
        assert all(values[0] is None and values[1] is not None for values in joint.values())
    for link in out["links"].values():
        assert all(values[0] is None for values in link.values())


@pytest.mark.parametrize("method", METHODS)
def test_near_a_change_point_rates_are_right_or_flagged(method):
    """The parallelogram at 5 rad/s: its rocker's angular acceleration is exactly 0 on the parallelogram branch (the
    default's up to 180 deg). A review found -0.0017, -4.81 and -435.7 rad/s^2 at 179.99, 179.999 and 179.9999 deg,
    none flagged: rounding in the positions grows as 1.5 eps / c^3 in the accelerations (c the dyad's condition, 1.7e-5
    at 179.999 deg). A sample is flagged where c < 1e-4; every other sample's rates hold: the coupler's omega and the
    rocker's alpha to 1e-3 of omega^2 = 25."""
    mech = lk.load("examples/seed003_ex22.yaml")
    off = 10.0 ** -np.arange(1.0, 7.5, 0.25)
    res = lk.analyze(mech, {"crank": 180.0 - off}, method=method)
    d = res.to_dict()["links"]
    alpha = np.array(d["rocker"]["alpha"], float)
    omega = np.array(d["coupler"]["omega"], float)
    ok = ~res.singular
    assert ok.sum() >= 4 and res.singular.sum() >= 10  # both kinds present
    assert np.all(np.abs(alpha[ok]) < 1e-3 * 25) and np.all(np.abs(omega[ok]) < 1e-6)
    assert np.all(np.isnan(alpha[~ok])) and np.all(res.assembled)
    cont = lk.analyze(mech, {"crank": 180.0 - off}, branch="continuous")  # the branch's limits, at every sample
    assert np.all(np.abs(np.asarray(cont.to_dict()["links"]["rocker"]["alpha"], float)) < 1e-3 * 25)
