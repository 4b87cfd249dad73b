"""Crank and coupler massless, inertia on the output only: the reduced inertia vanishes where the output stops.

The textbook model (mass and inertia on the rocker of a crank-rocker, or on the piston of a
slider-crank) has ``M(q) = 0`` at the output's limit positions. The crank turns fully and
``check`` finds no dead point there; the motion and the flywheel sizing go through. Independent
checks written here:

* ``M`` in closed form (``M = I_B gamma^2``, ``gamma`` the rocker's velocity ratio from the
  loop's velocity equation; ``M = m (dx/dq)^2`` for the block, ``dx/dq`` differentiated by hand);
* the flywheel by an RK4 march of the energy equation ``dE/dq = T(w)``, ``w = sqrt(2 E / (M + I))``
  over a turn, its periodic energy by the secant method (not the module's collocation), ``Cs``
  from the speeds, the inertia for the ``Cs`` asked by log-linear interpolation;
* ``simulate`` under a constant torque through many limit positions: kinetic + potential
  energy - the torque's work, from the Result's positions and velocities, stays constant.
"""

import numpy as np
import pytest
import yaml

import linkagekit as lk
from linkagekit import dynamics
from linkagekit.cli import main
from linkagekit.dynamics import TorqueLaw
from linkagekit.errors import InputError
from linkagekit.flywheel import steady_state

ROCKER = {"mass": 2.0, "cg": [2.41, 2.93], "inertia": 0.5}
CRANK_ROCKER = {
    "format": "linkagekit/1",
    "joints": {"A": [0, 0], "B": [4, 1], "C": [2, 0], "D": [0.820550528229663, 4.85889894354067]},
    "links": {
        "ground": ["A", "B"],
        "crank": ["A", "C"],
        "coupler": ["C", "D"],
        "rocker": {"joints": ["B", "D"], **ROCKER},
    },
    "drivers": [{"link": "crank", "pivot": "A", "toward": "C"}],
}
BLOCK_MASS, R, L = 0.4, 0.05, float(np.hypot(0.085, 0.04))
SLIDER_CRANK = {
    "format": "linkagekit/1",
    "joints": {"O": [0, 0], "A": [0.03, 0.04], "B": [0.115, 0]},
    "links": {
        "ground": ["O"],
        "crank": ["O", "A"],
        "rod": ["A", "B"],
        "block": {"joints": ["B"], "mass": BLOCK_MASS, "cg": [0.115, 0]},
    },
    "sliders": [{"link": "block", "on": "ground", "through": "B", "direction": [1, 0]}],
    "drivers": [{"link": "crank", "pivot": "O", "toward": "A"}],
}


def _rocker_mass(q):
    """``M = I_B gamma^2``: D on circle(C, 5) and circle(B, 5), the pose's side; gamma from (v_D - v_C).(D - C) = 0."""
    B, C = 4 + 1j, 2 * np.exp(1j * q)
    d = B - C
    a = np.abs(d) / 2  # equal circles: D on the perpendicular bisector of C-B
    D = C + d / 2 + np.sqrt(25 - a**2) * 1j * d / np.abs(d)  # the pose's side: D to the left of C -> B
    dot = lambda u, v: np.real(np.conj(u) * v)  # noqa: E731
    gamma = dot(1j * C, D - C) / dot(1j * (D - B), D - C)
    i_b = ROCKER["inertia"] + ROCKER["mass"] * abs(complex(*ROCKER["cg"]) - B) ** 2
    return i_b * gamma**2


def _block_mass(q):
    """``M = m (dx_B/dq)^2``, ``x_B = R cos q + sqrt(L^2 - R^2 sin^2 q)``."""
    s, c = np.sin(q), np.cos(q)
    return BLOCK_MASS * (R * s + R**2 * s * c / np.sqrt(L**2 - (R * s) ** 2)) ** 2


def _cs(mass, q0, motor, inertias, n=1024):
    """Cs of the periodic motion for each inertia: RK4 on ``dE/dq = T(w)`` over a turn, secant on its fixed point."""
    T0, W0 = motor
    q = q0 + np.linspace(0.0, 2 * np.pi, 2 * n + 1)  # RK4's half steps
    m = mass(q)[:, None] + np.asarray(inertias)[None, :]
    h = 2 * np.pi / n

    def march(e0):
        e = np.empty((n + 1, len(e0)))
        e[0] = e0
        f = lambda k, x: T0 * (1 - np.sqrt(2 * np.maximum(x, 0) / m[k]) / W0)  # noqa: E731
        for i in range(n):
            k1 = f(2 * i, e[i])
            k2 = f(2 * i + 1, e[i] + h / 2 * k1)
            k3 = f(2 * i + 1, e[i] + h / 2 * k2)
            k4 = f(2 * i + 2, e[i] + h * k3)
            e[i + 1] = e[i] + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        return e

    e_a = 0.5 * m[0] * W0**2
    e_b = 0.9 * e_a
    g_a, g_b = march(e_a)[-1] - e_a, march(e_b)[-1] - e_b
    for _ in range(4):  # the period map is nearly linear: the secant converges in two or three turns
        e_a, g_a, e_b = e_b, g_b, e_b - g_b * (e_b - e_a) / (g_b - g_a)
        g_b = march(e_b)[-1] - e_b
    w = np.sqrt(2 * march(e_b) / m[::2])
    lo, hi = _vertex(w, np.argmin(w, axis=0)), _vertex(w, np.argmax(w, axis=0))
    return (hi - lo) / ((hi + lo) / 2)


def _vertex(w, k):
    """The extreme of each column of ``w`` (closed over a turn) at row ``k``, by the parabola through its neighbours."""
    cols, n = np.arange(w.shape[1]), len(w) - 1
    a, b, c = w[(k - 1) % n, cols], w[k, cols], w[(k + 1) % n, cols]
    return b - (c - a) ** 2 / (8 * (a - 2 * b + c))


@pytest.mark.parametrize(
    ("doc", "mass", "motor", "reviewed"),
    [(CRANK_ROCKER, _rocker_mass, (50.0, 20.0), 113.2520), (SLIDER_CRANK, _block_mass, (3.0, 60.0), 0.0124380)],
    ids=["rocker-only", "block-only"],
)
def test_flywheel_where_the_reduced_inertia_vanishes(doc, mass, motor, reviewed):
    mech = lk.Mechanism.from_dict(doc)
    red = lk.reduced(mech)
    assert red.period == pytest.approx(2 * np.pi)  # the table holds over the whole turn, zeros of M included
    q = red.q0 + np.linspace(0, 2 * np.pi, 997)
    assert np.allclose(red.mass(q), mass(q), rtol=0, atol=1e-9 * mass(q).max())
    assert mass(q).min() < 1e-5 * mass(q).max()  # M falls to 0 where the output stops
    with pytest.raises(InputError, match="no steady state without a flywheel"):
        steady_state(red, TorqueLaw(*motor))  # the massless crank's speed there depends on the inertia left out
    size = lk.size_flywheel(mech, 0.05, motor=motor)
    assert size.cs == pytest.approx(0.05, rel=1e-5) and size.cs <= 0.05 and size.cs_without == 2.0
    # independent: Cs a hair either side of the inertia found, interpolated log-linearly to Cs = 0.05
    pair = size.inertia * np.array([1 - 2e-3, 1 + 2e-3])
    cs = _cs(mass, red.q0, motor, pair)
    assert cs[0] > 0.05 > cs[1]
    root = np.exp(np.interp(np.log(0.05), np.log(cs[::-1]), np.log(pair[::-1])))
    assert size.inertia == pytest.approx(root, rel=2e-6)
    assert size.inertia == pytest.approx(reviewed, rel=1e-5)  # the review's shooting method (fly_cr.py, fly_bo.py)


def _energy(res, doc, gravity):
    """Kinetic + potential energy (J) of the one massive link, from the Result's positions and velocities."""
    name, body = ("rocker", ROCKER) if "rocker" in doc["links"] else ("block", None)
    if body is None:  # the block slides: kinetic only
        return 0.5 * BLOCK_MASS * np.abs(res.velocity("B")) ** 2 - BLOCK_MASS * np.real(
            np.conj(gravity) * res.point("B")
        )
    ab = res.point("D") - res.point("B")
    rel = (complex(*body["cg"]) - 4 - 1j) / (complex(*doc["joints"]["D"]) - 4 - 1j)  # G in the rocker's frame
    zg = res.point("B") + rel * ab
    vg = 1j * res.omega(name) * (zg - res.point("B"))
    return (
        0.5 * body["mass"] * np.abs(vg) ** 2
        + 0.5 * body["inertia"] * res.omega(name) ** 2
        - body["mass"] * np.real(np.conj(gravity) * zg)
    )


@pytest.mark.parametrize(
    ("doc", "torque", "times", "gravity"),
    [(CRANK_ROCKER, 60.0, np.linspace(0.0, 3.0, 151), -9.81j), (SLIDER_CRANK, 1.0, np.linspace(0.0, 0.3, 151), 0j)],
    ids=["rocker-only", "block-only"],
)
def test_a_constant_torque_turns_the_crank_through_the_limit_positions(doc, torque, times, gravity):
    data = {**doc, "gravity": [gravity.real, gravity.imag]}
    mech = lk.Mechanism.from_dict(data)
    res = lk.simulate(mech, times, torque=torque)
    assert res.stopped is None and res.n == len(times) and np.all(res.assembled)
    q = np.radians(res.inputs["crank"])
    assert q[-1] - q[0] > 4 * np.pi and np.all(np.diff(q) > 0)  # two turns and more: four limit positions passed
    E = _energy(res, data, gravity) - torque * (q - q[0])  # minus the torque's work
    exchanged = torque * (q[-1] - q[0])
    assert np.max(np.abs(E - E[0])) <= 1e-8 * exchanged


def test_the_cli_runs_through_and_a_motor_curve_there_is_one_line(tmp_path, capsys):
    path = tmp_path / "cr.yaml"
    path.write_text(yaml.safe_dump(CRANK_ROCKER))
    assert (
        main(
            [
                "simulate",
                str(path),
                "--time",
                "0:2:0.5",
                "--torque",
                "5",
                "--format",
                "csv",
                "-o",
                str(tmp_path / "o.csv"),
            ]
        )
        == 0
    )
    capsys.readouterr()
    assert main(["simulate", str(path), "--time", "0:2:0.5", "--motor", "50,20"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "crank = 58.7783 deg" in err[0] and "toggle" not in err[0] and "inertia" in err[0]


def test_a_stop_on_a_crank_that_turns_fully_is_no_toggle():
    """Were the table cut where the crank turns fully, the line would not put a toggle at 0 deg (`check` has none)."""
    mech = lk.Mechanism.from_dict(CRANK_ROCKER)
    line = dynamics._toggle_message(dynamics._model(mech), 0, 1.69666, np.radians(58.7633))
    assert line.startswith("simulate: stopped at t = 1.69666 s, crank = 58.7633 deg: ")
    assert "(no toggle)" in line and "end of its range" not in line
