"""Periodic steady state under a torque law and flywheel sizing (src/linkagekit/flywheel.py).

Independent checks: a manufactured model whose periodic solution is known in closed form,
the coefficient of speed fluctuation against a brute-force time integration written here
(scipy on M q'' + 1/2 M' q'^2 = F + T, not the energy form the module uses), and the
stall / runaway cases.
"""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from linkagekit.errors import InputError, LinkageError
from linkagekit.dynamics import TorqueLaw as Motor
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


def test_constant_torque_without_damping_runs_away():
    with pytest.raises(StallError, match="without bound"):
        steady_state(Toy(load=50.0), Motor(60.0))


@pytest.mark.parametrize("cs", [0.0, -0.1, math.nan])
def test_bad_cs(cs):
    with pytest.raises(InputError, match="flywheel"):
        size_flywheel_reduced(Toy(), Motor(100.0, 10.0), cs)


def test_negative_direction_is_the_mirror():
    model = Toy(c=30.0, load=0.0)
    ahead = steady_state(model, Motor(100.0, 10.0))
    back = steady_state(model, Motor(-100.0, -10.0))
    assert back.cs == pytest.approx(ahead.cs, rel=1e-7)  # c sin q is odd: q -> -q maps one on the other
    assert np.all(back.w < 0)
