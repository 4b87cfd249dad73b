"""Every assembly mode of a numerical group, and the assembly range of its pose's mode (issue 10, points 3, 4).

Checked against computations written here, none of which shares code with linkagekit's:

* a class-3 triad (a 3-RR platform: a ternary held by three binary links) with six real
  assembly modes, known by the classical polynomial of the direct kinematics of planar
  3-RPR platforms: with ``t = tan(phi/2)`` (``phi`` the ternary's orientation) two of the
  three leg equations, minus the first, are linear in the first joint and give it by
  Cramer's rule; the first leg equation then is a polynomial of degree 8 in ``t`` whose
  real roots are the modes (two of its complex roots are the spurious ``t = +-i``, so at
  most six are real); each root polished by ``scipy.optimize.root``.  ``lk.modes`` finds all
  six to 1e-9 of the size (measured ~2e-14);
* 30 random triads at two inputs each: the modes equal those of a dense search over the
  ternary's orientation and the angle of its first joint on its circle (a 720 x 720 grid,
  every cell where both closure residuals change sign polished by ``scipy.optimize.root``),
  same number, each to 1e-9 of the size;
* a triad held by the rocker of a four-bar with a dyad hanging from it: every combination
  of the two closed-form signs with every mode of the group, each mode's joints checked
  against every link length and the grid search at that rocker position;
* a mode chosen by its positions (``Mode.mechanism``) and analysed: its positions come back
  at that input (1e-9 of the size), every link length is kept over a sweep (1e-10
  relative), and the sweep follows the mode (a fine continuation written here, 1e-7);
* ``check`` on triads: which joints are numerical, and the assembly range of the pose's
  mode against the singular position of the triad found here: a continuation with
  ``scipy.optimize.root`` in steps of 0.05 degree to where it stops, then the augmented
  system (six distance equations and det of their Jacobian = 0, unknowns the joints and
  the input) solved by ``scipy.optimize.root``: range ends to 1e-6 degree (measured ~1e-8).
"""

from __future__ import annotations

import functools
import math
import re

import numpy as np
import pytest
from numpy.polynomial import Polynomial
from scipy.optimize import root

import linkagekit as lk
from helpers import TRIAD_LINKS
from linkagekit.plan import make_plan

MOVING = ("J1", "J2", "J3")


def triad(p: dict[str, complex], links: dict | None = None, drivers: list | None = None) -> lk.Mechanism:
    return lk.Mechanism.from_dict(
        {
            "format": "linkagekit/1",
            "units": {"length": "mm", "angle": "deg"},
            "joints": {k: [v.real, v.imag] for k, v in p.items()},
            "links": links or TRIAD_LINKS,
            "drivers": drivers or [{"link": "crank", "pivot": "O", "toward": "A"}],
        }
    )


def scale_of(mech) -> float:
    z = np.array(list(mech.joints.values()))
    return float(np.max(np.abs(z - z.mean())))


# ----------------------------------------------------------------------------- independent solvers
def platform(base, plat, rho) -> dict:
    """A 3-RR platform: base joints a_k (where the binary links are held), the ternary's joints
    p_k relative to its first (at orientation 0), the binary links' lengths rho_k."""
    return {"a": np.asarray(base, complex), "p": np.asarray(plat, complex), "rho": np.asarray(rho, float)}


def polynomial_modes(d: dict) -> list[np.ndarray]:
    """Every real mode by the polynomial in t = tan(phi/2) (see the module docstring)."""
    a, p, rho = d["a"], d["p"], d["rho"]
    W, C, S = Polynomial([1, 0, 1]), Polynomial([1, 0, -1]), Polynomial([0, 2])  # (1 + t^2) times 1, cos, sin

    def lin(alpha, beta, gamma):  # (alpha + beta cos phi + gamma sin phi) (1 + t^2)
        return alpha * W + beta * C + gamma * S

    rows = []
    for k in (1, 2):
        dk = a[0] - a[k]  # c_k = dk + e^{i phi} p_k; 2 Re(conj(u) c_k) = rho_k^2 - rho_1^2 - |c_k|^2, u = J1 - a_1
        q = np.conj(dk) * p[k]
        re, im = lin(dk.real, p[k].real, -p[k].imag), lin(dk.imag, p[k].imag, p[k].real)
        r = (rho[k] ** 2 - rho[0] ** 2) * W - lin(abs(dk) ** 2 + abs(p[k]) ** 2, 2 * q.real, -2 * q.imag)
        rows.append((re, im, r))
    (re2, im2, r2), (re3, im3, r3) = rows
    nx, ny, det = r2 * im3 - r3 * im2, re2 * r3 - re3 * r2, 2 * (re2 * im3 - re3 * im2)
    poly = nx * nx + ny * ny - rho[0] ** 2 * det * det  # |u|^2 = rho_1^2, times det^2 (1 + t^2)^4
    assert poly.degree() <= 8
    phis = [2 * math.atan(t.real) for t in poly.roots() if abs(t.imag) <= 1e-7 * max(1.0, abs(t))]
    if abs(poly.coef[-1]) <= 1e-12 * np.max(np.abs(poly.coef)):  # a root at t = infinity
        phis.append(math.pi)

    def residual(x):
        J = complex(x[0], x[1]) + complex(math.cos(x[2]), math.sin(x[2])) * p
        return np.abs(J - a) ** 2 - rho**2

    out: list[np.ndarray] = []
    for phi in phis:
        e = complex(math.cos(phi), math.sin(phi))
        c2, c3 = a[0] - a[1] + e * p[1], a[0] - a[2] + e * p[2]
        m = 2 * np.array([[c2.real, c2.imag], [c3.real, c3.imag]])
        u = np.linalg.solve(m, [rho[1] ** 2 - rho[0] ** 2 - abs(c2) ** 2, rho[2] ** 2 - rho[0] ** 2 - abs(c3) ** 2])
        sol = root(residual, [a[0].real + u[0], a[0].imag + u[1], phi], method="lm", tol=1e-15)
        if np.max(np.abs(residual(sol.x))) <= 1e-9 * np.max(rho) ** 2:
            J = complex(sol.x[0], sol.x[1]) + complex(math.cos(sol.x[2]), math.sin(sol.x[2])) * p
            if not any(np.max(np.abs(J - o)) <= 1e-7 * np.max(rho) for o in out):
                out.append(J)
    return out


def grid_modes(d: dict, n: int = 720) -> list[np.ndarray]:
    """Every real mode by a dense search over (alpha, phi): J1 = a_1 + rho_1 e^{i alpha} on its circle,
    the ternary at orientation phi; cells where both closure residuals change sign are polished."""
    a, p, rho = d["a"], d["p"], d["rho"]
    ang = 2 * np.pi * np.arange(n + 1) / n
    al, ph = np.meshgrid(ang, ang, indexing="ij")
    j1, e = a[0] + rho[0] * np.exp(1j * al), np.exp(1j * ph)
    mixed = []
    for k in (1, 2):
        s = (np.abs(j1 + e * p[k] - a[k]) ** 2 - rho[k] ** 2) > 0
        c = s[:-1, :-1].astype(int) + s[1:, :-1] + s[:-1, 1:] + s[1:, 1:]
        mixed.append((c > 0) & (c < 4))

    def res(x):
        j, ee = a[0] + rho[0] * np.exp(1j * x[0]), np.exp(1j * x[1])
        return [(abs(j + ee * p[k] - a[k]) ** 2 - rho[k] ** 2) / rho[k] ** 2 for k in (1, 2)]

    h = 2 * np.pi / n
    out: list[np.ndarray] = []
    for i, k in np.argwhere(mixed[0] & mixed[1]):
        sol = root(res, [(i + 0.5) * h, (k + 0.5) * h], method="hybr", tol=1e-14)
        if np.max(np.abs(res(sol.x))) > 1e-12:
            continue
        J = a[0] + rho[0] * np.exp(1j * sol.x[0]) + np.exp(1j * sol.x[1]) * p
        if not any(np.max(np.abs(J - o)) <= 1e-7 * np.max(rho) for o in out):
            out.append(J)
    return out


def platform_of(mech, at: complex, held=("A", "B0", "C0")) -> dict:
    """The triad as a platform, its first binary link held at ``at`` (the others at their ground pivots)."""
    z = mech.joints
    legs = [("l1", held[0], "J1"), ("l2", held[1], "J2"), ("l3", held[2], "J3")]
    base = [at, z[held[1]], z[held[2]]]
    return platform(base, [0, z["J2"] - z["J1"], z["J3"] - z["J1"]], [mech.link(ln).length(h, j) for ln, h, j in legs])


def listed(found, joints=MOVING) -> list[np.ndarray]:
    """The distinct assembled modes of lk.modes, as arrays of the given joints."""
    return [np.array([complex(*m.joints[j]) for j in joints]) for m in found.modes if m.assembled and m.same_as is None]


def listed_one(mode, joints=MOVING) -> np.ndarray:
    return np.array([complex(*mode.joints[j]) for j in joints])


def same_sets(a: list[np.ndarray], b: list[np.ndarray], tol: float) -> float:
    """The worst distance from a mode of one set to the nearest of the other (inf if the counts differ)."""
    if len(a) != len(b):
        return math.inf
    return max([min(float(np.max(np.abs(x - y))) for y in b) for x in a] + [0.0])


# ----------------------------------------------------------------------------- (a) six real modes
#: base joints, the ternary's shape and the binary links' lengths of a triad with six real modes
#: (found by a search over random triads with the polynomial above; the test checks the six)
SIX = {"A": 4.70 + 7.26j, "B0": 5.99 + 3.40j, "C0": -7.13 - 1.15j, "p2": -6.55 + 4.90j, "p3": 7.30 + 4.94j}
SIX_RHO = (10.03, 12.95, 13.47)


def six_mode_triad(k: int = 0):
    d = platform([SIX["A"], SIX["B0"], SIX["C0"]], [0, SIX["p2"], SIX["p3"]], SIX_RHO)
    known = polynomial_modes(d)
    J = known[k]
    mech = triad({"O": 0j, "A": SIX["A"], "B0": SIX["B0"], "C0": SIX["C0"], "J1": J[0], "J2": J[1], "J3": J[2]})
    return mech, known, math.degrees(math.atan2(SIX["A"].imag, SIX["A"].real))


def test_a_triad_with_six_real_modes():
    mech, known, at = six_mode_triad()
    assert len(known) == 6  # by the polynomial: the most a 3-RR platform can have
    assert len(grid_modes(platform_of(mech, SIX["A"]))) == 6  # and by the grid search
    legs = [mech.link(n).length(a, b) for n, a, b in (("l1", "A", "J1"), ("l2", "B0", "J2"), ("l3", "C0", "J3"))]
    assert legs == pytest.approx(SIX_RHO, rel=1e-12)
    found = lk.modes(mech, at=at)
    got = listed(found)
    s = scale_of(mech)
    assert found.distinct == 6 and len(found.modes) == 6
    assert same_sets(got, known, s) <= 1e-9 * s
    assert [m.groups for m in found.modes] == [{"J1,J2,J3": {"index": i, "of": 6}} for i in range(6)]
    # the pose's own mode is the reference one, and it is the pose
    ref = [m for m in found.modes if m.reference]
    assert len(ref) == 1
    assert np.max(np.abs(np.array([complex(*ref[0].joints[j]) for j in MOVING]) - known[0])) <= 1e-9 * s
    # the modes are the same whichever of them is the file's pose
    other, _, _ = six_mode_triad(3)
    assert same_sets(listed(lk.modes(other, at=at)), known, s) <= 1e-9 * s


def test_six_modes_in_the_command_line(tmp_path, capsys):
    mech, _, at = six_mode_triad()
    path = tmp_path / "six.yaml"
    lk.save(mech, path)
    from linkagekit.cli import main

    assert main(["modes", str(path), "--at", repr(at)]) == 0
    out = capsys.readouterr().out
    assert "group modes" in out and "6/6" in out and "6 distinct assembled configuration(s) of 6." in out
    assert main(["modes", str(path), "--at", repr(at), "--format", "json"]) == 0
    import json

    doc = json.loads(capsys.readouterr().out)
    assert [m["groups"]["J1,J2,J3"]["index"] for m in doc["modes"]] == list(range(6))


# ----------------------------------------------------------------------------- (b) random triads
def random_triad(rng) -> lk.Mechanism:
    p = {
        "O": 0j,
        "A": complex(*rng.uniform(-1, 1, 2)) * 3,
        "B0": complex(*rng.uniform(-10, 10, 2)),
        "C0": complex(*rng.uniform(-10, 10, 2)),
    }
    c = complex(*rng.uniform(-4, 4, 2))
    for j in MOVING:
        p[j] = c + complex(*rng.uniform(-3, 3, 2))
    return triad(p)


@pytest.mark.parametrize("seed", range(30))
def test_random_triads_against_a_grid_search(seed):
    rng = np.random.default_rng(1000 + seed)
    mech = random_triad(rng)
    r, phi0 = abs(mech.joints["A"]), math.degrees(np.angle(mech.joints["A"]))
    s = scale_of(mech)
    for at in (phi0, phi0 + float(rng.uniform(-60, 60))):
        A = r * np.exp(1j * math.radians(at))
        expected = grid_modes(platform_of(mech, A))
        found = lk.modes(mech, at=at)
        got = listed(found)
        err = same_sets(got, expected, s)
        assert err <= 1e-9 * s, f"seed {seed} at {at}: {len(got)} modes, the grid search {len(expected)} ({err:.3g})"
        for m in found.modes:  # every listed mode closes every link
            if m.assembled:
                z = {j: complex(*xy) for j, xy in m.joints.items()}
                for ln in mech.links:
                    for a_ in ln.joints:
                        for b_ in ln.joints:
                            assert abs(abs(z[a_] - z[b_]) - ln.length(a_, b_)) <= 1e-10 * s
        n_ref = sum(m.reference for m in found.modes)
        assert n_ref == 1 if at == phi0 else n_ref <= 1  # the mode the solver continues to from the pose


# ----------------------------------------------------------------------------- closed-form signs and a group
def fourbar_triad_dyad() -> lk.Mechanism:
    """A four-bar O-A-B-O2 whose rocker tip B holds a triad (with B0, C0), and a dyad J2-E-D0 after it."""
    p = {
        "O": 0j,
        "O2": 9 + 0j,
        "A": 2.5 + 1.5j,
        "B": 8.0 + 5.5j,
        "B0": 14 - 3j,
        "C0": 4 + 12j,
        "J1": 10 + 7j,
        "J2": 13.5 + 6.5j,
        "J3": 11 + 9.5j,
        "E": 17.5 + 9j,
        "D0": 19 + 3j,
    }
    links = {
        "ground": ["O", "O2", "B0", "C0", "D0"],
        "crank": ["O", "A"],
        "coupler": ["A", "B"],
        "rocker": ["O2", "B"],
        "l1": ["B", "J1"],
        "l2": ["B0", "J2"],
        "l3": ["C0", "J3"],
        "tern": ["J1", "J2", "J3"],
        "e1": ["J2", "E"],
        "e2": ["D0", "E"],
    }
    return triad(p, links)


def test_closed_form_signs_times_group_modes():
    mech = fourbar_triad_dyad()
    plan = make_plan(mech)
    assert set(plan.sign_joints) == {"B", "E"} and [plan.joint_names[j] for j in plan.numerical] == list(MOVING)
    at = 40.0
    found = lk.modes(mech, at=at)
    s = scale_of(mech)
    A = abs(mech.joints["A"]) * np.exp(1j * math.radians(at))
    total = 0
    for sb in (1, -1):
        rows = [m for m in found.modes if m.signs["B"] == sb]
        b_pos = {complex(*m.joints["B"]) for m in rows if m.assembled}
        if not b_pos:
            continue
        B = next(iter(b_pos))
        assert all(abs(complex(*m.joints["B"]) - B) <= 1e-9 * s for m in rows if m.assembled)
        # B by the law of cosines: |B - A| = coupler, |B - O2| = rocker, on the side of its sign
        assert abs(abs(B - A) - mech.link("coupler").length("A", "B")) <= 1e-10 * s
        assert abs(abs(B - mech.joints["O2"]) - mech.link("rocker").length("O2", "B")) <= 1e-10 * s
        assert np.sign((np.conj(mech.joints["O2"] - A) * (B - A)).imag) == sb  # left of A -> O2 for +1
        expected = grid_modes(platform_of(mech, B, held=("B", "B0", "C0")))
        assert {m.groups["J1,J2,J3"]["of"] for m in rows} == {len(expected)}
        e1, e2, D0 = mech.link("e1").length("J2", "E"), mech.link("e2").length("D0", "E"), mech.joints["D0"]
        for J in expected:  # each group mode, with E on both sides where its dyad closes
            with_it = [m for m in rows if m.assembled and np.max(np.abs(listed_one(m) - J)) <= 1e-9 * s]
            closes = abs(e1 - e2) < abs(J[1] - D0) < e1 + e2
            assert len(with_it) == (2 if closes else 0)
            assert {m.signs["E"] for m in with_it} == ({1, -1} if closes else set())
            for m in with_it:  # E closes its dyad on the side of its sign
                E = complex(*m.joints["E"])
                assert abs(abs(E - J[1]) - e1) <= 1e-10 * s and abs(abs(E - D0) - e2) <= 1e-10 * s
                assert np.sign((np.conj(D0 - J[1]) * (E - J[1])).imag) == m.signs["E"]
            total += len(with_it)
        assert all(any(np.max(np.abs(listed_one(m) - J)) <= 1e-9 * s for J in expected) for m in rows if m.assembled)
    assert found.distinct == total


# ----------------------------------------------------------------------------- (c) choosing a mode
def continuation(mech, start: np.ndarray, inputs_deg: np.ndarray, step: float = 0.05) -> np.ndarray:
    """J1, J2, J3 along increasing inputs from a mode at inputs_deg[0], by scipy.optimize.root in small steps."""
    z0 = mech.joints
    bars = [("A", "J1"), ("B0", "J2"), ("C0", "J3"), ("J1", "J2"), ("J2", "J3"), ("J1", "J3")]
    L = {b: mech.link(next(ln.name for ln in mech.links if set(b) <= set(ln.joints))).length(*b) for b in bars}
    r = abs(z0["A"] - z0["O"])

    def residual(x, phi):
        pts = dict(z0)
        pts["A"] = r * np.exp(1j * math.radians(phi))
        pts.update({j: complex(x[2 * i], x[2 * i + 1]) for i, j in enumerate(MOVING)})
        return [abs(pts[a] - pts[b]) - L[(a, b)] for a, b in bars]

    x = np.array([v for z in start for v in (z.real, z.imag)])
    out = [start]
    phi = inputs_deg[0]
    for t in inputs_deg[1:]:
        while phi < t - 1e-12:
            nxt = min(t, phi + step)
            sol = root(lambda y, a=nxt: residual(y, a), x, method="lm", tol=1e-14)
            assert np.max(np.abs(residual(sol.x, nxt))) < 1e-9 and np.max(np.abs(sol.x - x)) < 0.1 * scale_of(mech)
            x, phi = sol.x, nxt
        out.append(x[0::2] + 1j * x[1::2])
    return np.array(out).T


def test_choose_each_mode_by_its_pose_and_follow_it():
    mech, known, at = six_mode_triad()
    found = lk.modes(mech, at=at)
    s = scale_of(mech)
    lengths = {(ln.name, a, b): ln.length(a, b) for ln in mech.links for a in ln.joints for b in ln.joints if a < b}
    for mode in found.modes:
        chosen = mode.mechanism(mech)
        sweep = at + np.array([0.0, 0.1, 0.2, 0.3, 0.5])
        res = lk.analyze(chosen, {"crank": sweep})
        assert res.assembled.all()
        got = np.array([res.point(j) for j in MOVING])
        mine = np.array([complex(*mode.joints[j]) for j in MOVING])
        assert np.max(np.abs(got[:, 0] - mine)) <= 1e-9 * s  # the mode comes back at its input
        for (ln, a, b), length in lengths.items():  # every dimension is the file's, over the sweep
            d = np.abs(res.point(a) - res.point(b))
            assert np.max(np.abs(d - length)) <= 1e-10 * max(length, 1.0), (ln, a, b)
        ref = continuation(mech, mine, sweep)  # and the sweep follows that mode
        assert np.max(np.abs(got - ref)) <= 1e-7 * s
        again = lk.modes(chosen, at=at)  # the chosen mode is now the reference one
        ref_rows = [m for m in again.modes if m.reference]
        assert len(ref_rows) == 1
        assert np.max(np.abs(np.array([complex(*ref_rows[0].joints[j]) for j in MOVING]) - mine)) <= 1e-9 * s


def test_a_mode_that_does_not_assemble_cannot_be_chosen():
    mech = fourbar_triad_dyad()
    found = lk.modes(mech, at=40.0)
    bad = [m for m in found.modes if not m.assembled]
    assert bad
    with pytest.raises(lk.LinkageError):
        bad[0].mechanism(mech)


# ----------------------------------------------------------------------------- check: numerical joints, range
BARS = [("A", "J1"), ("B0", "J2"), ("C0", "J3"), ("J1", "J2"), ("J2", "J3"), ("J1", "J3")]


def singular_ends(mech) -> tuple[float, float]:
    """Where the pose's mode of a crank-driven triad ends, both ways (degrees): a continuation by
    scipy.optimize.root in 0.05 degree steps, then the augmented system at its last point."""
    z0 = mech.joints
    L = [abs(z0[a] - z0[b]) for a, b in BARS]
    r = abs(z0["A"])

    def pts(x, phi):
        p = dict(z0)
        p["A"] = r * np.exp(1j * phi)
        p.update({j: complex(x[2 * i], x[2 * i + 1]) for i, j in enumerate(MOVING)})
        return p

    def constraints(x, phi):
        p = pts(x, phi)
        return np.array([abs(p[a] - p[b]) ** 2 - length**2 for (a, b), length in zip(BARS, L, strict=True)])

    def jac(x, phi):  # d constraints / d joint coordinates, 6 x 6
        p = pts(x, phi)
        J = np.zeros((6, 6))
        for row, (a, b) in enumerate(BARS):
            d = p[a] - p[b]
            for j, sgn in ((a, 2), (b, -2)):
                if j in MOVING:
                    k = MOVING.index(j)
                    J[row, 2 * k], J[row, 2 * k + 1] = sgn * d.real, sgn * d.imag
        return J

    phi0 = math.atan2(z0["A"].imag, z0["A"].real)
    ends = []
    for direction in (1, -1):
        x = np.array([v for j in MOVING for v in (z0[j].real, z0[j].imag)])
        phi, h = phi0, math.radians(0.05)
        d0 = np.sign(np.linalg.det(jac(x, phi)))
        while abs(phi - phi0) < 2 * math.pi:
            sol = root(lambda y, a=phi + direction * h: constraints(y, a), x, method="hybr", tol=1e-14)
            nxt = phi + direction * h
            ok = np.max(np.abs(constraints(sol.x, nxt))) < 1e-9 and np.sign(np.linalg.det(jac(sol.x, nxt))) == d0
            if not ok or np.max(np.abs(sol.x - x)) > 0.2 * scale_of(mech):
                break
            x, phi = sol.x, nxt
        else:
            ends.append(None)
            continue

        def augmented(y):
            J = jac(y[:6], y[6])  # its determinant over the product of its rows' norms: scale free
            return np.append(
                constraints(y[:6], y[6]) / max(L) ** 2, np.linalg.det(J) / np.prod(np.linalg.norm(J, axis=1))
            )

        aug = root(augmented, np.append(x, phi), method="hybr", tol=1e-15)
        assert np.max(np.abs(augmented(aug.x))) < 1e-12 and abs(aug.x[6] - phi) < math.radians(0.05)
        ends.append(math.degrees(aug.x[6]))
    return ends[0], ends[1]


THE_TRIAD = {"O": 0j, "A": 20 + 0j, "B0": 120 - 10j, "C0": 60 + 80j, "J1": 50 + 30j, "J2": 95 + 35j, "J3": 70 + 55j}


def test_check_says_which_joints_are_numerical(capsys):
    mech = triad(THE_TRIAD)
    rep = lk.check(mech)
    assert rep.numerical_joints == MOVING and rep.closed_form_joints == ("O", "A", "B0", "C0")
    doc = rep.to_dict()
    assert doc["solvable"] == "numerical" and doc["numerical_joints"] == list(MOVING)
    text = rep.text()
    assert "solved numerically for J1, J2, J3" in text and "in closed form for O, A, B0, C0" in text
    assert "solved in closed form." not in text
    assert "by continuation from the pose" in text
    assert "group J1, J2, J3 at a singular position" in text
    four = lk.check(lk.Mechanism.from_dict(triad_free_fourbar()))
    assert four.to_dict()["solvable"] == "closed-form" and four.numerical_joints == ()
    assert "solved in closed form." in four.text()


def triad_free_fourbar() -> dict:
    return {
        "format": "linkagekit/1",
        "joints": {"O": [0, 0], "O2": [4, 0], "A": [1, 0.5], "B": [3.5, 2]},
        "links": {"ground": ["O", "O2"], "crank": ["O", "A"], "coupler": ["A", "B"], "rocker": ["O2", "B"]},
        "drivers": [{"link": "crank", "pivot": "O", "toward": "A"}],
    }


@pytest.mark.parametrize(
    "which", ["file", pytest.param("seed 3", marks=pytest.mark.long), pytest.param("seed 11", marks=pytest.mark.long)]
)
def test_assembly_range_of_a_triad_against_its_singular_positions(which):
    mech = triad(THE_TRIAD) if which == "file" else random_triad(np.random.default_rng(int(which.split()[1])))
    up, down = singular_ends(mech)
    (rng_,) = lk.check(mech).input_range
    phi0 = math.degrees(math.atan2(mech.joints["A"].imag, mech.joints["A"].real))
    if up is None:  # the mode goes on over a full turn
        assert rng_ == [0.0, 360.0]
        return
    # the reported interval in [0, 360) (or through 0), the same ends modulo a turn
    lo, hi = rng_
    assert abs(((lo - down) + 180) % 360 - 180) <= 1e-6, (lo, down)
    assert abs(((hi - up) + 180) % 360 - 180) <= 1e-6, (hi, up)
    assert lo <= hi and hi - lo < 360
    # and analyze's own sweep assembles up to just inside each end (what it does past an end, where the
    # pose's mode does not exist, is its own rule for coming back after a gap: not tested here)
    for end in (up - 1e-4, down + 1e-4):
        walk = np.linspace(phi0, end, int(abs(end - phi0) / 0.05) + 2)  # the grid check walks on
        assert lk.analyze(mech, {"crank": walk}, rates=False).assembled.all()


def test_a_triad_that_turns_fully():
    p = dict(THE_TRIAD, A=2 + 0j)  # a short crank: the triad follows it all the way round
    mech = triad(p)
    assert singular_ends(mech) == (None, None)
    assert lk.check(mech).input_range == [[0.0, 360.0]]


#: a triad whose mode runs 418.28 deg of crank from fold to fold (review 14b): posed 0.74 deg above one fold, and
#: mid-way (at -160 deg)
LONG_MODE = {
    "O": 0j,
    "A": 1.6629534486171318 + 0j,
    "B0": 3.1620132974606356 - 3.8054986843670453j,
    "C0": 2.819402328001919 + 3.0819423420610086j,
    "J1": -2.922786444704469 + 7.267493629332787j,
    "J2": -0.6092754601624639 + 6.008189477752106j,
    "J3": 0.8458934362985033 + 0.561371225707588j,
}
LONG_MODE_MID = dict(
    LONG_MODE,
    A=-1.562665084375997 - 0.5687635768399464j,
    J1=-1.6607931990804172 + 8.024015071228348j,
    J2=0.3524924820135609 + 6.325527276722066j,
    J3=0.6835195831263259 + 0.6974044416764765j,
)


@functools.cache
def long_mode_reference():  # type: ignore[no-untyped-def]
    """The arclength continuation of :data:`LONG_MODE_MID`'s mode (from the pose near a fold it does not agree with
    itself), shared by the tests."""
    from helpers import ArclengthTriad

    bars = [("A", "J1"), ("B0", "J2"), ("C0", "J3"), ("J1", "J2"), ("J2", "J3"), ("J1", "J3")]
    return ArclengthTriad(LONG_MODE_MID, bars)


def test_a_mode_longer_than_a_turn_that_does_not_close_ends_at_its_two_folds():
    """The pose's mode of this triad goes 418.28 deg of crank from fold to fold: a turn round it comes back in
    another configuration, and the directions of 58.28 deg are reached twice. ``check`` took a walk that got a
    turn round as a full turn: [0, 360], no dead point, while a sweep jumped 6 to 9.6 mm between two samples 0.01
    deg apart (review 14b). Now a walk that gets a turn round goes on unless it is back where it started: posed
    mid-way, the range is the two folds of the independent arclength continuation (1e-6 deg), both listed as dead
    points, and the text says which directions are reached twice; posed 0.74 deg above a fold (on the same mode),
    the same range."""
    ref = long_mode_reference()
    lo, hi = ref.range
    assert 418.2 < hi - lo < 418.4
    rep = lk.check(triad(LONG_MODE_MID))
    ((a, b),) = rep.input_range  # as walked from the pose's input (-160 deg): the frame its jumps are told in
    assert abs(a - lo) < 1e-6 and abs(b - hi) < 1e-6
    ends = sorted(d["input"] for d in rep.dead_points["crank"] if d["kind"] == "end of range")
    assert np.allclose(ends, [a, b], rtol=0, atol=1e-6)
    assert f"directions from {a:.6f} to {b - 360:.6f} deg are reached twice" in rep.text()
    ((c, d),) = lk.check(triad(LONG_MODE)).input_range  # the same mode posed at 0 deg: its frame a turn up
    assert abs(c - (a + 360)) < 1e-6 and abs(d - (b + 360)) < 1e-6


@pytest.mark.parametrize("pose", [pytest.param("mid", marks=pytest.mark.long), "fold"])
def test_a_sweep_of_directions_over_a_mode_longer_than_a_turn_jumps_where_check_says_and_plot_breaks_there(pose):
    """The mode of 418.28 deg: ``check`` said a sweep of directions jumps between the two configurations half a turn
    from the pose's input, and ``plot`` drew the jump as motion (review 14d). Each sample of a sweep of
    directions over two turns (4 deg apart) is matched to the independent arclength continuation at one of its two
    representatives (1e-7 of the size); where the matched representative does not move with the input the answer
    jumps. ``check`` names exactly those directions (``reached_twice``: at -160 deg posed mid-way, half a turn from
    it; posed 0.74 deg above a fold, at that fold), and the scene breaks the curves at exactly those segments."""
    from linkagekit.viz.scene import build_scene

    ref = long_mode_reference()
    points, shift = (LONG_MODE_MID, 0.0) if pose == "mid" else (LONG_MODE, 360.0)  # its frame: a turn up
    mech = triad(points)
    u = np.arange(-360.0, 360.0 + 1e-9, 4.0) + 0.1
    res = lk.analyze(mech, {"crank": u}, rates=False)
    assert res.assembled.all()
    got = np.stack([res.point(j) for j in ("J1", "J2", "J3")], axis=1)
    rep = np.full(len(u), np.nan)
    for i, x in enumerate(u):
        for r in x + 360.0 * np.arange(-1, 2):
            want = ref.at(r - shift)
            if want is not None and np.max(np.abs(got[i] - want)) < 1e-7 * ref.size:
                rep[i] = r
    assert np.all(np.isfinite(rep))
    jumps = np.flatnonzero(np.abs(np.diff(rep) - np.diff(u)) > 1.0)
    rep_check = lk.check(mech)
    twice = rep_check.reached_twice["crank"]
    expect = [j for j in twice["jumps"] for j in j + 360.0 * np.arange(-3, 4) if u[0] < j <= u[-1]]
    assert sorted(u[jumps + 1]) == pytest.approx(sorted(np.ceil((np.array(expect) - 0.1) / 4.0) * 4.0 + 0.1))
    assert list(build_scene(res, input_range=rep_check.input_range).breaks) == jumps.tolist()


def test_a_group_that_cannot_be_cut_lists_the_continued_mode_with_a_note(monkeypatch, tmp_path, capsys):
    import linkagekit.groupmodes as gm

    mech = triad(THE_TRIAD)
    monkeypatch.setattr(gm, "reduction", lambda *args: None)  # as for a group no cut makes closed-form
    found = lk.modes(mech, at=30.0)
    assert len(found.modes) == 1 and found.modes[0].reference and found.modes[0].assembled
    assert found.modes[0].groups == {"J1,J2,J3": {"index": -1, "of": -1}}
    assert found.notes and "not enumerated" in found.notes[0] and found.to_dict()["notes"] == list(found.notes)
    cont = lk.analyze(mech, {"crank": [30.0]})
    assert abs(complex(*found.modes[0].joints["J2"]) - cont.point("J2")[0]) <= 1e-12 * scale_of(mech)
    path = tmp_path / "t.yaml"
    lk.save(mech, path)
    from linkagekit.cli import main

    assert main(["modes", str(path), "--at", "30"]) == 0
    out = capsys.readouterr().out
    assert "Note: the modes of group J1, J2, J3 are not enumerated" in out


def test_simulate_refuses_a_mode_longer_than_a_turn_in_one_line(tmp_path, capsys):
    """``simulate`` tabulated the mode of 418.28 deg over a turn of directions, as if it turned fully: its table jumped
    between the two configurations of the directions reached twice, and the motion went through the jump (review
    14d). It now refuses it in one line, exit status 2, naming the driver and the mode's length."""
    from linkagekit.cli import main

    doc = triad(LONG_MODE_MID).to_dict()
    doc["links"]["crank"] = {"joints": ["O", "A"], "mass": 1.0, "cg": [0.8, 0.0], "inertia": 0.1}
    mech = lk.Mechanism.from_dict(doc)
    path = tmp_path / "long.yaml"
    lk.save(mech, path)
    assert main(["simulate", str(path), "--time", "0:1:0.1", "--torque", "1", "-o", str(tmp_path / "m.csv")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and re.search(r"crank runs 418\.28\d deg from fold to fold, longer than a turn", err[0])
    assert "does not follow such a mode" in err[0]
