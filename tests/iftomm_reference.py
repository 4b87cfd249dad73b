"""Independent references for the IFToMM forward-dynamics benchmarks A01, A02 and A03.

Nothing here calls linkagekit: each case is written in its own textbook formulation, so
``tests/test_iftomm.py`` and ``benchmarks/bench_iftomm.py`` compare linkagekit's simulation
(Lagrange's equations in the driver coordinate, built from the mechanism file) against it.

Problem statements: IFToMM Technical Committee for Multibody Dynamics, benchmark library
(https://www.iftomm-multibody.org/benchmark/): A01 simple pendulum, A02 double four-bar
(N = 2 windows), A03 Andrews' squeezing mechanism; A03 as in the Test Set for IVP Solvers
(Mazzia and Magherini, University of Bari; originally CWI), problem ``andrews``
(Hairer and Wanner, Solving ODEs II, section VII.7).
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp
from scipy.special import ellipj, ellipk

G = 9.81  # m/s^2, both IFToMM statements

# --------------------------------------------------------------------------- A01
# A point mass of 1 kg on a massless bar of 1 m pinned at the origin, theta from +x,
# theta(0) = pi (the mass at (-1, 0), level with the pivot), at rest; gravity -y.


def a01_tip(t, length=1.0, g=G):
    """Exact position (x, y) of the mass at times t, by Jacobi's elliptic functions.

    With phi the angle from the downward vertical (theta = phi - pi/2), released at rest
    from phi0 = -pi/2: sin(phi/2) = k sn(K - w t, k), k = sin(|phi0|/2), w = sqrt(g/L)
    (energy: phi'^2 = 4 w^2 (k^2 - sin^2(phi/2)); at t = 0, sn(K) = 1 gives phi = phi0
    with the sign chosen so the mass first swings down towards phi = 0).
    """
    t = np.asarray(t, float)
    k = np.sin(np.pi / 4)
    w = np.sqrt(g / length)
    sn, cn, dn, _ = ellipj(ellipk(k * k) - w * t, k * k)
    s = -k * sn  # sin(phi / 2): phi0 = -pi/2 (the mass on the -x side)
    c = dn  # cos(phi / 2) = sqrt(1 - k^2 sn^2) = dn
    sin_phi, cos_phi = 2 * s * c, c * c - s * s
    return np.stack([length * sin_phi, -length * cos_phi], axis=-1)


# --------------------------------------------------------------------------- A02
# Five uniform bars of 1 m and 1 kg: cranks pinned at (0,0), (1,0), (2,0), couplers joining
# their tips. The windows stay parallelograms (the branch it starts on), so every crank has
# the same angle theta from +x and the couplers translate with the tips:
#   T = 3 * (1/2)(m L^2/3) theta'^2 + 2 * (1/2) m L^2 theta'^2 = (1/2) * 3 theta'^2  (M = 3 kg m^2)
#   V = 3 m g (L/2) sin(theta) + 2 m g L sin(theta) = 3.5 g sin(theta)
# so 3 theta'' = -3.5 g cos(theta). At t = 0 theta = pi/2 and B0 = (cos, sin) moves at
# +1 m/s along x: (-sin theta, cos theta) theta' = (1, 0) gives theta' = -1 rad/s.

A02_M, A02_V = 3.0, 3.5 * G


def a02_theta(t, rtol=1e-13, atol=1e-13):
    """Crank angle theta(t) (rad) and rate of the double four-bar, integrated by DOP853."""
    t = np.asarray(t, float)

    def rhs(_, y):
        return [y[1], -A02_V * np.cos(y[0]) / A02_M]

    sol = solve_ivp(rhs, (0.0, float(t.max())), [np.pi / 2, -1.0], "DOP853", t_eval=t, rtol=rtol, atol=atol)
    return sol.y[0], sol.y[1]


def a02_energy(theta, rate):
    """Total mechanical energy (J) of the reduced model."""
    return 0.5 * A02_M * rate**2 + A02_V * np.sin(theta)


# --------------------------------------------------------------------------- A03
# Andrews' squeezing mechanism in the test set's relative-angle formulation, verbatim in
# its symbols: q = (beta, Theta, gamma, Phi, delta, Omega, epsilon); M(q) q'' = f(q, q') - G^T lambda,
# g(q) = 0 (6 constraints).

A03 = dict(
    m=(0.04325, 0.00365, 0.02373, 0.00706, 0.07050, 0.00706, 0.05498),
    I=(2.194e-6, 4.410e-7, 5.255e-6, 5.667e-7, 1.169e-5, 5.667e-7, 1.912e-5),
    xa=-0.06934, ya=-0.00227, xb=-0.03635, yb=0.03273, xc=0.014, yc=0.072, c0=4530.0,
    d=0.028, da=0.0115, e=0.02, ea=0.01421, rr=0.007, ra=0.00092, l0=0.07785,
    ss=0.035, sa=0.01874, sb=0.01043, sc=0.018, sd=0.02, ta=0.02308, tb=0.00916,
    u=0.04, ua=0.01228, ub=0.00449, zf=0.02, zt=0.04, fa=0.01421, mom=0.033,
)  # fmt: skip

# The test set's consistent initial values (SUBROUTINE INITIAL; all rates zero).
A03_Q0 = np.array([
    -0.0617138900142764496358948458001,
    0.0,
    0.455279819163070380255912382449,
    0.222668390165885884674473185609,
    0.487364979543842550225598953530,
    -0.222668390165885884674473185609,
    1.23054744454982119249735015568,
])  # fmt: skip

# The test set's reference solution at t = 0.03 s (PSIDE, rtol = atol = 1e-14), as printed
# in its Fortran driver (andrews.f, SUBROUTINE SOLN, y(1..7)); the same values are in
# pySDC's DAE project (Parallel-in-Time/pySDC, pySDC/projects/DAE) and in R's deTestSet.
A03_Q_END = np.array([
    0.1581077119629904e2,
    -0.1575637105984298e2,
    0.4082224013073101e-1,
    -0.5347301163226948,
    0.5244099658805304,
    0.5347301163226948,
    0.1048080741042263e1,
])  # fmt: skip
A03_T_END = 0.03

# Each constraint row is a sum of terms a * trig(n . q); (row, a, trig, n) with trig "c"/"s".
# g1, g2: E from O (bodies 1, 2) equals E from B (body 3); g3, g4: ... from A via 5, 4;
# g5, g6: ... from A via 7, 6.
_E_FROM_O = [("c", "rr", (1, 0, 0, 0, 0, 0, 0), 1.0), ("c", "d", (1, 1, 0, 0, 0, 0, 0), -1.0)]
_E_FROM_O_Y = [("s", "rr", (1, 0, 0, 0, 0, 0, 0), 1.0), ("s", "d", (1, 1, 0, 0, 0, 0, 0), -1.0)]
_ROWS = [
    (_E_FROM_O + [("s", "ss", (0, 0, 1, 0, 0, 0, 0), -1.0)], "xb"),
    (_E_FROM_O_Y + [("c", "ss", (0, 0, 1, 0, 0, 0, 0), 1.0)], "yb"),
    (_E_FROM_O + [("s", "e", (0, 0, 0, 1, 1, 0, 0), -1.0), ("c", "zt", (0, 0, 0, 0, 1, 0, 0), -1.0)], "xa"),
    (_E_FROM_O_Y + [("c", "e", (0, 0, 0, 1, 1, 0, 0), 1.0), ("s", "zt", (0, 0, 0, 0, 1, 0, 0), -1.0)], "ya"),
    (_E_FROM_O + [("c", "zf", (0, 0, 0, 0, 0, 1, 1), -1.0), ("s", "u", (0, 0, 0, 0, 0, 0, 1), -1.0)], "xa"),
    (_E_FROM_O_Y + [("s", "zf", (0, 0, 0, 0, 0, 1, 1), -1.0), ("c", "u", (0, 0, 0, 0, 0, 0, 1), 1.0)], "ya"),
]


_ROW = np.array([i for i, (terms, _) in enumerate(_ROWS) for _ in terms])
_N = np.array([n for terms, _ in _ROWS for _, _, n, _ in terms], float)  # (terms, 7)
_COEF = np.array([sign * A03[name] for terms, _ in _ROWS for _, name, _, sign in terms])
_IS_COS = np.array([trig == "c" for terms, _ in _ROWS for trig, _, _, _ in terms])
_RHS = np.array([A03[c] for _, c in _ROWS])


def _trig(q):
    """Each term's a * trig(n.q) and its derivative a * trig'(n.q)."""
    phi = _N @ q
    c, s = np.cos(phi), np.sin(phi)
    return _COEF * np.where(_IS_COS, c, s), _COEF * np.where(_IS_COS, -s, c)


def _rows(values):
    """Sum term values (terms, ...) into their six rows."""
    out = np.zeros((6, *values.shape[1:]))
    np.add.at(out, _ROW, values)
    return out


def a03_g(q):
    """The six constraint residuals g(q) (m)."""
    return _rows(_trig(q)[0]) - _RHS


def a03_jac(q):
    """G = dg/dq, 6 x 7."""
    return _rows(_trig(q)[1][:, None] * _N)


def a03_gamma(q, qd):
    """The velocity-product part of g'': g'' = G q'' + gamma, gamma = -sum a trig(n.q) (n.q')^2."""
    return _rows(-_trig(q)[0] * (_N @ qd) ** 2)


def a03_mass(q):
    """The test set's 7 x 7 mass matrix M(q)."""
    p = A03
    m, inertia = p["m"], p["I"]
    rr, da, e, ea, zt, zf, fa, u = p["rr"], p["da"], p["e"], p["ea"], p["zt"], p["zf"], p["fa"], p["u"]
    cth, sph, som = np.cos(q[1]), np.sin(q[3]), np.sin(q[5])
    M = np.zeros((7, 7))
    M[0, 0] = m[0] * p["ra"] ** 2 + m[1] * (rr**2 - 2 * da * rr * cth + da**2) + inertia[0] + inertia[1]
    M[1, 0] = m[1] * (da**2 - da * rr * cth) + inertia[1]
    M[1, 1] = m[1] * da**2 + inertia[1]
    M[2, 2] = m[2] * (p["sa"] ** 2 + p["sb"] ** 2) + inertia[2]
    M[3, 3] = m[3] * (e - ea) ** 2 + inertia[3]
    M[4, 3] = m[3] * ((e - ea) ** 2 + zt * (e - ea) * sph) + inertia[3]
    M[4, 4] = (
        m[3] * (zt**2 + 2 * zt * (e - ea) * sph + (e - ea) ** 2) + m[4] * (p["ta"] ** 2 + p["tb"] ** 2)
        + inertia[3] + inertia[4]
    )  # fmt: skip
    M[5, 5] = m[5] * (zf - fa) ** 2 + inertia[5]
    M[6, 5] = m[5] * ((zf - fa) ** 2 - u * (zf - fa) * som) + inertia[5]
    M[6, 6] = (
        m[5] * ((zf - fa) ** 2 - 2 * u * (zf - fa) * som + u**2) + m[6] * (p["ua"] ** 2 + p["ub"] ** 2)
        + inertia[5] + inertia[6]
    )  # fmt: skip
    return np.tril(M) + np.tril(M, -1).T


def a03_spring_point(q):
    """D, the spring's end on body 3, and the spring's length."""
    p = A03
    cg, sg = np.cos(q[2]), np.sin(q[2])
    xd = p["sd"] * cg + p["sc"] * sg + p["xb"]
    yd = p["sd"] * sg - p["sc"] * cg + p["yb"]
    return xd, yd, np.hypot(xd - p["xc"], yd - p["yc"])


def a03_force(q, qd):
    """The test set's right-hand side f(q, q'): drive torque, spring, velocity-product terms."""
    p = A03
    m, rr, da, e, ea, zt, zf, fa, u = p["m"], p["rr"], p["da"], p["e"], p["ea"], p["zt"], p["zf"], p["fa"], p["u"]
    bep, thp, php, dep, omp, epp = qd[0], qd[1], qd[3], qd[4], qd[5], qd[6]
    xd, yd, length = a03_spring_point(q)
    force = -p["c0"] * (length - p["l0"]) / length
    fx, fy = force * (xd - p["xc"]), force * (yd - p["yc"])
    cg, sg = np.cos(q[2]), np.sin(q[2])
    sth, cph, com = np.sin(q[1]), np.cos(q[3]), np.cos(q[5])
    return np.array([
        p["mom"] - m[1] * da * rr * thp * (thp + 2 * bep) * sth,
        m[1] * da * rr * bep**2 * sth,
        fx * (p["sc"] * cg - p["sd"] * sg) + fy * (p["sd"] * cg + p["sc"] * sg),
        m[3] * zt * (e - ea) * dep**2 * cph,
        -m[3] * zt * (e - ea) * php * (php + 2 * dep) * cph,
        -m[5] * u * (zf - fa) * epp**2 * com,
        m[5] * u * (zf - fa) * omp * (omp + 2 * epp) * com,
    ])  # fmt: skip


def a03_accel(q, qd):
    """q'' of the index-1 form [M G^T; G 0] [q''; lambda] = [f; -gamma]."""
    G_ = a03_jac(q)
    A = np.zeros((13, 13))
    A[:7, :7] = a03_mass(q)
    A[:7, 7:] = G_.T
    A[7:, :7] = G_
    b = np.concatenate([a03_force(q, qd), -a03_gamma(q, qd)])
    return np.linalg.solve(A, b)[:7]


def a03_integrate(t_end=A03_T_END, rtol=1e-12, atol=1e-12):
    """q(t_end) of the index-1 DAE from the test set's initial values (DOP853), and the solution object."""

    def rhs(_, y):
        return np.concatenate([y[7:], a03_accel(y[:7], y[7:])])

    y0 = np.concatenate([A03_Q0, np.zeros(7)])
    sol = solve_ivp(rhs, (0.0, t_end), y0, "DOP853", rtol=rtol, atol=atol, dense_output=True)
    return sol.y[:7, -1], sol


def a03_energy(q, qd):
    """Kinetic energy + spring energy - work of the drive torque on beta (J): constant along the motion."""
    p = A03
    _, _, length = a03_spring_point(q)
    return 0.5 * qd @ a03_mass(q) @ qd + 0.5 * p["c0"] * (length - p["l0"]) ** 2 - p["mom"] * q[0]


# ------------------------------------------------------------ A03 as a linkage (the file's pose)
# Points of the bodies in the test set's symbols (derived from g and from the kinetic energy
# behind M; the derivation is in tests/test_iftomm.py's module docstring):
#   O = (0, 0), P = O + rr e(beta)                    body 1 (crank), G1 at ra from O
#   E = P - d e(beta + Theta)                         body 2 (rod P-E), G2 at da from P toward E
#   E = B + ss (sin gamma, -cos gamma)                body 3 (B, E, D), G3 at sqrt(sa^2 + sb^2) from B
#   D = B + sd e(gamma) + sc (sin gamma, -cos gamma)  (spring to C)
#   F = A + zt e(delta); E = F + e (sin(Phi+delta), -cos(Phi+delta))   bodies 5 (A-F), 4 (F-E)
#   H = A + u (sin eps, -cos eps); E = H + zf e(Omega+eps)            bodies 7 (A-H), 6 (H-E)
#   G4 at e - ea from F toward E; G6 at zf - fa from H toward E
# with e(a) = (cos a, sin a).


def _e(a):
    return np.array([np.cos(a), np.sin(a)])


def _perp(a):
    """(sin a, -cos a): e(a) turned by -90 degrees."""
    return np.array([np.sin(a), -np.cos(a)])


def a03_points(q):
    """Every named point of the mechanism at q (metres), from the test set's relative angles."""
    p = A03
    be, th, ga, ph, de, om, ep = q
    A, B, C = np.array([p["xa"], p["ya"]]), np.array([p["xb"], p["yb"]]), np.array([p["xc"], p["yc"]])
    P = p["rr"] * _e(be)
    E = P - p["d"] * _e(be + th)
    F = A + p["zt"] * _e(de)
    H = A + p["u"] * _perp(ep)
    D = B + p["sd"] * _e(ga) + p["sc"] * _perp(ga)
    return dict(
        O=np.zeros(2), A=A, B=B, C=C, P=P, E=E, F=F, H=H, D=D,
        E_via_B=B + p["ss"] * _perp(ga),
        E_via_F=F + p["e"] * _perp(ph + de),
        E_via_H=H + p["zf"] * _e(om + ep),
        G1=p["ra"] * _e(be),
        G2=P - p["da"] * _e(be + th),
        G4=F + (p["e"] - p["ea"]) * _perp(ph + de),
        G6=H + (p["zf"] - p["fa"]) * _e(om + ep),
    )  # fmt: skip


def a03_angles(pts):
    """The seven relative angles from points (arrays of shape (..., 2)), each in (-pi, pi]."""

    def ang(v):
        return np.arctan2(v[..., 1], v[..., 0])

    be = ang(pts["P"] - pts["O"])
    be_th = ang(pts["P"] - pts["E"])
    ga = ang(pts["E"] - pts["B"]) + np.pi / 2
    ph_de = ang(pts["E"] - pts["F"]) + np.pi / 2
    de = ang(pts["F"] - pts["A"])
    om_ep = ang(pts["E"] - pts["H"])
    ep = ang(pts["H"] - pts["A"]) + np.pi / 2
    wrap = lambda a: np.angle(np.exp(1j * a))  # noqa: E731
    return np.stack([wrap(be), wrap(be_th - be), wrap(ga), wrap(ph_de - de), wrap(de), wrap(om_ep - ep), wrap(ep)], -1)
