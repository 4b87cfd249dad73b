"""Property tests: random four-bars, Watt II and Stephenson six-bars.

For random reference poses (the lengths are read off the pose), over a sweep:
every distance within every link is kept to 1e-9 relative; the pose comes back at its
own input; and exactly the samples where some triangle cannot close are flagged, as
judged by an independent law-of-cosines construction (tests/helpers.py).
"""

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

import linkagekit as lk
from helpers import (
    fourbar_dict,
    fourbar_reference,
    points,
    stephenson_dict,
    stephenson_reference,
    watt2_dict,
    watt2_reference,
)

coord = st.floats(-10, 10, allow_nan=False, allow_infinity=False)
point = st.builds(complex, coord, coord)


def well_spread(pts, links, min_dist=0.2):
    for ln in links.values():
        for x in ln:
            for y in ln:
                if x < y and abs(pts[x] - pts[y]) < min_dist:
                    return False
    return True


def not_flat(k1, k2, j, tol=0.05):
    """The triangle a dyad closes at the pose is well shaped (no near-singular pose)."""
    u, v = k2 - k1, j - k1
    return abs(u) > 0.2 and abs((np.conj(u) * v).imag) > tol * abs(u) * abs(v)


PHI = np.linspace(0, 2 * np.pi, 181)


def check_mechanism(data, pose, reference, dyads):
    mech = lk.Mechanism.from_dict(data)
    res = lk.analyze(mech, np.degrees(PHI))
    # 1. rigid links keep every distance
    for ln in mech.links:
        for x in ln.joints:
            for y in ln.joints:
                if x < y:
                    dist = np.abs(res.point(x) - res.point(y))[res.assembled]
                    np.testing.assert_allclose(dist, abs(pose[x] - pose[y]), rtol=1e-9)
    # 2. the pose at its own input
    crank = data["drivers"][0]
    phi0 = np.angle(pose[crank["toward"]] - pose[crank["pivot"]])
    at_pose = lk.analyze(mech, [np.degrees(phi0)])
    for name, z in pose.items():
        assert abs(at_pose.point(name)[0] - z) < 1e-9 * (1 + abs(z))
    # 3. flags: exactly where an independent construction fails, away from the boundary
    ref = reference(pose, PHI)
    margin = np.full(PHI.shape, np.inf)
    closes = np.ones(PHI.shape, bool)
    for k1, k2, j in dyads:
        s = np.abs(ref[k2] - ref[k1])
        r1, r2 = abs(pose[j] - pose[k1]), abs(pose[j] - pose[k2])
        ok_here = (s <= r1 + r2) & (s >= abs(r1 - r2))
        closes &= ok_here | np.isnan(s)
        rel = np.minimum(np.abs(s - r1 - r2), np.abs(s - abs(r1 - r2))) / (r1 + r2)
        margin = np.minimum(margin, np.where(np.isnan(rel), np.inf, rel))
    expected = closes & np.all([np.isfinite(ref[k]) for k in ref], axis=0)
    clear = margin > 1e-6
    np.testing.assert_array_equal(res.assembled[clear], expected[clear])
    for name in pose:
        ok = res.assembled & clear
        np.testing.assert_allclose(res.point(name)[ok], ref[name][ok], atol=1e-8 * (1 + abs(pose[name])))


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.filter_too_much])
@given(st.lists(point, min_size=5, max_size=5))
def test_random_fourbars(pts):
    pose = dict(zip("ABCDP", pts, strict=True))
    data = fourbar_dict(*pts)
    assume(well_spread(pose, data["links"]))
    assume(not_flat(pose["C"], pose["B"], pose["D"]))
    check_mechanism(data, pose, fourbar_reference, [("C", "B", "D")])


SIXBARS = {
    "watt2": ("ABECDFGP", watt2_dict, watt2_reference, [("C", "B", "D"), ("F", "E", "G")]),
    "stephenson": ("ABCDEFGP", stephenson_dict, stephenson_reference, [("C", "B", "E"), ("D", "F", "G")]),
}


@pytest.mark.parametrize("kind", sorted(SIXBARS))
@settings(max_examples=50, deadline=None, suppress_health_check=[HealthCheck.filter_too_much])
@given(pts=st.lists(point, min_size=8, max_size=8))
def test_random_sixbars(kind, pts):
    names, make, reference, dyads = SIXBARS[kind]
    pose = dict(zip(names, pts, strict=True))
    data = make(pose)
    assume(well_spread(pose, data["links"]))
    assume(all(not_flat(pose[k1], pose[k2], pose[j]) for k1, k2, j in dyads))
    check_mechanism(data, pose, reference, dyads)


@settings(max_examples=40, deadline=None)
@given(st.lists(point, min_size=5, max_size=5), st.permutations(list(range(181))))
def test_results_do_not_depend_on_input_order(pts, perm):
    pose = dict(zip("ABCDP", pts, strict=True))
    data = fourbar_dict(*pts)
    assume(well_spread(pose, data["links"]) and not_flat(pose["C"], pose["B"], pose["D"]))
    mech = lk.Mechanism.from_dict(data)
    phi = np.degrees(PHI)
    perm = np.array(perm)
    a = lk.analyze(mech, phi)
    b = lk.analyze(mech, phi[perm])
    np.testing.assert_array_equal(points(a)[:, perm], points(b))
