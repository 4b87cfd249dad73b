"""Every public function answers bad input with the LinkageError family (issue 9).

Each call below passes a wrong type, shape or value; each must raise a LinkageError (an
InputError is also a ValueError, an UnknownNameError also a KeyError/LookupError), never a
bare TypeError/ValueError/KeyError from inside, and never return numbers that break the
mechanism's own constraints.
"""

from pathlib import Path

import numpy as np
import pytest

import linkagekit as lk

MECH = lk.load("examples/seed000_fourbar.yaml")
RES = lk.analyze(lk.load("examples/slider_crank.yaml"), [0.0, 30.0])
BATCH = lk.analyze(MECH, [0.0], poses=MECH.pose_array()[None])

CALLS = {
    "load None": lambda: lk.load(None),
    "load number": lambda: lk.load(3),
    "load missing": lambda: lk.load("/nonexistent/x.yaml"),
    "save None": lambda: lk.save(None, "/tmp/x.yaml"),
    "save bad suffix": lambda: lk.save(MECH, "/tmp/x.txt"),
    "from_dict list": lambda: lk.Mechanism.from_dict([1, 2]),
    "from_dict None": lambda: lk.Mechanism.from_dict(None),
    "from_dict empty ground": lambda: lk.Mechanism.from_dict({**MECH.to_dict(), "links": {"ground": []}}),
    "from_dict huge int": lambda: lk.Mechanism.from_dict({**MECH.to_dict(), "joints": {"A": [10**400, 0]}}),
    "from_dict bool index": lambda: lk.Mechanism.from_dict({**MECH.to_dict(), "drivers": [{"slider": True}]}),
    "with_pose wrong shape": lambda: MECH.with_pose(np.zeros((2, 2))),
    "analyze not a mechanism": lambda: lk.analyze({"joints": {}}, [0.0]),
    "analyze empty inputs": lambda: lk.analyze(MECH, []),
    "analyze 2-D inputs": lambda: lk.analyze(MECH, [[0.0, 1.0]]),
    "analyze text inputs": lambda: lk.analyze(MECH, ["a"]),
    "analyze nan input": lambda: lk.analyze(MECH, [np.nan]),
    "analyze huge input": lambda: lk.analyze(MECH, [1e300]),
    "analyze unknown driver": lambda: lk.analyze(MECH, {"rocker": [0.0]}),
    "analyze speed shape": lambda: lk.analyze(MECH, [0.0, 1.0], speed=[1.0, 2.0, 3.0]),
    "analyze speed text": lambda: lk.analyze(MECH, [0.0], speed="fast"),
    "analyze method": lambda: lk.analyze(MECH, [0.0], method="magic"),
    "analyze poses shape": lambda: lk.analyze(MECH, [0.0], poses=np.zeros((1, 3, 2))),
    "analyze poses text": lambda: lk.analyze(MECH, [0.0], poses="x"),
    "analyze static and speed": lambda: lk.analyze(MECH, [0.0], static=True, speed=1.0),
    "analyze too large": lambda: lk.analyze(
        MECH, np.zeros(10), poses=np.broadcast_to(MECH.pose_array(), (10**8, 5, 2))
    ),
    "analyze_chunks designs": lambda: list(lk.analyze_chunks(MECH, [0.0], poses=MECH.pose_array()[None], designs=0)),
    "check not a mechanism": lambda: lk.check("seed000"),
    "modes not a mechanism": lambda: lk.modes(None, 0.0),
    "modes unknown driver": lambda: lk.modes(MECH, {"rocker": 1.0}),
    "modes text": lambda: lk.modes(MECH, "x"),
    "reference_signs not a mechanism": lambda: lk.reference_signs(3),
    "result unknown joint": lambda: RES.xy("Z"),
    "result unknown link": lambda: RES.omega("Z"),
    "result design of one": lambda: RES.design(0),
    "result design out of range": lambda: BATCH.design(3),
    "result design text": lambda: BATCH.design("0"),
    "reaction unknown": lambda: RES.forces.reaction("Z", "rod"),
    "mechanism unknown link": lambda: MECH.link("nope"),
    # review 16a: ZeroDivisionError, IndexError, TypeError, and a table of 10^9 rows tried
    **{f"reduced points {p!r}": (lambda p=p: lk.reduced(MECH, points=p)) for p in (0, -1, None, 10**9)},
    "synthesize workers text": lambda: lk.synthesize(np.array([[0, 0], [1, 0.2], [2, 0.1]]), workers="x"),  # TypeError
}

BAD_SIGNS = [[0], [0.5], [7], [np.nan], [1, 1], "x", {"Q": 1}, {"D": 0}]


@pytest.mark.parametrize("name", sorted(CALLS))
def test_bad_input_raises_a_linkage_error(name):
    with pytest.raises(lk.LinkageError):
        CALLS[name]()


@pytest.mark.parametrize("signs", BAD_SIGNS, ids=[repr(s) for s in BAD_SIGNS])
def test_bad_signs_never_give_positions(signs):
    """signs=[0], [0.5], [7] or [nan] once returned positions breaking |CD| = 5, marked assembled."""
    with pytest.raises(lk.InputError):
        lk.analyze(MECH, [30.0], signs=signs)


@pytest.mark.parametrize("mirrors", [[2], [0.5], "x", {"coupler": "yes"}, {"nope": True}])
def test_bad_mirrors_are_refused(mirrors):
    with pytest.raises(lk.InputError):
        lk.analyze(MECH, [30.0], mirrors=mirrors)


def test_error_types_are_also_the_builtin_ones():
    with pytest.raises(ValueError):
        lk.analyze(MECH, [])
    with pytest.raises(LookupError):
        RES.xy("Z")


BASE = MECH.to_dict()
FILE_MESSAGES = {
    "units as a list": ({**BASE, "units": [1]}, "units: expected a mapping of keys"),
    "point of one number": ({**BASE, "joints": {**BASE["joints"], "B": [1]}}, "joints.B[1]: expected a point [x, y]"),
    "point of three numbers": ({**BASE, "joints": {**BASE["joints"], "B": [1, 2, 3]}}, "joints.B: expected a point"),
    "point as text": ({**BASE, "joints": {**BASE["joints"], "B": "here"}}, "joints.B: expected a point [x, y]"),
    "links as a list": ({**BASE, "links": ["ground"]}, "links: expected a mapping of keys"),
    "drivers as a mapping": ({**BASE, "drivers": {"link": "crank"}}, "drivers: expected a list"),
    "name as a number": ({**BASE, "name": 5}, "name: expected text"),
    "unknown unit": ({**BASE, "units": {"length": "furlong"}}, "units.length: expected 'mm', 'cm', 'm' or 'in'"),
    "empty link": ({**BASE, "links": {**BASE["links"], "ground": []}}, "links.ground: must not be empty"),
    "201 joints": ({**BASE, "joints": {f"J{i}": [i, 0] for i in range(201)}}, "joints: too many entries (at most 200)"),
}


@pytest.mark.parametrize("case", sorted(FILE_MESSAGES))
def test_file_errors_speak_the_file_format(case):
    """Located messages in the file format's words, not the validation library's."""
    data, expected = FILE_MESSAGES[case]
    with pytest.raises(lk.MechanismFileError) as info:
        lk.Mechanism.from_dict(data)
    assert expected in str(info.value) and "Input should" not in str(info.value)


def test_a_numpy_whole_number_of_table_points_is_taken():
    """The check added for ``points=0`` refused ``np.int64(2000)``, which worked before (review 16e)."""
    assert lk.reduced(lk.load("examples/motor_fourbar.yaml"), points=np.int64(2000)).period is not None


@pytest.mark.parametrize("call", ["analyze", "simulate", "size_flywheel"])
def test_an_array_quoted_in_an_api_message_stays_on_one_line(call: str) -> None:
    """Review 18b: ``analyze(branch=array)``, ``simulate(torque=array)`` and ``size_flywheel(cs=array)`` quoted the
    array's repr over several lines; the value is quoted on one line, shortened, as elsewhere."""
    examples = Path(__file__).resolve().parents[1] / "examples"
    bad = np.zeros((3, 2))
    with pytest.raises(lk.LinkageError) as info:
        if call == "analyze":
            lk.analyze(lk.load(examples / "seed000_fourbar.yaml"), {"crank": [0.0]}, branch=bad)
        elif call == "simulate":
            lk.simulate(lk.load(examples / "iftomm_a01_pendulum.yaml"), [0, 0.01], torque=bad)
        else:
            lk.size_flywheel(lk.load(examples / "motor_fourbar.yaml"), bad, torque=1.0)
    assert "\n" not in str(info.value) and "got array(" in str(info.value)
