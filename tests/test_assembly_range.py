"""Partial assembly (seed 003 example 2.1, non-Grashof) and the check report."""

import numpy as np
import pytest

import linkagekit as lk

check = lk.check

# Example 2.1: ground 350 (O2 = (-350, 0)), crank 700, coupler 300, rocker 500 (mm).
# It assembles while |A - O2| <= 300 + 500: 700^2 + 350^2 + 2*700*350 cos(t) <= 800^2.
LIMIT = np.degrees(np.arccos((800**2 - 700**2 - 350**2) / (2 * 700 * 350)))


def test_gap_flagged_and_same_mode_after_it(examples):
    mech = lk.load(examples / "seed003_ex21.yaml")
    theta = np.arange(0.0, 720.0, 0.5)
    res = lk.analyze(mech, {"crank": theta})
    t = np.mod(theta, 360)
    inside = (t >= LIMIT + 1e-9) & (t <= 360 - LIMIT - 1e-9)
    np.testing.assert_array_equal(res.assembled, inside)
    assert np.all(np.isnan(res.point("B")[~inside]))
    # second turn: the same mode as the first (the sign of B relative to A->O2 is kept)
    first, second = res.point("B")[theta < 360], res.point("B")[theta >= 360]
    np.testing.assert_allclose(first[inside[theta < 360]], second[inside[theta >= 360]], atol=1e-9)
    A, O2, B = res.point("A"), res.point("O2"), res.point("B")
    left = (np.conj(O2 - A) * (B - A)).imag[res.assembled]
    assert np.all(left > 0) or np.all(left < 0)


def test_table_of_example_21_is_reproduced(examples):
    """theta3, theta4 of the paper's table, example 2.1 (all rows on the pose's branch)."""
    mech = lk.load(examples / "seed003_ex21.yaml")
    res = lk.analyze(mech, {"crank": [90, 120, 150, 180]})
    th3 = np.mod(res.link_angle["coupler"], 360)
    th4 = res.link_angle["rocker"]
    np.testing.assert_allclose(th3, np.mod([258.9, -34.8, 30.0, 100.3], 360), atol=0.05)
    np.testing.assert_allclose(th4, [54.2, 60.5, 89.6, 143.8], atol=0.05)
    # P: the paper prints row 1 right and rows 2-4 wrong (see docs/seed-errata.md)
    np.testing.assert_allclose(res.x("P")[0], 64.9, atol=0.05)
    np.testing.assert_allclose(res.y("P")[0], 510.8, atol=0.05)
    P = res.point("P")[1:]
    np.testing.assert_allclose(
        P, [-150.696617 + 589.539613j, -506.209156 + 523.200100j, -829.322174 + 152.564004j], atol=1e-5
    )


def test_check_reports_range_to_1e6(examples):
    rep = check(lk.load(examples / "seed003_ex21.yaml"))
    assert rep["dof"] == 1
    assert rep["grashof"] == "non-grashof"
    ((lo, hi),) = rep["input_range"]
    assert abs(lo - LIMIT) < 1e-6 and abs(hi - (360 - LIMIT)) < 1e-6


def test_check_full_turn_and_grashof_types(examples):
    rep = check(lk.load(examples / "seed000_fourbar.yaml"))
    assert rep["input_range"] == [[0.0, 360.0]]
    assert rep["grashof"] == "crank-rocker"
    assert check(lk.load(examples / "seed003_ex22.yaml"))["grashof"] == "change-point"


def _fourbar(ground, crank, coupler, rocker, pose_angle=1.0):
    B = complex(ground, 0)
    C = crank * np.exp(1j * pose_angle)
    s = abs(B - C)
    along = (coupler**2 + s**2 - rocker**2) / (2 * s)
    D = C + (along + 1j * np.sqrt(coupler**2 - along**2)) * (B - C) / s
    return lk.Mechanism.from_dict(
        {
            "joints": {"A": [0, 0], "B": [B.real, 0], "C": [C.real, C.imag], "D": [D.real, D.imag]},
            "links": {"ground": ["A", "B"], "crank": ["A", "C"], "coupler": ["C", "D"], "rocker": ["B", "D"]},
            "drivers": [{"link": "crank", "pivot": "A", "toward": "C"}],
        }
    )


@pytest.mark.parametrize(
    ("dims", "kind"),
    [
        ((4.0, 1.0, 3.5, 3.0), "crank-rocker"),
        ((1.0, 3.0, 3.5, 3.2), "double-crank"),
        ((3.0, 3.5, 1.0, 3.2), "double-rocker"),
        ((3.0, 2.5, 3.5, 1.0), "crank-rocker"),  # rocker-crank: the output turns
        ((2.0, 3.0, 2.5, 4.0), "non-grashof"),
    ],
)
def test_grashof_classes(dims, kind):
    mech = _fourbar(*dims)
    rep = check(mech)
    assert rep["grashof"] == kind
    if kind in ("crank-rocker", "double-crank") and dims[1] == min(dims) or kind == "double-crank":
        assert rep["input_range"] == [[0.0, 360.0]]


def test_transmission_angle_extremes_of_a_crank_rocker():
    """Crank-rocker: the extremes occur with the crank along the ground line (law of cosines)."""
    g, a, b, c = 4.0, 1.0, 3.5, 3.0
    rep = check(_fourbar(g, a, b, c))
    mu = lambda diag: np.degrees(np.arccos((b * b + c * c - diag * diag) / (2 * b * c)))  # noqa: E731
    assert abs(rep["transmission_angle"]["min"] - mu(g - a)) < 1e-6
    assert abs(rep["transmission_angle"]["max"] - mu(g + a)) < 1e-6
