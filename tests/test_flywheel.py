"""Periodic steady state under a torque law and flywheel sizing (src/linkagekit/flywheel.py).

Independent checks: a manufactured model whose periodic solution is known in closed form,
the coefficient of speed fluctuation against a brute-force time integration written here
(scipy on M q'' + 1/2 M' q'^2 = F + T, not the energy form the module uses), and the
stall / runaway cases.
"""

import json
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import linkagekit as lk
from linkagekit.cli import main
from linkagekit.dynamics import TorqueLaw as Motor
from linkagekit.errors import InputError, LinkageError
from linkagekit.flywheel import StallError, size_flywheel_reduced, steady_state


class Toy:
    """M(q) = a + b cos 2q, a constant load torque L and a gravity-like -c sin q."""

    period = 2 * np.pi
    q_range = (0.0, 2 * np.pi)

    def __init__(self, a=1.0, b=0.5, c=30.0, load=50.0, damping=0.0):
        self.a, self.b, self.c, self.load, self.damping = a, b, c, load, damping

    def mass(self, q):
        return self.a + self.b * np.cos(2 * np.asarray(q))

    def dmass(self, q):
        return -2 * self.b * np.sin(2 * np.asarray(q))

    def force(self, q, w):
        return -self.load - self.c * np.sin(q) - self.damping * np.asarray(w)


class Manufactured(Toy):
    """A force built so that w*(q) = W (1 + eps sin q) is the periodic motion under ``motor``.

    force(q, w) = dE*/dq - T(w*(q)) - C (w - w*(q)) with E* = 1/2 M w*^2: along w* the
    energy equation dE/dq = force + T holds, and the damper term makes it the attracting one.
    Then Cs = 2 eps and (w_max + w_min) / 2 = W exactly.
    """

    def __init__(self, motor, speed=4.0, eps=0.05, damping=2.0):
        super().__init__()
        self.motor, self.speed, self.eps, self.damping = motor, speed, eps, damping

    def exact(self, q):
        return self.speed * (1 + self.eps * np.sin(q))

    def force(self, q, w):
        q = np.asarray(q)
        ws = self.exact(q)
        dws = self.speed * self.eps * np.cos(q)
        de = 0.5 * self.dmass(q) * ws**2 + self.mass(q) * ws * dws
        return de - self.motor(ws) - self.damping * (np.asarray(w) - ws)


def brute_cs(model, motor, inertia, w_start, turns):
    """Cs of the last turn of a time integration of M q'' + 1/2 M' q'^2 = F + T from (0, w_start)."""

    def rhs(t, y):
        q, w = y
        m = model.mass(q) + inertia
        return [w, (model.force(q, w) + motor(w) - 0.5 * model.dmass(q) * w * w) / m]

    def turn_done(t, y):
        return y[0] - 2 * np.pi * turns

    turn_done.terminal = True
    sol = solve_ivp(
        rhs, (0, 1e4), [0.0, w_start], "DOP853", rtol=1e-11, atol=1e-11, events=turn_done, dense_output=True
    )
    t_end = sol.t[-1]
    w_end = sol.y[1, -1]
    t = np.linspace(t_end - 2 * np.pi / w_end * 1.2, t_end, 40001)
    q, w = sol.sol(t)
    last = q >= q[-1] - 2 * np.pi
    w = w[last]
    return (w.max() - w.min()) / ((w.max() + w.min()) / 2), w_end


def test_manufactured_periodic_solution_is_found_exactly():
    motor = Motor(20.0, 6.0)
    model = Manufactured(motor)
    st = steady_state(model, motor)
    assert np.max(np.abs(st.w - model.exact(st.q))) < 1e-7 * model.speed
    assert st.cs == pytest.approx(2 * model.eps, abs=1e-7)
    assert st.mean_speed == pytest.approx(model.speed, rel=1e-8)
    assert 0 < st.contraction < 1


def test_constant_torque_with_damper_and_constant_mass():
    # M = 3, torque 12 against a load 2 and a damper 4 w: the steady speed (12 - 2)/4 = 2.5, Cs = 0
    model = Toy(a=3.0, b=0.0, c=0.0, load=2.0, damping=4.0)
    st = steady_state(model, Motor(12.0))
    assert np.allclose(st.w, 2.5, rtol=1e-9)
    assert st.cs == pytest.approx(0.0, abs=1e-9)


def test_flywheel_cs_matches_brute_force_time_integration():
    model, motor = Toy(), Motor(1000.0, 5.5)  # a stiff motor curve: the transient dies within a few turns
    size = size_flywheel_reduced(model, motor, 0.02)
    assert size.cs <= 0.02 * (1 + 1e-6)
    assert size.cs == pytest.approx(0.02, rel=1e-5)
    assert size.cs_without > 0.02
    # from rest, 15 turns (the period map contracts by 0.13 a turn): it settles on the periodic motion, Cs as sized
    cs, w_end = brute_cs(model, motor, size.inertia, 0.0, 15)
    assert cs == pytest.approx(0.02, rel=1e-5)
    assert w_end == pytest.approx(size.steady.w[-1], rel=1e-7)
    # the smallest: 1e-3 less inertia exceeds the Cs asked (Cs ~ 1 / inertia)
    cs_less, _ = brute_cs(model, motor, size.inertia * (1 - 1e-3), size.steady.w[0], 10)
    assert cs_less > 0.02 * (1 + 5e-4)


def test_cs_falls_with_the_flywheel():
    model, motor = Toy(), Motor(100.0, 10.0)
    cs = [steady_state(model, motor, inertia).cs for inertia in (0.0, 1.0, 3.0, 10.0, 30.0)]
    assert all(a > b for a, b in zip(cs, cs[1:], strict=False))


def test_cs_already_met_needs_no_flywheel():
    model = Toy(c=0.0, b=0.0, load=10.0, damping=1.0)
    size = size_flywheel_reduced(model, Motor(100.0, 10.0), 0.02)
    assert size.inertia == 0.0


def test_motor_too_weak_stalls():
    with pytest.raises(StallError, match="stalls") as err:
        steady_state(Toy(load=50.0), Motor(40.0, 10.0))  # mean torque 40 < load 50 at any speed
    assert err.value.exit_code == 1 and isinstance(err.value, LinkageError)


def test_potential_barrier_stops_a_slow_machine():
    # mean torque 52 > load 50, but the 200 sin q hump needs kinetic energy the machine cannot keep
    with pytest.raises(StallError, match="stalls"):
        steady_state(Toy(c=200.0, load=50.0), Motor(52.0, 1.0))


def test_a_flywheel_carries_a_stalling_machine_through():
    # without a flywheel the 200 sin q hump stops it within a turn; the sizing starts from Cs = 2 there
    model, motor = Toy(c=200.0, load=50.0), Motor(60.0, 100.0)
    with pytest.raises(StallError, match="within a turn"):
        steady_state(model, motor)
    size = size_flywheel_reduced(model, motor, 0.02)
    assert size.cs_without == 2.0 and size.cs == pytest.approx(0.02, rel=2e-6)
    cs, w_end = brute_cs(model, motor, size.inertia, size.steady.w[0], 3)  # a periodic motion: back where it began
    assert cs == pytest.approx(size.cs, rel=1e-6) and w_end == pytest.approx(size.steady.w[0], rel=1e-8)


def test_constant_torque_without_damping_runs_away():
    with pytest.raises(StallError, match="without bound"):
        steady_state(Toy(load=50.0), Motor(60.0))


@pytest.mark.parametrize("cs", [0.0, -0.1, 2.0, math.nan])
def test_bad_cs(cs):
    with pytest.raises(InputError, match="flywheel"):
        size_flywheel_reduced(Toy(), Motor(100.0, 10.0), cs)


def test_negative_direction_is_the_mirror():
    model = Toy(c=30.0, load=0.0)
    ahead = steady_state(model, Motor(100.0, 10.0))
    back = steady_state(model, Motor(-100.0, -10.0))
    assert back.cs == pytest.approx(ahead.cs, rel=1e-7)  # c sin q is odd: q -> -q maps one on the other
    assert np.all(back.w < 0)


# ---------------------------------------------------------------------- on a mechanism
EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "motor_fourbar.yaml"
MOTOR = (6500.0, 6.5)


@pytest.fixture(scope="module")
def pump():
    mech = lk.load(EXAMPLE)
    return mech, lk.size_flywheel(mech, 0.02, motor=MOTOR)


def test_the_sized_pump_keeps_cs_in_a_simulation(pump):
    """lk.simulate (time integration of the tabulated model) from the periodic state, with the flywheel."""
    mech, size = pump
    st = size.steady
    assert size.cs == pytest.approx(0.02, rel=2e-6) and size.cs <= 0.02
    assert size.cs_without > 0.2  # without it the beam's changing inertia swings the speed by about 23 %
    data = mech.to_dict()
    data["flywheels"] = [{"link": "crank", "inertia": size.inertia}]
    fly = lk.Mechanism.from_dict(data)
    period = 2 * np.pi / st.mean_speed
    res = lk.simulate(fly, np.linspace(0.0, 1.05 * period, 1500), motor=MOTOR, speed=st.w[0])
    q = np.unwrap(np.radians(res.inputs["crank"]))
    w = res.omega("crank")
    # the same motion: the collocation's w(q) at the simulated q, and back to the start after a turn
    assert np.max(np.abs(w - np.interp(q, st.q, st.w, period=2 * np.pi))) < 1e-7 * st.mean_speed
    turn = q <= q[0] + 2 * np.pi
    cs = (w[turn].max() - w[turn].min()) / ((w[turn].max() + w[turn].min()) / 2)
    assert cs == pytest.approx(size.cs, abs=2e-5)  # the samples, 1500 a turn, miss the extremes by ~1e-5
    # a flywheel on the file adds to it: the same steady state needs no more
    assert lk.size_flywheel(fly, 0.02, motor=MOTOR).inertia == 0.0


def test_cli_prints_the_inertia(pump, capsys):
    _, size = pump
    assert main(["simulate", str(EXAMPLE), "--motor", "6500,6.5", "--flywheel", "0.02"]) == 0
    assert float(capsys.readouterr().out) == pytest.approx(size.inertia, rel=1e-9)  # kg*m^2, the number alone
    assert main(["simulate", str(EXAMPLE), "--motor", "6500,6.5", "--flywheel", "0.02", "--format", "json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["link"] == "crank" and out["inertia"] == pytest.approx(size.inertia, rel=1e-9)
    assert out["units"] == {"inertia": "kg*m^2", "speed": "rad/s"}
    assert out["speed"]["min"] < out["speed"]["mean"] < out["speed"]["max"]


@pytest.mark.parametrize(
    ("args", "code", "words"),
    [
        (["--motor", "200,6.5", "--flywheel", "0.02"], 1, "stalls"),  # 200 N*m < the 300 N*m pumping load
        (["--torque", "500", "--flywheel", "0.02"], 1, "without bound"),  # no speed-dependent term: no balance
        (["--flywheel", "0.02"], 2, "torque law"),
        (["--motor", "6500,6.5", "--flywheel", "0"], 2, "(0, 2)"),
        (["--motor", "6500,6.5", "--flywheel", "0.02", "--speed", "1"], 2, "--speed"),
    ],
)
def test_cli_no_steady_state_or_bad_input_one_line(args, code, words, capsys):
    assert main(["simulate", str(EXAMPLE), *args]) == code
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and words in err[0]


def test_a_slider_driver_has_no_crank_for_a_flywheel():
    mech = lk.load(EXAMPLE.parent / "excavator_bucket_slider.yaml")
    with pytest.raises(InputError, match="crank driver"):
        lk.size_flywheel(mech, 0.02, torque=1.0)


def test_a_crank_that_does_not_turn_fully_is_refused():
    data = lk.load(EXAMPLE).to_dict()
    data["drivers"] = [{"link": "beam", "pivot": "B", "toward": "D", "angles": {"start": 110, "stop": 150, "step": 1}}]
    with pytest.raises(InputError, match="does not turn fully"):
        lk.size_flywheel(lk.Mechanism.from_dict(data), 0.02, motor=MOTOR)


@pytest.mark.parametrize(
    ("args", "kwargs", "words"),
    [
        ((0.02,), {}, "give the torque law: torque= or motor="),
        (("x",), {"torque": 1.0}, "cs (--flywheel CS): expected a number"),
        ((2.5,), {"motor": MOTOR}, "cs (--flywheel CS): the coefficient of speed fluctuation must be in (0, 2)"),
        # review 16a: a ValueError (math domain error) from the log of a fluctuation that rounded to 0
        ((1e-20,), {"motor": MOTOR}, "cs (--flywheel CS): at least 1e-09, what the steady state resolves"),
    ],
)
def test_python_errors_name_the_argument_not_only_the_option(args, kwargs, words):
    """``lk.size_flywheel`` serves Python and ``simulate --flywheel``: its errors began with '--flywheel:', an option a
    Python caller never gave; they name the argument (``cs``, ``torque=``/``motor=``) and the option beside it."""
    with pytest.raises(InputError) as info:
        lk.size_flywheel(lk.load(EXAMPLE), *args, **kwargs)
    message = str(info.value)
    assert words in message and not message.startswith("--")


def test_no_torque_on_conservative_loads_says_nothing_drives_the_crank(capsys):
    """``--torque 0`` on the slider-crank (gravity only, which takes nothing over a turn) said "the loads take -0
    N*m on average over a turn, more than the torque law gives at any speed (0 N*m at rest)" (review 16a)."""
    path = EXAMPLE.parent / "slider_crank.yaml"
    assert main(["simulate", str(path), "--flywheel", "0.02", "--torque", "0"]) == 1
    err = capsys.readouterr().err
    assert "nothing drives the crank on average over a turn (the loads take 0 N*m" in err and "-0" not in err, err
