"""The public Result: shapes, read-only arrays, one error type for unknown names, columns
shared by every output, pandas, a short repr; check and modes typed and in file units."""

import json

import numpy as np
import pytest

import linkagekit as lk
from linkagekit.checks import CheckReport, Modes
from linkagekit.cli import main


@pytest.fixture(scope="module")
def res():
    return lk.analyze(lk.load("examples/slider_crank.yaml"), np.linspace(0, 360, 361))


def test_points_as_float_pairs(res):
    xy = res.xy("A")
    assert xy.shape == (361, 2) and xy.dtype == float
    np.testing.assert_array_equal(xy[:, 0] + 1j * xy[:, 1], res.point("A"))
    np.testing.assert_array_equal(res.vxy("B")[:, 0], res.velocity("B").real)
    np.testing.assert_array_equal(res.axy("B")[:, 1], res.acceleration("B").imag)
    # the crank tip at 90 deg: 0.05 m straight up, and it moves at 10 rad/s * 0.05 m along -x
    assert res.xy("A")[90] == pytest.approx([0.0, 0.05], abs=1e-15)
    assert res.vxy("A")[90] == pytest.approx([-0.5, 0.0], abs=1e-14)


def test_arrays_are_read_only(res):
    for arr in (
        res.xy("A"),
        res.point("A"),
        res.velocity("A"),
        res.assembled,
        res.omega("rod"),
        res.angle("rod"),
        res.inputs["crank"],
        res.forces.driver_torque["crank"],
        res.forces.reactions[0].force,
    ):
        with pytest.raises(ValueError):
            arr[0] = 0
    with pytest.raises(AttributeError):
        res.forces = None
    with pytest.raises(TypeError):
        res.link_omega["rod"] = np.zeros(361)


def test_unknown_names_raise_one_error_type(res):
    for call in (
        lambda: res.xy("Z"),
        lambda: res.omega("nope"),
        lambda: res.forces.reaction("Z", "rod"),
        lambda: res.mechanism.link("nope"),
    ):
        with pytest.raises(lk.UnknownNameError) as info:
            call()
        assert isinstance(info.value, LookupError) and isinstance(info.value, lk.LinkageError)
        assert "'" in str(info.value) and not str(info.value).startswith('"')


def test_short_repr(res):
    text = repr(res)
    assert len(text) < 200 and "361 samples" in text and "forces" in text


def test_columns_are_shared_by_csv_json_and_pandas(res, capsys):
    cols = res.columns()
    units = res.column_units()
    assert list(cols) == list(units)
    assert units["B.vx"] == "m/s" and units["rod.alpha"] == "rad/s²" and units["T[crank]"] == "N·m"
    assert units["input:crank"] == "deg" and units["|F|[O:ground>crank]"] == "N"
    assert all(np.shape(c) == (361,) for c in cols.values())
    df = res.to_pandas()
    assert list(df.columns) == list(cols) and len(df) == 361
    np.testing.assert_array_equal(df["B.x"].to_numpy(), cols["B.x"])
    assert main(["analyze", "examples/slider_crank.yaml", "--format", "csv"]) == 0
    header = capsys.readouterr().out.splitlines()[0].split(",")
    assert header == list(cols)
    doc = res.to_dict()
    assert doc["joints"]["B"]["vx"][10] == pytest.approx(cols["B.vx"][10], rel=1e-15)
    assert doc["driver_torque"]["crank"][10] == pytest.approx(cols["T[crank]"][10], rel=1e-15)
    json.dumps(doc, allow_nan=False)


def test_batch_result_to_pandas_and_positions_only():
    mech = lk.load("examples/seed000_fourbar.yaml")
    poses = np.stack([mech.pose_array(), 1.5 * mech.pose_array()])
    res = lk.analyze(mech, [0.0, 90.0, 180.0], poses=poses, rates=False)
    assert res.n_designs == 2 and res.shape == (2, 3) and not res.has_rates
    df = res.to_pandas()
    assert df.index.names == ["design", "sample"] and len(df) == 6 and "P.vx" not in df
    np.testing.assert_allclose(res.xy("P")[1], 1.5 * res.xy("P")[0], rtol=1e-12)
    with pytest.raises(lk.InputError, match="positions only"):
        res.velocity("P")
    assert "2 designs x 3 samples" in repr(res)
    assert res.to_dict()["joints"]["P"]["x"][1] == pytest.approx(list(1.5 * res.xy("P")[0][:, 0]))


def test_check_and_modes_are_typed_and_in_file_units():
    mech = lk.load("examples/seed003_ex21.yaml")  # degrees
    rep = lk.check(mech)
    assert isinstance(rep, CheckReport) and isinstance(lk.modes(mech), Modes)
    assert rep.dof == 1 and rep.grashof == "non-grashof" and rep.to_dict()["input_range"] == rep.input_range
    m = lk.modes(mech, at=120.0)  # file units: 120 deg, not 120 rad
    assert m.input == {"crank": 120.0}
    res = lk.analyze(mech, [120.0])
    pose_mode = next(mo for mo in m.modes if mo.reference)
    assert pose_mode.joints["B"] == pytest.approx(tuple(res.xy("B")[0]), abs=1e-9)
    assert m.to_dict()["format"] == "linkagekit-modes/1"
    with pytest.raises(lk.InputError):
        lk.modes(mech, at={"rocker": 3.0})


def test_signs_by_name_and_opposite_mode():
    mech = lk.load("examples/seed000_fourbar.yaml")
    ref = lk.reference_signs(mech)
    assert ref == {"D": 1}
    a = lk.analyze(mech, [30.0])
    b = lk.analyze(mech, [30.0], signs={"D": -1})
    c = lk.analyze(mech, [30.0], signs=[-1])
    assert dict(a.signs) == {"D": 1} and dict(b.signs) == {"D": -1}
    np.testing.assert_array_equal(b.xy("D"), c.xy("D"))
    # the other circle-circle solution: D mirrored in the line C -> B
    C, B, D = a.point("C")[0], a.point("B")[0], a.point("D")[0]
    u = (B - C) / abs(B - C)
    mirrored = C + u * np.conj((D - C) / u)
    assert b.point("D")[0] == pytest.approx(mirrored, abs=1e-12)
    for bad in ({"Q": 1}, [0.5], [1, 1]):
        with pytest.raises(lk.InputError):
            lk.analyze(mech, [30.0], signs=bad)


def test_per_sample_signs_and_partial_mappings():
    rng_pose = lk.load("examples/watt2_sixbar.yaml")
    mech = lk.Mechanism.from_dict(
        rng_pose.to_dict()
        | {"links": {k: (v["joints"] if isinstance(v, dict) else v) for k, v in rng_pose.to_dict()["links"].items()}}
    )
    assert not mech.has_given_lengths
    ref = lk.reference_signs(mech)
    ang = np.array([10.0, 20.0, 30.0])
    # a mapping with one sign: the other keeps the pose's
    flip = next(iter(ref))
    other = [j for j in ref if j != flip]
    res = lk.analyze(mech, ang, signs={flip: -ref[flip]})
    assert res.signs[flip] == -ref[flip] and all(res.signs[j] == ref[j] for j in other)
    full = lk.analyze(mech, ang, signs=[(-ref[j] if j == flip else ref[j]) for j in ref])
    np.testing.assert_array_equal(res.xy("P"), full.xy("P"))
    # one sign per sample: reported per sample, equal to solving each sample in its mode
    per = np.array([[ref[j]] * 3 for j in ref], float)
    per[list(ref).index(flip), 1] = -ref[flip]
    res = lk.analyze(mech, ang, signs=per)
    assert res.signs[flip].shape == (3,) and res.signs[flip].tolist() == [ref[flip], -ref[flip], ref[flip]]
    np.testing.assert_array_equal(res.xy("P")[1], full.xy("P")[1])
    batch = lk.analyze(mech, ang, signs=per, poses=np.stack([mech.pose_array()] * 2))
    assert batch.signs[flip].shape == (2, 3) and batch.design(1).signs[flip].tolist() == res.signs[flip].tolist()
    with pytest.raises(ValueError):
        batch.signs[flip][0, 0] = 5
    # mirrors by name; bad values are input errors
    mirrored = lk.analyze(mech, ang, mirrors={"rocker": True})
    assert not np.allclose(mirrored.xy("F"), lk.analyze(mech, ang).xy("F"))
    for bad in ({flip: "x"}, {flip: 0.5}):
        with pytest.raises(lk.InputError):
            lk.analyze(mech, ang, signs=bad)
    with pytest.raises(lk.InputError):
        lk.analyze(mech, ang, mirrors={"rocker": "yes"})


def test_bad_arguments_to_the_api_are_linkage_errors(tmp_path):
    mech = lk.load("examples/seed000_fourbar.yaml")
    batch = lk.analyze(mech, [0.0], poses=mech.pose_array()[None])
    one = lk.analyze(mech, [0.0])
    calls = [
        lambda: lk.save(None, tmp_path / "x.yaml"),
        lambda: lk.save(mech, None),
        lambda: lk.save(mech, tmp_path / "x.txt"),
        lambda: lk.load(None),
        lambda: lk.analyze("not a mechanism", [0.0]),
        lambda: lk.analyze(mech, []),
        lambda: batch.design(1.0),
        lambda: batch.design("a"),
        lambda: batch.design(5),
        lambda: batch.mechanism_of(7),
        lambda: one.design(0),
        lambda: list(lk.analyze_chunks(mech, [0.0], poses=mech.pose_array()[None], designs="2")),
    ]
    for call in calls:
        with pytest.raises(lk.LinkageError):
            call()
