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


# ----------------------------------------------------------------------------- ranges through 0 deg
def expected_ranges(a, g, phi, c, r):
    """Crank angles (deg) where |A - O2| (crank a from O1, O2 at distance g, direction phi) is in [|c-r|, c+r].

    Law of cosines: |A - O2|^2 = a^2 + g^2 - 2 a g cos(theta - phi); so cos(theta - phi) must
    lie in [cmin, cmax].  Arcs are normalised as `check` reports them: starts in [0, 360),
    an arc running through 0 starts below 0.
    """
    cmin = (a * a + g * g - (c + r) ** 2) / (2 * a * g)
    cmax = (a * a + g * g - (c - r) ** 2) / (2 * a * g)
    if cmin >= 1 or cmax <= -1:
        return []
    t1 = np.pi if cmin <= -1 else np.arccos(cmin)
    t2 = 0.0 if cmax >= 1 else np.arccos(cmax)
    if t1 == np.pi and t2 == 0.0:
        return [[0.0, 360.0]]
    if t2 == 0.0:
        arcs = [(-t1, t1)]
    elif t1 == np.pi:
        arcs = [(t2, 2 * np.pi - t2)]
    else:
        arcs = [(t2, t1), (-t1, -t2)]
    out = []
    for lo, hi in arcs:
        lo_n = np.mod(lo + phi, 2 * np.pi)
        hi_n = lo_n + (hi - lo)
        if hi_n >= 2 * np.pi:
            lo_n, hi_n = lo_n - 2 * np.pi, hi_n - 2 * np.pi
        out.append([np.degrees(lo_n), np.degrees(hi_n)])
    return sorted(out)


def fourbar_at(a, g, phi, c, r):
    """A four-bar in a pose that assembles (crank at the middle of its first range)."""
    lo, hi = expected_ranges(a, g, phi, c, r)[0]
    th = np.radians(0.5 * (lo + hi))
    O2 = g * np.exp(1j * phi)
    C = a * np.exp(1j * th)
    s = abs(O2 - C)
    along = (c * c + s * s - r * r) / (2 * s)
    D = C + (along + 1j * np.sqrt(max(c * c - along * along, 0.0))) * (O2 - C) / s
    pts = {"O1": 0j, "O2": O2, "C": C, "D": D}
    return lk.Mechanism.from_dict(
        {
            "joints": {k: [v.real, v.imag] for k, v in pts.items()},
            "links": {"ground": ["O1", "O2"], "crank": ["O1", "C"], "coupler": ["C", "D"], "rocker": ["O2", "D"]},
            "drivers": [{"link": "crank", "pivot": "O1", "toward": "C"}],
        }
    )


def test_range_through_zero_of_the_issue_example():
    """O1 = (0, 0), O2 = (350, 0), crank 700, coupler 300, rocker 500: [-93.2173, 93.2173], not [-93.2, 453.2]."""
    rep = check(fourbar_at(700.0, 350.0, 0.0, 300.0, 500.0))
    ((lo, hi),) = rep["input_range"]
    t = np.degrees(np.arccos((700**2 + 350**2 - 800**2) / (2 * 700 * 350)))
    assert lo == pytest.approx(-t, abs=1e-6) and hi == pytest.approx(t, abs=1e-6)
    assert t == pytest.approx(93.2173, abs=1e-4)


def test_ranges_match_the_law_of_cosines_on_many_fourbars():
    rng = np.random.default_rng(12)
    kinds = {"through 0": 0, "two arcs": 0, "one arc": 0}
    while min(kinds.values()) < 4:
        a, g, c, r = rng.uniform(1, 10, 4)
        phi = rng.uniform(0, 2 * np.pi)
        exp = expected_ranges(a, g, phi, c, r)
        if exp in ([], [[0.0, 360.0]]) or any(hi - lo < 1.0 for lo, hi in exp):
            continue
        kind = "two arcs" if len(exp) == 2 else "through 0" if exp[0][0] < 0 else "one arc"
        if kinds[kind] >= 4:
            continue
        kinds[kind] += 1
        got = check(fourbar_at(a, g, phi, c, r))["input_range"]
        assert len(got) == len(exp), (got, exp)
        np.testing.assert_allclose(got, exp, atol=1e-6)
