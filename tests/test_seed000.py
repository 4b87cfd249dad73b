"""Seed 000 (Romero-Nunez 2016): all four configurations of its four-bar, to 1e-9.

Reference: the law of cosines and a rotation (tests/helpers.py), not the library's
circle-circle construction.  Dimensions a=2, b=c=d=e=5 cm, A=(0,0), B=(4,1).
"""

import numpy as np
import pytest

import linkagekit as lk
from helpers import by_cosines


def modes(mech, at, mirrors=False):
    return lk.modes(mech, at, mirrors).to_dict()


def paper_configuration(phi, t1, t2):
    A, B, a, b, c, d, e = 0j, 4 + 1j, 2.0, 5.0, 5.0, 5.0, 5.0
    C = A + a * np.exp(1j * phi)
    D = by_cosines(C, B, b, c, t1)  # eq. 15: t1 = +1 puts D left of C->B
    P = by_cosines(C, D, d, e, t2)  # eq. 18: t2 = +1 puts P left of C->D
    return {"C": C, "D": D, "P": P}


@pytest.mark.parametrize("phi_deg", [0.0, 37.0, 90.0, 155.5, 200.0, 271.0, 333.3])
def test_all_four_configurations(examples, phi_deg):
    mech = lk.load(examples / "seed000_fourbar.yaml")
    got = modes(mech, phi_deg, mirrors=True)["modes"]
    assert len(got) == 4
    expected = [paper_configuration(np.radians(phi_deg), t1, t2) for t1 in (1, -1) for t2 in (1, -1)]
    unmatched = list(range(4))
    for exp in expected:
        for i in unmatched:
            joints = got[i]["joints"]
            if all(abs(complex(*joints[k]) - exp[k]) < 1e-9 for k in "CDP"):
                unmatched.remove(i)
                break
        else:
            pytest.fail(f"configuration {exp} not among the modes at {phi_deg} deg")
    assert unmatched == []


def test_sign_convention_is_left_of_directed_line(examples):
    mech = lk.load(examples / "seed000_fourbar.yaml")
    out = modes(mech, np.degrees(0.3))["modes"]
    for mo in out:
        C, D, B = (complex(*mo["joints"][k]) for k in "CDB")
        left = (np.conj(B - C) * (D - C)).imag > 0
        assert mo["signs"]["D"] == (1 if left else -1)


def test_sweep_matches_paper_formula_over_full_turn(examples):
    mech = lk.load(examples / "seed000_fourbar.yaml")
    phi = np.linspace(0, 360, 721)
    res = lk.analyze(mech, {"crank": phi})
    ref = paper_configuration(np.radians(phi), 1, -1)  # the file's pose: t1 = +1, t2 = -1
    assert res.assembled.all()
    for k in "CDP":
        np.testing.assert_allclose(res.point(k), ref[k], atol=1e-9)
