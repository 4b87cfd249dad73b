"""Analysis of a mechanism over a sweep of its inputs: :func:`analyze` and its :class:`Result`.

Examples
--------
>>> import numpy as np, linkagekit as lk
>>> mech = lk.load("examples/seed000_fourbar.yaml")          # doctest: +SKIP
>>> res = lk.analyze(mech, {"crank": np.linspace(0, 360, 361)})  # doctest: +SKIP
>>> res.x("D")[:3]                                            # doctest: +SKIP
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .errors import InputError
from .model import Mechanism
from .positions import Positions, solve
from .rates import Rates, link_rates, solve_rates

ArrayLike = Any


@dataclass(frozen=True)
class Result:
    """Everything computed over one sweep.  Arrays have one entry per sample, NaN where undefined.

    Positions are in the file's length unit, velocities in length/s, accelerations in
    length/s^2, link angles in the file's angle unit, ``omega`` in rad/s, ``alpha`` in rad/s^2.
    """

    mechanism: Mechanism
    inputs: dict[str, np.ndarray]  # file units
    speeds: dict[str, np.ndarray]
    accelerations: dict[str, np.ndarray]
    positions: Positions
    rates: Rates
    link_angle: dict[str, np.ndarray]
    link_omega: dict[str, np.ndarray]
    link_alpha: dict[str, np.ndarray]
    forces: Any = None  # filled by the kinetostatics, when the file has mass properties or loads
    extra: dict[str, Any] = field(default_factory=dict)

    # ---------------------------------------------------------------- accessors
    @property
    def n(self) -> int:
        return int(self.positions.z.shape[1])

    @property
    def assembled(self) -> np.ndarray:
        return self.positions.assembled

    @property
    def singular(self) -> np.ndarray:
        return self.rates.singular

    def _j(self, name: str) -> int:
        try:
            return self.mechanism.joint_names.index(name)
        except ValueError:
            raise InputError(f"unknown joint '{name}'") from None

    def point(self, joint: str) -> np.ndarray:
        """Complex positions ``x + iy`` of a joint."""
        return self.positions.z[self._j(joint)]

    def velocity(self, joint: str) -> np.ndarray:
        return self.rates.v[self._j(joint)]

    def acceleration(self, joint: str) -> np.ndarray:
        return self.rates.a[self._j(joint)]

    def x(self, joint: str) -> np.ndarray:
        return self.point(joint).real

    def y(self, joint: str) -> np.ndarray:
        return self.point(joint).imag

    # ---------------------------------------------------------------- output
    def to_dict(self) -> dict[str, Any]:
        """The JSON result of the spec (section 3); NaN becomes ``None``."""
        m = self.mechanism
        out: dict[str, Any] = {
            "format": "linkagekit-result/1",
            "name": m.name,
            "units": {"length": m.length_unit, "angle": m.angle_unit, "time": "s", "force": "N", "torque": "N*m"},
            "inputs": {k: _list(v) for k, v in self.inputs.items()},
            "speeds": {k: _list(v) for k, v in self.speeds.items()},
            "input_accelerations": {k: _list(v) for k, v in self.accelerations.items()},
            "assembled": [bool(b) for b in self.assembled],
            "singular": [bool(b) for b in self.singular],
            "signs": dict(zip(_sign_joints(self), [int(s) for s in self.positions.signs[:, 0]], strict=True))
            if self.positions.signs.shape[1] == 1
            else None,
            "joints": {},
            "links": {},
        }
        for i, j in enumerate(m.joint_names):
            z, v, a = self.positions.z[i], self.rates.v[i], self.rates.a[i]
            out["joints"][j] = {
                "x": _list(z.real),
                "y": _list(z.imag),
                "vx": _list(v.real),
                "vy": _list(v.imag),
                "ax": _list(a.real),
                "ay": _list(a.imag),
            }
        for ln in m.links:
            out["links"][ln.name] = {
                "angle": _list(self.link_angle[ln.name]),
                "omega": _list(self.link_omega[ln.name]),
                "alpha": _list(self.link_alpha[ln.name]),
            }
        if self.forces is not None:
            out.update(self.forces.to_dict())
        return out


def _sign_joints(res: Result) -> list[str]:
    names = res.mechanism.joint_names
    out = []
    for st in res.mechanism.plan.sign_steps():
        out.append(names[st.joint])
    return out


def _list(a: np.ndarray) -> list[float | None]:
    return [None if not np.isfinite(x) else float(x) for x in np.asarray(a, float)]


def _as_array(value: ArrayLike, what: str) -> np.ndarray:
    try:
        arr = np.atleast_1d(np.asarray(value, dtype=float))
    except (TypeError, ValueError):
        raise InputError(f"{what}: expected numbers, got {value!r}") from None
    if arr.ndim != 1:
        raise InputError(f"{what}: expected a 1-D array of values")
    if not np.all(np.isfinite(arr)):
        raise InputError(f"{what}: values must be finite numbers")
    return arr


def _per_driver(mech: Mechanism, given: Mapping[str, ArrayLike] | ArrayLike | None, what: str) -> dict[str, Any]:
    names = [d.name for d in mech.drivers]
    if given is None:
        return {}
    if not isinstance(given, Mapping):
        if len(names) != 1:
            raise InputError(
                f"{what}: this mechanism has drivers {', '.join(names)}: give one value per driver by name"
            )
        return {names[0]: given}
    for k in given:
        if k not in names:
            raise InputError(f"{what}: no driver named '{k}' (drivers: {', '.join(names)})")
    return dict(given)


def analyze(
    mech: Mechanism,
    inputs: Mapping[str, ArrayLike] | ArrayLike | None = None,
    *,
    speed: Mapping[str, ArrayLike] | ArrayLike | None = None,
    acceleration: Mapping[str, ArrayLike] | ArrayLike | None = None,
    signs: ArrayLike | None = None,
    mirrors: ArrayLike | None = None,
    dynamics: bool = True,
    method: str = "natural",
    static: bool = False,
) -> Result:
    """Positions, velocities and accelerations (and forces, when the file has masses or loads).

    Parameters
    ----------
    mech : Mechanism
    inputs : mapping of driver name to array, optional
        Input values in the file's units (angle unit, or length unit for a slider
        driver).  With one driver a bare array is accepted.  Drivers left out follow
        their default sweep from the file when it has as many samples as the others,
        and otherwise stay at their reference-pose value.
    speed, acceleration : mapping of driver name to scalar or array, optional
        Input speed (rad/s, or length/s for a slider) and acceleration; default: the file's.
    signs, mirrors : array_like, optional
        Assembly mode (see :func:`linkagekit.positions.solve`); default: the pose's.
    static : bool
        Zero speed and acceleration for every driver: the forces are then the static ones
        that balance gravity and the loads (not to be combined with ``speed``/``acceleration``).
    method : {"natural", "vector-loop"}
        ``"natural"`` (default): successive triangulation in natural coordinates, any
        mechanism the plan can solve.  ``"vector-loop"``: the independent link-angle
        formulation of seeds 003/001 (:mod:`linkagekit.vectorloop`), for four-bars and
        Stephenson six-bars, in the pose's assembly mode.

    Returns
    -------
    Result
    """
    plan = mech.plan
    given = {k: _as_array(v, f"inputs[{k}]") for k, v in _per_driver(mech, inputs, "inputs").items()}
    n = max((len(v) for v in given.values()), default=0)
    for k, v in given.items():
        if len(v) not in (1, n):
            raise InputError(f"inputs: driver '{k}' has {len(v)} values but another has {n}; give equal lengths")
    from .positions import pose_inputs

    q0 = pose_inputs(mech)[:, 0]
    if n == 0:
        first = mech.drivers[0].sweep.values()
        n = len(first)
    values: dict[str, np.ndarray] = {}
    for i, d in enumerate(mech.drivers):
        if d.name in given:
            values[d.name] = np.broadcast_to(given[d.name], (n,)).astype(float)
        else:
            sw = d.sweep.values()
            if len(sw) == n:
                values[d.name] = sw
            else:
                factor = mech.angle_to_rad if d.kind == "angle" else 1.0
                values[d.name] = np.full(n, q0[i] / factor)
    q = np.array([values[d.name] * (mech.angle_to_rad if d.kind == "angle" else 1.0) for d in mech.drivers])

    if static:
        if speed is not None or acceleration is not None:
            raise InputError("static: the input speed and acceleration are zero; do not give them too")
        speed = {d.name: 0.0 for d in mech.drivers}
        acceleration = {d.name: 0.0 for d in mech.drivers}
    sp = _per_driver(mech, speed, "speed")
    ac = _per_driver(mech, acceleration, "acceleration")
    speeds = {d.name: _rate(sp.get(d.name, d.speed), n, f"speed[{d.name}]") for d in mech.drivers}
    accels = {d.name: _rate(ac.get(d.name, d.acceleration), n, f"acceleration[{d.name}]") for d in mech.drivers}

    w_in = np.array([speeds[d.name] for d in mech.drivers])
    a_in = np.array([accels[d.name] for d in mech.drivers])
    if method == "natural":
        pos = solve(plan, q, signs, mirrors)
        rates = solve_rates(plan, pos, w_in, a_in, plan.rotation_links)
    elif method == "vector-loop":
        if signs is not None or mirrors is not None:
            raise InputError("method 'vector-loop' follows the pose's assembly mode: signs/mirrors are not taken")
        pos, rates = _vector_loop(mech, q, w_in, a_in)
    else:
        raise InputError(f"method: expected 'natural' or 'vector-loop', got {method!r}")
    angle, omega, alpha = _link_motion(mech, pos, rates)
    res = Result(mech, values, speeds, accels, pos, rates, angle, omega, alpha)
    if dynamics and mech.has_dynamics:
        try:
            from .forces import solve_forces
        except ImportError:  # pragma: no cover - kinetostatics not available
            return res
        res = Result(mech, values, speeds, accels, pos, rates, angle, omega, alpha, solve_forces(res))
    return res


def _vector_loop(mech: Mechanism, q: np.ndarray, w_in: np.ndarray, a_in: np.ndarray) -> tuple[Positions, Rates]:
    """Positions and rates by :mod:`linkagekit.vectorloop`, packed like the main solver's."""
    from .positions import pose_signs
    from .vectorloop import from_mechanism

    model, offset = from_mechanism(mech)
    sol = model.solve(q[0] + offset, w_in[0], a_in[0])
    names = mech.joint_names
    z = np.array([sol.z[j] for j in names])
    v = np.array([sol.v[j] for j in names])
    a = np.array([sol.a[j] for j in names])
    margin = np.where(sol.assembled, 1.0, -1.0)[None, :]
    plan = mech.plan
    pos = Positions(
        z,
        {},
        margin,
        sol.assembled,
        q,
        np.array(pose_signs(mech, plan), float).reshape(-1, 1),
        np.zeros((plan.n_mirrors, 1), bool),
    )
    return pos, Rates(v, a, sol.omega, sol.alpha, sol.condition[None, :], sol.singular)


def _rate(value: ArrayLike, n: int, what: str) -> np.ndarray:
    arr = _as_array(value, what)
    if len(arr) not in (1, n):
        raise InputError(f"{what}: {len(arr)} values for {n} samples")
    return np.broadcast_to(arr, (n,)).astype(float)


def _link_motion(mech: Mechanism, pos: Positions, rates: Rates) -> tuple[dict[str, np.ndarray], ...]:
    """Angle (file unit), omega and alpha of every link, from its first two joints."""
    names = mech.joint_names
    n = pos.z.shape[1]
    angle, omega, alpha = {}, {}, {}
    bad = rates.singular | ~pos.assembled
    any_bad = bool(bad.any())
    for ln in mech.links:
        if ln.name == "ground":  # fixed: its angle is that of its shape, its rates zero
            js = ln.joints
            th0 = np.angle(ln.shape[js[1]] - ln.shape[js[0]]) if len(js) >= 2 else 0.0
            angle[ln.name] = np.where(pos.assembled, th0 / mech.angle_to_rad, np.nan)
            omega[ln.name] = np.where(bad, np.nan, 0.0)
            alpha[ln.name] = omega[ln.name].copy()
            continue
        if len(ln.joints) >= 2:
            i, k = names.index(ln.joints[0]), names.index(ln.joints[1])
            base = pos.z[k] - pos.z[i]
            th = np.angle(base)
            if ln.name in rates.omega:  # the step that placed the link knew its rates
                w, al = rates.omega[ln.name], rates.alpha[ln.name]
            else:
                w, al = link_rates(base, rates.v[k] - rates.v[i], rates.a[k] - rates.a[i])
        else:  # a block of one joint: it turns with the link it slides on; its angle is the slide's
            sl = next((s for s in mech.sliders if s.link == ln.name), None)
            turn = pos.rot.get(ln.name, np.ones(n, complex))
            d = sl.direction if sl is not None else 1.0 + 0j
            th = np.angle(turn * d)
            w = rates.omega.get(ln.name, np.zeros(n))
            al = rates.alpha.get(ln.name, np.zeros(n))
        if any_bad:
            th = np.where(pos.assembled, th, np.nan)
            w, al = np.where(bad, np.nan, w), np.where(bad, np.nan, al)
        angle[ln.name] = th / mech.angle_to_rad if mech.angle_to_rad != 1.0 else th
        omega[ln.name] = w
        alpha[ln.name] = al
    return angle, omega, alpha
