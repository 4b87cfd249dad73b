"""Exact motion generation by Burmester theory (synthesis/burmester.py).

Every four-bar listed is checked here by an independent computation: the linkage solver
(``lk.analyze``) run on its mechanism at the poses' crank angles, in both assembly modes, or
the plain geometry of the poses (a circle point's positions on one circle about its center).
"""

import json
from pathlib import Path

import numpy as np
import pytest

import linkagekit as lk
from linkagekit.errors import InputError, LinkageError
from linkagekit.synthesis import burmester as bm

TARGETS = Path("/work/shared/benchmarks/motion-function/targets.json")
LINKS = {"ground": ["A0", "B0"], "crank": ["A0", "A1"], "coupler": ["A1", "B1", "P", "Q"], "rocker": ["B0", "B1"]}


def fourbar(z):
    """A four-bar of joints A0, A1, B1, B0, P, Q (complex, in that order), driven by its crank."""
    joints = {j: [float(v.real), float(v.imag)] for j, v in zip(bm.JOINTS, z, strict=True)}
    drv = {"link": "crank", "pivot": "A0", "toward": "A1", "angles": {"start": 0, "stop": 360, "step": 1}}
    return lk.Mechanism.from_dict({"format": "linkagekit/1", "joints": joints, "links": LINKS, "drivers": [drv]})


def random_poses(rng, n):
    """A random four-bar, and ``n`` poses of its coupler in order along the run of crank angles it assembles over."""
    while True:
        z = rng.normal(size=6) + 1j * rng.normal(size=6)
        z[5] = z[4] + np.exp(1j * rng.uniform(0, 2 * np.pi))
        mech = fourbar(z)
        phi0 = np.degrees(np.angle(z[1] - z[0]))
        grid = phi0 + np.arange(-180, 180.5, 0.5)
        ok = lk.analyze(mech, {"crank": grid}, rates=False, dynamics=False).assembled
        k0 = 360  # the pose's own angle; the run of assembled samples around it
        lo = k0 - np.argmin(np.r_[ok[k0::-1], False])
        hi = k0 + np.argmin(np.r_[ok[k0:], False])
        if grid[hi - 1] - grid[lo + 1] < 40:
            continue
        inputs = np.sort(rng.uniform(grid[lo + 1], grid[hi - 1], n))
        if np.min(np.diff(inputs)) < 3:
            continue
        res = lk.analyze(mech, {"crank": inputs}, rates=False, dynamics=False)
        p, q = res.point("P"), res.point("Q")
        return z, res, (p.real, p.imag, np.angle(q - p))


def pose_errors(fb):
    """Largest position and angle error of a listed four-bar at its poses, by lk.analyze in the better of both modes."""
    mech = fb.mechanism()
    out = []
    for sign in (1, -1):
        res = lk.analyze(mech, {"crank": np.degrees(fb.inputs)}, signs=[sign], rates=False, dynamics=False)
        p, q = res.point("P"), res.point("Q")
        out.append((np.abs(p - fb.poses.d), np.abs(np.angle((q - p) / np.exp(1j * fb.poses.theta)))))
    pos = np.fmin(out[0][0], out[1][0])
    ang = np.where(out[0][0] <= out[1][0], out[0][1], out[1][1])
    return float(np.max(pos)), float(np.max(ang))


def on_circle(poses, dy):
    """How far the circle point's positions at the poses are from one circle about the ground pivot."""
    w = (dy.moving - poses.d[0]) / np.exp(1j * poses.theta[0])
    r = np.abs(poses.d + np.exp(1j * poses.theta) * w - dy.ground)
    return float(np.ptp(r))


def same_dyads(fb, a, b, tol):
    """Whether the four-bar's dyads are (a, b) in either order, to ``tol``."""
    pairs = ((fb.crank, fb.rocker), (fb.rocker, fb.crank))
    return any(
        abs(u.ground - x.ground) + abs(u.moving - x.moving) + abs(v.ground - y.ground) + abs(v.moving - y.moving) <= tol
        for (u, v), (x, y) in ((pq, (a, b)) for pq in pairs)
    )


# ---------------------------------------------------------------------- 5 poses
@pytest.mark.skipif(not TARGETS.exists(), reason="the public benchmark data is not on this machine")
def test_hsieh2_generator_is_among_the_burmester_fourbars():
    data = json.loads(TARGETS.read_text())["hsieh2_generating_mechanism"]
    poses = np.array(data["exact5_poses"]["poses"])
    x, y, angle = poses[:, 0], poses[:, 1], np.arctan2(poses[:, 3], poses[:, 2])
    fbs = bm.exact_motion((x, y, angle))
    par = data["four_bar_rs_params"]
    a0 = complex(par["p1x"], par["p1y"])
    b0 = a0 + par["l1"] * np.exp(1j * par["a"])
    t0 = data["exact5_poses"]["crank_angles_rad"][0]
    a1 = a0 + par["l2"] * np.exp(1j * (par["a"] + t0))
    phi3 = angle[0] - par["e"]  # body orientation = e + phi3, phi3 = angle(B1 - A1)
    b1 = a1 + par["l3"] * np.exp(1j * phi3)
    size = abs(b0 - a0) + par["l2"]
    gen = [fb for fb in fbs if same_dyads(fb, bm.Dyad(a0, a1), bm.Dyad(b0, b1), 1e-9 * size)]
    assert len(gen) == 1 and 2 <= len(fbs) <= 6
    assert gen[0].in_order and gen[0].grashof == "non-grashof"
    assert gen[0].crank.ground == pytest.approx(a0, abs=1e-9 * size)  # the crank of the generator drives
    for fb in fbs:
        pos, ang = pose_errors(fb)
        assert pos <= 1e-9 and ang <= 1e-9
        assert fb.position_error <= 1e-9 and fb.angle_error <= 1e-9


@pytest.mark.parametrize("seed", range(6))
def test_random_fourbar_is_found_from_five_poses(seed):
    rng = np.random.default_rng(seed)
    z, res, xya = random_poses(rng, 5)
    poses = bm.motion_poses(*xya)
    size = float(np.max(np.abs(z[:4, None] - z[None, :4])))
    fbs = bm.exact_motion(poses)
    crank, rocker = bm.Dyad(z[0], res.point("A1")[0]), bm.Dyad(z[3], res.point("B1")[0])
    found = [fb for fb in fbs if same_dyads(fb, crank, rocker, 1e-9 * size)]
    assert len(found) == 1 and found[0].in_order
    assert len(fbs) in (1, 3, 6)  # 2 or 4 real Burmester points, a pair each
    for fb in fbs:
        assert on_circle(poses, fb.crank) <= 1e-9 * size and on_circle(poses, fb.rocker) <= 1e-9 * size
        pos, ang = pose_errors(fb)
        assert pos <= 1e-9 * size and ang <= 1e-9
        assert fb.position_error == pytest.approx(pos, abs=1e-12 * size)  # its own residual is the solver's


def test_burmester_points_skip_the_poles_and_agree_with_the_center_point_curves():
    rng = np.random.default_rng(11)
    _, _, xya = random_poses(rng, 5)
    poses = bm.motion_poses(*xya)
    dyads = bm.burmester_points(poses)
    pole = bm.poles(poses, [(0, 1), (0, 2), (1, 2)])
    assert len(dyads) in (2, 4)
    for dy in dyads:
        assert np.min(np.abs(pole - dy.ground)) > 1e-6 * poses.size
        for drop in range(5):  # on every 4-pose center-point curve: its 4 positions concyclic
            four = bm.motion_poses(*(np.delete(v, drop) for v in xya))
            assert on_circle(four, bm.dyad_from_center(four, dy.ground)) <= 1e-9 * poses.size
    # a pole is on both cubics (f = g = 0) but no center point of all five poses
    assert on_circle(poses, bm.dyad_from_center(poses, pole[0])) > 1e-3 * poses.size


def newton_dyads(poses, starts, steps=40):
    """Dyads of 5 poses by Newton's method on ``|W_j - c|^2 = |W_0 - c|^2`` from many ground pivots at once.

    No cubic, no resultant: an independent search for the Burmester points (its circle point
    starts at the least-squares circle of the ground pivot's positions seen from the body);
    those with both pivots within ``bm.FAR`` sizes of the poses, as the module lists them.
    """
    d, rot = poses.d, np.exp(1j * poses.theta)
    c = np.asarray(starts, complex)
    z = (c[:, None] - d) / rot  # the ground pivot seen from the body
    a = np.stack([2 * z.real, 2 * z.imag, np.ones(z.shape)], axis=-1)
    sol = np.linalg.pinv(a) @ (np.abs(z) ** 2)[..., None]
    w = sol[:, 0, 0] + 1j * sol[:, 1, 0]
    with np.errstate(all="ignore"):
        for _ in range(steps):
            u = d + rot * w[:, None] - c[:, None]
            e = np.abs(u[:, 1:]) ** 2 - np.abs(u[:, :1]) ** 2
            dc = -2 * (u[:, 1:] - u[:, :1])
            dw = 2 * (np.conj(rot[1:]) * u[:, 1:] - np.conj(rot[0]) * u[:, :1])
            jac = np.stack([dc.real, dc.imag, dw.real, dw.imag], axis=-1)
            ok = np.abs(np.linalg.det(jac)) > 1e-300
            step = np.zeros((c.size, 4))
            step[ok] = np.linalg.solve(jac[ok], e[ok][..., None])[..., 0]
            c, w = c - (step[:, 0] + 1j * step[:, 1]), w - (step[:, 2] + 1j * step[:, 3])
        u = d + rot * w[:, None] - c[:, None]
        r = np.abs(u)
        good = np.isfinite(r).all(axis=1) & (np.ptp(r, axis=1) <= 1e-10 * poses.size)
        moving = d[0] + rot[0] * w
        mid = d.mean()
        near = np.maximum(np.abs(c - mid), np.abs(moving - mid)) < bm.FAR * poses.size  # the module's bound
    out = []
    for ci in c[good & near]:
        if all(abs(ci - o) > 1e-6 * poses.size for o in out):
            out.append(ci)
    return out


@pytest.mark.parametrize("seed", [21, 22, 23])
def test_every_burmester_point_newton_finds_is_listed(seed):
    rng = np.random.default_rng(seed)
    _, _, xya = random_poses(rng, 5)
    poses = bm.motion_poses(*xya)
    mid, size = poses.d.mean(), poses.size
    starts = mid + size * (rng.uniform(-4, 4, 600) + 1j * rng.uniform(-4, 4, 600))
    brute = newton_dyads(poses, starts)
    listed = [dy.ground for dy in bm.burmester_points(poses)]
    assert len(brute) >= 2
    for c in brute:  # complete: nothing the independent search finds is missing
        assert min(abs(c - g) for g in listed) <= 1e-8 * size


def test_translations_between_poses_put_poles_at_infinity():
    rng = np.random.default_rng(5)
    x, y = rng.normal(size=5), rng.normal(size=5)
    poses = bm.motion_poses(x, y, np.array([0.2, 0.2, 0.2, 1.4, 2.0]))  # poses 1, 2, 3: translations
    assert not np.isfinite(bm.poles(poses, [(0, 1), (0, 2), (1, 2)])).any()
    starts = poses.d.mean() + poses.size * (rng.uniform(-4, 4, 600) + 1j * rng.uniform(-4, 4, 600))
    brute = newton_dyads(poses, starts)
    listed = bm.burmester_points(poses)
    assert len(brute) >= 2 and len(listed) >= len(brute)
    for c in brute:
        assert min(abs(c - dy.ground) for dy in listed) <= 1e-8 * poses.size
    assert max(on_circle(poses, dy) for dy in listed) <= 1e-9 * poses.size


# ---------------------------------------------------------------------- 4 and 3 poses
def test_center_point_curve_holds_a_known_dyad_and_only_center_points():
    rng = np.random.default_rng(3)
    z, res, xya = random_poses(rng, 4)
    poses = bm.motion_poses(*xya)
    cur = bm.center_point_curve(poses, samples=720)
    f = bm._Frame.of(poses)
    cubic = f.cubic(poses, (0, 1, 2, 3))
    typical = np.max(np.abs(bm._eval(cubic, f.from_plane(poses.d))))
    for c in (z[0], z[3]):  # the generator's center points: roots of the cubic, and near a sample
        assert abs(bm._eval(cubic, f.from_plane(c))) <= 1e-12 * typical
        assert np.nanmin(np.abs(cur.center - c)) <= 0.02 * poses.size
    dyads = cur.dyads()
    assert len(dyads) > 300
    assert max(on_circle(poses, dy) for dy in dyads[::7]) <= 1e-9 * poses.size
    fbs = bm.exact_motion(poses, count=4)
    assert len(fbs) == 4 and fbs[0].in_order
    for fb in fbs:
        pos, ang = pose_errors(fb)
        assert pos <= 1e-9 * poses.size and ang <= 1e-9


def test_three_poses_exact_for_given_and_default_dyads():
    x, y, angle = [0.0, 1.0, 2.0], [0.0, 0.8, 0.6], np.radians([10.0, -20.0, -60.0])
    poses = bm.motion_poses(x, y, angle)
    fbs = bm.exact_motion(poses)
    assert len(fbs) == 6 and all(fb.in_order for fb in fbs)
    mine = bm.exact_motion(poses, centers=[-1 - 1j, 3 - 2j])
    assert {mine[0].crank.ground, mine[0].rocker.ground} == {-1 - 1j, 3 - 2j}
    by_point = bm.exact_motion(poses, circle_points=[0.5 + 0.5j, 1.5 - 0.2j])
    assert {by_point[0].crank.moving, by_point[0].rocker.moving} == {0.5 + 0.5j, 1.5 - 0.2j}
    for fb in [*fbs, *mine, *by_point]:
        assert on_circle(poses, fb.crank) <= 1e-12 and on_circle(poses, fb.rocker) <= 1e-12
        pos, ang = pose_errors(fb)
        assert pos <= 1e-9 and ang <= 1e-9


def test_mechanism_of_a_fourbar_is_the_spec_file():
    x, y, angle = [0.0, 1.0, 2.0], [0.0, 0.8, 0.6], np.radians([10.0, -20.0, -60.0])
    fb = bm.exact_motion((x, y, angle), count=1)[0]
    mech = fb.mechanism(unit="mm", name="hatch")
    d = mech.to_dict()
    assert d["units"]["length"] == "mm" and d["links"]["crank"] == ["A0", "A1"]
    assert d["drivers"][0]["link"] == "crank" and set(d["links"]) == {"ground", "crank", "coupler", "rocker"}
    # Q on the first pose's line, a tenth of the pose points' diagonal (2 x 0.8) from P (it was one length unit:
    # 47 diagonals for poses 21 mm across given in metres, review 18a)
    q = 0.1 * np.hypot(2.0, 0.8) * np.array([np.cos(0.1745329), np.sin(0.1745329)])
    assert d["joints"]["P"] == [0.0, 0.0] and np.allclose(d["joints"]["Q"], q, rtol=1e-7)
    res = lk.analyze(mech, rates=False, dynamics=False)  # its default sweep: the first pose to the last, in order
    assert res.assembled.all()
    sweep = np.radians(mech.drivers[0].sweep.values())
    assert sweep[0] == pytest.approx(fb.inputs[0]) and sweep[-1] == pytest.approx(fb.inputs[-1])


# ---------------------------------------------------------------------- bad input
@pytest.mark.parametrize(
    ("x", "y", "angle", "message"),
    [
        ([0, 1, 0], [0, 1, 0], [0, 1, 0], "poses 1 and 3 coincide"),
        ([0, 1], [0, 1], [0, 1], "at least 3 poses"),
        ([0, 1, np.nan], [0, 1, 2], [0, 1, 2], r"x\[2\] is not a finite number"),
        ([0, 1, 2], [0, 1], [0, 1, 2], "different lengths"),
        ([1, 1, 1], [2, 2, 2], [0, 1, 2], "one spot"),
        (range(6), np.arange(6) ** 2, np.arange(6) / 10, "takes 3, 4 or 5 poses, got 6"),
    ],
)
def test_bad_poses_raise_one_line(x, y, angle, message):
    with pytest.raises(InputError, match=message) as err:
        bm.exact_motion((np.asarray(x, float), np.asarray(y, float), np.asarray(angle, float)))
    assert isinstance(err.value, LinkageError) and "\n" not in str(err.value)


def test_given_centers_are_moved_onto_the_curve_or_to_the_burmester_points():
    rng = np.random.default_rng(3)
    z, res, xya = random_poses(rng, 5)
    four = bm.motion_poses(*(v[:4] for v in xya))
    near = [z[0] + 0.01, z[3] - 0.01j]  # a pick off a plot of the curve
    fb = bm.exact_motion(four, centers=near)[0]
    for dy in (fb.crank, fb.rocker):
        assert on_circle(four, dy) <= 1e-9 * four.size  # on the curve: exact
    for c in near:  # and near the picks
        assert min(abs(dy.ground - c) for dy in (fb.crank, fb.rocker)) <= 0.03
    pos, ang = pose_errors(fb)
    assert pos <= 1e-9 * four.size and ang <= 1e-9
    five = bm.motion_poses(*xya)
    fb5 = bm.exact_motion(five, centers=near)[0]  # the nearest Burmester points: the generator
    listed = np.array([fb5.crank.ground, fb5.rocker.ground])
    assert np.abs(listed[:, None] - z[[0, 3]]).min(axis=0).max() <= 1e-9 * five.size
    with pytest.raises(InputError, match=r"centers\[1\]: the same dyad as an earlier one"):
        bm.exact_motion(five, centers=[z[0], z[0] + 1e-3])
    with pytest.raises(InputError, match="count: a whole number"):
        bm.exact_motion(four, count=0)
