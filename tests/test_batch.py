"""A batch of designs equals each design solved on its own.

``lk.analyze(mech, inputs, poses=poses)`` runs every design through the vectorized kernels
at once, with numbers read off each pose by ``params.compile``.  The reference here is the
other path: ``mech.with_pose(pose)`` builds a Mechanism per design through the model's
validation and shape registration, and ``lk.analyze`` solves it alone.  Positions,
velocities, accelerations, link motion and forces must agree to 1e-12 (relative to the
design's size and to each quantity's scale), with the same NaN / assembled / singular pattern,
over random designs of every kind: different assembly modes, designs that never assemble,
masses, gravity and loads.
"""

import tracemalloc
import zlib

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import linkagekit as lk
from helpers import fourbar_dict, points, random_points, stephenson_dict, watt2_dict
from test_forces import with_dynamics
from test_rates import slider_crank

TOL = 1e-12
ANGLES = np.arange(0.0, 360.0, 7.5)


def random_poses(mech, rng, n):
    """Random reference poses (uniform in [-10, 10]^2 per joint) for the mechanism's topology."""
    return rng.uniform(-10, 10, (n, len(mech.joint_names), 2))


def same(a, b, scale, what):
    """Equal NaN pattern, and equal values to TOL * scale."""
    a, b = np.asarray(a), np.asarray(b)
    assert np.array_equal(np.isnan(a), np.isnan(b)), what
    ok = ~np.isnan(a)
    scale = np.broadcast_to(scale, a.shape)[ok]
    assert np.all(np.abs(a[ok] - b[ok]) <= TOL * scale), (what, np.max(np.abs(a[ok] - b[ok]) / scale))


def compare(mech, poses, inputs, speed=2.5, acceleration=-1.5):
    batch = lk.analyze(mech, inputs, poses=poses, speed=speed, acceleration=acceleration)
    assert batch.shape == (len(poses), len(next(iter(inputs.values()))))
    for i, pose in enumerate(poses):
        one = lk.analyze(mech.with_pose(pose), inputs, speed=speed, acceleration=acceleration)
        size = np.max(np.abs(pose)) + 1.0
        # round-off differs between the two paths (other operation orders); near a singular
        # position the rates amplify it by 1/c (velocities) and 1/c^2 (accelerations), c the
        # solver's dimensionless condition of the sample: the tolerance follows it
        c = np.clip(np.nan_to_num(np.asarray(one.condition, float), nan=1.0), 1e-6, 1.0)
        assert np.array_equal(batch.assembled[i], one.assembled), i
        assert np.array_equal(batch.singular[i], one.singular), i
        assert dict(batch.design(i).signs) == dict(one.signs)
        for j in mech.joint_names:
            same(batch.xy(j)[i], one.xy(j), size, (i, j, "xy"))
            same(batch.point(j)[i], one.point(j), size, (i, j, "z"))
            vs = np.nanmax(np.abs(one.velocity(j)), initial=0.0) + size
            same(batch.velocity(j)[i], one.velocity(j), vs / c, (i, j, "v"))
            acs = np.nanmax(np.abs(one.acceleration(j)), initial=0.0) + size
            same(batch.acceleration(j)[i], one.acceleration(j), acs / c**2, (i, j, "a"))
        for ln in mech.links:
            same(np.cos(np.radians(batch.angle(ln.name)[i])), np.cos(np.radians(one.angle(ln.name))), 1, ln.name)
            ws = np.nanmax(np.abs(one.omega(ln.name)), initial=0.0) + 1
            same(batch.omega(ln.name)[i], one.omega(ln.name), ws / c, (i, ln.name, "omega"))
            als = np.nanmax(np.abs(one.alpha(ln.name)), initial=0.0) + 1
            same(batch.alpha(ln.name)[i], one.alpha(ln.name), als / c**2, (i, ln.name, "alpha"))
        if one.forces is not None:
            fb, fo = batch.forces, one.forces
            scale = max(np.nanmax([np.nanmax(np.abs(r.force), initial=0.0) for r in fo.reactions]), 1.0)
            for rb, ro in zip(fb.reactions, fo.reactions, strict=True):
                assert (rb.joint, rb.on, rb.by) == (ro.joint, ro.on, ro.by)
                same(rb.force[i], ro.force, scale, (i, ro.joint, "reaction"))
            for k in fo.driver_torque:
                same(fb.driver_torque[k][i], fo.driver_torque[k], scale * size, (i, k, "torque"))
            same(fb.shaking_moment[i], fo.shaking_moment, scale * size, (i, "shaking moment"))
            same(fb.input_power[i], fo.input_power, np.nanmax(np.abs(fo.input_power), initial=0) + 1, "power")
    return batch


KINDS = {
    "fourbar": lambda rng: fourbar_dict(*random_points(rng, "ABCDP").values()),
    "watt2": lambda rng: watt2_dict(random_points(rng, "ABECDFGP")),
    "stephenson": lambda rng: stephenson_dict(random_points(rng, "ABCDEFGP")),
    "slider_crank": slider_crank,
}


@pytest.mark.parametrize("kind", sorted(KINDS))
def test_batch_equals_each_design_alone(kind):
    rng = np.random.default_rng(zlib.crc32(kind.encode()))
    mech = lk.Mechanism.from_dict(KINDS[kind](rng))
    poses = random_poses(mech, rng, 40)
    batch = compare(mech, poses, {mech.drivers[0].name: ANGLES})
    # the batch covers designs in different assembly modes, designs that assemble only in
    # part of the turn, and (with these random dimensions) designs that never do
    modes = {tuple(int(batch.signs[j][i]) for j in batch.signs) for i in range(len(poses))}
    assert len(modes) >= 2, modes
    per_design = batch.assembled.sum(axis=1)
    assert (per_design == len(ANGLES)).any() and (per_design < len(ANGLES)).any()


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("kind", ["fourbar", "slider_crank", "stephenson", "watt2"])
def test_batch_with_masses_gravity_and_loads(kind, seed):
    rng = np.random.default_rng(zlib.crc32(kind.encode()) + seed)
    for _ in range(100):  # a random draw that does not assemble at its pose is drawn again (a bounded number of times)
        try:
            d = with_dynamics(KINDS[kind](rng), rng, massless_share=0.0)
            # and always a load at a joint beyond a moving link's first two (it must follow that joint)
            name, spec = max(
                ((k, v) for k, v in d["links"].items() if k != "ground"),
                key=lambda kv: len(kv[1]["joints"] if isinstance(kv[1], dict) else kv[1]),
            )
            joints = spec["joints"] if isinstance(spec, dict) else spec
            d["loads"] = [*d["loads"], {"link": name, "at": joints[-1], "force": [3.0, -40.0]}]
            mech = lk.Mechanism.from_dict(d)
            break
        except lk.LinkageError:
            continue
    else:
        pytest.fail(f"no {kind} of seed {seed} was drawn valid in 100 tries")
    poses = random_poses(mech, rng, 6)
    batch = compare(mech, poses, {mech.drivers[0].name: ANGLES})
    assert batch.forces is not None and batch.forces.driver_torque[mech.drivers[0].name].shape == batch.shape


def test_a_design_that_never_assembles_is_nan_throughout():
    mech = lk.load("examples/seed000_fourbar.yaml")
    good = mech.pose_array()
    # ground 10, crank 9, coupler 1, rocker 1.5: it closes only with the crank near the rocker pivot
    never = good.copy()
    names = mech.joint_names
    for j, p in {"A": (0, 0), "B": (10, 0), "C": (9, 0), "D": (9.6, 0.8), "P": (9.5, 1.5)}.items():
        never[names.index(j)] = p
    batch = compare(mech, np.stack([good, never]), {"crank": [90.0, 180.0, 270.0]})
    assert batch.assembled[0].all() and not batch.assembled[1].any()
    assert np.isnan(batch.xy("P")[1]).all() and np.isnan(batch.velocity("D")[1]).all()


def test_degenerate_design_is_flagged_not_garbage():
    mech = lk.load("examples/seed000_fourbar.yaml")
    bad = mech.pose_array()
    bad[mech.joint_names.index("D")] = bad[mech.joint_names.index("C")]  # coupler of length 0
    res = lk.analyze(mech, [0.0, 45.0], poses=np.stack([mech.pose_array(), bad]))
    assert res.assembled[0].all() and not res.assembled[1].any()
    assert np.isnan(res.xy("P")[1]).all()
    with pytest.raises(lk.MechanismFileError):
        mech.with_pose(bad)


def test_one_pose_equals_the_file_and_design_returns_a_plain_result():
    rng = np.random.default_rng(8)
    mech = lk.Mechanism.from_dict(watt2_dict(random_points(rng, "ABECDFGP")))
    assert not mech.has_given_lengths
    a = lk.analyze(mech, ANGLES)
    b = lk.analyze(mech, ANGLES, poses=mech.pose_array()[None])
    np.testing.assert_allclose(points(b.design(0)), points(a), rtol=0, atol=1e-12)
    assert b.xy("P").shape == (1, len(ANGLES), 2) and b.design(0).xy("P").shape == (len(ANGLES), 2)
    assert b.design(0).to_dict()["joints"]["P"] == a.to_dict()["joints"]["P"]
    # a design back to a mechanism file
    assert lk.load(lk.save(b.mechanism_of(0), "/tmp/_lk_design.yaml")) == mech.with_pose(mech.pose_array())


def test_chunked_batches_equal_one_call(monkeypatch):
    import linkagekit.api as api

    mech = lk.load("examples/seed000_fourbar.yaml")
    rng = np.random.default_rng(4)
    poses = random_poses(mech, rng, 30)
    whole = lk.analyze(mech, ANGLES, poses=poses)
    monkeypatch.setattr(api, "CHUNK_SAMPLES", 100)  # 2 designs per chunk
    cut = lk.analyze(mech, ANGLES, poses=poses)
    np.testing.assert_array_equal(points(cut), points(whole))
    np.testing.assert_array_equal(cut.omega("rocker"), whole.omega("rocker"))
    pieces = list(lk.analyze_chunks(mech, ANGLES, poses=poses, designs=7))
    assert [sl.start for sl, _ in pieces] == [0, 7, 14, 21, 28]
    np.testing.assert_array_equal(np.concatenate([r.xy("P") for _, r in pieces]), whole.xy("P"))


def peak_memory(mech, poses, inputs):
    """Peak traced memory (bytes) of a chunked analysis that keeps only a count."""
    tracemalloc.start()
    assembled = 0
    for _, res in lk.analyze_chunks(mech, inputs, poses=poses):
        assembled += int(res.assembled.sum())
        del res
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return peak, assembled


def test_memory_stays_bounded_over_many_designs():
    """4x more designs in chunks: the same peak memory, far below what the whole output would take."""
    mech = lk.load("examples/seed000_fourbar.yaml")
    rng = np.random.default_rng(0)
    inputs = {"crank": np.arange(0.0, 360.0, 4.0)}
    peaks = {}
    for n_designs in (5_000, 20_000):
        poses = mech.pose_array() * rng.uniform(0.5, 2.0, (n_designs, 1, 1))
        peaks[n_designs], assembled = peak_memory(mech, poses, inputs)
        assert assembled == n_designs * 90  # scaled copies of a crank-rocker: all assemble
    whole = 20_000 * 90 * len(mech.joint_names) * 16 * 3  # z, v, a as complex128
    assert peaks[20_000] < 1.2 * peaks[5_000], peaks
    assert peaks[20_000] < whole / 3, (peaks, whole)


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_batch_property_fourbar(seed):
    rng = np.random.default_rng(seed)
    mech = lk.Mechanism.from_dict(KINDS["fourbar"](rng))
    compare(mech, random_poses(mech, rng, 5), {"crank": np.arange(0.0, 360.0, 30.0)})


def test_bad_poses_get_one_clear_error():
    mech = lk.load("examples/seed000_fourbar.yaml")
    for bad, needle in (
        (np.zeros((2, 4, 2)), "shape"),
        (np.full((1, 5, 2), np.nan), "finite"),
        ("abc", "numbers"),
        (np.zeros((0, 5, 2)), "no design"),
    ):
        with pytest.raises(lk.InputError, match=needle):
            lk.analyze(mech, [0.0], poses=bad)
    with pytest.raises(lk.InputError, match="vector-loop"):
        lk.analyze(mech, [0.0], poses=mech.pose_array()[None], method="vector-loop")


def test_every_number_carries_the_design_axis():
    """Steps' numbers, masses, inertias, centres of gravity and loads: one row per design; the plan holds none."""
    import pickle

    from linkagekit.params import compile
    from linkagekit.plan import make_plan

    mech = lk.load("examples/slider_crank.yaml")
    plan = make_plan(mech)
    assert hash(plan) == hash(pickle.loads(pickle.dumps(plan))) and pickle.loads(pickle.dumps(plan)) == plan
    for step in plan.steps:  # topology only: indices, names, slots
        for value in vars(step).values():
            assert isinstance(value, int | str | bool | tuple | type(None)), (step, value)
    poses = np.stack([mech.pose_array() * s for s in (1.0, 1.1, 1.2)])
    p = compile(mech, poses)

    def rows(x):
        if isinstance(x, tuple):
            return [r for y in x for r in rows(y)]
        return [np.shape(x)[-2]] if np.ndim(x) >= 2 else []

    assert set(rows(p.steps)) == {3}
    assert all(b.mass.shape == (3, 1) and b.inertia.shape == (3, 1) for b in p.bodies)
    assert all(b.cg is None or b.cg.shape == (3, 1) for b in p.bodies)
    assert p.loads and all(ld.force.shape == (3, 1) for ld in p.loads)
    assert p.signs.shape == (plan.n_signs, 3) and p.pose_inputs.shape == (1, 3)


def test_a_load_at_a_joint_follows_that_joint_in_every_design():
    """A load written `at: P` (third joint of the coupler) acts at each design's own P.

    Reference: virtual work, T = -F . dP/dphi, with dP/dphi from the per-design velocities.
    """
    d = {
        "joints": {"A": [0, 0], "B": [4, 1], "C": [2, 0], "D": [0.820550528229663, 4.85889894354067], "P": [5.6, 3.4]},
        "links": {"ground": ["A", "B"], "crank": ["A", "C"], "coupler": ["C", "D", "P"], "rocker": ["B", "D"]},
        "drivers": [{"link": "crank", "pivot": "A", "toward": "C"}],
        "loads": [{"link": "coupler", "at": "P", "force": [0, -100]}],
    }
    mech = lk.Mechanism.from_dict(d)
    other = mech.pose_array().copy()
    other[mech.joint_names.index("P")] = [1.0, 2.0]
    poses = np.stack([mech.pose_array(), other])
    batch = lk.analyze(mech, [0.0, 90.0], poses=poses, speed=1.0, acceleration=0.0)
    for i in range(2):
        one = lk.analyze(mech.with_pose(poses[i]), [0.0, 90.0], speed=1.0, acceleration=0.0)
        vp = one.velocity("P")  # dP/dphi at unit speed
        work = -(0 * vp.real + (-100) * vp.imag)  # T w = -F . v_P, w = 1
        np.testing.assert_allclose(batch.forces.driver_torque["crank"][i], work, rtol=1e-9)
        np.testing.assert_allclose(one.forces.driver_torque["crank"], work, rtol=1e-9)


def test_signs_by_name_in_a_batch_over_several_chunks(monkeypatch):
    """A mapping of signs keeps each design's own mode for the others, chunk by chunk."""
    import linkagekit.api as api

    rng = np.random.default_rng(21)
    mech = lk.Mechanism.from_dict(KINDS["watt2"](rng))
    poses = random_poses(mech, rng, 9)
    flip = next(iter(lk.reference_signs(mech)))
    whole = lk.analyze(mech, ANGLES, poses=poses, signs={flip: -1})
    monkeypatch.setattr(api, "CHUNK_SAMPLES", 2 * len(ANGLES))  # 2 designs per chunk
    cut = lk.analyze(mech, ANGLES, poses=poses, signs={flip: -1})
    np.testing.assert_array_equal(points(cut), points(whole))
    for i, pose in enumerate(poses):
        one = lk.analyze(mech.with_pose(pose), ANGLES, signs={flip: -1})
        np.testing.assert_allclose(points(cut.design(i)), points(one), rtol=0, atol=1e-12 * (1 + np.abs(pose).max()))
        assert dict(cut.design(i).signs) == dict(one.signs)
