"""Forward dynamics (spec section 7): every number against an independent computation.

* energy: kinetic + potential (gravity, springs) from the Result's own velocities and
  positions, conserved to 1e-8 of the energy exchanged, without dampers or motors;
* kinetostatics: the driver torque ``lk.analyze`` needs for the simulated q, q', q'' is the
  applied law, to 1e-8 (one driver and two);
* a crank with a spring, a damper and a flywheel: the one-coordinate equation written here
  by hand, integrated by SciPy, gives the same motion;
* a motor-driven four-bar from rest settles into a periodic motion;
* a parallelogram stays a parallelogram through its flat positions;
* a toggle stops the motion with one line (exit 1 after the output); bad input exit 2;
* several drivers: a cylinder's stroke end stops the motion where the motion (its stroke
  widened) reaches it, whatever the output step.
"""

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest
import yaml
from scipy.integrate import solve_ivp
from scipy.interpolate import CubicHermiteSpline

import linkagekit as lk
from linkagekit.cli import main
from linkagekit.dynamics import reduced

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def _example(name, **extra):
    doc = yaml.safe_load((EXAMPLES / name).read_text())
    doc.update(extra)
    return doc


def _bar(doc, link, mass, a, b):
    """A uniform bar from joint a to joint b: mass, cg at the middle, m l^2 / 12."""
    za, zb = (np.array(doc["joints"][j], float) for j in (a, b))
    si = {"mm": 1e-3, "cm": 1e-2, "m": 1.0}[doc["units"]["length"]]
    entry = doc["links"][link]
    entry.update(mass=mass, cg=((za + zb) / 2).tolist(), inertia=float(mass * (np.linalg.norm(zb - za) * si) ** 2 / 12))


def _fourbar(spring=True):
    """Seed 000's four-bar (cm), uniform bars, gravity, and a spring from the frame to the coupler."""
    doc = _example("seed000_fourbar.yaml", gravity=[0, -9.81])
    for link, a, b, m in (("crank", "A", "C", 0.3), ("coupler", "C", "D", 1.0), ("rocker", "B", "D", 0.8)):
        _bar(doc, link, m, a, b)
    if spring:
        doc["springs"] = [{"between": ["A", "D"], "stiffness": 60.0, "free_length": 4.0}]
    return lk.Mechanism.from_dict(doc)


def _energy(mech, res):
    """Kinetic + potential energy (J) along a Result, from its joint positions and velocities only."""
    si, g = mech.length_to_si, mech.gravity
    E = np.zeros(res.n)
    for ln in mech.links:
        if ln.name == "ground" or ln.mass == 0 and ln.inertia == 0:
            continue
        a, b = ln.joints[:2]
        rho = (ln.cg - ln.shape[a]) / (ln.shape[b] - ln.shape[a])
        zg = (res.point(a) + rho * (res.point(b) - res.point(a))) * si
        vg = (res.velocity(a) + rho * (res.velocity(b) - res.velocity(a))) * si
        E += 0.5 * ln.mass * np.abs(vg) ** 2 + 0.5 * ln.inertia * res.omega(ln.name) ** 2
        E -= ln.mass * np.real(np.conj(g) * zg)
    for s in mech.springs:
        L = np.abs(res.point(s.between[1]) - res.point(s.between[0])) * si
        E += 0.5 * s.stiffness * (L - s.free_length * si) ** 2
    return E


def test_energy_is_conserved_without_dampers_or_motors():
    mech = _fourbar()
    res = lk.simulate(mech, np.linspace(0.0, 2.0, 401), speed=3.0)
    assert res.stopped is None and np.all(res.assembled)
    E = _energy(mech, res)
    w = res.speeds["crank"]
    assert np.ptp(w) > 100.0  # the energy goes back and forth between kinetic and potential
    assert np.max(np.abs(E - E[0])) <= 1e-8 * abs(E[0])


#: review 17c's four-bar (m): a crank-rocker with masses and inertias on every link, under gravity
FAST_FOURBAR = """
units: {length: m, angle: deg}
joints: {A: [0, 0], B: [0.4, 0.1], C: [0.0866025, 0.05], D: [0.2497378, 0.3596561]}
links:
  ground: [A, B]
  crank: {joints: [A, C], lengths: {A-C: 0.1}, mass: 1.0, cg: [0.0433013, 0.025], inertia: 0.002}
  coupler: {joints: [C, D], lengths: {C-D: 0.35}, mass: 2.0, cg: [0.1233679, 0.2465917], inertia: 0.03}
  rocker: {joints: [B, D], lengths: {B-D: 0.3}, mass: 1.5, cg: [0.3248689, 0.229828], inertia: 0.012}
drivers: [{link: crank, pivot: A, toward: C}]
gravity: [0, -9.81]
"""


def test_the_motion_does_not_depend_on_the_output_times():
    """Each output time restarted DOP853 from its own guess of a first step: free from 300 rad/s for 2 s (96 turns),
    299 output steps ended 8.3e-4 deg from one step's end (energy off by 6e-8 of itself; review 17c). Each interval
    now starts from the last one's mean step: the ends agree to 4e-6 deg, the energy holds to 5e-10."""
    mech = lk.Mechanism.from_dict(yaml.safe_load(FAST_FOURBAR))
    ends = []
    for n in (1, 200, 299, 353):
        res = lk.simulate(mech, np.linspace(0.0, 2.0, n + 1), speed=300.0)
        E = _energy(mech, res)
        assert np.max(np.abs(E - E[0])) <= 2e-9 * abs(E[0]), n
        ends.append(res.inputs["crank"][-1])
    assert np.ptp(ends) <= 2e-5 and abs(ends[0] - 34715.53) < 0.01, ends


def test_kinetostatics_of_the_simulated_motion_needs_the_applied_torque():
    mech = _fourbar()
    res = lk.simulate(mech, np.linspace(0.0, 1.0, 201), motor=(2.0, 20.0))
    w = res.speeds["crank"]
    applied = 2.0 * (1 - w / 20.0)
    needed = res.forces.driver_torque["crank"]
    assert np.max(np.abs(needed - applied)) <= 1e-8 * 2.0
    signs = np.array([res.signs[j] for j in res.signs])
    again = lk.analyze(mech, res.inputs, speed=res.speeds, acceleration=res.accelerations, signs=signs)
    assert np.allclose(again.forces.driver_torque["crank"], applied, rtol=0, atol=2e-8)


def test_a_crank_with_spring_damper_and_flywheel_follows_the_hand_written_equation():
    arm, r, m, ig, fly, k, L0, c, g = 0.3, 0.15, 2.0, 0.02, 0.01, 200.0, 0.2, 0.5, 9.81
    S = np.array([0.0, 0.5])
    doc = {
        "format": "linkagekit/1",
        "units": {"length": "m", "angle": "deg"},
        "joints": {"O": [0, 0], "A": [arm, 0], "S": S.tolist()},
        "links": {"ground": ["O", "S"], "crank": {"joints": ["O", "A"], "mass": m, "cg": [r, 0], "inertia": ig}},
        "drivers": [{"link": "crank", "pivot": "O", "toward": "A"}],
        "gravity": [0, -g],
        "springs": [{"between": ["S", "A"], "stiffness": k, "free_length": L0}],
        "dampers": [{"between": ["S", "A"], "damping": c}],
        "flywheels": [{"link": "crank", "inertia": fly}],
    }
    mech = lk.Mechanism.from_dict(doc)
    M = ig + m * r * r + fly  # about O: the crank's own inertia, parallel axes, the flywheel

    def rhs(_t, y):
        q, w = y
        A = arm * np.array([math.cos(q), math.sin(q)])
        dA = arm * np.array([-math.sin(q), math.cos(q)])
        L = np.linalg.norm(A - S)
        dL = (A - S) @ dA / L
        Q = -m * g * r * math.cos(q) - k * (L - L0) * dL - c * dL * dL * w + 0.7
        return [w, Q / M]

    t = np.linspace(0.0, 1.5, 151)
    ref = solve_ivp(rhs, (0, 1.5), [0.0, 1.0], method="DOP853", t_eval=t, rtol=1e-12, atol=1e-12)
    res = lk.simulate(mech, t, torque=0.7, speed=1.0)
    q = np.radians(res.inputs["crank"])
    assert np.ptp(ref.y[0]) > 1.0
    assert np.max(np.abs(q - ref.y[0])) < 1e-8
    assert np.max(np.abs(res.speeds["crank"] - ref.y[1])) < 1e-7
    assert np.max(np.abs(res.forces.driver_torque["crank"] - 0.7)) < 1e-8  # kinetostatics with spring and damper
    red, heavier = reduced(mech), reduced(mech, flywheel=0.5)  # a flywheel on a crank adds its inertia to M
    assert red.mass(np.linspace(0, 7, 5)) == pytest.approx(M, rel=1e-12)
    assert heavier.mass(np.linspace(0, 7, 5)) == pytest.approx(M + 0.5, rel=1e-12)
    assert red.force(1.0, 2.0) == pytest.approx(rhs(0, [1.0, 2.0])[1] * M - 0.7, rel=1e-9)


def test_a_motor_driven_fourbar_from_rest_reaches_a_periodic_steady_state():
    mech = _fourbar(spring=False)
    t = np.linspace(0.0, 6.0, 6001)
    res = lk.simulate(mech, t, motor=(1.5, 12.0))
    q = np.radians(res.inputs["crank"]) - np.radians(res.inputs["crank"][0])
    w = res.speeds["crank"]
    turns = np.floor(q / (2 * np.pi)).astype(int)
    last = turns[-1] - 1
    # speed as a function of the crank angle over the last two whole turns: the same curve
    grid = np.linspace(0.1, 2 * np.pi - 0.1, 50)
    w1, w2 = (np.interp(grid, q[turns == n] - 2 * np.pi * n, w[turns == n]) for n in (last - 1, last))
    first = np.interp(grid, q[turns == 0], w[turns == 0])
    assert np.max(np.abs(w1 - w2)) < 1e-3 * np.max(w2) < np.max(np.abs(first - w2))


def test_a_parallelogram_stays_a_parallelogram_through_its_flat_positions():
    doc = _example("seed003_ex22.yaml", gravity=[0, -9.81])
    for link, a, b in (("crank", "O1", "A"), ("coupler", "A", "B"), ("rocker", "O2", "B")):
        _bar(doc, link, 1.0, a, b)
    mech = lk.Mechanism.from_dict(doc)
    res = lk.simulate(mech, np.linspace(0.0, 2.0, 201), speed=12.0)
    assert res.stopped is None
    assert np.ptp(res.inputs["crank"]) > 720  # two turns: four flat positions
    coupler = res.point("B") - res.point("A")
    assert np.max(np.abs(coupler - 1000.0)) < 1e-6  # parallel to the frame all along
    # no torque applied, none needed: to 1e-8 of the gravity torque (9.8 N*m) away from the flat positions,
    # where the rates solver's accelerations lose digits (condition < 1e-2: within about half a degree)
    T, well = np.abs(res.forces.driver_torque["crank"]), res.condition > 1e-2
    assert well.sum() > 0.9 * res.n and np.max(T[well]) < 1e-8 * 9.81
    assert np.max(T) < 1e-4 * 9.81


def _rocker_file(tmp_path):
    """A non-Grashof four-bar: the crank cannot turn fully (its toggles at the ends of its range)."""
    C = np.array([3 * math.cos(math.radians(60)), 3 * math.sin(math.radians(60))])
    B = np.array([4.0, 0.0])
    d = np.linalg.norm(B - C)
    a = (4.0 - 6.25 + d * d) / (2 * d)  # |CD| = 2, |BD| = 2.5
    h = math.sqrt(4.0 - a * a)
    u = (B - C) / d
    D = C + a * u + h * np.array([-u[1], u[0]])
    doc = {
        "format": "linkagekit/1",
        "units": {"length": "m", "angle": "deg"},
        "joints": {"A": [0, 0], "B": B.tolist(), "C": C.tolist(), "D": D.tolist()},
        "links": {"ground": ["A", "B"], "crank": ["A", "C"], "coupler": ["C", "D"], "rocker": ["B", "D"]},
        "drivers": [{"link": "crank", "pivot": "A", "toward": "C"}],
    }
    for link, j1, j2 in (("crank", "A", "C"), ("coupler", "C", "D"), ("rocker", "B", "D")):
        doc["links"][link] = {"joints": [j1, j2]}
        _bar(doc, link, 1.0, j1, j2)
    path = tmp_path / "rocker.yaml"
    path.write_text(yaml.safe_dump(doc))
    return path


def test_a_toggle_stops_the_motion_with_one_line_and_exit_1(tmp_path, capsys):
    path = _rocker_file(tmp_path)
    mech = lk.load(path)
    res = lk.simulate(mech, np.linspace(0.0, 3.0, 301), torque=20.0)
    assert res.stopped is not None and "toggle" in res.stopped and 1 < res.n < 301
    assert res.to_dict()["stopped"] == res.stopped and "stopped" not in lk.simulate(mech, [0.0, 0.1]).to_dict()
    hi = lk.check(mech).to_dict()["input_range"][0][1]
    assert res.inputs["crank"][-1] < hi
    out = tmp_path / "out.csv"
    assert main(["simulate", str(path), "--time", "0:3:0.01", "--torque", "20", "--format", "csv", "-o", str(out)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "t = " in err[0] and "crank" in err[0]
    assert f"at {hi:.6g} deg" in err[0]  # the line names where check puts the toggle, beside where the motion stopped
    rows = out.read_text().strip().splitlines()
    assert rows[0].startswith("time") and len(rows) == res.n + 1


def test_two_drivers_kinetostatics_agrees(tmp_path):
    doc = _example("fivebar_two_drivers.yaml", gravity=[0, -9.81])
    for link, a, b in (("crank1", "A", "C"), ("crank2", "B", "D"), ("link1", "C", "E"), ("link2", "D", "E")):
        _bar(doc, link, 0.2, a, b)
    mech = lk.Mechanism.from_dict(doc)
    res = lk.simulate(mech, np.linspace(0.0, 0.2, 9), torque={"crank1": 0.05, "crank2": -0.02})
    # the two links of the dyad at E come into line at t = 0.1238 s: a singular position the motion cannot pass
    assert res.stopped is not None and "singular" in res.stopped and res.n == 5
    assert res.condition[-1] > 1e-3
    # the one line names the time and where each driver is (file units), the event just past the last row
    stop = re.search(r"t = (\S+) s \(crank1 = (\S+) deg, crank2 = (\S+) deg\)", res.stopped)
    assert stop is not None and abs(float(stop[1]) - 0.1238) < 1e-3
    # there the cranks' tips C and D (30 mm cranks on A = (0, 0), B = (50, 0)) nearly meet: the dyad C-E-D folded
    c = 30 * np.exp(1j * math.radians(float(stop[2])))
    d = 50 + 30 * np.exp(1j * math.radians(float(stop[3])))
    assert abs(c - d) < 1.0
    T = res.forces.driver_torque
    assert np.max(np.abs(T["crank1"] - 0.05)) < 1e-8 and np.max(np.abs(T["crank2"] + 0.02)) < 1e-8
    assert np.ptp(res.inputs["crank1"]) > 1.0


def test_two_drivers_stop_at_a_cylinders_stroke_end_whatever_the_output_step(tmp_path, capsys):
    """The excavator's boom cylinder pushed to its 2.9 m stroke end (review item 3): the stop is that end,
    when and where the same motion with the stroke widened reaches 2.9 m (its cubic Hermite crossing between
    outputs 1 ms apart: ~1e-12 s), to the line's 6 digits; before, the line gave the last output time (0.25
    s with a 0.25 s step, 0.38 s with 0.01) and called it a singular position."""
    doc = _example("excavator_boom.yaml")
    torque = {"boom_cylinder": 4e5, "stick_cylinder": 0.0}
    doc["drivers"][0]["stroke"] = [1.8, 3.0]
    wide = lk.simulate(lk.Mechanism.from_dict(doc), [0.0, 0.38, 0.381], torque=torque)
    assert wide.stopped is None
    t, q, w = wide.time[1:], wide.inputs, wide.speeds
    boom = CubicHermiteSpline(t, q["boom_cylinder"][1:], w["boom_cylinder"][1:])
    (t_end,) = boom.solve(2.9, extrapolate=False)
    stick = CubicHermiteSpline(t, q["stick_cylinder"][1:], w["stick_cylinder"][1:])(t_end)
    mech = lk.load(EXAMPLES / "excavator_boom.yaml")
    lines = [lk.simulate(mech, np.arange(0.0, 3.0, step), torque=torque).stopped for step in (0.25, 0.01)]
    assert lines[0] == lines[1]
    stop = re.search(r"t = (\S+) s \(boom_cylinder = (\S+) m, stick_cylinder = (\S+) m\): (.*)", lines[0])
    assert abs(float(stop[1]) - t_end) <= 5e-7 * t_end and float(stop[2]) == 2.9
    assert abs(float(stop[3]) - stick) <= 5e-6 * stick
    assert stop[4] == "boom_cylinder reached the upper end of its stroke, 2.9 m, that the motion cannot pass"
    out = tmp_path / "out.csv"
    args = ["simulate", str(EXAMPLES / "excavator_boom.yaml"), "--time", "0:3:0.01", "--format", "csv", "-o", str(out)]
    assert main([*args, "--torque", "boom_cylinder=4e5", "--torque", "stick_cylinder=0"]) == 1
    assert capsys.readouterr().err.strip().splitlines() == [f"linkagekit: {lines[0]}"]
    assert out.read_text().strip().splitlines()[-1].startswith("0.38,")  # every output time before the end


def test_cli_json_has_the_time_beside_the_inputs(tmp_path, capsys):
    out = tmp_path / "r.json"
    code = main(["simulate", str(EXAMPLES / "slider_crank.yaml"), "--time", "0:0.02:0.01", "--motor", "2,100",
                 "--format", "json", "-o", str(out)])  # fmt: skip
    assert code == 0
    doc = json.loads(out.read_text())
    assert doc["time"] == pytest.approx([0.0, 0.01, 0.02]) and len(doc["inputs"]["crank"]) == 3
    keys = list(doc)
    assert keys.index("time") + 1 == keys.index("inputs")  # spec section 7: "time" beside "inputs"
    assert doc["speeds"]["crank"][0] == 0.0
    entry = next(q for q in doc["quantities"] if q["name"] == "time")  # the time axis is a catalogue entry
    assert entry["unit"] == "s" and entry["path"] == ["time"] and entry["owner"] == "mechanism"
    assert [q["name"] for q in doc["quantities"]][:2] == ["time", "input:crank"]
    assert main(["simulate", str(EXAMPLES / "slider_crank.yaml"), "--time", "0:0.02:0.01"]) == 0
    assert "time [s]" in capsys.readouterr().out


@pytest.mark.parametrize(
    "args, words",
    [
        (["--time", "0:1:0"], "--time"),
        (["--time", "0:0:1"], "times"),
        (["--time", "0:1:0.1", "--torque", "nan"], "--torque"),
        (["--time", "0:1:0.1", "--motor", "1"], "--motor"),
        (["--time", "0:1:0.1", "--motor", "1,0"], "W0"),
        (["--time", "0:1:0.1", "--torque", "1", "--motor", "1,2"], "not both"),
        (["--time", "0:1:0.1", "--torque", "rod=1"], "rod"),
    ],
)
def test_bad_input_one_line_exit_2(args, words, capsys):
    assert main(["simulate", str(EXAMPLES / "slider_crank.yaml"), *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and words in err[0]


def test_no_driver_or_no_inertia_is_refused():
    with pytest.raises(lk.InputError, match="inertia"):
        lk.simulate(lk.load(EXAMPLES / "seed000_fourbar.yaml"), [0.0, 1.0], torque=1.0)
    with pytest.raises(lk.InputError, match="times"):
        lk.simulate(_fourbar(), [0.0, np.nan])


def test_several_drivers_without_inertia_are_refused_naming_them(capsys):
    """The massless five-bar with a torque on each crank: its mass matrix is zero, and the solve raised numpy's
    LinAlgError ("internal error", exit 1; review 9). With mass on crank1 only, crank2 still moves nothing with
    inertia. Each is one line naming the drivers without inertia, exit 2."""
    path = str(EXAMPLES / "fivebar_two_drivers.yaml")
    args = ["--time", "0:0.1:0.01", "--torque", "crank1=0.5", "--torque", "crank2=0.5"]
    assert main(["simulate", path, *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no inertia along the motion of 'crank1', 'crank2'" in err[0]
    doc = _example("fivebar_two_drivers.yaml")
    _bar(doc, "crank1", 0.2, "A", "C")
    with pytest.raises(lk.InputError, match="no inertia along the motion of 'crank2': give the links it moves"):
        lk.simulate(lk.Mechanism.from_dict(doc), [0.0, 0.1], torque={"crank1": 0.5, "crank2": 0.5})


def test_two_drivers_spring_and_damper_agree_with_kinetostatics():
    """Several drivers with a spring and a damper: kinetostatics (forces.py, its own spring and damper code)
    of the simulated motion needs exactly the applied torques, so a wrong sign or factor of either in the
    several-driver equations of motion shows (as it does for one driver in the reduced table)."""
    doc = _example("fivebar_two_drivers.yaml", gravity=[0, -9.81])
    for link, a, b in (("crank1", "A", "C"), ("crank2", "B", "D"), ("link1", "C", "E"), ("link2", "D", "E")):
        _bar(doc, link, 0.2, a, b)
    doc["springs"] = [{"between": ["P", "B"], "stiffness": 40.0, "free_length": 60.0}]
    doc["dampers"] = [{"between": ["C", "D"], "damping": 0.5}]
    mech = lk.Mechanism.from_dict(doc)
    res = lk.simulate(mech, np.linspace(0.0, 0.04, 5), torque={"crank1": 0.05, "crank2": -0.02}, speed={"crank1": 2.0})
    assert res.stopped is None
    assert np.ptp(res.to_dict()["springs"]["P-B"]["force"]) > 0.5  # N: the spring works along the motion
    T = res.forces.driver_torque
    assert np.max(np.abs(T["crank1"] - 0.05)) < 1e-8 and np.max(np.abs(T["crank2"] + 0.02)) < 1e-8


def test_a_motion_too_fast_for_its_time_span_is_refused_in_one_line(monkeypatch, capsys):
    # --speed 1e9 over 0.1 s is ~1.6e7 turns: before the step budget this ran for hours. The budget is made
    # small here so the refusal is quick; the message gives the speed reached (near the start speed: 1e6 rad/s)
    import linkagekit.dynamics as dyn

    monkeypatch.setattr(dyn, "MAX_STEPS", 2000)
    args = ["simulate", str(EXAMPLES / "slider_crank.yaml"), "--time", "0:0.1:0.01", "--speed", "1e6"]
    assert main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "more than 2000 integration steps" in err[0] and "rad/s" in err[0]
    w = float(re.search(r"moves at (\S+) rad/s", err[0]).group(1))
    assert 0.5e6 < w < 1.5e6
    # the same motion at a sane speed still runs under the real budget
    monkeypatch.setattr(dyn, "MAX_STEPS", 200_000)
    assert main(["simulate", str(EXAMPLES / "slider_crank.yaml"), "--time", "0:0.1:0.01", "--speed", "100"]) == 0


#: a bar (cm) on a pivot, pulled by a spring and a damper from the frame, under gravity and a torque (review's pend)
PENDULUM = {
    "units": {"length": "cm", "angle": "deg"},
    "joints": {"O": [0, 0], "P": [30, 0], "G": [0, -40]},
    "links": {"ground": ["O", "G"], "bar": {"joints": ["O", "P"], "mass": 2, "cg": [15, 0], "inertia": 0.015}},
    "drivers": [{"link": "bar", "pivot": "O", "toward": "P"}],
    "gravity": [0, -9.81],
    "springs": [{"between": ["G", "P"], "stiffness": 200, "free_length": 20}],
    "dampers": [{"between": ["G", "P"], "damping": 3}],
    "flywheels": [{"link": "bar", "inertia": 0.01}],
    "loads": [{"link": "bar", "torque": 1}],
}


def test_a_motion_at_rest_past_the_step_budget_goes_on_with_a_stiff_method(monkeypatch):
    """A damped pendulum settles in about 100 s; DOP853's step then stays ~0.18 s (its stability on the spring's
    vibration), so 90000 s took more than 200000 steps and was refused as moving too fast ('the driver moves at
    -8.67e-14 rad/s: ... lower the speed'). Past the budget, a motion whose steps hardly moved the driver goes on
    with LSODA (stiff: long steps at rest). Here the budget is made 2000 steps over 3000 s (DOP853 alone needs
    ~17000): the motion equals DOP853's own under the full budget to 1e-9 deg and 1e-9 rad/s."""
    import linkagekit.dynamics as dyn

    mech = lk.Mechanism.from_dict(PENDULUM)
    times = np.linspace(0.0, 3000.0, 61)
    ref = lk.simulate(mech, times)
    monkeypatch.setattr(dyn, "MAX_STEPS", 2000)
    res = lk.simulate(mech, times)
    assert res.stopped is None and res.n == 61
    np.testing.assert_allclose(res.inputs["bar"], ref.inputs["bar"], rtol=0, atol=1e-9)
    np.testing.assert_allclose(res.speeds["bar"], ref.speeds["bar"], rtol=0, atol=1e-9)
    assert abs(res.inputs["bar"][-1] - ref.inputs["bar"][-1]) < 1e-9 and abs(res.speeds["bar"][-1]) < 1e-12
    # the refusal, where even that runs out: the speed is no cause there, the time span is
    line = dyn._too_many_steps(36941.0, "-8.67e-14 rad/s", 0.0)
    assert "shorten the time span" in line and "speed" not in line.split(":")[-1] and "vibration" in line


#: an arm on a pivot O lifted by a cylinder from the frame's C to the arm's B, posed fully retracted (1.2 m)
ARM = {
    "format": "linkagekit/1",
    "joints": {"O": [0, 0], "C": [2, 0], "B": [0.89, 0.45596052460711988]},
    "links": {
        "ground": ["O", "C"],
        "arm": {"joints": ["O", "B"], "mass": 20, "cg": [0.445, 0.22798026230355994], "inertia": 1.7},
    },
    "drivers": [{"cylinder": ["C", "B"], "name": "lift", "stroke": [1.2, 2.6]}],
    "gravity": [0, -9.81],
}


def _arm_by_hand(force: float, times: np.ndarray) -> tuple[np.ndarray, float]:
    """The arm's cylinder length at ``times`` and when it reaches 2.6 m, from the arm's own equation: the angle phi
    of OB, (I + m |OG|^2) phi'' = the moment of gravity + the cylinder's force along C -> B."""
    rb, rg, m, inertia = math.hypot(0.89, 0.45596052460711988), math.hypot(0.445, 0.22798026230355994), 20.0, 1.7
    phi0 = math.atan2(0.45596052460711988, 0.89)

    def length(phi: float) -> float:
        return math.hypot(rb * math.cos(phi) - 2.0, rb * math.sin(phi))

    def rhs(_t: float, y: list[float]) -> list[float]:
        phi = y[0]
        bx, by = rb * math.cos(phi), rb * math.sin(phi)
        s = length(phi)
        moment = bx * (force * by / s) - by * (force * (bx - 2.0) / s) - m * 9.81 * rg * math.cos(phi)
        return [y[1], moment / (inertia + m * rg * rg)]

    def end(_t: float, y: list[float]) -> float:
        return length(y[0]) - 2.6

    end.terminal = True  # type: ignore[attr-defined]
    sol = solve_ivp(
        rhs, (0.0, 1.0), [phi0, 0.0], method="DOP853", rtol=1e-12, atol=1e-12, dense_output=True, events=end
    )
    return np.array([length(p) for p in sol.sol(times)[0]]), float(sol.t_events[0][0])


def test_a_cylinder_posed_at_its_stroke_end_moves_away_from_it_and_stops_pushed_into_it():
    """Posed fully retracted (the commonest start of an actuator), the table began 1e-4 of the stroke inside it:
    pushed out, the motion crossed the table's end from outside and stopped at once at the end behind it; pushed in,
    it ran on through lengths that do not assemble, with no stop. Pushed out it follows the arm's own equation to the
    other end; pushed in it stops at once, at 1.2 m."""
    mech = lk.Mechanism.from_dict(ARM)
    times = np.array([0.0, 0.1, 0.2, 0.3])
    res = lk.simulate(mech, times, torque=300.0)
    want, t_end = _arm_by_hand(300.0, times)
    assert res.stopped is None
    np.testing.assert_allclose(res.inputs["lift"], want, rtol=0, atol=1e-8)
    late = lk.simulate(mech, np.array([0.0, 0.5]), torque=300.0)
    assert late.stopped is not None and "lift" in late.stopped and "2.6 m" in late.stopped
    assert abs(float(re.search(r"t = ([0-9.]+) s", late.stopped).group(1)) - t_end) < 1e-4, (late.stopped, t_end)
    held = lk.simulate(mech, np.array([0.0, 0.1, 0.2]), torque=100.0)  # less than gravity's 114.89 N: pulled in
    assert held.stopped is not None and "t = 0 s" in held.stopped and "1.2 m" in held.stopped
    assert held.n == 1 and np.all(held.assembled)


def test_one_cylinder_stops_at_its_stroke_end_itself_with_a_line_free_of_rounding():
    """The one-driver table ended 1e-4 of the range inside each end, a toggle's margin, so the arm pushed out stopped
    at 2.59986 m (t = 0.334068 s), 1.4e-4 m before its stroke's end, and the line said "the end of its range is
    2.6e-12 m on" when it did start on one. A stroke's end is no singular position: the table reaches it, and the
    integrator's event stops the motion there. Against the arm's own equation (DOP853 at 1e-12, its own event at
    2.6 m): the stop time to 1e-6 s (the line prints 6 digits), at 2.6 m."""
    mech = lk.Mechanism.from_dict(ARM)
    assert reduced(mech).q_range == pytest.approx((1.2, 2.6), rel=1e-15, abs=0)
    for force in (300.0, 400.0):
        _, t_end = _arm_by_hand(force, np.array([0.0]))
        line = lk.simulate(mech, np.array([0.0, 0.5]), torque=force).stopped
        stop = re.fullmatch(r"simulate: stopped at t = (\S+) s, lift = (\S+) m: (.*)", line or "")
        assert stop is not None and abs(float(stop[1]) - t_end) < 1e-6 and float(stop[2]) == 2.6, (line, t_end)
        assert stop[3] == "lift reached the upper end of its stroke, 2.6 m, that the motion cannot pass"
    held = lk.simulate(mech, np.array([0.0, 0.1]), torque=100.0).stopped
    assert held == (
        "simulate: stopped at t = 0 s, lift = 1.2 m: lift reached the lower end of its stroke, 1.2 m, that the motion"
        " cannot pass"
    )


def _parallelogram(pose_deg: float) -> lk.Mechanism:
    """A parallelogram (mm) with masses, posed ``pose_deg`` from its flat position: its coupler only translates, so
    M = I_crank + I_rocker + (m_crank/4 + m_rocker/4 + m_coupler) l^2 = 4.2e-4 kg m^2 exactly, Q = -0.11772 cos q."""
    c, s = 40 * math.cos(math.radians(pose_deg)), 40 * math.sin(math.radians(pose_deg))
    doc = {
        "units": {"length": "mm", "angle": "deg"},
        "joints": {"O1": [0, 0], "O2": [100, 0], "A": [c, s], "B": [100 + c, s]},
        "links": {
            "ground": ["O1", "O2"],
            "crank": {"joints": ["O1", "A"], "mass": 0.1, "cg": [c / 2, s / 2], "inertia": 1e-5},
            "coupler": {"joints": ["A", "B"], "mass": 0.2, "cg": [50 + c, s], "inertia": 2e-4},
            "rocker": {"joints": ["O2", "B"], "mass": 0.1, "cg": [100 + c / 2, s / 2], "inertia": 1e-5},
        },
        "drivers": [{"link": "crank", "pivot": "O1", "toward": "A"}],
        "gravity": [0, -9.81],
    }
    return lk.Mechanism.from_dict(doc)


@pytest.mark.parametrize("pose_deg", [2.0, 0.5, 10.0])
def test_a_parallelogram_posed_near_its_flat_position_has_its_exact_model_and_motion(pose_deg):
    """The table of a full turn starts at the pose; the fit that bridges a change point took its samples from one side
    only when the change point was near the table's start: posed 2 deg from flat, M was off by 7e-4 relative near
    0 deg and the motion by 1.2e-3 deg after 1 s (0.033 deg posed at 0.5 deg). Against the exact model (M constant,
    Q = -m g r cos q summed) and its own integration: M and Q to 1e-10, the motion to 1e-7 deg."""
    mech = _parallelogram(pose_deg)
    red = reduced(mech)
    q = np.radians(np.linspace(-10.0, 370.0, 3801))
    assert np.max(np.abs(red.mass(q) / 4.2e-4 - 1)) < 1e-10
    assert np.max(np.abs(red.force(q, 0 * q) + 0.11772 * np.cos(q))) < 1e-10 * 0.11772
    times = np.array([0.0, 0.25, 0.5, 1.0])
    res = lk.simulate(mech, times, speed=5.0)
    sol = solve_ivp(
        lambda _t, y: [y[1], -0.11772 * math.cos(y[0]) / 4.2e-4],
        (0.0, 1.0), [math.radians(pose_deg), 5.0], method="DOP853", rtol=1e-12, atol=1e-12, t_eval=times,
    )  # fmt: skip
    np.testing.assert_allclose(res.inputs["crank"], np.degrees(sol.y[0]), rtol=0, atol=1e-7)


@pytest.mark.parametrize("inside", [1e-4, 0.1, 0.3])
def test_a_crank_posed_next_to_its_toggle_moves_away_under_a_torque_that_pulls_it_out(tmp_path, inside):
    """The rocker's crank posed ``inside`` deg within the end of its range (a toggle), a torque turning it back: no
    table holds there (M grows without bound), and the run was refused as "a singular pose" (0.3 deg from the toggle
    is no singular pose). It runs on the model itself, and the work of the torque is the kinetic energy gained (no
    gravity), to 1e-8 J."""
    import dataclasses

    mech = lk.load(_rocker_file(tmp_path))
    hi = lk.check(mech).to_dict()["input_range"][0][1]
    at = lk.analyze(mech, {"crank": [hi - inside]}, rates=False)
    posed = mech.with_pose(np.stack([at.xy(j)[0] for j in mech.joint_names]))
    res = lk.simulate(posed, np.linspace(0.0, 0.5, 11), torque=-20.0)
    assert res.stopped is None and np.all(res.assembled) and res.n == 11, res.stopped
    q = np.radians(res.inputs["crank"])
    assert np.all(np.diff(q) < 0)  # away from the toggle
    energy = _energy(dataclasses.replace(posed, gravity=0j), res)
    np.testing.assert_allclose(energy - energy[0], -20.0 * (q - q[0]), rtol=0, atol=1e-8)


@pytest.mark.parametrize("torque", [20.0, -20.0])
def test_a_crank_posed_where_the_conditioning_is_below_the_stop_is_refused_not_integrated(tmp_path, torque):
    """Posed 1e-6 deg within its toggle (conditioning 2.9e-4, below STOP_CONDITION), no table holds and the model
    itself is past the stop: the singular event cannot fall through zero, so pushed in the integration ran on for
    minutes (it was refused before the fallback), and pulled out it stopped at once as 'a singular position' when
    the conditioning rose through the threshold. Refused as a singular pose, as before."""
    mech = lk.load(_rocker_file(tmp_path))
    hi = lk.check(mech).to_dict()["input_range"][0][1]
    at = lk.analyze(mech, {"crank": [hi - 1e-6]}, rates=False)
    posed = mech.with_pose(np.stack([at.xy(j)[0] for j in mech.joint_names]))
    with pytest.raises(lk.InputError, match="a singular pose"):
        lk.simulate(posed, np.linspace(0.0, 2.0, 21), torque=torque)


@pytest.mark.parametrize(("pose", "speed"), [(0.01, 5.0), (0.01, -5.0), (-0.01, 5.0)])
def test_a_parallelogram_posed_next_to_its_flat_position_falls_through_it_as_a_parallelogram(pose, speed):
    """Posed 0.01 deg from flat. Once the table's continuous branch folded the parallelogram into a kite when posed
    that near (the pose's input repeated took the rate 0), so the pose's cell failed the table's check and the run
    was refused ('a singular pose'); before that, the fallback said it 'reached a singular position it cannot pass'
    after 1.7e-4 s, moving away. Now it falls through its flat positions: the coupler stays parallel to the
    ground (1e-12 of the size) and the energy ``M w^2 / 2 + 0.11772 sin q`` (M = 4.2e-4 kg m^2) holds to 1e-8."""
    res = lk.simulate(_parallelogram(pose), np.linspace(0.0, 0.25, 51), speed=speed)
    assert res.stopped is None and res.assembled.all()
    d = res.to_dict()
    q, w = np.radians(np.array(d["inputs"]["crank"], float)), np.array(d["speeds"]["crank"], float)
    energy = 0.5 * 4.2e-4 * w**2 + 0.11772 * np.sin(q)
    assert np.ptp(energy) < 1e-8 * abs(energy[0])
    assert np.ptp(q) > np.radians(150)  # it went through a flat position (at 0 or -180 deg)
    A, B = (np.array(d["joints"][j]["x"], float) + 1j * np.array(d["joints"][j]["y"], float) for j in "AB")
    assert np.max(np.abs(B - A - 100)) < 1e-12 * 100


def test_a_pose_at_its_stroke_end_to_rounding_stops_at_once_when_pushed_in():
    """A review's arm, posed at its stroke's lower end as decimals give it (1.8000000000000003 m): pushed in, the line
    said "stopped at t = 7.65431e-09 s" (the integrator's event found the end a step later) where the docs say at once.
    On an end to rounding, driven out of the table: stopped at t = 0."""
    arm = {
        "format": "linkagekit/1",
        "joints": {"O": [0, 0], "C": [2, 0], "B": [0.44, 0.897997772825746]},
        "links": {"ground": ["O", "C"], "arm": {"joints": ["O", "B"], "mass": 20, "cg": [0.22, 0.449], "inertia": 1.7}},
        "drivers": [{"cylinder": ["C", "B"], "name": "lift", "stroke": [1.8, 2.6]}],
        "gravity": [0, -9.81],
    }
    mech = lk.Mechanism.from_dict(arm)
    res = lk.simulate(mech, np.array([0.0, 0.1]), torque=0.0)
    assert res.stopped is not None and res.stopped.startswith(
        "simulate: stopped at t = 0 s, lift = 1.8 m: lift reached"
    )
    assert res.n == 1
    assert lk.simulate(mech, np.array([0.0, 0.05]), torque=2000.0).stopped is None  # pushed out: it moves


def test_a_motor_whose_torque_grows_with_speed_is_refused_in_one_line():
    """``--motor 6500,-6.5``: T0 (1 - w/W0) grows with the speed; the run went on to the step limit (a review)."""
    mech = lk.load("examples/motor_fourbar.yaml")
    with pytest.raises(lk.errors.InputError, match=r"motor\[crank\]: T0 = 6500 and W0 = -6.5 have opposite signs"):
        lk.simulate(mech, np.array([0.0, 0.1]), motor=(6500.0, -6.5))
    assert lk.simulate(mech, np.array([0.0, 0.1]), motor=(-6500.0, -6.5)).stopped is None  # the other way round


def test_a_motion_at_rest_on_a_full_turn_goes_to_the_stiff_method_after_a_twentieth_of_the_budget(monkeypatch):
    """On a crank that turns fully, a motion whose last ``STIFF_PROBE`` of the step budget moved the driver less
    than ``SLOW_STEP`` a step along its path goes on by LSODA from the last output time reached, as one with ends
    does: the pendulum over 90000 s spent the whole budget of DOP853 first (6 s here, 16 s on a slower machine).
    Counted by the right-hand side's evaluations; the motion equals DOP853's alone (no probe) over 3000 s to 1e-9."""
    import linkagekit.dynamics as dyn

    mech = lk.Mechanism.from_dict(PENDULUM)
    evals: dict[str, int] = {}
    ode = dyn._ode

    def counted(rhs, method, times, y):
        def f(t, state):
            evals[method] = evals.get(method, 0) + 1
            return rhs(t, state)

        return ode(f, method, times, y)

    monkeypatch.setattr(dyn, "_ode", counted)
    res = lk.simulate(mech, np.linspace(0.0, 90000.0, 61))
    probe = dyn._EVALS_PER_STEP * int(dyn.STIFF_PROBE * dyn.MAX_STEPS)  # looked at after each (at rest by the second)
    assert probe - 1 <= evals["dop853"] <= 2 * probe and 0 < evals["lsoda"] < probe, evals
    assert res.stopped is None and abs(res.speeds["bar"][-1]) < 1e-12
    times = np.linspace(0.0, 3000.0, 61)
    handed = lk.simulate(mech, times)
    monkeypatch.setattr(dyn, "STIFF_PROBE", 2.0)  # never: DOP853 alone (about 17000 steps)
    alone = lk.simulate(mech, times)
    np.testing.assert_allclose(handed.inputs["bar"], alone.inputs["bar"], rtol=0, atol=1e-9)
    np.testing.assert_allclose(handed.speeds["bar"], alone.speeds["bar"], rtol=0, atol=1e-9)


def test_a_pendulum_swinging_long_is_no_stiff_motion_and_a_motion_repeats_exactly(monkeypatch):
    """Judged by its net travel, a pendulum that swings back looked at rest after a twentieth of the budget, and
    300 s of IFToMM A01 were refused ("more than 200000 integration steps") after 10000 (review 17d); the path its
    states went says it moves: DOP853 goes on, the same motion as with no probe at all. And one call repeated in a
    process gives the same numbers (the first step from counted evaluations differed by 4e-9)."""
    import linkagekit.dynamics as dyn

    mech = lk.load(EXAMPLES / "iftomm_a01_pendulum.yaml")
    times = np.linspace(0.0, 300.0, 301)
    res = lk.simulate(mech, times)
    assert res.stopped is None and res.n == 301
    monkeypatch.setattr(dyn, "STIFF_PROBE", 2.0)
    alone = lk.simulate(mech, times)
    np.testing.assert_array_equal(res.inputs[mech.drivers[0].name], alone.inputs[mech.drivers[0].name])
    motor = lk.load(EXAMPLES / "motor_fourbar.yaml")
    runs = [lk.simulate(motor, np.linspace(0.0, 3.0, 301)).inputs["crank"] for _ in range(2)]
    np.testing.assert_array_equal(runs[0], runs[1])


def test_a_stiff_motion_of_a_driver_with_ends_is_integrated_by_a_stiff_method_within_the_step_budget(monkeypatch):
    """A crank with a limited range is integrated by ``solve_ivp`` with the range's ends as events, which had no
    budget: a damper of 1e9 on the non-Grashof rocker ran for ever (killed after 400 CPU-s; review 16a). It now
    stops DOP853 after ``MAX_STEPS`` steps and, the driver hardly moving, goes on by LSODA (a stiff method) under
    the same budget; a motion that is merely long is refused in one line. (A smaller budget, for the suite's time.)
    Inverse dynamics at the motion found gives back the torque applied."""
    from linkagekit import dynamics

    monkeypatch.setattr(dynamics, "MAX_STEPS", 2000)
    doc = yaml.safe_load((EXAMPLES / "nongrashof_rocker.yaml").read_text())
    doc["dampers"] = [{"between": ["A", "D"], "damping": 1e9}]
    mech = lk.Mechanism.from_dict(doc)
    res = lk.simulate(mech, np.linspace(0.0, 1.0, 11), torque=20.0)
    q, w, a = res.inputs["crank"], res.omega("crank"), res.columns()["crank.alpha"]
    assert res.assembled.all() and np.all(w[1:] > 0) and np.all(w[1:] < 1e-6)  # crept forward, 3e-9 rad/s
    inv = lk.analyze(mech, {"crank": q[1:]}, speed={"crank": w[1:]}, acceleration={"crank": a[1:]})
    assert np.allclose(inv.columns()["T[crank]"], 20.0, rtol=1e-6, atol=0)
    monkeypatch.setattr(dynamics, "MAX_STEPS", 20)
    with pytest.raises(lk.LinkageError, match="more than 20 integration steps .* shorten the time span or lower"):
        lk.simulate(lk.load(EXAMPLES / "nongrashof_rocker.yaml"), np.linspace(0.0, 2.0, 5), torque=-20.0)


def test_a_motor_curve_beyond_the_machines_scale_is_one_line(capsys):
    """``--motor 1e12,1e-12`` made a trial state infinite: "internal error: OverflowError: cannot convert float
    infinity to integer" on a limited range, and on a crank that turns fully a ValueError from the compiled
    integrator (review 16a)."""
    for name in ("nongrashof_rocker.yaml", "iftomm_a03_andrews.yaml"):
        code = main(["simulate", str(EXAMPLES / name), "--time", "0:0.5:0.05", "--motor", "1e12,1e-12"])
        err = capsys.readouterr().err
        assert code == 2 and err.count("\n") == 1 and "no longer a finite number" in err, (name, err)


def test_a_motor_with_no_load_speed_zero_is_named_as_the_option(capsys):
    """``--motor 1,0`` was refused as ``motor[crank]`` (the API's name for it), not as the option given (review 19c)."""
    code = main(["simulate", str(EXAMPLES / "slider_crank.yaml"), "--time", "0:1:0.5", "--motor", "1,0"])
    assert code == 2
    assert capsys.readouterr().err == "linkagekit: error: --motor 1,0: the no-load speed W0 must not be zero\n"


FULL_TURN_TRIAD = """
format: linkagekit/1
name: full-turn class-3 triad with masses
units: {length: m, angle: deg}
joints:
  O: [0.0, 0.0]
  A: [0.094, 0.1452]
  B0: [0.599, 0.34]
  C0: [-0.713, -0.115]
  J1: [0.5257, 1.72745]
  J2: [1.28978, 1.43538]
  J3: [-0.04127, 1.05256]
links:
  ground: [O, B0, C0]
  crank: {joints: [O, A], mass: 1.0, cg: [0.057, 0.0526], inertia: 0.01}
  l1: {joints: [A, J1], mass: 0.5, cg: [0.30985, 0.936325], inertia: 0.004}
  l2: {joints: [B0, J2], mass: 0.7, cg: [0.96439, 0.88769], inertia: 0.006}
  l3: {joints: [C0, J3], mass: 0.6, cg: [-0.377135, 0.46878], inertia: 0.005}
  tern: {joints: [J1, J2, J3], mass: 2.0, cg: [0.6214033333333334, 1.45513], inertia: 0.03}
drivers:
  - {link: crank, pivot: O, toward: A}
gravity: [0.0, -9.81]
"""


def test_a_full_turn_table_cut_at_a_stiff_stretch_goes_on_round_the_turn(tmp_path):
    """A class-3 triad whose crank turns fully (check: [0, 360], no dead point) but whose one-driver table fails its
    tolerance near 152 deg (the group nearly loses rank there) was cut to the run of good cells from the table's
    first cell, 0.618 of a step below the pose, up to the cut: every motion that first went below the pose stopped
    at once (t = 0.009 s; review 19d). The run goes on round the turn to the other side of the cut. By an energy
    balance of the simulated motion, from its own positions and velocities and the file's masses: kinetic plus
    potential energy less the torque's work stays constant."""
    path = tmp_path / "triad.yaml"
    path.write_text(FULL_TURN_TRIAD)
    mech = lk.load(path)
    res = lk.simulate(mech, np.linspace(0.0, 0.55, 56), torque=-3.0)
    q = np.radians(res.inputs["crank"])
    assert res.stopped is None and q[-1] < q[0] - np.radians(150)  # down past the table's first cell and on
    energy, kinetic = 3.0 * (q - q[0]), 0.0  # less the work of the torque -3 N·m
    for link in mech.links:
        if link.mass == 0 and link.inertia == 0:
            continue
        a, b = link.joints[0], link.joints[1]
        za, zb = res.point(a), res.point(b)
        ratio = (link.cg - link.shape[a]) / (link.shape[b] - link.shape[a])  # the centre in its link's frame
        G = za + ratio * (zb - za)
        w = res.omega(link.name)
        vG = res.velocity(a) + 1j * w * (G - za)
        ke = 0.5 * link.mass * np.abs(vG) ** 2 + 0.5 * link.inertia * w**2
        energy, kinetic = energy + ke + link.mass * 9.81 * G.imag, kinetic + ke
    assert np.ptp(energy) < 1e-7 * np.max(kinetic), (np.ptp(energy), np.max(kinetic))  # 7.5e-8 J of 49.5 J


def test_a_cut_tables_model_is_nan_outside_it(tmp_path):
    """Outside a table that does not cover a turn, ``Reduced.mass`` went on along its end cells' cubics: 2.5e8
    kg*m^2 at 359.5 deg where the model is 0.5 (review 19d). It is NaN there (no model), as ``dmass`` and ``force``."""
    path = tmp_path / "triad.yaml"
    path.write_text(FULL_TURN_TRIAD)
    red = lk.reduced(lk.load(path))
    lo, hi = red.q_range
    assert red.period is None and hi - lo < 2 * np.pi
    inside, outside = np.array([red.q0, 0.5 * (lo + hi)]), np.array([hi + 0.01, lo - 0.01])
    assert np.all(np.isfinite(red.mass(inside))) and np.all(np.isnan(red.mass(outside)))
    assert np.all(np.isnan(red.dmass(outside))) and np.all(np.isnan(red.force(outside, 1.0)))
