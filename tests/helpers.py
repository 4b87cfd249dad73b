"""Independent reference computations for the tests (law of cosines and rotations).

Nothing here calls linkagekit's solver: these are the "other formulation" that the
library's natural-coordinate triangulation is checked against.
"""

from __future__ import annotations

from typing import Any

import numpy as np


def random_points(rng, names):
    """Points named by the letters of `names`, uniform in [-10, 10]^2, as complex numbers."""
    return {n: complex(*rng.uniform(-10, 10, 2)) for n in names}


def xy(points):
    """Complex points as the ``joints:`` mapping of a mechanism file."""
    return {k: [v.real, v.imag] for k, v in points.items()}


def by_cosines(k1, k2, r1, r2, t):
    """Joint at distance r1 from k1 and r2 from k2, on side t (+1 left of k1->k2), by the law of cosines.

    Returns NaN where the triangle does not close.
    """
    k1, k2 = np.asarray(k1, complex), np.asarray(k2, complex)
    s = np.abs(k2 - k1)
    with np.errstate(invalid="ignore", divide="ignore"):
        c = (r1**2 + s**2 - r2**2) / (2 * r1 * s)
        gamma = np.arccos(np.clip(c, -1, 1))
        z = k1 + r1 * np.exp(1j * (np.angle(k2 - k1) + t * gamma))
    return np.where(np.abs(c) <= 1 + 1e-12, z, np.nan)


def rigid(k1, k2, p_ref, k1_ref, k2_ref):
    """Point of a rigid body through k1, k2, at the same distance and angle as in the reference."""
    d = abs(p_ref - k1_ref)
    delta = np.angle((p_ref - k1_ref) / (k2_ref - k1_ref))
    return k1 + d * np.exp(1j * (np.angle(k2 - k1) + delta))


def side(k1, k2, j):
    """+1 if j is left of the directed line k1->k2, -1 if right."""
    return 1.0 if ((np.conj(k2 - k1) * (j - k1)).imag >= 0) else -1.0


def fourbar_dict(A, B, C, D, P, unit="m"):
    pts = dict(A=A, B=B, C=C, D=D, P=P)
    return {
        "format": "linkagekit/1",
        "units": {"length": unit, "angle": "deg"},
        "joints": xy(pts),
        "links": {"ground": ["A", "B"], "crank": ["A", "C"], "coupler": ["C", "D", "P"], "rocker": ["B", "D"]},
        "drivers": [{"link": "crank", "pivot": "A", "toward": "C"}],
    }


def fourbar_reference(pose, phi):
    """Independent four-bar solve (angles phi in rad) in the pose's mode."""
    A, B, C0, D0, P0 = (pose[k] for k in "ABCDP")
    a, b, c = abs(C0 - A), abs(D0 - C0), abs(D0 - B)
    C = A + a * np.exp(1j * phi)
    D = by_cosines(C, B, b, c, side(C0, B, D0))
    P = rigid(C, D, P0, C0, D0)
    return {"A": A + 0 * phi, "B": B + 0 * phi, "C": C, "D": D, "P": P}


def watt2_dict(p):
    return {
        "joints": xy(p),
        "links": {
            "ground": ["A", "B", "E"],
            "crank": ["A", "C"],
            "coupler": ["C", "D"],
            "rocker": ["B", "D", "F"],
            "coupler2": ["F", "G", "P"],
            "output": ["E", "G"],
        },
        "drivers": [{"link": "crank", "pivot": "A", "toward": "C"}],
    }


def watt2_reference(p, phi):
    A, B, E = p["A"], p["B"], p["E"]
    C = A + abs(p["C"] - A) * np.exp(1j * phi)
    D = by_cosines(C, B, abs(p["D"] - p["C"]), abs(p["D"] - B), side(p["C"], B, p["D"]))
    F = rigid(B, D, p["F"], B, p["D"])
    G = by_cosines(F, E, abs(p["G"] - p["F"]), abs(p["G"] - E), side(p["F"], E, p["G"]))
    P = rigid(F, G, p["P"], p["F"], p["G"])
    return {"A": A + 0 * phi, "B": B + 0 * phi, "E": E + 0 * phi, "C": C, "D": D, "F": F, "G": G, "P": P}


def stephenson_dict(p):
    return {
        "joints": xy(p),
        "links": {
            "ground": ["A", "B"],
            "input": ["A", "C", "D"],
            "link_ce": ["C", "E"],
            "ternary": ["B", "E", "F"],
            "coupler": ["D", "G", "P"],
            "link_fg": ["F", "G"],
        },
        "drivers": [{"link": "input", "pivot": "A", "toward": "C"}],
    }


def stephenson_reference(p, phi):
    A, B = p["A"], p["B"]
    C = A + abs(p["C"] - A) * np.exp(1j * phi)
    D = rigid(A, C, p["D"], A, p["C"])
    E = by_cosines(C, B, abs(p["E"] - p["C"]), abs(p["E"] - B), side(p["C"], B, p["E"]))
    F = rigid(B, E, p["F"], B, p["E"])
    G = by_cosines(D, F, abs(p["G"] - p["D"]), abs(p["G"] - p["F"]), side(p["D"], p["F"], p["G"]))
    P = rigid(D, G, p["P"], p["D"], p["G"])
    return {"A": A + 0 * phi, "B": B + 0 * phi, "C": C, "D": D, "E": E, "F": F, "G": G, "P": P}


def points(res):
    """Every joint's complex positions, stacked (n_joints, *res.shape), from the public Result."""
    return np.array([res.point(j) for j in res.mechanism.joint_names])


def velocities(res):
    return np.array([res.velocity(j) for j in res.mechanism.joint_names])


def accelerations(res):
    return np.array([res.acceleration(j) for j in res.mechanism.joint_names])


def pose_inputs(mech):
    """Driver values at the reference pose (radians or length), (n_drivers, 1), read off the pose here."""
    vals = []
    for d in mech.drivers:
        if d.kind == "angle":
            vals.append(np.angle(mech.joints[d.toward] - mech.joints[d.pivot]))
        else:
            vals.append(0.0)
    return np.array(vals, float).reshape(-1, 1)


def luminance(rgb):
    """Luminance (0-255) of an RGB image (..., 3)."""
    return rgb @ np.array([0.299, 0.587, 0.114])


def dark_ring_rays(lum, c, r, rays=16):
    """Rays from pixel (column c, row r) that meet a dark pixel (luminance < 110) between radius 2.5 and 6 px.

    A pin (a white circle with a black edge) drawn at (c, r) gives a dark pixel on every ray.
    """
    h, w = lum.shape
    a = 2 * np.pi * np.arange(rays) / rays
    rad = np.arange(2.5, 6.01, 0.5)
    cols = np.floor(c + rad[None, :] * np.cos(a)[:, None]).astype(int)
    rows = np.floor(r + rad[None, :] * np.sin(a)[:, None]).astype(int)
    inside = (cols >= 0) & (cols < w) & (rows >= 0) & (rows < h)
    vals = np.where(inside, lum[np.clip(rows, 0, h - 1), np.clip(cols, 0, w - 1)], np.inf)
    return int((vals.min(axis=1) < 110).sum())


def leading_comments(text: str) -> list[str]:
    """The comment lines at the top of a file (before its first other non-blank line)."""
    out = []
    for line in text.splitlines():
        if line.startswith("#"):
            out.append(line)
        elif line.strip():
            break
    return out


#: a class-3 triad on a crank: ternary J1 J2 J3 held by three binary links (to A on the crank, B0, C0)
TRIAD_LINKS = {
    "ground": ["O", "B0", "C0"],
    "crank": ["O", "A"],
    "l1": ["A", "J1"],
    "l2": ["B0", "J2"],
    "l3": ["C0", "J3"],
    "tern": ["J1", "J2", "J3"],
}


# ---------------------------------------------------------------------- synthesis: independent measures
def curve_distance(mech: Any, targets: np.ndarray, step: float = 0.01) -> np.ndarray:
    """Distance from each target (m, 2) to the polyline of P over a full crank turn sampled every ``step`` degrees."""
    import linkagekit as lk

    P = lk.analyze(mech, {"crank": np.arange(0.0, 360.0 + step / 2, step)}).xy("P")
    assert np.all(np.isfinite(P)), "the crank does not turn fully"
    a, ab = P[:-1], P[1:] - P[:-1]
    out = []
    for t in np.asarray(targets, float):
        s = np.clip(np.sum((t - a) * ab, axis=1) / np.maximum(np.sum(ab * ab, axis=1), 1e-300), 0.0, 1.0)
        out.append(np.min(np.hypot(*(a + s[:, None] * ab - t).T)))
    return np.array(out)


def diagonal(xy: np.ndarray) -> float:
    return float(np.hypot(*np.ptp(np.asarray(xy, float), axis=0)))


def assert_buildable(mech: Any, min_transmission: float = 20.0) -> None:
    """The crank turns fully and every four-bar loop's transmission angle stays in [MIN, 180 - MIN] (lk.check)."""
    import linkagekit as lk

    rep = lk.check(mech)
    assert rep.input_ranges["crank"] == [[0.0, 360.0]], rep.input_ranges
    assert rep.fourbars, "no four-bar loop found by lk.check"
    for loop in rep.fourbars:
        ta = loop["transmission_angle"]
        assert min_transmission - 1e-6 <= ta["min"] and ta["max"] <= 180 - min_transmission + 1e-6, ta


class ArclengthTriad:
    """A crank-driven linkage's branch through its pose by pseudo-arclength continuation (unknowns the joints
    ``unknown`` and the crank angle u, equations the squared lengths of ``bars``), its own Newton and tangents: a
    fold, where u turns back, ends the branch; a sharp turn where the Jacobian nearly vanishes but u goes on is
    followed through. By default a class-3 triad (unknowns J1, J2, J3).

    ``points``: the pose (complex), joints O (crank pivot), A (crank tip), the ground joints and the unknowns;
    ``bars`` the bars ``(a, b)`` other than the crank, as many as twice the unknowns. ``range``: the fold inputs
    below and above the pose's (degrees, continuous from it, each to 1e-9 deg; the same with arc steps of at most
    2e-2 and 2e-3 of the size, or an assertion fails: where two branches nearly cross, a long step can jump between
    them); :meth:`at`: the unknowns at an input between them."""

    def __init__(
        self, points: dict[str, complex], bars: list[tuple[str, str]], unknown: tuple[str, ...] = ("J1", "J2", "J3")
    ) -> None:
        self.UNKNOWN = unknown
        self.n = 2 * len(unknown)
        self.p = dict(points)
        self.bars = bars
        self.length2 = np.array([abs(points[a] - points[b]) ** 2 for a, b in bars])
        self.r = abs(points["A"] - points["O"])
        u0 = float(np.angle(points["A"] - points["O"]))
        x0 = np.array([c for j in self.UNKNOWN for c in (points[j].real, points[j].imag)] + [u0])
        self.size = float(np.mean(np.sqrt(self.length2)))
        coarse = [self._leg(x0, sign, 2e-2) for sign in (-1, 1)]
        self.legs = [self._leg(x0, sign, 2e-3) for sign in (-1, 1)]
        self.range = tuple(float(np.degrees(leg[-1][self.n])) for leg in self.legs)
        other = tuple(float(np.degrees(leg[-1][self.n])) for leg in coarse)
        # where two branches nearly cross, too long an arc step can jump between them: both steps must agree
        assert np.allclose(self.range, other, rtol=0, atol=1e-7), (
            "the reference depends on its step",
            self.range,
            other,
        )

    def _joints(self, x: np.ndarray) -> dict[str, complex]:
        J = {j: complex(x[2 * k], x[2 * k + 1]) for k, j in enumerate(self.UNKNOWN)}
        J["A"] = self.p["O"] + self.r * complex(np.cos(x[self.n]), np.sin(x[self.n]))
        return {**self.p, **J}

    def _F(self, x: np.ndarray) -> np.ndarray:
        J = self._joints(x)
        return np.array([abs(J[a] - J[b]) ** 2 for a, b in self.bars]) - self.length2

    def _jac(self, x: np.ndarray) -> np.ndarray:
        J = self._joints(x)
        out = np.zeros((len(self.bars), self.n + 1))
        dA = 1j * (J["A"] - self.p["O"])
        for row, (a, b) in enumerate(self.bars):
            d = J[a] - J[b]
            for name, f in ((a, 2.0), (b, -2.0)):
                if name in self.UNKNOWN:
                    k = self.UNKNOWN.index(name)
                    out[row, 2 * k : 2 * k + 2] += f * np.array([d.real, d.imag])
                elif name == "A":
                    out[row, self.n] += f * (d.real * dA.real + d.imag * dA.imag)
        return out

    def _tangent(self, x: np.ndarray, prev: np.ndarray) -> np.ndarray:
        t = np.linalg.svd(self._jac(x))[2][-1]
        return t if t @ prev > 0 else -t

    def _corrector(self, x: np.ndarray, t: np.ndarray, ds: float) -> np.ndarray | None:
        y = x + ds * t
        for _ in range(12):
            g = np.concatenate([self._F(y), [t @ (y - x) - ds]])
            step = np.linalg.solve(np.vstack([self._jac(y), t]), -g)
            y = y + step
            if np.max(np.abs(step)) < 1e-12 * self.size:
                return y
        return None

    def _leg(self, x: np.ndarray, sign: int, longest: float) -> list[np.ndarray]:
        """States from the pose with u going ``sign``-wards until u turns back (then the fold, refined)."""
        t = self._tangent(x, np.eye(self.n + 1)[self.n] * sign)
        ds, states = 1e-3 * self.size, [x]
        while abs(x[self.n] - states[0][self.n]) < 2 * np.pi:
            y = self._corrector(x, t, ds)
            tn = None if y is None else self._tangent(y, t)
            if tn is None or tn @ t < 0.995:  # not converged or too sharp a turn: a smaller step
                ds /= 2
                assert ds > 1e-12 * self.size, "the continuation stalled"
                continue
            if np.sign(tn[self.n]) != np.sign(t[self.n]):  # u turned: a fold between x and y
                states.append(self._fold(x, t, y))
                return states
            x, t = y, tn
            states.append(x)
            ds = min(ds * 1.5, longest * self.size)
        return states

    def _fold(self, x: np.ndarray, t: np.ndarray, y: np.ndarray) -> np.ndarray:
        """The fold between ``x`` and ``y``: where the tangent's u component vanishes, by bisection on the arc."""
        lo, hi = 0.0, float(t @ (y - x))
        best = y
        while hi - lo > 1e-13 * self.size:
            mid = (lo + hi) / 2
            z = self._corrector(x, t, mid)
            assert z is not None
            if np.sign(self._tangent(z, t)[self.n]) == np.sign(t[self.n]):
                lo = mid
            else:
                hi, best = mid, z
        return best

    def at(self, u_deg: float) -> np.ndarray | None:
        """The unknowns (complex) at input ``u_deg`` on the branch (None outside its range): on the arc between the
        two states about it, by bisection of the arclength from the first."""
        u = np.radians(u_deg)
        leg = self.legs[0] if u < self.legs[0][0][self.n] else self.legs[1]
        us = np.array([s[self.n] for s in leg])  # monotone along a leg
        if not min(us) <= u <= max(us):
            return None
        k = min(int(np.searchsorted(us if us[-1] > us[0] else -us, u if us[-1] > us[0] else -u)), len(leg) - 1)
        x, y = leg[max(k - 1, 0)], leg[k]
        t = self._tangent(x, y - x)
        lo, hi = 0.0, float(t @ (y - x))
        z = x
        for _ in range(200):
            mid = (lo + hi) / 2
            z = self._corrector(x, t, mid)
            assert z is not None
            if abs(z[self.n] - u) < 1e-15 or hi - lo < 1e-15 * self.size:
                break
            lo, hi = (mid, hi) if (z[self.n] - u) * (y[self.n] - x[self.n]) < 0 else (lo, mid)
        y = z.copy()
        y[self.n] = u
        for _ in range(5):  # the last rounding of u: Newton at fixed u from there
            y[: self.n] += np.linalg.solve(self._jac(y)[:, : self.n], -self._F(y))
        return np.array([complex(y[2 * k], y[2 * k + 1]) for k in range(len(self.UNKNOWN))])


def interruptible() -> None:
    """``preexec_fn`` for a child the test will interrupt: SIGINT back to its default.

    A shell without job control starts a background job (``pytest &``) with SIGINT ignored, and a
    child inherits that, so Python installs no KeyboardInterrupt handler and the signal the test
    sends, as a terminal's Ctrl-C would, does nothing.
    """
    import signal

    signal.signal(signal.SIGINT, signal.SIG_DFL)
