"""Seed 004 (Romero-Nunez & Florez-Serrano 2018): the 32 sign configurations of its Stephenson I.

Reference: the paper's triangle sequence ACD, BCE, BEF, DFG, DGP rebuilt with the law of
cosines (tests/helpers.py), independent of the library's complex-ratio formulas.
"""

import itertools

import numpy as np
import pytest

import linkagekit as lk
from helpers import by_cosines


def modes(mech, at, mirrors=False):
    return lk.modes(mech, at, mirrors).to_dict()


a, b, c, d, e, f, g, h, i, j, k = 2, 5, 3, 8, 6, 8, 3, 9, 8, 7, 6
A, B = 0j, 8 + 2j


def paper_configuration(phi, t):
    t1, t2, t3, t4, t5 = t
    C = A + a * np.exp(1j * phi)
    D = by_cosines(C, A, c, b, t1)  # triangle ACD (flat: a + c = b)
    E = by_cosines(C, B, d, e, t2)  # triangle BCE
    F = by_cosines(E, B, g, f, t3)  # triangle BEF
    G = by_cosines(D, F, i, h, t4)  # triangle DFG (eq. 6 with s4, not s2)
    P = by_cosines(D, G, j, k, t5)  # triangle DGP (s5 = |G - D| = i, not "t")
    return {"C": C, "D": D, "E": E, "F": F, "G": G, "P": P}


@pytest.mark.parametrize("phi_deg", [0.0, 45.0, 60.0, 123.0, 210.0, 300.0])
def test_all_32_configurations(examples, phi_deg):
    mech = lk.load(examples / "seed004_stephenson1.yaml")
    phi = np.radians(phi_deg)
    got = modes(mech, phi_deg, mirrors=True)["modes"]
    assert len(got) == 32
    got_pts = [np.array([complex(*m["joints"][n]) if m["joints"][n] else np.nan for n in "CDEFGP"]) for m in got]
    expected = [paper_configuration(phi, t) for t in itertools.product((1, -1), repeat=5)]
    # match as multisets: every paper configuration to a distinct mode, within 1e-9
    free = list(range(32))
    for exp in expected:
        e_pts = np.array([exp[n] for n in "CDEFGP"])
        hit = next((m for m in free if np.all(np.abs(got_pts[m] - e_pts) < 1e-9)), None)
        assert hit is not None, f"paper configuration missing at {phi_deg} deg"
        free.remove(hit)


def test_sixteen_distinct_configurations(examples):
    """t1 has no effect (flat triangle ACD), so the 32 configurations are 16 distinct ones."""
    mech = lk.load(examples / "seed004_stephenson1.yaml")
    out = modes(mech, 60.0, mirrors=True)
    assert out["distinct"] == 16
    ref = {
        tuple(np.round([paper_configuration(np.radians(60), t)[n] for n in "DEFGP"], 9))
        for t in itertools.product((1, -1), repeat=5)
    }
    assert len(ref) == 16


def test_flat_input_link_never_fails(examples):
    """ACD has a + c = b exactly: it must not turn into NaN anywhere on the sweep."""
    mech = lk.load(examples / "seed004_stephenson1.yaml")
    res = lk.analyze(mech, {"input": np.linspace(0, 360, 3601)})
    assert res.assembled.all()
    d = res.point("D") - res.point("A")
    np.testing.assert_allclose(np.abs(d), 5.0, rtol=1e-12)


def test_sweep_matches_reference_pose_mode(examples):
    mech = lk.load(examples / "seed004_stephenson1.yaml")
    phi = np.linspace(0, 360, 361)
    res = lk.analyze(mech, {"input": phi})
    ref = paper_configuration(np.radians(phi), (1, 1, 1, 1, 1))
    for n in "CDEFGP":
        np.testing.assert_allclose(res.point(n), ref[n], atol=1e-9)
