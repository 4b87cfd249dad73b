"""The result of an analysis: user-level arrays, one design or a batch, read-only.

Every array has the shape ``(*batch, n_samples)`` (points ``(*batch, n_samples, 2)`` as
floats, or complex with :meth:`Result.point`), where ``batch`` is ``()`` for one mechanism
and ``(n_designs,)`` for ``analyze(..., poses=...)``.  NaN marks a sample that does not
assemble (positions and rates) or sits at a singular position (rates and forces; with
``branch="continuous"`` a sample on a change point has the branch's limit for its rates, and
stays ``singular``).

Units: positions in the file's length unit, velocities per second, accelerations per
second squared, link angles in the file's angle unit, ``omega`` in rad/s, ``alpha`` in
rad/s^2, forces in N, torques in N*m, power in W.

Examples
--------
>>> import numpy as np, linkagekit as lk
>>> res = lk.analyze(lk.load("examples/seed000_fourbar.yaml"), np.arange(0.0, 360.0, 90.0))
>>> res
<Result 'Romero-Nunez 2016 four-bar (t1 = +1, t2 = -1)': 4 samples, 4 assembled, 0 singular; joints A, B, C, D, P>
>>> res.xy("C").round(12).tolist()
[[2.0, 0.0], [0.0, 2.0], [-2.0, 0.0], [-0.0, -2.0]]
>>> list(res.columns())[:5]
['input:crank', 'assembled', 'singular', 'A.x', 'A.y']
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property
from types import MappingProxyType
from typing import TYPE_CHECKING, Any

import numpy as np

from .catalogue import Catalogue, build
from .errors import InputError, UnknownNameError, shorten
from .forces import Forces, json_list

if TYPE_CHECKING:
    from .model import Mechanism


def frozen(a: Any) -> np.ndarray:
    """A read-only view of an array (the result owns its data; nobody writes through it)."""
    arr = np.asarray(a)
    view = arr.view()
    view.flags.writeable = False
    return view


@dataclass(frozen=True, repr=False, eq=False)
class Result:
    """Everything computed over one sweep, for one design or a batch of designs.

    Build it with :func:`linkagekit.analyze`; never by hand.

    Attributes
    ----------
    mechanism : Mechanism
        The analysed mechanism (for a batch: the topology, masses and loads; each design's
        own dimensions are ``mechanism_of(i)``).
    inputs, speeds, accelerations : mapping of driver name to ndarray
        Input values (file units), speeds and accelerations, broadcastable to ``shape``.
    assembled, singular : ndarray of bool, shape ``shape``
    condition : ndarray, shape ``shape``
        The smallest dimensionless determinant of the sign steps (1 well conditioned, 0
        singular); NaN where it does not assemble or without rates.
    signs : mapping of joint name to int or ndarray
        The assembly mode used (one entry per joint found by a sign step; per design for a batch;
        per sample too when given so, or with ``analyze(..., branch="continuous")``).
    forces : Forces or None
        Joint reactions and driver efforts, when the mechanism has masses, gravity or loads.
    poses : ndarray or None
        ``(n_designs, n_joints, 2)`` for a batch.
    time : ndarray or None
        The time of each sample (s) of a simulation (:func:`linkagekit.simulate`), else None.
    stopped : str or None
        A simulation that met a toggle it cannot pass: the one-line message (its rows end there).
    """

    mechanism: Mechanism
    inputs: Mapping[str, np.ndarray]
    speeds: Mapping[str, np.ndarray]
    accelerations: Mapping[str, np.ndarray]
    assembled: np.ndarray
    singular: np.ndarray
    condition: np.ndarray
    signs: Mapping[str, Any]
    forces: Forces | None
    poses: np.ndarray | None
    _z: np.ndarray = field(repr=False)
    _v: np.ndarray | None = field(repr=False)
    _a: np.ndarray | None = field(repr=False)
    _omega: Mapping[str, np.ndarray] | None = field(repr=False)
    _alpha: Mapping[str, np.ndarray] | None = field(repr=False)
    _block_rot: Mapping[str, np.ndarray] = field(repr=False)
    _ground_angle: Any = field(repr=False)
    time: np.ndarray | None = None
    stopped: str | None = None

    # ---------------------------------------------------------------- shape
    @property
    def shape(self) -> tuple[int, ...]:
        """``(*batch, n_samples)``."""
        return tuple(self.assembled.shape)

    @property
    def n_samples(self) -> int:
        """Number of samples of the sweep (the last axis of every array)."""
        return int(self.assembled.shape[-1])

    @property
    def n(self) -> int:
        """Number of samples (same as :attr:`n_samples`)."""
        return self.n_samples

    @property
    def n_designs(self) -> int | None:
        """Number of designs of a batch, None for one mechanism."""
        return None if self.poses is None else int(self.poses.shape[0])

    @property
    def has_rates(self) -> bool:
        """Whether velocities, accelerations and link rates were computed (``analyze(..., rates=True)``)."""
        return self._v is not None

    # ---------------------------------------------------------------- points
    def _j(self, name: str) -> int:
        names = self.mechanism.joint_names
        if not isinstance(name, str) or name not in names:
            raise UnknownNameError(f"unknown joint {shorten(repr(name))} (joints: {', '.join(names)})")
        return names.index(name)

    def _rates(self, which: str) -> np.ndarray:
        arr = self._v if which == "v" else self._a
        if arr is None:
            raise InputError("this result has positions only: analyze(..., rates=True) for velocities")
        return arr

    def point(self, joint: str) -> np.ndarray:
        """Complex positions ``x + iy`` of a joint, shape ``shape``."""
        out: np.ndarray = self._z[self._j(joint)]
        return out

    def velocity(self, joint: str) -> np.ndarray:
        """Complex velocity ``vx + i vy`` of a joint (length unit / s)."""
        out: np.ndarray = self._rates("v")[self._j(joint)]
        return out

    def acceleration(self, joint: str) -> np.ndarray:
        """Complex acceleration ``ax + i ay`` of a joint (length unit / s^2)."""
        out: np.ndarray = self._rates("a")[self._j(joint)]
        return out

    @staticmethod
    def _as_xy(z: np.ndarray) -> np.ndarray:
        return frozen(np.ascontiguousarray(z).view(float).reshape(*z.shape, 2))

    def xy(self, joint: str) -> np.ndarray:
        """Float positions ``(*shape, 2)``: x and y of a joint."""
        return self._as_xy(self.point(joint))

    def vxy(self, joint: str) -> np.ndarray:
        """Float velocities ``(*shape, 2)``: vx and vy of a joint."""
        return self._as_xy(self.velocity(joint))

    def axy(self, joint: str) -> np.ndarray:
        """Float accelerations ``(*shape, 2)``: ax and ay of a joint."""
        return self._as_xy(self.acceleration(joint))

    def x(self, joint: str) -> np.ndarray:
        """x coordinates of a joint (length unit), shape ``shape``."""
        out: np.ndarray = self.point(joint).real
        return out

    def y(self, joint: str) -> np.ndarray:
        """y coordinates of a joint (length unit), shape ``shape``."""
        out: np.ndarray = self.point(joint).imag
        return out

    # ---------------------------------------------------------------- links
    def _link(self, name: str) -> Any:
        for ln in self.mechanism.links:
            if isinstance(name, str) and ln.name == name:
                return ln
        links = ", ".join(ln.name for ln in self.mechanism.links)
        raise UnknownNameError(f"unknown link {shorten(repr(name))} (links: {links})")

    @cached_property
    def link_angle(self) -> Mapping[str, np.ndarray]:
        """Angle of every link (file's angle unit): the direction of its first joint -> its second.

        The ground's is that of its shape; a one-joint block's is its slide direction, turned
        with its guide.  NaN where the mechanism does not assemble.
        """
        mech = self.mechanism
        unit = mech.angle_to_rad
        out = {}
        for ln in mech.links:
            if ln.name == "ground":
                th = np.where(self.assembled, self._ground_angle, np.nan)
            elif len(ln.joints) >= 2:
                th = np.angle(self.point(ln.joints[1]) - self.point(ln.joints[0]))
            else:
                sl = next((s for s in mech.sliders if s.link == ln.name), None)
                d = sl.direction if sl is not None else 1.0 + 0j
                th = np.angle(self._block_rot[ln.name] * d)
                th = np.where(self.assembled, th, np.nan)
            out[ln.name] = frozen(th / unit if unit != 1.0 else th)
        return MappingProxyType(out)

    @property
    def link_omega(self) -> Mapping[str, np.ndarray]:
        """Angular velocity of every link (rad/s), NaN where undefined."""
        if self._omega is None:
            raise InputError("this result has positions only: analyze(..., rates=True) for link rates")
        return self._omega

    @property
    def link_alpha(self) -> Mapping[str, np.ndarray]:
        """Angular acceleration of every link (rad/s^2), NaN where undefined."""
        if self._alpha is None:
            raise InputError("this result has positions only: analyze(..., rates=True) for link rates")
        return self._alpha

    def angle(self, link: str) -> np.ndarray:
        """Angle of a link in the file's angle unit (see :attr:`link_angle`)."""
        return self.link_angle[self._link(link).name]

    def omega(self, link: str) -> np.ndarray:
        """Angular velocity of a link (rad/s)."""
        return self.link_omega[self._link(link).name]

    def alpha(self, link: str) -> np.ndarray:
        """Angular acceleration of a link (rad/s^2)."""
        return self.link_alpha[self._link(link).name]

    # ---------------------------------------------------------------- designs
    def design(self, i: int) -> Result:
        """One design of a batch, as the result of analysing it on its own (no design axis)."""
        i = self._design_index(i)

        def one(a: Any) -> Any:
            a = np.asarray(a)
            return frozen(a[i]) if a.ndim >= 2 else a

        def per(m: Mapping[str, Any] | None) -> Mapping[str, Any] | None:
            return None if m is None else MappingProxyType({k: one(v) for k, v in m.items()})

        return Result(
            self.mechanism_of(i),
            per(self.inputs),  # type: ignore[arg-type]
            per(self.speeds),  # type: ignore[arg-type]
            per(self.accelerations),  # type: ignore[arg-type]
            one(self.assembled),
            one(self.singular),
            one(self.condition),
            MappingProxyType({k: _one_sign(v, i) for k, v in self.signs.items()}),
            None if self.forces is None else self.forces.take(i),
            None,
            frozen(self._z[:, i]),
            None if self._v is None else frozen(self._v[:, i]),
            None if self._a is None else frozen(self._a[:, i]),
            per(self._omega),
            per(self._alpha),
            per(self._block_rot),  # type: ignore[arg-type]
            np.asarray(self._ground_angle)[i] if np.ndim(self._ground_angle) else self._ground_angle,
        )

    def mechanism_of(self, i: int) -> Mechanism:
        """Design ``i`` of a batch as a :class:`Mechanism` (its pose, no given lengths), e.g. to save it."""
        if self.poses is None:
            if isinstance(i, bool) or not isinstance(i, int | np.integer) or i not in (0, -1):
                raise InputError(f"mechanism_of: this result has one design (0), got {shorten(repr(i))}")
            return self.mechanism
        return self.mechanism.with_pose(self.poses[self._design_index(i)])

    def _design_index(self, i: Any) -> int:
        if self.poses is None:
            raise InputError("design(): this result has no design axis (analyze(..., poses=...) makes one)")
        n = int(self.poses.shape[0])
        if isinstance(i, bool) or not isinstance(i, int | np.integer):
            raise InputError(f"design: expected a whole number from 0 to {n - 1}, got {shorten(repr(i))}")
        if not -n <= i < n:
            raise UnknownNameError(f"design {i}: the batch has {n} designs (0 to {n - 1})")
        return int(i) % n

    # ---------------------------------------------------------------- tables
    @cached_property
    def catalogue(self) -> Catalogue:
        """Every quantity of this analysis, declared once (:mod:`linkagekit.catalogue`): name, owner, unit, group."""
        return build(
            self.mechanism,
            rates=self.has_rates,
            reactions=None if self.forces is None else self.forces.layout(),
            time=self.time is not None,
        )

    def columns(self) -> dict[str, np.ndarray]:
        """Every quantity as a named column, each of shape ``shape``, in a fixed order.

        ``input:<driver>``, ``assembled``, ``singular``, per joint ``<j>.x``, ``.y`` (and
        ``.vx``, ``.vy``, ``.ax``, ``.ay`` with rates), per link ``<l>.angle`` (and ``.omega``,
        ``.alpha``), then the force columns (reactions ``F[J:by>on].fx``, ``.fy``, ``.moment``
        of a slider, ``|F|[J:by>on]``, ``T[driver]``, ``F[driver]``, ``input_power``,
        ``shaking.fx``, ``.fy``, ``.moment``): the table quantities of :attr:`catalogue`.
        CSV, tables, JSON and :meth:`to_pandas` are all made from this.
        """
        shape = self.shape
        return {q.name: np.broadcast_to(q.values(self), shape) for q in self.catalogue.table}

    def column_units(self) -> dict[str, str]:
        """The unit of each of :meth:`columns` (``""`` for the flags), from :attr:`catalogue`."""
        return {q.name: q.unit_symbol for q in self.catalogue.table}

    def to_pandas(self) -> Any:
        """A :class:`pandas.DataFrame` of :meth:`columns` (pandas is optional: ``pip install pandas``).

        One row per sample; a batch has a ``(design, sample)`` MultiIndex.
        """
        try:
            import pandas as pd
        except ImportError:  # pragma: no cover - depends on the environment
            raise InputError("to_pandas needs pandas: pip install pandas") from None
        cols = {k: np.asarray(v).reshape(-1) for k, v in self.columns().items()}
        if self.poses is None:
            index = pd.RangeIndex(self.n_samples, name="sample")
        else:
            index = pd.MultiIndex.from_product(
                [range(self.poses.shape[0]), range(self.n_samples)], names=["design", "sample"]
            )
        return pd.DataFrame(cols, index=index)

    def to_dict(self) -> dict[str, Any]:
        """The JSON result of ``--format json`` (docs/commands.md); NaN becomes ``None``.

        Every quantity of :attr:`catalogue`'s table goes to its ``json_path``; ``quantities``
        lists the entries (name, owner, unit, group, path).  For a batch every array is a
        list per design.  Without rates the velocity, acceleration and link-rate keys are absent.
        """
        m = self.mechanism
        out: dict[str, Any] = {
            "format": "linkagekit-result/1",
            "name": m.name,
            "units": {"length": m.length_unit, "angle": m.angle_unit, "time": "s", "force": "N", "torque": "N*m"},
            **({"time": None} if self.time is not None else {}),  # a simulation's time axis, beside the inputs
            "inputs": {},
            "speeds": {k: json_list(v) for k, v in self.speeds.items()},
            "input_accelerations": {k: json_list(v) for k, v in self.accelerations.items()},
            "assembled": None,
            "singular": None,
            "signs": {k: np.asarray(v).tolist() for k, v in self.signs.items()},
            "joints": {j: {} for j in m.joint_names},
            "links": {ln.name: {} for ln in m.links},
        }
        if self.forces is not None:
            out["reactions"] = [
                {"joint": r.joint, "on": r.on, "by": r.by, **({"kind": "slider"} if r.slider else {})}
                for r in self.forces.layout()
            ]
            out["driver_torque"] = {}
        for q in self.catalogue.table:
            _put(out, q.json_path, q.values(self))
        out["quantities"] = [q.to_dict() for q in self.catalogue]
        if self.stopped is not None:  # a simulation that met a toggle: why its rows end early
            out["stopped"] = self.stopped
        return out

    def __repr__(self) -> str:
        m = self.mechanism
        names = ", ".join(m.joint_names[:8]) + (", ..." if len(m.joint_names) > 8 else "")
        what = f"{self.n_samples} samples"
        if self.poses is not None:
            what = f"{self.poses.shape[0]} designs x {what}"
        extra = "" if self.forces is None else "; forces"
        return (
            f"<Result {m.name!r}: {what}, {int(np.sum(self.assembled))} assembled, "
            f"{int(np.sum(self.singular))} singular; joints {names}{extra}>"
        )


def _put(doc: dict[str, Any], path: tuple[str | int, ...], values: Any) -> None:
    """Store ``values`` at ``path`` in the JSON document (flags as booleans, numbers with null for NaN)."""
    node: Any = doc
    for key in path[:-1]:
        node = node.setdefault(key, {}) if isinstance(node, dict) else node[key]
    arr = np.asarray(values)
    node[path[-1]] = arr.tolist() if arr.dtype == bool else json_list(arr)


def _one_sign(value: Any, i: int) -> Any:
    """Design ``i``'s entry of a sign: an int, or its per-sample array."""
    arr = np.asarray(value)
    if arr.ndim == 0:
        return int(arr)
    one = arr[i]
    return int(one) if np.ndim(one) == 0 else frozen(one)
