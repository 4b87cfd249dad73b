"""Driver types: each kind of driver declares its unit, conversion, effort and file entry once.

``Driver.type`` is a :class:`~linkagekit.model.CrankType`, :class:`~linkagekit.model.SliderType`
or :class:`~linkagekit.model.CylinderType`; ``Driver.kind`` is kept as a read-only tag.  The
last tests read the source with :mod:`ast`: no module decides on a driver's kind string, and
the model and planner keep short functions.
"""

import ast
import math
import pickle
import typing
from pathlib import Path

import pytest

import linkagekit as lk
from linkagekit.model import CrankType, CylinderType, Driver, DriverType, Mechanism, SliderType, Sweep
from linkagekit.units import UnitKind

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src" / "linkagekit"


def slider_mech(length: str = "mm") -> Mechanism:
    return Mechanism.from_dict(
        {
            "units": {"length": length, "angle": "rad"},
            "joints": {"O": [0, 0], "A": [30, 40], "B": [115, 0]},
            "links": {"ground": ["O"], "crank": ["O", "A"], "rod": ["A", "B"], "block": ["B"]},
            "drivers": [{"slider": 0, "displacements": {"start": -10, "stop": 10, "step": 1}, "speed": 2.0}],
            "sliders": [{"link": "block", "on": "ground", "through": "B", "direction": [1.0, 0.0]}],
        }
    )


@pytest.fixture(scope="module")
def mechs() -> dict[str, Mechanism]:
    return {
        "angle": lk.load(ROOT / "examples" / "seed000_fourbar.yaml"),
        "slider": slider_mech(),
        "cylinder": lk.load(ROOT / "examples" / "excavator_boom.yaml"),
    }


def test_each_type_declares_its_tag_unit_and_effort(mechs):
    expected = {  # tag: (type, sweep key, cyclic, effort, effort unit, input unit)
        "angle": (CrankType, "angles", True, UnitKind.TORQUE, "N·m", "deg"),
        "slider": (SliderType, "displacements", False, UnitKind.FORCE, "N", "mm"),
        "cylinder": (CylinderType, "lengths", False, UnitKind.FORCE, "N", "m"),
    }
    for tag, (cls, key, cyclic, symbol, unit, input_unit) in expected.items():
        mech = mechs[tag]
        d = mech.drivers[0]
        assert isinstance(d.type, cls) and d.kind == tag == cls.tag
        assert (d.type.sweep_key, d.type.cyclic, d.type.effort, d.type.effort.symbol("mm", "deg")) == (
            key,
            cyclic,
            symbol,
            unit,
        )
        assert d.input_unit(mech) == d.type.input_unit(mech) == input_unit


def test_every_type_of_the_union_is_complete():
    members = typing.get_args(DriverType)
    assert set(members) == {CrankType, SliderType, CylinderType}
    assert len({m.tag for m in members}) == len(members)
    for m in members:
        for attr in ("tag", "sweep_key", "cyclic", "input_kind", "effort"):
            assert attr in dir(m), (m, attr)


def test_input_scale_and_rate_conversion(mechs):
    crank, slider, cyl = (mechs[k].drivers[0] for k in ("angle", "slider", "cylinder"))
    assert crank.input_scale(mechs["angle"]) == pytest.approx(math.pi / 180, rel=1e-15)
    assert slider.input_scale(mechs["slider"]) == 1.0 and cyl.input_scale(mechs["cylinder"]) == 1.0
    # a crank's speed is rad/s whatever the angle unit; a length's speed goes to m/s
    assert crank.type.rate_to_si(1e-3) == 1.0
    assert slider.type.rate_to_si(mechs["slider"].length_to_si) == pytest.approx(1e-3, rel=1e-15)
    assert cyl.type.rate_to_si(mechs["cylinder"].length_to_si) == 1.0


def test_search_spans():
    assert CrankType("A", "B").search_span(7.0) == (0.0, 2 * math.pi)
    assert SliderType(0).search_span(7.0) == (-7.0, 7.0)
    assert CylinderType(("A", "B")).search_span(7.0) == (0.0, 7.0)
    lo, hi = CylinderType(("A", "B"), (1.0, 3.0)).search_span(7.0)
    assert (lo, hi) == pytest.approx((0.98, 3.02), abs=1e-15)


def test_the_input_power_reads_the_rate_conversion():
    """A slider in mm pushed at 2 mm/s: power = F * 2e-3 m/s (to 1e-12 relative)."""
    m = Mechanism.from_dict(
        {
            **{k: v for k, v in slider_mech().to_dict().items() if k != "drivers"},
            "drivers": [{"slider": 0, "displacements": {"start": -10, "stop": 10, "step": 5}, "speed": 2.0}],
            "loads": [{"link": "block", "at": "B", "force": [-50, 0]}],
        }
    )
    res = lk.analyze(m)
    f = res.forces.driver_force["block"]
    assert res.forces.input_power == pytest.approx(f * 2e-3, rel=1e-12)
    assert f == pytest.approx(50.0, rel=1e-9)  # the push holds the load, frictionless


def test_file_entries_round_trip(mechs):
    entries = {
        "angle": {"link", "pivot", "toward", "angles"},
        "slider": {"slider", "displacements", "speed"},
        "cylinder": {"cylinder", "name", "lengths", "stroke", "speed"},
    }
    for tag, mech in mechs.items():
        d = mech.drivers[0]
        assert set(d.to_dict()) == entries[tag]
        again = Mechanism.from_dict(mech.to_dict())
        assert again == mech and again.drivers[0] == d and again.drivers[0].type == d.type


def test_drivers_are_immutable_hashable_and_picklable(mechs):
    for mech in mechs.values():
        d = mech.drivers[0]
        assert pickle.loads(pickle.dumps(d)) == d and hash(pickle.loads(pickle.dumps(d))) == hash(d)
        with pytest.raises(AttributeError):
            d.type = CrankType("A", "B")  # type: ignore[misc]
        with pytest.raises(AttributeError):
            d.kind = "slider"  # type: ignore[misc]
    sw = Sweep(0.0, 1.0, 0.5)
    assert Driver("a", "a", sw, CrankType("A", "B")) != Driver("a", "a", sw, CylinderType(("A", "B")))


def test_compatibility_views(mechs):
    crank, slider, cyl = (mechs[k].drivers[0] for k in ("angle", "slider", "cylinder"))
    assert (crank.pivot, crank.toward, crank.slider, crank.ends, crank.stroke) == ("A", "C", None, None, None)
    assert (slider.pivot, slider.slider, slider.ends, slider.stroke) == (None, 0, None, None)
    assert (cyl.pivot, cyl.slider, cyl.ends, cyl.stroke) == (None, None, ("C1", "B1"), (1.8, 2.9))


# ------------------------------------------------------------------ the source


def _is_dtype(node: ast.expr) -> bool:
    """``dtype`` or ``x.dtype``: a NumPy dtype's one-letter ``kind``, not a driver's."""
    return (isinstance(node, ast.Name) and node.id == "dtype") or (
        isinstance(node, ast.Attribute) and node.attr == "dtype"
    )


def kind_compares(path: Path) -> int:
    """Comparisons of some ``X.kind`` with a string literal (``ln.kind``, a scene link's drawing kind, aside)."""
    n = 0
    for node in ast.walk(ast.parse(path.read_text())):
        if not isinstance(node, ast.Compare):
            continue
        operands = [node.left, *node.comparators]
        kinds = [
            o
            for o in operands
            if isinstance(o, ast.Attribute)
            and o.attr == "kind"
            and not (isinstance(o.value, ast.Name) and o.value.id == "ln")
            and not _is_dtype(o.value)
        ]
        if kinds and any(isinstance(o, ast.Constant) and isinstance(o.value, str) for o in operands):
            n += 1
    return n


def test_no_module_decides_on_the_kind_string():
    found = {str(p.relative_to(SRC)): kind_compares(p) for p in sorted(SRC.rglob("*.py"))}
    found = {k: v for k, v in found.items() if v}
    assert found == {}, "decide on the driver's type (match d.type / its attributes), not on d.kind"


def test_kind_compares_finds_them(tmp_path):
    path = tmp_path / "probe.py"
    path.write_text(
        "d.kind == 'angle'\nx = mech.drivers[0].kind != 'slider'\nln.kind == 'plate'\n"
        "a.dtype.kind == 'c'\ndtype.kind != 'U'\n"
    )
    assert kind_compares(path) == 2


@pytest.mark.parametrize("module", ["model.py", "plan.py"])
def test_short_functions(module):
    """No function of the model or the planner is over 60 lines."""
    long = [
        (node.name, node.end_lineno - node.lineno + 1)
        for node in ast.walk(ast.parse((SRC / module).read_text()))
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef) and node.end_lineno - node.lineno + 1 > 60
    ]
    assert long == []
