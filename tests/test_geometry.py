"""The circle-circle kernel against its defining equations; the objective's squared distances against direct ones."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from linkagekit.geometry import ASSEMBLY_RTOL, circle_circle, cross
from linkagekit.synthesis.distribute import keep_freed_memory
from linkagekit.synthesis.objective import _distances2

coord = st.floats(-10.0, 10.0, allow_nan=False)
radius = st.floats(0.05, 10.0, allow_nan=False)


@settings(max_examples=300, deadline=None)
@given(coord, coord, coord, coord, radius, radius, st.sampled_from([1.0, -1.0]))
def test_circle_circle_meets_both_circles_on_the_chosen_side(x1, y1, x2, y2, r1, r2, sign):
    z1, z2 = np.array([complex(x1, y1)]), np.array([complex(x2, y2)])
    z, m = circle_circle(z1, z2, r1, r2, sign)
    s = abs(z2[0] - z1[0])
    total = r1 + r2
    # the margin's definition, written out independently
    want = min(total * (1 + ASSEMBLY_RTOL) - s, s - abs(r1 - r2) + ASSEMBLY_RTOL * total) / total
    meets = want >= 0 and s > ASSEMBLY_RTOL * total
    if meets:
        assert m[0] == pytest.approx(want, abs=1e-12)
        tol = 1e-9 * (total + s)
        assert abs(abs(z[0] - z1[0]) - r1) <= tol and abs(abs(z[0] - z2[0]) - r2) <= tol
        side = cross(z2[0] - z1[0], z[0] - z1[0])
        if abs(side) > 1e-6 * s * r1:  # off the centre line: on the side the sign asks for
            assert np.sign(side) == sign
    else:
        assert np.isnan(z[0].real) and np.isnan(z[0].imag) and m[0] < 0


def test_circle_circle_writes_in_place_and_broadcasts_radii_per_design():
    rng = np.random.default_rng(3)
    D, n = 7, 50
    z1 = rng.normal(size=(D, n)) + 1j * rng.normal(size=(D, n))
    z2 = z1 + (2.0 + 4.0 * rng.random((D, n))) * np.exp(2j * np.pi * rng.random((D, n)))
    r1, r2 = 1.5 + rng.random((D, 1)), 1.5 + rng.random((D, 1))
    sign = np.where(rng.random((D, 1)) < 0.5, 1.0, -1.0)
    out, margin = np.empty((D, n), complex), np.empty((D, n))
    z, m = circle_circle(z1, z2, r1, r2, sign, out=out, margin=margin)
    assert z is out and m is margin
    ref, mref = circle_circle(z1, z2, r1, r2, sign)  # fresh arrays: the same numbers
    np.testing.assert_array_equal(ref, out)
    np.testing.assert_array_equal(mref, margin)
    ok = margin >= 0
    assert 0 < ok.sum() < ok.size  # some samples meet, some do not
    np.testing.assert_allclose(np.abs(z[ok] - z1[ok]), np.broadcast_to(r1, (D, n))[ok], rtol=1e-12)
    np.testing.assert_allclose(np.abs(z[ok] - z2[ok]), np.broadcast_to(r2, (D, n))[ok], rtol=1e-12)
    assert np.isnan(z[~ok]).all()
    # one design per row: each row alone gives the same as in the batch
    for d in range(D):
        zd, md = circle_circle(z1[d], z2[d], r1[d, 0], r2[d, 0], sign[d, 0])
        np.testing.assert_array_equal(zd, z[d])
        np.testing.assert_array_equal(md, m[d])


def test_coincident_centres_do_not_assemble():
    """Equal radii, one centre: every point of the circle would do; flagged, never a made-up point."""
    z1 = np.array([0j, 1 + 1j, 2 + 0j])
    z2 = np.array([0j, 1 + 1j, 5 + 0j])
    z, m = circle_circle(z1, z2, 2.0, 2.0, 1.0)
    assert np.isnan(z[:2]).all() and (m[:2] < 0).all()
    assert z[2] == pytest.approx(3.5 + np.sqrt(4 - 1.5**2) * 1j, abs=1e-12) and m[2] > 0


def test_squared_distances_equal_the_direct_ones():
    rng = np.random.default_rng(5)
    P = 100.0 + rng.normal(size=(4, 30)) + 1j * (50.0 + rng.normal(size=(4, 30)))  # far from the origin
    P[1, 3] = complex(np.nan, np.nan)
    T = 100.0 + rng.normal(size=6) + 1j * (50.0 + rng.normal(size=6))
    got = _distances2(P, T)
    want = np.abs(P[:, None, :] - T[None, :, None]) ** 2
    want[np.isnan(want)] = np.inf
    assert got.shape == (4, 6, 30)
    assert np.isinf(got[1, :, 3]).all()
    fin = np.isfinite(want)
    np.testing.assert_allclose(got[fin], want[fin], rtol=0, atol=1e-12 * 8.0)
    np.testing.assert_array_equal(np.argmin(got, axis=-1), np.argmin(want, axis=-1))


def test_keep_freed_memory_is_harmless_to_call_again():
    keep_freed_memory()
    keep_freed_memory()
    a = np.ones(1 << 20)
    assert float(a.sum()) == float(1 << 20)
