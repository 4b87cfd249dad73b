"""Following a branch through change points (``analyze --branch continuous``).

Independent checks: the geometry (a parallelogram's opposite sides are parallel: their cross
product, relative to size^2, is rounding) and the motion's smoothness (the solver's velocities
against central finite differences of its own positions, across the change points too).
"""

import json
import os

import numpy as np
import pytest

import linkagekit as lk
from helpers import by_cosines, fourbar_dict, xy
from linkagekit.api import prepare
from linkagekit.checks import change_points_crossed
from linkagekit.cli import main

DEG = np.arange(0.0, 721.0, 1.0)


def cross(u, v):
    return u.real * v.imag - u.imag * v.real


def z(res, name):
    p = res.xy(name)
    return p[:, 0] + 1j * p[:, 1]


def parallelogram(ground=4.0, crank=1.0, at=60.0):
    A, B = 0j, complex(ground, 0)
    C = crank * np.exp(1j * np.radians(at))
    D = C + ground
    return lk.Mechanism.from_dict(fourbar_dict(A, B, C, D, C + 0.5 + 0.7j))


def double_parallelogram(at=50.0, spans=(3.0, 2.0)):
    """Three parallel cranks of 1 on a line, two couplers; spans (1, 1): the IFToMM double four-bar (five 1 m bars)."""
    A1, A2, A3 = 0j, complex(spans[0]), complex(sum(spans))
    C1 = np.exp(1j * np.radians(at))
    pts = dict(A1=A1, A2=A2, A3=A3, C1=C1, C2=C1 + A2, C3=C1 + A3)
    return lk.Mechanism.from_dict(
        {
            "format": "linkagekit/1",
            "joints": xy(pts),
            "links": {
                "ground": ["A1", "A2", "A3"],
                "crank1": ["A1", "C1"],
                "crank2": ["A2", "C2"],
                "crank3": ["A3", "C3"],
                "coupler1": ["C1", "C2"],
                "coupler2": ["C2", "C3"],
            },
            "drivers": [{"link": "crank1", "pivot": "A1", "toward": "C1"}],
        }
    )


def worst_parallel(res, quads, skip=None):
    """The largest |cross| of opposite sides over the assembled samples (but ``skip``), relative to size^2."""
    worst = 0.0
    for a, b, c, d in quads:  # A-C parallel to B-D, and C-D parallel to A-B
        za, zb, zc, zd = (z(res, n) for n in (a, b, c, d))
        size2 = abs(zb - za) ** 2 + abs(zc - za) ** 2
        ok = res.assembled if skip is None else res.assembled & ~skip
        e = np.maximum(abs(cross(zc - za, zd - zb)), abs(cross(zd - zc, zb - za))) / size2
        worst = max(worst, float(np.max(e[ok])))
    return worst


def velocity_defect(res, joints, step_deg=1.0):
    """max |v - central difference of positions| / max |v| over interior samples with defined rates (speed 1 rad/s)."""
    h = np.radians(step_deg)
    worst, top = 0.0, 0.0
    for j in joints:
        p = z(res, j)
        d = res.to_dict()["joints"][j]
        vel = np.array([complex(x, y) if x is not None else np.nan for x, y in zip(d["vx"], d["vy"], strict=True)])
        fd = (p[2:] - p[:-2]) / (2 * h)
        ok = np.isfinite(vel[1:-1]) & np.isfinite(fd)
        worst = max(worst, float(np.max(np.abs(vel[1:-1] - fd)[ok])))
        top = max(top, float(np.max(np.abs(vel[1:-1])[ok])))
    return worst / top


def velocity_jump(res, joint, at):
    """|v(at + 1) - v(at - 1)| / |v(at - 1)| (samples one degree apart)."""
    d = res.to_dict()["joints"][joint]
    k = int(np.argmin(np.abs(DEG - at)))
    before, after = (complex(d["vx"][i], d["vy"][i]) for i in (k - 1, k + 1))
    return abs(after - before) / abs(before)


@pytest.mark.parametrize(("name", "mech"), [("parallelogram", parallelogram()), ("rhombus", parallelogram(2.0, 2.0))])
def test_four_bar_parallelograms_stay_parallelograms(name, mech):
    res = lk.analyze(mech, DEG, speed=1.0, branch="continuous")
    # the rhombus's crank lies on the ground at 0, 360, 720 deg: C on B, the dyad's two circles are one; the
    # continuous branch gives its limit there (test_change_points_on_samples_take_the_branch_limit)
    assert res.assembled.all()
    assert worst_parallel(res, [("A", "B", "C", "D")]) <= 1e-12
    assert velocity_defect(res, ["D", "P"]) < 2e-4  # finite differences' own error ~ h^2/6 = 5e-5
    # the coupler translates: omega 0 at every sample, across and at every change point
    w = res.link_omega["coupler"]
    assert np.max(np.abs(w)) < 1e-8
    # the default keeps the pose's sign and leaves the parallelogram after 180 deg
    base = lk.analyze(mech, DEG, speed=1.0)
    assert worst_parallel(base, [("A", "B", "C", "D")]) > 0.1
    # across the change point at 180 deg: D's velocity turns by 2 deg of crank on the parallelogram (0.035 of
    # its size), and jumps on the default's fold
    assert velocity_jump(res, "D", 180.0) < 0.036 < 0.5 < velocity_jump(base, "D", 180.0)
    if name == "rhombus":  # the other mode of a rhombus folds into a kite: D on A
        assert np.max(np.abs(z(base, "D") - z(base, "A"))[(DEG > 181) & (DEG < 359)]) < 1e-12
    # the signs per sample flip at each change point crossed
    s = np.asarray(res.signs["D"])
    assert s.shape == DEG.shape and set(np.unique(s)) == {-1, 1}


@pytest.mark.parametrize("spans", [(3.0, 2.0), (1.0, 1.0)])
def test_double_parallelogram_stays_parallel(spans):
    mech = double_parallelogram(90.0 if spans == (1.0, 1.0) else 50.0, spans)
    res = lk.analyze(mech, DEG, speed=1.0, branch="continuous")
    # the double rhombus's first crank lies on the ground at 0, 360, 720 deg (C1 on A2, C2 on A3), and at a flat
    # position the second dyad's circles touch (the rounding of its discriminant would become sqrt(1e-16) in its
    # position): the branch's limit is taken there
    assert res.assembled.all()
    quads = [("A1", "A2", "C1", "C2"), ("A2", "A3", "C2", "C3")]
    assert worst_parallel(res, quads) <= 1e-12
    assert velocity_defect(res, ["C2", "C3"]) < 2e-4
    assert worst_parallel(lk.analyze(mech, DEG), quads) > 0.1  # the default folds the first loop


@pytest.mark.parametrize("at", [179.0, 179.75, 179.99, 180.25, 0.01, 359.99])
def test_posed_a_hair_from_the_flat_position_every_parallelogram_stays_one(at):
    """Posed 0.01 to 1 deg before a flat position, the closed form's continuous branch folded a parallelogram, a
    rhombus and a double parallelogram into kites past it (537 of 721 samples): the path starts with the pose's
    input repeated (up to the first sample past it), and those samples took the rate 0, so the motion from them
    looked like a jump on either mode. They take the rate of the path's first interval that moves now. Opposite
    sides parallel to 1e-12 of the size at every sample and the velocities continuous (posed on the flat position
    itself, which mode the drawing is in is rounding's choice: not asked)."""
    quads = [("A1", "A2", "C1", "C2"), ("A2", "A3", "C2", "C3")]
    for mech, sides in [(parallelogram(at=at), [("A", "B", "C", "D")]), (parallelogram(2.0, 2.0, at), None)] + [
        (double_parallelogram(at, (3.0, 2.0)), quads)
    ]:
        res = lk.analyze(mech, DEG, speed=1.0, branch="continuous")
        assert res.assembled.all()
        assert worst_parallel(res, sides or [("A", "B", "C", "D")]) <= 1e-12
        assert velocity_defect(res, ["C3"] if sides is quads else ["D"]) < 2e-4


def test_crank_rocker_is_exactly_the_default():
    mech = lk.load("examples/seed000_fourbar.yaml")
    a = lk.analyze(mech, DEG, branch="continuous")
    b = lk.analyze(mech, DEG)
    for j in mech.joint_names:
        assert np.array_equal(a.xy(j), b.xy(j), equal_nan=True)
    da, db = a.to_dict(), b.to_dict()
    assert json.dumps(da["joints"]) == json.dumps(db["joints"])
    assert all(np.all(np.asarray(s) == b.signs[k]) for k, s in a.signs.items())


def test_numerical_group_follows_the_branch():
    mech = parallelogram()
    deg = np.arange(-30.0, 400.0, 2.0)
    res = lk.analyze(mech, deg, method="numerical", branch="continuous", rates=False)
    assert res.assembled.all()
    far = np.abs(((deg + 90) % 180) - 90) > 1  # Newton is slow at the flat positions themselves
    A, B, C, D = (z(res, n) for n in "ABCD")
    assert np.max(np.abs(cross(C - A, D - B))[far]) / 17 < 1e-10
    default = lk.analyze(mech, deg, method="numerical", rates=False)
    assert np.nanmax(np.abs(cross(z(default, "C") - A, z(default, "D") - B))) > 0.1


def test_check_lists_the_change_points_crossed():
    d = fourbar_dict(0j, 4 + 0j, np.exp(1j * np.radians(60)), np.exp(1j * np.radians(60)) + 4, 1 + 1j)
    d["drivers"][0]["angles"] = {"start": -90, "stop": 270, "step": 1}
    mech = lk.Mechanism.from_dict(d)
    got = lk.check(mech)["change_points"]
    # by hand: crank, ground 4 and coupler along one line at 0 deg (C = (1, 0), D = (5, 0)) and 180 deg
    # (C = (-1, 0), D = (3, 0)): the dyad's circles about C (radius 4) and B (radius 1) touch there
    assert [cp["joint"] for cp in got] == ["D", "D"]
    assert [cp["input"] for cp in got] == pytest.approx([0.0, 180.0], abs=1e-6)
    # a crank-rocker crosses none
    assert lk.check(lk.load("examples/seed000_fourbar.yaml"))["change_points"] == []


def test_cli_branch(tmp_path, capsys):
    path = tmp_path / "p.json"
    mech = parallelogram()
    path.write_text(json.dumps(mech.to_dict()))
    assert main(["analyze", str(path), "--angles", "0:720:10", "--branch", "continuous", "--format", "json"]) == 0
    out = json.loads(capsys.readouterr().out)
    ax, ay = np.array(out["joints"]["C"]["x"]), np.array(out["joints"]["C"]["y"])
    dx, dy = np.array(out["joints"]["D"]["x"]), np.array(out["joints"]["D"]["y"])
    assert np.max(np.abs(dx - ax - 4.0)) < 1e-12 and np.max(np.abs(dy - ay)) < 1e-12
    assert main(["analyze", str(path), "--branch", "sideways"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--branch" in err[0]
    # the command line speaks its own options, not Python's keywords
    assert main(["analyze", str(path), "--method", "vector-loop", "--branch", "continuous"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--branch continuous" in err[0] and "--method vector-loop" in err[0]
    assert "signs=" not in err[0] and "method=" not in err[0]


def test_bad_branch_in_python():
    with pytest.raises(lk.LinkageError, match="branch: expected 'pose' or 'continuous', got 'smooth'"):
        lk.analyze(parallelogram(), [0.0], branch="smooth")
    with pytest.raises(lk.LinkageError, match="branch"):
        lk.analyze(parallelogram(), [0.0], branch=["continuous"])
    with pytest.raises(lk.LinkageError, match="branch"):
        lk.analyze(parallelogram(), [0.0], branch="continuous", signs={"D": 1})


def test_check_of_a_sweep_too_long_to_follow(tmp_path, capsys):
    # a valid file whose sweep (1000 turns) is longer than the branch follows: check reports the rest,
    # and says the change points were not followed (it used to exit 2 on an option the user never gave)
    d = parallelogram().to_dict()
    d["drivers"][0]["angles"] = {"start": 0, "stop": 360000, "step": 100}
    path = tmp_path / "long.json"
    path.write_text(json.dumps(d))
    assert lk.check(lk.load(path))["change_points"] is None
    assert main(["check", str(path)]) == 0
    out = capsys.readouterr().out
    assert "Change points: not followed" in out and "change-point" in out
    with pytest.raises(lk.LinkageError, match="MAX_PATH"):  # analyze --branch continuous still refuses it
        lk.analyze(lk.load(path), [0.0, 360000.0], branch="continuous")


def test_batch_follows_each_designs_branch():
    one = parallelogram()
    pose = np.array([[one.joints[j].real, one.joints[j].imag] for j in one.joint_names])
    bent = pose.copy()
    bent[one.joint_names.index("D")] += [0.3, 0.2]  # no parallelogram: no change point
    poses = np.stack([pose, 2.0 * pose, bent])
    res = lk.analyze(one, DEG, poses=poses, branch="continuous", rates=False)
    for k, p in enumerate(poses):
        single = lk.Mechanism.from_dict(one.to_dict() | {"joints": dict(zip(one.joint_names, p.tolist(), strict=True))})
        alone = lk.analyze(single, DEG, branch="continuous", rates=False)
        assert np.array_equal(res.xy("D")[k], alone.xy("D"), equal_nan=True)
        assert np.array_equal(res.signs["D"][k], alone.signs["D"])
    assert len(set(res.signs["D"][0])) == 2 and len(set(res.signs["D"][2])) == 1


@pytest.mark.parametrize("rocker", [1.001, 0.999, 1 + 1e-7, 1 - 1e-7])
def test_near_parallelograms_keep_the_default(rocker):
    """Two modes that come near but do not meet (or lock just short of meeting): no change point, the default."""
    A, B, C = 0j, 4 + 0j, np.exp(1j * np.radians(60))
    D = complex(by_cosines(C, B, 4.0, rocker, 1))
    mech = lk.Mechanism.from_dict(fourbar_dict(A, B, C, D, C + 0.5 + 0.7j))
    a, b = lk.analyze(mech, DEG, branch="continuous"), lk.analyze(mech, DEG)
    assert all(np.array_equal(a.xy(j), b.xy(j), equal_nan=True) for j in mech.joint_names)
    assert lk.check(mech)["change_points"] == []


def test_isosceles_slider_crank_goes_through_its_pivot():
    """Crank = rod = 1, no offset: the block is at 2 cos(theta) on one branch and at the pivot on the other.

    The circle about A (radius 1) and the slider's line touch where A is at (0, +-1): theta = 90 and 270 deg.
    """
    th = np.radians(40.0)
    a = np.exp(1j * th)
    mech = lk.Mechanism.from_dict(
        {
            "format": "linkagekit/1",
            "joints": {"O": [0, 0], "A": [a.real, a.imag], "B": [2 * np.cos(th), 0]},
            "links": {"ground": ["O"], "crank": ["O", "A"], "rod": ["A", "B"], "block": ["B"]},
            "sliders": [{"link": "block", "on": "ground", "through": "B", "direction": [1, 0]}],
            "drivers": [{"link": "crank", "pivot": "O", "toward": "A"}],
        }
    )
    res = lk.analyze(mech, DEG, branch="continuous")
    assert np.max(np.abs(res.xy("B")[:, 0] - 2 * np.cos(np.radians(DEG)))) < 1e-12
    default = lk.analyze(mech, DEG)
    assert np.max(np.abs(default.xy("B")[:, 0] - 2 * np.cos(np.radians(DEG)))) > 1.0
    got = change_points_crossed(mech, prepare(mech))  # what check lists (check's other parts take a second here)
    assert [cp["joint"] for cp in got] == ["B", "B"]
    assert [cp["input"] for cp in got] == pytest.approx([90.0, 270.0], abs=1e-6)


def test_follow_step_by_step_as_a_simulation_would():
    """A simulation calls follow with its last sample and the next, carrying the signs: the same signs as a sweep."""
    from linkagekit.branch import along_sweep, follow

    params = prepare(double_parallelogram(90.0, (1.0, 1.0)))  # the IFToMM double four-bar: five 1 m bars
    rng = np.random.default_rng(7)
    q = np.radians(90.0) + np.cumsum(np.r_[0.0, rng.uniform(0.001, 0.12, 200)])  # uneven steps, about 2 turns
    signs, crossed = [params.signs[:, 0]], 0
    for k in range(len(q) - 1):
        br = follow(params, q[None, None, k : k + 2], q[None, k : k + 2], start=signs[-1][:, None])
        signs.append(br.signs[:, 0, 1])
        crossed += len(br.points[0])
    stepwise = np.array(signs).T
    sweep = along_sweep(params, q[None, None], (True,)).signs[:, 0]
    ok = np.abs(np.sin(q)) > 1e-6  # samples on a change point carry either sign
    assert np.array_equal(stepwise[:, ok], sweep[:, ok])
    # a change point every half turn (crank along the ground: 180, 360, ... deg), for both dyads
    half_turns = int(np.floor(q[-1] / np.pi))
    assert half_turns >= 3 and crossed == 2 * half_turns


def test_batch_in_blocks_and_a_path_too_long(monkeypatch):
    import linkagekit.branch as branch

    mech = parallelogram()
    pose = np.array([[mech.joints[j].real, mech.joints[j].imag] for j in mech.joint_names])
    poses = np.stack([pose * (1 + 0.1 * k) for k in range(5)])
    whole = lk.analyze(mech, DEG, poses=poses, branch="continuous", rates=False)
    monkeypatch.setattr(branch, "BLOCK", 3000)  # two designs' paths per block
    blocks = lk.analyze(mech, DEG, poses=poses, branch="continuous", rates=False)
    assert np.array_equal(whole.xy("D"), blocks.xy("D"), equal_nan=True)
    assert np.array_equal(whole.signs["D"], blocks.signs["D"])
    with pytest.raises(lk.LinkageError, match="MAX_PATH"):
        lk.analyze(mech, [0.0, 1e6], branch="continuous")


def test_numerical_groups_follow_the_double_rhombus():
    """IFToMM's double four-bar solved by Newton groups: a smooth change of the determinant's sign is accepted."""
    mech = double_parallelogram(90.0, (1.0, 1.0))
    deg = np.arange(-30.0, 400.0, 2.0)
    res = lk.analyze(mech, deg, method="numerical", branch="continuous", rates=False)
    assert res.assembled.all()
    far = np.abs(((deg + 90) % 180) - 90) > 1  # Newton is slow at the flat positions themselves
    c1, c2, c3 = (z(res, n) for n in ("C1", "C2", "C3"))
    assert np.max(np.maximum(np.abs((c2 - c1).imag), np.abs((c3 - c2).imag))[far]) < 1e-10
    default = lk.analyze(mech, deg, method="numerical", rates=False)
    assert np.nanmax(np.abs((z(default, "C2") - z(default, "C1")).imag)) > 0.5


def test_a_change_point_forced_through_newton_is_flagged_however_its_direction_is_written():
    """IFToMM's double rhombus (pose at 90 deg) forced through Newton, the pose's branch: at 0 deg C1 lies on A2 and
    C2 is undetermined, so the closed form flags it. Written as 0, 360, 720 or -360 deg, in a list and alone, it
    is flagged; 180 and 540 deg are assembled as in the closed form (to 1e-5: there C2 and C3 sit on tangent
    circles, which Newton fixes only to about the square root of its tolerance: 5.4e-7 and 1.1e-6). The chains'
    second pass (every group a turn the other way) once reached 360 deg from the other side and took a root Newton
    converged to only by rounding (C2 at (0, 0)): a configuration whose Jacobian's determinant is below 1e-12 of the
    pose's is no answer now (review 9)."""
    mech = double_parallelogram(90.0, (1.0, 1.0))
    u = [0.0, 360.0, 720.0, -360.0, 180.0, 540.0]
    ref = lk.analyze(mech, {"crank1": u}, rates=False)
    assert ref.assembled.tolist() == [False, False, False, False, True, True]
    for res in [lk.analyze(mech, {"crank1": u}, method="numerical", rates=False)] + [
        lk.analyze(mech, {"crank1": [x]}, method="numerical", rates=False) for x in u
    ]:
        k = slice(None) if len(res.assembled) == len(u) else [u.index(float(res.inputs["crank1"][0]))]
        assert res.assembled.tolist() == np.asarray(ref.assembled)[k].tolist()
        for j in ("C1", "C2", "C3"):
            assert np.nanmax(np.abs(z(res, j) - z(ref, j)[k]), initial=0.0) < 1e-5


def test_numerical_group_continuous_off_whole_degrees_and_after_a_gap():
    """Found by review (on the walk before it was rewritten): a parallelogram forced through Newton
    with the continuous branch, swept off whole degrees, took the crossed mode near 0.5 deg; a
    slider-crank forced through Newton came back from its gap in the other mode.  Checked here
    against the geometry and against the closed form."""
    para = lk.Mechanism.from_dict(
        {
            "format": "linkagekit/1",
            "units": {"length": "m", "angle": "deg"},
            "joints": {"A": [0, 0], "B": [3, 0], "C": [0.9396926207859084, 0.3420201433256687],
                       "D": [3.9396926207859084, 0.3420201433256687]},
            "links": {"ground": ["A", "B"], "crank": ["A", "C"], "coupler": ["C", "D"], "rocker": ["B", "D"]},
            "drivers": [{"link": "crank", "pivot": "A", "toward": "C"}],
        }
    )  # fmt: skip
    for off in (0.3,):
        r = lk.analyze(para, {"crank": np.arange(off, 720 + off, 1.0)}, method="numerical", branch="continuous")
        assert r.assembled.all()
        assert np.max(np.abs(r.point("D") - r.point("C") - 3)) < 1e-12  # still a parallelogram, every sample
    sc = lk.Mechanism.from_dict(
        {
            "format": "linkagekit/1",
            "joints": {"O": [0, 0], "A": [0.6, 0.8], "B": [1.4, 0.5], "T": [1.7, 0.6]},
            "links": {"ground": ["O"], "crank": ["O", "A"], "rod": ["A", "B"], "block": ["B", "T"]},
            "sliders": [{"link": "block", "on": "ground", "through": "B", "direction": [1, 0]}],
            "drivers": [{"link": "crank", "pivot": "O", "toward": "A"}],
        }
    )
    a = np.arange(300, 600, 0.7)
    num = lk.analyze(sc, {"crank": a}, method="numerical", branch="continuous")
    ref = lk.analyze(sc, {"crank": a}, method="natural", branch="continuous")
    assert np.array_equal(num.assembled, ref.assembled) and num.assembled.any() and not num.assembled.all()
    ok = num.assembled
    assert np.max(np.abs(num.point("B")[ok] - ref.point("B")[ok])) < 1e-9


def coupler_fed_triad(triad):
    """A crank-rocker (crank O-A at 90 deg in the pose, coupler A-B-C, rocker O2-B) whose coupler point C holds a
    triad: legs C-J1, B0-J2, C0-J3 on a ternary J1 J2 J3, the points of ``triad`` (review 8's attack family)."""
    joints = {"O": [0.0, 0.0], "O2": [4.0, 0.0], "A": [0.0, 1.0], "B": [3.489041676410868, 2.956166705643473],
              "C": [1.0109583235891315, 3.286473981475812], **triad}  # fmt: skip
    links = {"ground": ["O", "O2", "B0", "C0"], "crank": ["O", "A"], "coupler": ["A", "B", "C"],
             "rocker": ["O2", "B"], "l1": ["C", "J1"], "l2": ["B0", "J2"], "l3": ["C0", "J3"],
             "tern": ["J1", "J2", "J3"]}  # fmt: skip
    doc = {"format": "linkagekit/1", "units": {"length": "mm", "angle": "deg"}, "joints": joints, "links": links,
           "drivers": [{"link": "crank", "pivot": "O", "toward": "A"}]}  # fmt: skip
    pts = np.array([complex(*p) for p in joints.values()])
    return lk.Mechanism.from_dict(doc), np.max(np.abs(pts[:, None] - pts[None, :]))  # and the joints' span


TRIADS = {
    # range [72.96, 91.05] deg: continuous left the branch at 79.5..82 deg by 0.24 mm (span 10.5 mm), came back
    "inside": ({"B0": [9.296027354063606, -2.67709103873365], "C0": [7.255118164392492, -3.6114860306876757],
                "J1": [2.032968421114176, 2.8107302271602466], "J2": [0.7153310092334033, 3.3866216228656834],
                "J3": [2.7144505541325112, 0.29306816795673196]},
               (np.arange(73.0, 91.0, 0.5), np.arange(91.0, 73.0, -0.5)), (72.96178714675288, 91.05172568436907)),
    # range [-207.54, 90.60] deg: continuous went on past the fold at 90.60 deg (all 360 directions assembled)
    "fold": ({"B0": [2.1891459952041075, 9.207419141214965], "C0": [-3.6934461964858603, 9.178391154195902],
              "J1": [1.520460004754253, 2.3724283571570726], "J2": [0.12991547401734183, 0.4642282415266079],
              "J3": [1.1495125790260774, 3.0171492414076573]},
             (np.arange(0.0, 360.0, 1.0),), (-207.54221579821768, 90.60383629615204)),
}  # fmt: skip


@pytest.mark.parametrize("name", list(TRIADS))
def test_numerical_group_continuous_keeps_its_branch_where_no_modes_meet(name):
    """Review 8: a triad fed by a four-bar's coupler, no change point in its range, left its branch under
    ``branch="continuous"``. Inside its range the walk's look-ahead took a root of the other determinant sign (341,
    377 at 87, 84 deg, then -474 at 81 deg), and past a fold a root of the pose's sign on another branch: a step now
    keeps its sign only where the determinant's zero is not within it, and changes it only along its trend. Where no
    modes meet the result is the default's: the same flags, assembled exactly where the direction lies in the range
    an independent continuation finds (each end to 1e-7 deg), the joints to 1e-10 of the span (the two differ by
    2e-14: following the branch, the four-bar's joints go along the sub-steps' chord)."""
    triad, sweeps, (lo, hi) = TRIADS[name]
    mech, span = coupler_fed_triad(triad)
    for deg in sweeps:
        default = lk.analyze(mech, {"crank": deg}, rates=False)
        cont = lk.analyze(mech, {"crank": deg}, rates=False, branch="continuous")
        inside = (deg - lo) % 360.0 <= hi - lo
        assert default.assembled.tolist() == cont.assembled.tolist() == inside.tolist()
        for j in ("J1", "J2", "J3"):
            assert np.nanmax(np.abs(z(cont, j) - z(default, j))) / span < 1e-10


FLAT = DEG % 180 == 0  # the change points of a parallelogram driven by its crank: 0, 180, 360, 540, 720 deg


def joint_rates(res, name, key):
    """A joint's velocity (key "v") or acceleration ("a") per sample, complex (NaN where null)."""
    d = res.to_dict()["joints"][name]
    pairs = zip(d[key + "x"], d[key + "y"], strict=True)
    return np.array([complex(np.nan if x is None else x, np.nan if y is None else y) for x, y in pairs])


PARALLELOGRAMS = [  # (mechanism, [(crank tip, joint that translates with it, the offset B - A between them)])
    ("parallelogram", parallelogram(), [("C", "D", 4.0)]),
    ("rhombus", parallelogram(1.0, 1.0), [("C", "D", 1.0)]),  # ground 1, all sides 1: C on B at 0, 360, 720 deg
    ("double parallelogram", double_parallelogram(50.0, (3.0, 2.0)), [("C1", "C2", 3.0), ("C1", "C3", 5.0)]),
    ("double rhombus", double_parallelogram(90.0, (1.0, 1.0)), [("C1", "C2", 1.0), ("C1", "C3", 2.0)]),
]


@pytest.mark.parametrize(("name", "mech", "pairs"), PARALLELOGRAMS, ids=[p[0] for p in PARALLELOGRAMS])
def test_change_points_on_samples_take_the_branch_limit(name, mech, pairs, monkeypatch):
    """Samples exactly at a change point (0, 180, ... 720 deg) give the followed branch's limit.

    Independent checks: the geometry (on the parallel branch each coupler joint is its crank tip moved by
    B - A, so its position, velocity and acceleration are the crank tip's, exactly), fourth-order central
    differences of positions solved 0.1 and 0.2 deg either side (no change point there), and the one-sided
    limits (rates solved 1e-4 rad either side: nearer, the direct solve's own rounding grows as 1/distance^2)."""
    speed, accel = 1.0, 0.3
    res = lk.analyze(mech, DEG, speed=speed, acceleration=accel, branch="continuous")
    assert res.assembled.all()
    quads = [("A", "B", "C", "D")] if "C" in mech.joint_names else [("A1", "A2", "C1", "C2"), ("A2", "A3", "C2", "C3")]
    assert worst_parallel(res, quads) <= 1e-12
    for tip, j, off in pairs:
        assert np.max(np.abs(z(res, j) - z(res, tip) - off)) < 1e-12
        # limits' error: e^4 f''''/6 + rounding/e^k with e = 1e-3 rad: 1e-13 (positions), ~1e-9 (rates)
        assert np.max(np.abs(joint_rates(res, j, "v") - joint_rates(res, tip, "v"))) < 1e-8
        assert np.max(np.abs(joint_rates(res, j, "a") - joint_rates(res, tip, "a"))) < 1e-7
    # velocities continuous: central differences of positions on a fine grid around each change sample
    u = DEG[FLAT]
    h = 0.1
    offsets = np.array([-2.0, -1.0, 1.0, 2.0]) * h
    near = lk.analyze(mech, (u[:, None] + offsets).ravel(), speed=speed, branch="continuous")
    assert near.assembled.all() and not near.singular.any()
    for _, j, _ in pairs:
        p = z(near, j).reshape(-1, 4)
        fd = (p[:, 0] - 8 * p[:, 1] + 8 * p[:, 2] - p[:, 3]) / (12 * np.radians(h)) * speed
        assert np.max(np.abs(joint_rates(res, j, "v")[FLAT] - fd)) < 1e-8  # h^4 v^(5)/30 ~ 3e-13, rounding/h ~ 1e-10
        # the one-sided limits: rates a hair either side of the change point
        delta = np.degrees(1e-4)
        sides = lk.analyze(mech, np.r_[u - delta, u + delta], speed=speed, branch="continuous")
        v_side = joint_rates(sides, j, "v").reshape(2, -1)
        assert np.max(np.abs(v_side - joint_rates(res, j, "v")[FLAT])) < 2e-4  # |a| delta = 1e-4
    # every other sample is exactly what it was without the limits
    import linkagekit.api as api

    monkeypatch.setattr(api, "limits", lambda p, q, rates, mirrors, br, angular, pos, rt: (pos, rt))
    bare = lk.analyze(mech, DEG, speed=speed, acceleration=accel, branch="continuous")
    for j in mech.joint_names:
        assert np.array_equal(res.xy(j)[~FLAT], bare.xy(j)[~FLAT])
        for key in ("v", "a"):
            assert np.array_equal(joint_rates(res, j, key)[~FLAT], joint_rates(bare, j, key)[~FLAT])
    assert not bare.assembled.all() or np.isnan(joint_rates(bare, pairs[0][1], "v")[FLAT]).all()  # it was a gap
    # the Jacobian is singular there: still flagged, and so is a sample that did not assemble (a rhombus's crank over
    # its ground pivot: coincident circles; review 14b found it unflagged, as the method forced through Newton flags it)
    assert np.array_equal(res.singular, bare.singular | (FLAT & ~bare.assembled))
    assert res.singular[FLAT & ~bare.assembled].all() and np.array_equal(res.singular[~FLAT], bare.singular[~FLAT])
    # the default mode is unchanged: it keeps the pose's sign and the closed form's flags at the change points
    default = lk.analyze(mech, DEG, speed=speed)
    assert np.isnan(joint_rates(default, pairs[0][1], "v")[FLAT]).all()


@pytest.mark.parametrize(("name", "mech", "pairs"), PARALLELOGRAMS, ids=[p[0] for p in PARALLELOGRAMS])
def test_numerical_groups_at_change_points_give_the_limit_or_a_flag(name, mech, pairs):
    """With method="numerical" a sample on a change point is the branch's limit (the closed form's, to the
    group's Newton tolerance) where the group's walk gives the same sides whichever inputs it is given; else it
    stays as the walk left it (flagged, rates null), never another branch's number."""
    num = lk.analyze(mech, DEG, speed=1.0, method="numerical", branch="continuous")
    ref = lk.analyze(mech, DEG, speed=1.0, branch="continuous")
    limit = FLAT & num.assembled & np.isfinite(joint_rates(num, pairs[0][1], "v"))
    for _, j, _ in pairs:
        assert np.max(np.abs(z(num, j) - z(ref, j))[limit]) < 1e-9
        assert np.max(np.abs(joint_rates(num, j, "v") - joint_rates(ref, j, "v"))[limit]) < 1e-6
    if name in ("parallelogram", "double parallelogram"):  # tangent circles: the walk is unambiguous
        assert limit[FLAT].all()
    flagged = FLAT & ~limit
    assert np.all(~num.assembled[flagged] | num.singular[flagged])


def test_branch_modes_are_declared_once():
    """The mode as an enum member or as its word gives the same analysis; the CLI's choices are the words."""
    from linkagekit.cli import build_parser
    from linkagekit.options import BranchMode

    mech = parallelogram()
    a = lk.analyze(mech, [0.0, 200.0], branch=BranchMode.CONTINUOUS)
    b = lk.analyze(mech, [0.0, 200.0], branch="continuous")
    assert np.array_equal(a.xy("D"), b.xy("D")) and np.array_equal(a.signs["D"], b.signs["D"])
    assert BranchMode.words() == ("pose", "continuous")
    action = next(x for x in build_parser()._subparsers._group_actions[0].choices["analyze"]._actions
                  if "--branch" in x.option_strings)  # fmt: skip
    assert tuple(action.choices) == BranchMode.words() and action.default == BranchMode.POSE.value


@pytest.mark.parametrize(("name", "mech"), [("parallelogram", parallelogram()), ("double", double_parallelogram())])
@pytest.mark.parametrize("near", [1e-4, 1e-5, 1e-6])
def test_an_input_near_a_change_point_does_not_change_the_others_answers(name, mech, near):
    """A review: ``--at 181`` gave the parallelogram and ``--at 179.9999,181`` the crossed mode at 181 deg (its torque
    -5.22 where -16.2 N*m is right). The test at a meeting compared the two ways ``probe`` either side of it, cut to
    half the distance to the nearest sample: 1e-4 deg off, 9e-7 rad, where the rates have lost the digits that tell
    them apart. Every input's answer is the same alone or among others (positions to 1e-9 of the size)."""
    alone = lk.analyze(mech, {"crank" if name == "parallelogram" else "crank1": [181.0, 539.0]}, branch="continuous")
    for extra in ([180.0 - near], [180.0 + near], [180.0 - near, 180.0 + near], [540.0 - near]):
        asked = sorted([181.0, 539.0, *extra])
        res = lk.analyze(mech, {"crank" if name == "parallelogram" else "crank1": asked}, branch="continuous")
        keep = [asked.index(181.0), asked.index(539.0)]
        for j in mech.joint_names:
            assert np.max(np.abs(res.xy(j)[keep] - alone.xy(j))) < 1e-9 * 4.0, (extra, j)


def test_forces_at_a_change_point_taken_as_the_branch_limit_are_null_not_an_internal_error():
    """The shipped IFToMM double four-bar (masses, gravity) with ``--branch continuous`` over its own sweep (which
    holds 360 deg, a flat position): 'internal error: LinAlgError: Singular matrix' (a review). The reactions of a flat
    position are not determined (they grow without bound either side of it: 1404 N at 359 deg, -1406 N at 361): null
    there, the neighbours' as before."""
    mech = lk.load("examples/iftomm_a02_double_fourbar.yaml")
    res = lk.analyze(mech, {"crank0": [359.0, 360.0, 361.0]}, branch="continuous")
    d = res.to_dict()
    torque = d["driver_torque"]["crank0"]
    assert torque[1] is None and all(np.isfinite([torque[0], torque[2]]))
    assert abs(torque[0] - torque[2]) < 1e-6 * abs(torque[0])  # the gravity torque of a symmetric pose
    assert all(r["fx"][1] is None and r["fx"][0] is not None for r in d["reactions"])
    assert main(["analyze", "examples/iftomm_a02_double_fourbar.yaml", "--branch", "continuous", "--format", "csv",
                 "-o", os.devnull]) == 0  # fmt: skip


@pytest.mark.parametrize("at", [180.0, 180.001, 180.0 - 1e-6, 360.0])
def test_a_lone_sample_on_a_change_point_has_every_rate_as_among_others(at):
    """A review: ``--at 180.001 --branch continuous`` gave the crank's omega and alpha null, ``--at 180.001,181`` gave
    5.0 and 0: a driver link's own speed (one value for every sample) was not taken as its limit. Every link's
    omega and alpha, alone or beside other samples, are the same (the crank's 5.0 and 0, the ground's 0)."""
    mech = lk.load("examples/seed003_ex22.yaml")
    alone = lk.analyze(mech, {"crank": [at]}, branch="continuous")
    among = lk.analyze(mech, {"crank": [at - 7.0, at, 181.5]}, branch="continuous")
    for name in ("crank", "coupler", "rocker", "ground"):
        for got, want in ((alone.link_omega[name][0], among.link_omega[name][1]),
                          (alone.link_alpha[name][0], among.link_alpha[name][1])):  # fmt: skip
            assert np.isfinite(got) and abs(got - want) <= 1e-9 * 25, (name, got, want)
    assert alone.link_omega["crank"][0] == 5.0 and alone.link_alpha["crank"][0] == 0.0


TWO_TRIADS = {  # review 10's two triads in sequence (random dimensions, no change point): range [-110.09, 77.57] deg
    "format": "linkagekit/1",
    "units": {"length": "mm", "angle": "deg"},
    "joints": {"O": [0.0, 0.0], "A": [1.5, 0.5], "B0": [-1.3762362866295845, -0.32751758105198636],
               "C0": [2.046329470580689, 1.0895967417820724], "J1": [2.255857700785211, -1.6497238319947232],
               "J2": [1.5976513980143179, 2.019960185224155], "J3": [1.4460753947173322, -0.03224810101709963],
               "D0": [7.2013528451739575, -5.5667120917423105], "E0": [5.241159563110896, 2.4286807536678623],
               "K1": [-1.9158039920065058, -2.6576249901449067], "K2": [-0.5941629806356787, -1.3416471658678675],
               "K3": [-0.22814304279151365, -1.6806662131695047]},
    "links": {"ground": ["O", "B0", "C0", "D0", "E0"], "crank": ["O", "A"], "l1": ["A", "J1"], "l2": ["B0", "J2"],
              "l3": ["C0", "J3"], "tern": ["J1", "J2", "J3"], "m1": ["J3", "K1"], "m2": ["D0", "K2"],
              "m3": ["E0", "K3"], "tern2": ["K1", "K2", "K3"]},
    "drivers": [{"link": "crank", "pivot": "O", "toward": "A"}],
}  # fmt: skip


def test_continuous_takes_no_root_of_another_branch_before_a_fold():
    """Review 10 (A1): two triads in sequence, no change point in their range. 0.05 grid steps before the second
    triad's fold the walk took a root of another branch whose determinant followed the trend (-560.4, -124.5, then
    420.1): 62 of 360 samples off the branch by up to 0.29 of the span. A step that changes the determinant's sign
    must now keep the velocity continuous too. Where no modes meet the result is the default's (which an independent
    whole-mechanism continuation matched to 5e-13): the same flags, the joints to 1e-10 of the span."""
    mech = lk.Mechanism.from_dict(TWO_TRIADS)
    pts = np.array([complex(*p) for p in TWO_TRIADS["joints"].values()])
    span = np.max(np.abs(pts[:, None] - pts[None, :]))
    deg = np.arange(0.0, 360.0, 2.0)
    default = lk.analyze(mech, {"crank": deg}, rates=False)
    cont = lk.analyze(mech, {"crank": deg}, rates=False, branch="continuous")
    assert cont.assembled.tolist() == default.assembled.tolist() and 0 < default.assembled.sum() < len(deg)
    for j in mech.joint_names:
        assert np.nanmax(np.abs(z(cont, j) - z(default, j))) / span < 1e-10


def test_a_lone_input_crosses_the_change_point_next_to_the_pose():
    """Review 10 (A2): a double parallelogram posed 0.5 deg past its flat position, forced through Newton. Asked one
    input, its grid ends at the pose: the first step down has no determinant trend to follow, its sub-steps kept the
    pose's sign onto the other mode, and each input alone left the double parallelogram (by 0.49 to 1.9) while the
    list stayed on it. The whole step is smooth (its velocity continuous) and crosses. Alone or in a list, every
    input is a double parallelogram (couplers parallel to the ground, to 1e-10) and the two agree to 1e-10."""
    mech = double_parallelogram(0.5, (3.0, 2.0))
    xs = [-438.97, 616.483, 561.209, -28.079, -65.146, 240.47]

    def off(res):
        return np.maximum(np.abs(z(res, "C2") - z(res, "C1") - 3), np.abs(z(res, "C3") - z(res, "C2") - 2))

    both = lk.analyze(mech, {"crank1": xs}, method="numerical", branch="continuous", rates=False)
    assert both.assembled.all() and np.max(off(both)) < 1e-10
    for k, x in enumerate(xs):
        alone = lk.analyze(mech, {"crank1": [x]}, method="numerical", branch="continuous", rates=False)
        assert alone.assembled.all() and off(alone)[0] < 1e-10
        for j in mech.joint_names:
            assert abs(z(alone, j)[0] - z(both, j)[k]) < 1e-10


@pytest.mark.parametrize("rocker", [0.95, 0.99, 0.999, 0.9999])
def test_after_a_gap_the_walk_resumes_in_the_poses_mode(rocker):
    """Review 10 (B1): a four-bar (ground 4, crank 1, coupler 4, the rocker a little short of a parallelogram's), its
    crank assembling in two ranges with no change point (for 0.95: [15.81, 159.69] and [200.31, 344.19] deg), forced
    through Newton. Its down leg resumed past the gap with the other determinant sign (-2.32 after +2.32): 240 to
    344 deg in the other mode, the rocker's tip off by up to 1.84. A step after a gap (at least ``GAP_COLUMNS`` grid
    columns unsolved) now has the pose's sign. The closed form is the reference: the same flags, D to 1e-9, in a
    sweep and alone. Rockers 0.999 and 0.9999 leave gaps narrower than three columns (175 of 350 samples in the
    other mode at 0.999 before): a step after unsolved columns of which one has no configuration (a chain rules it
    out) has the pose's sign too."""
    A, B, C = 0j, 4 + 0j, np.exp(1j * np.radians(60))
    mech = lk.Mechanism.from_dict(fourbar_dict(A, B, C, complex(by_cosines(C, B, 4.0, rocker, 1)), C + 0.5 + 0.7j))
    for deg in (np.arange(0.0, 360.0, 3.0), np.array([300.0])):
        ref = lk.analyze(mech, deg, rates=False)
        num = lk.analyze(mech, deg, method="numerical", branch="continuous", rates=False)
        assert num.assembled.tolist() == ref.assembled.tolist() and ref.assembled.any()
        assert np.nanmax(np.abs(z(num, "D") - z(ref, "D"))) < 1e-9


@pytest.mark.parametrize("at", [177.37, 178.0, 178.25, 181.75, 351.37])
def test_a_pose_just_before_a_change_point_stays_a_parallelogram(at):
    """Review 10 (B3): the parallelogram (ground 4, crank 1) forced through Newton, posed a few degrees before its flat
    position. The grid step 2.63 deg from the pose landed 0.37 deg past it on the kite (determinants 1.57, 0.73,
    then 0.10 on the kite, -0.10 on the parallelogram, both along the trend as far as the determinant tells); refused
    now for its velocity, it is taken again from the tangent's predictor, where Newton finds the parallelogram
    (before: 356 of 721 samples kites posed at 177.37 or 178 deg, 5 posed at 351.37). Review 10b: posed at 178.25 or
    181.75, the look-ahead columns were still judged from the refused root (352 kites). Opposite sides parallel to
    1e-12 of the size at every sample, every sample assembled, as the acceptance asks."""
    res = lk.analyze(parallelogram(at=at), DEG, method="numerical", branch="continuous", rates=False)
    assert res.assembled.all()
    assert worst_parallel(res, [("A", "B", "C", "D")]) <= 1e-12


@pytest.mark.parametrize("at", [178.5, 179.0, 179.5, 179.7, 179.9, 180.3, 180.5, 181.5])
def test_forced_through_newton_posed_within_half_a_grid_step_of_the_flat_position(at):
    """Posed within half a grid step (1.5 deg) of the flat position, a parallelogram and a rhombus forced through
    Newton left the parallelogram for 358 to 363 of 721 samples, and a double parallelogram too. Two causes: the
    sub-steps of a refused grid step moved the crank's joint along the chord between two columns (no sign step
    before the group, but its empty signs counted as given per sample), where the two modes only come close and the
    smooth continuation is the other mode; and Newton, started at the last state, took either mode's root. Now the
    sub-steps follow the crank's arc and start from the secant through the last two states (the first from the
    tangent a grid step back). Opposite sides parallel to 1e-12 of the size (the rhombus 1e-11: 2.1e-12 posed at 179
    deg), every sample assembled (the rhombus's singular inputs, 0, 360 and 720 deg, may be flagged, as in
    ``test_a_rhombus_forced_through_newton_stays_a_parallelogram_past_its_singular_point``). The double
    parallelogram's second group takes its knowns from the first, whose
    steps cannot be re-run between two columns: they moved on the chord there (358 samples off posed within 0.4 deg
    of flat), and follow the cubic through the two columns and their rates now. Its sides to 1e-6 (at its flat
    positions, 0 and 360 deg, Newton places the joints of tangent circles to about 1e-7)."""
    res = lk.analyze(parallelogram(at=at), DEG, method="numerical", branch="continuous", rates=False)
    assert res.assembled.all() and worst_parallel(res, [("A", "B", "C", "D")]) <= 1e-12
    res = lk.analyze(parallelogram(2.0, 2.0, at), DEG, method="numerical", branch="continuous", rates=False)
    assert np.all(res.assembled | np.isin(DEG, [0.0, 360.0, 720.0]))  # the rhombus's singular inputs may be flagged
    assert worst_parallel(res, [("A", "B", "C", "D")]) <= 1e-11
    res = lk.analyze(double_parallelogram(at, (3.0, 2.0)), DEG, method="numerical", branch="continuous", rates=False)
    off = np.maximum(abs(z(res, "C2") - z(res, "C1") - 3), abs(z(res, "C3") - z(res, "C2") - 2))
    assert res.assembled.all() and np.max(off) < 1e-6


@pytest.mark.parametrize("at", [30.0, 60.0, 90.0])
def test_a_rhombus_forced_through_newton_stays_a_parallelogram_past_its_singular_point(at):
    """Review 10b (F1): a rhombus (all sides 2) forced through Newton, continuous. At 0 deg its crank lies on the
    ground pivot B and its rocker's tip anywhere on a circle: Newton leaves a column or two unsolved there, and the
    walk, taking that for a gap in the range, restarted in the pose's sign where the branch had crossed (240 of 721
    samples kites, 0..720 deg posed at 60). Only a gap of ``GAP_COLUMNS`` unsolved columns is one now. Opposite
    sides parallel at every assembled sample, in a sweep and each of a few inputs alone (to 1e-10 of the size: next
    to the singular point Newton places the joints to 2e-11, still open against the 1e-12 of the closed form); at
    most the singular inputs (0, 360, 720) flagged. (Posed at 300 or 330 deg, one to four samples just past the
    singular point still land on the kite: docs/method.md.)"""
    mech = parallelogram(2.0, 2.0, at)
    res = lk.analyze(mech, DEG, method="numerical", branch="continuous", rates=False)
    assert set(np.flatnonzero(~res.assembled).tolist()) <= {0, 360, 720}
    assert worst_parallel(res, [("A", "B", "C", "D")]) <= 1e-10
    for x in (241.0, 300.0, 357.0, 717.0):
        alone = lk.analyze(mech, [x], method="numerical", branch="continuous", rates=False)
        assert alone.assembled.all() and worst_parallel(alone, [("A", "B", "C", "D")]) <= 1e-10


def test_a_pose_on_a_flat_position_forced_through_newton_answers_not_an_internal_error():
    """Review 10b (F8): a parallelogram posed on its flat position (0 deg), forced through Newton, raised numpy's
    ValueError from an empty batch (``_real_pairs`` of no design), an internal error, in both branch modes. The walk
    cannot leave a pose where the Jacobian is singular, so every sample is flagged, as not assembled; where it does
    answer, the answer is the closed form's (D to 1e-9)."""
    mech = parallelogram(4.0, 1.0, 0.0)
    ref = lk.analyze(mech, [10.0, 200.0], rates=False)
    for branch in ("pose", "continuous"):
        res = lk.analyze(mech, [10.0, 200.0], method="numerical", branch=branch, rates=False)
        ok = res.assembled
        assert np.all(np.abs(z(res, "D")[ok] - z(ref, "D")[ok]) < 1e-9)
        assert np.all(np.isnan(z(res, "D")[~ok]))


@pytest.mark.long
def test_a_change_point_is_flagged_a_rounding_away_from_it():
    """The double rhombus forced through Newton, its crank within 3e-13 deg of the change point (written 0, 360,
    -360 or 720 deg, in lists): C1 lies within rounding of A2, so C2 is undetermined and every such
    input is flagged.  A dyad-like group's restart after the gap once took a root there whenever rounding gave
    its determinant (2e-16 of the pose's) the pose's sign: -360 deg, alone and in lists, on one machine (where
    the test above failed, CI stop 40).  A restart now refuses a singular root as every other step does."""
    mech = double_parallelogram(90.0, (1.0, 1.0))
    bases = (0.0, 360.0, -360.0, 720.0)
    near = [b + k * 1e-13 for b in bases for k in range(-3, 4)]
    lists = [near, [180.0, *bases], *([x, 180.0, x + 1e-13] for x in bases)]
    got = [lk.analyze(mech, {"crank1": u}, method="numerical", rates=False).assembled for u in lists]
    assert got[1][0] and all(r[-2] for r in got[2:])  # 180 deg is assembled
    flags = np.concatenate([got[0], got[1][1:], *(r[[0, 2]] for r in got[2:])])
    assert not flags.any(), f"{int(flags.sum())} of {len(flags)} assembled at a change point"


@pytest.mark.parametrize(
    ("spans", "at"), [((1.0, 1.0), 3.0), ((1.0, 1.0), 357.0), ((1.0, 2.0), 3.0), ((1.0, 2.0), 90.0), ((1.0, 2.0), 21.0)]
)
def test_forced_through_newton_posed_a_whole_number_of_grid_steps_from_the_flat_position(spans, at):
    """A double parallelogram forced through Newton, continuous, posed a whole number of 3-deg steps from its flat
    positions (0 and 180 deg): the walk's grid, then whole steps of 3 deg from the pose's input, put a column on
    the change point of both loops at once, where the second group's knowns are unknown, and it resumed on the
    other mode (the IFToMM double four-bar posed at 3 or 357 deg: 357 of 721 samples off; the first loop a rhombus
    posed at 3, 90 or 21 deg: 357, 185 and 7). The grid's step is now 3 deg x 998/997, so that no column of a pose
    at a round angle (a multiple of 0.1 deg) falls within 2e-4 deg of another round angle. Both couplers parallel
    to the ground to 1e-6 of the size at every sample off the flat positions (at them, Newton places the joints of
    tangent circles to about 1e-7), the singular inputs of a rhombus (0, 360, 720 deg) at most flagged."""
    res = lk.analyze(double_parallelogram(at, spans), DEG, method="numerical", branch="continuous", rates=False)
    singular = np.isin(DEG, [0.0, 360.0, 720.0]) if spans[0] == 1.0 else np.zeros(len(DEG), bool)
    assert np.all(res.assembled | singular)
    off = np.maximum(abs(z(res, "C2") - z(res, "C1") - spans[0]), abs(z(res, "C3") - z(res, "C2") - spans[1]))
    assert np.max(off[res.assembled]) < 1e-6
