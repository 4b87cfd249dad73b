"""The mechanism model: immutable, hashable, round-trips through to_dict, YAML and JSON; with_pose; dof."""

from __future__ import annotations

import copy
import dataclasses
import json
import os
import pickle
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

from linkagekit.errors import LinkageError, MechanismFileError, UnknownNameError
from linkagekit.files import dumps, load, save
from linkagekit.model import FrozenMap, Link, Mechanism

EXAMPLES = sorted(Path("examples").glob("*.yaml"))
assert EXAMPLES, "run from the repository root"


def pose_of(m: Mechanism) -> np.ndarray:
    return np.array([[z.real, z.imag] for z in m.joints.values()])


def fourbar_dict() -> dict:
    """The four-bar of the spec, with a coupler point, mass properties, loads and rad units."""
    return {
        "format": "linkagekit/1",
        "name": "four-bar",
        "description": "A crank-rocker.\nSecond line: with `on` and: colons\n",
        "units": {"length": "cm", "angle": "rad"},
        "joints": {"A": [0, 0], "B": [4, 1], "C": [2, 0], "D": [0.8206, 4.8589], "P": [5.6182, 3.4509]},
        "links": {
            "ground": {"joints": ["A", "B"]},
            "crank": {"joints": ["A", "C"], "mass": 0.5, "cg": [1.0, 0.0], "inertia": 0.01},
            "coupler": {"joints": ["C", "D", "P"], "mass": 2, "cg": [2.8, 2.77], "inertia": 0.3},
            "rocker": ["B", "D"],
        },
        "drivers": [{"link": "crank", "pivot": "A", "toward": "C", "speed": 2.5}],
        "gravity": [0, -9.81],
        "loads": [
            {"link": "coupler", "at": [3.1, 1.7], "force": [1, -2]},
            {"link": "rocker", "torque": -5},
            {"link": "rocker", "at": "D", "torque": 0.5},
        ],
    }


def slider_dict() -> dict:
    return {
        "name": "slider-crank",
        "joints": {"O": [0, 0], "A": [0.03, 0.04], "B": [0.115, 0.0]},
        "links": {
            "ground": ["O"],
            "crank": ["O", "A"],
            "rod": ["A", "B"],
            "block": {"joints": ["B"], "cg": [0.1, 0.01]},
        },
        "drivers": [{"slider": 0, "displacements": {"start": -0.01, "stop": 0.01, "step": 0.001}}],
        "sliders": [{"link": "block", "on": "ground", "through": "B", "direction": [3.0, 4.0]}],
        "loads": [{"link": "block", "at": [0.12, 0.02], "force": [-50, 0]}],
    }


def all_mechanisms() -> list[tuple[str, Mechanism]]:
    out = [(p.name, load(p)) for p in EXAMPLES]
    out.append(("fourbar_dict", Mechanism.from_dict(fourbar_dict())))
    out.append(("slider_dict", Mechanism.from_dict(slider_dict())))
    return out


CASES = all_mechanisms()
IDS = [name for name, _ in CASES]


def assert_plain(value: object, where: str = "") -> None:
    """Only dict (str keys), list, float, int (slider index), str: no numpy, no tuple, no complex."""
    if isinstance(value, dict):
        for k, v in value.items():
            assert type(k) is str, where
            assert_plain(v, f"{where}.{k}")
    elif isinstance(value, list):
        for i, v in enumerate(value):
            assert_plain(v, f"{where}[{i}]")
    else:
        assert type(value) in (float, str, int), f"{where}: {type(value)}"


# ---------------------------------------------------------------------- round trips
@pytest.mark.parametrize(("name", "m"), CASES, ids=IDS)
def test_to_dict_round_trip(name: str, m: Mechanism) -> None:
    d = m.to_dict()
    assert_plain(d)
    assert d["format"] == "linkagekit/1"
    back = Mechanism.from_dict(d)
    assert back == m
    assert hash(back) == hash(m)
    assert back.to_dict() == d
    assert back.joint_names == m.joint_names
    json.dumps(d, allow_nan=False)  # JSON-serialisable as it is


@pytest.mark.parametrize("suffix", [".yaml", ".yml", ".json"])
@pytest.mark.parametrize(("name", "m"), CASES, ids=IDS)
def test_save_load_round_trip(name: str, m: Mechanism, suffix: str, tmp_path: Path) -> None:
    out = save(m, tmp_path / f"x{suffix}")
    assert out == tmp_path / f"x{suffix}"
    back = load(out)
    assert back == m
    assert back.source == str(out)
    # floats bit-identical, not just equal to a tolerance
    assert back.to_dict() == m.to_dict()
    assert [ln.shape for ln in back.links] == [ln.shape for ln in m.links]
    assert sorted(os.listdir(tmp_path)) == [f"x{suffix}"]  # no temporary file left behind


@pytest.mark.parametrize(("name", "m"), CASES, ids=IDS)
def test_saved_yaml_reads_the_same_with_c_and_pure_loader(name: str, m: Mechanism, tmp_path: Path) -> None:
    from linkagekit.files import _Loader, _PyLoader

    text = save(m, tmp_path / "x.yaml").read_text(encoding="utf-8")
    pure = yaml.load(text, Loader=_PyLoader)  # noqa: S506 - a safe loader
    fast = yaml.load(text, Loader=_Loader)  # noqa: S506 - a safe loader
    assert pure == fast == m.to_dict()
    if yaml.__with_libyaml__:
        assert issubclass(_Loader, yaml.CSafeLoader)
    assert issubclass(_PyLoader, yaml.SafeLoader) and not issubclass(_PyLoader, yaml.CSafeLoader)


def test_yaml_is_readable() -> None:
    text = dumps(load("examples/slider_crank.yaml"))
    lines = text.splitlines()
    assert lines[:3] == [
        "format: linkagekit/1",
        "name: Slider-crank with mass properties",
        "units: {length: m, angle: deg}",
    ]
    assert "  A: [0.03, 0.04]" in lines
    assert "  ground: [O]" in lines
    assert "    lengths: {O-A: 0.05}" in lines
    assert "&" not in text and "*" not in text  # no anchors or aliases


@pytest.mark.parametrize("loader", ["_Loader", "_PyLoader"])
def test_loaders_use_yaml_12_booleans_and_numbers(loader: str) -> None:
    """YAML 1.2 core schema: only true/false are booleans, 1e-3 is a number (issue 9)."""
    import linkagekit.files as files

    cls = getattr(files, loader)
    d = yaml.load("on: yes\noff: true\nn: 1e-3\nf: 1.5e+3\ni: 7\nno: null\nt: False", Loader=cls)  # noqa: S506
    assert d == {"on": "yes", "off": True, "n": 0.001, "f": 1500.0, "i": 7, "no": None, "t": False}


def test_loader_importable_from_model_without_yaml_at_import() -> None:
    from linkagekit.files import _Loader
    from linkagekit.files import _Loader as files_loader

    assert _Loader is files_loader
    assert yaml.load("on: ground", Loader=_Loader) == {"on": "ground"}  # noqa: S506


def test_precision_survives_yaml_and_json(tmp_path: Path) -> None:
    d = fourbar_dict()
    d["joints"]["C"] = [0.1 + 0.2, 1 / 3]
    d["joints"]["P"] = [5.6182 + 1e-15, 3.4509e0 * (1 + 2**-52)]
    d["gravity"] = [1e-300, -9.81]
    m = Mechanism.from_dict(d)
    for suffix in (".yaml", ".json"):
        back = load(save(m, tmp_path / f"p{suffix}"))
        assert back.joints["C"] == complex(0.1 + 0.2, 1 / 3)
        assert back.joints["P"] == m.joints["P"]
        assert back == m


def test_description_and_forms_are_kept(tmp_path: Path) -> None:
    m = Mechanism.from_dict(fourbar_dict())
    back = load(save(m, tmp_path / "d.yaml"))
    assert back.description == fourbar_dict()["description"]
    d = back.to_dict()
    assert d["links"]["ground"] == {"joints": ["A", "B"]}  # written as a mapping: kept
    assert d["links"]["rocker"] == ["B", "D"]
    assert d["loads"] == [
        {"link": "coupler", "at": [3.1, 1.7], "force": [1.0, -2.0]},
        {"link": "rocker", "torque": -5.0},
        {"link": "rocker", "at": "D", "force": [0.0, 0.0], "torque": 0.5},
    ]
    assert d["drivers"][0]["angles"] == {"start": 0.0, "stop": 2 * np.pi, "step": np.pi / 180}
    assert "description" not in load("examples/seed000_fourbar.yaml").to_dict()


def test_slider_direction_written_as_given() -> None:
    m = Mechanism.from_dict(slider_dict())
    assert abs(m.sliders[0].direction - complex(0.6, 0.8)) < 1e-15
    assert m.to_dict()["sliders"][0]["direction"] == [3.0, 4.0]
    d = slider_dict()
    d["sliders"][0]["direction"] = [6.0, 8.0]
    assert Mechanism.from_dict(d) == m  # same unit direction: same mechanism
    assert Mechanism.from_dict(d).to_dict()["sliders"][0]["direction"] == [6.0, 8.0]


def test_save_refuses_an_unknown_suffix(tmp_path: Path) -> None:
    m = load("examples/seed000_fourbar.yaml")
    with pytest.raises(MechanismFileError, match=r"\.txt"):
        save(m, tmp_path / "x.txt")
    with pytest.raises(MechanismFileError, match="no suffix"):
        save(m, tmp_path / "x")
    assert list(tmp_path.iterdir()) == []


def test_save_replaces_atomically_and_keeps_permissions(tmp_path: Path) -> None:
    target = tmp_path / "m.yaml"
    target.write_text("old", encoding="utf-8")
    target.chmod(0o640)
    m = load("examples/jansen_leg.yaml")
    save(m, target)
    assert (target.stat().st_mode & 0o777) == 0o640
    assert load(target) == m
    assert sorted(os.listdir(tmp_path)) == ["m.yaml"]
    with pytest.raises(MechanismFileError, match="cannot write"):
        save(m, tmp_path / "no" / "such" / "dir.yaml")
    assert sorted(os.listdir(tmp_path)) == ["m.yaml"]


def test_load_messages() -> None:
    with pytest.raises(MechanismFileError, match="no such file"):
        load("examples/does-not-exist.yaml")
    with pytest.raises(MechanismFileError, match="is a directory"):
        load("examples")


def test_load_reports_yaml_and_json_syntax(tmp_path: Path) -> None:
    (tmp_path / "bad.yaml").write_text("joints: [A: 1\n", encoding="utf-8")
    with pytest.raises(MechanismFileError, match=r"bad\.yaml: YAML syntax error at line"):
        load(tmp_path / "bad.yaml")
    (tmp_path / "bad.json").write_text("{", encoding="utf-8")
    with pytest.raises(MechanismFileError, match=r"bad\.json: JSON syntax error at line 1"):
        load(tmp_path / "bad.json")
    (tmp_path / "evil.yaml").write_text("!!python/object/apply:os.system ['true']\n", encoding="utf-8")
    with pytest.raises(MechanismFileError):
        load(tmp_path / "evil.yaml")


# ---------------------------------------------------------------------- immutability, hashing
def test_immutable() -> None:
    m = load("examples/seed000_fourbar.yaml")
    with pytest.raises(TypeError):
        m.joints["A"] = 1  # type: ignore[index]
    with pytest.raises(TypeError):
        m.link("crank").shape["A"] = 0j  # type: ignore[index]
    with pytest.raises(TypeError):
        m.link("crank").lengths["A-C"] = 3.0  # type: ignore[index]
    with pytest.raises(dataclasses.FrozenInstanceError):
        m.name = "other"  # type: ignore[misc]
    with pytest.raises(dataclasses.FrozenInstanceError):
        m.link("crank").mass = 1.0  # type: ignore[misc]
    with pytest.raises(dataclasses.FrozenInstanceError):
        m.drivers[0].speed = 2.0  # type: ignore[misc]
    for attr in ("links", "drivers", "sliders", "loads", "joint_names"):
        assert isinstance(getattr(m, attr), tuple)
    assert all(isinstance(ln.joints, tuple) for ln in m.links)
    assert not hasattr(m, "plan")


def test_hash_and_equality() -> None:
    a = load("examples/seed000_fourbar.yaml")
    b = Mechanism.from_dict(a.to_dict(), source="elsewhere")
    assert a == b and hash(a) == hash(b)  # the source is not compared
    assert len({a, b, load("examples/jansen_leg.yaml")}) == 2
    d = a.to_dict()
    d["name"] = "other"
    assert Mechanism.from_dict(d) != a
    d = a.to_dict()
    d["links"]["crank"]["lengths"]["A-C"] = 2.0000001
    assert Mechanism.from_dict(d) != a
    d = a.to_dict()
    d["joints"] = dict(reversed(list(d["joints"].items())))
    assert Mechanism.from_dict(d) != a  # the joint order is the order of a pose array
    assert pickle.loads(pickle.dumps(a)) == a
    assert copy.deepcopy(a) == a


def test_frozen_map() -> None:
    m = FrozenMap({"A": 1.0, "B": 2.0})
    assert m == {"B": 2.0, "A": 1.0} and m == FrozenMap({"B": 2.0, "A": 1.0})
    assert hash(m) == hash(FrozenMap({"B": 2.0, "A": 1.0}))
    assert m != {"A": 1.0} and m != [("A", 1.0), ("B", 2.0)]
    assert list(m) == ["A", "B"] and len(m) == 2 and "A" in m and m.get("C") is None
    assert repr(m) == "FrozenMap({'A': 1.0, 'B': 2.0})"
    assert pickle.loads(pickle.dumps(m)) == m
    with pytest.raises(TypeError):
        del m["A"]  # type: ignore[attr-defined]


def test_unknown_link_name() -> None:
    m = load("examples/seed000_fourbar.yaml")
    with pytest.raises(UnknownNameError, match="no link named 'nope'") as info:
        m.link("nope")
    assert isinstance(info.value, KeyError) and isinstance(info.value, LinkageError)
    assert m.link("crank").name == "crank"


# ---------------------------------------------------------------------- dof and validation
@pytest.mark.parametrize("path", EXAMPLES, ids=[p.name for p in EXAMPLES])
def test_dof(path: Path) -> None:
    m = load(path)
    assert m.dof == (2 if path.name in ("fivebar_two_drivers.yaml", "excavator_boom.yaml") else 1)
    assert m.dof == len(m.drivers)
    # every example gives exact lengths, but the triad: its dimensions are its pose's (docs/commands.md)
    assert m.has_given_lengths or path.name == "triad_six_modes.yaml"


def test_drivers_must_match_dof() -> None:
    d = load("examples/seed000_fourbar.yaml").to_dict()
    d["drivers"].append({"link": "rocker", "pivot": "B", "toward": "D"})
    msg = (
        "here: drivers: 2 driver(s) given, but the mechanism has 1 degree(s) of freedom "
        "(Gruebler: 3*(4-1) - 2*(4 pins + 0 sliders) = 1)"
    )
    with pytest.raises(MechanismFileError) as info:
        Mechanism.from_dict(d, source="here")
    assert str(info.value) == msg


def test_slider_dof() -> None:
    m = Mechanism.from_dict(slider_dict())
    assert m.dof == 1 and m.drivers[0].kind == "slider"
    assert not m.has_given_lengths


# ---------------------------------------------------------------------- with_pose
def assert_same_dimensions(a: Mechanism, b: Mechanism, factor: float = 1.0) -> None:
    for la, lb in zip(a.links, b.links, strict=True):
        assert la.joints == lb.joints and la.mass == lb.mass and la.inertia == lb.inertia
        for j in la.joints:
            assert abs(lb.shape[j] - factor * la.shape[j]) <= 1e-12 * max(1.0, abs(factor * la.shape[j]))
        for i, p in enumerate(la.joints):
            for q in la.joints[i + 1 :]:
                assert lb.length(p, q) == pytest.approx(factor * la.length(p, q), rel=1e-12, abs=1e-12)
        if la.cg_pose is not None:
            assert lb.cg_pose is not None
            expect = scaled_point(la, la.cg_pose, factor)
            assert abs(lb.cg_pose - expect) <= 1e-12 * max(1.0, abs(expect))


def scaled_point(link: Link, p: complex, factor: float) -> complex:
    """Where a point of ``link`` goes when the pose is scaled by ``factor`` about the origin."""
    if len(link.joints) == 1:  # translated with its one joint (its shape is the pose)
        return p + (factor - 1) * link.shape[link.joints[0]]
    return factor * p  # similar triangles


@pytest.mark.parametrize(("name", "m"), CASES, ids=IDS)
def test_with_pose_of_its_own_pose(name: str, m: Mechanism) -> None:
    free = m.with_pose(pose_of(m))  # lengths dropped: everything read off the pose
    assert not free.has_given_lengths
    assert free.joints == m.joints and free.joint_names == m.joint_names
    assert free.drivers == m.drivers and free.sliders == m.sliders and free.gravity == m.gravity
    assert free.name == m.name and free.length_unit == m.length_unit and free.angle_unit == m.angle_unit
    again = free.with_pose(pose_of(free))
    assert_same_dimensions(free, again)
    if not m.has_given_lengths:
        assert_same_dimensions(m, free)
    # a mapping works as well as an array
    by_name = free.with_pose({n: (z.real, z.imag) for n, z in free.joints.items()})
    assert_same_dimensions(free, by_name)


@pytest.mark.parametrize(("name", "m"), CASES, ids=IDS)
def test_with_pose_scaled(name: str, m: Mechanism) -> None:
    if any(d.stroke for d in m.drivers):  # a stroke is a length: twice the size is outside it (test_cylinders.py)
        d = m.to_dict()
        for drv in d["drivers"]:
            drv.pop("stroke", None)
        m = Mechanism.from_dict(d)
    free = m.with_pose(pose_of(m))
    double = free.with_pose(2 * pose_of(m))
    assert_same_dimensions(free, double, factor=2.0)
    for la, lb in zip(free.loads, double.loads, strict=True):
        assert la.at_joint == lb.at_joint and la.force == lb.force and la.torque == lb.torque
        if la.at_pose is not None:
            assert lb.at_pose is not None
            assert abs(lb.at_pose - scaled_point(free.link(la.link), la.at_pose, 2.0)) < 1e-12


def test_with_pose_moves_cg_by_hand() -> None:
    # seed 001: link3's cg is Q + 0.45 (X - Q) + 0.1 i (X - Q), i.e. rho = 0.45 + 0.1i to (Q, X)
    m = load("examples/seed001_stephenson.yaml")
    assert m.link("link3").joints[:2] == ("Q", "X")
    pose = {n: (z.real, z.imag) for n, z in m.joints.items()}
    pose["Q"], pose["X"] = (1.0, 2.0), (1.0, 6.0)  # not similar to the old pose: a hand case
    new = m.with_pose(pose)
    q, x = 1 + 2j, 1 + 6j
    expect = q + (0.45 + 0.1j) * (x - q)  # = (0.6, 3.8)
    assert abs(new.link("link3").cg_pose - expect) < 1e-11  # the file's cg is rounded to 1e-12
    assert abs(expect - (0.6 + 3.8j)) < 1e-15
    assert new.link("link3").length("Q", "X") == 4.0
    assert new.link("link3").mass == 1.0 and new.link("link3").inertia == 0.02

    # slider-crank: the crank's cg is the middle of O-A; the block's cg is translated with B
    sc = load("examples/slider_crank.yaml")
    pose = {"O": (0.0, 0.0), "A": (0.0, 0.06), "B": (0.2, 0.0)}
    new = sc.with_pose(pose)
    assert new.link("crank").cg_pose == pytest.approx(0.03j, abs=1e-15)
    assert new.link("block").cg_pose == pytest.approx(0.2 + 0j, abs=1e-15)
    assert new.link("rod").length("A", "B") == pytest.approx(np.hypot(0.2, 0.06), rel=1e-15)
    assert new.sliders[0].direction == sc.sliders[0].direction
    assert new.loads == tuple(dataclasses.replace(ld, at=new.link("block").shape["B"]) for ld in sc.loads)


def test_with_pose_moves_a_load_point() -> None:
    m = Mechanism.from_dict(fourbar_dict())
    c, d = m.joints["C"], m.joints["D"]
    rho = (3.1 + 1.7j - c) / (d - c)
    new_c, new_d = 2.5 + 0.5j, 1.0 + 5.0j
    pose = pose_of(m)
    pose[m.joint_names.index("C")] = [new_c.real, new_c.imag]
    pose[m.joint_names.index("D")] = [new_d.real, new_d.imag]
    new = m.with_pose(pose)
    assert abs(new.loads[0].at_pose - (new_c + rho * (new_d - new_c))) < 1e-13
    for a, b in zip(new.loads, m.loads, strict=True):
        assert (a.link, a.at_joint, a.force, a.torque) == (b.link, b.at_joint, b.force, b.torque)
    assert new.loads[1] == m.loads[1]  # a torque only: nothing to move
    assert new.loads[2].at == new.link("rocker").shape["D"]
    assert new.description == m.description


def test_with_pose_validates() -> None:
    m = load("examples/seed000_fourbar.yaml")
    pose = pose_of(m)
    pose[m.joint_names.index("C")] = pose[m.joint_names.index("A")]  # two joints of the crank at one spot
    with pytest.raises(
        MechanismFileError, match=r"at one spot on one link \(closer than 1e-09 of the mechanism's size"
    ):
        m.with_pose(pose)
    with pytest.raises(MechanismFileError, match="shape"):
        m.with_pose(pose[:-1])
    with pytest.raises(MechanismFileError, match="finite"):
        m.with_pose(np.full_like(pose, np.nan))
    with pytest.raises(MechanismFileError, match="no position for joint"):
        m.with_pose({"A": (0, 0)})
    with pytest.raises(UnknownNameError, match="'Z'"):
        m.with_pose({**{n: (z.real, z.imag) for n, z in m.joints.items()}, "Z": (0, 0)})


# ---------------------------------------------------------------------- light imports
def test_model_import_is_light() -> None:
    code = "import linkagekit.model, sys; print('pydantic' in sys.modules, 'yaml' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["False", "False"], out.stdout + out.stderr


def test_a_file_without_a_name_is_saved_without_one(tmp_path):
    """Saving (lk.save, the editor) adds no ``name: ''`` to a file that had no name; one with a name keeps it."""
    text = Path("examples/seed000_fourbar.yaml").read_text(encoding="utf-8")
    lines = [ln for ln in text.splitlines() if not ln.startswith("name:")]
    src = tmp_path / "anon.yaml"
    src.write_text("\n".join(lines) + "\n", encoding="utf-8")
    mech = load(src)
    assert mech.name == "" and "name" not in mech.to_dict()
    out = tmp_path / "saved.yaml"
    save(mech, out)
    assert "name:" not in out.read_text(encoding="utf-8") and load(out).name == ""
    named = load("examples/seed000_fourbar.yaml")
    assert named.to_dict()["name"] == named.name != ""


@pytest.mark.parametrize(
    ("start", "stop", "step", "last"),
    [(0, 0.3, 0.1, 0.3), (0, -0.3, -0.1, -0.3), (0.1, 0.7, 0.2, 0.7), (0, 0.35, 0.1, 0.1 * 3)],
)
def test_a_sweep_that_lands_on_stop_ends_exactly_at_stop(start, stop, step, last):
    """``{start: 0, stop: 0.3, step: 0.1}`` ended at 0.30000000000000004 (0 + 3 * 0.1), in the file's sweep and in
    ``--angles``/``--time``; the last value is ``stop`` itself when the steps land on it within rounding, and a sweep
    whose steps do not reach ``stop`` (0.35) keeps its last step's value."""
    import linkagekit as lk
    from linkagekit.cli import _range

    d = fourbar_dict()
    d["drivers"][0]["angles"] = {"start": start, "stop": stop, "step": step}
    values = Mechanism.from_dict(d).drivers[0].sweep.values()
    assert len(values) == 4 and values[-1] == last  # exactly
    assert np.allclose(values, start + step * np.arange(4), rtol=0, atol=1e-15)
    assert _range(f"{start}:{stop}:{step}", "--angles").tolist() == values.tolist()
    res = lk.analyze(Mechanism.from_dict(d), rates=False)
    assert res.inputs["crank"][-1] == last


@pytest.mark.parametrize(("start", "stop", "step", "n"), [(10000.7, 10000.8, 0.001, 101), (-1e6, -1e6 + 0.3, 0.1, 4)])
def test_a_sweep_far_from_zero_keeps_its_stop(start, stop, step, n):
    """``Sweep(10000.7, 10000.8, 0.001)`` gave 100 values ending at 10000.799 (a review): the difference of the two
    ends is 0.1 only to 1.5e-12 at that size, 99.999999998 steps, and 1e-9 of a step did not cover it."""
    from linkagekit.cli import _range
    from linkagekit.model import Sweep

    values = Sweep(start, stop, step).values()
    assert len(values) == n and values[-1] == stop
    assert _range(f"{start!r}:{stop!r}:{step!r}", "--angles").tolist() == values.tolist()


@pytest.mark.parametrize(
    "value",
    [[np.int64(4), 1], np.array([4, 1]), np.array([4, 1], dtype=np.int8), [np.float32(4), np.uint16(1)], [4.0, 1.0]],
    ids=["int64", "int array", "int8 array", "float32 and uint16", "float"],
)
def test_from_dict_takes_numpy_numbers_of_any_width(value) -> None:
    # a review: "joints.B[0]: expected a number, got np.int64(4)" (np.array([4, 1]) refused, [4., 1.] taken)
    d = fourbar_dict()
    d["joints"]["B"] = value
    m = Mechanism.from_dict(d)
    assert m.to_dict()["joints"]["B"] == [4.0, 1.0] and type(m.to_dict()["joints"]["B"][0]) is float
    json.dumps(m.to_dict())
    d["joints"]["B"] = [np.bool_(True), 1]  # a truth value is still not a number
    with pytest.raises(MechanismFileError, match=r"joints.B\[0\]: expected a number, got np.True_"):
        Mechanism.from_dict(d)


def test_a_link_whose_given_lengths_are_flat_to_rounding_is_flat() -> None:
    """Whitworth's lever (O4-B 0.15, O4-L 0.32, B-L 0.47 m: flat) put L 2e-8 rad off the line B-O4: the law of
    cosines' height was the square root of a rounding error (in mm, 150 + 320 = 470 exactly, it was flat). Lengths
    whose two shorter add up to the longest within 4 units of rounding are flat; a triangle 1e-6 of its size high is
    kept as given."""
    import linkagekit as lk

    root = Path(__file__).resolve().parents[1]
    res = lk.analyze(lk.load(root / "examples" / "whitworth_quick_return.yaml"), rates=False, dynamics=False)
    O4, B, L = (res.point(j) for j in ("O4", "B", "L"))
    assert np.max(np.abs((np.conj(B - O4) * (L - O4)).imag) / np.abs(B - O4) / np.abs(L - O4)) < 1e-15

    def height(pq: float, pr: float, qr: float) -> float:
        """R's distance from the line P-Q of a crank P-Q-R given by its three lengths (R posed off the line)."""
        doc = {
            "format": "linkagekit/1",
            "name": "bar",
            "units": {"length": "mm", "angle": "deg"},
            "joints": {"P": [0, 0], "Q": [pq, 0], "R": [0.5 * pr, 0.3 * pr], "S": [-pq, 0]},
            "links": {
                "ground": ["P", "S"],
                "bar": {"joints": ["P", "Q", "R"], "lengths": {"P-Q": pq, "P-R": pr, "Q-R": qr}},
            },
            "drivers": [{"link": "bar", "pivot": "P", "toward": "Q"}],
        }
        r = lk.analyze(lk.Mechanism.from_dict(doc), [0.0], rates=False, dynamics=False)
        return float(np.abs((np.conj(r.point("Q") - r.point("P")) * (r.point("R") - r.point("P"))).imag[0]) / pq)

    rng = np.random.default_rng(5)
    for _ in range(100):  # flat decimal triangles at every scale, R between P and Q or beyond Q
        a, b = (int(x) for x in rng.integers(1, 999, 2))
        scale = 10.0 ** int(rng.integers(-6, 6))
        x, y, z = (float(f"{v * scale:.12g}") for v in (a, b, a + b))
        for pq, pr, qr in ((z, x, y), (x, z, y)):
            assert height(pq, pr, qr) <= 1e-15 * z, (pq, pr, qr)
    side = float(np.hypot(0.5, 1e-6))
    assert height(1.0, side, side) == pytest.approx(1e-6, rel=1e-4)  # thin, not flat (the square root: 1e-4)


def test_a_pivot_left_out_of_the_ground_is_named() -> None:
    """A crank-rocker whose ground lists O2 alone (review 19c) was refused with its Gruebler count only: the rocker
    hangs from B, swinging about it, and O4 is a tracer point. The message names them; a coupler point (on one link,
    which is held at two joints) is not taken for it."""
    doc = {
        "format": "linkagekit/1",
        "name": "crank-rocker",
        "units": {"length": "mm", "angle": "deg"},
        "joints": {"O2": [0, 0], "O4": [100, 0], "A": [15, 26], "B": [80, 70], "P": [40, 90]},
        "links": {"ground": ["O2"], "crank": ["O2", "A"], "coupler": ["A", "B", "P"], "rocker": ["O4", "B"]},
        "drivers": [{"link": "crank", "pivot": "O2", "toward": "A"}],
    }
    with pytest.raises(MechanismFileError) as e:
        Mechanism.from_dict(doc)
    assert str(e.value).endswith(
        "3 degree(s) of freedom (Gruebler: 3*(4-1) - 2*(3 pins + 0 sliders) = 3); link 'rocker' swings about B alone "
        "(O4 on no other link: add it to ground?)"
    )
    # a cylinder's end holds its joint (review 19e: the boom's stick was said to hang when its driver was left out)
    boom = yaml.safe_load((Path(__file__).resolve().parents[1] / "examples" / "excavator_boom.yaml").read_text())
    boom["drivers"] = boom["drivers"][1:]
    with pytest.raises(MechanismFileError) as e:
        Mechanism.from_dict(boom)
    assert "swings about" not in str(e.value) and "degree(s) of freedom" in str(e.value)
    doc["links"]["ground"] = ["O2", "O4"]
    assert Mechanism.from_dict(doc).dof == 1
